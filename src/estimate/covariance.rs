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
//! result stays positive semidefinite.
//!
//! [`cross_lag_weighted_products`] keeps the whole matrix `R_vv(l)` of eq. 6.86, the outputs'
//! cross-correlations included: turbulence drives the α or β vane, the rates and the accelerometers
//! together, and summing each output's information as if it were independent of the others counted
//! the same gusts several times (σ 2–6 times smaller than the scatter over gust realisations). Records
//! are treated as mutually uncorrelated.

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
    let acf = autocorrelation(r, lag_cap(len));
    bartlett_taper(&acf, lag_window(&acf, len))
}

/// The longest lag window for a series of `len` ≥ 2 samples: N/10.
fn lag_cap(len: usize) -> usize {
    (len / 10).max(1).min(len - 1)
}

/// The lag window L of [`lag_weights`] from the sample autocorrelation `acf` (lags 0 … the cap) of a
/// series of `len` samples: twice the first lag inside the 99 % white-noise band, at most the cap.
fn lag_window(acf: &[f64], len: usize) -> usize {
    let cap = acf.len() - 1;
    let r0 = acf[0].max(f64::MIN_POSITIVE);
    let bound = 2.58 / (len as f64).sqrt();
    let decay = (1..=cap)
        .find(|&l| (acf[l] / r0).abs() < bound)
        .unwrap_or(cap);
    (2 * decay).min(cap)
}

