//! `flightid demo`: the main job on the embedded default — c172x at its default trim, three doublets, the
//! paper's least squares vs the robust estimators (SRIVC, output error) vs JSBSim's linearization, as a report.

use super::common::{emit_json, TrimArgs};
use crate::compare::{self, CompareOptions};
use crate::ident::Method;
use crate::sim::JsbsimSim;
use anyhow::Context;
use std::path::PathBuf;

/// Trim c172x (or --aircraft) at its default point, linearize it with JSBSim, fly an elevator, an aileron and a
/// rudder doublet, identify theta/elevator, phi/aileron and phi/rudder with the paper's least squares, SRIVC and
/// output error, and compare them with JSBSim's linearization: a summary on the terminal and a self-contained
/// HTML report (Bode and time overlays, amplitude sweep) whose path is printed.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid demo\n  flightid demo --report out/demo --json demo.json\n  flightid demo --aircraft 737"
)]
pub struct DemoCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Doublet amplitude, deg of surface deflection.
    #[arg(long, default_value_t = 2.0, value_parser = crate::limits::AMPLITUDE_DEG.parser())]
    pub amplitude_deg: f64,
    /// Record length per doublet, s.
    #[arg(long, default_value_t = 30.0, value_parser = crate::limits::DURATION_S.parser())]
    pub duration_s: f64,
    /// Report directory (replaced whole; index.html, report.md, *.svg, report.json).
    #[arg(long, default_value = "flightid-out/demo")]
    pub report: PathBuf,
    /// Write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
}

/// Runs `flightid demo`.
pub fn run(args: &DemoCmd) -> anyhow::Result<()> {
    super::common::check_outputs(
        &[super::common::json_path(&args.json)],
        &[Some(&args.report)],
    )?;
    let quiet = args.json.as_deref() == Some("-");
    let cfg = args.trim.config()?;
    let point = args.trim.point(&cfg)?;
    let opts = CompareOptions {
        point,
        amplitude_deg: args.amplitude_deg,
        pulse_s: 1.0,
        duration_s: args.duration_s,
        methods: vec![Method::Ls, Method::Srivc, Method::Oe],
        sweep_amplitudes_deg: vec![0.5, 1.0, 2.0, 4.0, 8.0],
        rate_hz: args.trim.rate_hz,
    };
    let mut sim = JsbsimSim::start(&cfg, args.trim.rate_hz)
        .with_context(|| format!("starting JSBSim for {}", cfg.name))?;
    let compare::ExplainedComparison {
        outcome,
        report,
        json,
        verdicts,
    } = super::common::compare_with_spinner(&mut sim, &opts, &[])?;
    let index = crate::report::write_report_dir(&args.report, &report, &json)?;
    if let Some(target) = &args.json {
        emit_json(target, &json)?;
    }
    if quiet {
        return Ok(());
    }
    for line in compare::notes::terminal_summary(&outcome, opts.duration_s, opts.rate_hz, &verdicts)
    {
        println!("{line}");
    }
    println!("\nreport: {}", index.display());
    Ok(())
}
