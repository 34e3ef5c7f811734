//! The flight-data CSV writer: `#` metadata lines, the header, rows in shortest round-trip form, written
//! atomically.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::Path;

use super::super::error::DataError;
use super::super::record::FlightRecord;

/// Writes the record as CSV through a temporary file in the same directory, synced to disk and then
/// renamed over `path`: readers see either the old file or the complete new one, never a partial one.
///
/// A missing parent folder is created (as `mkdir -p` would).
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
    let io_err = |action: &'static str| DataError::io(path, action);
    std::fs::create_dir_all(&dir).map_err(io_err("cannot create the output's folder"))?;
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
