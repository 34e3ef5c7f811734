//! Attitude scale factors from the flight-path reconstruction, for the records a replay cannot judge them on.
//!
//! A scale error on the logged φ or θ changes the measurement, not the flight. The replay sees it only against
//! the attitude the model flies open loop, and in turbulence that attitude wanders by degrees from the
//! aircraft's: the selection weights φ by its residual (×99 on a record of the independent generator) and a φ
//! logged × 0.85 came out 0.87 ± 0.07, not named. The rates, though, integrate to the aircraft's own attitude
//! whatever the air does (Klein & Morelli eq. 10.2), and the compatibility check ([`data::check_compatibility`])
//! estimates the scale of φ and θ against that: −0.161 ± 0.003 on the same record.
//!
//! After the selection, a scale factor the reconstruction finds ([`KINEMATIC_Z`] standard errors, beyond the
//! entry's resolution) on an attitude the selection left alone is tested in the replay against its only
//! kinematic twin, the gyro of that axis scaled the other way (p for φ, q for θ, value 1/k): the rates
//! integrate to the same attitude either way, and only the aerodynamics tell them apart. The one of lower cost
//! is named with the reconstruction's value and standard error when it lowers the cost of the selected model;
//! the other joins its ambiguity group when the two costs are within the selection's own rule (n_eff ln(J/J₀)
//! < 10).

use super::extension::Extension;
use super::prepare::Prepared;
use super::search::{residuals, Active, Worker};
use super::select::Selection;
use super::{sim_err, Candidate, DiagnoseError, DiagnoseOptions, NamedCause};
use crate::data::{self, FlightRecord};

/// Least |s| / σ of the reconstruction's scale factor for the stage to test it (the check's own line is 3; its
/// clean turbulent records stay under 2.5).
pub const KINEMATIC_Z: f64 = 10.0;

/// The attitudes with a scale factor in the reconstruction: (its column, its name there, the gyro of its axis).
const ATTITUDES: [(&str, &str, &str); 2] = [
    ("phi_rad", "scale_phi", "p_rad_s"),
    ("theta_rad", "scale_theta", "q_rad_s"),
];

/// Names the attitude scale factors the reconstruction of `train` finds and the selection did not (module
/// doc), adding them to `sel` held at the reconstruction's value.
pub fn attitude_scales<'e>(
    worker: &mut Worker,
    train: &FlightRecord,
    p: &'e Prepared,
    sel: &mut Selection<'e>,
    opts: &DiagnoseOptions,
) -> Result<(), DiagnoseError> {
    let Ok(report) = data::check_compatibility(train, &data::CheckOptions::default()) else {
        return Ok(());
    };
    if !report.converged {
        return Ok(());
    }
    let w = p.training();
    let m = w.case.len();
    for (column, name, gyro) in ATTITUDES {
        let Some(est) = report.instrument.iter().find(|e| e.name == name) else {
            continue;
        };
        let entry = |target: &str| {
            let i = sel
                .entries
                .catalogue
                .iter()
                .position(|e| e.effect() == "sensor_scale" && e.target() == target)?;
            Some((sel.entries.catalogue[i], sel.entries.resolution[i]))
        };
        let Some((own, resolution)) = entry(column) else {
            continue;
        };
        let taken = sel
            .selected
            .iter()
            .any(|a| a.ext.effect() == "sensor_scale" && [column, gyro].contains(&a.ext.target()));
        let z = est.value.abs() / est.std_error.max(f64::MIN_POSITIVE);
        if taken
            || sel.named.len() >= opts.max_effects
            || z < KINEMATIC_Z
            || est.value.abs() < resolution
        {
            continue;
        }
        let k = 1.0 + est.value;
        let cost_of = |worker: &mut Worker, extra: Option<Active<'e>>| {
            let mut active = sel.selected.clone();
            active.extend(extra);
            residuals(worker, &w, &active)
                .map(|r| (crate::signal::sum_sq(&r), r))
                .map_err(sim_err("replay"))
        };
        let (before, _) = cost_of(worker, None)?;
        let mut tried = vec![(own, k, cost_of(worker, Some(held(own, k)))?)];
        if let Some((twin, _)) = entry(gyro) {
            tried.push((twin, 1.0 / k, cost_of(worker, Some(held(twin, 1.0 / k)))?));
        }
        tried.sort_by(|a, b| a.2 .0.total_cmp(&b.2 .0));
        let (ext, value, (after, r)) = &tried[0];
        let n_eff = super::residual::effective_n(r, m);
        if *after >= before {
            continue;
        }
        let ambiguous_with = tried[1..]
            .iter()
            .filter(|(_, _, (c, _))| n_eff * (c / after).ln() < 10.0)
            .map(|(e, _, _)| e.key())
            .collect();
        let std_error = est.std_error
            * if ext.target() == gyro {
                value * value
            } else {
                1.0
            };
        sel.named.push(NamedCause {
            effect: ext.effect().into(),
            target: ext.target().into(),
            value: *value,
            std_error,
            ambiguous_with,
        });
        sel.candidates.push(Candidate {
            effect: ext.effect().into(),
            target: ext.target().into(),
            value: *value,
            std_error,
            cost_before: before,
            cost_after: *after,
            criterion: "kinematics".into(),
            criterion_delta: n_eff * (after / before).ln(),
            z,
            n_eff,
            resolution,
            validation_gain: None,
            rejected_because: None,
            round: sel.named.len() - 1,
            full_fit: true,
            held_out_share: None,
        });
        sel.selected.push(held(*ext, *value));
    }
    Ok(())
}

/// `ext` held at `value`.
fn held(ext: &dyn Extension, value: f64) -> Active<'_> {
    Active {
        ext,
        params: vec![value],
        free: false,
    }
}
