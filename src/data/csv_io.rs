//! Flight-data CSV reader and atomic writer (schema: docs/data.md).
//!
//! Reading: `#` lines before the header are metadata; the header names the columns (`time_s`
//! required, any order, unknown columns kept); every data cell must be a finite number. The body is
//! split at line boundaries into chunks parsed in parallel (each chunk with the `csv` crate's
//! `ByteRecord`), unless it holds a quote character, in which case one chunk keeps quoting exact.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Read, Write};
use std::path::Path;

use rayon::prelude::*;

use super::columns::ColumnMap;
use super::error::{DataError, Warning};
use super::record::FlightRecord;

/// Reads and validates a flight-data CSV; soft findings are available from [`FlightRecord::validate`]
/// or directly from [`read_csv_with_warnings`].
///
/// Files above a few megabytes are read in blocks that are parsed in parallel while the next block
/// is read (the kernel's copy out of the page cache overlaps the parsing); smaller ones are read
/// whole and go through [`parse_csv_bytes`]. Both give the same record and the same errors.
pub fn read_csv(path: &Path) -> Result<FlightRecord, DataError> {
    read_csv_mapped(path, None)
}

/// Reads a flight-data CSV whose foreign columns and units `map` renames and converts to the
/// schema's SI columns while reading (see [`ColumnMap`]); without a map this is [`read_csv`].
pub fn read_csv_mapped(path: &Path, map: Option<&ColumnMap>) -> Result<FlightRecord, DataError> {
    let io_err = |action: &'static str| {
        move |source| DataError::Io {
            file: path.to_path_buf(),
            action,
            source,
        }
    };
    let mut f = File::open(path).map_err(io_err("cannot read the CSV file"))?;
    let size = f.metadata().map(|m| m.len()).unwrap_or(0);
    let file = path.display().to_string();
    if size < STREAM_MIN_BYTES {
        let mut bytes = Vec::with_capacity(size as usize + 1);
        f.read_to_end(&mut bytes)
            .map_err(io_err("cannot read the CSV file"))?;
        return parse_csv_bytes_mapped(&bytes, &file, map);
    }
    read_csv_in_blocks(f, &file, STREAM_BLOCK_BYTES, map).map_err(|e| match e {
        BlockReadError::Data(e) => e,
        BlockReadError::Io(source) => io_err("cannot read the CSV file")(source),
    })
}

/// Why a block-wise read failed: the data, or the file system.
enum BlockReadError {
    Data(DataError),
    Io(std::io::Error),
}

/// The block-wise path of [`read_csv`], `block_bytes` per block.
fn read_csv_in_blocks(
    mut f: File,
    file: &str,
    block_bytes: usize,
    map: Option<&ColumnMap>,
) -> Result<FlightRecord, BlockReadError> {
    // The preamble: read until the header line is complete (or the file ends).
    let mut head = Vec::with_capacity(1 << 16);
    let mut eof = false;
    while !eof && !header_complete(&head) {
        eof = read_block(&mut f, &mut head, 1 << 16).map_err(BlockReadError::Io)?;
    }
    let pre = parse_preamble(&head, file, map).map_err(BlockReadError::Data)?;
    let carry = head.split_off(pre.body_start);
    let (mut parsed, quoted_tail) =
        stream_chunks(&mut f, carry, eof, &pre, file, block_bytes).map_err(BlockReadError::Io)?;
    if let Some(tail) = quoted_tail {
        parsed.push(parse_chunk(&tail, true, &pre.names, pre.time_index, file));
    }
    assemble(parsed, pre, file).map_err(BlockReadError::Data)
}

/// Files at least this large are streamed in blocks (see [`read_csv`]).
const STREAM_MIN_BYTES: u64 = 4 << 20;

/// Bytes per streamed block; each is cut at its last line break and parsed as one chunk.
const STREAM_BLOCK_BYTES: usize = 8 << 20;

/// A parsed chunk, or the first error in it.
type ChunkResult = Result<Chunk, DataError>;

