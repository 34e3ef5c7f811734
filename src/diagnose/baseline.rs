//! Stage 2, baseline: the unextended model replayed on the records, its residual statistics, trim comparison
//! and noise-weighted costs.

use std::collections::BTreeMap;

use super::extension::Extension;
use super::prepare::Prepared;
use super::replay::{ReplayCase, TrimMismatch};
use super::residual::{self, ChannelResidual};
use super::search::{residuals, simulate, Worker};
use super::{sim_err, DiagnoseError};
use crate::data::FlightRecord;

/// A replayed record, its residual statistics per channel and the trim comparison.
pub type ReplayAnalysis = (
    FlightRecord,
    BTreeMap<String, ChannelResidual>,
    Vec<TrimMismatch>,
);

/// Replays a case with extensions and analyses every channel.
pub fn analyse_replay(
    worker: &mut Worker,
    case: &ReplayCase,
    extensions: &[(&dyn Extension, &[f64])],
) -> Result<ReplayAnalysis, DiagnoseError> {
    let (rec, trim) = simulate(worker, case, extensions).map_err(sim_err("replay"))?;
    let stats = case
        .outputs
        .iter()
        .filter_map(|c| {
            rec.column(c).map(|yhat| {
                (
                    c.clone(),
                    residual::analyse(case.measured(c), yhat, case.dt_s(), &case.inputs),
                )
            })
        })
        .collect();
    Ok((rec, stats, case.trim_mismatch(&trim)))
}

/// The unextended model on the records.
pub struct Baseline {
    /// Residual statistics per channel on the training record.
    pub residuals: BTreeMap<String, ChannelResidual>,
    /// Model trim vs measured initial condition.
    pub trim_mismatch: Vec<TrimMismatch>,
    /// Noise-weighted cost on the training record.
    pub cost: f64,
    /// Noise-weighted cost on the validation record.
    pub valid_cost: Option<f64>,
    /// The simulated training record.
    pub trace: FlightRecord,
}

/// Replays the unextended model on the training (and validation) record.
pub fn baseline(worker: &mut Worker, p: &Prepared) -> Result<Baseline, DiagnoseError> {
    let (trace, residuals_before, trim_mismatch) = analyse_replay(worker, &p.case, &[])?;
    let w = p.training();
    let cost = crate::signal::sum_sq(&residuals(worker, &w, &[]).map_err(sim_err("replay"))?);
    let valid_cost = match p.validation() {
        Some(vw) => {
            let r = residuals(worker, &vw, &[]).map_err(sim_err("validation replay"))?;
            Some(crate::signal::sum_sq(&r))
        }
        None => None,
    };
    Ok(Baseline {
        residuals: residuals_before,
        trim_mismatch,
        cost,
        valid_cost,
        trace,
    })
}
