//! Continuous ⇄ discrete conversion: zero-order hold (exact, matrix exponential/logarithm) and
//! Tustin (bilinear).

use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::Mat;
use serde::{Deserialize, Serialize};

use super::poly::{balance, taylor_shift};
use super::ss::{ss2tf, tf2ss, StateSpace};
use super::tf::TransferFunction;
use super::LtiError;

/// How to convert between continuous and discrete time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Discretization {
    /// Zero-order hold: the input is constant between samples; exact for such inputs.
    Zoh,
    /// Tustin / bilinear: s = (2/dt)(z − 1)/(z + 1).
    Tustin,
}

fn identity(n: usize) -> Mat<f64> {
    Mat::identity(n, n)
}

fn scaled(a: &Mat<f64>, k: f64) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| k * a[(i, j)])
}

fn lin(a: &Mat<f64>, ka: f64, b: &Mat<f64>, kb: f64) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| ka * a[(i, j)] + kb * b[(i, j)])
}

fn norm_inf(a: &Mat<f64>) -> f64 {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `a⁻¹ b` by LU with partial pivoting.
fn solve(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    a.partial_piv_lu().solve(b)
}

fn inverse(a: &Mat<f64>) -> Mat<f64> {
    a.partial_piv_lu().inverse()
}

/// Matrix exponential e^A by scaling and squaring with the diagonal Padé approximant of degree 6
/// (Golub & Van Loan, *Matrix Computations* 4th ed., Alg. 9.3.1), j chosen so that ‖A/2^j‖∞ < 1/2,
/// where the relative backward error bound of the approximant is 3.4e-16.
pub fn expm(a: &Mat<f64>) -> Mat<f64> {
    let n = a.nrows();
    let norm = norm_inf(a);
    let j = if norm > 0.0 {
        (2 + norm.log2().floor() as i64).max(0) as i32
    } else {
        0
    };
    let a = scaled(a, 0.5_f64.powi(j));
    let q = 6;
    let mut c = 1.0;
    let mut x = identity(n);
    let mut num = identity(n);
    let mut den = identity(n);
    for k in 1..=q {
        c *= (q - k + 1) as f64 / ((2 * q - k + 1) * k) as f64;
        x = &a * &x;
        num = lin(&num, 1.0, &x, c);
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        den = lin(&den, 1.0, &x, sign * c);
    }
    let mut f = solve(&den, &num);
    for _ in 0..j {
        f = &f * &f;
    }
    f
}

/// [`expm`] of a row-major n×n matrix given as a flat slice, returned the same way (for the
/// state-variable filters, which keep their matrices flat).
pub fn expm_rows(a: &[f64], n: usize) -> Vec<f64> {
    let e = expm(&Mat::<f64>::from_fn(n, n, |i, j| a[i * n + j]));
    (0..n * n).map(|k| e[(k / n, k % n)]).collect()
}

/// Principal square root by the product form of the Denman–Beavers iteration (Higham, *Functions of
/// Matrices*, 2008, eq. 6.29). `None` if it does not converge (eigenvalues on the closed negative axis).
fn sqrtm(a: &Mat<f64>) -> Option<Mat<f64>> {
    let n = a.nrows();
    let eye = identity(n);
    let mut m = a.clone();
    let mut y = a.clone();
    for _ in 0..100 {
        let m_inv = inverse(&m);
        if !norm_inf(&m_inv).is_finite() {
            return None;
        }
        y = scaled(&(&y * &lin(&eye, 1.0, &m_inv, 1.0)), 0.5);
        m = lin(&eye, 0.5, &lin(&m, 1.0, &m_inv, 1.0), 0.25);
        if norm_inf(&lin(&m, 1.0, &eye, -1.0)) <= 1e-15 * n as f64 {
            return Some(y);
        }
    }
    None
}

/// Principal matrix logarithm log(A); see [`log1pm`].
pub fn logm(a: &Mat<f64>) -> Result<Mat<f64>, LtiError> {
    let n = a.nrows();
    log1pm(&lin(a, 1.0, &identity(n), -1.0))
}

/// Principal logarithm log(I + E), taking the deviation E from the identity as input so that a
/// matrix close to I (a discrete model sampled fast) loses no digits to the subtraction.
///
/// Inverse scaling and squaring (Kenney & Laub 1989; Higham, *Functions of Matrices*, 2008, §11.5):
/// while ‖E‖∞ > 0.05, replace I + E by its square root I + E(I + S)⁻¹, S = (I + E)^½ (Denman–Beavers),
/// counting k roots; then log(I + E) = 2·atanh(Z) = 2 Σ Z^(2i+1)/(2i+1) with Z = E(2I + E)⁻¹
/// (‖Z‖ ≲ 0.026, eleven terms reach round-off), times 2^k. Fails when I + E has an eigenvalue on the
/// closed negative real axis (no real logarithm).
pub fn log1pm(e: &Mat<f64>) -> Result<Mat<f64>, LtiError> {
    let n = e.nrows();
    if n == 0 {
        return Ok(Mat::zeros(0, 0));
    }
    let eye = identity(n);
    let eig = lin(&eye, 1.0, e, 1.0)
        .eigenvalues()
        .map_err(|_| LtiError::NoConvergence {
            what: "eigenvalues for the matrix logarithm",
        })?;
    if let Some(z) = eig
        .iter()
        .find(|z| z.re <= 0.0 && z.im.abs() <= 1e-12 * z.norm().max(1e-300))
    {
        return Err(LtiError::NoRealLogarithm {
            pole_re: z.re,
            pole_im: z.im,
        });
    }
    let mut e = e.clone();
    let mut k = 0;
    while norm_inf(&e) > 0.05 {
        if k >= 64 {
            return Err(LtiError::NoConvergence {
                what: "matrix logarithm (square roots)",
            });
        }
        let s = sqrtm(&lin(&eye, 1.0, &e, 1.0)).ok_or(LtiError::NoConvergence {
            what: "matrix square root (Denman-Beavers)",
        })?;
        // (I + E)^½ − I = E (I + S)⁻¹; E and S commute
        e = solve(&lin(&eye, 1.0, &s, 1.0), &e);
        k += 1;
    }
    let z = solve(&lin(&eye, 2.0, &e, 1.0), &e);
    let z2 = &z * &z;
    let mut term = z.clone();
    let mut sum = z.clone();
    for i in 1..40 {
        term = &term * &z2;
        let coeff = 1.0 / (2 * i + 1) as f64;
        sum = lin(&sum, 1.0, &term, coeff);
        if norm_inf(&term) * coeff <= 1e-18 * norm_inf(&sum) {
            break;
        }
    }
    Ok(scaled(&sum, 2.0 * 2.0_f64.powi(k)))
}

fn check_dt(dt_s: f64) -> Result<(), LtiError> {
    if dt_s > 0.0 && dt_s.is_finite() {
        Ok(())
    } else {
        Err(LtiError::BadSamplePeriod { dt_s })
    }
}

/// Discretises a continuous model with sample period `dt_s`.
///
/// ZOH: exp([[A, B], [0, 0]]·dt) = [[A_d, B_d], [0, I]] (Van Loan 1978; Franklin, Powell & Workman,
/// *Digital Control*, §4.3.3), C and D unchanged. Tustin: A_d = (I − αA)⁻¹(I + αA),
/// B_d = (I − αA)⁻¹B·dt, C_d = C(I − αA)⁻¹, D_d = D + ½·C·B_d with α = dt/2 (the realisation
/// `scipy.signal.cont2discrete(method="bilinear")` uses). A model that is already discrete, or a
/// non-positive `dt_s`, is returned unchanged.
pub fn c2d(ss: &StateSpace, dt_s: f64, method: Discretization) -> StateSpace {
    if ss.is_discrete() || check_dt(dt_s).is_err() {
        return ss.clone();
    }
    let (n, m) = (ss.n_states(), ss.n_inputs());
    match method {
        Discretization::Zoh => {
            let aug = Mat::from_fn(n + m, n + m, |i, j| match (i < n, j < n) {
                (true, true) => ss.a[(i, j)] * dt_s,
                (true, false) => ss.b[(i, j - n)] * dt_s,
                _ => 0.0,
            });
            let e = expm(&aug);
            StateSpace {
                a: Mat::from_fn(n, n, |i, j| e[(i, j)]),
                b: Mat::from_fn(n, m, |i, j| e[(i, n + j)]),
                c: ss.c.clone(),
                d: ss.d.clone(),
                dt_s: Some(dt_s),
            }
        }
        Discretization::Tustin => {
            let alpha = dt_s / 2.0;
            let eye = identity(n);
            let ima = lin(&eye, 1.0, &ss.a, -alpha);
            let ipa = lin(&eye, 1.0, &ss.a, alpha);
            let ad = solve(&ima, &ipa);
            let bd = solve(&ima, &scaled(&ss.b, dt_s));
            let cd = solve(&ima.transpose().to_owned(), &ss.c.transpose().to_owned())
                .transpose()
                .to_owned();
            let dd = lin(&ss.d, 1.0, &(&ss.c * &bd), 0.5);
            let dd = if n == 0 { ss.d.clone() } else { dd };
            StateSpace {
                a: ad,
                b: bd,
                c: cd,
                d: dd,
                dt_s: Some(dt_s),
            }
        }
    }
}

/// Continuous model whose discretisation with `method` is `ss` (the inverse of [`c2d`]).
///
/// ZOH: log([[A_d, B_d], [0, I]])/dt = [[A, B], [0, 0]] with the principal logarithm ([`log1pm`]),
/// after balancing A_d; fails on a pole on the closed negative real z axis, which no continuous
/// system produces under ZOH. Tustin: with M = 2(A_d + I)⁻¹ = I − αA, A = (I − M)/α,
/// B = M·B_d/dt, C = C_d·M, D = D_d − ½·C·B_d; fails on a pole at z = −1.
pub fn d2c(ss: &StateSpace, method: Discretization) -> Result<StateSpace, LtiError> {
    let n = ss.n_states();
    let e = lin(&ss.a, 1.0, &identity(n), -1.0);
    d2c_delta(&e, ss, method)
}

/// [`d2c`] of the discrete model (I + E, B, C, D) given E = A_d − I directly (the δ form), so that
/// a fast-sampled model keeps the digits that A_d − I would lose. `ss.a` is ignored.
fn d2c_delta(
    e: &Mat<f64>,
    ss: &StateSpace,
    method: Discretization,
) -> Result<StateSpace, LtiError> {
    let dt_s = ss.dt_s.ok_or(LtiError::NotDiscrete)?;
    check_dt(dt_s)?;
    let (n, m) = (ss.n_states(), ss.n_inputs());
    let eye = identity(n);
    match method {
        Discretization::Zoh => {
            // balancing (exact power-of-two similarity) keeps the logarithm's square roots few
            let mut eb = e.clone();
            let scale = balance(&mut eb);
            let aug = Mat::from_fn(n + m, n + m, |i, j| match (i < n, j < n) {
                (true, true) => eb[(i, j)],
                (true, false) => ss.b[(i, j - n)] / scale[i],
                _ => 0.0,
            });
            let l = log1pm(&aug)?;
            Ok(StateSpace {
                a: Mat::from_fn(n, n, |i, j| l[(i, j)] * scale[i] / scale[j] / dt_s),
                b: Mat::from_fn(n, m, |i, j| l[(i, n + j)] * scale[i] / dt_s),
                c: ss.c.clone(),
                d: ss.d.clone(),
                dt_s: None,
            })
        }
        Discretization::Tustin => {
            let alpha = dt_s / 2.0;
            let two_plus_e = lin(&eye, 2.0, e, 1.0);
            let eig = two_plus_e.eigenvalues().unwrap_or_default();
            if eig.iter().any(|z| z.norm() < 1e-12) {
                return Err(LtiError::NoRealLogarithm {
                    pole_re: -1.0,
                    pole_im: 0.0,
                });
            }
            // M = 2(2I + E)⁻¹; I − M = E(2I + E)⁻¹ = (2I + E)⁻¹E
            let m_mat = scaled(&inverse(&two_plus_e), 2.0);
            let a = scaled(&solve(&two_plus_e, e), 1.0 / alpha);
            let b = scaled(&(&m_mat * &ss.b), 1.0 / dt_s);
            let c = &ss.c * &m_mat;
            let d = if n == 0 {
                ss.d.clone()
            } else {
                lin(&ss.d, 1.0, &(&c * &ss.b), -0.5)
            };
            Ok(StateSpace {
                a,
                b,
                c,
                d,
                dt_s: None,
            })
        }
    }
}

/// [`c2d`] for a transfer function (through its controllable canonical realisation).
pub fn c2d_tf(tf: &TransferFunction, dt_s: f64, method: Discretization) -> TransferFunction {
    if tf.is_discrete() {
        return tf.clone();
    }
    let ssd = c2d(&tf2ss(tf), dt_s, method);
    let mut out = ss2tf(&ssd, 0, 0);
    out.dt_s = ssd.dt_s;
    out
}

/// [`d2c`] for a transfer function (through the controllable canonical realisation in w = z − 1).
pub fn d2c_tf(tf: &TransferFunction, method: Discretization) -> Result<TransferFunction, LtiError> {
    if !tf.is_discrete() {
        return Err(LtiError::NotDiscrete);
    }
    // realise in the δ variable w = z − 1: the companion matrix of den(w + 1) is E = A_d − I
    // exactly, so the slow poles near z = 1 keep the digits that the coefficients carry
    let monic = tf.monic();
    let delta = TransferFunction {
        num: taylor_shift(&monic.num, 1.0),
        den: taylor_shift(&monic.den, 1.0),
        dt_s: tf.dt_s,
    };
    let ss_delta = tf2ss(&delta);
    let ssc = d2c_delta(&ss_delta.a, &ss_delta, method)?;
    Ok(ss2tf(&ssc, 0, 0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tf_close(a: &TransferFunction, b: &TransferFunction, rel: f64) {
        let (a, b) = (a.monic(), b.monic());
        assert_eq!(a.num.len(), b.num.len(), "num {:?} vs {:?}", a.num, b.num);
        assert_eq!(a.den.len(), b.den.len(), "den {:?} vs {:?}", a.den, b.den);
        for (x, y) in a.num.iter().zip(&b.num).chain(a.den.iter().zip(&b.den)) {
            assert!(
                (x - y).abs() <= rel * y.abs().max(1e-300),
                "{x} vs {y}: {a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn expm_of_a_rotation_generator_is_a_rotation() {
        let t = 2.5_f64;
        let a = Mat::from_fn(2, 2, |i, j| [[0.0, -t], [t, 0.0]][i][j]);
        let e = expm(&a);
        assert!((e[(0, 0)] - t.cos()).abs() < 1e-15);
        assert!((e[(1, 0)] - t.sin()).abs() < 1e-15);
    }

    #[test]
    fn zoh_of_first_order_lag_matches_analytic_result() {
        // a/(s + a) with ZOH: (1 − e^{−a dt}) / (z − e^{−a dt})  (Franklin, Powell & Workman, Table 4.1)
        let (a, dt) = (3.0_f64, 0.1);
        let tf = TransferFunction::new(vec![a], vec![1.0, a]);
        let p = (-a * dt).exp();
        tf_close(
            &c2d_tf(&tf, dt, Discretization::Zoh),
            &TransferFunction::discrete(vec![1.0 - p], vec![1.0, -p], dt),
            1e-14,
        );
    }

    #[test]
    fn zoh_of_double_integrator_matches_analytic_result() {
        // 1/s² with ZOH: dt²(z + 1) / (2 (z − 1)²)  (Franklin, Powell & Workman, Table 4.1)
        let dt = 0.05;
        let tf = TransferFunction::new(vec![1.0], vec![1.0, 0.0, 0.0]);
        let h = 0.5 * dt * dt;
        tf_close(
            &c2d_tf(&tf, dt, Discretization::Zoh),
            &TransferFunction::discrete(vec![h, h], vec![1.0, -2.0, 1.0], dt),
            1e-13,
        );
        // and back: the double pole at z = 1 is defective, which the logarithm must survive
        let back = d2c_tf(&c2d_tf(&tf, dt, Discretization::Zoh), Discretization::Zoh).unwrap();
        let back = back.monic();
        assert_eq!(back.num.len(), 1, "{back:?}");
        assert!((back.num[0] - 1.0).abs() < 1e-9);
        assert!(
            back.den[1].abs() < 1e-9 && back.den[2].abs() < 1e-9,
            "{back:?}"
        );
    }

    #[test]
    fn tustin_of_first_order_lag_matches_bilinear_substitution() {
        // 1/(s + 1), s = (2/dt)(z−1)/(z+1): (z + 1)·dt / ((2 + dt) z + (dt − 2))
        let dt = 0.2;
        let tf = TransferFunction::new(vec![1.0], vec![1.0, 1.0]);
        tf_close(
            &c2d_tf(&tf, dt, Discretization::Tustin),
            &TransferFunction::discrete(vec![dt, dt], vec![2.0 + dt, dt - 2.0], dt),
            1e-14,
        );
        let back = d2c_tf(
            &c2d_tf(&tf, dt, Discretization::Tustin),
            Discretization::Tustin,
        )
        .unwrap();
        tf_close(&back, &tf, 1e-13);
    }

    #[test]
    fn d2c_rejects_a_pole_on_the_negative_real_axis_and_continuous_input() {
        let tf = TransferFunction::discrete(vec![1.0], vec![1.0, 0.5], 0.1); // pole z = −0.5
        assert!(matches!(
            d2c_tf(&tf, Discretization::Zoh),
            Err(LtiError::NoRealLogarithm { .. })
        ));
        let c = TransferFunction::new(vec![1.0], vec![1.0, 1.0]);
        assert!(matches!(
            d2c_tf(&c, Discretization::Zoh),
            Err(LtiError::NotDiscrete)
        ));
    }
}
