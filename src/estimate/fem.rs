//! The filter error method: a steady-state Kalman filter in the loop, the process noise estimated
//! with the parameters (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., ch. 5;
//! Maine & Iliff, *Formulation and implementation of a practical algorithm for parameter
//! estimation with process and measurement noise*, SIAM J. Appl. Math. 41(3), 1981).
//!
//! Model: `ẋ = f(x, u, θ) + F w`, `z = h(x, u, θ) + b_y + v`, `w` unit white noise, `F` diagonal.
//! Per record, with the innovation covariance `R` held fixed during a parameter update:
//!
//! - gain: `A = ∂f/∂x`, `C = ∂h/∂x` at the record's initial state and first input (central
//!   differences; exact for a linear model), `P` the stabilising solution of
//!   `A P + P Aᵀ − P Cᵀ (Δt R)⁻¹ C P + F Fᵀ = 0` ([`super::riccati`]), `K = P Cᵀ R⁻¹`
//!   (Jategaonkar §5.3, the steady-state filter of a time-invariant or linearised system);
//! - filter: prediction `ỹ_k = h(x̃_k, u_k) + b_y`, innovation `v_k = z_k − ỹ_k`, correction
//!   `x̂_k = x̃_k + K v_k`, then `x̃_{k+1}` by integrating `f` from `x̂_k` over the sample
//!   interval with the nonlinear model (the "mixed" formulation for nonlinear systems: nonlinear
//!   state propagation, gain from the linearisation, recomputed at every evaluation, so every
//!   perturbed parameter vector gets its own gain — the finite-difference response gradients
//!   include the gain's dependence on θ and F, §5.4).
//!
//! The cost is the output-error cost with innovations in place of output errors, so the
//! optimiser, R relaxation and Cramér–Rao bounds are those of [`super::fit`]. Two additions:
//!
//! - **F–R compensation** (Maine & Iliff; Jategaonkar §5.5): after each R update, every `F_ii` is
//!   rescaled by `√(Σ_k C_ki² / R_kk,old ÷ Σ_k C_ki² / R_kk,new)`, which keeps the gain — and
//!   with it the progress of the parameter update — when R changes (scaling R and F F ᵀ by the
//!   same factor leaves `K` unchanged).
//! - **constraint**: `R = C P Cᵀ + G Gᵀ` needs `G Gᵀ ≥ 0`, i.e. the diagonal of `K C` at most 1
//!   (Jategaonkar §5.5). A trial step that breaks it is halved towards the current point until
//!   it holds (up to 8 times, then the damping grows), instead of Jategaonkar's linearised
//!   constraint in the update; finite-difference perturbations and the compensation may touch
//!   the boundary.
//!
//! The process noise is estimated as the variances `q_i = F_ii² ≥ 0` (reported as the nuisance
//! kind `process_noise`; `F_ii = √q_i`): the cost is even in `F`, so at `F = 0` its gradient
//! vanishes, whereas in `q` it does not and the bound `q ≥ 0` is an ordinary box constraint. A
//! record without process noise keeps `q` on its bound, `K = 0`, and the filter is the output-error
//! simulation: FEM gives the output-error answer.

use faer::Mat;

use super::integrate::{check_output, Propagation};
use super::model::{SimError, StateModel};
use super::record::Run;
use super::riccati::care_filter;

/// The steady-state gain of one record.
#[derive(Clone, Debug)]
pub(crate) struct Gain {
    /// `K`, `[state][output]`.
    pub k: Vec<Vec<f64>>,
    /// Largest diagonal entry of `K C` (the constraint is `≤ 1`).
    pub kc_max: f64,
}

/// `A = ∂f/∂x` (n×n) and `C = ∂h/∂x` (m×n) at `(x, u)` by central differences.
pub(crate) fn linearise(
    model: &dyn StateModel,
    theta: &[f64],
    x: &[f64],
    u: &[f64],
) -> (Mat<f64>, Mat<f64>) {
    let sig = model.signature();
    let (n, m) = (sig.states.len(), sig.outputs.len());
    let mut a = Mat::<f64>::zeros(n, n);
    let mut c = Mat::<f64>::zeros(m, n);
    let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
    let (mut hp, mut hm) = (vec![0.0; m], vec![0.0; m]);
    let mut xp = x.to_vec();
    for j in 0..n {
        let h = 1e-6 * x[j].abs().max(1e-3);
        xp[j] = x[j] + h;
        model.derivatives(theta, &xp, u, &mut fp);
        model.outputs(theta, &xp, u, &mut hp);
        xp[j] = x[j] - h;
        model.derivatives(theta, &xp, u, &mut fm);
        model.outputs(theta, &xp, u, &mut hm);
        xp[j] = x[j];
        for i in 0..n {
            a[(i, j)] = (fp[i] - fm[i]) / (2.0 * h);
        }
        for i in 0..m {
            c[(i, j)] = (hp[i] - hm[i]) / (2.0 * h);
        }
    }
    (a, c)
}

