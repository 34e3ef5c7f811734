//! The simulator: a trait, the JSBSim bridge (Python subprocess; its messages in [`protocol`]), and a linear-model
//! stand-in.
//!
//! Units: SI and radians inside flightid; feet and knots only at this edge (JSBSim's own units).

pub mod aero_truth;
pub mod atmosphere;
pub mod bridge;
pub mod derived;
pub mod env;
pub mod jsbsim;
pub mod linear;
pub mod linear_model;
pub mod protocol;
pub mod scratch;

use crate::data::FlightRecord;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use jsbsim::JsbsimSim;
pub use linear_model::LinearSim;

/// Feet to metres.
pub const FT_TO_M: f64 = 0.3048;
/// Knots to metres per second.
pub const KTS_TO_M_S: f64 = 1852.0 / 3600.0;

/// Errors of the simulator layer.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The Python environment could not be provided.
    #[error(transparent)]
    Env(#[from] env::EnvError),
    /// The Python process could not be started.
    #[error("could not start the JSBSim bridge with {python}: {source}")]
    Spawn {
        python: String,
        source: std::io::Error,
    },
    /// The bridge process died or stopped answering.
    #[error("the JSBSim bridge process died during '{during}' ({status}){}", if last_output.is_empty() { String::new() } else { format!("; its last output: {last_output}") })]
    Crashed {
        during: String,
        status: String,
        last_output: String,
    },
    /// The aircraft cannot be trimmed at the requested point.
    #[error("trim failed: {0}")]
    TrimFailed(String),
    /// JSBSim does not know the aircraft model.
    #[error("{0}")]
    UnknownModel(String),
    /// Any other error the bridge reported.
    #[error("JSBSim bridge: {kind}: {message}")]
    Bridge { kind: String, message: String },
    /// Malformed traffic between flightid and its bridge.
    #[error("JSBSim bridge protocol error: {0}")]
    Protocol(String),
    /// Request that makes no sense (e.g. fly before trim).
    #[error("{0}")]
    Usage(String),
    /// A loading (`--property`, an aircraft file's `properties`) the model cannot take: bad input.
    #[error("{0}")]
    Loading(String),
}

/// A steady, wings-level trim point.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct TrimPoint {
    /// Altitude above sea level, ft.
    pub altitude_ft: f64,
    /// True airspeed, kts.
    pub speed_kts: f64,
    /// True heading, deg.
    pub heading_deg: f64,
    /// Flight-path angle, deg.
    pub gamma_deg: f64,
    /// Geodetic latitude, deg (gravity grows by 0.5 % from the equator to the poles).
    pub latitude_deg: f64,
    /// How much warmer the day is than the standard atmosphere's, K (JSBSim's `atmosphere/delta-T`): at the same
    /// altitude and true airspeed a warmer day's air is thinner, and the aircraft trims at a higher α.
    #[serde(default)]
    pub temperature_offset_k: f64,
}

impl TrimPoint {
    /// Level flight at an altitude and speed, heading north, on the equator.
    pub fn level(altitude_ft: f64, speed_kts: f64) -> Self {
        TrimPoint {
            altitude_ft,
            speed_kts,
            heading_deg: 0.0,
            gamma_deg: 0.0,
            latitude_deg: 0.0,
            temperature_offset_k: 0.0,
        }
    }
}

/// The trimmed state: what an engineer checks first.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrimState {
    /// Aircraft name.
    pub aircraft: String,
    /// The requested point.
    pub point: TrimPoint,
    /// Angle of attack, rad.
    pub alpha_rad: f64,
    /// Pitch attitude, rad.
    pub theta_rad: f64,
    /// Bank angle, rad.
    pub phi_rad: f64,
    /// Sideslip, rad.
    pub beta_rad: f64,
    /// True airspeed, m/s.
    pub airspeed_m_s: f64,
    /// Altitude above sea level, m.
    pub altitude_m: f64,
    /// Throttle position 0..1.
    pub throttle: f64,
    /// Surface deflections the aero model reads at trim, rad.
    pub surfaces_rad: BTreeMap<String, f64>,
    /// Trim commands (normalised): `pitch-trim`, `aileron`, `rudder`, `throttle`.
    pub commands_norm: BTreeMap<String, f64>,
    /// The trim that found this state.
    #[serde(default)]
    pub method: TrimMethod,
}

/// The trim that found a [`TrimState`] (docs/jsbsim.md, "Trim").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrimMethod {
    /// JSBSim's full trim (FGTrim), one control per acceleration in turn.
    #[default]
    JsbsimFull,
    /// flightid's own: Newton's method on every trim unknown at once, where JSBSim's full trim failed.
    Newton,
}

impl TrimMethod {
    /// How `flightid trim` names it.
    pub fn describe(self) -> &'static str {
        match self {
            TrimMethod::JsbsimFull => "JSBSim's full trim",
            TrimMethod::Newton => "flightid's Newton trim; JSBSim's full trim failed here",
        }
    }
}

/// Input on one surface: deflection relative to trim, one value per simulation step, rad.
/// (`throttle` is accepted too: position relative to trim, 0..1 units.)
#[derive(Debug, Clone)]
pub struct SurfaceInput {
    /// `elevator`, `aileron`, `rudder` (or `throttle`).
    pub surface: String,
    /// Deflection relative to trim for each step, rad (held during the step).
    pub deflection_rad: Vec<f64>,
}

