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
use super::linalg::{inverse, matmul, poly_mul, solve_square};
use super::{ContinuousModel, IdentError};
use num_complex::Complex64;
use realfft::RealFftPlanner;

const MAX_ITER: usize = 100;

/// Simulated output for parameters `theta` = [num (m+1), a_1..a_n].
fn sim(theta: &[f64], m: usize, u: &[f64], dt_s: f64, delay_s: f64) -> Vec<f64> {
    let num = &theta[..=m];
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[m + 1..]);
    simulate(num, &den, u, dt_s, delay_s)
}

fn sse(y: &[f64], y_hat: &[f64]) -> f64 {
    y.iter().zip(y_hat).map(|(a, b)| (a - b) * (a - b)).sum()
}

/// Sensitivity matrix (N × p, row-major) at `theta`; a last column for τ when `with_delay`.
fn sensitivities(
    theta: &[f64],
    m: usize,
    u: &[f64],
    dt_s: f64,
    delay_s: f64,
    with_delay: bool,
) -> Vec<f64> {
    let num = &theta[..=m];
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[m + 1..]);
    let n = den.len() - 1;
    let a2 = poly_mul(&den, &den);
    let svf = Svf::new(&a2, dt_s, Hold::Zoh { delay_s });
    let xi = svf.run(u);
    let len = u.len();
    let p = m + 1 + n + usize::from(with_delay);
    let mut s = vec![0.0; len * p];
    // ∂ŷ/∂b (num index c ↔ s^{m−c}): s^{m−c} A ξ
    for c in 0..=m {
        let mut poly = den.clone();
        poly.extend(std::iter::repeat_n(0.0, m - c));
        let col = xi.combine(&poly);
        for k in 0..len {
            s[k * p + c] = col[k];
        }
    }
    // ∂ŷ/∂a_i = −s^{n−i} B ξ
    for i in 1..=n {
        let mut poly: Vec<f64> = num.iter().map(|b| -b).collect();
        poly.extend(std::iter::repeat_n(0.0, n - i));
        let col = xi.combine(&poly);
        for k in 0..len {
            s[k * p + m + i] = col[k];
        }
    }
    if with_delay {
        let h = 0.1 * dt_s;
        let (lo, hi) = if delay_s > h {
            (delay_s - h, delay_s + h)
        } else {
            (delay_s, delay_s + h)
        };
        let y_lo = sim(theta, m, u, dt_s, lo);
        let y_hi = sim(theta, m, u, dt_s, hi);
        for k in 0..len {
            s[k * p + p - 1] = (y_hi[k] - y_lo[k]) / (hi - lo);
        }
    }
    s
}

