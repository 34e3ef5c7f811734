//! `iv` — discrete-time instrumental variables with instruments from an auxiliary model's
//! simulated output (Söderström & Stoica 1989, *System Identification*, §8.2 and the
//! multistep IV4 idea of §8.4 / Ljung 1999 §15.3), then a ZOH conversion to continuous time.
//!
//! Start: the ARX least-squares fit of eq. 59 (see `ls.rs`) and, because at fast sampling
//! with noise that fit can be wild, also the SVF least-squares model (see `srivc.rs`)
//! discretised by ZOH; the run whose final model simulates best is kept. Each iteration with estimate
//! (Â, B̂): the auxiliary model `x̂(k) = B̂(q)/Â(q) u(k)` is simulated; every signal is
//! prefiltered by `1/Â(q)` (the simplified refined IV of Young 1976, which makes the estimate
//! approach the optimal-IV variance for white output noise); the instruments
//! `ζ(k) = [−x̂_f(k−1) … −x̂_f(k−n), u_f(k−1) … u_f(k−nb)]` replace the noisy output lags in
//! `Σ ζ φᵀ θ = Σ ζ y_f`. The instruments are uncorrelated with the output noise, so the
//! estimate is consistent where plain LS is not. Unstable Â are reflected inside the unit
//! circle before simulation and filtering.
//!
//! To continuous time: poles by `p = ln z / h`; the numerator is re-estimated with those
//! poles fixed by linear least squares on the simulated basis responses `s^j/A(s) · u`, which
//! fits the requested continuous structure directly (the dropped-term d2c of `ls` would
//! discard a non-negligible highest numerator term once the data are noisy).

use faer::Mat;

use super::filter::{simulate, Hold, Svf};
use super::linalg::{
    lstsq_qr, poly_from_roots, roots, solve_square, stabilize_continuous, stabilize_discrete,
};
use super::ls::{arx_ls, continuous_poles};
use super::{nrmse_fit, ContinuousModel, IdentError};

const MAX_ITER: usize = 20;

/// Output of `B(q)/A(q)` (b on u(k−1−d)…, a monic in q⁻¹) from rest.
fn sim_discrete(a: &[f64], b: &[f64], u: &[f64], d: usize) -> Vec<f64> {
    let mut x = vec![0.0; u.len()];
    for k in 0..u.len() {
        let mut s = 0.0;
        for (j, bj) in b.iter().enumerate() {
            if k > j + d {
                s += bj * u[k - 1 - j - d];
            }
        }
        for (i, ai) in a.iter().enumerate().skip(1) {
            if k >= i {
                s -= ai * x[k - i];
            }
        }
        x[k] = s;
    }
    x
}

/// `v / A(q)` from rest.
fn prefilter(a: &[f64], v: &[f64]) -> Vec<f64> {
    let mut f = vec![0.0; v.len()];
    for k in 0..v.len() {
        let mut s = v[k];
        for (i, ai) in a.iter().enumerate().skip(1) {
            if k >= i {
                s -= ai * f[k - i];
            }
        }
        f[k] = s;
    }
    f
}

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
    let n = svf.n;
    let states = svf.run(u);
    let mat = Mat::<f64>::from_fn(y.len(), m + 1, |k, c| states[k * n + (m - c)]);
    lstsq_qr(&mat, y, "numerator re-estimation")
}

