//! `flightid estimate`: fit a model written in a TOML file to measured records, or identify a
//! linear model by subspace identification (docs/estimate.md).

use std::path::PathBuf;

use super::common::ColumnsArg;
use super::UsageError;
use crate::data;
use crate::estimate::{self, InputHold, Method, Options, Record, SubspaceOptions, UserModel};

/// Fit a model you write (TOML: states, inputs, outputs, parameters, equations) to flight records,
/// or identify a linear state-space model with no model file at all (`--method n4sid`).
///
/// Parameters written `"auto"` in the model file get their start values from the records
/// (subspace identification of the measured states, then equation error).
#[derive(clap::Args, Debug, Clone)]
pub struct EstimateCmd {
    /// Model file (docs/estimate.md). Needed by oe and fem; with n4sid it gives the inputs, the
    /// outputs, the order (its number of states) and, when the states are outputs, their basis.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Flight-data CSV; repeat for a joint fit (one parameter set, nuisance terms per record).
    #[arg(long = "data", required = true)]
    pub data: Vec<PathBuf>,
    #[command(flatten)]
    pub columns: ColumnsArg,
    /// Estimator: oe (output error), fem (filter error: a steady-state Kalman filter in the loop
    /// with the process noise estimated; for records with turbulence or drift), or n4sid
    /// (subspace identification of a linear model: no start values, no iterations).
    #[arg(long, default_value = "oe")]
    pub method: String,
    /// n4sid without --model: input columns, comma-separated (e.g. elevator_rad).
    #[arg(long, value_delimiter = ',')]
    pub inputs: Vec<String>,
    /// n4sid without --model: output columns, comma-separated (e.g. alpha_rad,q_rad_s).
    #[arg(long, value_delimiter = ',')]
    pub outputs: Vec<String>,
    /// n4sid: model order (default: the model file's number of states, else the largest gap in
    /// the singular values up to 8).
    #[arg(long)]
    pub order: Option<usize>,
    /// Inputs between samples: linear (default) or zoh.
    #[arg(long = "input-hold", default_value = "linear")]
    pub input_hold: String,
    /// Write the estimate as JSON to this file ("-" for stdout).
    #[arg(long)]
    pub json: Option<String>,
    /// Write a report to this directory (index.html, report.md, SVG overlays of measured vs model
    /// output and the residuals, the correlation matrix). Replaces only an empty directory or an
    /// earlier flightid report. With oe and fem.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// Runs `flightid estimate`.
pub fn run(args: &EstimateCmd) -> anyhow::Result<()> {
    let method = match args.method.as_str() {
        "oe" => Some(Method::Oe),
        "fem" => Some(Method::Fem),
        "n4sid" => None,
        other => {
            return Err(UsageError(format!("--method {other}: available: oe, fem, n4sid")).into())
        }
    };
    let hold: InputHold = args.input_hold.parse().map_err(UsageError)?;
    if args.report.is_some() && method.is_none() {
        return Err(UsageError("--report is available with --method oe and fem".into()).into());
    }
    super::common::check_outputs(
        &[super::common::json_path(&args.json)],
        &[args.report.as_deref()],
    )?;
    let model = match &args.model {
        Some(path) => Some(UserModel::load(path).map_err(|e| UsageError(e.to_string()))?),
        None => None,
    };
    // Each log in uniformly sampled pieces: split at dropouts, jittered timestamps resampled (docs/data.md).
    let mut flights = Vec::new();
    for path in &args.data {
        flights.extend(args.columns.read_pieces(path)?);
    }
    let usage = |e: &dyn std::fmt::Display| UsageError(e.to_string());
    let Some(method) = method else {
        return subspace(args, model.as_ref(), &flights, hold);
    };
    let Some(model) = model else {
        return Err(UsageError(format!("--method {} needs --model FILE.toml", args.method)).into());
    };
    let records = flights
        .iter()
        .map(|(name, rec)| model.record(rec, name).map_err(|e| usage(&e)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut parameters = model.parameters.clone();
    if !model.auto_start.is_empty() {
        let state_records = flights
            .iter()
            .map(|(name, rec)| model.state_record(rec, name).map_err(|e| usage(&e)))
            .collect::<Result<Vec<_>, _>>()?;
        let start = estimate::start_values(
            &model,
            &parameters,
            &model.auto_start,
            &state_records,
            &records,
            hold,
        )
        .map_err(|e| usage(&e))?;
        let shown: Vec<String> = model
            .auto_start
            .iter()
            .map(|&j| {
                format!(
                    "{} = {:.6}",
                    start.parameters[j].name, start.parameters[j].value
                )
            })
            .collect();
        eprintln!(
            "start values from the records (subspace fit of the states in {:.3} s, then equation \
             error on {}): {}",
            start.subspace.wall_s,
            start.equations.join(", "),
            shown.join(", ")
        );
        parameters = start.parameters;
    }
    let options = Options {
        method,
        hold,
        ..Options::default()
    };
    let est = estimate::fit(&model, &parameters, &records, &model.nuisance, &options)?;
    // As `check`: a fit that diverged or did not converge is an error, and nothing is printed or written.
    est.outcome()?;
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

/// `--method n4sid`: the channels and order from the model file or the command line.
fn subspace(
    args: &EstimateCmd,
    model: Option<&UserModel>,
    flights: &[(String, data::FlightRecord)],
    hold: InputHold,
) -> anyhow::Result<()> {
    let (inputs, outputs, order) = match model {
        Some(m) => {
            let sig = estimate::StateModel::signature(m);
            (
                sig.inputs.clone(),
                sig.outputs.clone(),
                Some(sig.states.len()),
            )
        }
        None => {
            if args.inputs.is_empty() || args.outputs.is_empty() {
                return Err(UsageError(
                    "--method n4sid needs --model FILE.toml, or --inputs and --outputs".into(),
                )
                .into());
            }
            (args.inputs.clone(), args.outputs.clone(), None)
        }
    };
    let order = args.order.or(order);
    let records = flights
        .iter()
        .map(|(name, rec)| {
            Record::from_columns(rec, &inputs, &outputs, name)
                .map_err(|e| UsageError(e.to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // the model's states as the basis, when each is an output
    let basis: Option<Vec<usize>> = model.and_then(|m| {
        estimate::StateModel::signature(m)
            .states
            .iter()
            .map(|s| outputs.iter().position(|o| o == s))
            .collect()
    });
    let options = SubspaceOptions {
        order,
        hold,
        ..SubspaceOptions::default()
    };
    let sub = estimate::subspace(&records, &inputs, &outputs, basis.as_deref(), &options)?;
    print!("{}", sub.table());
    if let Some(target) = &args.json {
        super::common::emit_json(target, &sub.to_json())?;
    }
    Ok(())
}
