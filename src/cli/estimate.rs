//! `flightid estimate`: fit a model written in a TOML file to measured records (docs/estimate.md).

use std::path::PathBuf;

use super::UsageError;
use crate::data;
use crate::estimate::{self, InputHold, Method, Options, UserModel};

/// Fit a model you write (TOML: states, inputs, outputs, parameters, equations) to flight records.
#[derive(clap::Args, Debug, Clone)]
pub struct EstimateCmd {
    /// Model file (docs/estimate.md).
    #[arg(long)]
    pub model: PathBuf,
    /// Flight-data CSV; repeat for a joint fit (one parameter set, nuisance terms per record).
    #[arg(long = "data", required = true)]
    pub data: Vec<PathBuf>,
    /// Estimator: oe (output error) or fem (filter error: a steady-state Kalman filter in the
    /// loop with the process noise estimated; for records with turbulence or drift).
    #[arg(long, default_value = "oe")]
    pub method: String,
    /// Inputs between samples: linear (default) or zoh.
    #[arg(long = "input-hold", default_value = "linear")]
    pub input_hold: String,
    /// Write the estimate as JSON to this file ("-" for stdout).
    #[arg(long)]
    pub json: Option<String>,
    /// Write a report to this directory (index.html, report.md, SVG overlays of measured vs model
    /// output and the residuals, the correlation matrix). Replaces only an empty directory or an
    /// earlier flightid report.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Runs `flightid estimate`.
pub fn run(args: &EstimateCmd) -> anyhow::Result<()> {
    let method = match args.method.as_str() {
        "oe" => Method::Oe,
        "fem" => Method::Fem,
        other => return Err(UsageError(format!("--method {other}: available: oe, fem")).into()),
    };
    let hold: InputHold = args.input_hold.parse().map_err(UsageError)?;
    if let Some(dir) = &args.report {
        crate::report::check_output_dir(dir)?;
    }
    let model = UserModel::load(&args.model).map_err(|e| UsageError(e.to_string()))?;
    let mut records = Vec::new();
    for path in &args.data {
        let rec = data::read_csv(path)?;
        let name = path.display().to_string();
        records.push(
            model
                .record(&rec, &name)
                .map_err(|e| UsageError(e.to_string()))?,
        );
    }
    let options = Options {
        method,
        hold,
        ..Options::default()
    };
    let est = estimate::fit(
        &model,
        &model.parameters,
        &records,
        &model.nuisance,
        &options,
    )?;
    print!("{}", est.table());
    if let Some(target) = &args.json {
        super::common::emit_json(target, &est.to_json())?;
    }
    if let Some(dir) = &args.report {
        let index = crate::report::write_report_dir(dir, &est.report(), &est.to_json())?;
        eprintln!("report: {}", index.display());
    }
    Ok(())
}
