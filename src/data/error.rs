//! Errors and warnings of the `data` module.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in-memory records are reported from when they did not come from a file.
pub const IN_MEMORY: &str = "<in-memory record>";

/// A hard problem with flight data: the data cannot be used as it is.
///
/// Every variant names the file and, where it applies, the 1-based line number and the column.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// The file could not be read or written.
    #[error("{file}: {action}: {source}")]
    Io {
        file: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The file holds no header row at all.
    #[error("{file}: the file is empty (expected a header row starting with `time_s`)")]
    Empty { file: String },
    /// The header exists but no data row follows it.
    #[error("{file}: the header (line {line}) is not followed by any data row")]
    NoRows { file: String, line: usize },
    /// The header lacks the required `time_s` column.
    #[error(
        "{file}:{line}: the header has no `time_s` column (found: {found}){}; every flight-data CSV needs time in \
         seconds",
        separator_hint(found)
    )]
    MissingTime {
        file: String,
        line: usize,
        found: String,
    },
    /// The first line that is not metadata is numbers, and no column map names the columns.
    #[error("{file}:{line}: the file has no header row (line {line} is {columns} numbers); name its columns by position in a column map (`--columns MAP.toml` with e.g. `1 = {{ to = \"time_s\" }}`, `2 = {{ to = \"elevator_rad\", unit = \"deg\" }}`), or add a header row starting with `time_s`")]
    NoHeader {
        file: String,
        line: usize,
        columns: usize,
    },
    /// A column name appears twice in the header.
    #[error("{file}:{line}: column `{column}` appears more than once in the header")]
    DuplicateColumn {
        file: String,
        line: usize,
        column: String,
    },
    /// A row has a different number of fields than the header.
    #[error("{file}:{line}: row has {found} fields but the header has {expected}")]
    Ragged {
        file: String,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// A cell is not a number.
    #[error("{file}:{line}: column `{column}`: `{cell}` is not a number")]
    NonNumeric {
        file: String,
        line: usize,
        column: String,
        cell: String,
    },
    /// A cell is NaN or infinite.
    #[error("{file}:{line}: column `{column}`: value `{cell}` is not finite (NaN/inf are not allowed; drop or fill the sample)")]
    NonFinite {
        file: String,
        line: usize,
        column: String,
        cell: String,
    },
    /// A value outside what its schema column can physically hold (`Channel::plausible_range`).
    #[error("{file}:{line}: column `{column}`: {value} is outside what this column can hold ({min} to {max} in its \
             unit); a corrupt sample, or a unit that a column map (`--columns`) should convert")]
    Implausible {
        file: String,
        line: usize,
        column: String,
        /// The value as the file holds it, and in SI where a column map converts it.
        value: String,
        min: f64,
        max: f64,
    },
    /// An airspeed column that is zero on every row: not a record of flight.
    #[error("{file}: column `airspeed_m_s` is 0 on every one of its {rows} rows: this is not a record of an \
             aircraft in flight (a pitot not connected?); fix the column, or leave it out of the file")]
    NoAirspeed { file: String, rows: usize },
    /// A fit on the data ended with a non-finite cost or residual: its estimates are no estimates.
    #[error("{what} diverged: the residual of {columns} is not finite; the record holds values the model cannot \
             follow (a corrupt sample, a wrong unit?)")]
    Diverged {
        /// The fit, e.g. "the flight-path reconstruction of f.csv".
        what: String,
        /// The outputs whose residual is not finite.
        columns: String,
    },
    /// Time does not strictly increase.
    #[error("{file}:{line}: column `time_s`: {time_s} {relation} the previous time {previous_s} (line {previous_line}); time must strictly increase")]
    TimeNotIncreasing {
        file: String,
        line: usize,
        time_s: f64,
        previous_s: f64,
        previous_line: usize,
        /// "repeats" (duplicated time) or "goes back from" (time running backwards).
        relation: &'static str,
    },
    /// A column of an in-memory record has the wrong length.
    #[error("{file}: column `{column}` has {found} values but `time_s` has {expected}")]
    LengthMismatch {
        file: String,
        column: String,
        expected: usize,
        found: usize,
    },
    /// A tool needs a column the data does not have.
    #[error(
        "column `{column}` is required {why}, but the data has no such column (present: {present})"
    )]
    MissingColumn {
        column: String,
        why: String,
        present: String,
    },
    /// The CSV parser failed (e.g. invalid UTF-8 in the header).
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    /// A segment number that `segments` did not list for this file.
    #[error("{file}: there is no segment {segment}; `flightid segments` finds {found} in this file{listing}")]
    NoSuchSegment {
        file: String,
        segment: usize,
        found: usize,
        /// ` (1 … N)` or empty.
        listing: String,
    },
    /// The record, or every piece of it between dropouts, is shorter than an estimator can use.
    #[error("{}", too_short(*samples, *span_s, *dropouts, *min_s))]
    TooShort {
        samples: usize,
        span_s: f64,
        dropouts: usize,
        min_s: f64,
    },
    /// An argument is out of range (e.g. a non-positive resampling rate).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// A MATLAB MAT-file could not be read as flight data.
    #[error("{file}: {message}")]
    Mat { file: String, message: String },
    /// A MAVLink telemetry log could not be turned into a flight record.
    #[error("{file}: {message}")]
    Tlog { file: String, message: String },
    /// A column map (`--columns`) is invalid: unknown unit or target column, a unit of the wrong kind.
    #[error("column map {map}: {message}", map = map.display())]
    ColumnMap { map: PathBuf, message: String },
    /// A column map names columns the CSV does not have.
    #[error("{file}: the column map {map} names {columns}, which the file does not have (its columns: {present})", map = map.display())]
    MapColumnMissing {
        file: String,
        map: PathBuf,
        columns: String,
        present: String,
    },
    /// A servo mapping file (`--servo-map`) is missing or invalid.
    #[error("servo mapping `{servo_map}` ({file}): {message}")]
    ServoMap {
        servo_map: String,
        file: PathBuf,
        message: String,
    },
}

