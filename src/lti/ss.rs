//! State space models (MIMO) and the conversions to and from transfer functions.

use faer::Mat;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::poly::{poly_add, strip_leading};
use super::tf::TransferFunction;
use super::LtiError;
use crate::signal::sum_sq;

/// `ẋ = A x + B u, y = C x + D u` (continuous) or `x[k+1] = A x[k] + B u[k]` (discrete).
///
/// Serialises as row lists `{"a": [[..]], "b": .., "c": .., "d": .., "dt_s": ..}`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(into = "StateSpaceRows", try_from = "StateSpaceRows")]
pub struct StateSpace {
    /// State matrix, n×n.
    pub a: Mat<f64>,
    /// Input matrix, n×m.
    pub b: Mat<f64>,
    /// Output matrix, p×n.
    pub c: Mat<f64>,
    /// Feedthrough matrix, p×m.
    pub d: Mat<f64>,
    /// `None`: continuous time; `Some(dt)`: discrete time with sample period dt seconds.
    pub dt_s: Option<f64>,
}

/// A matrix as a list of rows.
pub type Rows = Vec<Vec<f64>>;

/// Row-list form of a [`StateSpace`], used for serialisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateSpaceRows {
    /// Rows of A.
    pub a: Vec<Vec<f64>>,
    /// Rows of B.
    pub b: Vec<Vec<f64>>,
    /// Rows of C.
    pub c: Vec<Vec<f64>>,
    /// Rows of D (may be empty for D = 0).
    pub d: Vec<Vec<f64>>,
    /// Sample period of a discrete model.
    #[serde(default)]
    pub dt_s: Option<f64>,
}

impl From<StateSpace> for StateSpaceRows {
    fn from(ss: StateSpace) -> Self {
        let (a, b, c, d) = ss.to_rows();
        Self {
            a,
            b,
            c,
            d,
            dt_s: ss.dt_s,
        }
    }
}

impl TryFrom<StateSpaceRows> for StateSpace {
    type Error = LtiError;
    fn try_from(r: StateSpaceRows) -> Result<Self, LtiError> {
        let mut ss = StateSpace::from_rows(&r.a, &r.b, &r.c, &r.d)?;
        ss.dt_s = r.dt_s;
        Ok(ss)
    }
}

/// Matrix from rows, checking that they are all `ncols` long.
fn mat_from_rows(
    name: &'static str,
    rows: &[Vec<f64>],
    nrows: usize,
    ncols: usize,
) -> Result<Mat<f64>, LtiError> {
    if rows.len() != nrows || rows.iter().any(|r| r.len() != ncols) {
        return Err(LtiError::Dimension {
            matrix: name,
            expected_rows: nrows,
            expected_cols: ncols,
            got: format!(
                "{} rows of lengths {:?}",
                rows.len(),
                rows.iter().map(Vec::len).collect::<Vec<_>>()
            ),
        });
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(LtiError::NonFinite { what: name });
    }
    Ok(Mat::from_fn(nrows, ncols, |i, j| rows[i][j]))
}

