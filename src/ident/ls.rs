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
        let k = r + first;
        if c < n {
            -y[k - 1 - c]
        } else {
            u[k - 1 - (c - n) - delay_samples]
        }
    });
    (phi, y[first..].to_vec())
}

/// Fits the ARX model of eq. 59 by QR least squares.
pub(crate) fn arx_ls(
    u: &[f64],
    y: &[f64],
    n: usize,
    nb: usize,
    delay_samples: usize,
) -> Result<Arx, IdentError> {
    let (phi, target) = arx_regressor(u, y, n, nb, delay_samples);
    let theta = lstsq_qr(&phi, &target, "ls")?;
    let mut a = vec![1.0];
    a.extend_from_slice(&theta[..n]);
    Ok(Arx {
        a,
        b: theta[n..].to_vec(),
    })
}

/// Continuous poles `ln z / h` of a discrete denominator (q⁻¹ coefficients, a₀ = 1).
pub(crate) fn continuous_poles(a: &[f64], dt_s: f64) -> Result<Vec<Complex64>, IdentError> {
    let z = roots(a);
    let mut p = Vec::with_capacity(z.len());
    for zi in z {
        if !(zi.norm() > 0.0) || !zi.re.is_finite() {
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
    let n = den_c.len() - 1;
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
                al * states[(i - l) * n + j]
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