/// Central-difference sensitivities of the exact simulation (N × p, row-major); used for the
/// covariance, where the small-eigenvalue directions of `SᵀS` (the slow modes) need the
/// sensitivities to full precision.
fn fd_sensitivities(
    theta: &[f64],
    m: usize,
    u: &[f64],
    dt_s: f64,
    delay_s: f64,
    with_delay: bool,
) -> Vec<f64> {
    let np = theta.len();
    let p = np + usize::from(with_delay);
    let len = u.len();
    let scale = theta.iter().fold(0.0_f64, |a, t| a.max(t.abs()));
    let mut s = vec![0.0; len * p];
    for j in 0..np {
        let h = 1e-6 * theta[j].abs().max(1e-6 * scale).max(1e-12);
        let mut tp = theta.to_vec();
        let mut tm = theta.to_vec();
        tp[j] += h;
        tm[j] -= h;
        let yp = sim(&tp, m, u, dt_s, delay_s);
        let ym = sim(&tm, m, u, dt_s, delay_s);
        for k in 0..len {
            s[k * p + j] = (yp[k] - ym[k]) / (2.0 * h);
        }
    }
    if with_delay {
        let d = sensitivities(theta, m, u, dt_s, delay_s, true);
        for k in 0..len {
            s[k * p + p - 1] = d[k * p + p - 1];
        }
    }
    s
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
    let mut theta: Vec<f64> = start.num.clone();
    theta.extend_from_slice(&start.den[1..]);
    let mut delay_s = start.delay_s;
    let mut c = start.y_bias;
    let np = m + 1 + n;
    let p = np + usize::from(with_delay);
    let pf = p + 1;
    let sim_c = |theta: &[f64], delay_s: f64, c: f64| {
        let mut v = sim(theta, m, u, dt_s, delay_s);
        v.iter_mut().for_each(|x| *x += c);
        v
    };
    let mut cost = sse(y, &sim_c(&theta, delay_s, c));
    if !cost.is_finite() {
        return Err(IdentError::Failed {
            method: "oe".into(),
            reason: "the starting model's simulation overflows".into(),
        });
    }
    let mut mu = 1e-3;
    for _ in 0..MAX_ITER {
        let s = with_offset_column(&sensitivities(&theta, m, u, dt_s, delay_s, with_delay), p);
        let y_hat = sim_c(&theta, delay_s, c);
        let r: Vec<f64> = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
        let (h, g) = normal(&s, &r, pf);
        let mut accepted = false;
        let mut last_gain = 0.0;
        for _ in 0..12 {
            let mut hm = h.clone();
            for a in 0..pf {
                hm[a * pf + a] += mu * h[a * pf + a].max(1e-300);
            }
            let Some(delta) = solve_square(&hm, &g) else {
                mu *= 10.0;
                continue;
            };
            let trial: Vec<f64> = theta.iter().zip(&delta).map(|(t, d)| t + d).collect();
            let trial_delay = if with_delay {
                (delay_s + delta[np]).max(0.0)
            } else {
                delay_s
            };
            let trial_c = c + delta[p];
            let cost_trial = sse(y, &sim_c(&trial[..np], trial_delay, trial_c));
            if cost_trial.is_finite() && cost_trial < cost {
                last_gain = (cost - cost_trial) / cost;
                theta = trial[..np].to_vec();
                delay_s = trial_delay;
                c = trial_c;
                cost = cost_trial;
                mu = (mu / 10.0).max(1e-12);
                accepted = true;
                break;
            }
            mu *= 10.0;
        }
        if !accepted || last_gain < 1e-12 {
            break;
        }
    }
    // covariance at the optimum, from central-difference sensitivities of the exact simulation
    let s = with_offset_column(
        &fd_sensitivities(&theta, m, u, dt_s, delay_s, with_delay),
        p,
    );
    let y_hat = sim_c(&theta, delay_s, c);
    let r: Vec<f64> = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
    let (mmat, _) = normal(&s, &r, pf);
    let cov = inverse(&mmat, pf).map(|minv| {
        let full = coloured_covariance(&s, &r, &minv, pf);
        (0..p * p).map(|k| full[(k / p) * pf + k % p]).collect()
    });
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[m + 1..]);
    Ok(ContinuousModel {
        num: theta[..=m].to_vec(),
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
    let p = theta.len();
    let pf = p + 1;
    let s = with_offset_column(
        &fd_sensitivities(&theta, m, u, dt_s, model.delay_s, false),
        p,
    );
    let y_hat = sim(&theta, m, u, dt_s, model.delay_s);
    let r: Vec<f64> = y
        .iter()
        .zip(&y_hat)
        .map(|(a, b)| a - b - model.y_bias)
        .collect();
    let (mmat, _) = normal(&s, &r, pf);
    inverse(&mmat, pf).map(|minv| {
        let full = coloured_covariance(&s, &r, &minv, pf);
        (0..p * p).map(|k| full[(k / p) * pf + k % p]).collect()
    })
}

/// `M⁻¹ [Σ_i Σ_j s_i w(i−j) R(i−j) s_jᵀ] M⁻¹` (Morelli & Klein 1994). The sum runs over the
/// lags where the residuals are actually correlated: L = twice the first lag at which the
/// sample autocorrelation falls inside the 99 % white-noise band (at most N/10), with Bartlett
/// weights `w(k) = 1 − |k|/(L+1)` (Newey & West 1987) so the result stays positive
/// semidefinite. Summing the sample autocorrelation over all lags instead would add noise of
/// the order of the variance itself for slow-mode parameters, whose sensitivities are nearly
/// constant over hundreds of lags.
fn coloured_covariance(s: &[f64], r: &[f64], minv: &[f64], p: usize) -> Vec<f64> {
    let len = r.len();
    let cap = (len / 10).max(1).min(len - 1);
    let acf = autocorrelation(r, cap);
    let r0 = acf[0].max(f64::MIN_POSITIVE);
    let bound = 2.58 / (len as f64).sqrt();
    let decay = (1..=cap)
        .find(|&l| (acf[l] / r0).abs() < bound)
        .unwrap_or(cap);
    let max_lag = (2 * decay).min(cap);
    let weighted: Vec<f64> = (0..=max_lag)
        .map(|l| acf[l] * (1.0 - l as f64 / (max_lag as f64 + 1.0)))
        .collect();
    let w = lag_weighted_products(s, &weighted, len, p);
    matmul(&matmul(minv, &w, p), minv, p)
}

/// Sample autocorrelation `R(l) = (1/N) Σ_k r_k r_{k−l}` for l = 0 … `max_lag`, by FFT (Wiener–
/// Khinchin on the record zero-padded past `N + max_lag`, so the circular correlation is the
/// linear one).
fn autocorrelation(r: &[f64], max_lag: usize) -> Vec<f64> {
    let len = r.len();
    let size = (len + max_lag).next_power_of_two();
    let mut planner = RealFftPlanner::<f64>::new();
    let spectrum = real_spectrum(&mut planner, r, size);
    let mut power: Vec<Complex64> = spectrum
        .iter()
        .map(|z| Complex64::new(z.norm_sqr(), 0.0))
        .collect();
    let mut out = vec![0.0; size];
    planner
        .plan_fft_inverse(size)
        .process(&mut power, &mut out)
        .expect("inverse FFT of a Hermitian spectrum");
    out.truncate(max_lag + 1);
    // realfft's inverse is unnormalised: divide by the FFT size, then by N for the estimate
    out.iter_mut().for_each(|v| *v /= size as f64 * len as f64);
    out
}

/// The one-sided spectrum (`size/2 + 1` bins) of `v` zero-padded to `size`.
fn real_spectrum(planner: &mut RealFftPlanner<f64>, v: &[f64], size: usize) -> Vec<Complex64> {
    let fft = planner.plan_fft_forward(size);
    let mut input = vec![0.0; size];
    input[..v.len()].copy_from_slice(v);
    let mut spectrum = fft.make_output_vec();
    fft.process(&mut input, &mut spectrum)
        .expect("forward FFT of a real signal");
    spectrum
}

/// `W = Σ_i Σ_j s_i R(|i−j|) s_jᵀ` (p × p, row-major) for the row-major `len × p` matrix `s` and
/// the lag weights `acf[0..=L]` (zero beyond L).
///
/// `W_ab = ⟨s_a, K * s_b⟩` with the symmetric kernel `K(l) = R(|l|)`; by Parseval on columns
/// zero-padded to `M ≥ N + L` (no wrap-around), `W_ab = (1/M) Σ_f conj(Ŝ_a(f)) K̂(f) Ŝ_b(f)`,
/// `K̂(f) = R(0) + 2 Σ_l R(l) cos(2π f l / M)` real: p FFTs instead of p convolutions of
/// length 2L+1 (O(pN log N) instead of O(pNL)).
fn lag_weighted_products(s: &[f64], acf: &[f64], len: usize, p: usize) -> Vec<f64> {
    let max_lag = acf.len() - 1;
    let size = (len + max_lag).next_power_of_two();
    let mut planner = RealFftPlanner::<f64>::new();
    // K̂ from the kernel laid out circularly: K[0] = R(0), K[l] = K[M−l] = R(l)
    let mut kernel = vec![0.0; size];
    kernel[0] = acf[0];
    for l in 1..=max_lag {
        kernel[l] = acf[l];
        kernel[size - l] = acf[l];
    }
    let k_hat: Vec<f64> = real_spectrum(&mut planner, &kernel, size)
        .iter()
        .map(|z| z.re)
        .collect();
    let spectra: Vec<Vec<Complex64>> = (0..p)
        .map(|c| {
            let col: Vec<f64> = (0..len).map(|i| s[i * p + c]).collect();
            real_spectrum(&mut planner, &col, size)
        })
        .collect();
    // the full spectrum counts every bin but DC and Nyquist twice (conjugate symmetry)
    let half = size / 2;
    let weight: Vec<f64> = (0..=half)
        .map(|f| if f == 0 || f == half { 1.0 } else { 2.0 } * k_hat[f] / size as f64)
        .collect();
    let mut w = vec![0.0; p * p];
    for a in 0..p {
        for b in a..p {
            let v: f64 = spectra[a]
                .iter()
                .zip(&spectra[b])
                .zip(&weight)
                .map(|((x, y), g)| g * (x.re * y.re + x.im * y.im))
                .sum();
            w[a * p + b] = v;
            w[b * p + a] = v;
        }
    }
    w
}

#[cfg(test)]
mod lag_tests {
    use super::{autocorrelation, lag_weighted_products};

    /// Deterministic pseudo-random numbers in [−0.5, 0.5) (xorshift64).
    fn noise(count: usize) -> Vec<f64> {
        let mut state = 0x2545F4914F6CDD1D_u64;
        (0..count)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    #[test]
    fn fft_autocorrelation_equals_the_lagged_sums() {
        // a coloured record (first-order filtered noise, plus a mean) and lags up to a third of it
        let mut r = noise(301);
        for k in 1..r.len() {
            r[k] += 0.8 * r[k - 1] + 0.01;
        }
        let acf = autocorrelation(&r, 100);
        assert_eq!(acf.len(), 101);
        for (l, a) in acf.iter().enumerate() {
            let d = (l..r.len()).map(|k| r[k] * r[k - l]).sum::<f64>() / r.len() as f64;
            assert!((a - d).abs() <= 1e-13 * acf[0], "lag {l}: {a} vs {d}");
        }
    }

    /// The definition, summed pair by pair: `Σ_i Σ_j s_i R(|i−j|) s_jᵀ`.
    fn by_definition(s: &[f64], acf: &[f64], len: usize, p: usize) -> Vec<f64> {
        let mut w = vec![0.0; p * p];
        for i in 0..len {
            for j in 0..len {
                let Some(r) = acf.get(i.abs_diff(j)) else {
                    continue;
                };
                for a in 0..p {
                    for b in 0..p {
                        w[a * p + b] += s[i * p + a] * r * s[j * p + b];
                    }
                }
            }
        }
        w
    }

    #[test]
    fn spectral_products_equal_the_double_sum() {
        // deterministic pseudo-random sensitivities (len 157, p 5) and Bartlett-like lag weights
        // (L = 23): both edges, lags reaching both ends, a size (157 + 23 → 256) with padding to spare
        let (len, p) = (157, 5);
        let s = noise(len * p);
        let acf: Vec<f64> = (0..=23)
            .map(|l| (1.0 - l as f64 / 24.0) * (0.9f64).powi(l))
            .collect();
        let fast = lag_weighted_products(&s, &acf, len, p);
        let slow = by_definition(&s, &acf, len, p);
        // FFT round-off is relative to the size of the whole product, √(W_aa W_bb)
        for a in 0..p {
            for b in 0..p {
                let (f, d) = (fast[a * p + b], slow[a * p + b]);
                let scale = (slow[a * p + a] * slow[b * p + b]).sqrt();
                assert!((f - d).abs() <= 1e-12 * scale, "W[{a}][{b}]: {f} vs {d}");
            }
        }
    }
}
