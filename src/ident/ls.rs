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
//!   fixed, so the discrete numerator of each basis term `s^j/A(s)` (j = 0..m) is computed and
//!   the continuous coefficients `c_j` solve `Σ c_j b_d^{(j)} ≈ b̂_d` in least squares. With
//!   `m = n − 1` this is exactly MATLAB's `d2c(…, 'zoh')`; with fewer zeros it is `d2c` followed
//!   by dropping the negligible highest numerator terms, done as a projection so the kept terms
//!   absorb the dropped ones' tiny contribution.

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
    let first = n.max(nb + delay_samples);
    let rows = y.len().saturating_sub(first);
    let phi = Mat::<f64>::from_fn(rows, n + nb, |r, c| {
        arx_entry(u, y, n, delay_samples, r + first, c)
    });
    (phi, y[first..].to_vec())
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
    let first = n.max(nb + delay_samples);
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
    let first = n.max(nb + delay_samples);
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

/// Exact ZOH d2c of a discrete numerator `b` (on u(k−1)…u(k−nb)) given the continuous monic
/// denominator, projected onto a continuous numerator with `zeros` zeros (see module docs).
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
    // columns ordered highest power first: column c ↔ s^{m−c}
    let mat = Mat::<f64>::from_fn(nb, m + 1, |r, c| basis_num(m - c, r + 1));
    lstsq_qr(&mat, b, "ls (d2c numerator)")
}

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
