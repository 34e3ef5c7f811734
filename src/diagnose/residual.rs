//! Residual analysis per output channel: fit %, ISE, RMS, whiteness, cross-correlation with the inputs.

use serde::Serialize;

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
