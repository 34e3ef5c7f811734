//! The output-error fit of the compatibility check: Gauss–Newton with Levenberg–Marquardt damping and the
//! diagonal residual covariance re-estimated every iteration (Klein & Morelli §6.2, eq. 6.51–6.56), and the
//! Cramér–Rao bounds corrected for coloured residuals (Morelli & Klein, J. Aircraft 1997).

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, Side};

use super::kinematics::{residuals, Data, Param, N_OUT};
use crate::estimate::covariance;
use crate::optimise;
use crate::signal::sum_sq;

/// Cramér–Rao bounds corrected for coloured residuals by the estimation core's rule
/// ([`covariance`], Morelli & Klein §6.6, eq. 6.86): `M⁻¹ W M⁻¹`, `W = Σ_o W_o / σ_o⁴`, with `W_o` the
/// products of output o's sensitivities weighted by its Bartlett-windowed residual autocorrelation over the
/// lags where it is correlated; outputs mutually uncorrelated. `j[a][o]` is ∂ŷ_o/∂θ_a per sample.
pub(super) fn coloured_residual_covariance(
    m_inv: &[f64],
    j: &[Vec<Vec<f64>>],
    r: &[Vec<f64>],
    np: usize,
) -> Vec<f64> {
    let mut w = vec![0.0; np * np];
    for (o, ro) in r.iter().enumerate() {
        let acf = covariance::lag_weights(ro);
        let var = acf[0].max(1e-300);
        let cols: Vec<&[f64]> = (0..np).map(|a| j[a][o].as_slice()).collect();
        let w_o = covariance::lag_weighted_products(&cols, &acf);
        // lag_weights' R(0) is Bartlett weight 1 times the residual power
        for (acc, v) in w.iter_mut().zip(&w_o) {
            *acc += v / (var * var);
        }
    }
    covariance::sandwich(m_inv, &w, np)
}

/// Outcome of one output-error fit.
pub(super) struct Fit {
    pub(super) theta: Vec<f64>,
    pub(super) fisher: Vec<f64>,
    pub(super) residuals: Vec<Vec<f64>>,
    pub(super) iterations: usize,
    pub(super) converged: bool,
}

/// Output-error Gauss–Newton with Levenberg–Marquardt damping ([`optimise::levenberg_marquardt`]);
/// the diagonal residual covariance is re-estimated from the residuals after every step (Klein &
/// Morelli §6.2).
pub(super) fn fit(data: &Data, params: &[Param], start: Vec<f64>, max_iterations: usize) -> Fit {
    let outputs: Vec<usize> = (0..N_OUT).filter(|&j| data.out[j].is_some()).collect();
    let r = residuals(data, params, &start, &outputs);
    let np = params.len();
    let mut problem = Reconstruction {
        data,
        params,
        variances: variances(&r),
        outputs,
        fisher: vec![0.0; np * np],
    };
    let options = optimise::Options {
        max_iterations,
        tolerance: 1e-9,
        min_decrease: 0.0,
        damping: optimise::Damping {
            tries: 12,
            ..optimise::Damping::default()
        },
        solver: optimise::StepSolver::Marquardt,
    };
    let Ok(min) = optimise::levenberg_marquardt(&mut problem, start, r, &options);
    // Fisher information at the final point with the final residual covariance.
    let r = min.point;
    let var = variances(&r);
    let j = jacobian(data, params, &min.x, &problem.outputs, &r);
    let m = information(&j, &var, np);
    Fit {
        theta: min.x,
        fisher: if m.iter().all(|x| x.is_finite()) {
            m
        } else {
            problem.fisher
        },
        residuals: r,
        iterations: min.iterations,
        converged: min.stop != optimise::Stop::MaxIterations,
    }
}

/// Per-output residual variance (the diagonal R of the relaxation algorithm).
fn variances(r: &[Vec<f64>]) -> Vec<f64> {
    r.iter()
        .map(|rj| (sum_sq(rj) / rj.len().max(1) as f64).max(1e-24))
        .collect()
}

/// The flight-path reconstruction for [`optimise::levenberg_marquardt`], with the current
/// residual variances.
struct Reconstruction<'a> {
    data: &'a Data,
    params: &'a [Param],
    outputs: Vec<usize>,
    variances: Vec<f64>,
    /// Information matrix of the last linearisation.
    fisher: Vec<f64>,
}

