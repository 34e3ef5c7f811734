//! Ordinary least squares with the parameter covariance, by the thin singular value decomposition.

use faer::Mat;

use super::sum_sq;

/// Why a regression has no unique solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LeastSquaresError {
    /// No more samples than parameters.
    TooFewSamples { samples: usize, parameters: usize },
    /// The regressors are collinear: the smallest singular value is at most 10⁻¹² of the largest.
    Collinear { condition: f64 },
    /// The singular value decomposition did not converge.
    Decomposition,
}

/// θ̂ = argmin ‖z − Xθ‖² and (XᵀX)⁻¹, from X = U Σ Vᵀ: θ̂ = V Σ⁻¹ Uᵀ z, (XᵀX)⁻¹ = V Σ⁻² Vᵀ (Klein & Morelli,
/// *Aircraft System Identification*, eq. 5.8 for θ̂ and eq. 5.9 for its covariance s² (XᵀX)⁻¹; Golub & Van Loan,
/// *Matrix Computations*, §5.5.4 for the SVD solution).
#[derive(Debug, Clone)]
pub struct LeastSquares {
    /// The estimate θ̂, one value per regressor column.
    pub theta: Vec<f64>,
    /// The residual z − Xθ̂.
    pub residual: Vec<f64>,
    /// (XᵀX)⁻¹.
    pub inverse_normal: Mat<f64>,
}

impl LeastSquares {
    /// Fits `z` on the regressor `columns` (each as long as `z`).
    pub fn fit(columns: &[Vec<f64>], z: &[f64]) -> Result<Self, LeastSquaresError> {
        let n = z.len();
        let p = columns.len();
        if n <= p || p == 0 {
            return Err(LeastSquaresError::TooFewSamples {
                samples: n,
                parameters: p,
            });
        }
        let x = Mat::from_fn(n, p, |i, j| columns[j][i]);
        let svd = x.thin_svd().map_err(|_| LeastSquaresError::Decomposition)?;
        let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
        if s[p - 1] <= 1e-12 * s[0] {
            return Err(LeastSquaresError::Collinear {
                condition: s[0] / s[p - 1].max(f64::MIN_POSITIVE),
            });
        }
        let (u, v) = (svd.U(), svd.V());
        let uz: Vec<f64> = (0..p)
            .map(|k| (0..n).map(|i| u[(i, k)] * z[i]).sum())
            .collect();
        let theta: Vec<f64> = (0..p)
            .map(|a| (0..p).map(|k| v[(a, k)] * uz[k] / s[k]).sum())
            .collect();
        let residual = (0..n)
            .map(|i| z[i] - (0..p).map(|j| columns[j][i] * theta[j]).sum::<f64>())
            .collect();
        let inverse_normal = Mat::from_fn(p, p, |a, b| {
            (0..p)
                .map(|k| v[(a, k)] * v[(b, k)] / (s[k] * s[k]))
                .sum::<f64>()
        });
        Ok(Self {
            theta,
            residual,
            inverse_normal,
        })
    }

    /// The fit error variance s² = ‖z − Xθ̂‖² / (n − p).
    pub fn fit_variance(&self) -> f64 {
        sum_sq(&self.residual) / (self.residual.len() - self.theta.len()) as f64
    }

    /// The standard errors √(s² [(XᵀX)⁻¹]ₖₖ) for white residuals.
    pub fn std_errors(&self) -> Vec<f64> {
        let s2 = self.fit_variance();
        (0..self.theta.len())
            .map(|k| (s2 * self.inverse_normal[(k, k)]).sqrt())
            .collect()
    }
}
