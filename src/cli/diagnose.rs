//! `flightid diagnose`: what the simulation gets wrong on measured data, the named cause, the validation gain.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;

use super::common::{check_outputs, emit_json, json_path, write_atomic, ColumnsArg, LoadingArg};
use super::UsageError;
use crate::data::FlightRecord;
use crate::diagnose::model::write_model;
use crate::diagnose::replay::ReplayCase;
use crate::diagnose::workers::{start_workers, SimSource};
use crate::diagnose::{diagnose, report, DiagnoseOptions, Diagnosis};

/// Replay measured data on the aircraft's simulation, fit the catalogue of model extensions (signal path,
/// sensors, aerodynamic derivative scales, added nonlinear terms), name the significant cause(s) and measure the
/// gain on a validation record.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid diagnose --aircraft c172x --data train.csv --validate valid.csv --json out.json --report rep --model-out model\n  flightid diagnose --linear lin.json --data train.csv --validate valid.csv"
)]
pub struct DiagnoseCmd {
    /// Aircraft configuration (c172x, 737, f16, a path to an aircraft .toml, or any JSBSim model:
    /// c182, c310, B747, …, configured from the model, docs/airframe.md).
    #[arg(long, default_value = "c172x")]
    pub aircraft: String,
    #[command(flatten)]
    pub loading: LoadingArg,
    /// Use a linear model (`flightid linearize --json` output) as the simulation instead of JSBSim
    /// (signal-path and sensor effects only).
    #[arg(long, value_name = "LIN.json")]
    pub linear: Option<PathBuf>,
    /// Training record (flight-data CSV).
    #[arg(long)]
    pub data: PathBuf,
    /// Validation record (flight-data CSV) the fit never sees.
    #[arg(long)]
    pub validate: Option<PathBuf>,
    /// Write the JSON result (docs/diagnose.md) to this file (`-` for stdout).
    #[arg(long)]
    pub json: Option<String>,
    /// Write the fitted effects as an extension file (JSON, loadable by `flightid replay --extension`).
    #[arg(long)]
    pub extension_out: Option<PathBuf>,
    /// Write the extended model: the aircraft with the fitted terms in its XML plus extension.json
    /// (loadable by `flightid fly --model DIR` and `flightid replay --model DIR`).
    #[arg(long, value_name = "DIR")]
    pub model_out: Option<PathBuf>,
    /// Write a report directory (index.html with overlays and residual plots, report.md, report.json).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Parallel simulations (one JSBSim process each).
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Rate the replay integrates at, Hz: a whole multiple of the record's rate (default: the smallest one of
    /// at least 200 Hz). The surfaces move in straight lines between the record's samples; at the record's own
    /// rate that is a hold of each sample over the step that ends at it (the convention of `flightid fly`).
    #[arg(long, value_name = "HZ")]
    pub replay_rate_hz: Option<f64>,
    /// Estimate the replay's integration rate from the record: replay the unextended model at every whole
    /// multiple of the record's rate from 100 to 200 Hz and keep the best fit (experimental: a hidden input
    /// delay pulls the choice to a coarser step; docs/diagnose.md, "Replay conventions")
    #[arg(long, conflicts_with = "replay_rate_hz")]
    pub estimate_rate: bool,
    /// Records flown in turbulence (experimental): estimate the process noise from the replay's residuals and,
    /// when the likelihood finds it, fit every candidate on the filter error method's innovations instead of the
    /// output error (a steady-state Kalman filter of the linearised error dynamics; docs/diagnose.md,
    /// "Turbulence")
    #[arg(long)]
    pub process_noise: bool,
    /// After forward selection, drop every named effect that no longer passes the significance tests with the
    /// other named effects in the model (experimental; docs/diagnose.md, "Selection")
    #[arg(long)]
    pub backward_elimination: bool,
    /// Weight every channel by its sensor noise only, even where the unextended model misses it by far more
    /// (by default such a channel is weighted by its residual, as output error with the residual covariance
    /// unknown does; docs/diagnose.md, "Turbulence")
    #[arg(long)]
    pub noise_weights: bool,
    #[command(flatten)]
    pub columns: ColumnsArg,
}

/// The replay of `rec`, read from `path` as the `role` record ("training", "validation"): an error names both.
fn replay_case(rec: &FlightRecord, path: &Path, role: &str) -> anyhow::Result<ReplayCase> {
    ReplayCase::new(rec).with_context(|| format!("{} (the {role} record)", path.display()))
}

