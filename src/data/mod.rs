//! Flight-data schema, CSV and MAVLink readers/writers, units and validation.
//!
//! The exchange format is the CSV schema of docs/data.md ([`SCHEMA_COLUMNS`]): SI units, radians,
//! `time_s` strictly increasing, unknown columns kept. [`FlightRecord`] is its in-memory form.

mod channel;
mod columns;
mod csv_io;
mod error;
mod record;
mod resample;

pub use channel::{Channel, UnknownChannel};
pub use columns::{did_you_mean, resolve_column, unit_names, ColumnMap, ColumnMapping, Dimension};
pub use csv_io::{
    parse_csv_bytes, parse_csv_bytes_mapped, read_csv, read_csv_mapped, read_csv_with_warnings,
    write_csv_atomic, write_csv_to,
};
pub use error::{DataError, Warning, WarningKind, IN_MEMORY};
pub use record::{
    control_moments, sampling_warning, time_unit_suspicion, unit_warnings, ControlMoment,
    FlightRecord, G0_M_S2, SCHEMA_COLUMNS, SIGN_T_RATIO,
};
pub use resample::{
    dropout_starts, resample_uniform, uniform_pieces, UniformPieces, RESAMPLE_METHOD,
};

pub mod servo_map;
pub mod tlog;

pub use servo_map::ServoMap;
pub use tlog::{
    parse_tlog_bytes, read_tlog, AirspeedKind, Stretch, StretchChoice, TlogOptions, TlogReport,
};
pub mod segments;
pub use segments::{
    find_segments, scan_segments, segment_window, ManeuverKind, Rejected, Segment, SegmentOptions,
    SegmentRef, SegmentScan, SEGMENT_LEAD_IN_S, SEGMENT_TAIL_S,
};
pub mod check;
pub use check::{check_compatibility, skew_bound_s, CheckOptions, CheckReport, Estimate};
