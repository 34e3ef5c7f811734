//! The CSV body parser: the body split at line boundaries into chunks parsed in parallel, each chunk parsed
//! row by row into column-major values with chunk-relative line numbers, and the number scanner behind it (a
//! fast path for plain decimals, the standard library's parser for everything else).

use super::next_line_end;
use crate::data::error::DataError;
use crate::data::Channel;

/// Splits the body at line boundaries into roughly equal chunks for parallel parsing; one chunk if
/// the body holds a quote (a quoted field may contain a newline).
pub(super) fn split_chunks(body: &[u8]) -> (Vec<&[u8]>, bool) {
    const MIN_CHUNK: usize = 1 << 20;
    let n_chunks = (rayon::current_num_threads() * 4).max(1);
    let quoted = body.contains(&b'"');
    if body.len() < 2 * MIN_CHUNK || quoted {
        return (vec![body], quoted);
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
    (out, false)
}

/// Moves the line numbers of a chunk-relative error by `offset` lines.
pub(super) fn shift_lines(e: DataError, offset: usize) -> DataError {
    match e {
        DataError::Ragged {
            file,
            line,
            expected,
            found,
        } => DataError::Ragged {
            file,
            line: line + offset,
            expected,
            found,
        },
        DataError::NonNumeric {
            file,
            line,
            column,
            cell,
        } => DataError::NonNumeric {
            file,
            line: line + offset,
            column,
            cell,
        },
        DataError::NonFinite {
            file,
            line,
            column,
            cell,
        } => DataError::NonFinite {
            file,
            line: line + offset,
            column,
            cell,
        },
        DataError::TimeNotIncreasing {
            file,
            line,
            time_s,
            previous_s,
            previous_line,
            relation,
        } => DataError::TimeNotIncreasing {
            file,
            line: line + offset,
            time_s,
            previous_s,
            previous_line: previous_line + offset,
            relation,
        },
        DataError::Parse {
            file,
            line,
            message,
        } => DataError::Parse {
            file,
            line: line + offset,
            message,
        },
        DataError::Implausible {
            file,
            line,
            column,
            value,
            min,
            max,
        } => DataError::Implausible {
            file,
            line: line + offset,
            column,
            value,
            min,
            max,
        },
        other => other,
    }
}

/// A schema column's plausible range ([`Channel::plausible_range`]) as the file holds the column: the SI
/// range over the factor a column map converts it by, so that each cell is checked as it is read.
pub(super) struct FileRange {
    lo: f64,
    hi: f64,
    factor: f64,
    si: (f64, f64),
}

impl FileRange {
    /// The range of the column `name` (after the column map's renaming) whose values the map multiplies by
    /// `factor`; `None` for a column that is not a bounded schema column.
    pub(super) fn of(name: &str, factor: f64) -> Option<FileRange> {
        let si @ (min, max) = Channel::from_name(name)?.plausible_range()?;
        if factor == 0.0 || !factor.is_finite() {
            return None;
        }
        let (a, b) = (min / factor, max / factor);
        Some(FileRange {
            lo: a.min(b),
            hi: a.max(b),
            factor,
            si,
        })
    }
}

/// A value for a message: plain decimals where they are short, else in exponent form (1e300, not 301 digits).
fn short_number(v: f64) -> String {
    if v == 0.0 || (1e-4..1e7).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// One parsed chunk: column-major values, its line span and the line breaks it holds.
pub(super) struct Chunk {
    pub(super) columns: Vec<Vec<f64>>,
    pub(super) rows: usize,
    pub(super) first_line: usize,
    pub(super) last_line: usize,
    pub(super) newlines: usize,
    /// Lines dropped as repeats of the row before (same time, same values).
    pub(super) repeated: Vec<usize>,
}

/// Parses one chunk with chunk-relative line numbers (its first line is line 1).
pub(super) fn parse_chunk(
    bytes: &[u8],
    quoted: bool,
    names: &[String],
    ranges: &[Option<FileRange>],
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
        ranges,
        time_index,
        file,
        repeated: Vec::new(),
    };
    let newlines = if quoted {
        parse_chunk_quoted(bytes, 1, &mut sink)?;
        bytes.iter().filter(|&&b| b == b'\n').count()
    } else {
        parse_chunk_plain(bytes, 1, &mut sink)?
    };
    Ok(Chunk {
        columns: sink.columns,
        rows: sink.rows,
        first_line: sink.first_line,
        last_line: sink.last_line,
        newlines,
        repeated: sink.repeated,
    })
}

/// Accumulates rows of one chunk, checking field count, numbers and time order.
pub(super) struct ChunkSink<'a> {
    columns: Vec<Vec<f64>>,
    rows: usize,
    first_line: usize,
    last_line: usize,
    names: &'a [String],
    /// Per column, its plausible range as the file holds it, if it is a bounded schema column.
    ranges: &'a [Option<FileRange>],
    time_index: usize,
    file: &'a str,
    repeated: Vec<usize>,
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

    /// [`DataError::Ragged`] unless the row at `line` has as many fields (`n_fields`) as the header.
    fn check_width(&self, line: usize, n_fields: usize) -> Result<(), DataError> {
        let ncols = self.names.len();
        if n_fields != ncols {
            return Err(DataError::Ragged {
                file: self.file.to_string(),
                line,
                expected: ncols,
                found: n_fields,
            });
        }
        Ok(())
    }

    /// Adds one row given as an iterator over its cells; `n_fields` is the row's field count.
    fn push_row<'c>(
        &mut self,
        line: usize,
        n_fields: usize,
        cells: impl Iterator<Item = &'c [u8]>,
    ) -> Result<(), DataError> {
        self.check_width(line, n_fields)?;
        for (k, cell) in cells.enumerate() {
            let v = parse_cell(cell).map_err(|_| self.cell_error(line, k, cell))?;
            self.columns[k].push(v);
        }
        self.finish_row(line)
    }

    /// Checks the time order of the row just pushed and counts it. A row that repeats the one before it in
    /// every column (a data system writing a frame twice) is taken back and its line remembered.
    fn finish_row(&mut self, line: usize) -> Result<(), DataError> {
        let rows = self.rows;
        if rows > 0 {
            let t = &self.columns[self.time_index];
            let (prev, cur) = (t[rows - 1], t[rows]);
            if cur == prev && self.columns.iter().all(|c| c[rows] == c[rows - 1]) {
                self.columns.iter_mut().for_each(|c| {
                    c.pop();
                });
                self.repeated.push(line);
                return Ok(());
            }
            if cur <= prev {
                return Err(DataError::time_not_increasing(
                    self.file,
                    (line, cur),
                    (self.last_line, prev),
                ));
            }
        } else {
            self.first_line = line;
        }
        self.check_plausible(line)?;
        self.last_line = line;
        self.rows += 1;
        Ok(())
    }

    /// [`DataError::Implausible`] for the first cell of the row just pushed (at `line`) that lies outside its
    /// column's plausible range.
    fn check_plausible(&self, line: usize) -> Result<(), DataError> {
        let rows = self.rows;
        for (k, range) in self.ranges.iter().enumerate() {
            let Some(r) = range else { continue };
            let v = self.columns[k][rows];
            if !(r.lo..=r.hi).contains(&v) {
                let value = if r.factor == 1.0 {
                    short_number(v)
                } else {
                    format!(
                        "{} ({} after the column map's conversion)",
                        short_number(v),
                        short_number(v * r.factor)
                    )
                };
                return Err(DataError::Implausible {
                    file: self.file.to_string(),
                    line,
                    column: self.names[k].clone(),
                    value,
                    min: r.si.0,
                    max: r.si.1,
                });
            }
        }
        Ok(())
    }
}