/// `W = Σ_i Σ_j Σ_a Σ_b x_a,i R_ab(i−j) x_b,jᵀ` (p × p, row-major; Morelli & Klein eq. 6.86 with the whole
/// residual correlation matrix): `cols[a]` are the p sensitivity columns of output a (each of length N,
/// weighted by 1/√R_aa), `residuals[a]` its residuals (weighted alike), and `R_ab(l) = (1/N) Σ_k
/// v_a(k+l) v_b(k)` the sample cross-correlation, Bartlett-tapered over one lag window for all the
/// outputs (the longest of [`lag_weights`]' windows), so that the matrix sequence, and W, stay positive
/// semidefinite (Newey & West 1987).
///
/// By convolution and Parseval on series zero-padded to `M ≥ N + L`:
/// `W_ij = (1/M) Σ_f Σ_a conj(X̂_a,i(f)) Σ_b K̂_ab(f) X̂_b,j(f)`, `K_ab(l) = w(l) R_ab(l)` for |l| ≤ L laid
/// out circularly (`R_ab(−l) = R_ba(l)`); every bin but DC and Nyquist counts twice (conjugate symmetry).
pub fn cross_lag_weighted_products<C: AsRef<[f64]>, R: AsRef<[f64]>>(
    cols: &[Vec<C>],
    residuals: &[R],
) -> Vec<f64> {
    let m = residuals.len();
    let p = cols.first().map_or(0, Vec::len);
    let len = residuals.first().map_or(0, |r| r.as_ref().len());
    let mut w = vec![0.0; p * p];
    if m == 0 || p == 0 || len < 2 {
        return w;
    }
    // one spectrum per residual, padded for lags up to the cap (N/10), serves both the window and the kernels
    let cap = lag_cap(len);
    let size = (len + cap).next_power_of_two().max(2);
    let half = size / 2;
    let norm = size as f64 * len as f64;
    let mut planner = RealFftPlanner::<f64>::new();
    let v_hat: Vec<Vec<Complex64>> = residuals
        .iter()
        .map(|r| real_spectrum(&mut planner, r.as_ref(), size))
        .collect();
    // N·R_ab(l) at circular index l (l ≥ 0) and size − l (l < 0), for a ≤ b
    let inverse = planner.plan_fft_inverse(size);
    let mut corr = vec![Vec::new(); m * m];
    for a in 0..m {
        for b in a..m {
            let mut cross: Vec<Complex64> = v_hat[a]
                .iter()
                .zip(&v_hat[b])
                .map(|(x, y)| x * y.conj())
                .collect();
            // a real sequence's spectrum has real DC and Nyquist bins; drop the round-off
            cross[0].im = 0.0;
            cross[half].im = 0.0;
            let mut out = vec![0.0; size];
            inverse
                .process(&mut cross, &mut out)
                .expect("inverse FFT of a cross spectrum");
            corr[a * m + b] = out;
        }
    }
    let max_lag = (0..m)
        .map(|a| {
            let acf: Vec<f64> = corr[a * m + a][..=cap].iter().map(|v| v / norm).collect();
            lag_window(&acf, len)
        })
        .max()
        .unwrap_or(0);
    // K̂_ab from the cross-correlations at lags −L … L; K_ba(l) = K_ab(−l), so K̂_ba = conj(K̂_ab)
    let mut k_hat = vec![Vec::new(); m * m];
    for a in 0..m {
        for b in a..m {
            let c = &corr[a * m + b];
            let mut kernel = vec![0.0; size];
            for l in 0..=max_lag {
                let taper = 1.0 - l as f64 / (max_lag as f64 + 1.0);
                kernel[l] = taper * c[l] / norm;
                if l > 0 {
                    kernel[size - l] = taper * c[size - l] / norm;
                }
            }
            k_hat[a * m + b] = real_spectrum(&mut planner, &kernel, size);
            if b > a {
                k_hat[b * m + a] = k_hat[a * m + b].iter().map(|z| z.conj()).collect();
            }
        }
    }
    let x_hat: Vec<Vec<Vec<Complex64>>> = cols
        .iter()
        .map(|c| {
            c.iter()
                .map(|col| real_spectrum(&mut planner, col.as_ref(), size))
                .collect()
        })
        .collect();
    let mut z = vec![Complex64::new(0.0, 0.0); m * p];
    for f in 0..=half {
        let g = if f == 0 || f == half { 1.0 } else { 2.0 } / size as f64;
        for a in 0..m {
            for j in 0..p {
                z[a * p + j] = (0..m).map(|b| k_hat[a * m + b][f] * x_hat[b][j][f]).sum();
            }
        }
        for a in 0..m {
            for i in 0..p {
                let xi = x_hat[a][i][f].conj();
                for j in 0..p {
                    w[i * p + j] += g * (xi * z[a * p + j]).re;
                }
            }
        }
    }
    for i in 0..p {
        for j in i + 1..p {
            let v = 0.5 * (w[i * p + j] + w[j * p + i]);
            w[i * p + j] = v;
            w[j * p + i] = v;
        }
    }
    w
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
    use super::{
        autocorrelation, bartlett_taper, cross_lag_weighted_products, effective_samples, lag_cap,
        lag_weighted_products, lag_weights, lag_window,
    };

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
    fn cross_products_equal_the_double_sum_over_outputs_and_lags() {
        // three outputs whose residuals share a coloured component (as gusts make them), p = 4
        let (len, p, m) = (211, 4, 3);
        let common = {
            let mut c = noise(len);
            for k in 1..len {
                c[k] += 0.9 * c[k - 1];
            }
            c
        };
        let own = noise(m * len);
        let residuals: Vec<Vec<f64>> = (0..m)
            .map(|a| {
                (0..len)
                    .map(|k| {
                        own[a * len + k] + [1.0, -0.5, 0.8][a] * common[(k + 2 * a).min(len - 1)]
                    })
                    .collect()
            })
            .collect();
        let s = noise(m * p * len + 7);
        let cols: Vec<Vec<Vec<f64>>> = (0..m)
            .map(|a| {
                (0..p)
                    .map(|j| (0..len).map(|k| s[(a * p + j) * len + k + a]).collect())
                    .collect()
            })
            .collect();
        let fast = cross_lag_weighted_products(&cols, &residuals);
        // the definition: one window for all outputs, the longest
        let lag = residuals
            .iter()
            .map(|r| lag_window(&autocorrelation(r, lag_cap(len)), len))
            .max()
            .unwrap();
        assert!(lag > 2, "the test needs a window of several lags: {lag}");
        let r_ab = |a: usize, b: usize, l: i64| -> f64 {
            (0..len as i64)
                .filter(|&k| (0..len as i64).contains(&(k + l)))
                .map(|k| residuals[a][(k + l) as usize] * residuals[b][k as usize])
                .sum::<f64>()
                / len as f64
        };
        let mut slow = vec![0.0; p * p];
        for a in 0..m {
            for b in 0..m {
                for l in -(lag as i64)..=lag as i64 {
                    let w = (1.0 - l.unsigned_abs() as f64 / (lag as f64 + 1.0)) * r_ab(a, b, l);
                    for k in 0..len as i64 {
                        let j = k - l;
                        if !(0..len as i64).contains(&j) {
                            continue;
                        }
                        for i1 in 0..p {
                            for i2 in 0..p {
                                slow[i1 * p + i2] +=
                                    cols[a][i1][k as usize] * w * cols[b][i2][j as usize];
                            }
                        }
                    }
                }
            }
        }
        for i in 0..p {
            for j in 0..p {
                let (f, d) = (fast[i * p + j], slow[i * p + j]);
                let scale = (slow[i * p + i] * slow[j * p + j]).sqrt();
                assert!((f - d).abs() <= 1e-10 * scale, "W[{i}][{j}]: {f} vs {d}");
            }
        }
        // one output: the single-output products
        let first: Vec<&[f64]> = cols[0].iter().map(Vec::as_slice).collect();
        let single = lag_weighted_products(&first, &lag_weights(&residuals[0]));
        let one = cross_lag_weighted_products(&cols[..1], &residuals[..1]);
        for (a, b) in one.iter().zip(&single) {
            assert!(
                (a - b).abs() <= 1e-10 * single[0].abs().max(1e-300),
                "{a} vs {b}"
            );
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
