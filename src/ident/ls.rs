//! `ls` — the paper's discrete ARX least squares (Şahin & Kalyon 2021, eq. 59–64), then a ZOH
//! conversion to a continuous transfer function.
//!
//! Model (eq. 59): `y(k) = −a₁y(k−1) − … − a_n y(k−n) + b₁u(k−1) + … + b_{nb}u(k−nb) + e(k)`,
//! stacked over k into `Y = Φθ` (eq. 60–62) and solved in the least-squares sense (eq. 63–64,
//! `θ = (ΦᵀΦ)⁻¹ΦᵀY`) — here by column-pivoted QR, never through the normal equations.
//!
//! Relative degree. The ZOH equivalent of a strictly proper n-pole continuous model has a
//! full discrete numerator (n coefficients, n − 1 zeros) whatever the continuous zeros are, so
//! the fit uses `nb = n`. The continuous model follows from the exact ZOH relations:
//! - poles: `z = e^{ph}` ⇒ `p = ln z / h` (a discrete pole on the negative real axis has no real
//!   continuous equivalent; its magnitude `ln|z|/h` is kept, which only happens on noisy data);
//! - numerator: ZOH discretisation is linear in the continuous numerator once the poles are
//!   fixed, so the discrete numerator `b_d^{(j)}` of each basis term `s^j/A(s)` (j = 0..m) is
//!   computed and the continuous coefficients `c_j` make the frequency responses agree:
//!   `Σ c_j B_d^{(j)}(z)/A_d(z) ≈ B̂_d(z)/A_d(z)` in least squares over `z = e^{iωh}`, ω on a
//!   logarithmic grid up to the Nyquist frequency. With `m = n − 1` the residual is zero and this
//!   is exactly MATLAB's `d2c(…, 'zoh')`; with fewer zeros it is the continuous model of that
//!   structure whose response is closest to the discrete model's. The response must be compared,
//!   not the numerator coefficients: near a pole at z ≈ 1 (a slow phugoid or spiral, or an
//!   integrator-like pole of a biased fit) a tiny change of a coefficient moves the low-frequency
//!   gain by orders of magnitude, and a coefficient-space projection turned a discrete ARX model
//!   simulating at 45 % into a continuous one at −1492 % (c172x θ/δe doublet at 120 Hz, checked
//!   against an exact d2c by scipy's matrix logarithm in `scripts/oracle_ls_d2c.py`).

use faer::Mat;
use num_complex::Complex64;

use super::filter::{Hold, Svf};
use super::linalg::{lstsq_qr, poly_from_roots, roots};
use super::{ContinuousModel, IdentError};

/// Discrete ARX estimate: `a` = [1, a₁…a_n] (in q⁻¹), `b` = [b₁…b_nb].
#[derive(Clone, Debug)]
pub(crate) struct Arx {
    pub a: Vec<f64>,
    pub b: Vec<f64>,
}

/// Regressor matrix of eq. 60–62 with an extra input delay of `delay_samples`: row k holds
/// `[−y(k−1) … −y(k−n), u(k−1−d) … u(k−nb−d)]` for k = first..N−1.
pub(crate) fn arx_regressor(
    u: &[f64],
    y: &[f64],
    n: usize,
    nb: usize,
    delay_samples: usize,
) -> (Mat<f64>, Vec<f64>) {
    let first = first_row(n, nb, delay_samples);
    let rows = y.len().saturating_sub(first);
    let phi = Mat::<f64>::from_fn(rows, n + nb, |r, c| {
        arx_entry(u, y, n, delay_samples, r + first, c)
    });
    (phi, y[first..].to_vec())
}

/// The first sample k whose regressor row of eq. 60–62 exists: every `y(k−n)` and `u(k−nb−d)` is in the record.
fn first_row(n: usize, nb: usize, delay_samples: usize) -> usize {
    n.max(nb + delay_samples)
}

/// Entry of row k, column c of the regressor of eq. 60–62: `−y(k−1−c)` for c < n, else `u(k−1−(c−n)−d)`.
#[inline]
fn arx_entry(u: &[f64], y: &[f64], n: usize, delay_samples: usize, k: usize, c: usize) -> f64 {
    if c < n {
        -y[k - 1 - c]
    } else {
        u[k - 1 - (c - n) - delay_samples]
    }
}

/// Fits the ARX model of eq. 59 by QR least squares.
pub(crate) fn arx_ls(
    u: &[f64],
    y: &[f64],
    n: usize,
    nb: usize,
    delay_samples: usize,
) -> Result<Arx, IdentError> {
    let first = first_row(n, nb, delay_samples);
    let rows = y.len().saturating_sub(first);
    let theta = match (rows >= TSQR_MIN_ROWS)
        .then(|| arx_lstsq_tsqr(u, y, n, nb, delay_samples))
        .flatten()
    {
        Some(theta) => theta,
        None => {
            let (phi, target) = arx_regressor(u, y, n, nb, delay_samples);
            lstsq_qr(&phi, &target, "ls")?
        }
    };
    let mut a = vec![1.0];
    a.extend_from_slice(&theta[..n]);
    Ok(Arx {
        a,
        b: theta[n..].to_vec(),
    })
}

