//! The one parameter-covariance computation: Cramér–Rao bounds corrected for coloured residuals.
//!
//! For an output-error fit with sensitivities `S` (`∂ŷ/∂θ`) and residuals `v`, the Cramér–Rao
//! bound `Cov = M⁻¹`, `M = Σ Sᵀ R⁻¹ S`, assumes white residuals. Residuals of real models are
//! coloured (unmodelled dynamics, turbulence, sensor filters), which makes that bound optimistic
//! by factors of 2–5. The correction used here is Morelli & Klein's (*Accounting for the effects
//! of colored residuals in output-error parameter estimates*, NASA CR-194893, 1994; *Aircraft
//! System Identification* 2nd ed., §6.6, eq. 6.86):
//!
//! `Cov = M⁻¹ [Σ_outputs w² Σ_i Σ_j s_i R_vv(i−j) s_jᵀ] M⁻¹`, `w = 1/R_oo`,
//!
//! with the residual autocorrelation `R_vv` estimated from the residuals and summed over the lags
//! where they are actually correlated, weighted by a Bartlett window (Newey & West 1987) so the
//! result stays positive semidefinite. Outputs and records are treated as mutually uncorrelated.

use num_complex::Complex64;
use realfft::RealFftPlanner;

use crate::signal::sum_sq;

/// Bartlett-weighted residual autocorrelation `w(l) R(l)`, l = 0 … L, for the coloured-residual
/// correction: L = twice the first lag at which the sample autocorrelation falls inside the 99 %
/// white-noise band (at most N/10). Summing the sample autocorrelation over all lags instead would
/// add noise of the order of the variance itself for slow-mode parameters, whose sensitivities
/// are nearly constant over hundreds of lags.
pub fn lag_weights(r: &[f64]) -> Vec<f64> {
    let len = r.len();
    if len < 2 {
        return vec![sum_sq(r) / len.max(1) as f64];
    }
    let cap = (len / 10).max(1).min(len - 1);
    let acf = autocorrelation(r, cap);
    let r0 = acf[0].max(f64::MIN_POSITIVE);
    let bound = 2.58 / (len as f64).sqrt();
    let decay = (1..=cap)
        .find(|&l| (acf[l] / r0).abs() < bound)
        .unwrap_or(cap);
    bartlett_taper(&acf, (2 * decay).min(cap))
}

/// The Bartlett-tapered autocorrelation `(1 − l/(L+1)) R(l)`, l = 0 … L = `max_lag` (Newey & West
/// 1987): the lag weights for [`lag_weighted_products`] with a lag window chosen by the caller.
pub fn bartlett_taper(acf: &[f64], max_lag: usize) -> Vec<f64> {
    let max_lag = max_lag.min(acf.len().saturating_sub(1));
    (0..=max_lag)
        .map(|l| acf[l] * (1.0 - l as f64 / (max_lag as f64 + 1.0)))
        .collect()
}

/// The effective number of independent samples `N / (1 + 2 Σ_{l≥1} w(l) R(l) / R(0))` of a series of
/// `len` samples with the tapered autocorrelation `tapered` ([`bartlett_taper`] or [`lag_weights`]):
/// the variance-inflation factor of a mean of correlated samples (Bartlett 1946; Box, Jenkins &
/// Reinsel, *Time Series Analysis*, §2.1.6), clamped to [1, N].
pub fn effective_samples(tapered: &[f64], len: usize) -> f64 {
    let n = len as f64;
    match tapered.split_first() {
        Some((&r0, rest)) if r0 > 0.0 => {
            let inflation = 1.0 + 2.0 * rest.iter().sum::<f64>() / r0;
            (n / inflation.max(1.0)).clamp(1.0_f64.min(n), n)
        }
        _ => n,
    }
}

/// `M⁻¹ W M⁻¹` for one residual series `r` and row-major `len × p` sensitivities `s`, with
/// `W` = [`lag_weighted_products`] of the [`lag_weights`] of `r` (row-major p × p result).
pub fn coloured_covariance(s: &[f64], r: &[f64], minv: &[f64], p: usize) -> Vec<f64> {
    let len = r.len();
    let cols: Vec<Vec<f64>> = (0..p)
        .map(|c| (0..len).map(|i| s[i * p + c]).collect())
        .collect();
    let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    let w = lag_weighted_products(&refs, &lag_weights(r));
    sandwich(minv, &w, p)
}

