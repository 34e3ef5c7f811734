//! MAVLink telemetry log (`.tlog`) reader: frames → messages → the flight-data schema.
//!
//! A `.tlog` (as written by MAVProxy / Mission Planner / QGroundControl) is a sequence of
//! `[8-byte big-endian µs Unix timestamp][MAVLink v1 or v2 frame]`. Framing, CRC (X.25 / MCRF4XX
//! with the message's CRC_EXTRA, MAVLink serialization spec) and resynchronisation after corrupt
//! bytes are done here; payloads are decoded by the `mavlink` crate (`Message::parse`).
//!
//! Mapping onto the schema (docs/data.md), all onto one uniform grid:
//! - ATTITUDE → `phi_rad theta_rad psi_rad` (yaw unwrapped), `p_rad_s q_rad_s r_rad_s`;
//! - HIGHRES_IMU (m/s²) or else SCALED_IMU / RAW_IMU (milli-g) → `ax_m_s2 ay_m_s2 az_m_s2`
//!   (body FRD specific force, 1-g level flight gives az ≈ −9.81);
//! - VFR_HUD → `airspeed_m_s` (the autopilot's equivalent airspeed made true with the standard atmosphere at the
//!   logged altitude, or taken as true with [`AirspeedKind::True`]), `altitude_m`
//!   (MSL), and `throttle` (percent/100) when the servo mapping maps no throttle servo;
//! - AOA_SSA (degrees) → `alpha_rad beta_rad`;
//! - SERVO_OUTPUT_RAW (port 0) → `elevator_rad aileron_rad rudder_rad throttle` via [`ServoMap`].

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use mavlink::dialects::ardupilotmega::MavMessage;
use mavlink::{MavlinkVersion, Message};

use super::channel::Channel;
use super::error::{DataError, Warning, WarningKind};
use super::record::{FlightRecord, G0_M_S2};
use super::servo_map::ServoMap;

mod frame;
mod options;
pub use frame::{scan_frames, Frame, ScanStats};
pub use options::{true_from_equivalent, AirspeedKind, StretchChoice, TlogOptions};

/// A step back in log time up to this (µs) is jitter between message streams, not a jump back.
const BACKWARD_JITTER_US: u64 = 50_000;
/// A pause in the ATTITUDE stream longer than this many median intervals breaks the log: nothing is
/// interpolated across it.
const GAP_INTERVALS: f64 = 5.0;
/// Log times after 2100-01-01 (µs since the Unix epoch) are not microsecond timestamps.
const LATEST_EPOCH_US: u64 = 4_102_444_800_000_000;
/// Log times after 2000-01-01 (µs since the Unix epoch): a plausible ground-station clock.
const EARLIEST_EPOCH_US: u64 = 946_684_800_000_000;
/// An ATTITUDE rate above this (Hz, in log time) means the timestamps are not microseconds.
const MAX_ATTITUDE_RATE_HZ: f64 = 5000.0;

/// A stretch of a log over which its time base is continuous (no gap longer than a few ATTITUDE intervals, no
/// jump back).
#[derive(Debug, Clone, PartialEq)]
pub struct Stretch {
    /// First and last ATTITUDE time, s after the system's first ATTITUDE in log order (negative after a jump
    /// back to before it).
    pub start_s: f64,
    /// See `start_s`.
    pub end_s: f64,
    /// ATTITUDE samples in it.
    pub attitude_samples: usize,
    /// What ended the stretch before it (`None` for the first).
    pub after: Option<String>,
}

impl std::fmt::Display for Stretch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.2} to {:.2} s, {} ATTITUDE samples",
            self.start_s, self.end_s, self.attitude_samples
        )?;
        if let Some(a) = &self.after {
            write!(f, " (after {a})")?;
        }
        Ok(())
    }
}

/// A system seen in the log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SystemSummary {
    /// System id.
    pub sysid: u8,
    /// ATTITUDE messages from it.
    pub attitude_messages: usize,
    /// All valid frames from it.
    pub messages: usize,
}

