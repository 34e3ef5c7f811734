//! Linear time-invariant systems: transfer functions, state space, conversions, simulation,
//! frequency response and modal parameters.
//!
//! Vocabulary follows python-control (`TransferFunction`, `StateSpace`, `ss2tf`, `c2d`); polynomial
//! coefficients are stored highest power first, as there.

mod discretize;
mod modes;
mod poly;
mod sim;
mod ss;
mod tf;

pub use discretize::{c2d, c2d_tf, d2c, d2c_tf, expm, expm_rows, log1pm, logm, Discretization};
pub use modes::{modes, modes_discrete, Mode};
pub use poly::{
    poly_add, poly_from_roots, poly_mul, polyval, polyval_complex, roots, strip_leading,
};
pub use sim::{lsim, lsim_ss};
pub use ss::{charpoly, mat_to_rows, ss2tf, tf2ss, Rows, StateSpace, StateSpaceRows};
pub use tf::{bode, TransferFunction, LEADING_ZERO_REL_TOL};

/// What can go wrong with a linear model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LtiError {
    /// A matrix has the wrong shape for the model.
    #[error("matrix {matrix} must be {expected_rows}x{expected_cols}, got {got}")]
    Dimension {
        matrix: &'static str,
        expected_rows: usize,
        expected_cols: usize,
        got: String,
    },
    /// A matrix holds NaN or infinity.
    #[error("matrix {what} holds a NaN or infinite entry")]
    NonFinite { what: &'static str },
    /// A state, input or output index does not exist.
    #[error("{what} index {index} out of range: the model has {count}")]
    IndexOutOfRange {
        what: &'static str,
        index: usize,
        count: usize,
    },
    /// A discrete-time operation was asked of a continuous model.
    #[error(
        "the model is continuous-time; this conversion needs a discrete-time model (dt_s set)"
    )]
    NotDiscrete,
    /// The sample period is not a positive finite number.
    #[error("sample period must be a positive finite number of seconds, got {dt_s}")]
    BadSamplePeriod { dt_s: f64 },
    /// A discrete pole has no continuous counterpart under the requested method.
    #[error(
        "discrete pole z = {pole_re}{pole_im:+}i lies on the closed negative real axis (or at z = -1 \
         for Tustin): no continuous-time model maps to it"
    )]
    NoRealLogarithm { pole_re: f64, pole_im: f64 },
    /// An iterative matrix function did not converge.
    #[error("{what} did not converge")]
    NoConvergence { what: &'static str },
}

#[cfg(test)]
mod tests;