/// `A W A` for row-major p × p matrices (A symmetric).
pub fn sandwich(a: &[f64], w: &[f64], p: usize) -> Vec<f64> {
    let mul = |x: &[f64], y: &[f64]| {
        let mut c = vec![0.0; p * p];
        for i in 0..p {
            for k in 0..p {
                let xik = x[i * p + k];
                for j in 0..p {
                    c[i * p + j] += xik * y[k * p + j];
                }
            }
        }
        c
    };
    mul(&mul(a, w), a)
}

/// Sample autocorrelation `R(l) = (1/N) Σ_k r_k r_{k−l}` for l = 0 … `max_lag`, by FFT (Wiener–
/// Khinchin on the record zero-padded past `N + max_lag`, so the circular correlation is the
/// linear one).
pub fn autocorrelation(r: &[f64], max_lag: usize) -> Vec<f64> {
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

/// `W = Σ_i Σ_j s_i R(|i−j|) s_jᵀ` (p × p, row-major) for the sensitivity columns `cols` (p
/// columns of equal length N) and the lag weights `acf[0..=L]` (zero beyond L).
///
/// `W_ab = ⟨s_a, K * s_b⟩` with the symmetric kernel `K(l) = R(|l|)`; by Parseval on columns
/// zero-padded to `M ≥ N + L` (no wrap-around), `W_ab = (1/M) Σ_f conj(Ŝ_a(f)) K̂(f) Ŝ_b(f)`,
/// `K̂(f) = R(0) + 2 Σ_l R(l) cos(2π f l / M)` real: p FFTs instead of p convolutions of
/// length 2L+1 (O(pN log N) instead of O(pNL)).
pub fn lag_weighted_products(cols: &[&[f64]], acf: &[f64]) -> Vec<f64> {
    let p = cols.len();
    let len = cols.first().map_or(0, |c| c.len());
    let max_lag = acf.len() - 1;
    let size = (len + max_lag).next_power_of_two().max(2);
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
    let spectra: Vec<Vec<Complex64>> = cols
        .iter()
        .map(|col| real_spectrum(&mut planner, col, size))
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
mod tests {
    use super::{autocorrelation, bartlett_taper, effective_samples, lag_weighted_products};

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
        let cols: Vec<Vec<f64>> = (0..p)
            .map(|c| (0..len).map(|i| s[i * p + c]).collect())
            .collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let fast = lag_weighted_products(&refs, &acf);
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

    #[test]
    fn effective_samples_of_a_first_order_process_follow_its_variance_inflation() {
        // AR(1) with φ = 0.5: the variance of a mean is inflated by (1 + φ)/(1 − φ) = 3; a Bartlett
        // window of 50 lags shortens the sum by Σ l φ^l / 51 = 2/51, so the inflation is 2.92.
        let len = 20_000;
        let white = noise(len);
        let mut ar = white.clone();
        for k in 1..len {
            ar[k] += 0.5 * ar[k - 1];
        }
        let n_of = |r: &[f64]| effective_samples(&bartlett_taper(&autocorrelation(r, 50), 50), len);
        let inflation = len as f64 / n_of(&ar);
        assert!(
            (inflation - 2.92).abs() < 0.25,
            "AR(1) inflation {inflation}"
        );
        let white_n = n_of(&white) / len as f64;
        assert!(
            (white_n - 1.0).abs() < 0.15,
            "white noise: n_eff/N = {white_n}"
        );
        // never more samples than there are, never fewer than one
        let alternating: Vec<f64> = (0..len)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert_eq!(n_of(&alternating), len as f64);
        let constant = vec![1.0; 100];
        let n = effective_samples(&bartlett_taper(&autocorrelation(&constant, 99), 99), 100);
        assert!((1.0..=100.0).contains(&n), "{n}");
    }
}
