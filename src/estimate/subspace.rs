//! Subspace identification of a linear state-space model from input–output records: past-output
//! MOESP (Verhaegen, *Automatica* 30(1), 1994; Verhaegen & Verdult, *Filtering and System
//! Identification*, 2007, §9.5–9.6; Katayama, *Subspace Methods for System Identification*, 2005,
//! §9.3), then the continuous-time model for the declared input hold.
//!
//! With `s` block rows, the stacked data matrix `[U_f; U_p; Y_p; Y_f]` (future inputs, past inputs
//! and outputs as instruments, future outputs; block Hankel, columns from every record) is
//! factored `L Qᵀ` (LQ, through the QR factorisation of its transpose). The block `L₃₂` — the part
//! of the future outputs explained by the past data once the future inputs are projected out — has
//! the column space of the extended observability matrix `Γ_s`; its SVD gives the order (the
//! largest gap in the singular values, unless given) and `Γ_s = U₁ S₁^{1/2}`. Then `C` is the first
//! block row of `Γ_s` and `A` solves the shift equation `Γ_s↑ A = Γ_s↓` by least squares. With `A`
//! and `C` known the outputs are linear in `B`, `D` and each record's initial state and output
//! offset, which one least-squares problem over all samples gives (Verhaegen & Verdult §9.2.4).
//! Every channel is scaled by its standard deviation first, so the result does not depend on units.
//!
//! Continuous time: `A = log(Φ)/h` (principal logarithm), and `B` from the discrete input matrix
//! for the hold the records were sampled under:
//! - zero-order hold: `Γ = Ψ₁ B`, `D = D_d`, with `Ψ₁ = ∫₀ʰ e^{Aτ} dτ`;
//! - linear interpolation: the discrete model of `x_{k+1} = Φ x_k + Γ₁ u_k + Γ₂ (u_{k+1} − u_k)`
//!   in the state `ξ_k = x_k − Γ₂ u_k` has input matrix `(Φ Ψ₂ + Ψ₁ − Ψ₂) B` and feedthrough
//!   `D + C Ψ₂ B`, with `Γ₁ = Ψ₁ B`, `Γ₂ = Ψ₂ B` (the blocks of `exp([[Ah, Bh, 0], [0, 0, I],
//!   [0, 0, 0]])`, Franklin, Powell & Workman §6.3.2); both are solved for `B` and `D`.
//!
//! When the caller names `n` outputs that are the states (e.g. α and q for a short period), the
//! model is returned in that basis (`x' = C_S x`), so `A` and `B` read as dimensional derivatives.

use std::time::Instant;

use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::Mat;

use super::record::{InputHold, Record};
use super::EstimateError;
use crate::ident::lstsq_qr;
use crate::ident::nrmse_fit;
use crate::lti::{expm, logm, modes, Mode, StateSpace};
use crate::signal::sum_sq;

/// Settings of [`subspace`].
#[derive(Clone, Debug)]
pub struct SubspaceOptions {
    /// Model order; `None`: the largest gap in the singular values up to `max_order`.
    pub order: Option<usize>,
    /// Largest order considered when the order is chosen from the singular values.
    pub max_order: usize,
    /// Block rows `s` of the Hankel matrices; `None`: enough to span 0.4 s of data and at least
    /// `max_order + 1`, at most 60.
    pub horizon: Option<usize>,
    /// How the inputs were reconstructed between samples when the records were made.
    pub hold: InputHold,
}

impl Default for SubspaceOptions {
    fn default() -> Self {
        SubspaceOptions {
            order: None,
            max_order: 8,
            horizon: None,
            hold: InputHold::Linear,
        }
    }
}

/// One record's part of a subspace fit.
#[derive(Clone, Debug)]
pub struct SubspaceRecord {
    /// Record name.
    pub name: String,
    /// Model outputs at the record's samples, `[output][k]` (with the record's initial state and
    /// output offsets).
    pub predicted: Vec<Vec<f64>>,
    /// Fit percent per output.
    pub fit_percent: Vec<f64>,
}

