//! The steady-state Riccati equation of the Kalman filter, solved by the matrix sign function.
//!
//! Filter form (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., §5.3, the
//! first-order approximation of the discrete filter's covariance equation with the innovation
//! covariance `R` of one sample interval `Δt`):
//!
//! `A P + P Aᵀ − P Cᵀ R_c⁻¹ C P + Q = 0`,  `R_c = Δt R`,  `Q = F Fᵀ`.
//!
//! With `A' = Aᵀ` it is the control-form equation `A'ᵀ P + P A' − P G P + Q = 0`, `G = Cᵀ R_c⁻¹
//! C`, whose stabilising solution spans the stable invariant subspace `[I; P]` of the Hamiltonian
//! `H = [[A', −G], [−Q, −A'ᵀ]]`. The sign function `W = sign(H)` is −I on that subspace, so
//! `(W + I) [I; P] = 0`, i.e. `[W₁₂; W₂₂ + I] P = −[W₁₁ + I; W₂₁]`, solved by least squares
//! (Roberts 1980; Byers, *Solving the algebraic Riccati equation with the matrix sign function*,
//! Linear Algebra Appl. 85, 1987). The sign is Newton's iteration `Z ← ½ (c Z + Z⁻¹/c)` with
//! Frobenius-norm scaling `c = √(‖Z⁻¹‖/‖Z‖)` (Higham, *Functions of Matrices*, §5.5), which needs
//! no eigenvalue ordering and stays in real arithmetic.

use faer::prelude::*;
use faer::Mat;

/// Newton iterations allowed for the sign function.
const MAX_ITERATIONS: usize = 100;

/// Stabilising solution `P` (n×n, symmetric) of `A P + P Aᵀ − P Cᵀ R_c⁻¹ C P + Q = 0` (module
/// doc), or `None` when the Hamiltonian has eigenvalues on the imaginary axis (no stabilising
/// solution: e.g. an undamped, unobserved mode) or the numbers are not finite.
///
/// `a` n×n, `c` m×n, `q` n×n symmetric positive semidefinite, `r_c` m×m symmetric positive
/// definite.
pub fn care_filter(a: &Mat<f64>, c: &Mat<f64>, q: &Mat<f64>, r_c: &Mat<f64>) -> Option<Mat<f64>> {
    let n = a.nrows();
    let m = c.nrows();
    let r_inv = r_c.partial_piv_lu().solve(Mat::<f64>::identity(m, m));
    let g = c.transpose() * &r_inv * c;
    let mut z = Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => a[(j, i)],
        (true, false) => -g[(i, j - n)],
        (false, true) => -q[(i - n, j)],
        (false, false) => -a[(i - n, j - n)],
    });
    if !finite(&z) {
        return None;
    }
    let eye = Mat::<f64>::identity(2 * n, 2 * n);
    let mut converged = false;
    let mut last_change = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let inv = z.partial_piv_lu().solve(&eye);
        if !finite(&inv) {
            return None;
        }
        let (nz, ni) = (z.norm_l2(), inv.norm_l2());
        // scaling speeds the first iterations; near convergence it only adds round-off
        let scale = if nz > 0.0 && ni > 0.0 && last_change > 1e-3 * nz {
            (ni / nz).sqrt()
        } else {
            1.0
        };
        let next = Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| {
            0.5 * (scale * z[(i, j)] + inv[(i, j)] / scale)
        });
        let change = (&next - &z).norm_l2();
        z = next;
        // quadratic convergence until round-off; stop there (the change no longer falls)
        let size = z.norm_l2();
        if change <= 1e-13 * size || (change <= 1e-8 * size && change >= 0.5 * last_change) {
            converged = true;
            break;
        }
        last_change = change;
    }
    if !converged {
        return None;
    }
    // [W12; W22 + I] P = −[W11 + I; W21]
    let lhs = Mat::<f64>::from_fn(2 * n, n, |i, j| {
        z[(i, n + j)] + if i >= n && i - n == j { 1.0 } else { 0.0 }
    });
    let mut rhs = Mat::<f64>::from_fn(2 * n, n, |i, j| {
        -(z[(i, j)] + if i == j { 1.0 } else { 0.0 })
    });
    lhs.qr().solve_lstsq_in_place(rhs.as_mut());
    let p = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (rhs[(i, j)] + rhs[(j, i)]));
    finite(&p).then_some(p)
}

fn finite(m: &Mat<f64>) -> bool {
    (0..m.nrows()).all(|i| (0..m.ncols()).all(|j| m[(i, j)].is_finite()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Residual of the filter-form equation, relative to the size of its terms.
    fn residual(a: &Mat<f64>, c: &Mat<f64>, q: &Mat<f64>, r_c: &Mat<f64>, p: &Mat<f64>) -> f64 {
        let r_inv = r_c
            .partial_piv_lu()
            .solve(Mat::<f64>::identity(c.nrows(), c.nrows()));
        let lhs = a * p + p * a.transpose() - p * c.transpose() * &r_inv * c * p + q;
        lhs.norm_l2() / (q.norm_l2() + (a * p).norm_l2())
    }

    #[test]
    fn scalar_case_has_the_closed_form() {
        // 2 a p − p² c²/r + q = 0 → p = r (a + √(a² + c² q / r)) / c²
        let (a, c, q, r) = (-0.7, 2.0, 0.3, 0.05);
        let p = care_filter(
            &Mat::from_fn(1, 1, |_, _| a),
            &Mat::from_fn(1, 1, |_, _| c),
            &Mat::from_fn(1, 1, |_, _| q),
            &Mat::from_fn(1, 1, |_, _| r),
        )
        .unwrap();
        let want = r * (a + (a * a + c * c * q / r).sqrt()) / (c * c);
        assert!(
            (p[(0, 0)] - want).abs() < 1e-12 * want,
            "{} vs {want}",
            p[(0, 0)]
        );
    }

    #[test]
    fn unstable_and_oscillatory_systems_are_stabilised() {
        // short period with an unstable M_α and a lightly damped 4-state longitudinal case
        let a = Mat::from_fn(4, 4, |i, j| {
            [
                [-0.04, 4.0, 0.0, -9.81],
                [-0.003, -1.1, 1.0, 0.0],
                [0.002, 2.5, -0.3, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ][i][j]
        });
        let c = Mat::from_fn(2, 4, |i, j| if j == i + 1 { 1.0 } else { 0.0 });
        let q = Mat::from_fn(4, 4, |i, j| {
            if i == j {
                [0.1, 0.01, 0.02, 0.0][i]
            } else {
                0.0
            }
        });
        let r_c = Mat::from_fn(2, 2, |i, j| if i == j { [1e-6, 4e-6][i] } else { 0.0 });
        let p = care_filter(&a, &c, &q, &r_c).unwrap();
        assert!(residual(&a, &c, &q, &r_c, &p) < 1e-9);
        // closed loop A − P Cᵀ R_c⁻¹ C is stable
        let r_inv = r_c.partial_piv_lu().solve(Mat::<f64>::identity(2, 2));
        let closed = &a - &p * c.transpose() * &r_inv * &c;
        let ev = closed.eigenvalues().unwrap();
        assert!(ev.iter().all(|e| e.re < 0.0), "{ev:?}");
    }
}