/// What [`read_tlog`] produced.
#[derive(Debug, Clone)]
pub struct TlogReport {
    /// The flight record on the uniform grid.
    pub record: FlightRecord,
    /// The system id extracted.
    pub sysid: u8,
    /// Every system seen, by id.
    pub systems: Vec<SystemSummary>,
    /// Frame counts.
    pub stats: ScanStats,
    /// Valid frames per message name (all systems).
    pub messages_by_name: BTreeMap<String, usize>,
    /// Soft problems (skipped bytes, missing message types).
    pub warnings: Vec<Warning>,
    /// The stretches of continuous log time of the extracted system.
    pub stretches: Vec<Stretch>,
    /// Which of them the record holds (index into `stretches`).
    pub stretch: usize,
}

/// Time series of one system, collected from its messages (times in µs).
#[derive(Default)]
struct Series {
    attitude: Vec<(u64, [f64; 6])>,
    highres_imu: Vec<(u64, [f64; 3])>,
    scaled_imu: Vec<(u64, [f64; 3])>,
    raw_imu: Vec<(u64, [f64; 3])>,
    vfr_hud: Vec<(u64, [f64; 3])>,
    aoa_ssa: Vec<(u64, [f64; 2])>,
    servo: Vec<(u64, [f64; 8])>,
}

impl Series {
    /// Sorts every stream by time (see [`tidy`]).
    fn tidy(&mut self) {
        tidy(&mut self.attitude);
        tidy(&mut self.highres_imu);
        tidy(&mut self.scaled_imu);
        tidy(&mut self.raw_imu);
        tidy(&mut self.vfr_hud);
        tidy(&mut self.aoa_ssa);
        tidy(&mut self.servo);
    }

    /// The samples of every stream within `[from_us, to_us]`.
    fn window(&self, from_us: u64, to_us: u64) -> Series {
        fn cut<const N: usize>(s: &[(u64, [f64; N])], a: u64, b: u64) -> Vec<(u64, [f64; N])> {
            s.iter()
                .filter(|(t, _)| (a..=b).contains(t))
                .copied()
                .collect()
        }
        Series {
            attitude: cut(&self.attitude, from_us, to_us),
            highres_imu: cut(&self.highres_imu, from_us, to_us),
            scaled_imu: cut(&self.scaled_imu, from_us, to_us),
            raw_imu: cut(&self.raw_imu, from_us, to_us),
            vfr_hud: cut(&self.vfr_hud, from_us, to_us),
            aoa_ssa: cut(&self.aoa_ssa, from_us, to_us),
            servo: cut(&self.servo, from_us, to_us),
        }
    }
}

/// Smallest default grid step, µs (1 kHz).
const MIN_DEFAULT_STEP_US: f64 = 1000.0;

/// Message ids this reader decodes (others are only counted).
const ATTITUDE_ID: u32 = 30;
const SCALED_IMU_ID: u32 = 26;
const RAW_IMU_ID: u32 = 27;
const HIGHRES_IMU_ID: u32 = 105;
const VFR_HUD_ID: u32 = 74;
const SERVO_OUTPUT_RAW_ID: u32 = 36;
const AOA_SSA_ID: u32 = 11020;

/// Reads a `.tlog` file into the flight-data schema (see the module documentation).
pub fn read_tlog(
    path: &Path,
    servo_map: Option<&ServoMap>,
    options: &TlogOptions,
) -> Result<TlogReport, DataError> {
    let bytes =
        std::fs::read(path).map_err(DataError::io(path, "cannot read the telemetry log"))?;
    parse_tlog_bytes(&bytes, &path.display().to_string(), servo_map, options)
}

