//! `flightid segments`: list the maneuvers (doublet, 3-2-1-1, sweep) found in a flight log.

use std::path::PathBuf;

use super::common::{resample, RecordArgs};
use crate::data::{self, SegmentOptions};

/// Find maneuvers in a flight-data CSV.
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Examples:\n  flightid segments flight.csv\n  flightid segments flight.csv --min-amplitude-deg 1 --json"
)]
pub struct SegmentsArgs {
    /// Flight-data CSV (docs/data.md).
    pub file: PathBuf,
    /// Smallest input that counts as a maneuver, degrees.
    #[arg(long, default_value_t = 0.25, value_parser = crate::limits::MIN_AMPLITUDE_DEG.parser())]
    pub min_amplitude_deg: f64,
    /// Print the segments as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Runs `flightid segments`.
pub fn run(args: &SegmentsArgs) -> anyhow::Result<()> {
    let rec = args.record.columns.read(&args.file)?;
    let rec = resample(rec, args.record.resample_hz, &args.file)?;
    let opts = SegmentOptions {
        min_amplitude_rad: args.min_amplitude_deg.to_radians(),
        ..SegmentOptions::default()
    };
    let scan = data::scan_segments(&rec, &opts)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&scan)?);
        return Ok(());
    }
    let segments = &scan.segments;
    if !scan.rejected.is_empty() {
        println!("surface activity that is not a maneuver:");
        for r in &scan.rejected {
            println!(
                "  {:<13} {:>9.2} - {:>9.2} s  {:>6.2} deg  {}",
                r.surface,
                r.start_s,
                r.end_s,
                r.amplitude_rad.to_degrees(),
                r.reason
            );
        }
        println!();
    }
    if segments.is_empty() {
        println!("no maneuvers found in {}", args.file.display());
        return Ok(());
    }
    println!(
        "{:>3}  {:<13} {:<8} {:>9} {:>9} {:>9} {:>9}  steady",
        "#", "surface", "kind", "start_s", "end_s", "amp_deg", "trim_deg"
    );
    for s in segments {
        println!(
            "{:>3}  {:<13} {:<8} {:>9.2} {:>9.2} {:>9.2} {:>9.2}  {}",
            s.number,
            s.surface,
            s.kind.name(),
            s.start_s,
            s.end_s,
            s.amplitude_rad.to_degrees(),
            s.trim_rad.to_degrees(),
            if s.steady_before { "yes" } else { "no" }
        );
    }
    Ok(())
}
