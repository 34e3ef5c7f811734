//! Sensitivities `S = ∂ŷ/∂φ` of the predictions: from the model when it has them, else forward differences
//! during the iterations and central differences for the final covariance, the perturbed simulations run in
//! parallel; and the rows weighted by the noise variances for the normal equations.

use super::*;

impl Problem<'_> {
    /// Sensitivity column of φ entry `j`, stacked over records and outputs (unweighted), by
    /// forward or central differences (or exactly, for an output bias).
    pub(super) fn column(
        &self,
        phi: &[f64],
        base: &Predictions,
        j: usize,
        central: bool,
    ) -> Result<Vec<f64>, SimError> {
        let off = self.offsets();
        let mut col = vec![0.0; *off.last().unwrap()];
        if let Some(slot) = self.layout.slot(j) {
            // exact for output error; under the filter a bias also moves the state corrections
            if slot.kind == NuisanceKind::OutputBias && self.method == Method::Oe {
                let r = slot.record.unwrap_or(0);
                let n = self.records[r].len();
                let start = off[r] + slot.index * n;
                col[start..start + n].iter_mut().for_each(|v| *v = 1.0);
                return Ok(col);
            }
        }
        let rel = if central { 1e-5 } else { 1e-6 };
        let mut h = rel * phi[j].abs().max(self.layout.scale[j]);
        if phi[j] + h > self.layout.upper[j] {
            h = -h;
        }
        let records: Vec<usize> = match self.layout.only_record(j) {
            Some(r) => vec![r],
            None => (0..self.records.len()).collect(),
        };
        let mut plus = phi.to_vec();
        plus[j] += h;
        let minus_ok = central && phi[j] - h.abs() >= self.layout.lower[j] && h > 0.0;
        let mut minus = phi.to_vec();
        minus[j] -= h;
        for r in records {
            let yp = self.predict(&plus, r)?;
            let ym = if minus_ok {
                Some(self.predict(&minus, r)?)
            } else {
                None
            };
            let n = self.records[r].len();
            for o in 0..yp.len() {
                let start = off[r] + o * n;
                for k in 0..n {
                    col[start + k] = match &ym {
                        Some(ym) => (yp[o][k] - ym[o][k]) / (2.0 * h),
                        None => (yp[o][k] - base[r][o][k]) / h,
                    };
                }
            }
        }
        Ok(col)
    }

    /// All sensitivity columns (analytic ones from the model where it has them).
    pub(super) fn jacobian(
        &self,
        phi: &[f64],
        base: &Predictions,
        central: bool,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let p = self.layout.len();
        let nf = self.layout.free.len();
        let mut analytic: Vec<Option<Vec<f64>>> = vec![None; p];
        if nf > 0 && self.method == Method::Oe {
            let theta = self.layout.theta(phi);
            let off = self.offsets();
            let mut cols = vec![vec![0.0; *off.last().unwrap()]; nf];
            let mut have = true;
            for (r, rec) in self.records.iter().enumerate() {
                let terms = self.layout.record_terms(phi, r);
                let run = self.run(r, &terms);
                match self
                    .model
                    .sensitivities(&theta, &terms.x0, &run, &self.layout.free)
                {
                    None => {
                        have = false;
                        break;
                    }
                    Some(s) => {
                        let s = s?;
                        for (j, sj) in s.iter().enumerate().take(nf) {
                            for (o, so) in sj.iter().enumerate() {
                                let start = off[r] + o * rec.len();
                                cols[j][start..start + rec.len()].copy_from_slice(so);
                            }
                        }
                    }
                }
            }
            if have {
                for (j, c) in cols.into_iter().enumerate() {
                    analytic[j] = Some(c);
                }
            }
        }
        let one = |j: usize| match analytic[j].clone() {
            Some(c) => Ok(c),
            None => self.column(phi, base, j, central),
        };
        if self.model.parallel() {
            (0..p).into_par_iter().map(one).collect()
        } else {
            (0..p).map(one).collect()
        }
    }

    /// The stacked sensitivities weighted by `R^{-1/2}` as a matrix, and the weighted residuals.
    pub(super) fn weighted(
        &self,
        cols: &[Vec<f64>],
        res: &Predictions,
        noise: &[f64],
    ) -> (Mat<f64>, Vec<f64>) {
        let off = self.offsets();
        let rows = *off.last().unwrap();
        let mut w = vec![0.0; rows];
        let mut e = vec![0.0; rows];
        for (r, rec) in self.records.iter().enumerate() {
            let n = rec.len();
            for (o, r_o) in noise.iter().enumerate() {
                let s = 1.0 / r_o.sqrt();
                for k in 0..n {
                    w[off[r] + o * n + k] = s;
                    e[off[r] + o * n + k] = s * res[r][o][k];
                }
            }
        }
        let x = Mat::from_fn(rows, cols.len(), |i, j| w[i] * cols[j][i]);
        (x, e)
    }
}
