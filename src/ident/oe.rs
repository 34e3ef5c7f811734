//! `oe` — output error: Levenberg–Marquardt on the simulated output of the continuous model,
//! with Cramér–Rao standard errors corrected for coloured residuals.
//!
//! Cost (Morelli & Klein 2016, *Aircraft System Identification*, 2nd ed., ch. 6):
//! `J(θ) = ½ Σ_k (y(k) − ŷ(k; θ))²`, `ŷ = B(s)/A(s) · e^{−τs} u` simulated exactly for a ZOH
//! input, `θ = [b_0 … b_m, a_1 … a_n, (τ)]`.
//!
//! Sensitivities by filtering (Ljung 1999 §10.3): with `ξ = e^{−τs}u / A(s)²`,
//! - `∂ŷ/∂b_j = s^j A(s) ξ`,
//! - `∂ŷ/∂a_i = −s^{n−i} B(s) ξ`,
//!
//! all linear combinations of the 2n states of one SVF run for `1/A²`; `∂ŷ/∂τ` by a central
//! difference. Levenberg–Marquardt step `(H + μ diag H) δ = Sᵀr` with `H = SᵀS`
//! (Marquardt 1963).
//!
//! Standard errors: the Cramér–Rao bound `Cov = σ² (SᵀS)⁻¹` assumes white residuals. Residuals of
//! real models are coloured, which makes that bound optimistic; the correction of Morelli &
//! Klein (NASA CR-194893, 1994; book §6.6) uses the residual autocorrelation `R_vv`:
//! `Cov = M⁻¹ [Σ_i Σ_j s_i R_vv(i−j) s_jᵀ] M⁻¹`, `M = SᵀS`, summed over the lags where the
//! residuals are correlated (see [`coloured_covariance`]).

use super::filter::{simulate, Hold, Svf};
use super::linalg::{inverse, poly_mul};
use super::{ContinuousModel, IdentError};
use crate::estimate::covariance::coloured_covariance;
use crate::optimise;
use crate::signal::sum_sq;
use faer::Mat;

const MAX_ITER: usize = 100;

/// The numerator and monic denominator of `theta` = [num (m+1), a_1..a_n].
fn num_den(theta: &[f64], m: usize) -> (&[f64], Vec<f64>) {
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[m + 1..]);
    (&theta[..=m], den)
}

/// Simulated output for parameters `theta` = [num (m+1), a_1..a_n].
fn sim(theta: &[f64], m: usize, u: &[f64], dt_s: f64, delay_s: f64) -> Vec<f64> {
    let (num, den) = num_den(theta, m);
    simulate(num, &den, u, dt_s, delay_s)
}

/// How [`sensitivities`] differentiates the simulated output with respect to `[num…, a…]`.
#[derive(Clone, Copy)]
enum Differentiation {
    /// By filtering (module docs): fast, for the Levenberg–Marquardt steps.
    Filtered,
    /// By central differences of the exact simulation: for the covariance, where the
    /// small-eigenvalue directions of `SᵀS` (the slow modes) need the sensitivities to full
    /// precision.
    CentralDifference,
}

/// Sensitivity matrix (N × p, row-major) at `theta`: the columns of `[num…, a…]` by `how`, and a
/// last column for τ (a central difference in both cases) when `with_delay`.
fn sensitivities(
    theta: &[f64],
    m: usize,
    u: &[f64],
    dt_s: f64,
    delay_s: f64,
    with_delay: bool,
    how: Differentiation,
) -> Vec<f64> {
    let mut columns = match how {
        Differentiation::Filtered => filtered_columns(theta, m, u, dt_s, delay_s),
        Differentiation::CentralDifference => fd_columns(theta, m, u, dt_s, delay_s),
    };
    if with_delay {
        columns.push(delay_column(theta, m, u, dt_s, delay_s));
    }
    let p = columns.len();
    let mut s = vec![0.0; u.len() * p];
    for (j, col) in columns.iter().enumerate() {
        for (k, v) in col.iter().enumerate() {
            s[k * p + j] = *v;
        }
    }
    s
}

/// `∂ŷ/∂b` and `∂ŷ/∂a` by filtering, one column per parameter of `theta`.
fn filtered_columns(theta: &[f64], m: usize, u: &[f64], dt_s: f64, delay_s: f64) -> Vec<Vec<f64>> {
    let (num, den) = num_den(theta, m);
    let n = den.len() - 1;
    let a2 = poly_mul(&den, &den);
    let svf = Svf::new(&a2, dt_s, Hold::Zoh { delay_s });
    let xi = svf.run(u);
    // ∂ŷ/∂b (num index c ↔ s^{m−c}): s^{m−c} A ξ
    let d_num = (0..=m).map(|c| {
        let mut poly = den.clone();
        poly.extend(std::iter::repeat_n(0.0, m - c));
        xi.combine(&poly)
    });
    // ∂ŷ/∂a_i = −s^{n−i} B ξ
    let d_den = (1..=n).map(|i| {
        let mut poly: Vec<f64> = num.iter().map(|b| -b).collect();
        poly.extend(std::iter::repeat_n(0.0, n - i));
        xi.combine(&poly)
    });
    d_num.chain(d_den).collect()
}

