//! `flightid ingest`: a MAVLink telemetry log → the flight-data CSV schema.

use std::path::PathBuf;

use anyhow::Context;

use crate::data::{self, ServoMap, TlogOptions};

/// Convert a MAVLink `.tlog` into a flight-data CSV (docs/data.md).
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Examples:\n  flightid ingest --tlog tests/fixtures/flight.tlog --servo-map c172x --out flight.csv\n  flightid ingest --tlog flight.tlog --servo-map my_servos.toml --resample-hz 50 --out flight.csv --json"
)]
pub struct IngestArgs {
    /// The telemetry log ([8-byte µs timestamp][MAVLink frame] records).
    #[arg(long)]
    pub tlog: PathBuf,
    /// MAVLink servo mapping (PWM → surface radians): a name under aircraft/servo_maps/ or a path to a .toml
    /// file. Without it, surface columns are left out. (Not an airframe description: mass, inertia and
    /// geometry are `--airframe` on the commands that need them.)
    #[arg(long = "servo-map", value_name = "NAME|FILE.toml")]
    pub servo_map: Option<String>,
    /// Output CSV (written atomically).
    #[arg(long)]
    pub out: PathBuf,
    /// System id to extract (default: the one with the most ATTITUDE messages).
    #[arg(long)]
    pub sysid: Option<u8>,
    /// Output sample rate, Hz (default: the ATTITUDE rate). Linear interpolation.
    #[arg(long = "resample-hz", value_parser = crate::limits::RESAMPLE_HZ.parser())]
    pub resample_hz: Option<f64>,
    /// Which stretch of the log to read when its time base breaks (a pause in ATTITUDE longer than five
    /// intervals, or a jump back in log time): its number from 1 as listed by the refusal, or `longest`.
    /// Nothing is ever interpolated across a break; without this such a log is refused with the list.
    #[arg(long, value_name = "K|longest")]
    pub stretch: Option<data::StretchChoice>,
    /// What the log's VFR_HUD airspeed is: `equivalent` (ArduPilot and PX4 send equivalent or indicated
    /// airspeed; it is made true with the standard atmosphere at the logged altitude, ×1.06 at 1 200 m) or `true`
    /// (taken as it is). The CSV's `airspeed_m_s` is true airspeed, which the replay trims at.
    #[arg(long, value_enum, default_value = "equivalent")]
    pub airspeed: data::AirspeedKind,
    /// Print the summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs `flightid ingest`.
pub fn run(args: &IngestArgs) -> anyhow::Result<()> {
    super::common::check_outputs(&[Some(&args.out)], &[])?;
    let servo_map = match &args.servo_map {
        Some(name) => Some(ServoMap::resolve(name)?),
        None => None,
    };
    let options = TlogOptions {
        sysid: args.sysid,
        rate_hz: args.resample_hz,
        stretch: args.stretch,
        airspeed: args.airspeed,
    };
    let report = data::read_tlog(&args.tlog, servo_map.as_ref(), &options)?;
    let unit_warnings = report.record.warnings();
    data::write_csv_atomic(&args.out, &report.record)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let s = &report.stats;
    if args.json {
        let summary = serde_json::json!({
            "out": args.out,
            "sysid": report.sysid,
            "rows": report.record.len(),
            "columns": report.record.column_names(),
            "frames": s.frames, "frames_v1": s.frames_v1, "frames_v2": s.frames_v2,
            "skipped_bytes": s.skipped_bytes, "corrupt_regions": s.corrupt_regions,
            "truncated_tail_bytes": s.truncated_tail_bytes, "bad_timestamps": s.bad_timestamps,
            "stretch": report.stretch + 1,
            "stretches": report.stretches.iter().map(|x| serde_json::json!({
                "start_s": x.start_s, "end_s": x.end_s, "attitude_samples": x.attitude_samples, "after": x.after
            })).collect::<Vec<_>>(),
            "systems": report.systems.iter().map(|x| serde_json::json!({
                "sysid": x.sysid, "attitude_messages": x.attitude_messages, "messages": x.messages
            })).collect::<Vec<_>>(),
            "messages": report.messages_by_name,
            "warnings": report.warnings.iter().chain(&unit_warnings).map(|w| w.to_string()).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        eprintln!(
            "{}: system {} → {} rows × {} columns in {} ({} frames: {} v1, {} v2; {} bytes skipped; {} truncated)",
            args.tlog.display(),
            report.sysid,
            report.record.len(),
            report.record.columns.len() + 1,
            args.out.display(),
            s.frames,
            s.frames_v1,
            s.frames_v2,
            s.skipped_bytes,
            s.truncated_tail_bytes
        );
        if report.stretches.len() > 1 {
            eprintln!(
                "read stretch {} of {}: {}",
                report.stretch + 1,
                report.stretches.len(),
                report.stretches[report.stretch]
            );
        }
        for w in report.warnings.iter().chain(&unit_warnings) {
            super::warn(w);
        }
    }
    Ok(())
}
