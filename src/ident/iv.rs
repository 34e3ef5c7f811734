//! `iv` — discrete-time instrumental variables in the δ-operator, with instruments from an
//! auxiliary model's simulated output (Söderström & Stoica 1989, *System Identification*, §8.2;
//! the refined-IV prefilter of Young 1976), then a ZOH conversion to continuous time.
//!
//! Why the δ-operator: at fast sampling the poles of the shift-operator (q) model crowd at
//! z = 1 and the regression on `y(k−1) … y(k−n)` is nearly singular; with 1 % output noise the
//! q-domain IV iterations of the paper's φ/δa and φ/δr diverged. The δ-operator
//! `δ = (q − 1)/h` (Middleton & Goodwin 1990, *Digital Control and Estimation: A Unified
//! Approach*, ch. 2) has poles `γ = (z − 1)/h` that tend to the continuous poles as h → 0, so
//! its coefficients are as well conditioned as the continuous ones. The model is the ZOH
//! equivalent of the continuous system, exact on noise-free data:
//! `A(δ) y(k) = B(δ) u(k − d)`, `A(δ) = δⁿ + α₁ δⁿ⁻¹ + … + αₙ`, `B(δ) = β₀ δⁿ⁻¹ + … + βₙ₋₁`.
//!
//! Each iteration, with the current continuous estimate (poles `p`, numerator):
//! 1. prefilter y, u and the auxiliary output `x̂` (the estimate's simulated response) by
//!    `1/Â(δ)`, `Â` from the stabilised poles `γ = (e^{p h} − 1)/h`, which gives every
//!    filtered δ-derivative `δ^i v_f` as a state of one well-conditioned recursion;
//! 2. solve `Σ ζ φᵀ θ = Σ ζ δⁿy_f` with `φ = [−δⁿ⁻¹y_f … −y_f, δⁿ⁻¹u_f … u_f]` and the
//!    instruments `ζ` = the same with `x̂_f` for `y_f` (uncorrelated with the output noise);
//! 3. continuous poles `p = ln(1 + h γ)/h`, numerator re-estimated with those poles fixed
//!    ([`refit_numerator`]).
//!
//! Start: the SRIVC estimate (the ARX least-squares fit of `ls` when SRIVC fails). The iterate
//! that simulates best is returned; when no iterate simulates within a point of the start's
//! fit, the start is returned with a warning.

use faer::Mat;
use num_complex::Complex64;

use super::filter::{simulate, Hold, Svf};
use super::linalg::{lstsq_qr, poly_from_roots, roots, solve_square, stabilize_continuous};
use super::{nrmse_fit, ContinuousModel, IdentError};

const MAX_ITER: usize = 20;

/// Continuous numerator with `m` zeros for fixed poles `den`, by least squares of `y` on the
/// basis responses `s^j/A(s) · e^{−τs} u` (ZOH-exact SVF states). Highest power first.
pub(crate) fn refit_numerator(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    den: &[f64],
    m: usize,
    delay_s: f64,
) -> Result<Vec<f64>, IdentError> {
    let svf = Svf::new(den, dt_s, Hold::Zoh { delay_s });
    let states = svf.run(u);
    let mat = Mat::<f64>::from_fn(y.len(), m + 1, |k, c| states.col(m - c)[k]);
    lstsq_qr(&mat, y, "numerator re-estimation")
}

/// States `[v_f, δv_f, …, δⁿ⁻¹v_f]` of `v_f = v / A(δ)` (A monic, `alpha` = [α₁ … αₙ]) from
/// rest, row-major N × n, and the top derivative `δⁿ v_f(k) = v(k) − Σ αᵢ δⁿ⁻ⁱ v_f(k)`.
/// Exact for the δ-operator: `ξᵢ(k+1) = ξᵢ(k) + h δξᵢ(k)`.
fn delta_filter(alpha: &[f64], v: &[f64], h: f64) -> (Vec<f64>, Vec<f64>) {
    let n = alpha.len();
    let mut xi = vec![0.0; n];
    let mut states = vec![0.0; v.len() * n];
    let mut top = vec![0.0; v.len()];
    for (k, vk) in v.iter().enumerate() {
        states[k * n..(k + 1) * n].copy_from_slice(&xi);
        let t = vk
            - alpha
                .iter()
                .enumerate()
                .map(|(i, a)| a * xi[n - 1 - i])
                .sum::<f64>();
        top[k] = t;
        for i in 0..n - 1 {
            xi[i] += h * xi[i + 1];
        }
        xi[n - 1] += h * t;
    }
    (states, top)
}

