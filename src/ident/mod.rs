//! Estimators: the paper's ARX least squares, instrumental variables / SRIVC, output error.
//!
//! Every estimator identifies a continuous SISO model `y = B(s)/A(s) · e^{−τs} u` (A monic,
//! `poles` = deg A, `zeros` = deg B) from a sampled input/output record and returns the same
//! [`IdentResult`]: coefficients, poles/zeros/modes, standard errors where the method gives
//! them, simulation and one-step-ahead fits and residual correlation tests.
//!
//! | method | file | source |
//! |---|---|---|
//! | [`Method::Ls`] | `ls.rs` | Şahin & Kalyon 2021, eq. 59–64 (discrete ARX LS + ZOH d2c) |
//! | [`Method::Iv`] | `iv.rs` | Söderström & Stoica 1989, ch. 8 (auxiliary-model instruments) |
//! | [`Method::Srivc`] | `srivc.rs` | Young & Jakeman 1980; Garnier's CONTSID |
//! | [`Method::Oe`] | `oe.rs` | Morelli & Klein 2016, ch. 6 (output error, Cramér–Rao bounds) |
//!
//! Signals are treated as perturbations about the initial trim: the mean of each signal over
//! the samples before the input first moves (beyond 5 σ of its own noise) is removed (reported as
//! `u_offset`/`y_offset`).

mod complex_serde;
mod delay;
mod filter;
mod iv;
mod joint;
pub(crate) mod linalg;
pub(crate) use linalg::lstsq_qr;
mod ls;
mod metrics;
mod oe;
mod order;
mod srivc;
#[cfg(test)]
mod tests;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

pub use crate::lti::{modes, Mode, TransferFunction};
pub use joint::{identify_joint, JointRecord, JointResult, RecordFit};
pub use metrics::{ise, CorrelationTest};
pub use order::{
    select_order, OrderCandidate, OrderSelection, FIT_MARGIN_PERCENT, UNSTABLE_MARGIN_PERCENT,
};

/// Which estimator [`identify`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The paper's discrete ARX least squares + ZOH d2c (exact on noise-free data only).
    Ls,
    /// Discrete instrumental variables with auxiliary-model instruments, then d2c.
    Iv,
    /// Simplified refined instrumental variable for continuous-time models.
    Srivc,
    /// Output error (Levenberg–Marquardt) with Cramér–Rao standard errors.
    Oe,
}

impl Method {
    /// Lower-case name as used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::Iv => "iv",
            Method::Srivc => "srivc",
            Method::Oe => "oe",
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = IdentError;
    fn from_str(s: &str) -> Result<Method, IdentError> {
        match s.to_ascii_lowercase().as_str() {
            "ls" => Ok(Method::Ls),
            "iv" => Ok(Method::Iv),
            "srivc" => Ok(Method::Srivc),
            "oe" => Ok(Method::Oe),
            other => Err(IdentError::InvalidOptions(format!(
                "unknown method '{other}' (expected ls, iv, srivc or oe)"
            ))),
        }
    }
}

/// Options for [`identify`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentOptions {
    /// The estimator.
    pub method: Method,
    /// Number of poles (degree of the monic denominator).
    pub poles: usize,
    /// Number of zeros (degree of the numerator), less than `poles`.
    pub zeros: usize,
    /// Also estimate a pure input delay (searched over 0 … min(1 s, record/10)).
    pub estimate_delay: bool,
}

impl Default for IdentOptions {
    fn default() -> Self {
        IdentOptions {
            method: Method::Srivc,
            poles: 4,
            zeros: 2,
            estimate_delay: false,
        }
    }
}

