//! Flight-data CSV reader and atomic writer (schema: docs/data.md).
//!
//! Reading: `#` lines before the header are metadata; the header names the columns (`time_s`
//! required, any order, unknown columns kept); every data cell must be a finite number. The body is
//! split at line boundaries into chunks parsed in parallel (each chunk with the `csv` crate's
//! `ByteRecord`), unless it holds a quote character, in which case one chunk keeps quoting exact.
//!
//! Text files as data systems and textbooks also write them are read too: columns separated by spaces
//! or tabs instead of commas (the first line that is not metadata has no comma), and files without a
//! header row (that line is all numbers). A headerless file's columns are named by their position,
//! `1`, `2`, …, which a column map renames (`1 = { to = "time_s" }`). `%` lines before the header are
//! metadata as `#` lines are, and a row of units under the header is kept as metadata. A MATLAB MAT-file (`.mat`) is read
//! as such a headerless file: its matrix of samples × channels ([`mat`]).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use rayon::prelude::*;

use super::columns::{ColumnMap, PlacedDerivedColumn};
use super::error::{DataError, Warning};
use super::record::FlightRecord;

mod chunk;
mod mat;
mod text;
mod write;
use chunk::{parse_chunk, shift_lines, split_chunks, Chunk, FileRange};
use text::{comment, is_numbers_row, is_units_row, whitespace_separated, whitespace_to_commas};
pub use write::{write_csv_atomic, write_csv_to};

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
    let mut rec = read_columns_mapped(path, map)?;
    if let Some(map) = map {
        map.finish(&mut rec, &path.display().to_string())?;
    }
    Ok(rec)
}