impl optimise::Problem for Reconstruction<'_> {
    type Point = Vec<Vec<f64>>;
    type Error = std::convert::Infallible;

    fn evaluate(&mut self, th: &[f64]) -> Result<Option<Self::Point>, Self::Error> {
        Ok(Some(residuals(self.data, self.params, th, &self.outputs)))
    }

    fn cost(&self, r: &Self::Point) -> f64 {
        r.iter()
            .zip(&self.variances)
            .map(|(rj, v)| sum_sq(rj) / v)
            .sum()
    }

    fn linearise(
        &mut self,
        th: &[f64],
        r: &Self::Point,
    ) -> Result<Option<optimise::Linearised>, Self::Error> {
        let j = jacobian(self.data, self.params, th, &self.outputs, r);
        let np = self.params.len();
        self.fisher = information(&j, &self.variances, np);
        let n = r.first().map_or(0, Vec::len);
        let w: Vec<f64> = self.variances.iter().map(|v| 1.0 / v.sqrt()).collect();
        Ok(Some(optimise::Linearised {
            sensitivities: Mat::from_fn(r.len() * n, np, |i, a| j[a][i / n][i % n] * w[i / n]),
            residuals: (0..r.len() * n)
                .map(|i| r[i / n][i % n] * w[i / n])
                .collect(),
        }))
    }

    fn relax(
        &mut self,
        _th: &mut Vec<f64>,
        r: &mut Self::Point,
    ) -> Result<optimise::Relaxation, Self::Error> {
        self.variances = variances(r);
        Ok(optimise::Relaxation::Steady)
    }
}

/// Sensitivities of the residuals by forward differences: J[p][j][k] = ∂model/∂θ_p (= −∂r/∂θ).
pub(super) fn jacobian(
    data: &Data,
    params: &[Param],
    th: &[f64],
    outputs: &[usize],
    r0: &[Vec<f64>],
) -> Vec<Vec<Vec<f64>>> {
    use rayon::prelude::*;
    (0..params.len())
        .into_par_iter()
        .map(|p| {
            let (step, _) = params[p].step_and_floor();
            let h = step * th[p].abs().max(1.0);
            let mut tp = th.to_vec();
            tp[p] += h;
            let rp = residuals(data, params, &tp, outputs);
            rp.iter()
                .zip(r0)
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| (y - x) / h).collect())
                .collect()
        })
        .collect()
}

/// Information matrix M = Σ Jᵀ R⁻¹ J of the Gauss–Newton normal equations (Klein & Morelli eq. 6.56).
fn information(j: &[Vec<Vec<f64>>], var: &[f64], np: usize) -> Vec<f64> {
    let mut m = vec![0.0; np * np];
    for a in 0..np {
        for b in a..np {
            let mut s = 0.0;
            for (o, v) in var.iter().enumerate() {
                s += j[a][o]
                    .iter()
                    .zip(&j[b][o])
                    .map(|(x, y)| x * y)
                    .sum::<f64>()
                    / v;
            }
            m[a * np + b] = s;
            m[b * np + a] = s;
        }
    }
    m
}

/// Inverse of a symmetric positive-definite matrix (row-major, n×n): Cholesky factorisation (faer) of the
/// equilibrated copy D A D, D = diag(1/√a_ii), which copes with parameters of very different units. `None`
/// when the matrix is not positive definite or a pivot of the equilibrated copy falls below 1e-14 (a
/// parameter the data do not determine).
pub(super) fn invert(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let d: Vec<f64> = (0..n)
        .map(|i| 1.0 / a[i * n + i].abs().sqrt().max(1e-300))
        .collect();
    let m = Mat::from_fn(n, n, |i, j| a[i * n + j] * d[i] * d[j]);
    let llt = m.llt(Side::Lower).ok()?;
    let l = llt.L();
    if (0..n).any(|i| l[(i, i)] * l[(i, i)] < 1e-14) {
        return None;
    }
    let inv = llt.inverse();
    let out: Vec<f64> = (0..n * n)
        .map(|k| inv[(k / n, k % n)] * d[k / n] * d[k % n])
        .collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}