/// Fast path for bodies without quotes: one pass over the bytes that splits cells at `,`/`\n` and
/// parses plain decimals on the fly; anything else (exponents, spaces, `\r`, text) goes through
/// [`parse_cell`].
pub(super) fn parse_chunk_plain(
    bytes: &[u8],
    first_line: usize,
    sink: &mut ChunkSink,
) -> Result<usize, DataError> {
    let n = bytes.len();
    let ncols = sink.names.len();
    let mut line = first_line;
    let mut newlines = 0usize;
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
            sink.check_width(line, k)?;
            sink.finish_row(line)?;
        }
        line += 1;
        newlines += usize::from(line_end < n);
        p = line_end + 1;
    }
    Ok(newlines)
}

/// Scans one cell starting at `p`: its value (`None` if not a finite number) and the index of the
/// delimiter (`,` or `\n`) or end of input that ends it. One pass: plain decimals of up to 15
/// significant digits take Clinger's exact fast path (as in [`fast_decimal`]), 16–19 digits
/// [`long_decimal`]; the rest goes to the standard library's correctly rounded parser. Fraction
/// digits are read eight at a time (SWAR, as in Lemire's fast_float: "Number parsing at a
/// gigabyte per second", Softw. Pract. Exper. 2021, §5).
#[inline]
pub(super) fn scan_cell(bytes: &[u8], p: usize) -> (Option<f64>, usize) {
    let n = bytes.len();
    let mut i = p;
    let negative = i < n && bytes[i] == b'-';
    if negative {
        i += 1;
    }
    // Wrapping arithmetic is harmless: past 19 digits the cell leaves the fast paths anyway.
    let mut mantissa: u64 = 0;
    let int_start = i;
    while i < n && bytes[i].is_ascii_digit() {
        mantissa = mantissa
            .wrapping_mul(10)
            .wrapping_add(u64::from(bytes[i] - b'0'));
        i += 1;
    }
    let mut n_digits = i - int_start;
    let mut frac_digits = 0usize;
    if i < n && bytes[i] == b'.' {
        i += 1;
        let frac_start = i;
        while let Some(eight) = bytes.get(i..i + 8) {
            let word = u64::from_le_bytes(eight.try_into().expect("eight bytes"));
            if !eight_digits(word) {
                break;
            }
            mantissa = mantissa
                .wrapping_mul(100_000_000)
                .wrapping_add(eight_digit_value(word));
            i += 8;
        }
        while i < n && bytes[i].is_ascii_digit() {
            mantissa = mantissa
                .wrapping_mul(10)
                .wrapping_add(u64::from(bytes[i] - b'0'));
            i += 1;
        }
        frac_digits = i - frac_start;
        n_digits += frac_digits;
    }
    let at_delimiter = i >= n || bytes[i] == b',' || bytes[i] == b'\n';
    if at_delimiter && n_digits > 0 && n_digits <= 19 && frac_digits < POW10.len() {
        if mantissa <= (1u64 << 53) {
            let v = mantissa as f64 / POW10[frac_digits];
            return (Some(if negative { -v } else { v }), i);
        }
        if let Some(v) = long_decimal(mantissa, frac_digits) {
            return (Some(if negative { -v } else { v }), i);
        }
    }
    let end = i + bytes[i..]
        .iter()
        .position(|&c| c == b',' || c == b'\n')
        .unwrap_or(n - i);
    (parse_cell_std(&bytes[p..end]).ok(), end)
}