/// `v(k − d)`, zero before the record.
fn delayed(v: &[f64], d: usize) -> Vec<f64> {
    (0..v.len())
        .map(|k| if k >= d { v[k - d] } else { 0.0 })
        .collect()
}

/// δ-domain denominator `[α₁ … αₙ]` whose poles are `(e^{p h} − 1)/h` for the continuous poles
/// `p` reflected into the left half plane (a stable prefilter).
fn delta_den(den: &[f64], h: f64) -> Vec<f64> {
    let gammas: Vec<Complex64> = roots(&stabilize_continuous(den))
        .iter()
        .map(|p| ((p * h).exp() - 1.0) / h)
        .collect();
    poly_from_roots(&gammas)[1..].to_vec()
}

/// Continuous poles of the δ-model `[α₁ … αₙ]`: `ln(1 + hγ)/h`.
fn continuous_den(alpha: &[f64], h: f64) -> Result<Vec<f64>, IdentError> {
    let mut a = vec![1.0];
    a.extend_from_slice(alpha);
    let mut poles = Vec::with_capacity(alpha.len());
    for g in roots(&a) {
        let z = 1.0 + g * h;
        if z.norm() < 1e-12 || !z.norm().is_finite() {
            return Err(IdentError::Failed {
                method: "iv".into(),
                reason: format!("discrete pole {z} has no continuous equivalent"),
            });
        }
        poles.push(z.ln() / h);
    }
    Ok(poly_from_roots(&poles))
}

/// Simulation fit (%) of a model; −∞ when the simulation overflows.
fn fit_of(model: &ContinuousModel, u: &[f64], y: &[f64], dt_s: f64) -> (f64, Vec<f64>) {
    let y_sim = simulate(&model.num, &model.den, u, dt_s, model.delay_s);
    let f = nrmse_fit(y, &y_sim);
    (if f.is_finite() { f } else { f64::NEG_INFINITY }, y_sim)
}

/// One δ-IV step: prefilter by the current poles, instruments from `x_hat`; returns `[α…, β…]`.
fn iv_step(u_d: &[f64], y: &[f64], x_hat: &[f64], den: &[f64], h: f64) -> Option<Vec<f64>> {
    let n = den.len() - 1;
    let alpha_f = delta_den(den, h);
    let (sy, ty) = delta_filter(&alpha_f, y, h);
    let (su, _) = delta_filter(&alpha_f, u_d, h);
    let (sx, _) = delta_filter(&alpha_f, x_hat, h);
    let p = 2 * n;
    let mut zphi = vec![0.0; p * p];
    let mut zy = vec![0.0; p];
    let mut phi = vec![0.0; p];
    let mut zeta = vec![0.0; p];
    for (k, target) in ty.iter().enumerate() {
        let row = k * n;
        for i in 0..n {
            phi[i] = -sy[row + n - 1 - i];
            zeta[i] = -sx[row + n - 1 - i];
            phi[n + i] = su[row + n - 1 - i];
            zeta[n + i] = phi[n + i];
        }
        for r in 0..p {
            zy[r] += zeta[r] * target;
            for c in 0..p {
                zphi[r * p + c] += zeta[r] * phi[c];
            }
        }
    }
    solve_square(&zphi, &zy).filter(|t| t.iter().all(|v| v.is_finite()))
}