/// Rows of a matrix.
pub fn mat_to_rows(m: &Mat<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

impl StateSpace {
    /// Continuous model from row lists; `d` may be empty for D = 0. Checks all dimensions.
    pub fn from_rows(
        a: &[Vec<f64>],
        b: &[Vec<f64>],
        c: &[Vec<f64>],
        d: &[Vec<f64>],
    ) -> Result<Self, LtiError> {
        let n = a.len();
        let m = b.first().map_or(0, Vec::len);
        let p = c.len();
        let a = mat_from_rows("A", a, n, n)?;
        let b = mat_from_rows("B", b, n, m)?;
        let c = mat_from_rows("C", c, p, n)?;
        let d = if d.is_empty() {
            Mat::zeros(p, m)
        } else {
            mat_from_rows("D", d, p, m)?
        };
        Ok(Self {
            a,
            b,
            c,
            d,
            dt_s: None,
        })
    }

    /// Continuous model from matrices; checks that the dimensions agree.
    pub fn new(a: Mat<f64>, b: Mat<f64>, c: Mat<f64>, d: Mat<f64>) -> Result<Self, LtiError> {
        let (n, m, p) = (a.nrows(), b.ncols(), c.nrows());
        let check = |name, mat: &Mat<f64>, r: usize, cl: usize| {
            if mat.nrows() == r && mat.ncols() == cl {
                Ok(())
            } else {
                Err(LtiError::Dimension {
                    matrix: name,
                    expected_rows: r,
                    expected_cols: cl,
                    got: format!("{}x{}", mat.nrows(), mat.ncols()),
                })
            }
        };
        check("A", &a, n, n)?;
        check("B", &b, n, m)?;
        check("C", &c, p, n)?;
        check("D", &d, p, m)?;
        Ok(Self {
            a,
            b,
            c,
            d,
            dt_s: None,
        })
    }

    /// Number of states.
    pub fn n_states(&self) -> usize {
        self.a.nrows()
    }

    /// Number of inputs.
    pub fn n_inputs(&self) -> usize {
        self.b.ncols()
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.c.nrows()
    }

    /// True for a discrete-time model.
    pub fn is_discrete(&self) -> bool {
        self.dt_s.is_some()
    }

    /// (A, B, C, D) as row lists.
    pub fn to_rows(&self) -> (Rows, Rows, Rows, Rows) {
        (
            mat_to_rows(&self.a),
            mat_to_rows(&self.b),
            mat_to_rows(&self.c),
            mat_to_rows(&self.d),
        )
    }

    /// The model restricted to the listed states, inputs and outputs (in the given order), e.g. the
    /// decoupled longitudinal 4-state model out of JSBSim's full linearisation. Indices out of range
    /// are skipped; use [`StateSpace::try_submodel`] to have them reported.
    pub fn submodel(&self, states: &[usize], inputs: &[usize], outputs: &[usize]) -> Self {
        let keep = |idx: &[usize], n: usize| -> Vec<usize> {
            idx.iter().copied().filter(|&i| i < n).collect()
        };
        let s = keep(states, self.n_states());
        let u = keep(inputs, self.n_inputs());
        let y = keep(outputs, self.n_outputs());
        Self {
            a: Mat::from_fn(s.len(), s.len(), |i, j| self.a[(s[i], s[j])]),
            b: Mat::from_fn(s.len(), u.len(), |i, j| self.b[(s[i], u[j])]),
            c: Mat::from_fn(y.len(), s.len(), |i, j| self.c[(y[i], s[j])]),
            d: Mat::from_fn(y.len(), u.len(), |i, j| self.d[(y[i], u[j])]),
            dt_s: self.dt_s,
        }
    }

    /// Like [`StateSpace::submodel`] but an index out of range is an error naming it.
    pub fn try_submodel(
        &self,
        states: &[usize],
        inputs: &[usize],
        outputs: &[usize],
    ) -> Result<Self, LtiError> {
        for (what, idx, n) in [
            ("state", states, self.n_states()),
            ("input", inputs, self.n_inputs()),
            ("output", outputs, self.n_outputs()),
        ] {
            if let Some(&bad) = idx.iter().find(|&&i| i >= n) {
                return Err(LtiError::IndexOutOfRange {
                    what,
                    index: bad,
                    count: n,
                });
            }
        }
        Ok(self.submodel(states, inputs, outputs))
    }

    /// Eigenvalues of A (conjugate pairs adjacent).
    pub fn poles(&self) -> Vec<Complex64> {
        if self.n_states() == 0 {
            return Vec::new();
        }
        self.a.eigenvalues().unwrap_or_default()
    }
}

/// Characteristic polynomial det(sI − A), highest power first (monic, length n+1).
///
/// A is reduced to upper Hessenberg form H by Householder similarities (Golub & Van Loan, *Matrix
/// Computations* 4th ed., Alg. 7.4.2); det(sI − H) then follows from the recurrence on its leading
/// principal minors, expanding along the last column (Wilkinson, *The Algebraic Eigenvalue Problem*,
/// §7.11): p_k = (s − h_kk) p_{k−1} − Σ_{i<k} h_ik (∏_{j=i+1..k} h_{j,j−1}) p_{i−1}.
pub fn charpoly(a: &Mat<f64>) -> Vec<f64> {
    let h = hessenberg(a);
    let n = h.nrows();
    // p[k] holds the coefficients of p_k, highest power first, length k+1
    let mut p: Vec<Vec<f64>> = vec![vec![1.0]];
    for k in 0..n {
        // (s − h_kk) p_{k}
        let prev = &p[k];
        let mut next = vec![0.0; k + 2];
        for (i, &c) in prev.iter().enumerate() {
            next[i] += c;
            next[i + 1] -= h[(k, k)] * c;
        }
        let mut prod = 1.0;
        for i in (0..k).rev() {
            prod *= h[(i + 1, i)];
            let f = h[(i, k)] * prod;
            if f != 0.0 {
                // subtract f · p_i (degree i), aligned at the constant term
                let pi = &p[i];
                let off = next.len() - pi.len();
                for (j, &c) in pi.iter().enumerate() {
                    next[off + j] -= f * c;
                }
            }
        }
        p.push(next);
    }
    p.pop().unwrap_or_else(|| vec![1.0])
}

/// Upper Hessenberg form of `a` by Householder reflections (a similarity, so eigenvalues are kept).
fn hessenberg(a: &Mat<f64>) -> Mat<f64> {
    let n = a.nrows();
    let mut h = a.clone();
    for k in 0..n.saturating_sub(2) {
        let alpha_sq: f64 = (k + 1..n).map(|i| h[(i, k)] * h[(i, k)]).sum();
        let norm = alpha_sq.sqrt();
        if norm == 0.0 {
            continue;
        }
        let x0 = h[(k + 1, k)];
        let alpha = if x0 >= 0.0 { -norm } else { norm };
        // v = x − alpha e1, reflect with P = I − 2 v vᵀ / (vᵀ v)
        let mut v: Vec<f64> = (k + 1..n).map(|i| h[(i, k)]).collect();
        v[0] -= alpha;
        let vtv = sum_sq(&v);
        if vtv == 0.0 {
            continue;
        }
        // H ← P H
        for j in 0..n {
            let dot: f64 = v
                .iter()
                .enumerate()
                .map(|(i, vi)| vi * h[(k + 1 + i, j)])
                .sum();
            let f = 2.0 * dot / vtv;
            for (i, vi) in v.iter().enumerate() {
                h[(k + 1 + i, j)] -= f * vi;
            }
        }
        // H ← H P
        for i in 0..n {
            let dot: f64 = v
                .iter()
                .enumerate()
                .map(|(j, vj)| h[(i, k + 1 + j)] * vj)
                .sum();
            let f = 2.0 * dot / vtv;
            for (j, vj) in v.iter().enumerate() {
                h[(i, k + 1 + j)] -= f * vj;
            }
        }
        for i in k + 2..n {
            h[(i, k)] = 0.0;
        }
    }
    h
}

/// Relative size below which a leading numerator coefficient of [`ss2tf`] is round-off from the
/// cancellation det(sI − A + bc) − det(sI − A).
const SS2TF_CANCEL_REL_TOL: f64 = 1e-11;

/// Transfer function from input `input` to output `output`.
///
/// den = det(sI − A); num = det(sI − A + b c) − det(sI − A) + d · det(sI − A), since
/// det(sI − A + b c) = det(sI − A)(1 + c (sI − A)⁻¹ b) (matrix determinant lemma). Leading numerator
/// terms at round-off level of that difference are set to zero and stripped, so the relative degree
/// comes out right. An index out of range gives the zero transfer function over det(sI − A).
pub fn ss2tf(ss: &StateSpace, input: usize, output: usize) -> TransferFunction {
    let n = ss.n_states();
    let den = charpoly(&ss.a);
    if input >= ss.n_inputs() || output >= ss.n_outputs() {
        return TransferFunction {
            num: vec![0.0],
            den,
            dt_s: ss.dt_s,
        };
    }
    let d = ss.d[(output, input)];
    let a_bc = Mat::from_fn(n, n, |i, j| {
        ss.a[(i, j)] - ss.b[(i, input)] * ss.c[(output, j)]
    });
    let p2 = charpoly(&a_bc);
    let scaled_den: Vec<f64> = den.iter().map(|c| d * c).collect();
    let diff: Vec<f64> = p2.iter().zip(&den).map(|(x, y)| x - y).collect();
    let mut num = poly_add(&diff, &scaled_den);
    for k in 0..num.len() {
        let noise = SS2TF_CANCEL_REL_TOL * p2[k].abs().max(den[k].abs());
        if d == 0.0 && num[k].abs() <= noise {
            num[k] = 0.0;
        } else {
            break;
        }
    }
    TransferFunction {
        num: strip_leading(&num, 0.0),
        den,
        dt_s: ss.dt_s,
    }
}

/// Controllable canonical realisation of a proper transfer function (as `scipy.signal.tf2ss`):
/// A has −a₁…−aₙ in its first row and ones on the subdiagonal, B = e₁, C = b − d·a, D = d, after
/// dividing through by a₀. Round-off-sized leading numerator terms are dropped first; an improper
/// transfer function keeps only its proper part (check with [`TransferFunction::is_proper`]).
pub fn tf2ss(tf: &TransferFunction) -> StateSpace {
    let m = tf.monic();
    let den = m.den;
    let n = den.len().saturating_sub(1);
    let mut num = m.num;
    if num.len() > n + 1 {
        num = num[num.len() - (n + 1)..].to_vec();
    }
    let mut padded = vec![0.0; n + 1 - num.len()];
    padded.extend_from_slice(&num);
    let d = padded[0];
    let a = Mat::from_fn(n, n, |i, j| {
        if i == 0 {
            -den[j + 1]
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let b = Mat::from_fn(n, 1, |i, _| if i == 0 { 1.0 } else { 0.0 });
    let c = Mat::from_fn(1, n, |_, j| padded[j + 1] - d * den[j + 1]);
    let d = Mat::from_fn(1, 1, |_, _| d);
    StateSpace {
        a,
        b,
        c,
        d,
        dt_s: tf.dt_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charpoly_of_a_dense_matrix_matches_hand_expansion() {
        // A = [[1,2,0],[3,4,5],[0,1,-2]]: det(sI−A) = s³ − 3s² − 17s + 1 (hand expansion)
        let a = Mat::from_fn(3, 3, |i, j| {
            [[1.0, 2.0, 0.0], [3.0, 4.0, 5.0], [0.0, 1.0, -2.0]][i][j]
        });
        let p = charpoly(&a);
        let expected = [1.0, -3.0, -17.0, 1.0];
        for (x, e) in p.iter().zip(expected) {
            assert!((x - e).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn ss2tf_of_a_mass_spring_damper_is_one_over_ms2_cs_k() {
        // m = 2, c = 3, k = 5: x = [pos, vel]; position output, force input
        let ss = StateSpace::from_rows(
            &[vec![0.0, 1.0], vec![-2.5, -1.5]],
            &[vec![0.0], vec![0.5]],
            &[vec![1.0, 0.0]],
            &[],
        )
        .unwrap();
        let tf = ss2tf(&ss, 0, 0).monic();
        assert_eq!(tf.num.len(), 1, "relative degree 2 kept: {:?}", tf.num);
        assert!((tf.num[0] - 0.5).abs() < 1e-15);
        for (x, e) in tf.den.iter().zip([1.0, 1.5, 2.5]) {
            assert!((x - e).abs() < 1e-15);
        }
    }

    #[test]
    fn tf2ss_then_ss2tf_returns_the_paper_theta_transfer_function() {
        let tf = TransferFunction::new(
            vec![-24.7885, -18.2186, -0.4659],
            vec![1.0, 2.0072, 32.5269, 0.8638, 0.0179],
        );
        let back = ss2tf(&tf2ss(&tf), 0, 0).monic();
        assert_eq!(back.num.len(), 3);
        for (x, e) in back
            .num
            .iter()
            .zip(&tf.num)
            .chain(back.den.iter().zip(&tf.den))
        {
            assert!((x - e).abs() <= 1e-13 * e.abs().max(1.0), "{x} vs {e}");
        }
    }

    #[test]
    fn feedthrough_survives_tf2ss_and_back() {
        // (2s + 3)/(s + 1) = 2 + 1/(s + 1)
        let tf = TransferFunction::new(vec![2.0, 3.0], vec![1.0, 1.0]);
        let ss = tf2ss(&tf);
        assert_eq!(ss.d[(0, 0)], 2.0);
        assert_eq!(ss.c[(0, 0)], 1.0);
        let back = ss2tf(&ss, 0, 0);
        assert_eq!(back.num, vec![2.0, 3.0]);
    }

    #[test]
    fn bad_dimensions_are_reported_with_the_matrix_name() {
        let err = StateSpace::from_rows(
            &[vec![0.0, 1.0], vec![-1.0]],
            &[vec![0.0], vec![1.0]],
            &[vec![1.0, 0.0]],
            &[],
        )
        .unwrap_err();
        assert!(err.to_string().contains('A'), "{err}");
        let ok = StateSpace::from_rows(&[vec![-1.0]], &[vec![1.0]], &[vec![1.0]], &[]).unwrap();
        assert!(ok.try_submodel(&[0], &[1], &[0]).is_err());
    }

    #[test]
    fn submodel_picks_states_inputs_outputs_in_order_and_serde_round_trips() {
        let ss = StateSpace::from_rows(
            &[
                vec![1.0, 2.0, 3.0],
                vec![4.0, 5.0, 6.0],
                vec![7.0, 8.0, 9.0],
            ],
            &[vec![1.0, 0.1], vec![2.0, 0.2], vec![3.0, 0.3]],
            &[vec![1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0]],
            &[],
        )
        .unwrap();
        let sub = ss.submodel(&[2, 0], &[1], &[1]);
        assert_eq!(sub.to_rows().0, vec![vec![9.0, 7.0], vec![3.0, 1.0]]);
        assert_eq!(sub.to_rows().1, vec![vec![0.3], vec![0.1]]);
        assert_eq!(sub.to_rows().2, vec![vec![1.0, 0.0]]);
        let json = serde_json::to_string(&sub).unwrap();
        let back: StateSpace = serde_json::from_str(&json).unwrap();
        assert_eq!(back.to_rows(), sub.to_rows());
    }
}
