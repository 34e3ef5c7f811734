//! `flightid compare`: identified linear models vs JSBSim's linearization and nonlinear flight, as a report.

use super::common::{emit_json, TrimArgs};
use crate::cli::UsageError;
use crate::compare::{self, CompareOptions};
use crate::ident::Method;
use crate::sim::JsbsimSim;
use anyhow::Context;
use std::path::PathBuf;

/// Trim, linearize (JSBSim), fly elevator/aileron/rudder doublets, identify θ/δe, φ/δa, φ/δr with each method
/// and compare with the linearization: modal parameters with errors, Bode and time overlays, ISE and fit %,
/// and an amplitude sweep. Also probes the model's coefficient functions for kinks at the trim (terms in |β|,
/// table breakpoints) that the linearization cannot see, and where the linearization fits a response below
/// 80 % measures each kink's share by comparing again without it. Writes DIR/index.html (self-contained),
/// report.md, *.svg and report.json.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid compare --aircraft c172x --report out/compare\n  flightid compare --aircraft c172x --json out/compare.json\n  flightid compare --aircraft 737 --amplitude-deg 1 --method ls,srivc,oe --report out/737 --json out/737.json\n\nTesting why the linearization misses a response: scale one aerodynamic coefficient function of the model\n(both the nonlinear flight and the linearization use the scaled model). On c172x, phi/rudder fits the\nlinearization at ~26 %; without the sideslip drag CD_beta*|beta| (not differentiable at beta = 0, so the\nlinearization sees none of it) it fits at ~95 %:\n  flightid compare --aircraft c172x --scale CDbeta=0 --report out/no-cdbeta"
)]
pub struct CompareCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Doublet amplitude of the main comparison, deg.
    #[arg(long, default_value_t = 2.0, value_parser = crate::limits::AMPLITUDE_DEG.parser())]
    pub amplitude_deg: f64,
    /// Doublet pulse width, s.
    #[arg(long, default_value_t = 1.0, value_parser = crate::limits::PULSE_S.parser())]
    pub pulse_s: f64,
    /// Record length, s.
    #[arg(long, default_value_t = 20.0, value_parser = crate::limits::DURATION_S.parser())]
    pub duration_s: f64,
    /// Estimators, comma separated (ls, iv, srivc, oe).
    #[arg(long, value_delimiter = ',', default_value = "ls,srivc,oe")]
    pub method: Vec<String>,
    /// Amplitudes of the linearity sweep, deg, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "0.5,1,2,4,8,12")]
    pub sweep_deg: Vec<f64>,
    /// Report directory (index.html, report.md, *.svg, report.json); without it only the terminal summary and
    /// --json.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Also write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    /// Scale an aerodynamic coefficient function of the JSBSim model, NAME=FACTOR (e.g. CDbeta=0, Cnb=1.2);
    /// repeatable. Names are the model's `aero/coefficient/NAME` functions; an unknown name lists them.
    #[arg(long = "scale", value_name = "NAME=FACTOR", value_parser = parse_scale)]
    pub scales: Vec<(String, f64)>,
}

/// `NAME=FACTOR` with a finite factor.
fn parse_scale(s: &str) -> Result<(String, f64), String> {
    let (name, factor) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=FACTOR (e.g. CDbeta=0), got '{s}'"))?;
    let factor: f64 = factor
        .trim()
        .parse()
        .map_err(|_| format!("'{factor}' in '{s}' is not a number"))?;
    if !factor.is_finite() || name.trim().is_empty() {
        return Err(format!(
            "expected NAME=FACTOR with a finite factor, got '{s}'"
        ));
    }
    Ok((name.trim().to_string(), factor))
}

/// Runs `flightid compare`.
pub fn run(args: &CompareCmd) -> anyhow::Result<()> {
    super::common::check_outputs(
        &[super::common::json_path(&args.json)],
        &[args.report.as_deref()],
    )?;
    let cfg = args.trim.config()?;
    let point = args.trim.point(&cfg)?;
    let methods: Vec<Method> = args
        .method
        .iter()
        .map(|m| m.parse::<Method>().map_err(|e| UsageError(e.to_string())))
        .collect::<Result<_, _>>()?;
    let opts = CompareOptions {
        point,
        amplitude_deg: args.amplitude_deg,
        pulse_s: args.pulse_s,
        duration_s: args.duration_s,
        methods,
        sweep_amplitudes_deg: args.sweep_deg.clone(),
        rate_hz: args.trim.rate_hz,
    };
    let mut sim = JsbsimSim::start(&cfg, args.trim.rate_hz)
        .with_context(|| format!("starting JSBSim for {}", cfg.name))?;
    for (name, factor) in &args.scales {
        sim.set_coefficient_scale(name, *factor)
            .map_err(|e| UsageError(e.to_string()))?;
    }
    let compare::ExplainedComparison {
        outcome,
        report,
        json,
        verdicts,
    } = super::common::compare_with_spinner(&mut sim, &opts, &args.scales)?;
    let index = match &args.report {
        Some(dir) => Some(crate::report::write_report_dir(dir, &report, &json)?),
        None => None,
    };
    if let Some(target) = &args.json {
        emit_json(target, &json)?;
    }
    if args.json.as_deref() != Some("-") {
        for line in
            compare::notes::terminal_summary(&outcome, opts.duration_s, opts.rate_hz, &verdicts)
        {
            println!("{line}");
        }
        if let Some(index) = index {
            println!("report: {}", index.display());
        }
    }
    Ok(())
}
