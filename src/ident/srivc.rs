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

use super::filter::{Columns, Hold, Svf};
use super::linalg::{dot, poly_from_roots, solve_square, stabilize_continuous};
use super::{nrmse_fit, ContinuousModel, IdentError};
use num_complex::Complex64;

/// Maximum SRIVC iterations (CONTSID's default is 10–20; convergence is usually reached in 5).
const MAX_ITER: usize = 30;

/// The iterations stop when no parameter moves by more than this, relative. The fixed-point
/// iteration converges linearly (each step shrinks the change 3–15-fold on the JSBSim records),
/// so what is left is of the order of this change, while the smallest relative standard error
/// seen on clean 60 s JSBSim records is 2.5e-4: 1e-6 stops 250× below the statistical resolution,
/// three to six iterations earlier than 1e-9 did.
const CONVERGED: f64 = 1e-6;

/// One IV step with the prefilter `svf_y` (`1/Â_f`, first-order hold for the output) and the
/// input already filtered by it (`xu`, zero-order hold and delay); `aux_num` = None means plain
/// LS (instruments = regressors). With `with_offset` a constant output offset `c` is estimated
/// too: for `y = B/A·u + c`, the filtered equation gains the term `c·A(s)/Â(s)·1(t)`, which is `c`
/// itself once `Â = A`, so `c` enters as one more regressor (and instrument) equal to 1 (Young
/// 2011, *Recursive Estimation and Time-Series Analysis*, §8.6, offset parameters). Returns
/// `(num, den, c)`.
///
/// The normal equations are assembled column by column, `[Σ ζ̂_f φ_fᵀ]_rc = ⟨ζ̂_r, φ_c⟩` over the
/// filtered signals, each inner product over contiguous memory.
fn iv_step(
    y: &[f64],
    m: usize,
    svf_y: &Svf,
    xu: &Columns,
    aux_num: Option<&[f64]>,
    with_offset: bool,
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let n = svf_y.n;
    let xy = svf_y.run(y);
    let target = svf_y.top_derivative(&xy, y);
    let sx = aux_num.map(|b| svf_y.run(&xu.combine(b)));
    let ones = vec![1.0; if with_offset { y.len() } else { 0 }];
    // φ_f = [−y_f^{(n−1)} … −y_f, u_f^{(m)} … u_f, (1)], as (column, sign)
    let mut phi: Vec<(&[f64], f64)> = (0..n).map(|i| (xy.col(n - 1 - i), -1.0)).collect();
    phi.extend((0..=m).map(|j| (xu.col(m - j), 1.0)));
    if with_offset {
        phi.push((&ones, 1.0));
    }
    // ζ̂_f: the same with the auxiliary model's filtered output for y
    let mut zeta = phi.clone();
    if let Some(sx) = &sx {
        for (i, z) in zeta.iter_mut().take(n).enumerate() {
            *z = (sx.col(n - 1 - i), -1.0);
        }
    }
    let p = phi.len();
    // rows and columns where ζ̂ = φ form a symmetric block
    let shared = |k: usize| k >= n || sx.is_none();
    let mut zphi = vec![0.0; p * p];
    let mut zy = vec![0.0; p];
    for r in 0..p {
        let (zr, sr) = zeta[r];
        zy[r] = sr * dot(zr, &target);
        for c in 0..p {
            zphi[r * p + c] = if shared(r) && shared(c) && c < r {
                zphi[c * p + r]
            } else {
                sr * phi[c].1 * dot(zr, phi[c].0)
            };
        }
    }
    let theta = solve_square(&zphi, &zy)?;
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[..n]);
    let c = if with_offset { theta[p - 1] } else { 0.0 };
    Some((theta[n..=n + m].to_vec(), den, c))
}

/// Simulation fit (%) of a candidate's simulated output plus output offset `c`; −∞ when the
/// simulation overflowed (the caller reflects wild unstable poles first).
fn candidate_fit(y: &[f64], mut y_sim: Vec<f64>, c: f64) -> f64 {
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
///
/// One SVF run of the input per iteration serves twice: `u` filtered by the new `1/Â` gives the
/// candidate's simulated output `B̂/Â · u` (its fit) and, being the next prefilter, the next
/// iteration's filtered input and auxiliary-model output.
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
    let input_filter = |den_f: &[f64]| Svf::new(den_f, dt_s, Hold::Zoh { delay_s }).run(u);
    let mut den_f = stabilize_if_wild(&den, record_s);
    let mut xu = input_filter(&den_f);
    let mut best: Option<Iterate> = None;
    for _ in 0..MAX_ITER {
        let svf_y = Svf::new(&den_f, dt_s, Hold::Foh);
        let (num_new, den_new, c) = iv_step(y, m, &svf_y, &xu, Some(&num), true)?;
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
        den_f = stabilize_if_wild(&den, record_s);
        xu = input_filter(&den_f);
        let fit = candidate_fit(y, xu.combine(&num), c);
        if best.as_ref().is_none_or(|b| fit > b.3) {
            best = Some((num.clone(), den.clone(), c, fit));
        }
        if change < CONVERGED {
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
        let xu = Svf::new(&den_f, dt_s, Hold::Zoh { delay_s }).run(u);
        let svf_y = Svf::new(&den_f, dt_s, Hold::Foh);
        if let Some((num, den, _)) = iv_step(y, m, &svf_y, &xu, None, false) {
            let y_sim =
                super::filter::simulate(&num, &stabilize_if_wild(&den, record_s), u, dt_s, delay_s);
            let fit = candidate_fit(y, y_sim, 0.0);
            if best.as_ref().is_none_or(|b| fit > b.2) {
                best = Some((num, den, fit));
            }
        }
    }
    best.map(|(num, den, _)| (num, den))
}

/// Prefilter break frequencies tried for the SVF-LS start (one record or all records stacked), rad/s.
pub(super) fn lambdas(dt_s: f64) -> Vec<f64> {
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
