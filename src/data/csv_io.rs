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
    let ncols = names.len();
    let estimate = bytes.len() / (ncols * 8).max(1);
    let mut sink = ChunkSink {
        columns: (0..ncols).map(|_| Vec::with_capacity(estimate)).collect(),
        rows: 0,
        first_line: 0,
        last_line: 0,
        names,
        time_index,
        file,
    };
    if bytes.contains(&b'"') {
        parse_chunk_quoted(bytes, first_line, &mut sink)?;
    } else {
        parse_chunk_plain(bytes, first_line, &mut sink)?;
    }
    Ok(Chunk {
        columns: sink.columns,
        rows: sink.rows,
        first_line: sink.first_line,
        last_line: sink.last_line,
    })
}

/// Accumulates rows of one chunk, checking field count, numbers and time order.
struct ChunkSink<'a> {
    columns: Vec<Vec<f64>>,
    rows: usize,
    first_line: usize,
    last_line: usize,
    names: &'a [String],
    time_index: usize,
    file: &'a str,
}

impl ChunkSink<'_> {
    /// The error for a cell that is not a finite number.
    fn cell_error(&self, line: usize, k: usize, cell: &[u8]) -> DataError {
        let file = self.file.to_string();
        let column = self.names[k].clone();
        let not_a_number = parse_cell(cell).err().unwrap_or(true);
        let cell = String::from_utf8_lossy(cell).trim().to_string();
        if not_a_number {
            DataError::NonNumeric {
                file,
                line,
                column,
                cell,
            }
        } else {
            DataError::NonFinite {
                file,
                line,
                column,
                cell,
            }
        }
    }

    /// Adds one row given as an iterator over its cells; `n_fields` is the row's field count.
    fn push_row<'c>(
        &mut self,
        line: usize,
        n_fields: usize,
        cells: impl Iterator<Item = &'c [u8]>,
    ) -> Result<(), DataError> {
        let ncols = self.names.len();
        if n_fields != ncols {
            return Err(DataError::Ragged {
                file: self.file.to_string(),
                line,
                expected: ncols,
                found: n_fields,
            });
        }
        for (k, cell) in cells.enumerate() {
            let v = parse_cell(cell).map_err(|_| self.cell_error(line, k, cell))?;
            self.columns[k].push(v);
        }
        self.finish_row(line)
    }

    /// Checks the time order of the row just pushed and counts it.
    fn finish_row(&mut self, line: usize) -> Result<(), DataError> {
        let rows = self.rows;
        if rows > 0 {
            let t = &self.columns[self.time_index];
            let (prev, cur) = (t[rows - 1], t[rows]);
            if cur <= prev {
                return Err(DataError::TimeNotIncreasing {
                    file: self.file.to_string(),
                    line,
                    time_s: cur,
                    previous_s: prev,
                    previous_line: self.last_line,
                    relation: if cur == prev {
                        "repeats"
                    } else {
                        "goes back from"
                    },
                });
            }
        } else {
            self.first_line = line;
        }
        self.last_line = line;
        self.rows += 1;
        Ok(())
    }
}

/// Fast path for bodies without quotes: one pass over the bytes that splits cells at `,`/`\n` and
/// parses plain decimals on the fly; anything else (exponents, spaces, `\r`, text) goes through
/// [`parse_cell`].
fn parse_chunk_plain(
    bytes: &[u8],
    first_line: usize,
    sink: &mut ChunkSink,
) -> Result<(), DataError> {
    let n = bytes.len();
    let ncols = sink.names.len();
    let mut line = first_line;
    let mut p = 0usize;
    while p < n {
        let mut k = 0usize;
        let line_end;
        loop {
            let (value, end) = scan_cell(bytes, p);
            let at_line_end = end >= n || bytes[end] == b'\n';
            if k == 0 && at_line_end && bytes[p..end].iter().all(u8::is_ascii_whitespace) {
                // A blank line is not a row.
                k = usize::MAX;
                line_end = end;
                break;
            }
            if k < ncols {
                match value {
                    Some(v) => sink.columns[k].push(v),
                    None => return Err(sink.cell_error(line, k, &bytes[p..end])),
                }
            }
            k += 1;
            if at_line_end {
                line_end = end;
                break;
            }
            p = end + 1;
        }
        if k != usize::MAX {
            if k != ncols {
                return Err(DataError::Ragged {
                    file: sink.file.to_string(),
                    line,
                    expected: ncols,
                    found: k,
                });
            }
            sink.finish_row(line)?;
        }
        line += 1;
        p = line_end + 1;
    }
    Ok(())
}

