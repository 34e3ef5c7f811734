//! Flight-data CSV reader and atomic writer (schema: DESIGN.md §4).
//!
//! Reading: `#` lines before the header are metadata; the header names the columns (`time_s`
//! required, any order, unknown columns kept); every data cell must be a finite number. The body is
//! split at line boundaries into chunks parsed in parallel (each chunk with the `csv` crate's
//! `ByteRecord`), unless it holds a quote character, in which case one chunk keeps quoting exact.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::Path;

use rayon::prelude::*;

use super::error::{DataError, Warning};
use super::record::FlightRecord;

/// Reads and validates a flight-data CSV; soft findings are available from [`FlightRecord::validate`]
/// or directly from [`read_csv_with_warnings`].
pub fn read_csv(path: &Path) -> Result<FlightRecord, DataError> {
    let bytes = fs::read(path).map_err(|source| DataError::Io {
        file: path.to_path_buf(),
        action: "cannot read the CSV file",
        source,
    })?;
    parse_csv_bytes(&bytes, &path.display().to_string())
}

/// Reads a flight-data CSV and returns it with its unit-sanity and sampling warnings.
pub fn read_csv_with_warnings(path: &Path) -> Result<(FlightRecord, Vec<Warning>), DataError> {
    let rec = read_csv(path)?;
    let warnings = rec.warnings();
    Ok((rec, warnings))
}

/// Parses flight-data CSV bytes; `file` names the source in error messages.
pub fn parse_csv_bytes(bytes: &[u8], file: &str) -> Result<FlightRecord, DataError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut pos = 0usize;
    let mut line = 0usize; // 1-based number of the line starting at `pos`, minus one
    let mut metadata = Vec::new();
    // Metadata (`#` lines) and blank lines before the header.
    let header_line = loop {
        if pos >= bytes.len() {
            return Err(DataError::Empty {
                file: file.to_string(),
            });
        }
        let end = next_line_end(bytes, pos);
        let text = trim_cr(&bytes[pos..end]);
        line += 1;
        if let Some(meta) = text.strip_prefix(b"#") {
            metadata.push(String::from_utf8_lossy(meta).into_owned());
        } else if !text.iter().all(u8::is_ascii_whitespace) {
            break (pos, end);
        }
        pos = (end + 1).min(bytes.len());
    };
    let header_lineno = line;
    let names = parse_header(&bytes[header_line.0..header_line.1], file, header_lineno)?;
    let time_index =
        names
            .iter()
            .position(|n| n == "time_s")
            .ok_or_else(|| DataError::MissingTime {
                file: file.to_string(),
                line: header_lineno,
                found: names.join(", "),
            })?;
    let body_start = (header_line.1 + 1).min(bytes.len());
    let body = &bytes[body_start..];
    let chunks = split_chunks(body);
    // First line number of each chunk.
    let newline_counts: Vec<usize> = chunks
        .par_iter()
        .map(|c| c.iter().filter(|&&b| b == b'\n').count())
        .collect();
    let mut first_lines = Vec::with_capacity(chunks.len());
    let mut next = header_lineno + 1;
    for n in &newline_counts {
        first_lines.push(next);
        next += n;
    }
    let parsed: Vec<Result<Chunk, DataError>> = chunks
        .par_iter()
        .zip(first_lines.par_iter())
        .map(|(c, &first)| parse_chunk(c, first, &names, time_index, file))
        .collect();
    let mut parts = Vec::with_capacity(parsed.len());
    for p in parsed {
        parts.push(p?);
    }
    let parts: Vec<Chunk> = parts.into_iter().filter(|c| c.rows > 0).collect();
    if parts.is_empty() {
        return Err(DataError::NoRows {
            file: file.to_string(),
            line: header_lineno,
        });
    }
    // Time must also increase across chunk boundaries.
    for w in parts.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (ta, tb) = (a.columns[time_index][a.rows - 1], b.columns[time_index][0]);
        if tb <= ta {
            return Err(DataError::TimeNotIncreasing {
                file: file.to_string(),
                line: b.first_line,
                time_s: tb,
                previous_s: ta,
                previous_line: a.last_line,
                relation: if tb == ta {
                    "repeats"
                } else {
                    "goes back from"
                },
            });
        }
    }
    let total: usize = parts.iter().map(|c| c.rows).sum();
    let mut columns: Vec<Vec<f64>> = (0..names.len())
        .map(|_| Vec::with_capacity(total))
        .collect();
    for part in parts {
        for (dst, src) in columns.iter_mut().zip(part.columns) {
            dst.extend_from_slice(&src);
        }
    }
    let time_s = std::mem::take(&mut columns[time_index]);
    let mut rec = FlightRecord::new(time_s);
    rec.metadata = metadata;
    for (i, (name, values)) in names.into_iter().zip(columns).enumerate() {
        if i != time_index {
            rec.columns.push((name, values));
        }
    }
    Ok(rec)
}