/// Central-difference sensitivities of the exact simulation, one column per parameter of `theta`.
fn fd_columns(theta: &[f64], m: usize, u: &[f64], dt_s: f64, delay_s: f64) -> Vec<Vec<f64>> {
    let scale = theta.iter().fold(0.0_f64, |a, t| a.max(t.abs()));
    (0..theta.len())
        .map(|j| {
            let h = 1e-6 * theta[j].abs().max(1e-6 * scale).max(1e-12);
            let mut tp = theta.to_vec();
            let mut tm = theta.to_vec();
            tp[j] += h;
            tm[j] -= h;
            let yp = sim(&tp, m, u, dt_s, delay_s);
            let ym = sim(&tm, m, u, dt_s, delay_s);
            yp.iter()
                .zip(&ym)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        })
        .collect()
}

/// `∂ŷ/∂τ` by a central difference (one-sided when τ is within the step of zero).
fn delay_column(theta: &[f64], m: usize, u: &[f64], dt_s: f64, delay_s: f64) -> Vec<f64> {
    let h = 0.1 * dt_s;
    let (lo, hi) = if delay_s > h {
        (delay_s - h, delay_s + h)
    } else {
        (delay_s, delay_s + h)
    };
    let y_lo = sim(theta, m, u, dt_s, lo);
    let y_hi = sim(theta, m, u, dt_s, hi);
    y_hi.iter()
        .zip(&y_lo)
        .map(|(a, b)| (a - b) / (hi - lo))
        .collect()
}

/// `SᵀS` and `Sᵀr`.
fn normal(s: &[f64], r: &[f64], p: usize) -> (Vec<f64>, Vec<f64>) {
    let mut h = vec![0.0; p * p];
    let mut g = vec![0.0; p];
    for (k, rk) in r.iter().enumerate() {
        let row = &s[k * p..(k + 1) * p];
        for a in 0..p {
            g[a] += row[a] * rk;
            for b in a..p {
                h[a * p + b] += row[a] * row[b];
            }
        }
    }
    for a in 0..p {
        for b in 0..a {
            h[a * p + b] = h[b * p + a];
        }
    }
    (h, g)
}

/// Appends a column of ones (the sensitivity of the output offset `c`) to an N × p matrix.
fn with_offset_column(s: &[f64], p: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(s.len() / p * (p + 1));
    for row in s.chunks_exact(p) {
        out.extend_from_slice(row);
        out.push(1.0);
    }
    out
}

/// The damping schedule and stopping rule of the transfer-function output-error fits: a step
/// that lowers the cost by less than 1e-12 of it ends the iterations.
pub(super) fn lm_options(max_iterations: usize) -> optimise::Options {
    optimise::Options {
        max_iterations,
        tolerance: 1e-12,
        min_decrease: 0.0,
        damping: optimise::Damping {
            initial: 1e-3,
            min: 1e-12,
            decrease: 10.0,
            increase: 10.0,
            tries: 12,
        },
        solver: optimise::StepSolver::Marquardt,
    }
}

/// One record's output error for [`optimise::levenberg_marquardt`]: `x = [b…, a…, (τ), c]`.
struct OutputError<'a> {
    u: &'a [f64],
    y: &'a [f64],
    dt_s: f64,
    m: usize,
    with_delay: bool,
    /// τ when it is not estimated.
    fixed_delay_s: f64,
    lower: Vec<f64>,
}

impl OutputError<'_> {
    /// The model parameters `[b…, a…]` of `x` and the delay τ, s (estimated or fixed).
    fn model_and_delay<'x>(&self, x: &'x [f64]) -> (&'x [f64], f64) {
        let np = x.len() - 1 - usize::from(self.with_delay);
        let delay_s = if self.with_delay {
            x[np]
        } else {
            self.fixed_delay_s
        };
        (&x[..np], delay_s)
    }

    /// `y − ŷ(x)`.
    fn residuals(&self, x: &[f64]) -> Vec<f64> {
        let (model, delay_s) = self.model_and_delay(x);
        let c = x[x.len() - 1];
        let y_hat = sim(model, self.m, self.u, self.dt_s, delay_s);
        self.y.iter().zip(&y_hat).map(|(a, b)| a - b - c).collect()
    }
}