/// Discrete IV estimate converted to a continuous model with `n` poles and `m` zeros.
pub(crate) fn iv(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    n: usize,
    m: usize,
    d: usize,
) -> Result<ContinuousModel, IdentError> {
    let nb = n;
    let arx = arx_ls(u, y, n, nb, d)?;
    let delay_s = d as f64 * dt_s;
    let mut best: Option<(ContinuousModel, f64)> = None;
    let mut last_err = None;
    let mut starts = vec![(arx.a, arx.b)];
    if let Some((num_c, den_c)) = super::srivc::svf_ls_start(u, y, dt_s, n, m, delay_s) {
        let den_c = stabilize_continuous(&den_c);
        let zd: Vec<_> = roots(&den_c).iter().map(|p| (p * dt_s).exp()).collect();
        let a_d = poly_from_roots(&zd);
        let b_d = c2d_numerator(&num_c, &den_c, &a_d, dt_s, nb);
        starts.push((a_d, b_d));
    }
    for start in starts {
        match iv_from(u, y, dt_s, n, m, d, start) {
            Ok(model) => {
                let y_sim = simulate(&model.num, &model.den, u, dt_s, delay_s);
                let fit = nrmse_fit(y, &y_sim);
                let fit = if fit.is_finite() {
                    fit
                } else {
                    f64::NEG_INFINITY
                };
                if best.as_ref().is_none_or(|b| fit > b.1) {
                    best = Some((model, fit));
                }
            }
            Err(e) => last_err = Some(e),
        }
    }
    match (best, last_err) {
        (Some((model, _)), _) => Ok(model),
        (None, Some(e)) => Err(e),
        (None, None) => Err(IdentError::Failed {
            method: "iv".into(),
            reason: "no starting model".into(),
        }),
    }
}

/// ZOH discrete numerator (on u(k−1)…u(k−nb)) of the continuous `num/den`, given the discrete
/// denominator `a_d` of the same poles: `b_i = Σ_{l<i} a_l h_{i−l}` from the Markov parameters.
fn c2d_numerator(num: &[f64], den: &[f64], a_d: &[f64], dt_s: f64, nb: usize) -> Vec<f64> {
    let svf = Svf::new(den, dt_s, Hold::Zoh { delay_s: 0.0 });
    let mut impulse = vec![0.0; nb + 1];
    impulse[0] = 1.0;
    let h = super::filter::combine(&svf.run(&impulse), svf.n, num, nb + 1);
    (1..=nb)
        .map(|i| {
            (0..i)
                .map(|l| a_d.get(l).copied().unwrap_or(0.0) * h[i - l])
                .sum()
        })
        .collect()
}

/// The IV iterations from a discrete starting model `(a, b)`, then the continuous conversion.
fn iv_from(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    n: usize,
    m: usize,
    d: usize,
    start: (Vec<f64>, Vec<f64>),
) -> Result<ContinuousModel, IdentError> {
    let nb = n;
    let (mut a, mut b) = start;
    let first = n.max(nb + d);
    let p = n + nb;
    for _ in 0..MAX_ITER {
        let af = stabilize_discrete(&a);
        let xhat = sim_discrete(&af, &b, u, d);
        let yf = prefilter(&af, y);
        let uf = prefilter(&af, u);
        let xf = prefilter(&af, &xhat);
        let mut zphi = vec![0.0; p * p];
        let mut zy = vec![0.0; p];
        let mut phi = vec![0.0; p];
        let mut zeta = vec![0.0; p];
        for k in first..y.len() {
            for i in 0..n {
                phi[i] = -yf[k - 1 - i];
                zeta[i] = -xf[k - 1 - i];
            }
            for j in 0..nb {
                phi[n + j] = uf[k - 1 - j - d];
                zeta[n + j] = phi[n + j];
            }
            for r in 0..p {
                zy[r] += zeta[r] * yf[k];
                for c in 0..p {
                    zphi[r * p + c] += zeta[r] * phi[c];
                }
            }
        }
        let Some(theta) = solve_square(&zphi, &zy) else {
            return Err(IdentError::SingularRegression {
                method: "iv".into(),
                rank: 0,
                n_params: p,
            });
        };
        let mut a_new = vec![1.0];
        a_new.extend_from_slice(&theta[..n]);
        let b_new = theta[n..].to_vec();
        let change = a_new
            .iter()
            .zip(&a)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0_f64, f64::max);
        a = a_new;
        b = b_new;
        if change < 1e-12 {
            break;
        }
    }
    let poles = continuous_poles(&a, dt_s)?;
    let den = poly_from_roots(&poles);
    let delay_s = d as f64 * dt_s;
    let num = refit_numerator(u, y, dt_s, &den, m, delay_s)?;
    Ok(ContinuousModel::new(num, den, delay_s))
}