/// The aircraft's state set mid-flight (the start of a multiple-shooting segment, or a perturbation of the
/// initial state of one): after simulation step `step` (0: before the first) the simulation continues from
/// these values (SI; a `None` keeps the simulated value, as do the heading and the horizontal position).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateReset {
    /// Steps flown before the reset (the state of sample `step` is the reset one).
    pub step: usize,
    /// Roll angle, rad.
    pub phi_rad: Option<f64>,
    /// Pitch angle, rad.
    pub theta_rad: Option<f64>,
    /// Body rates p, q, r, rad/s.
    pub rates_rad_s: Option<[f64; 3]>,
    /// Air-relative velocity (no wind): airspeed m/s, angle of attack rad, sideslip rad.
    pub airspeed_alpha_beta: Option<(f64, f64, f64)>,
    /// Altitude above sea level, m.
    pub altitude_m: Option<f64>,
    /// Body-axis velocity components u, v, w, m/s.
    pub uvw_m_s: Option<[f64; 3]>,
    /// The values are increments to the simulated state (`airspeed_alpha_beta` is then not allowed).
    pub relative: bool,
}

/// Lowest integration rate a flight uses by default, Hz.
pub const MIN_SIM_RATE_HZ: f64 = 120.0;

/// The integration rate for a logging rate `log_rate_hz` and the number of integration steps per logged
/// sample: `requested_hz` when given, else the logging rate if it is at least [`MIN_SIM_RATE_HZ`], else its
/// smallest whole multiple at or above it. `None` when the rate is not a whole multiple of the logging rate or
/// is above 2000 Hz.
pub fn simulation_rate(log_rate_hz: f64, requested_hz: Option<f64>) -> Option<(f64, usize)> {
    let sim_hz = requested_hz
        .unwrap_or_else(|| log_rate_hz * (MIN_SIM_RATE_HZ / log_rate_hz).ceil().max(1.0));
    let ratio = sim_hz / log_rate_hz;
    let step = ratio.round();
    (sim_hz.is_finite() && sim_hz <= 2000.0 && step >= 1.0 && (ratio - step).abs() < 1e-9)
        .then_some((sim_hz, step as usize))
}

/// A maneuver to fly from trim.
#[derive(Debug, Clone)]
pub struct FlightPlan {
    /// Simulation and sampling rate, Hz.
    pub rate_hz: f64,
    /// Number of simulation steps (the record has `n_steps + 1` samples; sample 0 is the trim state).
    pub n_steps: usize,
    /// Surface inputs (several at once are allowed).
    pub inputs: Vec<SurfaceInput>,
}

impl FlightPlan {
    /// The unit-peak `maneuver` ([`crate::signal::generate`], from `start_s`) scaled to `amplitude_rad` on each
    /// of `surfaces`, for `duration_s` at `rate_hz`.
    pub fn maneuver(
        surfaces: &[&str],
        maneuver: &crate::signal::Maneuver,
        amplitude_rad: f64,
        start_s: f64,
        duration_s: f64,
        rate_hz: f64,
    ) -> FlightPlan {
        let n_steps = (duration_s * rate_hz).round() as usize;
        let mut unit = crate::signal::generate(maneuver, 1.0 / rate_hz, duration_s, start_s);
        unit.resize(n_steps, 0.0);
        FlightPlan {
            rate_hz,
            n_steps,
            inputs: surfaces
                .iter()
                .map(|s| SurfaceInput {
                    surface: s.to_string(),
                    deflection_rad: unit.iter().map(|u| u * amplitude_rad).collect(),
                })
                .collect(),
        }
    }
}

/// A linear model from the simulator: ẋ = A x + B u, y = C x + D u.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Linearization {
    /// State names.
    pub states: Vec<String>,
    /// State units.
    pub state_units: Vec<String>,
    /// Input names.
    pub inputs: Vec<String>,
    /// Input units (`rad` for surfaces linearized per radian, `norm` for commands).
    pub input_units: Vec<String>,
    /// Output names.
    pub outputs: Vec<String>,
    /// Output units.
    pub output_units: Vec<String>,
    /// System matrix, row-major.
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// Input matrix.
    #[serde(rename = "B")]
    pub b: Vec<Vec<f64>>,
    /// Output matrix.
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// Feedthrough matrix.
    #[serde(rename = "D")]
    pub d: Vec<Vec<f64>>,
}

/// Something that can be trimmed, linearized and flown: JSBSim, or a linear model standing in for it.
pub trait Simulator {
    /// Trims at a point; a failure is an error, never a garbage state.
    fn trim(&mut self, point: &TrimPoint) -> Result<TrimState, SimError>;
    /// Linear model at the current trim, inputs per radian of surface deflection where possible.
    fn linearize(&mut self) -> Result<Linearization, SimError>;
    /// Flies a maneuver from the current trim and returns the flight-data record (docs/data.md).
    fn fly(&mut self, plan: &FlightPlan) -> Result<FlightRecord, SimError>;
}
