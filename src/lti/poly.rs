//! Real polynomials with coefficients highest power first: roots, products, evaluation.

use faer::Mat;
use num_complex::Complex64;

/// Roots of `c[0]·xⁿ + … + c[n]` (highest power first), as eigenvalues of the balanced companion matrix.
///
/// Leading zero coefficients are dropped; trailing zeros give exact roots at 0. Eigenvalues come from
/// faer's real Schur decomposition after Parlett–Reinsch balancing (Golub & Van Loan, *Matrix
/// Computations* 4th ed., §7.4.6 and §7.5.4), then each is refined by Newton steps on the polynomial
/// as long as the residual drops. Complex roots come in exact conjugate pairs. A constant or empty
/// polynomial has no roots; non-finite coefficients give no roots either.
pub fn roots(coeffs_highest_first: &[f64]) -> Vec<Complex64> {
    if coeffs_highest_first.iter().any(|c| !c.is_finite()) {
        return Vec::new();
    }
    let first = coeffs_highest_first.iter().position(|&c| c != 0.0);
    let Some(first) = first else {
        return Vec::new();
    };
    let c = &coeffs_highest_first[first..];
    let last = c.iter().rposition(|&v| v != 0.0).unwrap_or(0);
    let n_zero_roots = c.len() - 1 - last;
    let p = &c[..=last];
    let n = p.len() - 1;
    let mut out = vec![Complex64::new(0.0, 0.0); n_zero_roots];
    if n == 0 {
        return out;
    }
    if n == 1 {
        out.push(Complex64::new(-p[1] / p[0], 0.0));
        return out;
    }
    // companion matrix: first row −p[1..]/p[0], ones on the subdiagonal
    let mut comp = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        comp[(0, j)] = -p[j + 1] / p[0];
    }
    for i in 1..n {
        comp[(i, i - 1)] = 1.0;
    }
    let _ = balance(&mut comp);
    let eig = match comp.eigenvalues() {
        Ok(e) => e,
        Err(_) => return out,
    };
    for z in eig {
        if z.im < 0.0 {
            continue; // added as the conjugate of its partner below
        }
        let z = polish(p, z);
        if z.im.abs() > 0.0 {
            out.push(z);
            out.push(z.conj());
        } else {
            out.push(z);
        }
    }
    out
}

/// Newton refinement of one root while the residual |p(z)| keeps dropping (at most 5 steps).
fn polish(p: &[f64], mut z: Complex64) -> Complex64 {
    let is_real = z.im == 0.0;
    let mut res = polyval_complex(p, z).norm();
    for _ in 0..5 {
        if res == 0.0 {
            break;
        }
        let (v, dv) = polyval_with_derivative(p, z);
        if dv.norm() == 0.0 {
            break;
        }
        let mut next = z - v / dv;
        if is_real {
            next.im = 0.0;
        }
        let next_res = polyval_complex(p, next).norm();
        if next_res < res {
            z = next;
            res = next_res;
        } else {
            break;
        }
    }
    z
}

