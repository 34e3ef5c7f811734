//! Small numerical helpers private to `ident`: least squares by column-pivoted QR, small dense
//! solves and products. Polynomial roots and products are the `lti` ones, re-exported here.
//!
//! Square matrices here are tiny (model order ≤ ~10) and stored row-major in a `Vec<f64>`.

use faer::prelude::*;
use num_complex::Complex64;

use super::IdentError;

pub(crate) use crate::lti::{poly_from_roots, poly_mul, roots};

/// Least-squares solution of `phi θ ≈ y` by Householder QR, column-pivoted when the
/// diagonal of R shows poor conditioning (Golub & Van Loan, *Matrix Computations*, 4th ed.,
/// §5.3.3, §5.4.2). Normal equations are never formed: at the
/// condition numbers of fast-sampled ARX regressors (1e8–1e10) they lose every digit.
///
/// Returns θ, or [`IdentError::SingularRegression`] when the numerical rank (|R_ii| above
/// 1e-13·|R_00|) is below the number of columns.
pub(crate) fn lstsq_qr(phi: &Mat<f64>, y: &[f64], method: &str) -> Result<Vec<f64>, IdentError> {
    // plain (blocked, faster) Householder QR first; pivoting only when R's diagonal shows
    // a condition number that plain QR would not resolve
    let p = phi.ncols();
    let qr = phi.qr();
    let r = qr.thin_R();
    let (lo, hi) = (0..p).fold((f64::INFINITY, 0.0_f64), |(lo, hi), i| {
        (lo.min(r[(i, i)].abs()), hi.max(r[(i, i)].abs()))
    });
    if lo > 1e-10 * hi {
        let mut rhs = Mat::<f64>::from_fn(y.len(), 1, |i, _| y[i]);
        qr.solve_lstsq_in_place(rhs.as_mut());
        let theta: Vec<f64> = (0..p).map(|i| rhs[(i, 0)]).collect();
        if theta.iter().all(|v| v.is_finite()) {
            return Ok(theta);
        }
    }
    let qr = phi.col_piv_qr();
    let r = qr.thin_R();
    let r00 = r[(0, 0)].abs();
    let rank = (0..p).filter(|&i| r[(i, i)].abs() > 1e-13 * r00).count();
    if r00 == 0.0 || rank < p {
        return Err(IdentError::SingularRegression {
            method: method.to_string(),
            rank,
            n_params: p,
        });
    }
    let mut rhs = Mat::<f64>::from_fn(y.len(), 1, |i, _| y[i]);
    qr.solve_lstsq_in_place(rhs.as_mut());
    let theta: Vec<f64> = (0..p).map(|i| rhs[(i, 0)]).collect();
    if theta.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::SingularRegression {
            method: method.to_string(),
            rank,
            n_params: p,
        });
    }
    Ok(theta)
}

/// Solves the small square system `a x = b` (row-major `a`, n×n) by partial-pivoting LU.
/// Returns `None` when a pivot vanishes relative to the largest entry.
pub(crate) fn solve_square(a: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let m = Mat::<f64>::from_fn(n, n, |i, j| a[i * n + j]);
    let scale = a.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    let lu = m.partial_piv_lu();
    let mut rhs = Mat::<f64>::from_fn(n, 1, |i, _| b[i]);
    lu.solve_in_place(rhs.as_mut());
    let x: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();
    if x.iter().all(|v| v.is_finite()) {
        Some(x)
    } else {
        None
    }
}

/// Inverse of a small symmetric positive (semi)definite matrix via LU; `None` when singular.
pub(crate) fn inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut inv = vec![0.0; n * n];
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let col = solve_square(a, &e)?;
        for i in 0..n {
            inv[i * n + j] = col[i];
        }
    }
    Some(inv)
}

/// The n×n identity, row-major.
pub(crate) fn identity(n: usize) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
    }
    m
}

/// Reflects right-half-plane roots into the left half plane (s → −s̄); used to keep the
/// SRIVC prefilter and auxiliary model stable (Garnier, Gilson & Huselstein 2003, CONTSID).
pub(crate) fn stabilize_continuous(den_monic: &[f64]) -> Vec<f64> {
    let r = roots(den_monic);
    if r.iter().all(|z| z.re < 0.0) {
        return den_monic.to_vec();
    }
    let refl: Vec<Complex64> = r
        .iter()
        .map(|z| {
            if z.re >= 0.0 {
                // a root on the imaginary axis is moved just inside the stable region
                Complex64::new(-(z.re.abs().max(1e-6 * (1.0 + z.norm()))), z.im)
            } else {
                *z
            }
        })
        .collect();
    poly_from_roots(&refl)
}

/// Inner product with eight independent partial sums (lets the compiler vectorise the loop).
pub(crate) fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let (xc, yc) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = xc
        .remainder()
        .iter()
        .zip(yc.remainder())
        .map(|(a, b)| a * b)
        .sum();
    for (a, b) in xc.zip(yc) {
        for k in 0..8 {
            acc[k] += a[k] * b[k];
        }
    }
    acc.iter().sum::<f64>() + tail
}