/// What kind of soft problem a [`Warning`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WarningKind {
    /// A `_rad` column holds values that look like degrees.
    LooksLikeDegrees,
    /// A `_rad_s` column holds values that look like deg/s.
    LooksLikeDegreesPerSecond,
    /// An airspeed looks like knots or ft/s instead of m/s.
    LooksLikeKnotsOrFeet,
    /// Accelerations look like g instead of m/s².
    LooksLikeG,
    /// `time_s` steps look like milliseconds or microseconds instead of seconds.
    LooksLikeMilliseconds,
    /// `throttle` lies outside 0..1 (percent?).
    ThrottleOutOfRange,
    /// A column has the other sign convention (a load factor for `az_m_s2`, a rate of the other sign).
    OppositeSign,
    /// Sample spacing is not uniform.
    IrregularSampling,
    /// The reader dropped rows that repeat the row before them (same time, same values).
    RepeatedRows,
    /// A flight-state sensor that never moves over the whole record: stuck or unplugged.
    StuckSensor,
    /// Anything else the reader wants the user to know (e.g. skipped bytes in a tlog).
    Other,
}

/// A soft problem: the data can be used, but the user should look at the evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    /// The kind of problem.
    pub kind: WarningKind,
    /// The column concerned, if any.
    pub column: Option<String>,
    /// The evidence in words and numbers.
    pub message: String,
}

/// The message of [`DataError::TooShort`]: the record's length, and its dropouts only when it has some.
fn too_short(samples: usize, span_s: f64, dropouts: usize, min_s: f64) -> String {
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    let length = format!("{}, {span_s} s", plural(samples, "sample"));
    if dropouts == 0 {
        format!("the record is {length} long; at least {min_s} s is needed")
    } else {
        format!(
            "no piece of the record ({length}) between its {} is {min_s} s long; at least {min_s} s without a \
             dropout is needed",
            plural(dropouts, "dropout")
        )
    }
}

/// For a header read as one column holding `;`: advice that the file seems to use `;` as its separator (a header
/// separated by spaces or tabs is read as such, docs/data.md).
fn separator_hint(header: &str) -> &'static str {
    if header.contains(';') && !header.contains(',') {
        "; the file seems to separate its columns with `;`, and flightid reads comma-separated files (replace the \
         separators with commas)"
    } else {
        ""
    }
}

impl DataError {
    /// Turns an I/O error on `path` into [`DataError::Io`], `action` saying what failed:
    /// `.map_err(DataError::io(path, "cannot read the column map"))`.
    pub(crate) fn io(
        path: &Path,
        action: &'static str,
    ) -> impl FnOnce(std::io::Error) -> DataError {
        let file = path.to_path_buf();
        move |source| DataError::Io {
            file,
            action,
            source,
        }
    }

    /// [`DataError::TimeNotIncreasing`] for the sample at `time_s` (line `line`) that does not exceed the one
    /// before it, `previous_s` (line `previous_line`).
    pub(crate) fn time_not_increasing(
        file: &str,
        (line, time_s): (usize, f64),
        (previous_line, previous_s): (usize, f64),
    ) -> Self {
        DataError::TimeNotIncreasing {
            file: file.to_string(),
            line,
            time_s,
            previous_s,
            previous_line,
            relation: if time_s == previous_s {
                "repeats"
            } else {
                "goes back from"
            },
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.column {
            Some(c) => write!(f, "column `{c}`: {}", self.message),
            None => write!(f, "{}", self.message),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_separated_by_semicolons_is_named_as_such() {
        let missing = |found: &str| DataError::MissingTime {
            file: "f.csv".into(),
            line: 1,
            found: found.into(),
        };
        let e = missing("time_s;elevator_rad").to_string();
        assert!(
            e.contains("separate its columns with `;`") && e.contains("comma-separated"),
            "{e}"
        );
        let e = missing("t, elevator_rad").to_string();
        assert!(!e.contains("separate"), "{e}");
    }

    #[test]
    fn a_short_record_speaks_of_dropouts_only_when_it_has_some() {
        let short = |samples, span_s, dropouts| {
            DataError::TooShort {
                samples,
                span_s,
                dropouts,
                min_s: 2.0,
            }
            .to_string()
        };
        assert_eq!(
            short(1, 0.0, 0),
            "the record is 1 sample, 0 s long; at least 2 s is needed"
        );
        assert_eq!(
            short(300, 6.0, 2),
            "no piece of the record (300 samples, 6 s) between its 2 dropouts is 2 s long; at least 2 s without a \
             dropout is needed"
        );
    }
}