/// Parlett–Reinsch balancing by powers of two: replaces `a` by D⁻¹AD, which evens row and column
/// norms without rounding error, and returns the diagonal of D.
pub(crate) fn balance(a: &mut Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut scale = vec![1.0; n];
    let radix = 2.0_f64;
    for _ in 0..100 {
        let mut converged = true;
        for i in 0..n {
            let (mut col, mut row) = (0.0, 0.0);
            for j in 0..n {
                if j != i {
                    col += a[(j, i)].abs();
                    row += a[(i, j)].abs();
                }
            }
            if col == 0.0 || row == 0.0 {
                continue;
            }
            let total = col + row;
            let mut f = 1.0;
            let (mut c, mut r) = (col, row);
            while c < r / radix {
                c *= radix;
                r /= radix;
                f *= radix;
            }
            while c >= r * radix {
                c /= radix;
                r *= radix;
                f /= radix;
            }
            if (c + r) < 0.95 * total {
                converged = false;
                scale[i] *= f;
                for j in 0..n {
                    a[(i, j)] /= f;
                }
                for j in 0..n {
                    a[(j, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
    scale
}

/// Coefficients of q(w) = p(w + 1) (Taylor shift by one; repeated synthetic division, Knuth TAOCP
/// vol. 2 §4.6.4). Used to write a z-domain polynomial in the δ variable w = z − 1.
pub fn taylor_shift(p: &[f64], by: f64) -> Vec<f64> {
    let mut c = p.to_vec();
    let n = c.len().saturating_sub(1);
    for i in 0..n {
        for j in 1..=(n - i) {
            c[j] += by * c[j - 1];
        }
    }
    c
}

/// Monic real polynomial with the given roots (complex roots should come in conjugate pairs; the
/// imaginary parts of the product are dropped). Empty roots give `[1.0]`.
pub fn poly_from_roots(roots: &[Complex64]) -> Vec<f64> {
    let mut c = vec![Complex64::new(1.0, 0.0)];
    for &r in roots {
        let mut next = vec![Complex64::new(0.0, 0.0); c.len() + 1];
        for (i, &ci) in c.iter().enumerate() {
            next[i] += ci;
            next[i + 1] -= ci * r;
        }
        c = next;
    }
    c.into_iter().map(|z| z.re).collect()
}

/// Value of the real polynomial `p` (highest power first) at the complex point `z` (Horner).
pub fn polyval_complex(p: &[f64], z: Complex64) -> Complex64 {
    p.iter()
        .fold(Complex64::new(0.0, 0.0), |acc, &c| acc * z + c)
}

/// Value of the real polynomial `p` (highest power first) at the real point `x` (Horner).
pub fn polyval(p: &[f64], x: f64) -> f64 {
    p.iter().fold(0.0, |acc, &c| acc * x + c)
}

fn polyval_with_derivative(p: &[f64], z: Complex64) -> (Complex64, Complex64) {
    let mut v = Complex64::new(0.0, 0.0);
    let mut dv = Complex64::new(0.0, 0.0);
    for &c in p {
        dv = dv * z + v;
        v = v * z + c;
    }
    (v, dv)
}

/// Product of two polynomials (highest power first).
pub fn poly_mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, &ai) in a.iter().enumerate() {
        for (j, &bj) in b.iter().enumerate() {
            out[i + j] += ai * bj;
        }
    }
    out
}

/// Sum of two polynomials (highest power first), aligned at the constant term.
pub fn poly_add(a: &[f64], b: &[f64]) -> Vec<f64> {
    let n = a.len().max(b.len());
    let mut out = vec![0.0; n];
    for (i, &v) in a.iter().enumerate() {
        out[n - a.len() + i] += v;
    }
    for (i, &v) in b.iter().enumerate() {
        out[n - b.len() + i] += v;
    }
    out
}

/// `p` without leading coefficients whose magnitude is at most `rel_tol · max|p|` (at least one
/// coefficient is kept).
pub fn strip_leading(p: &[f64], rel_tol: f64) -> Vec<f64> {
    let scale = p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let first = p
        .iter()
        .position(|v| v.abs() > rel_tol * scale)
        .unwrap_or(p.len().saturating_sub(1));
    if p.is_empty() {
        return vec![0.0];
    }
    p[first..].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted(mut r: Vec<Complex64>) -> Vec<Complex64> {
        r.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        r
    }

    /// Each expected root has its own found root within `tol` (relative, at least absolute).
    fn assert_roots_near(found: Vec<Complex64>, expected: Vec<Complex64>, tol: f64) {
        assert_eq!(found.len(), expected.len(), "{found:?}");
        let mut left = found.clone();
        for e in expected {
            let (i, d) = left
                .iter()
                .enumerate()
                .map(|(i, f)| (i, (f - e).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            assert!(d <= tol * e.norm().max(1.0), "{e} not found in {found:?}");
            left.remove(i);
        }
    }

    #[test]
    fn lightly_damped_pair_is_found_to_round_off() {
        // ζ = 1e-4, ωn = 30 rad/s: s² + 2ζωn s + ωn²
        let (zeta, wn) = (1e-4, 30.0_f64);
        let r = roots(&[1.0, 2.0 * zeta * wn, wn * wn]);
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        assert_roots_near(
            r,
            vec![
                Complex64::new(-zeta * wn, wd),
                Complex64::new(-zeta * wn, -wd),
            ],
            1e-13,
        );
    }

    #[test]
    fn repeated_roots_are_found_to_the_cube_root_of_eps() {
        // (s+2)³: a triple root is only determined to ~eps^(1/3) ≈ 6e-6 relative by any method
        let r = roots(&[1.0, 6.0, 12.0, 8.0]);
        assert_roots_near(r, vec![Complex64::new(-2.0, 0.0); 3], 1e-4);
        // (s² + 1)²: repeated imaginary pair, determined to ~sqrt(eps)
        let r = roots(&[1.0, 0.0, 2.0, 0.0, 1.0]);
        assert_roots_near(
            r,
            vec![
                Complex64::new(0.0, 1.0),
                Complex64::new(0.0, 1.0),
                Complex64::new(0.0, -1.0),
                Complex64::new(0.0, -1.0),
            ],
            1e-6,
        );
    }

    #[test]
    fn widely_scaled_roots_keep_relative_accuracy() {
        // roots −1e-3, −1, −1e3: balancing plus Newton keep each to ~1e-12 relative
        let expected = vec![
            Complex64::new(-1e-3, 0.0),
            Complex64::new(-1.0, 0.0),
            Complex64::new(-1e3, 0.0),
        ];
        let p = poly_from_roots(&expected);
        let r = sorted(roots(&p));
        for (f, e) in r.iter().zip(sorted(expected)) {
            assert!((f - e).norm() <= 1e-12 * e.norm(), "{f} vs {e}");
        }
    }

    #[test]
    fn zeros_and_leading_zeros_are_handled() {
        assert_roots_near(
            roots(&[0.0, 0.0, 1.0, -3.0, 0.0, 0.0]),
            vec![
                Complex64::new(3.0, 0.0),
                Complex64::new(0.0, 0.0),
                Complex64::new(0.0, 0.0),
            ],
            1e-15,
        );
        assert!(roots(&[5.0]).is_empty());
        assert!(roots(&[]).is_empty());
        assert!(roots(&[0.0, 0.0]).is_empty());
        assert!(roots(&[1.0, f64::NAN]).is_empty());
    }

    #[test]
    fn paper_theta_denominator_roots_rebuild_the_polynomial() {
        let den = [1.0, 2.0072, 32.5269, 0.8638, 0.0179];
        let p = poly_from_roots(&roots(&den));
        for (a, b) in p.iter().zip(den) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn polynomial_helpers_agree_with_hand_results() {
        assert_eq!(poly_mul(&[1.0, 2.0], &[1.0, -3.0]), vec![1.0, -1.0, -6.0]);
        assert_eq!(poly_add(&[1.0, 2.0, 3.0], &[1.0, 1.0]), vec![1.0, 3.0, 4.0]);
        assert_eq!(polyval(&[1.0, -1.0, -6.0], 3.0), 0.0);
        assert_eq!(
            strip_leading(&[1e-16, 0.0, 2.0, 1.0], 1e-12),
            vec![2.0, 1.0]
        );
    }
}
