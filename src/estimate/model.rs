//! The model trait the core fits, and the state-space form most models take.

use super::record::{InputHold, Run};

/// Names of a model's parameters, states, inputs and outputs, in the order the model uses them.
///
/// Inputs and outputs are flight-data columns (`elevator_rad`, `q_rad_s`, …); states are the
/// model's own (for models written in schema columns they are columns too, and a record gives
/// their initial values).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Signature {
    /// Model parameters θ (every one; the fit decides which are free).
    pub parameters: Vec<String>,
    /// States x (empty for a model without an initial state to estimate).
    pub states: Vec<String>,
    /// Inputs u, as columns of the record.
    pub inputs: Vec<String>,
    /// Outputs y, as columns of the record.
    pub outputs: Vec<String>,
}

/// One model parameter as the fit sees it: start value, bounds, fixed or free.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name (as in [`Signature::parameters`]).
    pub name: String,
    /// Start value (the value used throughout when `fixed`).
    pub value: f64,
    /// Lower bound (−∞ for none).
    pub lower: f64,
    /// Upper bound (+∞ for none).
    pub upper: f64,
    /// Held at `value`, not estimated.
    pub fixed: bool,
    /// For a held parameter whose value is not known exactly: its standard deviation about `value`, carried
    /// into the free parameters' covariance as a consider parameter ([`Parameter::considered`]).
    pub consider_std: Option<f64>,
}

impl Parameter {
    /// A free, unbounded parameter.
    pub fn free(name: impl Into<String>, value: f64) -> Parameter {
        Parameter {
            name: name.into(),
            value,
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            fixed: false,
            consider_std: None,
        }
    }

    /// A parameter held at `value`.
    pub fn fixed(name: impl Into<String>, value: f64) -> Parameter {
        Parameter {
            fixed: true,
            ..Parameter::free(name, value)
        }
    }

    /// The same held parameter with an uncertainty σ about its value that the free parameters' covariance
    /// carries (consider covariance: Tapley, Schutz & Born, *Statistical Orbit Determination*, ch. 6).
    /// Holding a term the records cannot separate from the free ones (C_mα̇ beside C_mα and C_mq) moves
    /// those by ∂φ̂/∂c per unit of its error, ∂φ̂/∂c = −(SᵀR⁻¹S)⁻¹ SᵀR⁻¹ s_c with s_c its sensitivity column, and the covariance
    /// reported becomes P + σ² (∂φ̂/∂c)(∂φ̂/∂c)ᵀ. The estimates themselves do not change.
    pub fn considered(self, std: f64) -> Parameter {
        Parameter {
            consider_std: Some(std),
            ..self
        }
    }

    /// The same parameter with bounds.
    pub fn bounded(self, lower: f64, upper: f64) -> Parameter {
        Parameter {
            lower,
            upper,
            ..self
        }
    }
}

/// Why a simulation failed. The fit treats it as a rejected step; at the start values it is an
/// error for the user.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A state or output left the finite numbers (or exceeded 1e12).
    #[error("the simulation diverges at t = {time_s:.3} s ({what})")]
    Diverged {
        /// Time of the first non-finite value, seconds from the record start.
        time_s: f64,
        /// Which state or output.
        what: String,
    },
    /// The model failed for a reason of its own (an external simulator, a table out of range).
    #[error("{0}")]
    Failed(String),
}

/// A model the core can fit: it simulates one record for a parameter vector.
///
/// Implementations must be deterministic (the same `theta` and run give the same outputs, bit for
/// bit): finite-difference sensitivities depend on it. `Sync` because the core simulates the
/// perturbed parameter vectors in parallel (see [`Model::parallel`]).
pub trait Model: Sync {
    /// Parameter, state, input and output names.
    fn signature(&self) -> &Signature;

    /// Outputs at the run's sample times, one `Vec` per output (`[output][k]`, each of length
    /// `run.time_s.len()`), for parameters `theta` (all of them, in signature order) and initial
    /// state `x0` (length = number of states).
    ///
    /// The inputs are read through `run.input` (biases removed, skews and the declared hold
    /// applied by the core). Return [`SimError`] instead of non-finite numbers.
    fn simulate(&self, theta: &[f64], x0: &[f64], run: &Run<'_>)
        -> Result<Vec<Vec<f64>>, SimError>;

    /// Analytic sensitivities `∂y/∂θ_j` for the listed parameter indices, `[j][output][k]`, if the
    /// model has them. `None` (the default): the core uses finite differences.
    fn sensitivities(
        &self,
        _theta: &[f64],
        _x0: &[f64],
        _run: &Run<'_>,
        _params: &[usize],
    ) -> Option<Result<Vec<Vec<Vec<f64>>>, SimError>> {
        None
    }

    /// The state-space form, if the model has one (the filter error method needs it).
    fn state_model(&self) -> Option<&dyn StateModel> {
        None
    }

    /// Whether the core may simulate this model from several threads at once (default true).
    /// A model driving one external process returns false.
    fn parallel(&self) -> bool {
        true
    }
}

/// A continuous-time model `ẋ = f(x, u, θ)`, `y = h(x, u, θ)`.
///
/// Implement this, then [`Model`] with [`model_from_state_model!`](crate::model_from_state_model) (or by hand
/// when the model simulates itself another way, as [`super::LinearModel`] does).
pub trait StateModel: Sync {
    /// Parameter, state, input and output names.
    fn signature(&self) -> &Signature;
    /// `dx = f(x, u, θ)`.
    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]);
    /// `y = h(x, u, θ)`.
    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]);

    /// The exact transition over one sample interval `dt_s` for the declared hold, if the model
    /// is linear and has it (see [`Discrete`]). The default `None`: the core integrates `f`.
    fn discrete(&self, _theta: &[f64], _dt_s: f64, _hold: InputHold) -> Option<Discrete> {
        None
    }
}

/// A linear model's exact transition over one sample interval `h` (Franklin, Powell & Workman,
/// *Digital Control of Dynamic Systems*, 3rd ed., §6.3.2): `x_{k+1} = Φ x_k + Γ₁ u_k + Γ₂ (u_{k+1}
/// − u_k)` with `Γ₂ = 0` for a zero-order hold. Row-major: `phi` n×n, `gamma1`, `gamma2` n×m.
#[derive(Clone, Debug, PartialEq)]
pub struct Discrete {
    /// Φ = e^{A h}.
    pub phi: Vec<f64>,
    /// Γ₁ = ∫₀ʰ e^{A s} ds B.
    pub gamma1: Vec<f64>,
    /// Γ₂ (linear interpolation's ramp term; zeros for a zero-order hold).
    pub gamma2: Vec<f64>,
}
