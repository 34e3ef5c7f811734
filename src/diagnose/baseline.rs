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

/// The difference between the record's trim elevator and the model's above which a loading other than the
/// model's is pointed out, rad (0.086°). The c172x replayed with its own loading trims within 0.0005 rad of the
/// independent generator's records, in still air and in light turbulence; 200 lb less fuel (8 % of its weight)
/// moves the trim elevator by 0.0034–0.0042 rad and α by 0.004–0.005 rad.
const LOADING_ELEVATOR_RAD: f64 = 0.0015;

impl Baseline {
    /// A warning when the record trims at another elevator than the unextended model: a weight, CG, flap setting
    /// or air density other than the simulation's moves the trim elevator and α as a change of `Cm_0` or of the
    /// lift does, and the search names such a change in its place (200 lb less fuel in the c172x: `Cm_0` ×2.4 on
    /// clean records).
    pub fn loading_warning(&self) -> Option<String> {
        loading_warning(&self.trim_mismatch)
    }
}

/// [`Baseline::loading_warning`] from a replay's trim comparison.
pub fn loading_warning(trim_mismatch: &[TrimMismatch]) -> Option<String> {
    let get = |q: &str| trim_mismatch.iter().find(|m| m.quantity == q);
    let e = get("elevator_rad")?;
    if (e.measured - e.model).abs() <= LOADING_ELEVATOR_RAD {
        return None;
    }
    let (measured_alpha, model_alpha) =
        get("alpha_rad").map_or((String::new(), String::new()), |a| {
            let deg = |x: f64| format!(" and α {:.2}°", x.to_degrees());
            (deg(a.measured), deg(a.model))
        });
    Some(format!(
        "the record trims at elevator {:.2}°{measured_alpha}, the model at {:.2}°{model_alpha} (same speed and \
         altitude): a weight, CG or flap setting other than the simulation's, or air of another density (a record \
         without density_kg_m3 or qbar_pa is flown in the standard atmosphere), moves the trim as a change of \
         Cm_0 or of the lift does, and the search names such a change in its place; so does an airspeed column \
         that holds equivalent, calibrated or indicated airspeed instead of true airspeed (declare it with \
         `airspeed = \"equivalent\"` in the --columns map). If the aircraft flew loaded or configured otherwise, \
         give that with --property (docs/diagnose.md, \"Loading\")",
        e.measured.to_degrees(),
        e.model.to_degrees(),
    ))
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
