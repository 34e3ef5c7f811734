//! Residual analysis per output channel: fit %, ISE, RMS, whiteness, cross-correlation with the inputs.

use serde::Serialize;

use crate::estimate::covariance;
use crate::ident::nrmse_fit;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Statistics of one channel's residual (measured − simulated).
#[derive(Debug, Clone, Serialize)]
pub struct ChannelResidual {
    /// Root mean square of the residual, column units.
    pub rms: f64,
    /// Mean of the residual (a constant offset suggests a bias or trim mismatch), column units.
    pub mean: f64,
    /// Integral of the squared residual, column units² · s.
    pub ise: f64,
    /// Fit, % (100 · (1 − ‖e‖ / ‖y − ȳ‖)).
    pub fit_percent: f64,
    /// Ljung–Box portmanteau p-value of residual whiteness (20 lags); small = coloured residual.
    pub whiteness_p: f64,
    /// Per input: peak |cross-correlation| of residual and input deviation and its lag (s, positive = residual lags).
    pub input_correlation: Vec<InputCorrelation>,
}

/// Peak normalised cross-correlation between a residual and an input.
#[derive(Debug, Clone, Serialize)]
pub struct InputCorrelation {
    /// Input (surface) name.
    pub input: String,
    /// Peak |ρ| over lags within ±2 s.
    pub peak: f64,
    /// Lag of the peak, s.
    pub lag_s: f64,
}

/// Ljung–Box Q statistic p-value for `lags` autocorrelation lags (Ljung & Box 1978, Biometrika 65, eq. 2.1).
pub fn whiteness_p(e: &[f64], lags: usize) -> f64 {
    let n = e.len();
    if n <= lags + 1 {
        return f64::NAN;
    }
    let mean = e.iter().sum::<f64>() / n as f64;
    let c0: f64 = e.iter().map(|v| (v - mean).powi(2)).sum();
    if c0 <= 0.0 {
        return 1.0;
    }
    let mut q = 0.0;
    for k in 1..=lags {
        let ck: f64 = (k..n).map(|i| (e[i] - mean) * (e[i - k] - mean)).sum();
        let rho = ck / c0;
        q += rho * rho / (n - k) as f64;
    }
    q *= n as f64 * (n as f64 + 2.0);
    match ChiSquared::new(lags as f64) {
        Ok(chi) => 1.0 - chi.cdf(q),
        Err(_) => f64::NAN,
    }
}

/// Peak of the normalised cross-correlation ρ(τ) = Σ e[k] u[k−τ] / (‖e‖‖u‖) over |τ| ≤ `max_lag` samples.
pub fn peak_cross_correlation(e: &[f64], u: &[f64], max_lag: usize) -> (f64, isize) {
    let n = e.len().min(u.len());
    let me = e[..n].iter().sum::<f64>() / n.max(1) as f64;
    let mu = u[..n].iter().sum::<f64>() / n.max(1) as f64;
    let ne: f64 = e[..n].iter().map(|v| (v - me).powi(2)).sum::<f64>().sqrt();
    let nu: f64 = u[..n].iter().map(|v| (v - mu).powi(2)).sum::<f64>().sqrt();
    if ne <= 0.0 || nu <= 0.0 {
        return (0.0, 0);
    }
    let mut best = (0.0, 0isize);
    let l = max_lag as isize;
    for lag in -l..=l {
        let mut s = 0.0;
        for k in 0..n as isize {
            let j = k - lag;
            if j >= 0 && j < n as isize {
                s += (e[k as usize] - me) * (u[j as usize] - mu);
            }
        }
        let rho = s / (ne * nu);
        if rho.abs() > best.0 {
            best = (rho.abs(), lag);
        }
    }
    best
}

/// All statistics of one channel.
pub fn analyse(
    measured: &[f64],
    simulated: &[f64],
    dt_s: f64,
    inputs: &[(String, Vec<f64>)],
) -> ChannelResidual {
    let n = measured.len().min(simulated.len());
    let e: Vec<f64> = (0..n).map(|k| measured[k] - simulated[k]).collect();
    let ss: f64 = e.iter().map(|v| v * v).sum();
    let max_lag = ((2.0 / dt_s).round() as usize).min(n / 4);
    let input_correlation = inputs
        .iter()
        .map(|(name, u)| {
            let (peak, lag) = peak_cross_correlation(&e, u, max_lag);
            InputCorrelation {
                input: name.clone(),
                peak,
                lag_s: lag as f64 * dt_s,
            }
        })
        .collect();
    ChannelResidual {
        rms: (ss / n.max(1) as f64).sqrt(),
        mean: e.iter().sum::<f64>() / n.max(1) as f64,
        ise: ss * dt_s,
        fit_percent: nrmse_fit(&measured[..n], &simulated[..n]),
        whiteness_p: whiteness_p(&e, 20),
        input_correlation,
    }
}

pub use crate::signal::noise_std;

/// Sample correlation of two sensitivity vectors (|ρ| near 1: the data cannot tell the parameters apart).
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa <= 0.0 || bb <= 0.0 {
        0.0
    } else {
        ab / (aa * bb).sqrt()
    }
}

/// `Σ_c Σ_i Σ_j s_c[i] R_c(|i−j|) s_c[j]ᵀ` (row-major p × p) over the output channels c, with R_c the
/// Bartlett-tapered autocorrelation of channel c's residual over the lags where it is correlated
/// ([`covariance::lag_weights`], the estimation core's window; channel-major vectors of `m` samples each; the
/// channels are taken as mutually uncorrelated). A window fitted to the residual matters in gusts: their
/// response stays correlated over the phugoid and Dutch-roll periods, and a fixed one-second window made the
/// standard errors of the effects that absorb it several times too small.
pub fn coloured_products(cols: &[Vec<f64>], r: &[f64], m: usize) -> Vec<f64> {
    let p = cols.len();
    let mut total = vec![0.0; p * p];
    for (c, rc) in r.chunks(m.max(1)).enumerate() {
        let slices: Vec<&[f64]> = cols.iter().map(|s| &s[c * m..c * m + rc.len()]).collect();
        let w = covariance::lag_weighted_products(&slices, &covariance::lag_weights(rc));
        total.iter_mut().zip(w).for_each(|(t, v)| *t += v);
    }
    total
}

/// Effective number of independent residuals: the sum over channels of
/// [`covariance::effective_samples`] of the mean-removed residual with the window of [`coloured_products`].
pub fn effective_n(r: &[f64], m: usize) -> f64 {
    if m == 0 {
        return 0.0;
    }
    r.chunks(m)
        .map(|e| {
            let mean = e.iter().sum::<f64>() / e.len() as f64;
            let centred: Vec<f64> = e.iter().map(|v| v - mean).collect();
            covariance::effective_samples(&covariance::lag_weights(&centred), e.len())
        })
        .sum()
}
