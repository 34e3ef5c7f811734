//! `flightid replay`: drive the simulation with measured deflections and compare every output channel.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::common::emit_json;
use super::common::{ColumnsArg, LoadingArg};
use super::UsageError;
use crate::diagnose::analyse_replay;
use crate::diagnose::extension::ExtensionFile;
use crate::diagnose::model::ExtendedModel;
use crate::diagnose::replay::ReplayCase;
use crate::diagnose::workers::{start_workers, SimSource};

/// Replay a measured record on the aircraft's simulation (trimmed at the measured initial condition, surfaces
/// driven with the measured deflections), optionally with fitted extensions, and compare the outputs.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid replay --aircraft c172x --data flight.csv --extension ext.json --json"
)]
pub struct ReplayCmd {
    /// Aircraft configuration.
    #[arg(long, default_value = "c172x")]
    pub aircraft: String,
    #[command(flatten)]
    pub loading: LoadingArg,
    /// Measured record (flight-data CSV).
    #[arg(long)]
    pub data: PathBuf,
    /// Extension file written by `flightid diagnose --extension-out`.
    #[arg(long)]
    pub extension: Option<PathBuf>,
    /// Extended model directory written by `flightid diagnose --model-out` (its aircraft and its extension.json).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["linear", "extension"])]
    pub model: Option<PathBuf>,
    /// Use a linear model (`flightid linearize --json` output) as the simulation.
    #[arg(long, value_name = "LIN.json")]
    pub linear: Option<PathBuf>,
    /// Print the comparison as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    #[command(flatten)]
    pub columns: ColumnsArg,
}

/// Runs `flightid replay`.
pub fn run(args: &ReplayCmd) -> anyhow::Result<()> {
    super::common::check_outputs(&[super::common::json_path(&args.json)], &[])?;
    let rec = args.columns.read(&args.data)?;
    let case = ReplayCase::new(&rec)?;
    // what preparing the record did to it (a dropout cut, a start inside a maneuver)
    for note in &case.sampling_notes {
        eprintln!("warning: {note}");
    }
    let model = args.model.as_deref().map(ExtendedModel::read).transpose()?;
    // read (and range-checked) before any simulation starts
    let extension = match (&model, &args.extension) {
        (None, Some(p)) => Some(ExtensionFile::read(p).map_err(|e| UsageError(e.to_string()))?),
        _ => None,
    };
    // The loading an extension file was fitted with, then the command line's.
    let loading: Vec<String> = extension
        .iter()
        .flat_map(|f| f.properties.iter().map(|(k, v)| format!("{k}={v}")))
        .chain(args.loading.properties.iter().cloned())
        .collect();
    let source = match (&model, &args.linear) {
        (Some(m), _) => SimSource::Model(m, &loading),
        (None, Some(p)) => SimSource::Linear(p),
        (None, None) => SimSource::Aircraft(&args.aircraft, &loading),
    };
    let mut workers = start_workers(&source, case.sim_rate_hz(), 1)?;
    let names = workers[0].sim.coefficient_names();
    let exts = match (&model, &extension) {
        (Some(m), _) => m.effects(&names)?,
        (None, Some(f)) => f.build(&names).map_err(|e| UsageError(e.to_string()))?,
        (None, None) => Vec::new(),
    };
    let refs: Vec<_> = exts
        .iter()
        .map(|(e, p)| (e.as_ref(), p.as_slice()))
        .collect();
    let (_, stats, trim) = analyse_replay(&mut workers[0], &case, &refs)?;
    if let Some(target) = &args.json {
        let mut v = BTreeMap::new();
        v.insert("residuals", serde_json::to_value(&stats)?);
        v.insert("trim_mismatch", serde_json::to_value(&trim)?);
        return emit_json(target, &v);
    }
    println!(
        "{:<13} {:>9} {:>12} {:>10}",
        "channel", "fit %", "rms", "white p"
    );
    for (c, s) in &stats {
        println!(
            "{c:<13} {:9.1} {:12.5} {:10.3}",
            s.fit_percent, s.rms, s.whiteness_p
        );
    }
    for m in &trim {
        println!(
            "trim: {:<13} measured {:+.5}  model {:+.5}",
            m.quantity, m.measured, m.model
        );
    }
    if let Some(w) = crate::diagnose::baseline::loading_warning(&trim) {
        eprintln!("warning: {w}");
    }
    Ok(())
}
