//! A linear state-space model whose matrix entries are affine in the parameters:
//! `ẋ = A(θ) x + B(θ) u`, `y = C(θ) x + D(θ) u`.
//!
//! On uniformly sampled records without input skew it is simulated by exact discretisation for
//! the declared input hold (Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, 3rd
//! ed., §6.3.2): with `M = [[A, B, 0], [0, 0, I/h], [0, 0, 0]]`, `e^{Mh} = [[Φ, Γ₁, Γ₂], …]`, and
//! - zero-order hold: `x_{k+1} = Φ x_k + Γ₁ u_k`,
//! - linear interpolation: `x_{k+1} = Φ x_k + Γ₁ u_k + Γ₂ (u_{k+1} − u_k)`;
//!
//! otherwise by the core's Runge–Kutta integrator.

use faer::Mat;

use super::integrate::{check_states, simulate_states};
use super::model::{Discrete, Model, Signature, SimError, StateModel};
use super::record::{InputHold, Run};
use super::EstimateError;
use crate::lti::expm;

/// One matrix entry: `constant + Σ coefficient · θ[index]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Entry {
    /// Constant part.
    pub constant: f64,
    /// `(parameter index, coefficient)` terms.
    pub terms: Vec<(usize, f64)>,
}

impl Entry {
    /// A constant entry.
    pub fn constant(value: f64) -> Entry {
        Entry {
            constant: value,
            terms: Vec::new(),
        }
    }

    /// The entry equal to parameter `index`.
    pub fn param(index: usize) -> Entry {
        Entry {
            constant: 0.0,
            terms: vec![(index, 1.0)],
        }
    }

    /// Value for θ.
    pub fn value(&self, theta: &[f64]) -> f64 {
        self.constant + self.terms.iter().map(|(i, c)| c * theta[*i]).sum::<f64>()
    }
}

/// A linear state-space model with parameterised entries (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearModel {
    signature: Signature,
    a: Vec<Vec<Entry>>,
    b: Vec<Vec<Entry>>,
    c: Vec<Vec<Entry>>,
    d: Vec<Vec<Entry>>,
}

/// Numeric matrices at one θ, row-major.
struct Numeric {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    d: Vec<f64>,
}

impl LinearModel {
    /// A model with the given names and entries (`a` n×n, `b` n×m, `c` p×n, `d` p×m; rows of
    /// entries).
    pub fn new(
        signature: Signature,
        a: Vec<Vec<Entry>>,
        b: Vec<Vec<Entry>>,
        c: Vec<Vec<Entry>>,
        d: Vec<Vec<Entry>>,
    ) -> Result<LinearModel, EstimateError> {
        let (n, m, p) = (
            signature.states.len(),
            signature.inputs.len(),
            signature.outputs.len(),
        );
        for (name, mat, rows, cols) in [
            ("A", &a, n, n),
            ("B", &b, n, m),
            ("C", &c, p, n),
            ("D", &d, p, m),
        ] {
            if mat.len() != rows || mat.iter().any(|r| r.len() != cols) {
                return Err(EstimateError::Invalid(format!(
                    "{name} must be {rows}×{cols}"
                )));
            }
            let np = signature.parameters.len();
            if mat
                .iter()
                .flatten()
                .flat_map(|e| &e.terms)
                .any(|(i, _)| *i >= np)
            {
                return Err(EstimateError::Invalid(format!(
                    "{name} refers to a parameter beyond the {np} named"
                )));
            }
        }
        Ok(LinearModel {
            signature,
            a,
            b,
            c,
            d,
        })
    }

