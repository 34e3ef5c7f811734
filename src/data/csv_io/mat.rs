//! MATLAB MAT-files (level 5, compressed or not; MATLAB's default up to `-v7`) as flight data: the file's
//! numeric matrix of samples × channels, read as a headerless text file would be (columns named `1`, `2`, …
//! by position, which a column map renames), so that the same map serves a book's `.asc` and `.mat` records.
//!
//! Which matrix: the one named as the file (`fAttasElv1` in `fAttasElv1.mat`), else the largest real 2-D
//! numeric array; one with fewer rows than columns is taken as channels × samples and read transposed.
//! Character, cell and structure variables are passed over. The record's metadata names the matrix read and
//! any other numeric arrays.
//!
//! A file without such a matrix that holds one vector per signal (`t`, `alpha`, `q`, …, as a logger's
//! export or MATLAB's `save(f, '-struct', 'S')` writes them) is read as a file with a header row: the
//! vectors of the length most of them share are the columns, named as the variables (so a column map
//! renames them by name); vectors of other lengths and scalars are listed in the metadata. A file that keeps its
//! signals in a structure (`Maneuver.t`, `Maneuver.p`, …) is read the same way through the project's Python
//! environment (`scripts/mat_struct_columns.py`: scipy reads structures, the `matfile` crate passes over them):
//! the numeric fields of the length most share are the columns, named by the field (a dotted path where a name
//! repeats; an N × k field as `name_1` … `name_k`).

use std::path::Path;

use super::super::error::DataError;

/// Whether `path` names a MAT-file (extension `.mat`, any case).
pub(super) fn is_mat_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"))
}

/// The MAT-file's sample matrix as the text of a headerless, comma-separated file (one row per line, so a
/// message's line N is the matrix's row N; numbers in their shortest round-trip form, so nothing is lost),
/// and a metadata line naming the matrix.
pub(super) fn matrix_as_text(path: &Path) -> Result<(Vec<u8>, String), DataError> {
    let file = path.display().to_string();
    let fail = |message: String| DataError::Mat {
        file: file.clone(),
        message,
    };
    let reader = std::fs::File::open(path)
        .map_err(|e| DataError::io(path, "cannot read the MAT-file")(e))?;
    let mat = matfile::MatFile::parse(std::io::BufReader::new(reader)).map_err(|e| {
        fail(format!(
            "not a readable MATLAB level-5 MAT-file ({e}); a `-v7.3` file is HDF5 and is not read: \
             save it with `save(..., '-v7')` or export the matrix as text"
        ))
    })?;
    let matrices: Vec<&matfile::Array> = mat
        .arrays()
        .iter()
        .filter(|a| a.ndims() == 2 && a.size()[0] >= 2 && a.size()[1] >= 2)
        .collect();
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let Some(chosen) = matrices
        .iter()
        .find(|a| a.name() == stem)
        .or_else(|| matrices.iter().max_by_key(|a| a.size()[0] * a.size()[1]))
    else {
        return vectors_as_text(&mat).or_else(|why_vectors| {
            struct_as_text(path).map_err(|why_struct| {
                let found: Vec<String> = mat
                    .arrays()
                    .iter()
                    .map(|a| format!("`{}` {:?}", a.name(), a.size()))
                    .collect();
                fail(format!(
                    "no numeric matrix of samples × channels (at least 2 × 2) in the file, {why_vectors}, and \
                     no structure of signals ({why_struct}) (numeric arrays: {}); save the signals as a matrix \
                     or as variables (`save(file, '-struct', 'S', '-v7')`)",
                    if found.is_empty() { "none".to_string() } else { found.join(", ") }
                ))
            })
        });
    };
    let (rows, cols) = (chosen.size()[0], chosen.size()[1]);
    // A record has more samples than channels: a matrix stored the other way round (channels as rows, as
    // some tools save it) is read transposed.
    let transposed = rows < cols;
    let (samples, channels) = if transposed {
        (cols, rows)
    } else {
        (rows, cols)
    };
    let values = real_values(chosen.data()).ok_or_else(|| {
        fail(format!(
            "the matrix `{}` is complex; flight data are real numbers",
            chosen.name()
        ))
    })?;
    let others: Vec<String> = matrices
        .iter()
        .filter(|a| a.name() != chosen.name())
        .map(|a| format!("`{}` {} × {}", a.name(), a.size()[0], a.size()[1]))
        .collect();
    let note = format!(
        " MAT-file matrix `{}`: {samples} samples × {channels} channels{}{}",
        chosen.name(),
        if transposed {
            " (stored as channels × samples, read transposed)"
        } else {
            ""
        },
        if others.is_empty() {
            String::new()
        } else {
            format!(" (also in the file: {})", others.join(", "))
        }
    );
    let mut text = Vec::with_capacity(rows * cols * 12);
    for i in 0..samples {
        for j in 0..channels {
            if j > 0 {
                text.push(b',');
            }
            // MATLAB stores column by column: element (r, c) is at c·rows + r.
            let (r, c) = if transposed { (j, i) } else { (i, j) };
            text.extend_from_slice(format!("{:?}", values[c * rows + r]).as_bytes());
        }
        text.push(b'\n');
    }
    Ok((text, note))
}