/// Index of the `\n` ending the line at `pos`, or the end of the input.
fn next_line_end(bytes: &[u8], pos: usize) -> usize {
    bytes[pos..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| pos + i)
}

fn trim_cr(s: &[u8]) -> &[u8] {
    s.strip_suffix(b"\r").unwrap_or(s)
}

/// Column names from the header line (quoted names allowed), trimmed, unique and non-empty.
fn parse_header(line_bytes: &[u8], file: &str, line: usize) -> Result<Vec<String>, DataError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(line_bytes);
    let mut rec = csv::ByteRecord::new();
    let parse_err = |message: String| DataError::Parse {
        file: file.to_string(),
        line,
        message,
    };
    match rdr.read_byte_record(&mut rec) {
        Ok(true) => {}
        Ok(false) => return Err(parse_err("cannot read the header row".into())),
        Err(e) => return Err(parse_err(format!("cannot parse the header row: {e}"))),
    }
    let mut names: Vec<String> = Vec::with_capacity(rec.len());
    for (k, cell) in rec.iter().enumerate() {
        let name = String::from_utf8_lossy(cell).trim().to_string();
        if name.is_empty() {
            return Err(parse_err(format!(
                "header field {} is empty; every column needs a name (trailing comma?)",
                k + 1
            )));
        }
        if names.contains(&name) {
            return Err(DataError::DuplicateColumn {
                file: file.to_string(),
                line,
                column: name,
            });
        }
        names.push(name);
    }
    Ok(names)
}

/// Splits the body at line boundaries into roughly equal chunks for parallel parsing; one chunk if
/// the body holds a quote (a quoted field may contain a newline).
fn split_chunks(body: &[u8]) -> Vec<&[u8]> {
    const MIN_CHUNK: usize = 1 << 20;
    let n_chunks = (rayon::current_num_threads() * 4).max(1);
    if body.len() < 2 * MIN_CHUNK || body.contains(&b'"') {
        return vec![body];
    }
    let target = (body.len() / n_chunks).max(MIN_CHUNK);
    let mut out = Vec::new();
    let mut start = 0;
    while start < body.len() {
        let guess = (start + target).min(body.len());
        let end = if guess >= body.len() {
            body.len()
        } else {
            next_line_end(body, guess).saturating_add(1).min(body.len())
        };
        out.push(&body[start..end]);
        start = end;
    }
    out
}

/// One parsed chunk: column-major values and its line span.
struct Chunk {
    columns: Vec<Vec<f64>>,
    rows: usize,
    first_line: usize,
    last_line: usize,
}

