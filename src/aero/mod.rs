//! The paper's parametric linear aircraft model: aerodynamic derivatives ⇄ state space ⇄ transfer functions.
//!
//! Şahin & Kalyon (2021) back aerodynamic derivatives out of identified transfer functions through a
//! small-perturbation model around a steady trim (their eq. 21–33 longitudinal, eq. 38–53 lateral). Their expanded
//! coefficient formulas contain typos, so this module builds the model from the textbook equations instead
//! (Etkin & Reid, *Dynamics of Flight*, §4.9 and §5.4; Nelson, *Flight Stability and Automatic Control*, §4.2, §5.2)
//! in the descriptor form the paper uses, `C ẋ = A x + B u`, and obtains the transfer functions numerically.
//!
//! - [`params`]: flight condition, mass, geometry, the named nondimensional [`Derivative`]s and the switchable
//!   simplifying [`Assumptions`].
//! - [`model`]: longitudinal (u, α, q, θ) and lateral (β, p, r, φ) state space, θ/δe, φ/δa, φ/δr, modes.
//! - [`fit`]: derivatives from identified transfer functions by Levenberg–Marquardt, with covariance.
//! - [`identifiability`]: which derivatives a set of transfer functions determines, in plain words.
//! - [`airframe`]: an aircraft's mass, inertia, geometry, thrust line and sensor positions (`--airframe`).
//! - [`flight_models`]: the nondimensional longitudinal and lateral models fitted to measured records.
//! - [`measured`]: derivatives from measured records of any aircraft (air data, sensors moved to the CG).
//! - [`output_error`]: the flight models fitted to measured records by the estimation core (output error).
//! - [`regression`]: equation-error estimates from flight-data channels (SIDPAC `lesq` style) and the
//!   Savitzky–Golay differentiator it needs.
//!
//! Typical use: build an [`AeroModel`] (lateral derivatives and inertia in stability axes — convert body-axis
//! values with [`Derivatives::body_to_stability`] and [`MassProperties::to_stability_axes`]), get
//! `model.paper_transfer_functions()` or `model.longitudinal()?.modes()`, run
//! [`analyse_identifiability`] to see what a manoeuvre can determine, then [`estimate_derivatives`] from
//! identified transfer functions, or [`equation_error`] from flight-data channels.
//!
//! Transfer functions come from `crate::lti::ss2tf`. The JSBSim derivative study (truth, trials, scores,
//! attribution) that builds on this model is [`crate::study`].

pub mod airframe;
pub mod coefficients;
pub mod fit;
pub mod flight_models;
pub mod identifiability;
pub mod measured;
pub mod model;
pub mod output_error;
pub mod params;
pub mod regression;

pub use airframe::{Airframe, AirframeError};
pub use fit::{estimate_derivatives, DerivativeEstimate, FitOptions, IdentifiedTf, IdentifiedTfs};
pub use identifiability::{
    analyse_identifiability, DerivativeVerdict, IdentifiabilityReport, Verdict,
};
pub use model::{AeroModel, Axis, LinearModel, Mode, TfCoefficients, TfOutput};
pub use params::{
    Assumptions, Derivative, Derivatives, FlightCondition, Geometry, MassProperties, ThrustModel,
};
pub use regression::{
    equation_error, savitzky_golay_derivative, savitzky_golay_smooth, EquationErrorOptions,
    EquationErrorResult, FlightRecord, RegressionResult, RegressionTerm,
};

/// Everything that can go wrong in the aero module, with the context a user needs to fix it.
#[derive(Debug, thiserror::Error)]
pub enum AeroError {
    /// A physical parameter is missing, zero, negative or not finite.
    #[error("{name} must be a positive finite number (got {value}); set it in the aircraft configuration")]
    BadParameter {
        /// Parameter name with its unit.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A derivative name that the model does not have.
    #[error("unknown derivative name `{0}`; known names: {known}", known = params::Derivative::ALL.iter().map(|d| d.name()).collect::<Vec<_>>().join(", "))]
    UnknownDerivative(String),
    /// An identified transfer function whose order does not match the model.
    #[error("{tf}: {problem}")]
    WrongTfOrder {
        /// Which transfer function (e.g. `theta/elevator`).
        tf: String,
        /// What is wrong and what the model expects.
        problem: String,
    },
    /// A covariance matrix of the wrong size or not positive definite.
    #[error("{tf}: covariance {problem}")]
    BadCovariance {
        /// Which transfer function.
        tf: String,
        /// What is wrong.
        problem: String,
    },
    /// Nothing to fit: no transfer function or no free derivative.
    #[error("nothing to estimate: {0}")]
    NothingToFit(String),
    /// A flight-data channel the estimator needs is missing or has the wrong length.
    #[error("flight record: {0}")]
    BadRecord(String),
    /// A numerical step (SVD, eigenvalues) failed.
    #[error("numerical failure in {0}")]
    Numerical(&'static str),
    /// Unusable user input (a file, an option) with what is wrong.
    #[error("{0}")]
    BadInput(String),
    /// The simulator failed while flying the estimation manoeuvres.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// Identification of a transfer function failed.
    #[error("identifying {tf}: {source}")]
    Ident {
        /// Which transfer function.
        tf: String,
        /// The estimator's error.
        source: crate::ident::IdentError,
    },
}