/// Records at least this long are solved by two-block TSQR on two threads.
const TSQR_MIN_ROWS: usize = 20_000;

/// ARX least squares by a two-block tall-skinny QR (Demmel et al. 2012, "Communication-optimal parallel and
/// sequential QR", §3): each half of the rows of the augmented regressor `[Φ Y]` (eq. 60–62) is built and
/// QR-factorised on its own thread, the two triangular factors `[R_i  Q_iᵀY_i]` are stacked and factorised once
/// more, and `θ` follows from `R θ = QᵀY` by back substitution — the same Householder least squares as
/// [`lstsq_qr`], never the normal equations. Returns `None` when `R` is ill-conditioned (diagonal ratio below
/// 1e-10) or not finite, so the caller falls back to column-pivoted QR with its rank diagnosis.
fn arx_lstsq_tsqr(
    u: &[f64],
    y: &[f64],
    n: usize,
    nb: usize,
    delay_samples: usize,
) -> Option<Vec<f64>> {
    let p = n + nb;
    let first = first_row(n, nb, delay_samples);
    let mid = first + (y.len() - first) / 2;
    let block_r = |from: usize, to: usize| -> Mat<f64> {
        let aug = Mat::<f64>::from_fn(to - from, p + 1, |r, c| {
            let k = r + from;
            if c < p {
                arx_entry(u, y, n, delay_samples, k, c)
            } else {
                y[k]
            }
        });
        aug.qr().thin_R().to_owned()
    };
    let (r1, r2) = rayon::join(|| block_r(first, mid), || block_r(mid, y.len()));
    let stacked = Mat::<f64>::from_fn(2 * (p + 1), p + 1, |r, c| {
        if r <= p {
            r1[(r, c)]
        } else {
            r2[(r - p - 1, c)]
        }
    });
    let r = stacked.qr().thin_R().to_owned();
    let (lo, hi) = (0..p).fold((f64::INFINITY, 0.0_f64), |(lo, hi), i| {
        (lo.min(r[(i, i)].abs()), hi.max(r[(i, i)].abs()))
    });
    // also rejects NaN diagonals
    if lo.partial_cmp(&(1e-10 * hi)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut theta = vec![0.0; p];
    for i in (0..p).rev() {
        let acc: f64 = (i + 1..p).map(|j| r[(i, j)] * theta[j]).sum();
        theta[i] = (r[(i, p)] - acc) / r[(i, i)];
    }
    theta.iter().all(|v| v.is_finite()).then_some(theta)
}

/// Continuous poles `ln z / h` of a discrete denominator (q⁻¹ coefficients, a₀ = 1).
pub(crate) fn continuous_poles(a: &[f64], dt_s: f64) -> Result<Vec<Complex64>, IdentError> {
    let z = roots(a);
    let mut p = Vec::with_capacity(z.len());
    for zi in z {
        if zi.norm().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !zi.re.is_finite() {
            return Err(IdentError::Failed {
                method: "ls".into(),
                reason: format!("discrete pole {zi} has no continuous ZOH equivalent"),
            });
        }
        let pi = if zi.im.abs() <= 1e-12 * zi.norm() && zi.re < 0.0 {
            Complex64::new(zi.norm().ln() / dt_s, 0.0)
        } else if zi.im.abs() <= 1e-12 * zi.norm() {
            Complex64::new(zi.re.ln() / dt_s, 0.0)
        } else {
            zi.ln() / dt_s
        };
        p.push(pi);
    }
    Ok(p)
}

/// ZOH d2c of a discrete numerator `b` (on u(k−1)…u(k−nb)) given the continuous monic
/// denominator: the continuous numerator with `zeros` zeros whose ZOH frequency response matches
/// the discrete model's in least squares (exact when `zeros = nb − 1`; see module docs).
pub(crate) fn d2c_numerator(
    b: &[f64],
    den_c: &[f64],
    dt_s: f64,
    zeros: usize,
) -> Result<Vec<f64>, IdentError> {
    let nb = b.len();
    // discrete denominator of the ZOH model, from the same poles
    let p_c = roots(den_c);
    let zd: Vec<Complex64> = p_c.iter().map(|p| (p * dt_s).exp()).collect();
    let a_d = poly_from_roots(&zd);
    // Markov parameters of each basis term s^j/A(s): states of the ZOH SVF driven by an impulse
    let svf = Svf::new(den_c, dt_s, Hold::Zoh { delay_s: 0.0 });
    let mut impulse = vec![0.0; nb + 1];
    impulse[0] = 1.0;
    let states = svf.run(&impulse);
    // discrete numerator of basis j: b_i = Σ_{l=0}^{i−1} a_l h_{i−l}, i = 1..nb
    let m = zeros;
    let basis_num = |j: usize, i: usize| -> f64 {
        (0..i)
            .map(|l| {
                let al = if l < a_d.len() { a_d[l] } else { 0.0 };
                al * states.col(j)[i - l]
            })
            .sum()
    };
    // frequency responses on z = e^{iωh}: ω log-spaced from below the slowest pole to Nyquist
    let nyquist = std::f64::consts::PI / dt_s;
    let slowest = p_c
        .iter()
        .map(|p| p.norm())
        .filter(|w| *w > 0.0)
        .fold(nyquist, f64::min);
    let w_lo = (0.1 * slowest).min(1e-3 * nyquist);
    let at = |coeffs: &dyn Fn(usize) -> f64, len: usize, w: f64| -> Complex64 {
        (0..len)
            .map(|i| coeffs(i) * Complex64::from_polar(1.0, -w * dt_s * i as f64))
            .sum()
    };
    let grid: Vec<(Vec<Complex64>, Complex64)> = (0..FREQ_POINTS)
        .map(|k| {
            let w = w_lo * (nyquist / w_lo).powf(k as f64 / (FREQ_POINTS - 1) as f64);
            let inv_a = 1.0 / at(&|l| a_d[l], a_d.len(), w);
            // discrete numerators: coefficient i ↔ z^{−i}, i = 1..nb (index 0 is zero)
            let num_at =
                |f: &dyn Fn(usize) -> f64| at(&|i| if i == 0 { 0.0 } else { f(i) }, nb + 1, w);
            // columns ordered highest power first: column c ↔ s^{m−c}
            let basis = (0..=m)
                .map(|c| num_at(&|i| basis_num(m - c, i)) * inv_a)
                .collect();
            (basis, num_at(&|i| b[i - 1]) * inv_a)
        })
        .collect();
    let mat = Mat::<f64>::from_fn(2 * FREQ_POINTS, m + 1, |r, c| {
        let v = grid[r / 2].0[c];
        if r % 2 == 0 {
            v.re
        } else {
            v.im
        }
    });
    let target: Vec<f64> = grid.iter().flat_map(|(_, t)| [t.re, t.im]).collect();
    lstsq_qr(&mat, &target, "ls (d2c numerator)")
}

/// Frequencies on which [`d2c_numerator`] matches the discrete and continuous responses.
const FREQ_POINTS: usize = 256;

/// The paper's estimator end to end: ARX fit, continuous poles, continuous numerator.
pub(crate) fn ls(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    poles: usize,
    zeros: usize,
    delay_samples: usize,
) -> Result<(ContinuousModel, Arx), IdentError> {
    let arx = arx_ls(u, y, poles, poles, delay_samples)?;
    let model = arx_to_continuous(&arx, dt_s, zeros, delay_samples)?;
    Ok((model, arx))
}

/// ZOH d2c of an ARX model to the requested continuous structure.
pub(crate) fn arx_to_continuous(
    arx: &Arx,
    dt_s: f64,
    zeros: usize,
    delay_samples: usize,
) -> Result<ContinuousModel, IdentError> {
    let p = continuous_poles(&arx.a, dt_s)?;
    let den = poly_from_roots(&p);
    let num = d2c_numerator(&arx.b, &den, dt_s, zeros)?;
    Ok(ContinuousModel::new(num, den, delay_samples as f64 * dt_s))
}

#[cfg(test)]
mod tsqr_tests {
    use super::*;

    /// Two-block TSQR and one-shot Householder QR solve the same least-squares problem: on a noisy
    /// 4-pole ARX record of 60,000 samples the estimates agree to 1e-9 relative (both are backward
    /// stable; the regressor's condition number here is about 1e4, so rounding differs near 1e-12).
    #[test]
    fn tsqr_matches_one_shot_qr_on_a_long_noisy_record() {
        let n_samples = 60_000;
        let mut state = 12345_u64;
        let mut noise = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let u: Vec<f64> = (0..n_samples)
            .map(|k| if (k / 300) % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let (a, b) = ([1.0, -2.6, 2.8, -1.45, 0.3], [0.01, 0.02, 0.015, 0.005]);
        let mut y = vec![0.0; n_samples];
        for k in 4..n_samples {
            y[k] = (1..5)
                .map(|i| -a[i] * y[k - i] + b[i - 1] * u[k - i])
                .sum::<f64>();
        }
        let y: Vec<f64> = y.iter().map(|v| v + 0.01 * noise()).collect();
        let fast = arx_lstsq_tsqr(&u, &y, 4, 4, 0).expect("well conditioned");
        let (phi, target) = arx_regressor(&u, &y, 4, 4, 0);
        let reference = lstsq_qr(&phi, &target, "ls").unwrap();
        for (f, r) in fast.iter().zip(&reference) {
            assert!((f - r).abs() <= 1e-9 * r.abs().max(1e-3), "{f} vs {r}");
        }
    }
}