/// The identified model (module doc).
#[derive(Clone, Debug)]
pub struct SubspaceModel {
    /// Model order n.
    pub order: usize,
    /// Block rows used.
    pub horizon: usize,
    /// Singular values of `L₃₂` (scaled data), largest first.
    pub singular_values: Vec<f64>,
    /// The discrete model at the records' sample interval (in the basis of `continuous`).
    pub discrete: StateSpace,
    /// The continuous-time model for the declared hold.
    pub continuous: StateSpace,
    /// Names of the states when the model is in the basis of measured outputs.
    pub state_names: Option<Vec<String>>,
    /// Input names.
    pub inputs: Vec<String>,
    /// Output names.
    pub outputs: Vec<String>,
    /// Modes of the continuous model.
    pub modes: Vec<Mode>,
    /// Per record: the model's outputs and fit.
    pub records: Vec<SubspaceRecord>,
    /// Fit percent per output over all records together.
    pub fit_percent: Vec<f64>,
    /// The order was chosen from the singular values (not given).
    pub order_from_data: bool,
    /// The input hold the continuous model assumes.
    pub hold: InputHold,
    /// Wall time, s.
    pub wall_s: f64,
}

/// Identifies a linear model from `records` (inputs and outputs in the same order in each).
///
/// `input_names` and `output_names` name the channels; `basis`, when given, lists `order` outputs whose values are the
/// states, and the model is returned in that basis.
pub fn subspace(
    records: &[Record],
    input_names: &[String],
    output_names: &[String],
    basis: Option<&[usize]>,
    options: &SubspaceOptions,
) -> Result<SubspaceModel, EstimateError> {
    let start = Instant::now();
    let data = Prepared::new(records)?;
    let (m, p) = (data.m, data.p);
    let dt_s = data.dt_s;
    let shortest = records.iter().map(Record::len).min().unwrap_or(0);
    let s = match options.horizon {
        Some(s) => s,
        None => ((0.4 / dt_s).ceil() as usize)
            .max(options.max_order + 1)
            .min(60),
    };
    let order_cap = options.order.unwrap_or(options.max_order);
    if s <= order_cap || s < 2 {
        return Err(EstimateError::Invalid(format!(
            "horizon of {s} block rows is too short for order {order_cap}"
        )));
    }
    let columns: usize = records
        .iter()
        .map(|r| r.len().saturating_sub(2 * s - 1))
        .sum();
    if shortest < 2 * s || columns < 2 * s * (m + p) + records.len() {
        return Err(EstimateError::Invalid(format!(
            "the records are too short for a subspace fit with {s} block rows: {columns} Hankel \
             columns over {} records, at least {} needed",
            records.len(),
            2 * s * (m + p)
        )));
    }
    let l32 = data.projected_future_outputs(s);
    let svd = l32
        .thin_svd()
        .map_err(|_| EstimateError::Invalid("SVD of the data matrix did not converge".into()))?;
    let sv: Vec<f64> = (0..l32.nrows().min(l32.ncols()))
        .map(|i| svd.S().column_vector()[i])
        .collect();
    let n = match options.order {
        Some(n) => n,
        None => order_from_gap(&sv, options.max_order),
    };
    if n == 0 || n >= sv.len() {
        return Err(EstimateError::Invalid(format!(
            "order {n} is outside 1..{}",
            sv.len() - 1
        )));
    }
    // Γ_s = U₁ S₁^{1/2}; C its first block row, A from the shift equation
    let gamma = Mat::from_fn(s * p, n, |i, j| svd.U()[(i, j)] * sv[j].sqrt());
    let up = Mat::from_fn((s - 1) * p, n, |i, j| gamma[(i, j)]);
    let down = Mat::from_fn((s - 1) * p, n, |i, j| gamma[(i + p, j)]);
    let mut a = Mat::<f64>::zeros(n, n);
    for col in 0..n {
        let rhs: Vec<f64> = (0..(s - 1) * p).map(|i| down[(i, col)]).collect();
        let sol = lstsq_qr(&up, &rhs, "subspace shift equation")
            .map_err(|e| EstimateError::Invalid(e.to_string()))?;
        for (row, v) in sol.into_iter().enumerate() {
            a[(row, col)] = v;
        }
    }
    let c = Mat::from_fn(p, n, |i, j| gamma[(i, j)]);
    let fitted = data.input_matrices(&a, &c)?;
    // undo the channel scaling
    let b_d = Mat::from_fn(n, m, |i, j| fitted.b[(i, j)] / data.u_scale[j]);
    let c_d = Mat::from_fn(p, n, |i, j| c[(i, j)] * data.y_scale[i]);
    let d_d = Mat::from_fn(p, m, |i, j| {
        fitted.d[(i, j)] * data.y_scale[i] / data.u_scale[j]
    });
    let (mut cont, mut disc) = to_continuous(&a, &b_d, &c_d, &d_d, dt_s, options.hold)?;
    let state_names = match basis {
        Some(rows) if rows.len() == n => {
            let t = Mat::from_fn(n, n, |i, j| c_d[(rows[i], j)]);
            let smallest = t.singular_values().ok().and_then(|v| {
                let (hi, lo) = (v.first().copied()?, v.last().copied()?);
                Some(lo / hi)
            });
            if smallest.is_some_and(|r| r > 1e-8) {
                cont = similarity(&cont, &t);
                disc = similarity(&disc, &t);
                Some(rows.iter().map(|&r| output_names[r].clone()).collect())
            } else {
                None
            }
        }
        _ => None,
    };
    let poles = cont.a.eigenvalues().unwrap_or_default();
    let records_out: Vec<SubspaceRecord> = records
        .iter()
        .zip(&fitted.predicted)
        .enumerate()
        .map(|(r, (rec, pred))| {
            let predicted: Vec<Vec<f64>> = (0..p)
                .map(|o| {
                    pred[o]
                        .iter()
                        .map(|v| v * data.y_scale[o] + data.y_mean[r][o])
                        .collect()
                })
                .collect();
            let fit_percent = (0..p)
                .map(|o| nrmse_fit(&rec.outputs[o], &predicted[o]))
                .collect();
            SubspaceRecord {
                name: rec.name.clone(),
                predicted,
                fit_percent,
            }
        })
        .collect();
    let fit_percent = (0..p)
        .map(|o| {
            let z: Vec<f64> = records.iter().flat_map(|r| r.outputs[o].clone()).collect();
            let y: Vec<f64> = records_out
                .iter()
                .flat_map(|r| r.predicted[o].clone())
                .collect();
            nrmse_fit(&z, &y)
        })
        .collect();
    Ok(SubspaceModel {
        fit_percent,
        order_from_data: options.order.is_none(),
        hold: options.hold,
        order: n,
        horizon: s,
        singular_values: sv,
        discrete: disc,
        continuous: cont,
        state_names,
        inputs: input_names.to_vec(),
        outputs: output_names.to_vec(),
        modes: modes(&poles),
        records: records_out,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// The order at the largest drop (ratio) between consecutive singular values, 1..=max_order.
fn order_from_gap(sv: &[f64], max_order: usize) -> usize {
    // values at rounding level are no information: the order stops before them
    let floor = sv.first().copied().unwrap_or(0.0) * 1e-9;
    let top = max_order
        .min(sv.len().saturating_sub(1))
        .min(sv.iter().take_while(|v| **v > floor).count().max(1));
    (1..=top)
        .max_by(|&i, &j| {
            let gap = |k: usize| sv[k - 1] / sv[k].max(f64::MIN_POSITIVE);
            gap(i).total_cmp(&gap(j))
        })
        .unwrap_or(1)
}

/// Records scaled and centred: every channel divided by its standard deviation over all records,
/// each record's mean removed.
struct Prepared {
    m: usize,
    p: usize,
    dt_s: f64,
    u: Vec<Vec<Vec<f64>>>,
    y: Vec<Vec<Vec<f64>>>,
    u_scale: Vec<f64>,
    y_scale: Vec<f64>,
    y_mean: Vec<Vec<f64>>,
}

/// `B`, `D` and the per-record predictions of the scaled, centred outputs.
struct InputFit {
    b: Mat<f64>,
    d: Mat<f64>,
    predicted: Vec<Vec<Vec<f64>>>,
}

impl Prepared {
    fn new(records: &[Record]) -> Result<Prepared, EstimateError> {
        let first = records
            .first()
            .ok_or_else(|| EstimateError::Invalid("no record to fit".into()))?;
        let (m, p) = (first.inputs.len(), first.outputs.len());
        if m == 0 || p == 0 {
            return Err(EstimateError::Invalid(
                "a subspace fit needs at least one input and one output".into(),
            ));
        }
        let mut dt_s = None;
        for rec in records {
            let bad = |reason: String| EstimateError::Record {
                record: rec.name.clone(),
                reason,
            };
            if rec.inputs.len() != m || rec.outputs.len() != p {
                return Err(bad(
                    "its inputs and outputs differ from the first record's".into()
                ));
            }
            let t = &rec.time_s;
            if t.len() < 3 {
                return Err(bad(format!("{} samples are too few", t.len())));
            }
            let h = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
            if let Some(k) = t
                .windows(2)
                .position(|w| ((w[1] - w[0]) - h).abs() > 1e-3 * h)
            {
                return Err(bad(format!(
                    "not uniformly sampled (the interval at t = {:.3} s is {:.4} s, the mean {h:.4} s); \
                     a subspace fit needs one sample interval",
                    t[k],
                    t[k + 1] - t[k]
                )));
            }
            match dt_s {
                None => dt_s = Some(h),
                Some(d) if ((h - d) / d).abs() > 1e-3 => {
                    return Err(bad(format!(
                        "sampled every {h:.4} s, the first record every {d:.4} s"
                    )))
                }
                _ => {}
            }
            let channels = rec.inputs.iter().chain(&rec.outputs);
            if channels.clone().flatten().any(|v| !v.is_finite()) {
                return Err(bad("holds a NaN or infinite value".into()));
            }
        }
        let centred =
            |pick: &dyn Fn(&Record) -> &Vec<Vec<f64>>| -> (Vec<Vec<Vec<f64>>>, Vec<Vec<f64>>) {
                let means: Vec<Vec<f64>> = records
                    .iter()
                    .map(|r| {
                        pick(r)
                            .iter()
                            .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                            .collect()
                    })
                    .collect();
                let data = records
                    .iter()
                    .zip(&means)
                    .map(|(r, mu)| {
                        pick(r)
                            .iter()
                            .zip(mu)
                            .map(|(c, m)| c.iter().map(|v| v - m).collect())
                            .collect()
                    })
                    .collect();
                (data, means)
            };
        let (mut u, _) = centred(&|r| &r.inputs);
        let (mut y, y_mean) = centred(&|r| &r.outputs);
        let scale = |data: &mut Vec<Vec<Vec<f64>>>, channels: usize, what: &str| {
            (0..channels)
                .map(|j| {
                    let (sum, count) = data.iter().fold((0.0, 0usize), |(s, c), r| {
                        (s + sum_sq(&r[j]), c + r[j].len())
                    });
                    let sd = (sum / count as f64).sqrt();
                    if sd <= 1e-12 {
                        return Err(EstimateError::Invalid(format!(
                            "{what} {j} never moves in any record: nothing to identify from"
                        )));
                    }
                    for r in data.iter_mut() {
                        r[j].iter_mut().for_each(|v| *v /= sd);
                    }
                    Ok(sd)
                })
                .collect::<Result<Vec<f64>, EstimateError>>()
        };
        let u_scale = scale(&mut u, m, "input")?;
        let y_scale = scale(&mut y, p, "output")?;
        Ok(Prepared {
            m,
            p,
            dt_s: dt_s.unwrap_or(1.0),
            u,
            y,
            u_scale,
            y_scale,
            y_mean,
        })
    }

    /// `L₃₂` of the LQ factorisation of `[U_f; 1_r; U_p; Y_p; Y_f]` (module doc). The rows `1_r`
    /// (one per record: 1 on that record's columns) project out the constant each record's
    /// centring leaves as a forcing term (its mean state is not exactly the equilibrium of its
    /// mean input, and trim offsets are unknown); without them every record adds a spurious order.
    fn projected_future_outputs(&self, s: usize) -> Mat<f64> {
        let (m, p) = (self.m, self.p);
        let nr = self.u.len();
        let starts: Vec<(usize, usize)> = self
            .u
            .iter()
            .enumerate()
            .flat_map(|(r, ur)| (0..ur[0].len() + 1 - 2 * s).map(move |j| (r, j)))
            .collect();
        let (a, b, c) = (s * m + nr, s * (m + p), s * p);
        // the transpose of the data matrix: one row per Hankel column
        let ht = Mat::from_fn(starts.len(), a + b + c, |row, col| {
            let (r, j) = starts[row];
            let (u, y) = (&self.u[r], &self.y[r]);
            if col < s * m {
                u[col % m][j + s + col / m]
            } else if col < a {
                f64::from(u8::from(col - s * m == r))
            } else if col < a + s * m {
                let k = col - a;
                u[k % m][j + k / m]
            } else if col < a + b {
                let k = col - a - s * m;
                y[k % p][j + k / p]
            } else {
                let k = col - a - b;
                y[k % p][j + s + k / p]
            }
        });
        let r = ht.qr().thin_R().to_owned();
        // L = Rᵀ; L₃₂ = rows of Y_f, columns of the instruments
        Mat::from_fn(c, b, |i, j| r[(a + j, a + b + i)])
    }

    /// `B`, `D`, and per record the initial state and output offsets, by least squares with `A`,
    /// `C` fixed (module doc).
    fn input_matrices(&self, a: &Mat<f64>, c: &Mat<f64>) -> Result<InputFit, EstimateError> {
        let (n, m, p) = (a.nrows(), self.m, self.p);
        let nr = self.u.len();
        let cols = n * m + p * m + nr * (n + p);
        let rows: usize = self.y.iter().map(|r| r[0].len() * p).sum();
        let mut phi = Mat::<f64>::zeros(rows, cols);
        let mut target = Vec::with_capacity(rows);
        let mut row = 0;
        for (r, (u, y)) in self.u.iter().zip(&self.y).enumerate() {
            let len = u[0].len();
            // x[j] = state response to e_i through input j, columns i; ca = C A^k
            let mut x: Vec<Mat<f64>> = vec![Mat::zeros(n, n); m];
            let mut ca = c.clone();
            let x0_col = n * m + p * m + r * (n + p);
            for k in 0..len {
                for o in 0..p {
                    for j in 0..m {
                        let cx = c.row(o) * &x[j];
                        for i in 0..n {
                            phi[(row, j * n + i)] = cx[i];
                        }
                        phi[(row, n * m + o * m + j)] = u[j][k];
                    }
                    for i in 0..n {
                        phi[(row, x0_col + i)] = ca[(o, i)];
                    }
                    phi[(row, x0_col + n + o)] = 1.0;
                    target.push(y[o][k]);
                    row += 1;
                }
                for (j, xj) in x.iter_mut().enumerate() {
                    let mut next = a * &*xj;
                    for i in 0..n {
                        next[(i, i)] += u[j][k];
                    }
                    *xj = next;
                }
                ca = &ca * a;
            }
        }
        let theta = lstsq_qr(&phi, &target, "subspace input matrices")
            .map_err(|e| EstimateError::Invalid(e.to_string()))?;
        let b = Mat::from_fn(n, m, |i, j| theta[j * n + i]);
        let d = Mat::from_fn(p, m, |o, j| theta[n * m + o * m + j]);
        let prediction = &phi * Mat::from_fn(cols, 1, |i, _| theta[i]);
        let mut predicted = Vec::with_capacity(nr);
        let mut row = 0;
        for y in &self.y {
            let len = y[0].len();
            let mut out = vec![vec![0.0; len]; p];
            for k in 0..len {
                for o_out in out.iter_mut() {
                    o_out[k] = prediction[(row, 0)];
                    row += 1;
                }
            }
            predicted.push(out);
        }
        Ok(InputFit { b, d, predicted })
    }
}

/// `(continuous, discrete)` models from the identified discrete `(Φ, B_d, C, D_d)` (module doc).
fn to_continuous(
    phi: &Mat<f64>,
    b_d: &Mat<f64>,
    c: &Mat<f64>,
    d_d: &Mat<f64>,
    dt_s: f64,
    hold: InputHold,
) -> Result<(StateSpace, StateSpace), EstimateError> {
    let n = phi.nrows();
    let log = logm(phi).map_err(|e| {
        EstimateError::Invalid(format!(
            "the identified discrete model has no continuous-time counterpart: {e}"
        ))
    })?;
    let a = Mat::from_fn(n, n, |i, j| log[(i, j)] / dt_s);
    // exp([[A h, I h, 0], [0, 0, I], [0, 0, 0]]) = [[Φ, Ψ₁, Ψ₂], …]
    let big = Mat::from_fn(3 * n, 3 * n, |i, j| match (i / n, j / n) {
        (0, 0) => a[(i, j)] * dt_s,
        (0, 1) if i == j - n => dt_s,
        (1, 2) if i - n == j - 2 * n => 1.0,
        _ => 0.0,
    });
    let e = expm(&big);
    let psi1 = Mat::from_fn(n, n, |i, j| e[(i, n + j)]);
    let psi2 = Mat::from_fn(n, n, |i, j| e[(i, 2 * n + j)]);
    let w = match hold {
        InputHold::Zoh => psi1.clone(),
        InputHold::Linear => &(phi * &psi2) + &psi1 - &psi2,
    };
    let b = w.partial_piv_lu().solve(b_d);
    let d = match hold {
        InputHold::Zoh => d_d.clone(),
        InputHold::Linear => d_d - &(c * &(&psi2 * &b)),
    };
    let finite = |mat: &Mat<f64>| {
        (0..mat.nrows()).all(|i| (0..mat.ncols()).all(|j| mat[(i, j)].is_finite()))
    };
    if !(finite(&a) && finite(&b) && finite(&d)) {
        return Err(EstimateError::Invalid(
            "the continuous-time conversion of the identified model is not finite".into(),
        ));
    }
    let cont = StateSpace {
        a,
        b,
        c: c.clone(),
        d,
        dt_s: None,
    };
    let disc = StateSpace {
        a: phi.clone(),
        b: b_d.clone(),
        c: c.clone(),
        d: d_d.clone(),
        dt_s: Some(dt_s),
    };
    Ok((cont, disc))
}

/// The model in the state `x' = T x`.
fn similarity(ss: &StateSpace, t: &Mat<f64>) -> StateSpace {
    let t_inv = t.partial_piv_lu().inverse();
    StateSpace {
        a: t * &ss.a * &t_inv,
        b: t * &ss.b,
        c: &ss.c * &t_inv,
        d: ss.d.clone(),
        dt_s: ss.dt_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lti::{c2d, Discretization};

    /// A short period (α, q) sampled at 50 Hz under a zero-order hold, driven by a 3-2-1-1 and a
    /// pseudo-random binary sequence, outputs α and q.
    fn records(noise: f64) -> (StateSpace, Vec<Record>) {
        let truth = StateSpace {
            a: Mat::from_fn(2, 2, |i, j| [[-1.2, 1.0], [-6.0, -2.5]][i][j]),
            b: Mat::from_fn(2, 1, |i, _| [-0.1, -12.0][i]),
            c: Mat::identity(2, 2),
            d: Mat::zeros(2, 1),
            dt_s: None,
        };
        let dt = 0.02;
        let disc = c2d(&truth, dt, Discretization::Zoh);
        let mut seed = 7_u64;
        let mut rand = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut recs = Vec::new();
        for r in 0..2 {
            let len = 1500;
            let u: Vec<f64> = (0..len)
                .map(|k| {
                    let t = k as f64 * dt;
                    let step = |a: f64, b: f64| if t >= a && t < b { 1.0 } else { 0.0 };
                    0.02 * (3.0 * step(1.0, 1.9) - 2.0 * step(1.9, 2.5) + step(2.5, 2.8)
                        - step(2.8, 3.1))
                        + 0.01 * (((k / 25 + r * 3) * 7919 % 13) as f64 / 6.0 - 1.0)
                })
                .collect();
            let mut x = [0.01 * (r as f64 + 1.0), -0.02];
            let mut ys = vec![Vec::new(), Vec::new()];
            for &uk in &u {
                for (o, yo) in ys.iter_mut().enumerate() {
                    yo.push(x[o] + 0.05 + noise * rand());
                }
                let nx0 = disc.a[(0, 0)] * x[0] + disc.a[(0, 1)] * x[1] + disc.b[(0, 0)] * uk;
                let nx1 = disc.a[(1, 0)] * x[0] + disc.a[(1, 1)] * x[1] + disc.b[(1, 0)] * uk;
                x = [nx0, nx1];
            }
            recs.push(Record {
                name: format!("r{r}"),
                time_s: (0..len).map(|k| k as f64 * dt).collect(),
                inputs: vec![u.iter().map(|v| v + 0.03).collect()],
                outputs: ys,
                initial_state: vec![0.0, 0.0],
            });
        }
        (truth, recs)
    }

    /// The subspace fit of `recs` (input elevator, outputs α and q as the state basis).
    fn short_period_fit(recs: &[Record], order: Option<usize>, hold: InputHold) -> SubspaceModel {
        let names = ["alpha_rad".to_string(), "q_rad_s".to_string()];
        let opts = SubspaceOptions {
            order,
            hold,
            ..SubspaceOptions::default()
        };
        subspace(
            recs,
            &["elevator_rad".to_string()],
            &names,
            Some(&[0, 1]),
            &opts,
        )
        .unwrap()
    }

    #[test]
    fn recovers_a_short_period_in_the_measured_state_basis() {
        let (truth, recs) = records(0.0);
        let est = short_period_fit(&recs, None, InputHold::Zoh);
        assert_eq!(est.order, 2, "singular values {:?}", est.singular_values);
        assert_eq!(
            est.state_names,
            Some(vec!["alpha_rad".to_string(), "q_rad_s".to_string()])
        );
        for i in 0..2 {
            for j in 0..2 {
                let (got, want) = (est.continuous.a[(i, j)], truth.a[(i, j)]);
                assert!(
                    (got - want).abs() < 1e-6 * (1.0 + want.abs()),
                    "A[{i},{j}] {got} vs {want}"
                );
            }
            let (got, want) = (est.continuous.b[(i, 0)], truth.b[(i, 0)]);
            assert!(
                (got - want).abs() < 1e-6 * (1.0 + want.abs()),
                "B[{i}] {got} vs {want}"
            );
        }
        for r in &est.records {
            assert!(
                r.fit_percent.iter().all(|f| *f > 99.99),
                "{:?}",
                r.fit_percent
            );
        }
    }

    #[test]
    fn the_wrong_hold_biases_only_the_input_matrix() {
        let (truth, recs) = records(0.0);
        let est = short_period_fit(&recs, Some(2), InputHold::Linear);
        let a_err = (est.continuous.a[(1, 0)] - truth.a[(1, 0)]).abs();
        let b_err = (est.continuous.b[(1, 0)] - truth.b[(1, 0)]).abs();
        assert!(a_err < 1e-5, "A is the same under any hold: {a_err}");
        assert!(
            b_err > 1e-3 * 12.0,
            "a ZOH record read as linear moves B: {b_err}"
        );
    }

    #[test]
    fn noisy_records_land_near_the_truth() {
        let (truth, recs) = records(0.004);
        let est = short_period_fit(&recs, Some(2), InputHold::Zoh);
        for (i, j) in [(1, 0), (1, 1)] {
            let (got, want) = (est.continuous.a[(i, j)], truth.a[(i, j)]);
            assert!(
                ((got - want) / want).abs() < 0.1,
                "A[{i},{j}] {got} vs {want}"
            );
        }
    }

    #[test]
    fn a_constant_input_is_refused_by_name() {
        let (_, mut recs) = records(0.0);
        for r in &mut recs {
            r.inputs[0].iter_mut().for_each(|v| *v = 0.1);
        }
        let err = subspace(&recs, &[], &[], None, &SubspaceOptions::default()).unwrap_err();
        assert!(err.to_string().contains("never moves"), "{err}");
    }
}
