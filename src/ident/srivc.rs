//! `srivc` — simplified refined instrumental variable for continuous-time models
//! (Young & Jakeman 1980, "Refined instrumental variable methods of recursive time-series
//! analysis, Part III: extensions", IJC 31(4); the algorithm of Garnier's CONTSID toolbox,
//! Garnier, Gilson & Huselstein 2003, IFAC SYSID).
//!
//! Model: `A(s) y(t) = B(s) u(t − τ) + A(s) (e(t) + c)`, A monic of degree n, B of degree m,
//! `c` a constant output offset (the residual trim). Each iteration j, with the previous estimate (Â, B̂):
//! 1. prefilter every signal with the SVF bank `s^i / Â(s)` (i = 0..n) — the optimal prefilter
//!    for white output noise;
//! 2. auxiliary-model output `x̂ = B̂/Â · u` (the instrument source);
//! 3. solve the IV normal equations `Σ ζ̂_f φ_fᵀ θ = Σ ζ̂_f y_f^{(n)}` with
//!    `φ_f = [−y_f^{(n−1)} … −y_f, u_f^{(m)} … u_f, 1]` and `ζ̂_f` the same with `x̂_f` for
//!    `y_f` (the last entry estimates `c`, see [`iv_step`]).
//!
//! Unstable Â are reflected into the left half plane before filtering (as CONTSID does) only
//! when they would grow more than 20-fold over the record; a slow physical instability (the
//! spiral) is kept, see [`stabilize_if_wild`]. Reflection changes only the efficiency, not the
//! consistency, of the estimate.
//!
//! Initialisation: the plain SVF least-squares estimate (instruments = regressors) with the
//! fixed prefilter `(s + λ)^n`, tried for several λ; the one with the best simulation fit
//! starts the iterations, and the iterate with the best simulation fit is returned.

use super::filter::{Hold, Svf};
use super::linalg::{poly_from_roots, solve_square, stabilize_continuous};
use super::{nrmse_fit, ContinuousModel, IdentError};
use num_complex::Complex64;

/// Maximum SRIVC iterations (CONTSID's default is 10–20; convergence is usually reached in 5).
const MAX_ITER: usize = 30;

/// One IV step with prefilter `den_f`; `aux_num` = None means plain LS (instruments = regressors).
/// With `with_offset` a constant output offset `c` is estimated too: for `y = B/A·u + c`, the
/// filtered equation gains the term `c·A(s)/Â(s)·1(t)`, which is `c` itself once `Â = A`, so `c`
/// enters as one more regressor (and instrument) equal to 1 (Young 2011, *Recursive Estimation
/// and Time-Series Analysis*, §8.6, offset parameters). Returns `(num, den, c)`.
#[allow(clippy::too_many_arguments)]
fn iv_step(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    delay_s: f64,
    m: usize,
    den_f: &[f64],
    aux_num: Option<&[f64]>,
    with_offset: bool,
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let n = den_f.len() - 1;
    let len = y.len();
    let svf_u = Svf::new(den_f, dt_s, Hold::Zoh { delay_s });
    let svf_y = Svf::new(den_f, dt_s, Hold::Foh);
    let xu = svf_u.run(u);
    let xy = svf_y.run(y);
    let xx = aux_num.map(|b| {
        let xhat = super::filter::combine(&xu, n, b, len);
        let s = svf_y.run(&xhat);
        (xhat, s)
    });
    let p = n + m + 1 + usize::from(with_offset);
    let mut zphi = vec![0.0; p * p];
    let mut zy = vec![0.0; p];
    let mut phi = vec![0.0; p];
    let mut zeta = vec![0.0; p];
    for k in 0..len {
        for i in 0..n {
            phi[i] = -xy[k * n + n - 1 - i];
        }
        for j in 0..=m {
            phi[n + j] = xu[k * n + m - j];
        }
        if with_offset {
            phi[p - 1] = 1.0;
        }
        let target = svf_y.top_derivative(&xy, k, y[k]);
        match &xx {
            Some((_, sx)) => {
                for i in 0..n {
                    zeta[i] = -sx[k * n + n - 1 - i];
                }
                zeta[n..].copy_from_slice(&phi[n..]);
            }
            None => zeta.copy_from_slice(&phi),
        }
        for r in 0..p {
            let zr = zeta[r];
            zy[r] += zr * target;
            for c in 0..p {
                zphi[r * p + c] += zr * phi[c];
            }
        }
    }
    let theta = solve_square(&zphi, &zy)?;
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[..n]);
    let c = if with_offset { theta[p - 1] } else { 0.0 };
    Some((theta[n..=n + m].to_vec(), den, c))
}

/// Simulation fit (%) of a candidate model plus output offset `c`; the caller reflects wild
/// unstable poles first so a candidate cannot overflow.
#[allow(clippy::too_many_arguments)]
fn candidate_fit(
    num: &[f64],
    den: &[f64],
    c: f64,
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    delay_s: f64,
) -> f64 {
    let mut y_sim = super::filter::simulate(num, den, u, dt_s, delay_s);
    y_sim.iter_mut().for_each(|v| *v += c);
    let f = nrmse_fit(y, &y_sim);
    if f.is_finite() {
        f
    } else {
        f64::NEG_INFINITY
    }
}