/// [`read_csv_mapped`]'s columns, renamed and converted, before the map's record-wide step.
fn read_columns_mapped(path: &Path, map: Option<&ColumnMap>) -> Result<FlightRecord, DataError> {
    let io_err = |action: &'static str| DataError::io(path, action);
    if mat::is_mat_file(path) {
        let (text, note) = mat::matrix_as_text(path)?;
        let file = path.display().to_string();
        let mut rec = parse_csv_bytes_mapped(&text, &file, map).map_err(|e| match e {
            DataError::NoHeader { columns, .. } => DataError::Mat {
                file,
                message: format!(
                    "{}, without column names: name its {columns} channels by position in a column map (`--columns MAP.toml` with e.g. `1 = {{ to = \"time_s\" }}`, \
                     `2 = {{ to = \"elevator_rad\", unit = \"deg\" }}`)",
                    note.trim()
                ),
            },
            other => other,
        })?;
        rec.metadata.insert(0, note);
        return Ok(rec);
    }
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
    if whitespace_separated(&head) {
        // Rare in files this large; converted whole rather than block by block.
        f.read_to_end(&mut head).map_err(BlockReadError::Io)?;
        return parse_csv_bytes_mapped(&head, file, map).map_err(BlockReadError::Data);
    }
    let pre = parse_preamble(&head, file, map).map_err(BlockReadError::Data)?;
    let carry = head.split_off(pre.body_start);
    let (mut parsed, quoted_tail) =
        stream_chunks(&mut f, carry, eof, &pre, file, block_bytes).map_err(BlockReadError::Io)?;
    if let Some(tail) = quoted_tail {
        parsed.push(parse_chunk(
            &tail,
            true,
            &pre.names,
            &pre.ranges,
            pre.time_index,
            file,
        ));
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
                let chunk =
                    parse_chunk(&block, false, &pre.names, &pre.ranges, pre.time_index, file);
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
    // the header and the line after it (a units row, or the first data row)
    lines
        .filter(|l| comment(l).is_none() && !l.iter().all(u8::is_ascii_whitespace))
        .nth(1)
        .is_some()
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
    let spaced;
    let bytes = if whitespace_separated(bytes) {
        spaced = whitespace_to_commas(bytes);
        &spaced[..]
    } else {
        bytes
    };
    let pre = parse_preamble(bytes, file, map)?;
    let body = &bytes[pre.body_start..];
    let (chunks, quoted) = split_chunks(body);
    let parsed: Vec<Result<Chunk, DataError>> = chunks
        .par_iter()
        .map(|c| parse_chunk(c, quoted, &pre.names, &pre.ranges, pre.time_index, file))
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
    /// Columns a column map forms as weighted sums of the file's columns (their values as read).
    derived: Vec<PlacedDerivedColumn>,
    /// Per column: its plausible range as the file holds it (a bounded schema column), checked while parsing.
    ranges: Vec<Option<FileRange>>,
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
        if let Some(meta) = comment(text) {
            metadata.push(String::from_utf8_lossy(meta).into_owned());
        } else if !text.iter().all(u8::is_ascii_whitespace) {
            break (pos, end);
        }
        pos = (end + 1).min(bytes.len());
    };
    let first_row = trim_cr(&bytes[header_span.0..header_span.1]);
    let headerless = is_numbers_row(first_row);
    let names = if headerless {
        let n = first_row.split(|&b| b == b',').count();
        (1..=n).map(|k| k.to_string()).collect()
    } else {
        parse_header(&bytes[header_span.0..header_span.1], file, line)?
    };
    let (names, factors, derived) = match map {
        Some(m) => {
            let h = m.apply_to_header(&names, file).map_err(|e| match e {
                DataError::MapColumnMissing {
                    file, map, columns, ..
                } if headerless => DataError::MapColumnMissing {
                    file,
                    map,
                    columns,
                    present: format!(
                        "1 to {} by position, as it has no header row (line {line} is numbers)",
                        names.len()
                    ),
                },
                e => e,
            })?;
            (h.names, h.factors, h.derived)
        }
        None if headerless => {
            return Err(DataError::NoHeader {
                file: file.to_string(),
                line,
                columns: names.len(),
            })
        }
        None => {
            let n = names.len();
            (names, vec![1.0; n], Vec::new())
        }
    };
    // A headerless file's first row is data: the body starts there, after an implied header line. A row of
    // units under the header (no field a number, as data systems export them) is kept as metadata.
    let (mut header_line, mut body_start) = if headerless {
        (line - 1, header_span.0)
    } else {
        (line, (header_span.1 + 1).min(bytes.len()))
    };
    if !headerless && body_start < bytes.len() {
        let end = next_line_end(bytes, body_start);
        let row = trim_cr(&bytes[body_start..end]);
        if is_units_row(row, names.len()) {
            metadata.push(format!(" units: {}", String::from_utf8_lossy(row).trim()));
            header_line += 1;
            body_start = (end + 1).min(bytes.len());
        }
    }
    let time_index =
        names
            .iter()
            .position(|n| n == "time_s")
            .ok_or_else(|| DataError::MissingTime {
                file: file.to_string(),
                line,
                found: names.join(", "),
            })?;
    let ranges = names
        .iter()
        .zip(&factors)
        .map(|(name, &factor)| FileRange::of(name, factor))
        .collect();
    Ok(Preamble {
        metadata,
        names,
        time_index,
        header_line,
        body_start,
        factors,
        derived,
        ranges,
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
                chunk.repeated.iter_mut().for_each(|l| *l += base);
                base += chunk.newlines;
                parts.push(chunk);
            }
            Err(e) => return Err(shift_lines(e, base)),
        }
    }
    let mut repeated: Vec<usize> = parts.iter().flat_map(|c| c.repeated.clone()).collect();
    let mut parts: Vec<Chunk> = parts.into_iter().filter(|c| c.rows > 0).collect();
    if parts.is_empty() {
        return Err(DataError::NoRows {
            file: file.to_string(),
            line: pre.header_line,
        });
    }
    // A row repeated across a chunk boundary: the later chunk's first row goes.
    for k in 1..parts.len() {
        let (a, b) = (&parts[k - 1], &parts[k]);
        if b.rows > 0 && (0..b.columns.len()).all(|c| b.columns[c][0] == a.columns[c][a.rows - 1]) {
            repeated.push(b.first_line);
            let b = &mut parts[k];
            b.columns.iter_mut().for_each(|c| {
                c.remove(0);
            });
            b.rows -= 1;
            b.first_line += 1;
        }
    }
    let parts: Vec<Chunk> = parts.into_iter().filter(|c| c.rows > 0).collect();
    for w in parts.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (ta, tb) = (a.columns[time_index][a.rows - 1], b.columns[time_index][0]);
        if tb <= ta {
            return Err(DataError::time_not_increasing(
                file,
                (b.first_line, tb),
                (a.last_line, ta),
            ));
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
    let derived: Vec<(String, Vec<f64>)> = pre
        .derived
        .iter()
        .map(|d| {
            let values = (0..total)
                .map(|k| d.terms.iter().map(|&(c, w)| w * columns[c][k]).sum())
                .collect();
            (d.to.clone(), values)
        })
        .collect();
    for (values, &factor) in columns.iter_mut().zip(&pre.factors) {
        if factor != 1.0 {
            values.iter_mut().for_each(|v| *v *= factor);
        }
    }
    let time_s = std::mem::take(&mut columns[time_index]);
    let mut rec = FlightRecord::new(time_s);
    // A note of an earlier read, written back with the record, is history, not news about this file.
    rec.metadata = pre
        .metadata
        .into_iter()
        .map(
            |m| match m.strip_prefix(super::record::REPEATED_ROWS_NOTE) {
                Some(rest) => format!(" (when read before) {rest}"),
                None => m,
            },
        )
        .collect();
    if !repeated.is_empty() {
        repeated.sort_unstable();
        rec.metadata.push(repeated_rows_note(&repeated));
    }
    for (i, (name, values)) in pre.names.into_iter().zip(columns).enumerate() {
        if i != time_index {
            rec.columns.push((name, values));
        }
    }
    rec.columns.extend(derived);
    if let Some(v) = rec.column(super::Channel::Airspeed) {
        if v.iter().all(|&v| v <= 0.0) {
            return Err(DataError::NoAirspeed {
                file: file.to_string(),
                rows: v.len(),
            });
        }
    }
    Ok(rec)
}

/// The metadata line that records the repeated rows a reader dropped (file line numbers, ascending): it
/// travels with the record, is written back as a `#` line and comes out of [`FlightRecord::warnings`].
fn repeated_rows_note(lines: &[usize]) -> String {
    let shown: Vec<String> = lines.iter().take(5).map(|l| l.to_string()).collect();
    format!(
        "{}{} repeated row(s) dropped, each the same time and values as the row before (line {}{})",
        super::record::REPEATED_ROWS_NOTE,
        lines.len(),
        shown.join(", "),
        if lines.len() > 5 { ", …" } else { "" }
    )
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

#[cfg(test)]
mod tests;
