//! Stage 3b, values in turbulence: the named effects refitted by the filter error method.
//!
//! The selection runs on output error, whose residual statistics (the coloured-residual standard errors and
//! effective sample counts with a lag window fitted to the residual) keep gust responses from being named as
//! causes. Output-error *values* are biased in turbulence, though: the fit bends the named effects towards
//! the gusts' response (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., §5.1). Once the causes
//! are named, the extended model's residual holds the gusts and the noise only, so the process noise is
//! estimated from it ([`super::process_noise::estimate`]) and, when the likelihood finds it, the named
//! effects are refitted jointly on the filter's innovations.

use super::process_noise::{self, ProcessNoise};
use super::search::{self, Worker};
use super::select::{drop_below_resolution, Selection};
use super::{prepare::Prepared, sim_err, DiagnoseError};

/// Refits the named effects of `sel` on the filter error method's innovations when the extended model's
/// residual carries process noise; `columns` are the segment initial-state responses. Returns the process
/// noise found (`used`: the values are the filter's; None when nothing is named or the error dynamics cannot
/// be formed).
pub fn refit_in_turbulence(
    worker: &mut Worker,
    p: &Prepared,
    columns: &[Vec<f64>],
    sel: &mut Selection,
) -> Result<Option<ProcessNoise>, DiagnoseError> {
    if sel.selected.is_empty() || columns.is_empty() {
        return Ok(None);
    }
    let r = search::raw_residuals(worker, &p.case, &p.sigma, &sel.selected)
        .map_err(sim_err("replay"))?;
    let Some((filter, report)) = process_noise::estimate(&p.case, columns, &r) else {
        return Ok(None);
    };
    let Some(filter) = filter else {
        return Ok(Some(report));
    };
    let mut filtered = columns.to_vec();
    filtered.iter_mut().for_each(|c| filter.apply(c));
    let basis = search::orthonormal_basis(&filtered);
    let w = search::Weighted {
        case: &p.case,
        sigma: p.sigma.clone(),
        nuisance: &basis,
        filter: Some(&filter),
        correction: None,
    };
    // A sensor bias stays at its output-error value: to the filter a constant offset on a rate gyro looks like
    // a steady moment disturbance, which the process noise on the body rates partly tracks.
    let mut active = sel.selected.clone();
    active
        .iter_mut()
        .for_each(|a| a.free = a.ext.effect() != "sensor_bias");
    if !active.iter().any(|a| a.free) {
        return Ok(Some(report));
    }
    // At the coarse rate from the output-error values, then at the replay's rate from there.
    let reference = sel.selected.clone();
    let coarse = search::coarse(std::slice::from_mut(worker), &w, &reference, |ws, cw| {
        search::fit(&mut ws[0], cw, &mut active, 10, false)
    })
    .and_then(|fitted| fitted)
    .map_err(sim_err("filter error refit"))?;
    let o = search::polish(worker, &w, &mut active, &coarse.sensitivities)
        .map_err(sim_err("filter error refit"))?;
    // One parameter per named effect is reported, the first; the fit's free parameters are in the same order.
    let mut k = 0;
    for (a, named) in active.iter_mut().zip(sel.named.iter_mut()) {
        if a.free {
            named.value = a.params[0];
            named.std_error = o.std_errors.get(k).copied().unwrap_or(f64::NAN);
            k += a.params.len();
        }
        a.free = false;
    }
    sel.selected = active;
    // The refit may move an effect named by output error back to "no effect": it goes, as after any joint fit.
    drop_below_resolution(&mut sel.selected, &mut sel.named, &mut sel.candidates);
    Ok(Some(report))
}

/// The warning that says the named values are the filter error method's.
pub fn warning(n: &ProcessNoise) -> String {
    format!(
        "the extended model's residual carries process noise (turbulence, or dynamics that no named effect \
         explains): the named effects' values are the filter error method's (likelihood gain {:.0} against a \
         penalty of {:.0})",
        n.likelihood_gain, n.penalty
    )
}