/// An SRIVC iterate: numerator, denominator, output offset, simulation fit (%).
type Iterate = (Vec<f64>, Vec<f64>, f64, f64);

/// SRIVC iterations from a starting estimate; returns the iterate with the best simulation fit.
///
/// A constant output offset `c` (ŷ = B/A·u + c) is estimated beside the model (see [`iv_step`]),
/// as in `oe`: the trim removed by [`super::identify`] is the mean of the few samples before the
/// input moves, and its noise, left unmodelled, biases the slow poles (the spiral of the paper's
/// φ/δa landed 5σ off).
fn iterate(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    delay_s: f64,
    m: usize,
    start: (Vec<f64>, Vec<f64>),
) -> Option<Iterate> {
    let (mut num, mut den) = start;
    let record_s = y.len() as f64 * dt_s;
    let mut best: Option<Iterate> = None;
    for _ in 0..MAX_ITER {
        let den_f = stabilize_if_wild(&den, record_s);
        let aux_num = num.clone();
        let (num_new, den_new, c) = iv_step(u, y, dt_s, delay_s, m, &den_f, Some(&aux_num), true)?;
        if num_new.iter().chain(den_new.iter()).any(|v| !v.is_finite()) || !c.is_finite() {
            break;
        }
        let change = den_new
            .iter()
            .zip(&den)
            .chain(num_new.iter().zip(&num))
            .map(|(a, b)| (a - b).abs() / (1e-6 + b.abs()))
            .fold(0.0_f64, f64::max);
        num = num_new;
        den = den_new;
        let fit = candidate_fit(
            &num,
            &stabilize_if_wild(&den, record_s),
            c,
            u,
            y,
            dt_s,
            delay_s,
        );
        if best.as_ref().is_none_or(|b| fit > b.3) {
            best = Some((num.clone(), den.clone(), c, fit));
        }
        if change < 1e-9 {
            break;
        }
    }
    best
}

/// Reflects the poles only if one is unstable enough to grow more than e³ ≈ 20-fold over the
/// record (`record_s` seconds): slow unstable poles (an aircraft's spiral mode) are physical and
/// kept, both in the simulation and in the prefilter and auxiliary model. Reflecting a slow
/// spiral there leaves instruments that no longer resemble the noise-free output over a long
/// record: on the paper's φ/δa, 300 s doublet, the spiral then came out 10σ off.
fn stabilize_if_wild(den: &[f64], record_s: f64) -> Vec<f64> {
    let r = super::linalg::roots(den);
    if r.iter().all(|p| p.re * record_s < 3.0) {
        den.to_vec()
    } else {
        stabilize_continuous(den)
    }
}

/// The plain SVF least-squares estimate with prefilter `(s + λ)^n`, for the λ among a few
/// decade-spaced values (below a fifth of the Nyquist frequency) whose model simulates best.
pub(crate) fn svf_ls_start(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    n: usize,
    m: usize,
    delay_s: f64,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let record_s = y.len() as f64 * dt_s;
    let mut best: Option<(Vec<f64>, Vec<f64>, f64)> = None;
    for lambda in lambdas(dt_s) {
        let den_f = poly_from_roots(&vec![Complex64::new(-lambda, 0.0); n]);
        if let Some((num, den, _)) = iv_step(u, y, dt_s, delay_s, m, &den_f, None, false) {
            let fit = candidate_fit(
                &num,
                &stabilize_if_wild(&den, record_s),
                0.0,
                u,
                y,
                dt_s,
                delay_s,
            );
            if best.as_ref().is_none_or(|b| fit > b.2) {
                best = Some((num, den, fit));
            }
        }
    }
    best.map(|(num, den, _)| (num, den))
}

/// Prefilter break frequencies tried for the SVF-LS start, rad/s.
fn lambdas(dt_s: f64) -> Vec<f64> {
    let nyquist = std::f64::consts::PI / dt_s;
    [0.5, 2.0, 8.0, 30.0]
        .into_iter()
        .filter(|l| *l < 0.2 * nyquist)
        .collect()
}

/// SRIVC estimate with `m` zeros and `n` poles, for a known input delay.
pub(crate) fn srivc(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    n: usize,
    m: usize,
    delay_s: f64,
) -> Result<ContinuousModel, IdentError> {
    // iterate from the best-simulating SVF-LS start only (one IV chain keeps SRIVC < 100 ms)
    let best = svf_ls_start(u, y, dt_s, n, m, delay_s)
        .and_then(|start| iterate(u, y, dt_s, delay_s, m, start));
    match best {
        Some((num, den, y_bias, _)) => Ok(ContinuousModel {
            y_bias,
            ..ContinuousModel::new(num, den, delay_s)
        }),
        None => Err(IdentError::SingularRegression {
            method: "srivc".into(),
            rank: 0,
            n_params: n + m + 1,
        }),
    }
}
