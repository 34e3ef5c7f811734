//! The model order chosen from the data when the user gives none.
//!
//! Every candidate `(poles, zeros)` with `1 ≤ poles ≤ max_poles`, `zeros < poles` is identified with
//! the requested estimator and judged on its simulation fit (Ljung, *System Identification*, 2nd
//! ed., §16.4–16.6: compare model structures on the simulation error, prefer the simplest that
//! explains the data). A candidate is set aside when
//! - it fails (the estimator's own error);
//! - it has a pole that grows more than 20-fold over the record (`Re p · T > 3`) — the record's
//!   response stayed bounded, so such a pole describes noise or a wrong structure;
//! - a pole and a zero (nearly) cancel (`|p − z| < 5 % |p|`) — a pole the data do not need;
//! - a pole is not significant: its magnitude is below twice its standard error (when the
//!   estimator gives one);
//! - it has a slowly growing pole (`0 < Re p · T ≤ 3`) and does not beat the best candidate without
//!   one by [`UNSTABLE_MARGIN_PERCENT`]: a slow divergence is usually an initial transient, a drift
//!   or a bias the model absorbs, and is kept only when the data clearly need it (a spiral mode).
//!
//! Among the rest the simplest (fewest parameters, then the better fit) whose simulation fit is
//! within [`FIT_MARGIN_PERCENT`] of the best is chosen: each extra parameter has to buy at least
//! that much fit. The candidates and the verdict on each are returned for the table.

use serde::Serialize;

use super::{identify, IdentError, IdentOptions, IdentResult, Method};

/// Fit (percentage points of NRMSE fit) an extra pole or zero has to buy.
pub const FIT_MARGIN_PERCENT: f64 = 1.0;

/// Fit a candidate with a slowly growing pole has to gain over the best one without.
pub const UNSTABLE_MARGIN_PERCENT: f64 = 5.0;

/// One order tried.
#[derive(Clone, Debug, Serialize)]
pub struct OrderCandidate {
    /// Number of poles.
    pub poles: usize,
    /// Number of zeros.
    pub zeros: usize,
    /// Simulation fit, % (`None` when the estimator failed).
    pub fit_sim_percent: Option<f64>,
    /// Why it was set aside (`None`: eligible).
    pub set_aside: Option<String>,
}

/// The chosen model with every candidate.
#[derive(Clone, Debug)]
pub struct OrderSelection {
    /// The identified model at the chosen order.
    pub result: IdentResult,
    /// Chosen number of poles.
    pub poles: usize,
    /// Chosen number of zeros.
    pub zeros: usize,
    /// Every order tried, in the order tried.
    pub candidates: Vec<OrderCandidate>,
}

/// Identifies `u → y` at every order up to `max_poles` and chooses one (module doc).
pub fn select_order(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    method: Method,
    estimate_delay: bool,
    max_poles: usize,
) -> Result<OrderSelection, IdentError> {
    let record_s = u.len() as f64 * dt_s;
    let mut candidates = Vec::new();
    let mut eligible: Vec<(usize, IdentResult)> = Vec::new();
    let mut slow_unstable: Vec<(usize, IdentResult)> = Vec::new();
    let mut first_error = None;
    for poles in 1..=max_poles.max(1) {
        for zeros in 0..poles {
            let opts = IdentOptions {
                method,
                poles,
                zeros,
                estimate_delay,
            };
            let (fit, set_aside) = match identify(u, y, dt_s, &opts) {
                Err(e) => {
                    let reason = e.to_string();
                    first_error.get_or_insert(e);
                    (None, Some(reason))
                }
                Ok(r) => {
                    let fit = r.fit_sim_percent;
                    let why = reject(&r, record_s);
                    let slow = slow_growth(&r);
                    match (&why, &slow) {
                        _ if !fit.is_finite() => {}
                        (None, None) => eligible.push((candidates.len(), r)),
                        (None, Some(_)) => slow_unstable.push((candidates.len(), r)),
                        _ => {}
                    }
                    (Some(fit), why.or(slow))
                }
            };
            candidates.push(OrderCandidate {
                poles,
                zeros,
                fit_sim_percent: fit,
                set_aside,
            });
        }
    }
    let best_stable = eligible
        .iter()
        .map(|(_, r)| r.fit_sim_percent)
        .fold(f64::NEG_INFINITY, f64::max);
    for (i, r) in slow_unstable {
        if r.fit_sim_percent > best_stable + UNSTABLE_MARGIN_PERCENT {
            candidates[i].set_aside = None;
            eligible.push((i, r));
        }
    }
    let best = eligible
        .iter()
        .map(|(_, r)| r.fit_sim_percent)
        .fold(f64::NEG_INFINITY, f64::max);
    let chosen = eligible
        .into_iter()
        .filter(|(_, r)| r.fit_sim_percent >= best - FIT_MARGIN_PERCENT)
        .min_by(|(a, ra), (b, rb)| {
            let size = |i: &usize| candidates[*i].poles + candidates[*i].zeros;
            size(a)
                .cmp(&size(b))
                .then(rb.fit_sim_percent.total_cmp(&ra.fit_sim_percent))
        });
    match chosen {
        Some((i, result)) => Ok(OrderSelection {
            result,
            poles: candidates[i].poles,
            zeros: candidates[i].zeros,
            candidates,
        }),
        None => Err(match first_error {
            // every candidate failed the same way the first did (too few samples, constant input …)
            Some(e) if candidates.iter().all(|c| c.fit_sim_percent.is_none()) => e,
            _ => IdentError::InvalidOptions(format!(
                "no order up to {max_poles} poles describes these data: {}; give --poles and --zeros \
                 to see one anyway",
                candidates
                    .iter()
                    .map(|c| format!(
                        "{}/{} {}",
                        c.poles,
                        c.zeros,
                        c.set_aside.as_deref().unwrap_or("")
                    ))
                    .collect::<Vec<_>>()
                    .join("; ")
            )),
        }),
    }
}

/// Why a fitted candidate is not eligible (module doc), or `None`.
fn reject(r: &IdentResult, record_s: f64) -> Option<String> {
    if let Some(p) = r.poles.iter().find(|p| p.re * record_s > 3.0) {
        return Some(format!("unstable pole {:.3}{:+.3}i", p.re, p.im));
    }
    for p in &r.poles {
        if let Some(z) = r.zeros.iter().find(|z| (**z - *p).norm() < 0.05 * p.norm()) {
            return Some(format!(
                "pole {:.3}{:+.3}i cancels zero {:.3}{:+.3}i",
                p.re, p.im, z.re, z.im
            ));
        }
    }
    for (p, s) in r.poles.iter().zip(&r.pole_std) {
        if 2.0 * s.norm() > p.norm() && p.norm() > 0.0 {
            return Some(format!(
                "pole {:.3}{:+.3}i insignificant (σ {:.3})",
                p.re,
                p.im,
                s.norm()
            ));
        }
    }
    None
}

/// A slowly growing pole (`Re p > 0`, not caught by [`reject`]), described for the table.
fn slow_growth(r: &IdentResult) -> Option<String> {
    r.poles.iter().find(|p| p.re > 0.0).map(|p| {
        format!(
            "slowly growing pole {:.3}{:+.3}i, not {UNSTABLE_MARGIN_PERCENT} points better than the best stable order",
            p.re, p.im
        )
    })
}
