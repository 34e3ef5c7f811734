//! Fit measures and residual tests shared by all estimators (Ljung 1999, *System
//! Identification*, §16.6 "Model validation"), and the paper's Integral Square Error.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::filter::simulate;
use super::linalg::{poly_from_roots, roots};
use super::{modes, nrmse_fit, ContinuousModel, IdentResult, Method, TransferFunction};

/// Lags used by the residual tests (Ljung's `resid` default, M = 25).
const MAX_LAG: usize = 25;

/// A correlation test against the 99 % bound ±2.58/√N of a white sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrelationTest {
    /// Lags in samples.
    pub lags: Vec<i64>,
    /// Normalised correlation at each lag.
    pub correlation: Vec<f64>,
    /// The 99 % confidence bound 2.58/√N.
    pub bound_99: f64,
    /// Fraction of lags whose |correlation| exceeds the bound.
    pub fraction_outside: f64,
    /// True when at most 5 % of the lags exceed the bound (1 % expected for a white sequence;
    /// the margin absorbs one chance excursion in 25 lags).
    pub pass: bool,
}

impl CorrelationTest {
    fn new(lags: Vec<i64>, correlation: Vec<f64>, n_samples: usize) -> CorrelationTest {
        let bound_99 = 2.58 / (n_samples as f64).sqrt();
        let outside = correlation.iter().filter(|c| c.abs() > bound_99).count();
        let fraction_outside = outside as f64 / correlation.len().max(1) as f64;
        CorrelationTest {
            lags,
            correlation,
            bound_99,
            fraction_outside,
            pass: fraction_outside <= 0.05,
        }
    }
}

/// Cross-covariance `(1/N) Σ a(k) b(k−lag)` of zero-mean sequences.
fn cross_cov(a: &[f64], b: &[f64], lag: i64) -> f64 {
    let n = a.len();
    let mut s = 0.0;
    if lag >= 0 {
        let l = lag as usize;
        for k in l..n {
            s += a[k] * b[k - l];
        }
    } else {
        let l = (-lag) as usize;
        for k in 0..n.saturating_sub(l) {
            s += a[k] * b[k + l];
        }
    }
    s / n as f64
}

fn demean(v: &[f64]) -> Vec<f64> {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().map(|x| x - m).collect()
}

/// Residual autocorrelation test, lags 1…25.
pub(crate) fn whiteness(e: &[f64]) -> CorrelationTest {
    let e = demean(e);
    let r0 = cross_cov(&e, &e, 0).max(f64::MIN_POSITIVE);
    let lags: Vec<i64> = (1..=MAX_LAG as i64).collect();
    let corr = lags.iter().map(|l| cross_cov(&e, &e, *l) / r0).collect();
    CorrelationTest::new(lags, corr, e.len())
}

/// Residual–input cross-correlation test, lags −25…25 (residual at k against input at k−lag).
pub(crate) fn independence(e: &[f64], u: &[f64]) -> CorrelationTest {
    let e = demean(e);
    let u = demean(u);
    let norm = (cross_cov(&e, &e, 0) * cross_cov(&u, &u, 0))
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let lags: Vec<i64> = (-(MAX_LAG as i64)..=MAX_LAG as i64).collect();
    let corr = lags.iter().map(|l| cross_cov(&e, &u, *l) / norm).collect();
    CorrelationTest::new(lags, corr, e.len())
}

/// Integral Square Error `∫ (y_true − y_model)² dt` by the trapezoidal rule (the paper's
/// Table 2 measure). Extra samples of the longer record are ignored.
pub fn ise(y_true: &[f64], y_model: &[f64], dt_s: f64) -> f64 {
    let n = y_true.len().min(y_model.len());
    if n < 2 {
        return 0.0;
    }
    let sq: Vec<f64> = (0..n)
        .map(|k| (y_true[k] - y_model[k]) * (y_true[k] - y_model[k]))
        .collect();
    dt_s * (sq.iter().sum::<f64>() - 0.5 * (sq[0] + sq[n - 1]))
}