/// The MAT-file's vectors of one common length as the text of a comma-separated file with a header row of
/// their names (module doc), and the metadata line; `Err` says why there are none to read.
fn vectors_as_text(mat: &matfile::MatFile) -> Result<(Vec<u8>, String), String> {
    let vectors: Vec<(&matfile::Array, Vec<f64>)> = mat
        .arrays()
        .iter()
        .filter(|a| a.ndims() == 2 && a.size().iter().min() == Some(&1))
        .filter(|a| a.size().iter().max().is_some_and(|&n| n >= 2))
        .filter_map(|a| real_values(a.data()).map(|v| (a, v)))
        .collect();
    // the length most vectors share (the longer on a tie): the samples
    let mut counts: std::collections::BTreeMap<usize, usize> = std::collections::BTreeMap::new();
    for (_, v) in &vectors {
        *counts.entry(v.len()).or_default() += 1;
    }
    let Some((&samples, &count)) = counts.iter().max_by_key(|(len, n)| (**n, **len)) else {
        return Err("no vectors of samples".into());
    };
    if count < 2 {
        return Err("no two vectors of the same length (one per signal)".into());
    }
    let (columns, others): (Vec<_>, Vec<_>) = vectors.iter().partition(|(_, v)| v.len() == samples);
    let names: Vec<&str> = columns.iter().map(|(a, _)| a.name()).collect();
    let mut text = names.join(",").into_bytes();
    text.push(b'\n');
    for i in 0..samples {
        for (j, (_, v)) in columns.iter().enumerate() {
            if j > 0 {
                text.push(b',');
            }
            text.extend_from_slice(format!("{:?}", v[i]).as_bytes());
        }
        text.push(b'\n');
    }
    let passed_over: Vec<String> = others
        .iter()
        .map(|(a, v)| format!("`{}` ({} values)", a.name(), v.len()))
        .collect();
    let note = format!(
        " MAT-file vectors: {samples} samples × {} channels ({}){}",
        names.len(),
        names.join(", "),
        if passed_over.is_empty() {
            String::new()
        } else {
            format!(" (other lengths, not read: {})", passed_over.join(", "))
        }
    );
    Ok((text, note))
}

/// `scripts/mat_struct_columns.py`, run by the project's Python environment (scipy reads MATLAB structures; the
/// `matfile` crate passes over them).
const STRUCT_SCRIPT: &str = include_str!("../../../scripts/mat_struct_columns.py");

/// The signals of the MAT-file's structures as the text of a comma-separated file with a header row (module
/// doc), and the metadata line; `Err` says why there are none.
fn struct_as_text(path: &Path) -> Result<(Vec<u8>, String), String> {
    let python = crate::sim::env::python().map_err(|e| {
        format!("the Python environment that reads structures is not available: {e}")
    })?;
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg(STRUCT_SCRIPT)
        .arg(path)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| format!("the Python environment did not start: {e}"))?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).trim().to_string());
    }
    let text = out.stdout;
    let first_line_end = text.iter().position(|&b| b == b'\n').unwrap_or(text.len());
    let note = String::from_utf8_lossy(&text[..first_line_end])
        .trim_start_matches('#')
        .trim_end()
        .to_string();
    let body = text.get(first_line_end + 1..).unwrap_or_default().to_vec();
    Ok((body, format!(" {}", note.trim_start())))
}

/// The array's values as f64, column-major; `None` for a complex array.
fn real_values(data: &matfile::NumericData) -> Option<Vec<f64>> {
    use matfile::NumericData as D;
    fn cast<T: Copy + Into<f64>>(real: &[T]) -> Vec<f64> {
        real.iter().map(|&v| v.into()).collect()
    }
    Some(match data {
        D::Double { real, imag: None } => real.clone(),
        D::Single { real, imag: None } => cast(real),
        D::Int8 { real, imag: None } => cast(real),
        D::UInt8 { real, imag: None } => cast(real),
        D::Int16 { real, imag: None } => cast(real),
        D::UInt16 { real, imag: None } => cast(real),
        D::Int32 { real, imag: None } => cast(real),
        D::UInt32 { real, imag: None } => cast(real),
        D::Int64 { real, imag: None } => real.iter().map(|&v| v as f64).collect(),
        D::UInt64 { real, imag: None } => real.iter().map(|&v| v as f64).collect(),
        _ => return None,
    })
}