/// Whether the eight bytes of `word` (little-endian) are all ASCII digits.
#[inline]
pub(super) fn eight_digits(word: u64) -> bool {
    let above = word.wrapping_add(0x4646_4646_4646_4646); // sets bit 7 for bytes > b'9'
    let below = word.wrapping_sub(0x3030_3030_3030_3030); // sets bit 7 for bytes < b'0'
    (above | below) & 0x8080_8080_8080_8080 == 0
}

/// The value of eight ASCII digits packed little-endian (first digit in the lowest byte), by
/// three multiplications: pairs, then quads, then the two quads.
#[inline]
pub(super) fn eight_digit_value(word: u64) -> u64 {
    const MASK: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 100 + (1_000_000 << 32);
    const MUL2: u64 = 1 + (10_000 << 32);
    let mut v = word.wrapping_sub(0x3030_3030_3030_3030);
    v = v.wrapping_mul(10).wrapping_add(v >> 8);
    ((v & MASK)
        .wrapping_mul(MUL1)
        .wrapping_add(((v >> 16) & MASK).wrapping_mul(MUL2)))
        >> 32
}

/// `w / 10^k` correctly rounded for a mantissa above 2^53 (16–19 digits, as round-trip output
/// has), or `None` when this fast path cannot prove the rounding (then the caller falls back).
///
/// Method: `w = wh + wl` exactly (`wh` = w rounded to f64, |wl| ≤ 2^11); `q = RN(wh / P)`;
/// the division remainder `r = wh − q·P` is exactly representable and exact by FMA (Boldo &
/// Daumas, "Representable correcting terms for possibly underflowing floating point operations",
/// ARITH 2003); the value is `q + (r + wl)/P`. The sum is rounded once more and accepted only if
/// the exact value lies clearly (by 8× the bound on the correction's own error) inside the
/// rounding interval of the result; near-midpoints go to the standard parser.
#[inline]
pub(super) fn long_decimal(w: u64, k: usize) -> Option<f64> {
    let p = *POW10.get(k)?;
    let wh = w as f64;
    if wh >= 18_446_744_073_709_551_616.0 {
        return None; // rounding reached 2^64: `wh as u64` would saturate
    }
    // Exact, |wl| ≤ 2^11: the wrapping difference of two nearby u64 read as i64.
    let wl = w.wrapping_sub(wh as u64) as i64 as f64;
    let q = wh / p;
    let r = (-q).mul_add(p, wh); // exact remainder
    let c = (r + wl) / p;
    let x = q + c;
    // Distance of the exact value from x, in units of x's ulp: (q − x) is exact (Sterbenz).
    // The smaller of the two neighbour gaps (they differ when x is a power of two).
    let ulp = (f64::from_bits(x.to_bits() + 1) - x).min(x - f64::from_bits(x.to_bits() - 1));
    let offset = (q - x) + c;
    let err = 8.0 * (c.abs() * f64::EPSILON + (r.abs() + wl.abs()) * f64::EPSILON / p);
    (x.is_normal() && x > 0.0 && offset.abs() + err < 0.5 * ulp).then_some(x)
}

/// General path (quoted fields) through the `csv` crate's `ByteRecord`.
pub(super) fn parse_chunk_quoted(
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
pub(super) const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses one numeric cell. `Err(true)`: not a number; `Err(false)`: a number but not finite.
pub(super) fn parse_cell(cell: &[u8]) -> Result<f64, bool> {
    let trimmed = cell.trim_ascii();
    if let Some(v) = fast_decimal(trimmed) {
        return Ok(v);
    }
    parse_cell_std(trimmed)
}

/// [`parse_cell`] through the standard library's parser only (trims ASCII whitespace).
pub(super) fn parse_cell_std(cell: &[u8]) -> Result<f64, bool> {
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
pub(super) fn fast_decimal(b: &[u8]) -> Option<f64> {
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