/// Reads the body in blocks of whole lines, each parsed on the rayon pool while the next is read.
/// Returns the parsed chunks in file order and, if a quote character turned up, the unparsed rest
/// of the file from the first block holding it (a quoted field may hold a line break, so that
/// part is parsed as one chunk by the caller).
fn stream_chunks(
    f: &mut File,
    mut carry: Vec<u8>,
    mut eof: bool,
    pre: &Preamble,
    file: &str,
    block_bytes: usize,
) -> std::io::Result<(Vec<ChunkResult>, Option<Vec<u8>>)> {
    let slots: std::sync::Mutex<Vec<Option<ChunkResult>>> = Default::default();
    let mut quoted_tail = None;
    let mut io_result = Ok(());
    rayon::scope(|s| {
        let slots = &slots;
        loop {
            let mut block = Vec::with_capacity(block_bytes + carry.len() + 1);
            block.append(&mut carry);
            if !eof {
                match read_block(f, &mut block, block_bytes) {
                    Ok(e) => eof = e,
                    Err(e) => {
                        io_result = Err(e);
                        return;
                    }
                }
            }
            if block.contains(&b'"') {
                if let Err(e) = f.read_to_end(&mut block) {
                    io_result = Err(e);
                } else {
                    quoted_tail = Some(block);
                }
                return;
            }
            if !eof {
                // Keep the unfinished last line for the next block.
                match block.iter().rposition(|&b| b == b'\n') {
                    Some(i) => carry = block.split_off(i + 1),
                    None => {
                        carry = block;
                        continue;
                    }
                }
            }
            let k = {
                let mut v = slots.lock().expect("no parser panics");
                v.push(None);
                v.len() - 1
            };
            s.spawn(move |_| {
                let chunk = parse_chunk(&block, false, &pre.names, pre.time_index, file);
                slots.lock().expect("no parser panics")[k] = Some(chunk);
            });
            if eof {
                return;
            }
        }
    });
    io_result?;
    let parsed = slots
        .into_inner()
        .expect("no parser panics")
        .into_iter()
        .map(|c| c.expect("every spawned block was parsed"))
        .collect();
    Ok((parsed, quoted_tail))
}

/// Appends up to `max` bytes from `f` to `buf`; `true` when the file has ended.
fn read_block(f: &mut File, buf: &mut Vec<u8>, max: usize) -> std::io::Result<bool> {
    let n = (&mut *f).take(max as u64).read_to_end(buf)?;
    Ok(n < max)
}

/// Whether `bytes` holds a complete header line: a line ended by `\n` that is neither blank nor
/// a `#` metadata line.
fn header_complete(bytes: &[u8]) -> bool {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut lines = bytes.split(|&b| b == b'\n');
    let _unfinished = lines.next_back();
    lines.any(|l| !l.starts_with(b"#") && !l.iter().all(u8::is_ascii_whitespace))
}

/// Reads a flight-data CSV and returns it with its unit-sanity and sampling warnings.
pub fn read_csv_with_warnings(path: &Path) -> Result<(FlightRecord, Vec<Warning>), DataError> {
    let rec = read_csv(path)?;
    let warnings = rec.warnings();
    Ok((rec, warnings))
}

/// Parses flight-data CSV bytes; `file` names the source in error messages.
pub fn parse_csv_bytes(bytes: &[u8], file: &str) -> Result<FlightRecord, DataError> {
    parse_csv_bytes_mapped(bytes, file, None)
}

/// [`parse_csv_bytes`] through a column map (see [`read_csv_mapped`]).
pub fn parse_csv_bytes_mapped(
    bytes: &[u8],
    file: &str,
    map: Option<&ColumnMap>,
) -> Result<FlightRecord, DataError> {
    let pre = parse_preamble(bytes, file, map)?;
    let body = &bytes[pre.body_start..];
    let (chunks, quoted) = split_chunks(body);
    let parsed: Vec<Result<Chunk, DataError>> = chunks
        .par_iter()
        .map(|c| parse_chunk(c, quoted, &pre.names, pre.time_index, file))
        .collect();
    assemble(parsed, pre, file)
}

/// What precedes the data rows: metadata lines, the header's column names and where the body starts.
struct Preamble {
    metadata: Vec<String>,
    names: Vec<String>,
    time_index: usize,
    /// 1-based line number of the header.
    header_line: usize,
    /// Byte offset of the first body line (after the BOM, metadata and header).
    body_start: usize,
    /// Per column: the factor taking file values to SI (1 unless a column map converts it).
    factors: Vec<f64>,
}

