//! `flightid derivatives`: aerodynamic derivatives backed out of identified transfer functions (the paper's
//! Section 5) and by equation error, scored against the JSBSim model's own values (Tables 1 and 3).

use super::common::{emit_json, TrimArgs};
use super::paper::text_table;
use crate::aero::AeroError;
use crate::cli::UsageError;
use crate::data;
use crate::ident::Method;
use crate::report;
use crate::report::text::{wrap, TERMINAL_WIDTH};
use crate::study::spec::{parse_derivatives, Structure};
use crate::study::trials::{SensorNoise, TrialOptions};
use crate::study::{self, Source, StudyOptions};
use std::path::PathBuf;

/// Model structure for the transfer-function route.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum StructureArg {
    /// The paper's simplifying assumptions.
    Paper,
    /// Every term the model knows, JSBSim's wind-axis side force.
    Full,
}

/// Estimate aerodynamic derivatives and score them against the aircraft's own (JSBSim) values.
///
/// Without --from/--data it flies elevator, aileron and rudder doublets on JSBSim, identifies θ/δe, φ/δa, φ/δr,
/// backs the derivatives out of them through the paper's parametric model, estimates them also by equation
/// error on the full state, and prints the paper's Table 1 (truth vs estimate, 3σ interval, identifiability)
/// and Table 3 (errors, 3σ coverage, targets, the structure term behind a miss).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid derivatives --aircraft c172x\n  flightid derivatives --aircraft c172x --noise --report deriv-report\n  flightid identify --data el.csv --input elevator --output theta_rad --json th.json && flightid derivatives --from th.json\n  flightid derivatives --data lateral.csv --json out.json"
)]
pub struct DerivativesCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Identified transfer functions (`flightid identify --json` output, or an array of them); repeatable.
    /// May carry `mass` / `geometry` objects replacing the JSBSim model's.
    #[arg(long, value_name = "IDENTIFIED.json", conflicts_with = "data")]
    pub from: Vec<PathBuf>,
    /// A flight-data CSV (docs/data.md) for equation error on the full state. Taken as a JSBSim record
    /// (`flightid fly`): its differentiated rates lag the moments by half a sample, which is modelled.
    #[arg(long, value_name = "FLIGHT.csv")]
    pub data: Option<PathBuf>,
    /// With --data: the CSV is measured sensor data, sampled together, with no integrator lag to model.
    #[arg(long, requires = "data")]
    pub sensor_data: bool,
    /// Model structure of the transfer-function route.
    #[arg(long = "model", value_enum, default_value = "paper")]
    pub structure: StructureArg,
    /// Free derivatives of the TF route, comma separated (default: Cm_alpha,Cm_q,Cm_alphadot,Cm_de,
    /// Cl_beta,Cl_p,Cl_da,Cn_beta,Cn_r).
    #[arg(long, value_delimiter = ',')]
    pub free: Option<Vec<String>>,
    /// Estimator of the transfer functions when flying: srivc or oe.
    #[arg(long, default_value = "srivc")]
    pub method: String,
    /// Add realistic sensor noise to the flown records (vanes 0.1°, AHRS 0.05°, gyros 0.1°/s, …).
    #[arg(long)]
    pub noise: bool,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    /// Write index.html, report.md and report.json into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Bad input (exit 2) vs failure (exit 1).
fn classify(e: AeroError) -> anyhow::Error {
    match e {
        AeroError::BadParameter { .. }
        | AeroError::UnknownDerivative(_)
        | AeroError::WrongTfOrder { .. }
        | AeroError::BadCovariance { .. }
        | AeroError::NothingToFit(_)
        | AeroError::BadRecord(_)
        | AeroError::BadInput(_) => UsageError(e.to_string()).into(),
        other => other.into(),
    }
}

/// Runs `flightid derivatives`.
pub fn run(args: &DerivativesCmd) -> anyhow::Result<()> {
    if let Some(dir) = &args.report {
        crate::report::check_output_dir(dir)?;
    }
    let free = match &args.free {
        Some(names) => Some(parse_derivatives(names).map_err(classify)?),
        None => None,
    };
    let method: Method = args
        .method
        .parse()
        .map_err(|e| UsageError(format!("--method: {e}")))?;
    let source = if let Some(path) = &args.data {
        let record = data::read_csv(path).map_err(|e| UsageError(e.to_string()))?;
        Source::Data {
            record,
            simulated: !args.sensor_data,
        }
    } else if !args.from.is_empty() {
        let mut docs = Vec::new();
        for p in &args.from {
            let text = std::fs::read_to_string(p)
                .map_err(|e| UsageError(format!("{}: {e}", p.display())))?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| UsageError(format!("{}: not JSON: {e}", p.display())))?;
            docs.push((p.display().to_string(), v));
        }
        Source::Identified(docs)
    } else {
        Source::Fly(TrialOptions {
            rate_hz: args.trim.rate_hz,
            noise: args.noise.then(SensorNoise::realistic),
            seed: args.seed,
            method,
            ..TrialOptions::default()
        })
    };
    let opts = StudyOptions {
        source,
        structure: match args.structure {
            StructureArg::Paper => Structure::Paper,
            StructureArg::Full => Structure::Full,
        },
        free,
        start_factor: 1.2,
    };
    let cfg = args.trim.config()?;
    let point = args.trim.point(&cfg)?;
    let progress = super::common::spinner("derivatives: trim, model check, flights, estimates");
    let mut sim = crate::sim::JsbsimSim::start(&cfg, args.trim.rate_hz)?;
    let result = study::run(&mut sim, &point, &opts).map_err(classify);
    progress.finish_and_clear();
    let result = result?;
    let quiet = args.json.as_deref() == Some("-");
    if !quiet {
        println!(
            "{} at {} ft, {} kts: derivatives vs the JSBSim model's own values\n",
            cfg.name, point.altitude_ft, point.speed_kts
        );
        for t in result.tables() {
            println!("{}", text_table(&t));
        }
        if !result.identifiability.is_empty() {
            println!("Identifiability (TF route):");
            for line in result.identifiability.lines() {
                let indent = &line[..line.len() - line.trim_start().len()];
                let rest = format!("{indent}    ");
                for l in wrap(line.trim_start(), TERMINAL_WIDTH, indent, &rest) {
                    println!("{l}");
                }
            }
        }
        for n in &result.notes {
            for l in wrap(n, TERMINAL_WIDTH, "- ", "  ") {
                println!("{l}");
            }
        }
    }
    let json = result.to_json();
    if let Some(dir) = &args.report {
        let index = report::write_report_dir(dir, &result.report(), &json)?;
        if !quiet {
            println!("\nreport: {}", index.display());
        }
    }
    if let Some(target) = &args.json {
        emit_json(target, &json)?;
    }
    Ok(())
}