/// One-step-ahead predictions of the ZOH-equivalent model in equation-error form:
/// `ŷ(k|k−1) = y(k) − [A_d(q)(y − ŷ_sim)](k)`, where `A_d(z) = Π (1 − e^{p_i h} z⁻¹)`; because
/// the simulated output satisfies `A_d ŷ_sim = B_d u` exactly, this equals the ARX predictor
/// `(1 − A_d) y + B_d u` without having to form `B_d`.
fn one_step(y: &[f64], y_sim: &[f64], poles: &[Complex64], dt_s: f64) -> Vec<f64> {
    let zd: Vec<Complex64> = poles.iter().map(|p| (p * dt_s).exp()).collect();
    let a_d = poly_from_roots(&zd);
    let e: Vec<f64> = y.iter().zip(y_sim).map(|(a, b)| a - b).collect();
    (0..y.len())
        .map(|k| {
            let mut s = 0.0;
            for (i, a) in a_d.iter().enumerate() {
                if k >= i {
                    s += a * e[k - i];
                }
            }
            y[k] - s
        })
        .collect()
}

/// Standard errors of Re and Im of each pole from the denominator covariance block `cov_a`
/// (n×n over a₁…a_n): `∂p/∂a_i = −p^{n−i} / A'(p)` (implicit differentiation of A(p) = 0).
fn pole_std(den: &[f64], poles: &[Complex64], cov_a: &[f64]) -> Vec<Complex64> {
    let n = den.len() - 1;
    poles
        .iter()
        .map(|p| {
            // A'(p)
            let mut d = Complex64::new(0.0, 0.0);
            for (i, c) in den.iter().enumerate().take(n) {
                d += c * (n - i) as f64 * p.powu((n - i - 1) as u32);
            }
            let g: Vec<Complex64> = (1..=n).map(|i| -p.powu((n - i) as u32) / d).collect();
            let quad = |f: &dyn Fn(&Complex64) -> f64| -> f64 {
                let mut s = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        s += f(&g[i]) * cov_a[i * n + j] * f(&g[j]);
                    }
                }
                s.max(0.0).sqrt()
            };
            Complex64::new(quad(&|c| c.re), quad(&|c| c.im))
        })
        .collect()
}

/// Assembles the public result: fits, tests, roots, modes and standard errors.
#[allow(clippy::too_many_arguments)]
pub(crate) fn build_result(
    method: Method,
    model: ContinuousModel,
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    delay_requested: bool,
    u_offset: f64,
    y_offset: f64,
) -> IdentResult {
    let mut y_sim = simulate(&model.num, &model.den, u, dt_s, model.delay_s);
    y_sim.iter_mut().for_each(|v| *v += model.y_bias);
    let poles = roots(&model.den);
    let zeros = roots(&model.num);
    // ls/iv carry the ARX (equation-error) noise model, whose one-step predictor is the ARX
    // predictor; srivc/oe assume white output noise, for which the predictor is the simulation.
    let y_one = match method {
        Method::Ls | Method::Iv => one_step(y, &y_sim, &poles, dt_s),
        Method::Srivc | Method::Oe => y_sim.clone(),
    };
    let e: Vec<f64> = y.iter().zip(&y_sim).map(|(a, b)| a - b).collect();
    let (nb, n) = (model.num.len(), model.den.len() - 1);
    let (num_std, den_std, p_std, delay_std_s) = match &model.cov {
        Some(cov) => {
            let p = (cov.len() as f64).sqrt().round() as usize;
            let sd = |i: usize| cov[i * p + i].max(0.0).sqrt();
            let num_std = (0..nb).map(sd).collect();
            let mut den_std = vec![0.0];
            den_std.extend((nb..nb + n).map(sd));
            let cov_a: Vec<f64> = (0..n * n)
                .map(|k| cov[(nb + k / n) * p + nb + k % n])
                .collect();
            let delay_std = (p > nb + n).then(|| sd(nb + n));
            (
                num_std,
                den_std,
                pole_std(&model.den, &poles, &cov_a),
                delay_std,
            )
        }
        None => (Vec::new(), Vec::new(), Vec::new(), None),
    };
    IdentResult {
        method: method.name().to_string(),
        tf: TransferFunction {
            num: model.num.clone(),
            den: model.den.clone(),
            dt_s: None,
        },
        delay_s: delay_requested.then_some(model.delay_s),
        num_std,
        den_std,
        delay_std_s,
        modes: modes(&poles),
        poles,
        pole_std: p_std,
        zeros,
        fit_sim_percent: nrmse_fit(y, &y_sim),
        fit_one_step_percent: nrmse_fit(y, &y_one),
        residual_whiteness: whiteness(&e),
        input_residual_independence: independence(&e, u),
        n_samples: y.len(),
        dt_s,
        u_offset,
        y_offset: y_offset + model.y_bias,
        warnings: model.warnings,
    }
}
