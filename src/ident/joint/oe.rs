//! Joint output error by variable projection and its Cramér–Rao bound corrected for coloured residuals
//! (the `oe` row of the method table in [`super`]).

use super::{linear_system, Centered, Nuisance};
use crate::estimate::covariance;
use crate::ident::linalg::{inverse, lstsq_qr};
use crate::ident::{ContinuousModel, IdentError};
use crate::optimise;
use crate::signal::sum_sq;
use faer::Mat;

/// Variable-projection output error (Golub & Pereyra): Levenberg–Marquardt on `a₁…a_n` of the
/// projected cost `min over (B, x_r, c_r)` of the joint simulation error; forward-difference
/// Jacobian of the projected residual (Kaufman's simplification is not needed at this size).
pub(super) fn oe_joint(
    recs: &[Centered],
    dt_s: f64,
    m: usize,
    start: ContinuousModel,
) -> Result<ContinuousModel, IdentError> {
    const MAX_ITER: usize = 60;
    let delay_s = start.delay_s;
    let n = start.den.len() - 1;
    let residual = |a: &[f64]| -> Option<(Vec<f64>, Vec<f64>)> {
        let mut den = vec![1.0];
        den.extend_from_slice(a);
        let (mat, y) = linear_system(recs, dt_s, &den, m, delay_s);
        let theta = lstsq_qr(&mat, &y, "oe (joint)").ok()?;
        let r: Vec<f64> = (0..y.len())
            .map(|i| {
                y[i] - (0..theta.len())
                    .map(|c| mat[(i, c)] * theta[c])
                    .sum::<f64>()
            })
            .collect();
        r.iter().all(|v| v.is_finite()).then_some((r, theta))
    };
    let a = start.den[1..].to_vec();
    let Some(at_start) = residual(&a) else {
        return Err(IdentError::Failed {
            method: "oe (joint)".into(),
            reason: "the starting model cannot be simulated".into(),
        });
    };
    let mut problem = Projected { residual, n };
    let Ok(min) = optimise::levenberg_marquardt(
        &mut problem,
        a,
        at_start,
        &crate::ident::oe::lm_options(MAX_ITER),
    );
    let (a, theta) = (min.x, min.point.1);
    let mut den = vec![1.0];
    den.extend_from_slice(&a);
    Ok(ContinuousModel::new(theta[..=m].to_vec(), den, delay_s))
}

/// The projected residual `r(a)` (with the eliminated linear parameters) for
/// [`optimise::levenberg_marquardt`], its Jacobian by forward differences.
struct Projected<F> {
    residual: F,
    n: usize,
}

impl<F> optimise::Problem for Projected<F>
where
    F: Fn(&[f64]) -> Option<(Vec<f64>, Vec<f64>)>,
{
    type Point = (Vec<f64>, Vec<f64>);
    type Error = std::convert::Infallible;

    fn evaluate(&mut self, a: &[f64]) -> Result<Option<Self::Point>, Self::Error> {
        Ok((self.residual)(a))
    }

    fn cost(&self, (r, _): &Self::Point) -> f64 {
        sum_sq(r)
    }

    fn linearise(
        &mut self,
        a: &[f64],
        (r, _): &Self::Point,
    ) -> Result<Option<optimise::Linearised>, Self::Error> {
        // ∂ŷ/∂a = −∂r/∂a; a column whose perturbed model cannot be simulated stays 0
        let mut s = Mat::<f64>::zeros(r.len(), self.n);
        for i in 0..self.n {
            let h = 1e-6 * a[i].abs().max(1e-3);
            let mut ap = a.to_vec();
            ap[i] += h;
            let Some((rp, _)) = (self.residual)(&ap) else {
                continue;
            };
            for k in 0..r.len() {
                s[(k, i)] = (r[k] - rp[k]) / h;
            }
        }
        Ok(Some(optimise::Linearised {
            sensitivities: s,
            residuals: r.clone(),
        }))
    }
}

/// Cramér–Rao bound of `[b…, a…]` for the joint output-error model, corrected for coloured residuals
/// by the estimation core's rule ([`covariance`]): `(JᵀJ)⁻¹ [Σ_records W_r] (JᵀJ)⁻¹`, `W_r` the
/// products of record r's rows of `J` weighted by its Bartlett-windowed residual autocorrelation
/// (records mutually uncorrelated; white residuals give `σ²(JᵀJ)⁻¹`). Over all parameters
/// (nuisances included), `J` by central differences for `a` and exactly (the basis columns) for the
/// linear parameters; the `[B, A]` block is returned.
pub(super) fn covariance(
    recs: &[Centered],
    dt_s: f64,
    model: &ContinuousModel,
    nuis: &[Nuisance],
) -> Option<Vec<f64>> {
    let (n, m) = (model.den.len() - 1, model.num.len() - 1);
    let (lin, y) = linear_system(recs, dt_s, &model.den, m, model.delay_s);
    // Linear parameters in `lin`'s column order: B, then per record [x_r…, c_r].
    let mut theta = model.num.clone();
    for q in nuis {
        theta.extend_from_slice(&q.coef);
    }
    let output = |den: &[f64]| -> Vec<f64> {
        let (mat, _) = linear_system(recs, dt_s, den, m, model.delay_s);
        (0..y.len())
            .map(|i| (0..theta.len()).map(|c| mat[(i, c)] * theta[c]).sum())
            .collect()
    };
    let nl = theta.len();
    let p = nl + n;
    let mut da = Vec::with_capacity(n);
    for i in 1..=n {
        let h = 1e-6 * model.den[i].abs().max(1e-3);
        let (mut up, mut dn) = (model.den.clone(), model.den.clone());
        up[i] += h;
        dn[i] -= h;
        let (yu, yd) = (output(&up), output(&dn));
        da.push(
            yu.iter()
                .zip(&yd)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect::<Vec<f64>>(),
        );
    }
    // Parameter order for the matrix: [b (m+1), a (n), nuisances].
    let col = |i: usize, c: usize| -> f64 {
        if c <= m {
            lin[(i, c)]
        } else if c <= m + n {
            da[c - m - 1][i]
        } else {
            lin[(i, c - n)]
        }
    };
    let mut jtj = vec![0.0; p * p];
    let mut row = vec![0.0; p];
    for i in 0..y.len() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = col(i, c);
        }
        for a in 0..p {
            if row[a] == 0.0 {
                continue;
            }
            for b in 0..p {
                jtj[a * p + b] += row[a] * row[b];
            }
        }
    }
    let inv = inverse(&jtj, p)?;
    let mut w = vec![0.0; p * p];
    let mut start = 0;
    for (rec, q) in recs.iter().zip(nuis) {
        let rows = start..start + rec.y.len();
        let e: Vec<f64> = y[rows.clone()]
            .iter()
            .zip(&q.y_model)
            .map(|(a, b)| a - b)
            .collect();
        let cols: Vec<Vec<f64>> = (0..p)
            .map(|c| rows.clone().map(|i| col(i, c)).collect())
            .collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let w_r = covariance::lag_weighted_products(&refs, &covariance::lag_weights(&e));
        w.iter_mut().zip(&w_r).for_each(|(acc, v)| *acc += v);
        start = rows.end;
    }
    let cov = covariance::sandwich(&inv, &w, p);
    let q = m + 1 + n;
    Some((0..q * q).map(|k| cov[(k / q) * p + k % q]).collect())
}
