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
}

impl ResidualFilter {
    /// Replaces the channel-major residual `r` by its innovations.
    pub fn apply(&self, r: &mut [f64]) {
        let (n, m, len) = (self.a.len(), self.c.len(), self.len);
        if r.len() != m * len {
            return;
        }
        let mut x = vec![0.0; n];
        let mut nu = vec![0.0; m];
        for k in 0..len {
            for (o, v) in nu.iter_mut().enumerate() {
                let pred: f64 = self.c[o].iter().zip(&x).map(|(a, b)| a * b).sum();
                *v = r[o * len + k] - pred;
                r[o * len + k] = *v;
            }
            let corrected: Vec<f64> = (0..n)
                .map(|i| x[i] + self.k[i].iter().zip(&nu).map(|(a, b)| a * b).sum::<f64>())
                .collect();
            for (i, xi) in x.iter_mut().enumerate() {
                *xi = self.a[i].iter().zip(&corrected).map(|(a, b)| a * b).sum();
            }
        }
    }
}
