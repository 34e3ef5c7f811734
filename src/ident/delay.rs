//! Pure input delay search wrapped around any estimator: a coarse grid over
//! 0 … min(1 s, record/10), then a local refinement — whole samples for the discrete methods
//! (`ls`, `iv`), a golden-section search (Kiefer 1953) for `srivc`; `oe` starts from the
//! SRIVC delay and refines τ as one more Levenberg–Marquardt parameter.
//!
//! Criterion: the simulation error `Σ (y − ŷ_sim)²` of the model fitted at that delay — for
//! `ls` the equation-error residual would reward delays that let the output lags explain
//! everything.

use super::filter::simulate;
use super::{estimate, oe, ContinuousModel, IdentError, IdentOptions, Method};

fn sim_cost(model: &ContinuousModel, u: &[f64], y: &[f64], dt_s: f64) -> f64 {
    let y_sim = simulate(&model.num, &model.den, u, dt_s, model.delay_s);
    let c: f64 = y.iter().zip(&y_sim).map(|(a, b)| (a - b) * (a - b)).sum();
    if c.is_finite() {
        c
    } else {
        f64::INFINITY
    }
}

/// Fits at each delay of a search and keeps the model with the lowest simulation error.
pub(crate) fn with_delay_search(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    opts: &IdentOptions,
) -> Result<ContinuousModel, IdentError> {
    let (n, m) = (opts.poles, opts.zeros);
    let base = if opts.method == Method::Oe {
        Method::Srivc
    } else {
        opts.method
    };
    let record_s = u.len() as f64 * dt_s;
    let max_delay_s = (record_s / 10.0).min(1.0);
    let max_samples = (max_delay_s / dt_s).floor() as usize;
    let mut best: Option<(f64, ContinuousModel)> = None;
    let mut last_err = None;
    let mut try_delay = |delay_s: f64, best: &mut Option<(f64, ContinuousModel)>| -> f64 {
        match estimate(u, y, dt_s, base, n, m, delay_s) {
            Ok(model) => {
                let c = sim_cost(&model, u, y, dt_s);
                if best.as_ref().is_none_or(|b| c < b.0) {
                    *best = Some((c, model));
                }
                c
            }
            Err(e) => {
                last_err = Some(e);
                f64::INFINITY
            }
        }
    };
    // coarse grid: at most 21 points, whole samples
    let step = (max_samples / 20).max(1);
    let grid: Vec<usize> = (0..=max_samples).step_by(step).collect();
    let mut best_k = 0;
    let mut best_c = f64::INFINITY;
    for &k in &grid {
        let c = try_delay(k as f64 * dt_s, &mut best);
        if c < best_c {
            best_c = c;
            best_k = k;
        }
    }
    let lo = best_k.saturating_sub(step);
    let hi = (best_k + step).min(max_samples);
    match base {
        Method::Ls | Method::Iv => {
            for k in lo..=hi {
                if !grid.contains(&k) {
                    try_delay(k as f64 * dt_s, &mut best);
                }
            }
        }
        _ => {
            // golden section on [lo, hi]·dt for the continuous estimators
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut a, mut b) = (lo as f64 * dt_s, hi as f64 * dt_s);
            let mut x1 = b - g * (b - a);
            let mut x2 = a + g * (b - a);
            let mut f1 = try_delay(x1, &mut best);
            let mut f2 = try_delay(x2, &mut best);
            while b - a > 0.02 * dt_s {
                if f1 < f2 {
                    b = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = b - g * (b - a);
                    f1 = try_delay(x1, &mut best);
                } else {
                    a = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = a + g * (b - a);
                    f2 = try_delay(x2, &mut best);
                }
            }
        }
    }
    let Some((_, model)) = best else {
        return Err(last_err.unwrap_or(IdentError::Failed {
            method: opts.method.name().into(),
            reason: "no delay in the search range gave a model".into(),
        }));
    };
    if opts.method == Method::Oe {
        oe::oe(u, y, dt_s, model, true)
    } else {
        Ok(model)
    }
}