/// [`read_tlog`] on bytes in memory; `file` names the source in errors and metadata.
pub fn parse_tlog_bytes(
    bytes: &[u8],
    file: &str,
    servo_map: Option<&ServoMap>,
    options: &TlogOptions,
) -> Result<TlogReport, DataError> {
    let err = |message: String| DataError::Tlog {
        file: file.to_string(),
        message,
    };
    if let Some(r) = options.rate_hz {
        if !(r.is_finite() && r > 0.0) {
            return Err(DataError::InvalidArgument(format!(
                "output rate must be a positive number of Hz, got {r}"
            )));
        }
    }
    // Frames in log order; a jump back in log time starts a new run (what came before it is not merged with
    // what came after it by sorting).
    let mut per_run: BTreeMap<(u8, usize), (Series, usize)> = BTreeMap::new();
    let mut by_id: HashMap<u32, usize> = HashMap::new();
    let mut run = 0usize;
    let mut jumps_back: Vec<String> = Vec::new();
    let (mut steps, mut steps_back) = (0usize, 0usize);
    let mut latest_us: Option<u64> = None;
    let mut previous_us: Option<u64> = None;
    let stats = scan_frames(bytes, |frame| {
        let t = frame.time_us;
        if let Some(p) = previous_us {
            steps += 1;
            steps_back += usize::from(t < p);
        }
        previous_us = Some(t);
        if let Some(l) = latest_us {
            if t + BACKWARD_JITTER_US < l {
                run += 1;
                jumps_back.push(format!("a jump back of {:.3} s", (l - t) as f64 * 1e-6));
                latest_us = Some(t);
            }
        }
        latest_us = Some(latest_us.map_or(t, |l| l.max(t)));
        *by_id.entry(frame.msgid).or_insert(0) += 1;
        let entry = per_run.entry((frame.sysid, run)).or_default();
        entry.1 += 1;
        collect(&mut entry.0, frame);
    });
    let mut per_system: BTreeMap<u8, (Vec<(usize, Series)>, usize)> = BTreeMap::new();
    for ((sysid, r), (series, n)) in per_run {
        let entry = per_system.entry(sysid).or_default();
        entry.0.push((r, series));
        entry.1 += n;
    }
    let messages_by_name: BTreeMap<String, usize> = by_id
        .iter()
        .map(|(&id, &count)| {
            let name = MavMessage::default_message_from_id(id)
                .map_or_else(|| format!("#{id}"), |m| m.message_name().to_string());
            (name, count)
        })
        .collect();
    let systems: Vec<SystemSummary> = per_system
        .iter()
        .map(|(&sysid, (runs, n))| SystemSummary {
            sysid,
            attitude_messages: runs.iter().map(|(_, s)| s.attitude.len()).sum(),
            messages: *n,
        })
        .collect();
    if stats.frames == 0 {
        return Err(err(format!(
            "no valid MAVLink frame found in {} bytes (is this a .tlog: [8-byte timestamp][frame] …?)",
            bytes.len()
        )));
    }
    let sysid = match options.sysid {
        Some(id) => id,
        None => systems
            .iter()
            .max_by_key(|s| (s.attitude_messages, std::cmp::Reverse(s.sysid)))
            .map(|s| s.sysid)
            .unwrap_or(0),
    };
    let describe = || {
        systems
            .iter()
            .map(|s| format!("{} ({} ATTITUDE)", s.sysid, s.attitude_messages))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some((runs, _)) = per_system.get_mut(&sysid) else {
        return Err(err(format!(
            "system id {sysid} sent no valid message; systems present: {}",
            describe()
        )));
    };
    if stats.bad_timestamps >= 10 && stats.bad_timestamps * 2 > stats.frames + stats.bad_timestamps
    {
        let first = bytes
            .get(..8)
            .map_or(0, |b| u64::from_be_bytes(b.try_into().unwrap_or([0; 8])));
        return Err(err(format!(
            "{} of {} valid frames have log times more than 10 s from their neighbours': the time base is not \
             usable.{}",
            stats.bad_timestamps,
            stats.frames + stats.bad_timestamps,
            little_endian_hint(first)
        )));
    }
    let attitude_messages: usize = runs.iter().map(|(_, s)| s.attitude.len()).sum();
    if attitude_messages < 2 {
        return Err(err(format!(
            "system id {sysid} sent {attitude_messages} ATTITUDE messages; at least 2 are needed for the time \
             base (systems present: {})",
            describe()
        )));
    }
    if steps >= 10 && steps_back * 2 > steps {
        return Err(err(format!(
            "the log time runs backwards in {steps_back} of {steps} steps between frames: the records are in \
             reverse order, or the 8-byte field before each frame is not the log time"
        )));
    }
    for (_, series) in runs.iter_mut() {
        series.tidy();
    }
    check_time_units(runs, sysid).map_err(err)?;
    let (stretches, windows) = stretches(runs, &jumps_back);
    let chosen = match (options.stretch, stretches.len()) {
        (None, 1) | (Some(StretchChoice::Index(1)), 1) => 0,
        (None, n) => {
            return Err(err(format!(
                "system id {sysid}: the log time breaks into {n} stretches; nothing is interpolated across \
                 a break, so ingest one of them with --stretch K (or --stretch longest):\n{}",
                list_stretches(&stretches)
            )))
        }
        (Some(StretchChoice::Longest), _) => (0..stretches.len())
            .max_by_key(|&k| (stretches[k].attitude_samples, std::cmp::Reverse(k)))
            .unwrap_or(0),
        (Some(StretchChoice::Index(k)), n) if k <= n => k - 1,
        (Some(StretchChoice::Index(k)), n) => {
            return Err(DataError::InvalidArgument(format!(
                "--stretch {k}: system id {sysid} of {file} has {n} stretch(es):\n{}",
                list_stretches(&stretches)
            )))
        }
    };
    let (run_index, from_us, to_us) = windows[chosen];
    let mut series = runs[run_index].1.window(from_us, to_us);
    let mut record = build_record(&mut series, servo_map, options.rate_hz, options.airspeed)
        .map_err(|m| err(format!("system id {sysid}: {m}")))?;
    if stretches.len() > 1 {
        record.metadata.push(format!(
            " stretch {} of {} of the log: {}",
            chosen + 1,
            stretches.len(),
            stretches[chosen]
        ));
    }
    let mut warnings = Vec::new();
    if stats.skipped_bytes > 0 {
        warnings.push(Warning {
            kind: WarningKind::Other,
            column: None,
            message: format!(
                "skipped {} corrupt or unknown bytes in {} region(s)",
                stats.skipped_bytes, stats.corrupt_regions
            ),
        });
    }
    if stats.truncated_tail_bytes > 0 {
        warnings.push(Warning {
            kind: WarningKind::Other,
            column: None,
            message: format!(
                "dropped a truncated final frame ({} bytes)",
                stats.truncated_tail_bytes
            ),
        });
    }
    if stats.bad_timestamps > 0 {
        warnings.push(Warning {
            kind: WarningKind::Other,
            column: None,
            message: format!(
                "dropped {} frames whose log timestamp jumped by more than 10 s without confirmation",
                stats.bad_timestamps
            ),
        });
    }
    for (needed, why) in [
        (Channel::Ax, "no HIGHRES_IMU/SCALED_IMU/RAW_IMU"),
        (Channel::Airspeed, "no VFR_HUD"),
        (Channel::Alpha, "no AOA_SSA"),
        (Channel::Elevator, "no SERVO_OUTPUT_RAW or no --servo-map"),
    ] {
        if record.column(needed).is_none() {
            warnings.push(Warning {
                kind: WarningKind::Other,
                column: Some(needed.to_string()),
                message: format!("not in the output: {why} from system {sysid}"),
            });
        }
    }
    record.metadata.insert(
        0,
        format!(
            " source: {file} (MAVLink tlog), system id {sysid}; {} valid frames ({} v1, {} v2), \
             {} bytes skipped, {} truncated tail bytes",
            stats.frames,
            stats.frames_v1,
            stats.frames_v2,
            stats.skipped_bytes,
            stats.truncated_tail_bytes
        ),
    );
    if let Some(af) = servo_map {
        record
            .metadata
            .insert(1, format!(" servo mapping: {}", af.name));
    }
    Ok(TlogReport {
        record,
        sysid,
        systems,
        stats,
        messages_by_name,
        warnings,
        stretches,
        stretch: chosen,
    })
}

/// The stretches, one per line, numbered from 1.
fn list_stretches(stretches: &[Stretch]) -> String {
    stretches
        .iter()
        .enumerate()
        .map(|(k, s)| format!("  {}: {s}", k + 1))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Refuses log times that are not microseconds since the Unix epoch or since the log's start: times after the
/// year 2100 (little-endian timestamps read as big-endian look like that) and an ATTITUDE rate no autopilot
/// sends (millisecond timestamps look like that).
fn check_time_units(runs: &[(usize, Series)], sysid: u8) -> Result<(), String> {
    let att: Vec<u64> = runs
        .iter()
        .flat_map(|(_, s)| s.attitude.iter().map(|(t, _)| *t))
        .collect();
    let (Some(&lo), Some(&hi)) = (att.iter().min(), att.iter().max()) else {
        return Ok(());
    };
    if hi > LATEST_EPOCH_US {
        return Err(format!(
            "system id {sysid}: log times reach {hi} µs, after the year 2100: not microseconds since the Unix \
             epoch.{}",
            little_endian_hint(hi)
        ));
    }
    let span_s = (hi - lo) as f64 * 1e-6;
    let rate_hz = (att.len() - 1) as f64 / span_s.max(1e-12);
    if att.len() >= 10 && rate_hz > MAX_ATTITUDE_RATE_HZ {
        return Err(format!(
            "system id {sysid}: {} ATTITUDE messages within {:.6} s of log time ({:.0} Hz): no autopilot sends \
             attitude that fast, so the times are not microseconds (milliseconds read as microseconds look \
             like this; the .tlog format stores microseconds)",
            att.len(),
            span_s,
            rate_hz
        ));
    }
    Ok(())
}

/// A sentence saying that a log time read big-endian is a plausible epoch time with its bytes reversed, or "".
fn little_endian_hint(time_us: u64) -> &'static str {
    if (EARLIEST_EPOCH_US..LATEST_EPOCH_US).contains(&time_us.swap_bytes()) {
        " The times read as a plausible date with their bytes reversed: the log was written little-endian, and \
         the .tlog format stores the time big-endian."
    } else {
        ""
    }
}

/// Splits the runs of a system (separated by jumps back) at pauses of the ATTITUDE stream longer than
/// [`GAP_INTERVALS`] median intervals. Returns the stretches and, for each, its run (index into `runs`) and
/// time window in µs.
fn stretches(
    runs: &[(usize, Series)],
    jumps_back: &[String],
) -> (Vec<Stretch>, Vec<(usize, u64, u64)>) {
    let mut intervals: Vec<f64> = runs
        .iter()
        .flat_map(|(_, s)| s.attitude.windows(2).map(|w| (w[1].0 - w[0].0) as f64))
        .filter(|d| *d >= MIN_DEFAULT_STEP_US / 2.0)
        .collect();
    let median_us = if intervals.is_empty() {
        MIN_DEFAULT_STEP_US
    } else {
        super::record::median_in_place(&mut intervals).max(MIN_DEFAULT_STEP_US)
    };
    let gap_us = GAP_INTERVALS * median_us;
    // Times from the first ATTITUDE in log order (a stretch after a jump back can start before it).
    let origin_us = runs
        .iter()
        .find_map(|(_, s)| s.attitude.first().map(|a| a.0))
        .unwrap_or(0);
    let rel = |t: u64| (t as f64 - origin_us as f64) * 1e-6;
    let (mut out, mut windows) = (Vec::new(), Vec::new());
    let mut why: Option<String> = None;
    for (k, (run, series)) in runs.iter().enumerate() {
        if k > 0 {
            why = jumps_back.get(run - 1).cloned().or(why);
        }
        let att = &series.attitude;
        let mut start = 0usize;
        for i in 0..att.len() {
            let last = i + 1 == att.len();
            let gap = !last && (att[i + 1].0 - att[i].0) as f64 > gap_us;
            if gap || last {
                if i > start {
                    out.push(Stretch {
                        start_s: rel(att[start].0),
                        end_s: rel(att[i].0),
                        attitude_samples: i + 1 - start,
                        after: why.take(),
                    });
                    windows.push((k, att[start].0, att[i].0));
                }
                if gap {
                    why = Some(format!(
                        "a gap of {:.3} s",
                        (att[i + 1].0 - att[i].0) as f64 * 1e-6
                    ));
                }
                start = i + 1;
            }
        }
    }
    (out, windows)
}

/// Decodes the messages the schema needs and appends them to the system's series.
fn collect(series: &mut Series, frame: &Frame) {
    let wanted = matches!(
        frame.msgid,
        ATTITUDE_ID
            | SCALED_IMU_ID
            | RAW_IMU_ID
            | HIGHRES_IMU_ID
            | VFR_HUD_ID
            | SERVO_OUTPUT_RAW_ID
            | AOA_SSA_ID
    );
    if !wanted {
        return;
    }
    let version = if frame.version == 1 {
        MavlinkVersion::V1
    } else {
        MavlinkVersion::V2
    };
    let Ok(msg) = MavMessage::parse(version, frame.msgid, frame.payload) else {
        return;
    };
    let t = frame.time_us;
    let milli_g = |x: i16| f64::from(x) * 1e-3 * G0_M_S2;
    match msg {
        MavMessage::ATTITUDE(a) => series.attitude.push((
            t,
            [
                a.roll,
                a.pitch,
                a.yaw,
                a.rollspeed,
                a.pitchspeed,
                a.yawspeed,
            ]
            .map(f64::from),
        )),
        MavMessage::HIGHRES_IMU(m) => series
            .highres_imu
            .push((t, [m.xacc, m.yacc, m.zacc].map(f64::from))),
        MavMessage::SCALED_IMU(m) => series
            .scaled_imu
            .push((t, [m.xacc, m.yacc, m.zacc].map(milli_g))),
        MavMessage::RAW_IMU(m) => series
            .raw_imu
            .push((t, [m.xacc, m.yacc, m.zacc].map(milli_g))),
        MavMessage::VFR_HUD(m) => series.vfr_hud.push((
            t,
            [
                f64::from(m.airspeed),
                f64::from(m.alt),
                f64::from(m.throttle) / 100.0,
            ],
        )),
        MavMessage::AOA_SSA(m) => series.aoa_ssa.push((
            t,
            [f64::from(m.AOA).to_radians(), f64::from(m.SSA).to_radians()],
        )),
        MavMessage::SERVO_OUTPUT_RAW(m) if m.port == 0 => series.servo.push((
            t,
            [
                m.servo1_raw,
                m.servo2_raw,
                m.servo3_raw,
                m.servo4_raw,
                m.servo5_raw,
                m.servo6_raw,
                m.servo7_raw,
                m.servo8_raw,
            ]
            .map(f64::from),
        )),
        _ => {}
    }
}

/// Sorts a series by time and keeps the first sample of each repeated time.
fn tidy<const N: usize>(s: &mut Vec<(u64, [f64; N])>) {
    s.sort_by_key(|(t, _)| *t);
    s.dedup_by_key(|(t, _)| *t);
    s.retain(|(_, v)| v.iter().all(|x| x.is_finite()));
}

/// Linear interpolation of component `k` of a time-sorted series at grid times (held constant
/// beyond its ends).
fn interp<const N: usize>(s: &[(u64, [f64; N])], k: usize, grid_us: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grid_us.len());
    let mut j = 0usize;
    for &tg in grid_us {
        while j + 1 < s.len() && (s[j + 1].0 as f64) < tg {
            j += 1;
        }
        let (t0, v0) = (s[j].0 as f64, s[j].1[k]);
        let v = if j + 1 < s.len() && tg > t0 {
            let (t1, v1) = (s[j + 1].0 as f64, s[j + 1].1[k]);
            v0 + (v1 - v0) * ((tg - t0) / (t1 - t0)).min(1.0)
        } else {
            v0
        };
        out.push(v);
    }
    out
}