/// δ-operator IV estimate with `n` poles, `m` zeros and `d` samples of input delay.
pub(crate) fn iv(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    n: usize,
    m: usize,
    d: usize,
) -> Result<ContinuousModel, IdentError> {
    let delay_s = d as f64 * dt_s;
    let (start, start_name) = match super::srivc::srivc(u, y, dt_s, n, m, delay_s) {
        Ok(s) => (s, "srivc"),
        Err(_) => (super::ls::ls(u, y, dt_s, n, m, d)?.0, "ls"),
    };
    let u_d = delayed(u, d);
    let (start_fit, mut y_sim) = fit_of(&start, u, y, dt_s);
    let mut current = start.clone();
    let mut best: Option<(ContinuousModel, f64)> = None;
    let mut failure = None;
    for _ in 0..MAX_ITER {
        let Some(theta) = iv_step(&u_d, y, &y_sim, &current.den, dt_s) else {
            failure = Some("singular instrument matrix".to_string());
            break;
        };
        let den = match continuous_den(&theta[..n], dt_s) {
            Ok(den) => den,
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
        };
        let num = match refit_numerator(u, y, dt_s, &den, m, delay_s) {
            Ok(num) => num,
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
        };
        let change = den
            .iter()
            .zip(&current.den)
            .map(|(a, b)| (a - b).abs() / (1e-6 + b.abs()))
            .fold(0.0_f64, f64::max);
        current = ContinuousModel::new(num, den, delay_s);
        let (fit, sim) = fit_of(&current, u, y, dt_s);
        y_sim = sim;
        if best.as_ref().is_none_or(|b| fit > b.1) {
            best = Some((current.clone(), fit));
        }
        if change < 1e-10 || fit == f64::NEG_INFINITY {
            break;
        }
    }
    Ok(best_or_start(best, failure, start, start_fit, start_name))
}

/// The best iterate when it simulates within a point of the start's fit; otherwise the start,
/// with a warning saying why (the iteration's `failure`, or the best iterate's fit).
fn best_or_start(
    best: Option<(ContinuousModel, f64)>,
    failure: Option<String>,
    start: ContinuousModel,
    start_fit: f64,
    start_name: &str,
) -> ContinuousModel {
    match best {
        Some((model, fit)) if fit >= start_fit - 1.0 => model,
        other => {
            let why = match (other, failure) {
                (Some((_, fit)), _) => format!(
                    "its best iterate simulates at {fit:.2} % against the start's {start_fit:.2} %"
                ),
                (None, Some(f)) => f,
                (None, None) => "no iterate".into(),
            };
            let mut model = start;
            model.warnings.push(format!(
                "iv did not converge ({why}); returning its starting estimate ({start_name})"
            ));
            model
        }
    }
}

#[cfg(test)]
mod fallback_tests {
    use super::best_or_start;
    use crate::ident::ContinuousModel;

    fn model(pole: f64) -> ContinuousModel {
        ContinuousModel::new(vec![1.0], vec![1.0, pole], 0.0)
    }

    #[test]
    fn an_iterate_within_a_point_of_the_start_is_returned_as_is() {
        let m = best_or_start(Some((model(2.0), 89.5)), None, model(1.0), 90.0, "srivc");
        assert_eq!(m.den, vec![1.0, 2.0]);
        assert!(m.warnings.is_empty());
    }

    #[test]
    fn a_worse_iterate_returns_the_start_with_both_fits_in_the_warning() {
        let m = best_or_start(Some((model(2.0), 88.9)), None, model(1.0), 90.0, "srivc");
        assert_eq!(m.den, vec![1.0, 1.0]);
        assert_eq!(
            m.warnings,
            vec!["iv did not converge (its best iterate simulates at 88.90 % against the start's 90.00 %); \
                  returning its starting estimate (srivc)"]
        );
    }

    #[test]
    fn a_failure_before_any_iterate_returns_the_start_naming_the_failure() {
        let m = best_or_start(
            None,
            Some("singular instrument matrix".into()),
            model(1.0),
            90.0,
            "ls",
        );
        assert_eq!(m.den, vec![1.0, 1.0]);
        assert_eq!(
            m.warnings,
            vec!["iv did not converge (singular instrument matrix); returning its starting estimate (ls)"]
        );
    }
}