fn parse_chunk(
    bytes: &[u8],
    first_line: usize,
    names: &[String],
    time_index: usize,
    file: &str,
) -> Result<Chunk, DataError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(bytes);
    let ncols = names.len();
    let estimate = bytes.len() / (ncols * 8).max(1);
    let mut columns: Vec<Vec<f64>> = (0..ncols).map(|_| Vec::with_capacity(estimate)).collect();
    let mut rec = csv::ByteRecord::new();
    let mut rows = 0usize;
    let mut chunk_first = 0usize;
    let mut last_line = 0usize;
    loop {
        match rdr.read_byte_record(&mut rec) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                let line = e
                    .position()
                    .map_or(first_line, |p| first_line + p.line() as usize - 1);
                return Err(DataError::Parse {
                    file: file.to_string(),
                    line,
                    message: e.to_string(),
                });
            }
        }
        let line = rec
            .position()
            .map_or(first_line, |p| first_line + p.line() as usize - 1);
        // A line of only whitespace is not a row.
        if rec.len() == 1 && rec[0].iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        if rec.len() != ncols {
            return Err(DataError::Ragged {
                file: file.to_string(),
                line,
                expected: ncols,
                found: rec.len(),
            });
        }
        for (k, cell) in rec.iter().enumerate() {
            let v = parse_cell(cell).map_err(|finite_but_bad| {
                let cell_text = String::from_utf8_lossy(cell).into_owned();
                if finite_but_bad {
                    DataError::NonNumeric {
                        file: file.to_string(),
                        line,
                        column: names[k].clone(),
                        cell: cell_text,
                    }
                } else {
                    DataError::NonFinite {
                        file: file.to_string(),
                        line,
                        column: names[k].clone(),
                        cell: cell_text,
                    }
                }
            })?;
            columns[k].push(v);
        }
        if rows > 0 {
            let t = &columns[time_index];
            let (prev, cur) = (t[rows - 1], t[rows]);
            if cur <= prev {
                return Err(DataError::TimeNotIncreasing {
                    file: file.to_string(),
                    line,
                    time_s: cur,
                    previous_s: prev,
                    previous_line: last_line,
                    relation: if cur == prev {
                        "repeats"
                    } else {
                        "goes back from"
                    },
                });
            }
        } else {
            chunk_first = line;
        }
        last_line = line;
        rows += 1;
    }
    Ok(Chunk {
        columns,
        rows,
        first_line: chunk_first,
        last_line,
    })
}

/// Parses one numeric cell. `Err(true)`: not a number; `Err(false)`: a number but not finite.
fn parse_cell(cell: &[u8]) -> Result<f64, bool> {
    let trimmed = cell.trim_ascii();
    let s = std::str::from_utf8(trimmed).map_err(|_| true)?;
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(false),
        Err(_) => Err(true),
    }
}

/// Writes the record as CSV through a temporary file in the same directory, synced to disk and then
/// renamed over `path`: readers see either the old file or the complete new one, never a partial one.
///
/// Floats are written in Rust's shortest round-trip form, so reading the file back gives the same bits.
pub fn write_csv_atomic(path: &Path, rec: &FlightRecord) -> Result<(), DataError> {
    for (name, values) in &rec.columns {
        if values.len() != rec.time_s.len() {
            return Err(DataError::LengthMismatch {
                file: path.display().to_string(),
                column: name.clone(),
                expected: rec.time_s.len(),
                found: values.len(),
            });
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "flight.csv".into());
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let io_err = |action: &'static str| {
        let file = path.to_path_buf();
        move |source| DataError::Io {
            file,
            action,
            source,
        }
    };
    let result = (|| {
        let f = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)
            .map_err(io_err("cannot create a temporary file next to the output"))?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write_csv_to(&mut w, rec).map_err(io_err("cannot write the CSV"))?;
        let f = w
            .into_inner()
            .map_err(|e| io_err("cannot write the CSV")(e.into_error()))?;
        f.sync_all()
            .map_err(io_err("cannot sync the CSV to disk"))?;
        fs::rename(&tmp, path).map_err(io_err("cannot move the finished CSV into place"))?;
        // Persist the rename itself (best effort: not every platform can sync a directory).
        if let Ok(d) = File::open(&dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes metadata, header and rows to any writer.
pub fn write_csv_to<W: Write>(w: &mut W, rec: &FlightRecord) -> std::io::Result<()> {
    for m in &rec.metadata {
        for line in m.lines() {
            writeln!(w, "#{line}")?;
        }
    }
    write_name(w, "time_s")?;
    for (name, _) in &rec.columns {
        w.write_all(b",")?;
        write_name(w, name)?;
    }
    w.write_all(b"\n")?;
    for i in 0..rec.time_s.len() {
        write!(w, "{:?}", rec.time_s[i])?;
        for (_, values) in &rec.columns {
            write!(w, ",{:?}", values[i])?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Writes a column name, quoting it if it holds a comma, quote or line break.
fn write_name<W: Write>(w: &mut W, name: &str) -> std::io::Result<()> {
    if name.contains([',', '"', '\n', '\r']) {
        write!(w, "\"{}\"", name.replace('"', "\"\""))
    } else {
        w.write_all(name.as_bytes())
    }
}