/// What went wrong in an identification, with what the user needs to fix it.
#[derive(Debug, thiserror::Error)]
pub enum IdentError {
    /// Input and output records differ in length.
    #[error("length mismatch: the input has {input} samples but the output has {output}")]
    LengthMismatch {
        /// Input samples.
        input: usize,
        /// Output samples.
        output: usize,
    },
    /// Too few samples for the requested model order.
    #[error(
        "too few samples: {n_samples} samples for a {poles}-pole/{zeros}-zero model; at least {needed} are needed"
    )]
    TooFewSamples {
        /// Samples given.
        n_samples: usize,
        /// Requested poles.
        poles: usize,
        /// Requested zeros.
        zeros: usize,
        /// Minimum accepted.
        needed: usize,
    },
    /// The input is constant: no excitation, nothing to identify.
    #[error("the input never moves (all {n_samples} samples equal {value}); apply a doublet, 3-2-1-1 or multisine")]
    ConstantInput {
        /// Samples given.
        n_samples: usize,
        /// The constant value.
        value: f64,
    },
    /// NaN or infinity in the data.
    #[error("non-finite value {value} in the {signal} at sample {index}")]
    NonFinite {
        /// "input" or "output".
        signal: &'static str,
        /// Sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The regression matrix is rank deficient.
    #[error("singular regression in {method}: numerical rank {rank} of {n_params} parameters (input not exciting enough for this order?)")]
    SingularRegression {
        /// Estimator.
        method: String,
        /// Numerical rank found.
        rank: usize,
        /// Parameters sought.
        n_params: usize,
    },
    /// Inconsistent options (orders, sample time, method name).
    #[error("invalid options: {0}")]
    InvalidOptions(String),
    /// The estimator ran but could not produce a model.
    #[error("{method} failed: {reason}")]
    Failed {
        /// Estimator.
        method: String,
        /// Why.
        reason: String,
    },
}

/// The common result of every estimator (continuous model, monic denominator).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct IdentResult {
    /// Estimator name (`ls`, `iv`, `srivc`, `oe`).
    pub method: String,
    /// Identified continuous transfer function, monic denominator, highest power first.
    pub tf: TransferFunction,
    /// Pure input delay in seconds (`None` unless requested).
    pub delay_s: Option<f64>,
    /// Standard error of each numerator coefficient (empty if the method gives none).
    pub num_std: Vec<f64>,
    /// Standard error of each denominator coefficient, 0 for the leading 1 (empty if none).
    pub den_std: Vec<f64>,
    /// Standard error of the delay in seconds, when estimated by a method that gives one.
    pub delay_std_s: Option<f64>,
    /// Poles of `tf`.
    #[serde(with = "complex_serde::many")]
    pub poles: Vec<Complex64>,
    /// Standard errors of each pole's real and imaginary parts (first-order propagation of the
    /// denominator covariance, d p/d a_i = −p^{n−i}/A'(p)); empty if the method gives none.
    #[serde(with = "complex_serde::many")]
    pub pole_std: Vec<Complex64>,
    /// Zeros of `tf`.
    #[serde(with = "complex_serde::many")]
    pub zeros: Vec<Complex64>,
    /// Modal parameters of the poles.
    pub modes: Vec<Mode>,
    /// Simulation fit, NRMSE %: 100 (1 − ‖y − ŷ_sim‖ / ‖y − ȳ‖).
    pub fit_sim_percent: f64,
    /// One-step-ahead fit, NRMSE %: the ARX predictor of the ZOH model for `ls`/`iv`, equal to
    /// the simulation fit for the output-error noise model of `srivc`/`oe`.
    pub fit_one_step_percent: f64,
    /// Autocorrelation test of the simulation residuals (lags 1…25).
    pub residual_whiteness: CorrelationTest,
    /// Residual–input cross-correlation test (lags −25…25).
    pub input_residual_independence: CorrelationTest,
    /// Samples used.
    pub n_samples: usize,
    /// Sample time, seconds.
    pub dt_s: f64,
    /// Input trim removed before identification (input units).
    pub u_offset: f64,
    /// Output trim removed before identification (output units); for `srivc` and `oe` it includes the
    /// constant output offset estimated beside the model.
    pub y_offset: f64,
    /// What the user should know about this estimate (e.g. an estimator that fell back to its
    /// starting model); empty when all went as designed.
    #[serde(default)]
    pub warnings: Vec<String>,
}

/// A continuous model inside `ident`: monic `den`, `num` highest power first, optional full
/// parameter covariance ordered `[num…, a₁…a_n, (delay)]`.
#[derive(Clone, Debug)]
pub(crate) struct ContinuousModel {
    pub num: Vec<f64>,
    pub den: Vec<f64>,
    pub delay_s: f64,
    /// Constant output offset estimated beside the model (added to the simulated output).
    pub y_bias: f64,
    pub cov: Option<Vec<f64>>,
    /// Notes for [`IdentResult::warnings`].
    pub warnings: Vec<String>,
}