    /// A, B, C, D at θ as faer matrices.
    pub fn matrices(&self, theta: &[f64]) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
        let f = |m: &Vec<Vec<Entry>>, cols: usize| {
            Mat::from_fn(m.len(), cols, |i, j| m[i][j].value(theta))
        };
        let (n, nu) = (self.signature.states.len(), self.signature.inputs.len());
        (f(&self.a, n), f(&self.b, nu), f(&self.c, n), f(&self.d, nu))
    }

    fn numeric(&self, theta: &[f64]) -> Numeric {
        let f = |m: &Vec<Vec<Entry>>| m.iter().flatten().map(|e| e.value(theta)).collect();
        Numeric {
            a: f(&self.a),
            b: f(&self.b),
            c: f(&self.c),
            d: f(&self.d),
        }
    }

    /// Φ, Γ₁, Γ₂ over `h` for the hold (module doc).
    fn transition(&self, num: &Numeric, h: f64, hold: InputHold) -> Discrete {
        let (n, m) = (self.signature.states.len(), self.signature.inputs.len());
        let size = n + 2 * m;
        let mut big = Mat::<f64>::zeros(size, size);
        for i in 0..n {
            for j in 0..n {
                big[(i, j)] = num.a[i * n + j] * h;
            }
            for j in 0..m {
                big[(i, n + j)] = num.b[i * m + j] * h;
            }
        }
        for j in 0..m {
            big[(n + j, n + m + j)] = 1.0;
        }
        let e = expm(&big);
        let linear = hold == InputHold::Linear;
        Discrete {
            phi: (0..n * n).map(|k| e[(k / n, k % n)]).collect(),
            gamma1: (0..n * m).map(|k| e[(k / m, n + k % m)]).collect(),
            gamma2: (0..n * m)
                .map(|k| {
                    if linear {
                        e[(k / m, n + m + k % m)]
                    } else {
                        0.0
                    }
                })
                .collect(),
        }
    }

    /// Exact discretisation on a uniform grid (module doc); `None` when the run is not uniform or
    /// has skewed inputs.
    #[allow(clippy::needless_range_loop)] // row-major matrix-vector products read best indexed
    fn simulate_exact(
        &self,
        theta: &[f64],
        x0: &[f64],
        run: &Run<'_>,
    ) -> Option<Result<Vec<Vec<f64>>, SimError>> {
        let u = run.input.aligned_samples()?;
        let t = run.time_s;
        let len = t.len();
        let h = (t[len - 1] - t[0]) / (len - 1) as f64;
        if t.windows(2).any(|w| ((w[1] - w[0]) - h).abs() > 1e-6 * h) {
            return None;
        }
        let (n, m, p) = (
            self.signature.states.len(),
            self.signature.inputs.len(),
            self.signature.outputs.len(),
        );
        let num = self.numeric(theta);
        let Discrete {
            phi,
            gamma1: g1,
            gamma2: g2,
        } = self.transition(&num, h, run.input.hold());
        let linear = run.input.hold() == InputHold::Linear;
        let mut x = x0.to_vec();
        let mut next = vec![0.0; n];
        let mut y = vec![vec![0.0; len]; p];
        for k in 0..len {
            for o in 0..p {
                let mut v = 0.0;
                for i in 0..n {
                    v += num.c[o * n + i] * x[i];
                }
                for j in 0..m {
                    v += num.d[o * m + j] * u[j][k];
                }
                y[o][k] = v;
            }
            if k + 1 == len {
                break;
            }
            for i in 0..n {
                let mut v = 0.0;
                for l in 0..n {
                    v += phi[i * n + l] * x[l];
                }
                for j in 0..m {
                    v += g1[i * m + j] * u[j][k];
                    if linear {
                        v += g2[i * m + j] * (u[j][k + 1] - u[j][k]);
                    }
                }
                next[i] = v;
            }
            if let Err(e) = check_states(&next, &self.signature.states, t[k + 1] - t[0]) {
                return Some(Err(e));
            }
            x.copy_from_slice(&next);
        }
        Some(Ok(y))
    }
}

/// One row of `A x + B u` (or `C x + D u`): `state_row · x + input_row · u`, the entries evaluated at `theta`.
fn row_value(state_row: &[Entry], input_row: &[Entry], theta: &[f64], x: &[f64], u: &[f64]) -> f64 {
    state_row
        .iter()
        .zip(x)
        .map(|(e, v)| e.value(theta) * v)
        .sum::<f64>()
        + input_row
            .iter()
            .zip(u)
            .map(|(e, v)| e.value(theta) * v)
            .sum::<f64>()
}

impl StateModel for LinearModel {
    fn signature(&self) -> &Signature {
        &self.signature
    }

    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]) {
        for (i, d) in dx.iter_mut().enumerate() {
            *d = row_value(&self.a[i], &self.b[i], theta, x, u);
        }
    }

    fn discrete(&self, theta: &[f64], dt_s: f64, hold: InputHold) -> Option<Discrete> {
        Some(self.transition(&self.numeric(theta), dt_s, hold))
    }

    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]) {
        for (o, yo) in y.iter_mut().enumerate() {
            *yo = row_value(&self.c[o], &self.d[o], theta, x, u);
        }
    }
}

impl Model for LinearModel {
    fn signature(&self) -> &Signature {
        &self.signature
    }

    fn simulate(
        &self,
        theta: &[f64],
        x0: &[f64],
        run: &Run<'_>,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        match self.simulate_exact(theta, x0, run) {
            Some(result) => result,
            None => simulate_states(self, theta, x0, run),
        }
    }

    fn state_model(&self) -> Option<&dyn StateModel> {
        Some(self)
    }
}