/// Scans one cell starting at `p`: its value (`None` if not a finite number) and the index of the
/// delimiter (`,` or `\n`) or end of input that ends it. One pass: plain decimals of up to 15
/// significant digits take Clinger's exact fast path (as in [`fast_decimal`]); the rest goes to
/// the standard library's correctly rounded parser.
#[inline]
fn scan_cell(bytes: &[u8], p: usize) -> (Option<f64>, usize) {
    let n = bytes.len();
    let mut i = p;
    let negative = i < n && bytes[i] == b'-';
    if negative {
        i += 1;
    }
    let mut mantissa: u64 = 0;
    let mut n_digits = 0u32;
    let mut frac_digits = 0usize;
    let mut seen_dot = false;
    let mut simple = true;
    while i < n {
        let c = bytes[i];
        if c.is_ascii_digit() {
            // Saturates harmlessly: past 19 digits the cell leaves the fast path anyway.
            mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
            n_digits += 1;
            frac_digits += usize::from(seen_dot);
        } else if c == b',' || c == b'\n' {
            break;
        } else if c == b'.' && !seen_dot {
            seen_dot = true;
        } else {
            simple = false;
        }
        i += 1;
    }
    if simple
        && n_digits > 0
        && n_digits <= 19
        && mantissa <= (1u64 << 53)
        && frac_digits < POW10.len()
    {
        let v = mantissa as f64 / POW10[frac_digits];
        return (Some(if negative { -v } else { v }), i);
    }
    (parse_cell_std(&bytes[p..i]).ok(), i)
}

/// General path (quoted fields) through the `csv` crate's `ByteRecord`.
fn parse_chunk_quoted(
    bytes: &[u8],
    first_line: usize,
    sink: &mut ChunkSink,
) -> Result<(), DataError> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(bytes);
    let mut rec = csv::ByteRecord::new();
    let line_of =
        |p: Option<&csv::Position>| p.map_or(first_line, |p| first_line + p.line() as usize - 1);
    loop {
        match rdr.read_byte_record(&mut rec) {
            Ok(true) => {}
            Ok(false) => return Ok(()),
            Err(e) => {
                return Err(DataError::Parse {
                    file: sink.file.to_string(),
                    line: line_of(e.position()),
                    message: e.to_string(),
                })
            }
        }
        let line = line_of(rec.position());
        // A line of only whitespace is not a row.
        if rec.len() == 1 && rec[0].iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        sink.push_row(line, rec.len(), rec.iter())?;
    }
}

/// Exactly representable powers of ten (10^22 is the largest below 2^53·2^22).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses one numeric cell. `Err(true)`: not a number; `Err(false)`: a number but not finite.
fn parse_cell(cell: &[u8]) -> Result<f64, bool> {
    let trimmed = cell.trim_ascii();
    if let Some(v) = fast_decimal(trimmed) {
        return Ok(v);
    }
    parse_cell_std(trimmed)
}

/// [`parse_cell`] through the standard library's parser only (trims ASCII whitespace).
fn parse_cell_std(cell: &[u8]) -> Result<f64, bool> {
    let s = std::str::from_utf8(cell.trim_ascii()).map_err(|_| true)?;
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(false),
        Err(_) => Err(true),
    }
}

/// Exact fast path for plain decimals (`-12.345`, no exponent): with an integer mantissa below 2^53
/// and at most 22 fraction digits, `mantissa / 10^k` is one correctly rounded IEEE division
/// (Clinger 1990, "How to read floating point numbers accurately", fast path). Else `None`.
fn fast_decimal(b: &[u8]) -> Option<f64> {
    let (negative, digits) = match b.first()? {
        b'-' => (true, &b[1..]),
        b'+' => (false, &b[1..]),
        _ => (false, b),
    };
    if digits.is_empty() || digits.len() > 19 {
        return None;
    }
    let mut mantissa: u64 = 0;
    let mut n_digits = 0;
    let mut frac_digits: Option<usize> = None;
    for &c in digits {
        match c {
            b'0'..=b'9' => {
                mantissa = mantissa * 10 + u64::from(c - b'0');
                n_digits += 1;
                if let Some(f) = frac_digits.as_mut() {
                    *f += 1;
                }
            }
            b'.' if frac_digits.is_none() => frac_digits = Some(0),
            _ => return None,
        }
    }
    if n_digits == 0 || mantissa > (1u64 << 53) {
        return None;
    }
    let k = frac_digits.unwrap_or(0);
    let v = mantissa as f64 / *POW10.get(k)?;
    Some(if negative { -v } else { v })
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn fast_decimal_path_agrees_bit_for_bit_with_std_parse() {
        // 200k random decimals of 1..19 characters: the fast path must give exactly std's result
        // whenever it answers (Clinger's fast path is exact, so any difference is a bug).
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut answered = 0;
        for _ in 0..200_000 {
            let int_digits = rng.gen_range(0..10);
            let frac_digits = rng.gen_range(0..12);
            let mut s = String::new();
            if rng.gen_bool(0.5) {
                s.push('-');
            }
            for _ in 0..int_digits {
                s.push(char::from(b'0' + rng.gen_range(0..10u8)));
            }
            if frac_digits > 0 || rng.gen_bool(0.3) {
                s.push('.');
            }
            for _ in 0..frac_digits {
                s.push(char::from(b'0' + rng.gen_range(0..10u8)));
            }
            let std = s.parse::<f64>().ok();
            if let Some(v) = fast_decimal(s.as_bytes()) {
                answered += 1;
                assert_eq!(Some(v.to_bits()), std.map(f64::to_bits), "input {s}");
            }
        }
        assert!(answered > 100_000, "fast path used for {answered} inputs");
    }
}