/// The steady-state gain for process-noise variances `q` (per state), innovation variances `r`
/// (per output) and sample interval `dt_s` (module doc), with the largest diagonal entry of `K C`
/// (the optimiser keeps it ≤ 1). `Err` when no stabilising solution exists.
pub(crate) fn gain(
    a: &Mat<f64>,
    c: &Mat<f64>,
    q: &[f64],
    r: &[f64],
    dt_s: f64,
) -> Result<Gain, SimError> {
    let (n, m) = (a.nrows(), c.nrows());
    let no_gain = || {
        Ok(Gain {
            k: vec![vec![0.0; m]; n],
            kc_max: 0.0,
        })
    };
    if q.iter().all(|v| *v == 0.0) && r.len() < m {
        // before any innovation variance (the first simulation of a fit): no filter yet
        return no_gain();
    }
    let qm = Mat::<f64>::from_fn(n, n, |i, j| if i == j { q[i] } else { 0.0 });
    let r_c = Mat::<f64>::from_fn(m, m, |i, j| if i == j { dt_s * r[i] } else { 0.0 });
    if q.iter().all(|v| *v == 0.0) {
        // Without process noise a stable model needs no correction (P = 0: the filter is the simulation).
        // An unstable one does: the stabilising solution of the Riccati equation with Q → 0⁺ keeps a gain on
        // the unstable modes (Kwakernaak & Sivan §4.4), so the gain, and the cost, jump at q = 0 if it is
        // taken as 0 there. That jump stopped the fit at its first step (a p51d lateral model with its
        // slightly divergent spiral, +0.02 /s).
        let stable = a
            .eigenvalues()
            .is_ok_and(|ev: Vec<num_complex::Complex64>| ev.iter().all(|e| e.re < 0.0));
        if stable {
            return no_gain();
        }
    }
    let p = care_filter(a, c, &qm, &r_c).ok_or_else(|| {
        SimError::Failed("the filter's Riccati equation has no stabilising solution".into())
    })?;
    let pct = &p * c.transpose();
    let k: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..m).map(|o| pct[(i, o)] / r[o]).collect())
        .collect();
    let mut kc_max = 0.0_f64;
    for (i, ki) in k.iter().enumerate() {
        let kc: f64 = (0..m).map(|o| ki[o] * c[(o, i)]).sum();
        if !kc.is_finite() {
            return Err(SimError::Failed("the filter gain is not finite".into()));
        }
        kc_max = kc_max.max(kc);
    }
    Ok(Gain { k, kc_max })
}

/// Rescales the process-noise variances after R moved from `r_old` to `r_new` (module doc:
/// F–R compensation), with `c` the output matrix.
pub(crate) fn compensate(q: &mut [f64], c: &Mat<f64>, r_old: &[f64], r_new: &[f64]) {
    for (i, qi) in q.iter_mut().enumerate() {
        let old: f64 = (0..c.nrows()).map(|o| c[(o, i)].powi(2) / r_old[o]).sum();
        let new: f64 = (0..c.nrows()).map(|o| c[(o, i)].powi(2) / r_new[o]).sum();
        if old > 0.0 && new > 0.0 && (old / new).is_finite() {
            *qi *= old / new;
        }
    }
}

/// The sample interval of a uniform grid (to 1e-6 relative), `None` otherwise.
fn uniform_step(time: &[f64]) -> Option<f64> {
    let n = time.len();
    let h = (time[n - 1] - time[0]) / (n - 1).max(1) as f64;
    time.windows(2)
        .all(|w| ((w[1] - w[0]) - h).abs() <= 1e-6 * h)
        .then_some(h)
}

/// One-step-ahead predicted outputs `ỹ_k` (output biases included), `[output][k]`, of the
/// steady-state filter with gain `gain` on measured outputs `z` (module doc).
pub(crate) fn filter(
    model: &dyn StateModel,
    theta: &[f64],
    x0: &[f64],
    run: &Run<'_>,
    output_bias: &[f64],
    z: &[Vec<f64>],
    gain: &Gain,
) -> Result<Vec<Vec<f64>>, SimError> {
    let sig = model.signature();
    let (nx, nu, ny) = (sig.states.len(), sig.inputs.len(), sig.outputs.len());
    let time = run.time_s;
    let n = time.len();
    let mut out = vec![vec![0.0; n]; ny];
    let mut p = Propagation::new(model, theta, x0, run);
    let mut v = vec![0.0; ny];
    // a linear model on a uniform, unskewed record steps exactly (as its simulation does)
    let exact = uniform_step(time).and_then(|h| {
        let samples = run.input.aligned_samples()?;
        Some((model.discrete(theta, h, run.input.hold())?, samples))
    });
    let mut next = vec![0.0; nx];
    for k in 0..n {
        if k > 0 {
            match &exact {
                Some((d, us)) => {
                    for (i, ni) in next.iter_mut().enumerate() {
                        let mut acc = 0.0;
                        for (l, xl) in p.x.iter().enumerate() {
                            acc += d.phi[i * nx + l] * xl;
                        }
                        for (j, uj) in us.iter().enumerate() {
                            acc += d.gamma1[i * nu + j] * uj[k - 1]
                                + d.gamma2[i * nu + j] * (uj[k] - uj[k - 1]);
                        }
                        *ni = acc;
                    }
                    p.x.copy_from_slice(&next);
                }
                None => p.integrate_to(k),
            }
            p.check_state(k)?;
        }
        p.outputs(k);
        for o in 0..ny {
            let yo = p.y[o] + output_bias[o];
            check_output(yo, &sig.outputs[o], time[k] - time[0])?;
            out[o][k] = yo;
            v[o] = z[o][k] - yo;
        }
        for (xi, ki) in p.x.iter_mut().zip(&gain.k) {
            *xi += ki.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>();
        }
    }
    Ok(out)
}
