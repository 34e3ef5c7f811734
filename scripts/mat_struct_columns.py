"""The signals of a MATLAB MAT-file's structure as comma-separated text, for flightid's MAT reader.

flightid reads a MAT-file's numeric matrix, or its vectors one per signal, itself; a file that keeps its signals
in a structure (`Maneuver.t`, `Maneuver.p`, ..., as many logging and test scripts save them) is passed here.
scipy reads the structure; its numeric fields are flattened, nested structures by a dotted path where a name
repeats (`flight.imu.q`), an N x k field into k columns `name_1`, ..., `name_k`; the fields of the length most
share are the columns. Written on stdout: one `# ...` line saying what was read, a header row of the names, the
samples (numbers in their shortest round-trip form). Nothing usable: a message on stderr and exit 2.

Usage: python3 mat_struct_columns.py FILE.mat
"""
import sys
from collections import Counter

import numpy as np
import scipy.io


def fields(value, path, out):
    """Appends (path, 1-D float array) for every numeric leaf under `value`."""
    if isinstance(value, scipy.io.matlab.mat_struct):
        for name in value._fieldnames:
            fields(getattr(value, name), path + [name], out)
    elif isinstance(value, np.ndarray) and value.dtype == object:
        if value.size == 1:
            fields(value.reshape(-1)[0], path, out)
    elif isinstance(value, np.ndarray) and np.issubdtype(value.dtype, np.number) \
            and not np.iscomplexobj(value) and value.size >= 2:
        if value.ndim == 1:
            out.append((path, value.astype(float)))
        elif value.ndim == 2:
            rows, cols = value.shape
            # samples along the longer dimension
            m = value if rows >= cols else value.T
            for k in range(m.shape[1]):
                out.append((path[:-1] + [f"{path[-1]}_{k + 1}"], m[:, k].astype(float)))


def main():
    path = sys.argv[1]
    try:
        mat = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    except Exception as e:  # noqa: BLE001  (any reader failure is the file's)
        print(f"scipy cannot read it either ({type(e).__name__}: {e})", file=sys.stderr)
        sys.exit(2)
    structs = [k for k, v in mat.items() if not k.startswith("__")
               and (isinstance(v, scipy.io.matlab.mat_struct) or (isinstance(v, np.ndarray) and v.dtype == object))]
    leaves = []
    for k in structs:
        fields(mat[k], [k], leaves)
    lengths = Counter(len(v) for _, v in leaves)
    if not lengths:
        print("no structure with numeric fields in it", file=sys.stderr)
        sys.exit(2)
    samples, count = max(lengths.items(), key=lambda kv: (kv[1], kv[0]))
    if count < 2:
        print("no two numeric fields of the same length in its structures", file=sys.stderr)
        sys.exit(2)
    columns = [(p, v) for p, v in leaves if len(v) == samples]
    last = Counter(p[-1] for p, _ in columns)
    names = [p[-1] if last[p[-1]] == 1 else ".".join(p[1:] or p) for p, _ in columns]
    others = [".".join(p) for p, v in leaves if len(v) != samples]
    note = (f"# MAT-file structure {', '.join(f'`{s}`' for s in structs)}: {samples} samples x {len(names)} "
            f"channels ({', '.join(names)})")
    if others:
        note += f" (other lengths, not read: {', '.join(others)})"
    out = sys.stdout
    out.write(note + "\n")
    out.write(",".join(names) + "\n")
    data = np.column_stack([v for _, v in columns])
    for row in data:
        out.write(",".join(repr(float(x)) for x in row) + "\n")


if __name__ == "__main__":
    main()