impl ContinuousModel {
    /// A model without covariance.
    pub fn new(num: Vec<f64>, den: Vec<f64>, delay_s: f64) -> ContinuousModel {
        ContinuousModel {
            num,
            den,
            delay_s,
            y_bias: 0.0,
            cov: None,
            warnings: Vec::new(),
        }
    }
}

/// Fit in percent, 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖) (Ljung, *System Identification*, 2nd ed., §16.6
/// "fit"): the crate's one fit measure. Extra samples of the longer series are ignored; an empty
/// series gives NaN, a constant one 100 when matched exactly and −∞ otherwise.
pub fn nrmse_fit(y: &[f64], y_hat: &[f64]) -> f64 {
    let n = y.len().min(y_hat.len());
    if n == 0 {
        return f64::NAN;
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let num: f64 = (0..n).map(|k| (y[k] - y_hat[k]).powi(2)).sum();
    let den: f64 = (0..n).map(|k| (y[k] - mean).powi(2)).sum();
    if den <= 0.0 {
        return if num <= 0.0 { 100.0 } else { f64::NEG_INFINITY };
    }
    100.0 * (1.0 - (num / den).sqrt())
}

/// Checks the record and options; returns the error naming the first problem found.
fn validate(u: &[f64], y: &[f64], dt_s: f64, opts: &IdentOptions) -> Result<(), IdentError> {
    if u.len() != y.len() {
        return Err(IdentError::LengthMismatch {
            input: u.len(),
            output: y.len(),
        });
    }
    for (signal, v) in [("input", u), ("output", y)] {
        if let Some((index, value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(IdentError::NonFinite {
                signal,
                index,
                value: *value,
            });
        }
    }
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(IdentError::InvalidOptions(format!(
            "sample time must be a positive number of seconds, got {dt_s}"
        )));
    }
    if opts.poles == 0 || opts.zeros >= opts.poles {
        return Err(IdentError::InvalidOptions(format!(
            "need at least one pole and fewer zeros than poles (strictly proper model), got {} poles and {} zeros",
            opts.poles, opts.zeros
        )));
    }
    if opts.poles > MAX_POLES {
        return Err(IdentError::InvalidOptions(format!(
            "at most {MAX_POLES} poles, got {} (flight data do not determine more)",
            opts.poles
        )));
    }
    // ten samples per parameter of the largest regression (the ARX fit, 2n parameters)
    let needed = 20 * opts.poles + 10;
    if u.len() < needed {
        return Err(IdentError::TooFewSamples {
            n_samples: u.len(),
            poles: opts.poles,
            zeros: opts.zeros,
            needed,
        });
    }
    let u0 = u[0];
    if u.iter().all(|x| *x == u0) {
        return Err(IdentError::ConstantInput {
            n_samples: u.len(),
            value: u0,
        });
    }
    Ok(())
}

/// Trim offsets: means of u and y over the samples before the input first moves (at least
/// the first sample).
///
/// "Moves" means leaving a band of 5 σ around the first sample, with σ the input's white
/// measurement noise estimated from its first differences (1.4826 · MAD(Δu) / √2, robust to the
/// few large steps of a maneuver). A noise-free input has σ = 0: the band is the first sample
/// itself, as before. With a noisy surface transducer the trim becomes the mean of the whole
/// quiet lead-in instead of one noisy sample, which otherwise biases every offset-free estimate.
/// A lead-in shorter than [`MIN_NOISY_LEAD_IN`] samples is not a trim but an input that moves
/// from the start (a multisine, a chirp): then only samples equal to the first count.
fn trim_offsets(u: &[f64], y: &[f64]) -> (f64, f64) {
    let band = 5.0 * crate::signal::difference_noise_std(u);
    let quiet = |band: f64| u.iter().take_while(|x| (**x - u[0]).abs() <= band).count();
    let still = match quiet(band) {
        n if n >= MIN_NOISY_LEAD_IN => n,
        _ => quiet(0.0).max(1),
    };
    let n = still as f64;
    // u as u₀ + mean deviation: exactly u₀ when the lead-in is constant
    let u0 = u[0] + u[..still].iter().map(|x| x - u[0]).sum::<f64>() / n;
    (u0, y[..still].iter().sum::<f64>() / n)
}

/// Fewest samples of a noisy quiet lead-in that [`trim_offsets`] averages as the trim.
const MIN_NOISY_LEAD_IN: usize = 10;

/// Largest model order accepted: the output-error sensitivities filter by `A(s)²`, and the state
/// filters are specialised up to order 2 × 32 (see [`filter::Svf`]).
pub const MAX_POLES: usize = 32;

/// Identifies a continuous transfer function from input `u` to output `y` sampled every
/// `dt_s` seconds with the estimator and orders in `opts`.
pub fn identify(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    opts: &IdentOptions,
) -> Result<IdentResult, IdentError> {
    validate(u, y, dt_s, opts)?;
    let (u_offset, y_offset) = trim_offsets(u, y);
    let u: Vec<f64> = u.iter().map(|x| x - u_offset).collect();
    let y: Vec<f64> = y.iter().map(|x| x - y_offset).collect();
    let (n, m) = (opts.poles, opts.zeros);
    let mut model = if opts.estimate_delay {
        delay::with_delay_search(&u, &y, dt_s, opts)?
    } else {
        estimate(&u, &y, dt_s, opts.method, n, m, 0.0)?
    };
    if opts.method == Method::Srivc && model.cov.is_none() {
        model.cov = oe::covariance(&u, &y, dt_s, &model);
    }
    let record_s = u.len() as f64 * dt_s;
    if let Some(p) = linalg::roots(&model.den)
        .into_iter()
        .find(|p| p.re * record_s > 3.0)
    {
        model.warnings.push(format!(
            "pole {p:.4} grows {:.1e}-fold over the {record_s:.1} s record: the model does not describe these \
             data (wrong order, an input that does not drive this output, or direct feedthrough?)",
            (p.re * record_s).exp()
        ));
    }
    Ok(metrics::build_result(
        opts.method,
        model,
        &u,
        &y,
        dt_s,
        opts.estimate_delay,
        u_offset,
        y_offset,
    ))
}

/// Simulated response of the continuous `num/den` (den monic, highest power first, degree of
/// num below that of den) to a zero-order-hold input sampled every `dt_s`, from rest.
pub fn simulate_tf(num: &[f64], den_monic: &[f64], u: &[f64], dt_s: f64) -> Vec<f64> {
    filter::simulate(num, den_monic, u, dt_s, 0.0)
}

/// The paper's discrete ARX least squares alone (eq. 59–64): returns
/// `[a₁ … a_n, b₁ … b_nb]` of `y(k) = −Σ a_i y(k−i) + Σ b_j u(k−j)`, solved by pivoted QR.
pub fn arx_least_squares(
    u: &[f64],
    y: &[f64],
    n: usize,
    nb: usize,
) -> Result<Vec<f64>, IdentError> {
    if u.len() != y.len() {
        return Err(IdentError::LengthMismatch {
            input: u.len(),
            output: y.len(),
        });
    }
    if u.len() < 10 * (n + nb) + n.max(nb) {
        return Err(IdentError::TooFewSamples {
            n_samples: u.len(),
            poles: n,
            zeros: nb.saturating_sub(1),
            needed: 10 * (n + nb) + n.max(nb),
        });
    }
    let arx = ls::arx_ls(u, y, n, nb, 0)?;
    Ok(arx.a[1..].iter().chain(arx.b.iter()).copied().collect())
}

/// Runs one estimator at a fixed delay (whole samples for `ls`/`iv`).
pub(crate) fn estimate(
    u: &[f64],
    y: &[f64],
    dt_s: f64,
    method: Method,
    n: usize,
    m: usize,
    delay_s: f64,
) -> Result<ContinuousModel, IdentError> {
    let delay_samples = (delay_s / dt_s).round() as usize;
    match method {
        Method::Ls => Ok(ls::ls(u, y, dt_s, n, m, delay_samples)?.0),
        Method::Iv => iv::iv(u, y, dt_s, n, m, delay_samples),
        Method::Srivc => srivc::srivc(u, y, dt_s, n, m, delay_s),
        Method::Oe => {
            let start = srivc::srivc(u, y, dt_s, n, m, delay_s)?;
            oe::oe(u, y, dt_s, start, false)
        }
    }
}