impl optimise::Problem for OutputError<'_> {
    type Point = Vec<f64>;
    type Error = std::convert::Infallible;

    fn evaluate(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, Self::Error> {
        Ok(Some(self.residuals(x)))
    }

    fn cost(&self, r: &Vec<f64>) -> f64 {
        sum_sq(r)
    }

    fn linearise(
        &mut self,
        x: &[f64],
        r: &Vec<f64>,
    ) -> Result<Option<optimise::Linearised>, Self::Error> {
        let (model, delay_s) = self.model_and_delay(x);
        let p = x.len() - 1;
        let s = with_offset_column(
            &sensitivities(
                model,
                self.m,
                self.u,
                self.dt_s,
                delay_s,
                self.with_delay,
                Differentiation::Filtered,
            ),
            p,
        );
        Ok(Some(optimise::Linearised {
            sensitivities: Mat::from_fn(r.len(), p + 1, |k, j| s[k * (p + 1) + j]),
            residuals: r.clone(),
        }))
    }

    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &[])
    }
}

/// Output-error estimate from `start` (usually SRIVC); `with_delay` adds τ as a parameter.
///
/// A constant output offset `c` (ŷ = B/A·u + c) is always estimated beside the model: the trim
/// removed by [`super::identify`] is the mean of the few samples before the input moves, and its
/// noise, left unmodelled, biases the slow poles (phugoid, spiral) by many standard errors — on
/// the paper's φ/δa with 1 % noise the spiral landed up to 20σ away. The returned covariance is
/// the marginal block of `[num…, a…, (τ)]` from the full covariance including `c`.
pub(crate) fn oe(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    start: ContinuousModel,
    with_delay: bool,
) -> Result<ContinuousModel, IdentError> {
    let m = start.num.len() - 1;
    let n = start.den.len() - 1;
    let np = m + 1 + n;
    let p = np + usize::from(with_delay);
    let pf = p + 1;
    // x = [b…, a…, (τ), c]; τ ≥ 0
    let mut x: Vec<f64> = start.num.clone();
    x.extend_from_slice(&start.den[1..]);
    if with_delay {
        x.push(start.delay_s);
    }
    x.push(start.y_bias);
    let mut lower = vec![f64::NEG_INFINITY; pf];
    if with_delay {
        lower[np] = 0.0;
    }
    let mut problem = OutputError {
        u,
        y,
        dt_s,
        m,
        with_delay,
        fixed_delay_s: start.delay_s,
        lower,
    };
    let r0 = problem.residuals(&x);
    if !optimise::Problem::cost(&problem, &r0).is_finite() {
        return Err(IdentError::Failed {
            method: "oe".into(),
            reason: "the starting model's simulation overflows".into(),
        });
    }
    let Ok(min) = optimise::levenberg_marquardt(&mut problem, x, r0, &lm_options(MAX_ITER));
    let theta = min.x[..np].to_vec();
    let delay_s = if with_delay { min.x[np] } else { start.delay_s };
    let c = min.x[p];
    // covariance at the optimum, from central-difference sensitivities of the exact simulation
    let s = sensitivities(
        &theta,
        m,
        u,
        dt_s,
        delay_s,
        with_delay,
        Differentiation::CentralDifference,
    );
    let cov = marginal_covariance(&s, &problem.residuals(&min.x), p);
    let (num, den) = num_den(&theta, m);
    Ok(ContinuousModel {
        num: num.to_vec(),
        den,
        delay_s,
        y_bias: c,
        cov,
        warnings: start.warnings,
    })
}

/// Parameter covariance of a given model (e.g. SRIVC's estimate) by the same rule as [`oe`]:
/// coloured-residual Cramér–Rao bound from exact sensitivities, output offset included and
/// marginalised. At convergence SRIVC's filtered instruments are these sensitivities, so this is
/// Young's SRIVC covariance `σ² [Σ ζ̂_f ζ̂_fᵀ]⁻¹` (Young 2011, *Recursive Estimation and
/// Time-Series Analysis*, §8.3) with the coloured-residual correction.
pub(crate) fn covariance(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    model: &ContinuousModel,
) -> Option<Vec<f64>> {
    let m = model.num.len() - 1;
    let mut theta = model.num.clone();
    theta.extend_from_slice(&model.den[1..]);
    let s = sensitivities(
        &theta,
        m,
        u,
        dt_s,
        model.delay_s,
        false,
        Differentiation::CentralDifference,
    );
    let y_hat = sim(&theta, m, u, dt_s, model.delay_s);
    let r: Vec<f64> = y
        .iter()
        .zip(&y_hat)
        .map(|(a, b)| a - b - model.y_bias)
        .collect();
    marginal_covariance(&s, &r, theta.len())
}

/// The coloured-residual covariance ([`coloured_covariance`]) of the `p` model parameters whose
/// sensitivities are `s` (N × p, row-major), with the output offset `c` estimated beside them and
/// marginalised out; `None` when `SᵀS` is singular.
fn marginal_covariance(s: &[f64], r: &[f64], p: usize) -> Option<Vec<f64>> {
    let pf = p + 1;
    let s = with_offset_column(s, p);
    let (mmat, _) = normal(&s, r, pf);
    inverse(&mmat, pf).map(|minv| {
        let full = coloured_covariance(&s, r, &minv, pf);
        (0..p * p).map(|k| full[(k / p) * pf + k % p]).collect()
    })
}
