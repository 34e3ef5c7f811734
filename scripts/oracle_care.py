"""Oracle for flightid's steady-state filter Riccati solver (src/estimate/riccati.rs).

Reads JSON {"a": n×n, "c": m×n, "q": n×n, "r_c": m×m} on stdin and prints {"p": n×n}, the
stabilising solution of  A P + P Aᵀ − P Cᵀ R_c⁻¹ C P + Q = 0  from scipy.linalg.solve_continuous_are
(control form with a = Aᵀ, b = Cᵀ).
"""
import json
import sys

import numpy as np
from scipy.linalg import solve_continuous_are

d = json.load(sys.stdin)
a, c, q, r = (np.array(d[k], dtype=float) for k in ("a", "c", "q", "r_c"))
p = solve_continuous_are(a.T, c.T, q, r)
json.dump({"p": p.tolist()}, sys.stdout)