/// Parses the metadata (`#` lines and blank lines before the header) and the header.
fn parse_preamble(
    bytes: &[u8],
    file: &str,
    map: Option<&ColumnMap>,
) -> Result<Preamble, DataError> {
    let bom = if bytes.starts_with(b"\xEF\xBB\xBF") {
        3
    } else {
        0
    };
    let mut pos = bom;
    let mut line = 0usize; // 1-based number of the line starting at `pos`, minus one
    let mut metadata = Vec::new();
    let header_span = loop {
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
    let names = parse_header(&bytes[header_span.0..header_span.1], file, line)?;
    let (names, factors) = match map {
        Some(m) => m.apply_to_header(&names, file)?,
        None => {
            let n = names.len();
            (names, vec![1.0; n])
        }
    };
    let time_index =
        names
            .iter()
            .position(|n| n == "time_s")
            .ok_or_else(|| DataError::MissingTime {
                file: file.to_string(),
                line,
                found: names.join(", "),
            })?;
    Ok(Preamble {
        metadata,
        names,
        time_index,
        header_line: line,
        body_start: (header_span.1 + 1).min(bytes.len()),
        factors,
    })
}

/// Joins chunks parsed with chunk-relative line numbers (1 = the chunk's first line) into the
/// record: shifts their line numbers by the lines before them, reports the first error in file
/// order and checks that time also increases across chunk boundaries.
fn assemble(
    parsed: Vec<Result<Chunk, DataError>>,
    pre: Preamble,
    file: &str,
) -> Result<FlightRecord, DataError> {
    let time_index = pre.time_index;
    let mut parts = Vec::with_capacity(parsed.len());
    let mut base = pre.header_line; // line number just before the chunk
    for p in parsed {
        match p {
            Ok(mut chunk) => {
                chunk.first_line += base;
                chunk.last_line += base;
                base += chunk.newlines;
                parts.push(chunk);
            }
            Err(e) => return Err(shift_lines(e, base)),
        }
    }
    let parts: Vec<Chunk> = parts.into_iter().filter(|c| c.rows > 0).collect();
    if parts.is_empty() {
        return Err(DataError::NoRows {
            file: file.to_string(),
            line: pre.header_line,
        });
    }
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
    let mut columns: Vec<Vec<f64>> = (0..pre.names.len())
        .map(|_| Vec::with_capacity(total))
        .collect();
    for part in parts {
        for (dst, src) in columns.iter_mut().zip(part.columns) {
            dst.extend_from_slice(&src);
        }
    }
    for (values, &factor) in columns.iter_mut().zip(&pre.factors) {
        if factor != 1.0 {
            values.iter_mut().for_each(|v| *v *= factor);
        }
    }
    let time_s = std::mem::take(&mut columns[time_index]);
    let mut rec = FlightRecord::new(time_s);
    rec.metadata = pre.metadata;
    for (i, (name, values)) in pre.names.into_iter().zip(columns).enumerate() {
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
fn split_chunks(body: &[u8]) -> (Vec<&[u8]>, bool) {
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
fn shift_lines(e: DataError, offset: usize) -> DataError {
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
        other => other,
    }
}

/// One parsed chunk: column-major values, its line span and the line breaks it holds.
struct Chunk {
    columns: Vec<Vec<f64>>,
    rows: usize,
    first_line: usize,
    last_line: usize,
    newlines: usize,
}

/// Parses one chunk with chunk-relative line numbers (its first line is line 1).
fn parse_chunk(
    bytes: &[u8],
    quoted: bool,
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
fn scan_cell(bytes: &[u8], p: usize) -> (Option<f64>, usize) {
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
fn eight_digits(word: u64) -> bool {
    let above = word.wrapping_add(0x4646_4646_4646_4646); // sets bit 7 for bytes > b'9'
    let below = word.wrapping_sub(0x3030_3030_3030_3030); // sets bit 7 for bytes < b'0'
    (above | below) & 0x8080_8080_8080_8080 == 0
}

/// The value of eight ASCII digits packed little-endian (first digit in the lowest byte), by
/// three multiplications: pairs, then quads, then the two quads.
#[inline]
fn eight_digit_value(word: u64) -> u64 {
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
fn long_decimal(w: u64, k: usize) -> Option<f64> {
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

    #[test]
    fn long_decimal_path_agrees_bit_for_bit_with_std_parse() {
        // 300k shortest round-trip strings of random doubles (16–17 digits) and random 16–19
        // digit decimals: whenever the long path answers it must equal std's correctly rounded
        // result, and it must answer for the vast majority.
        // Hard cases first: near powers of two and exact midpoints between doubles.
        for s in [
            "0.50000000000000001",
            "0.49999999999999997",
            "1.0000000000000001",
            "0.99999999999999994",
            "0.99999999999999989",
            "9007199254740993",
            "9007199254740995",
            "2.2250738585072014",
            "1844674407370955161",
            "0.1000000000000000055511151231257827",
            "7.3786976294838206464",
        ] {
            let (v, _) = scan_cell(s.as_bytes(), 0);
            assert_eq!(
                v.map(f64::to_bits),
                s.parse::<f64>().ok().map(f64::to_bits),
                "{s}"
            );
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let (mut answered, mut total) = (0, 0);
        for case in 0..300_000 {
            let s = if case % 2 == 0 {
                let x: f64 = rng.gen_range(-1e3..1e3) * 10f64.powi(rng.gen_range(-6..3));
                format!("{x:?}")
            } else {
                let digits = rng.gen_range(16..=19);
                let mut s = String::new();
                let dot = rng.gen_range(0..digits);
                for d in 0..digits {
                    if d == dot {
                        s.push('.');
                    }
                    s.push(char::from(b'0' + rng.gen_range(0..10u8)));
                }
                s
            };
            if s.contains('e') {
                continue;
            }
            let (v, end) = scan_cell(s.as_bytes(), 0);
            assert_eq!(end, s.len());
            let std = s.parse::<f64>().unwrap();
            assert_eq!(v.map(f64::to_bits), Some(std.to_bits()), "input {s}");
            total += 1;
            let digits: String = s.chars().filter(char::is_ascii_digit).collect();
            let w: u64 = digits.parse().unwrap();
            let k = s.len() - s.find('.').map_or(s.len(), |i| i + 1);
            if w > (1u64 << 53) && k < 23 {
                if let Some(x) = long_decimal(w, k) {
                    answered += 1;
                    assert_eq!(x.to_bits(), std.abs().to_bits(), "long path, input {s}");
                }
            }
        }
        assert!(
            answered > total / 3,
            "long path answered {answered} of {total}"
        );
    }

    /// Reads `text` through the block-wise path with tiny blocks, and in memory.
    fn both_ways(text: &str) -> (String, String) {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("f.csv");
        fs::write(&path, text).expect("write");
        let blocks = read_csv_in_blocks(File::open(&path).expect("open"), "f.csv", 97, None);
        let blocks = match blocks {
            Ok(r) => format!("{:?} {:?} {:?}", r.time_s, r.columns, r.metadata),
            Err(BlockReadError::Data(e)) => e.to_string(),
            Err(BlockReadError::Io(e)) => panic!("io: {e}"),
        };
        let whole = match parse_csv_bytes(text.as_bytes(), "f.csv") {
            Ok(r) => format!("{:?} {:?} {:?}", r.time_s, r.columns, r.metadata),
            Err(e) => e.to_string(),
        };
        (blocks, whole)
    }

    #[test]
    fn block_wise_read_gives_the_same_record_and_errors_as_in_memory() {
        // 97-byte blocks cut almost every line of these files at a different place; records
        // and error messages (with their line numbers) must be identical to the in-memory parse.
        let mut good = String::from("# meta\n\ntime_s,q_rad_s,alpha_rad\n");
        for i in 0..400 {
            let t = f64::from(i) * 0.01;
            good += &format!(
                "{t:.2},{:?},{:?}\n",
                (t * 1.3).sin() * 0.123,
                0.05 + t.cos() / 7.0
            );
        }
        let cases = [
            good.clone(),
            good.replace("\n1.20,", "\n1.2x,"),
            good.replace("\n2.50,", "\n2.50,1,2,3\n2.51,"),
            good.replace("\n3.00,", "\n2.00,"),
            good.clone() + "4.0,\"1.5\",2\n",
            good.replace("\n1.00,", "\n1.00,\"1\n\",2\n1.001,"),
            good.trim_end().to_string(),
            "time_s,q\n".to_string(),
            "# only\n".to_string(),
            good.replace("time_s", "t"),
        ];
        for (k, text) in cases.iter().enumerate() {
            let (blocks, whole) = both_ways(text);
            assert_eq!(blocks, whole, "case {k}");
            // Cases 1-3 carry an error late in the file, reported as `file:line:`.
            if [1, 2, 3].contains(&k) {
                assert!(blocks.starts_with("f.csv:"), "case {k}: {blocks}");
            }
        }
    }

    #[test]
    fn swar_digit_scan_reads_every_eight_digit_group() {
        for s in [
            "0.12345678",
            "-3.1234567890123456",
            "12.00000000",
            "0.99999999999",
        ] {
            let (v, end) = scan_cell(s.as_bytes(), 0);
            assert_eq!(end, s.len());
            assert_eq!(
                v.map(f64::to_bits),
                s.parse::<f64>().ok().map(f64::to_bits),
                "{s}"
            );
        }
        assert!(!eight_digits(u64::from_le_bytes(*b"1234567,")));
        assert!(!eight_digits(u64::from_le_bytes(*b"/1234567")));
        assert!(!eight_digits(u64::from_le_bytes(*b"123:4567")));
        assert_eq!(
            eight_digit_value(u64::from_le_bytes(*b"12345678")),
            12_345_678
        );
    }
}