/// Runs `flightid diagnose`.
pub fn run(args: &DiagnoseCmd) -> anyhow::Result<()> {
    if args.model_out.is_some() && args.linear.is_some() {
        return Err(UsageError(
            "--model-out needs a JSBSim aircraft; with --linear use --extension-out".into(),
        )
        .into());
    }
    check_outputs(
        &[json_path(&args.json), args.extension_out.as_deref()],
        &[args.report.as_deref(), args.model_out.as_deref()],
    )?;
    let train = args.columns.read(&args.data)?;
    crate::limits::check_rows(&args.data.display().to_string(), train.len())?;
    let valid = args
        .validate
        .as_deref()
        .map(|p| args.columns.read(p))
        .transpose()?;
    // Each record is prepared for replay once here, where its file is known, so a record that cannot be replayed
    // is named before the simulations start.
    let train_case = replay_case(&train, &args.data, "training")?;
    if let (Some(v), Some(p)) = (&valid, &args.validate) {
        replay_case(v, p, "validation")?;
    }
    let source = match &args.linear {
        Some(p) => SimSource::Linear(p),
        None => SimSource::Aircraft(&args.aircraft, &args.loading.properties),
    };
    let rate = match args.replay_rate_hz {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => {
            return Err(UsageError(format!("--replay-rate-hz {r}: must be positive")).into())
        }
        None => train_case.sim_rate_hz(),
    };
    let starting = super::common::spinner("diagnose: starting the simulations");
    let workers = start_workers(&source, rate, args.workers);
    starting.finish_and_clear();
    let mut workers = workers?;
    // The search shows its own progress line (stage, candidate round, fits and simulations) on stderr.
    let d = diagnose(
        &mut workers,
        &train,
        valid.as_ref(),
        &DiagnoseOptions {
            process_noise: args.process_noise,
            backward_elimination: args.backward_elimination,
            relax_weights: !args.noise_weights,
            choose_rate: args.estimate_rate,
            ..DiagnoseOptions::default()
        },
    )?;
    // With `--json -` stdout carries only the JSON; the summary goes to stderr.
    let mut out: Box<dyn Write> = if args.json.as_deref() == Some("-") {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    };
    summary(&d, workers.len(), &mut out)?;
    let mut ext = d.extension_file(&args.aircraft);
    ext.properties = crate::sim::derived::aircraft_config(&args.aircraft)?
        .with_properties(&args.loading.properties)?
        .properties;
    ext.notes
        .insert("data".into(), args.data.display().to_string());
    // The directories, which take work to fill, first; the single files, already checked, last.
    if let Some(dir) = &args.model_out {
        let m = write_model(workers[0].sim.as_mut(), &ext, dir)?;
        writeln!(
            out,
            "extended model written to {} (load with `flightid fly --model {0}` or `flightid replay --model {0}`)",
            m.dir.display()
        )?;
    }
    if let Some(dir) = &args.report {
        let index = report::write_report(&d, &args.aircraft, &train, valid.as_ref(), dir)?;
        eprintln!("report written to {}", index.display());
    }
    if let Some(p) = &args.extension_out {
        write_atomic(p, serde_json::to_string_pretty(&ext)?.as_bytes())?;
    }
    if let Some(target) = &args.json {
        emit_json(target, &d)?;
    }
    Ok(())
}

/// Terminal summary: named causes with value ± standard error, and the validation gain.
fn summary(d: &Diagnosis, workers: usize, out: &mut dyn Write) -> std::io::Result<()> {
    if d.named_cause.is_empty() {
        writeln!(
            out,
            "no significant model error found (no extension passes the BIC, significance and validation tests)"
        )?;
    }
    for c in &d.named_cause {
        write!(
            out,
            "named cause: {} on {} = {:.5} ± {:.5}",
            c.effect, c.target, c.value, c.std_error
        )?;
        if !c.ambiguous_with.is_empty() {
            write!(
                out,
                "  (cannot be told apart from: {})",
                c.ambiguous_with.join(", ")
            )?;
        }
        writeln!(out)?;
    }
    for m in &d.trim_mismatch {
        writeln!(
            out,
            "trim: {:<13} measured {:+.5}  model {:+.5}",
            m.quantity, m.measured, m.model
        )?;
    }
    if let Some(v) = &d.validation {
        writeln!(
            out,
            "validation (weighted ISE): {:.1} -> {:.1} ({:.0} % less)",
            v.ise_before,
            v.ise_after,
            100.0 * (1.0 - v.ise_after / v.ise_before)
        )?;
        for (c, before) in &v.fit_percent_before {
            let after = v.fit_percent_after.get(c).copied().unwrap_or(f64::NAN);
            writeln!(out, "  {c:<13} fit {before:6.1} % -> {after:6.1} %")?;
        }
    } else {
        writeln!(
            out,
            "no validation record (--validate): the gain on unseen data is not measured"
        )?;
    }
    for w in &d.warnings {
        super::warn(w);
    }
    for s in &d.skipped {
        if s.effect != "aero_derivative" {
            let text = format!("skipped {} on {}: {}", s.effect, s.target, s.reason);
            for line in
                crate::report::text::wrap(&text, crate::report::text::TERMINAL_WIDTH, "", "  ")
            {
                writeln!(out, "{line}")?;
            }
        }
    }
    writeln!(
        out,
        "{} simulations in {:.1} s ({:.0} % of the workers' time inside the simulation)",
        d.simulations,
        d.wall_s,
        100.0 * d.simulation_s / d.wall_s.max(1e-9) / workers.max(1) as f64
    )?;
    Ok(())
}
