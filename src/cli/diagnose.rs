//! `flightid diagnose`: what the simulation gets wrong on measured data, the named cause, the validation gain.

use std::path::{Path, PathBuf};

use anyhow::Context;

use super::common::{emit_json, write_atomic};
use super::UsageError;
use crate::aircraft;
use crate::data::{read_csv, FlightRecord};
use crate::diagnose::search::Worker;
use crate::diagnose::{diagnose, DiagnoseError, DiagnoseOptions, Diagnosis};
use crate::sim::JsbsimSim;

/// Replay measured data on the aircraft's simulation, fit the catalogue of model extensions (signal path,
/// sensors, aerodynamic derivative scales), name the significant cause(s) and measure the gain on a
/// validation record.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid diagnose --aircraft c172x --data train.csv --validate valid.csv --json out.json"
)]
pub struct DiagnoseCmd {
    /// Aircraft configuration (c172x, 737, f16, or a path to an aircraft .toml).
    #[arg(long, default_value = "c172x")]
    pub aircraft: String,
    /// Training record (flight-data CSV).
    #[arg(long)]
    pub data: PathBuf,
    /// Validation record (flight-data CSV) the fit never sees.
    #[arg(long)]
    pub validate: Option<PathBuf>,
    /// Write the JSON result (DESIGN.md §7) to this file (`-` for stdout).
    #[arg(long)]
    pub json: Option<String>,
    /// Write the extended model (fitted effects, JSON, loadable by `flightid replay --extension`) here.
    #[arg(long)]
    pub extension_out: Option<PathBuf>,
    /// Write a report directory (summary JSON and the extension file).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Parallel simulations (one JSBSim process each).
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
}

/// Reads a record; unreadable data are a usage error (exit 2).
pub fn read_record(path: &Path) -> anyhow::Result<FlightRecord> {
    read_csv(path).map_err(|e| UsageError(e.to_string()).into())
}

/// Maps diagnose errors on the user's input to exit code 2.
pub fn classify(e: DiagnoseError) -> anyhow::Error {
    match e {
        DiagnoseError::Sim { .. } => e.into(),
        other => UsageError(other.to_string()).into(),
    }
}

/// Starts `n` JSBSim workers at the record's rate.
pub fn start_workers(aircraft: &str, rate_hz: f64, n: usize) -> anyhow::Result<Vec<Worker>> {
    let cfg = aircraft::load(aircraft).map_err(|e| UsageError(e.to_string()))?;
    (0..n.max(1))
        .map(|_| {
            JsbsimSim::start(&cfg, rate_hz)
                .map(|s| Worker::new(Box::new(s)))
                .with_context(|| format!("starting JSBSim for {}", cfg.name))
        })
        .collect()
}

fn rate_of(rec: &FlightRecord) -> anyhow::Result<f64> {
    let n = rec.len();
    if n < 2 {
        return Err(UsageError("the record has fewer than two samples".into()).into());
    }
    Ok((n - 1) as f64 / (rec.time_s[n - 1] - rec.time_s[0]))
}

/// Runs `flightid diagnose`.
pub fn run(args: &DiagnoseCmd) -> anyhow::Result<()> {
    let train = read_record(&args.data)?;
    let valid = args.validate.as_deref().map(read_record).transpose()?;
    let mut workers = start_workers(&args.aircraft, rate_of(&train)?, args.workers)?;
    let d = diagnose(
        &mut workers,
        &train,
        valid.as_ref(),
        &DiagnoseOptions::default(),
    )
    .map_err(classify)?;
    summary(&d);
    if let Some(target) = &args.json {
        emit_json(target, &d)?;
    }
    let ext = d.extension_file(&args.aircraft);
    if let Some(p) = &args.extension_out {
        write_atomic(p, serde_json::to_string_pretty(&ext)?.as_bytes())?;
    }
    if let Some(dir) = &args.report {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_atomic(
            &dir.join("diagnose.json"),
            serde_json::to_string_pretty(&d)?.as_bytes(),
        )?;
        write_atomic(
            &dir.join("extension.json"),
            serde_json::to_string_pretty(&ext)?.as_bytes(),
        )?;
        eprintln!("report written to {}", dir.display());
    }
    Ok(())
}

/// Terminal summary: named causes with value ± standard error, and the validation gain.
fn summary(d: &Diagnosis) {
    if d.named_cause.is_empty() {
        println!(
            "no significant model error found (no extension passes the BIC and significance tests)"
        );
    }
    for c in &d.named_cause {
        print!(
            "named cause: {} on {} = {:.5} ± {:.5}",
            c.effect, c.target, c.value, c.std_error
        );
        if !c.ambiguous_with.is_empty() {
            print!(
                "  (cannot be told apart from: {})",
                c.ambiguous_with.join(", ")
            );
        }
        println!();
    }
    for m in &d.trim_mismatch {
        println!(
            "trim: {:<13} measured {:+.5}  model {:+.5}",
            m.quantity, m.measured, m.model
        );
    }
    if let Some(v) = &d.validation {
        println!(
            "validation (weighted ISE): {:.1} -> {:.1} ({:.0} % less)",
            v.ise_before,
            v.ise_after,
            100.0 * (1.0 - v.ise_after / v.ise_before)
        );
        for (c, before) in &v.fit_percent_before {
            let after = v.fit_percent_after.get(c).copied().unwrap_or(f64::NAN);
            println!("  {c:<13} fit {before:6.1} % -> {after:6.1} %");
        }
    }
    for s in &d.skipped {
        if s.effect != "aero_derivative" {
            println!("skipped {} on {}: {}", s.effect, s.target, s.reason);
        }
    }
    println!("{} simulations in {:.1} s", d.simulations, d.wall_s);
}