/// Unwraps an angle sequence (rad) so that consecutive samples differ by less than π.
fn unwrap_angles(s: &mut [(u64, [f64; 6])], k: usize) {
    let tau = std::f64::consts::TAU;
    let Some(first) = s.first() else { return };
    let mut prev_raw = first.1[k];
    let mut offset = 0.0;
    for sample in s.iter_mut().skip(1) {
        let raw = sample.1[k];
        offset -= tau * ((raw - prev_raw) / tau).round();
        prev_raw = raw;
        sample.1[k] = raw + offset;
    }
}

/// Puts the collected series onto one uniform grid over the ATTITUDE time span.
fn build_record(
    series: &mut Series,
    servo_map: Option<&ServoMap>,
    rate_hz: Option<f64>,
    airspeed: AirspeedKind,
) -> Result<FlightRecord, String> {
    series.tidy();
    let att = &mut series.attitude;
    // Drop ATTITUDE duplicates (the same sample relayed twice, µs apart).
    let mut last_kept: Option<u64> = None;
    att.retain(|(t, _)| {
        let keep = last_kept.is_none_or(|l| t - l >= MIN_DEFAULT_STEP_US as u64 / 2);
        if keep {
            last_kept = Some(*t);
        }
        keep
    });
    if att.len() < 2 {
        return Err("fewer than 2 usable ATTITUDE messages".into());
    }
    unwrap_angles(att, 2);
    let t0_us = att[0].0;
    let span_us = (att[att.len() - 1].0 - t0_us) as f64;
    let dt_us = match rate_hz {
        Some(r) => 1e6 / r,
        None => {
            let mut steps: Vec<f64> = att.windows(2).map(|w| (w[1].0 - w[0].0) as f64).collect();
            // Floor at 1 ms: no tlog carries ATTITUDE faster than 1 kHz; closer samples are
            // duplicates relayed over a second link.
            super::record::median_in_place(&mut steps)
                .round()
                .max(MIN_DEFAULT_STEP_US)
        }
    };
    let n = (span_us / dt_us + 1e-9).floor() as usize + 1;
    if n > 100_000_000 {
        return Err(format!(
            "the output grid would hold {n} samples ({} s at {} Hz); give a lower rate",
            span_us / 1e6,
            1e6 / dt_us
        ));
    }
    let grid_us: Vec<f64> = (0..n).map(|k| t0_us as f64 + k as f64 * dt_us).collect();
    let mut rec = FlightRecord::new(grid_us.iter().map(|t| (t - t0_us as f64) * 1e-6).collect());
    rec.metadata.push(format!(
        " time_s = log timestamp - {t0_us} µs (Unix epoch); grid {} Hz; linear interpolation per message stream",
        1e6 / dt_us
    ));
    if let Some(af) = servo_map {
        if !series.servo.is_empty() {
            let surfaces = [
                (Channel::Elevator, af.elevator),
                (Channel::Aileron, af.aileron),
                (Channel::Rudder, af.rudder),
            ];
            for (name, map) in surfaces {
                if let Some(m) = map {
                    let pwm = interp(&series.servo, usize::from(m.channel - 1), &grid_us);
                    rec.push_column(name, pwm.into_iter().map(|p| m.to_rad(p)).collect());
                }
            }
            if let Some(t) = af.throttle {
                let pwm = interp(&series.servo, usize::from(t.channel - 1), &grid_us);
                rec.push_column(
                    Channel::Throttle,
                    pwm.into_iter().map(|p| t.to_fraction(p)).collect(),
                );
            }
        }
    }
    if rec.column(Channel::Throttle).is_none() && !series.vfr_hud.is_empty() {
        rec.push_column(Channel::Throttle, interp(&series.vfr_hud, 2, &grid_us));
    }
    for (k, channel) in Channel::ATTITUDE_AND_RATES.into_iter().enumerate() {
        rec.push_column(channel, interp(&series.attitude, k, &grid_us));
    }
    if !series.aoa_ssa.is_empty() {
        rec.push_column(Channel::Alpha, interp(&series.aoa_ssa, 0, &grid_us));
        rec.push_column(Channel::Beta, interp(&series.aoa_ssa, 1, &grid_us));
    }
    if !series.vfr_hud.is_empty() {
        let mut v = interp(&series.vfr_hud, 0, &grid_us);
        let h = interp(&series.vfr_hud, 1, &grid_us);
        if airspeed == AirspeedKind::Equivalent {
            for (v, h) in v.iter_mut().zip(&h) {
                *v = true_from_equivalent(*v, *h);
            }
            let ratio = h
                .first()
                .map_or(f64::NAN, |h| true_from_equivalent(1.0, *h));
            rec.metadata.push(format!(
                " airspeed_m_s: VFR_HUD's equivalent airspeed made true with the standard atmosphere at the logged \
                 altitude (x{ratio:.4} at the start; --airspeed true if the autopilot sends true airspeed)"
            ));
        }
        rec.push_column(Channel::Airspeed, v);
        rec.push_column(Channel::Altitude, h);
    }
    let imu = [
        (&series.highres_imu, "HIGHRES_IMU"),
        (&series.scaled_imu, "SCALED_IMU"),
        (
            &series.raw_imu,
            "RAW_IMU (assumed milli-g, as ArduPilot sends it)",
        ),
    ]
    .into_iter()
    .find(|(s, _)| !s.is_empty());
    if let Some((s, source)) = imu {
        for (k, channel) in Channel::SPECIFIC_FORCES.into_iter().enumerate() {
            rec.push_column(channel, interp(s, k, &grid_us));
        }
        rec.metadata.push(format!(" accelerations from {source}"));
    }
    // Schema order for readability.
    let order = |n: &str| Channel::from_name(n).map_or(usize::MAX, |c| c as usize);
    rec.columns.sort_by_key(|(n, _)| order(n));
    Ok(rec)
}
