//! The one estimation core: grey-box models fitted to measured records by output error (and
//! filter error), with the nuisance terms every measured record carries.
//!
//! - [`Model`] is what the core fits: it simulates one record for a parameter vector. A model
//!   written as `ẋ = f(x, u, θ)`, `y = h(x, u, θ)` implements [`StateModel`] and gets its
//!   simulation from [`simulate_states`] (fixed-step RK4 at its own step, split at the input's
//!   breakpoints).
//! - [`fit`] runs bounded Levenberg–Marquardt on the maximum-likelihood output-error cost with the
//!   measurement-noise covariance estimated from the residuals between steps (the relaxation
//!   algorithm: Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., §4.7–4.9; Morelli &
//!   Klein, *Aircraft System Identification*, 2nd ed., §6.2), and returns Cramér–Rao bounds
//!   corrected for coloured residuals ([`covariance`]).
//! - Nuisance terms ([`Nuisance`]): initial states, output biases and input biases per record, and
//!   a time skew per input shared by all records. Several records are fitted jointly: one model
//!   parameter vector, nuisance terms per record.
//! - Inputs are reconstructed between samples by a declared [`InputHold`] (linear interpolation by
//!   default, zero-order hold on request).
//!
//! The contract and how to plug in a model: `docs/estimate.md`.

pub mod covariance;
pub mod expr;
pub(crate) mod fem;
mod fit;
mod integrate;
mod layout;
mod linear;
mod model;
mod record;
mod report;
pub mod riccati;
mod start;
mod subspace;
mod summary;
mod user_model;

pub use fit::{fit, Estimate, Method, Options, ParameterEstimate, RecordFit, StopReason};
pub use integrate::simulate_states;
pub use layout::{Nuisance, NuisanceKind};
pub use linear::{Entry, LinearModel};
pub use model::{Discrete, Model, Parameter, Signature, SimError, StateModel};
pub use record::{InputHold, InputSignal, Record, Run};
pub use start::{start_values, StartValues};
pub use subspace::{subspace, SubspaceModel, SubspaceOptions, SubspaceRecord};
pub use summary::HIGH_CORRELATION;
pub use user_model::{ModelFileError, UserModel};

/// What went wrong in an estimation, with what the user needs to fix it.
#[derive(Debug, thiserror::Error)]
pub enum EstimateError {
    /// The problem is inconsistent (dimensions, names, bounds).
    #[error("invalid estimation problem: {0}")]
    Invalid(String),
    /// A record does not fit the model (length, sampling, a missing column).
    #[error("record '{record}': {reason}")]
    Record {
        /// Record name (usually its file).
        record: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The model cannot be simulated at the start values.
    #[error("the model cannot be simulated at the start values on record '{record}': {source}")]
    StartDiverges {
        /// Record name.
        record: String,
        /// The simulation failure.
        source: SimError,
    },
    /// The information matrix is singular: some parameters are not identifiable from these records.
    #[error("the information matrix is singular: {0}")]
    Singular(String),
    /// The fit ended with a cost that is not a number: nothing it estimated is an estimate.
    #[error("the fit diverged: its cost is {cost} after {iterations} iterations; the records hold values the \
             model cannot follow, or the start values are far off")]
    Diverged {
        /// The final cost.
        cost: f64,
        /// Iterations taken.
        iterations: usize,
    },
    /// The iterations stopped before the fit converged: its values are not estimates.
    #[error("the fit did not converge ({stop:?} after {iterations} iterations, cost {cost:.6e}): its values are \
             not estimates. Check that the records excite every parameter (a surface that moves), or start \
             nearer (parameters \"auto\" in the model file)")]
    NotConverged {
        /// Why the iterations stopped.
        stop: StopReason,
        /// Iterations taken.
        iterations: usize,
        /// The final cost.
        cost: f64,
    },
}

#[cfg(test)]
mod tests;
