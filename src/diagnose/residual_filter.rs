//! The steady-state Kalman filter on a replay's residuals (the filter error method's innovations; built by
//! `process_noise::estimate`, applied by every residual of the search in turbulence).

/// The linearised error dynamics of a case and the steady-state filter on its residuals.
#[derive(Debug, Clone)]
pub struct ResidualFilter {
    /// `A`, n×n (sample interval of the record).
    pub(super) a: Vec<Vec<f64>>,
    /// `C`, channels×n.
    pub(super) c: Vec<Vec<f64>>,
    /// `K`, n×channels.
    pub(super) k: Vec<Vec<f64>>,
    /// Samples per channel.
    pub(super) len: usize,
    /// Per channel, the factor each innovation leaves the filter with: `R_c^{−1/2}` with `R_c` the channel's
    /// innovation variance at the likelihood's optimum (the last relaxation of `process_noise::estimate`), so
    /// that a sum of squared innovations is the filter error method's cost `Σ νᵀR⁻¹ν` (Jategaonkar, *Flight
    /// Vehicle System Identification*, 2nd ed., eq. 5.6); all 1 while the variances are being estimated. The
    /// state is corrected with the innovations as they are.
    pub(super) weight: Vec<f64>,
}

impl ResidualFilter {
    /// Replaces the channel-major residual `r` by its innovations (times the channels' [`weight`](Self::weight)).
    pub fn apply(&self, r: &mut [f64]) {
        let mut v = [r.to_vec()];
        self.apply_all(&mut v);
        r.copy_from_slice(&v[0]);
    }

    /// [`apply`](Self::apply) on every vector of `rs` at once, each to the same result as alone (the same
    /// operations in the same order); one pass over the samples with the filter's state for all of them, so
    /// the inner loops run over the vectors and vectorise. A vector of the wrong length is left as it is.
    pub fn apply_all(&self, rs: &mut [Vec<f64>]) {
        let (n, m, len) = (self.a.len(), self.c.len(), self.len);
        let idx: Vec<usize> = (0..rs.len()).filter(|&v| rs[v].len() == m * len).collect();
        let b = idx.len();
        if b == 0 {
            return;
        }
        // State, innovations and corrected state, row-major with the vectors along the rows.
        let mut x = vec![0.0; n * b];
        let mut nu = vec![0.0; m * b];
        let mut corrected = vec![0.0; n * b];
        let mut acc = vec![0.0; b];
        for k in 0..len {
            for o in 0..m {
                acc.fill(0.0);
                for (j, &cj) in self.c[o].iter().enumerate() {
                    let xj = &x[j * b..(j + 1) * b];
                    acc.iter_mut().zip(xj).for_each(|(s, v)| *s += cj * v);
                }
                let row = &mut nu[o * b..(o + 1) * b];
                let weight = self.weight[o];
                for ((v, s), &vi) in row.iter_mut().zip(&acc).zip(&idx) {
                    let at = &mut rs[vi][o * len + k];
                    *v = *at - s;
                    *at = *v * weight;
                }
            }
            for i in 0..n {
                acc.fill(0.0);
                for (o, &kio) in self.k[i].iter().enumerate() {
                    let nuo = &nu[o * b..(o + 1) * b];
                    acc.iter_mut().zip(nuo).for_each(|(s, v)| *s += kio * v);
                }
                let xi = &x[i * b..(i + 1) * b];
                corrected[i * b..(i + 1) * b]
                    .iter_mut()
                    .zip(xi.iter().zip(&acc))
                    .for_each(|(c, (xv, s))| *c = xv + s);
            }
            for i in 0..n {
                acc.fill(0.0);
                for (j, &aij) in self.a[i].iter().enumerate() {
                    let cj = &corrected[j * b..(j + 1) * b];
                    acc.iter_mut().zip(cj).for_each(|(s, v)| *s += aij * v);
                }
                x[i * b..(i + 1) * b].copy_from_slice(&acc);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ResidualFilter;

    /// The filter one vector at a time, written out as the recursion reads.
    fn one_by_one(f: &ResidualFilter, r: &mut [f64]) {
        let (n, m, len) = (f.a.len(), f.c.len(), f.len);
        let mut x = vec![0.0; n];
        let mut nu = vec![0.0; m];
        for k in 0..len {
            for (o, v) in nu.iter_mut().enumerate() {
                let pred: f64 = f.c[o].iter().zip(&x).map(|(a, b)| a * b).sum();
                *v = r[o * len + k] - pred;
                r[o * len + k] = *v * f.weight[o];
            }
            let corrected: Vec<f64> = (0..n)
                .map(|i| x[i] + f.k[i].iter().zip(&nu).map(|(a, b)| a * b).sum::<f64>())
                .collect();
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = f.a[i].iter().zip(&corrected).map(|(a, b)| a * b).sum();
            }
        }
    }

    #[test]
    fn many_vectors_at_once_give_each_vector_its_own_innovations_exactly() {
        // Values in (−0.5, 0.5) without a pattern the filter could cancel: the fractional parts of k·√2.
        let mut k = 0.0;
        let mut next = move || {
            k += 1.0;
            (k * std::f64::consts::SQRT_2).fract() - 0.5
        };
        let (n, m, len) = (4, 3, 50);
        let mut mat = |r: usize, c: usize, s: f64| -> Vec<Vec<f64>> {
            (0..r)
                .map(|_| (0..c).map(|_| s * next()).collect())
                .collect()
        };
        let f = ResidualFilter {
            a: mat(n, n, 0.9),
            c: mat(m, n, 1.0),
            k: mat(n, m, 0.5),
            len,
            weight: vec![1.0, 0.5, 2.0],
        };
        let mut rs: Vec<Vec<f64>> = (0..5)
            .map(|_| (0..m * len).map(|_| next()).collect())
            .collect();
        rs.push(vec![1.0; 3]); // the wrong length: left alone
        let mut want = rs.clone();
        want.iter_mut().take(5).for_each(|r| one_by_one(&f, r));
        f.apply_all(&mut rs);
        assert_eq!(rs, want);
        let mut single = want[0].clone();
        let mut again = rs[0].clone();
        one_by_one(&f, &mut single);
        f.apply(&mut again);
        assert_eq!(again, single);
        // The weights scale what leaves the filter, channel by channel, and leave its state alone.
        let unweighted = ResidualFilter {
            weight: vec![1.0; m],
            ..f.clone()
        };
        let mut plain = rs[1].clone();
        let mut weighted = rs[1].clone();
        unweighted.apply(&mut plain);
        f.apply(&mut weighted);
        for (i, (w, p)) in weighted.iter().zip(&plain).enumerate() {
            assert_eq!(*w, p * f.weight[i / len], "sample {i}");
        }
    }
}
