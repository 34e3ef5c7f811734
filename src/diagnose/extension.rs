//! The catalogue of model extensions: one small type per effect (docs/diagnose.md vocabulary).
//!
//! An extension acts at one of three places of the replay: on the model before trimming (aerodynamic
//! coefficient scales), on the surface inputs before simulating (signal path), or on the simulated
//! outputs (sensors). The search in [`super::search`] only sees the [`Extension`] trait, so a new effect
//! is a new type here and one line in [`catalogue`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::replay::ReplaySim;
use super::DiagnoseError;
use crate::data::FlightRecord;
use crate::sim::SimError;

/// Where in the replay an extension acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// On the model, before trimming (needs a new trim and a new simulation).
    Model,
    /// On a surface input sequence, before simulating (needs a new simulation).
    Input,
    /// On a simulated output column (no new simulation).
    Output,
}

/// One parameter of an extension: the value that means "no effect", its bounds and a finite-difference step.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// Value at which the extension changes nothing.
    pub null: f64,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// Finite-difference step for sensitivities (parameter units).
    pub fd_step: f64,
}

/// A model extension: an effect on a target with parameters fitted by output error.
pub trait Extension: Send + Sync {
    /// Effect name from the docs/diagnose.md vocabulary (`input_delay`, `sensor_bias`, ...).
    fn effect(&self) -> &'static str;
    /// Target: a surface, a CSV column or a derivative name.
    fn target(&self) -> &str;
    /// Where the extension acts.
    fn stage(&self) -> Stage;
    /// Parameter specifications (the first one is the reported `value`).
    fn params(&self) -> Vec<ParamSpec>;
    /// CSV columns the extension needs in the measured record.
    fn required_columns(&self) -> Vec<String>;
    /// Changes the model before trimming (Stage::Model).
    fn apply_model(&self, _p: &[f64], _sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        Ok(())
    }
    /// Changes the deviation sequence of `surface` (sampled at `dt_s`, sample 0 = initial condition, value 0).
    fn apply_input(&self, _p: &[f64], _surface: &str, _dev: &mut [f64], _dt_s: f64) {}
    /// Changes the simulated record (Stage::Output).
    fn apply_output(&self, _p: &[f64], _rec: &mut FlightRecord) {}
}

/// Pure time delay of a surface deflection: the aircraft responds to δ(t − τ). Value: τ, s.
pub struct InputDelay(pub String);
/// First-order actuator lag τ ẋ = δ − x between the measured deflection and the one the aero model sees. Value: τ, s.
pub struct ActuatorLag(pub String);
/// Factor on a surface's aerodynamic effect (the deflection deviation the model sees is k·δ). Value: k.
pub struct ControlEffectiveness(pub String);
/// Additive offset on a measured column. Value: offset in column units.
pub struct SensorBias(pub String);
/// Factor on a measured column (measured = k · true). Value: k.
pub struct SensorScale(pub String);
/// Factor on one aerodynamic coefficient function of the simulation. Value: factor.
pub struct AeroDerivative {
    /// docs/diagnose.md name, e.g. `Cm_alpha`.
    pub name: String,
    /// The simulation's coefficient (knob) name, e.g. `Cmalpha`.
    pub knob: String,
}

/// An added aerodynamic term the simulation's model lacks, e.g. `Cm_alpha2`: ΔC_m = k α² (α in rad).
/// Value: the coefficient k.
pub struct AeroNonlinearity(pub String);

impl Extension for AeroNonlinearity {
    fn effect(&self) -> &'static str {
        "aero_nonlinearity"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Model
    }
    fn params(&self) -> Vec<ParamSpec> {
        // |k| ≤ 100: at α = 0.2 rad that is a ΔC of 4, far beyond any plausible correction.
        vec![ParamSpec {
            null: 0.0,
            min: -100.0,
            max: 100.0,
            fd_step: 0.2,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        Vec::new()
    }
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        sim.set_added_term(&self.0, p[0])
    }
}

fn surface_column(surface: &str) -> String {
    if surface == "throttle" {
        "throttle".into()
    } else {
        format!("{surface}_rad")
    }
}

impl Extension for InputDelay {
    fn effect(&self) -> &'static str {
        "input_delay"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Input
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 0.0,
            min: 0.0,
            max: 1.0,
            fd_step: 0.005,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![surface_column(&self.0)]
    }
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], dt_s: f64) {
        if surface != self.0 {
            return;
        }
        // δ_d(t_k) = δ(t_k − τ), linear interpolation between samples, δ = 0 before the record.
        let shift = p[0].max(0.0) / dt_s;
        let whole = shift.floor() as usize;
        let frac = shift - whole as f64;
        let src = dev.to_vec();
        let at = |j: isize| -> f64 {
            if j < 0 {
                0.0
            } else {
                src[(j as usize).min(src.len() - 1)]
            }
        };
        for (k, v) in dev.iter_mut().enumerate() {
            let j = k as isize - whole as isize;
            *v = (1.0 - frac) * at(j) + frac * at(j - 1);
        }
    }
}

impl Extension for ActuatorLag {
    fn effect(&self) -> &'static str {
        "actuator_lag"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Input
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 0.0,
            min: 0.0,
            max: 2.0,
            fd_step: 0.005,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![surface_column(&self.0)]
    }
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], dt_s: f64) {
        if surface != self.0 || p[0] <= 0.0 {
            return;
        }
        // τ ẋ = δ − x, discretised exactly for the input the simulation applies: sample k is held over the
        // step that ends at it (zero-order hold; Franklin, Powell & Workman, Digital Control of Dynamic
        // Systems, §6.3.1): x_k = a x_{k−1} + (1 − a) δ_k, a = e^{−Δt/τ}.
        let a = (-dt_s / p[0]).exp();
        let mut x = 0.0;
        for v in dev.iter_mut() {
            x = a * x + (1.0 - a) * *v;
            *v = x;
        }
    }
}

impl Extension for ControlEffectiveness {
    fn effect(&self) -> &'static str {
        "control_effectiveness"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Input
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 1.0,
            min: 0.1,
            max: 3.0,
            fd_step: 0.01,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![surface_column(&self.0)]
    }
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], _dt_s: f64) {
        if surface == self.0 {
            dev.iter_mut().for_each(|v| *v *= p[0]);
        }
    }
}

impl Extension for SensorBias {
    fn effect(&self) -> &'static str {
        "sensor_bias"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Output
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 0.0,
            min: -1e6,
            max: 1e6,
            fd_step: 1e-3,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![self.0.clone()]
    }
    fn apply_output(&self, p: &[f64], rec: &mut FlightRecord) {
        if let Some((_, col)) = rec.columns.iter_mut().find(|(n, _)| *n == self.0) {
            col.iter_mut().for_each(|v| *v += p[0]);
        }
    }
}

impl Extension for SensorScale {
    fn effect(&self) -> &'static str {
        "sensor_scale"
    }
    fn target(&self) -> &str {
        &self.0
    }
    fn stage(&self) -> Stage {
        Stage::Output
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 1.0,
            min: 0.2,
            max: 5.0,
            fd_step: 0.01,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![self.0.clone()]
    }
    fn apply_output(&self, p: &[f64], rec: &mut FlightRecord) {
        if let Some((_, col)) = rec.columns.iter_mut().find(|(n, _)| *n == self.0) {
            col.iter_mut().for_each(|v| *v *= p[0]);
        }
    }
}

impl Extension for AeroDerivative {
    fn effect(&self) -> &'static str {
        "aero_derivative"
    }
    fn target(&self) -> &str {
        &self.name
    }
    fn stage(&self) -> Stage {
        Stage::Model
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec {
            null: 1.0,
            min: 0.2,
            max: 4.0,
            fd_step: 0.02,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        Vec::new()
    }
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        sim.set_coefficient_scale(&self.knob, p[0])
    }
}

/// docs/diagnose.md derivative names and the coefficient function names of JSBSim's c172x that carry them.
pub const DERIVATIVE_KNOBS: [(&str, &str); 23] = [
    ("CL_alpha", "CLwbh"),
    ("CL_q", "CLq"),
    ("CL_alphadot", "CLadot"),
    ("CL_de", "CLDe"),
    ("CD_0", "CDo"),
    ("Cm_0", "Cmo"),
    ("Cm_alpha", "Cmalpha"),
    ("Cm_q", "Cmq"),
    ("Cm_alphadot", "Cmadot"),
    ("Cm_de", "Cmde"),
    ("CY_beta", "CYb"),
    ("Cl_beta", "Clb"),
    ("Cl_p", "Clp"),
    ("Cl_r", "Clr"),
    ("Cl_da", "Clda"),
    ("Cl_dr", "Cldr"),
    ("Cn_beta", "Cnb"),
    ("Cn_p", "Cnp"),
    ("Cn_r", "Cnr"),
    ("Cn_da", "Cnda"),
    ("Cn_dr", "Cndr"),
    ("CY_p", "CYp"),
    ("CY_r", "CYr"),
];

/// Output columns that may carry a sensor bias or scale. Airspeed and altitude are not among them: they set
/// the trim point of the replay, so an error in them shows as a trim mismatch instead.
pub const SENSOR_COLUMNS: [&str; 10] = [
    "phi_rad",
    "theta_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "alpha_rad",
    "beta_rad",
    "ax_m_s2",
    "ay_m_s2",
    "az_m_s2",
];

/// Builds one extension from its effect and target names (the `--extension` file and the catalogue use it).
pub fn make(
    effect: &str,
    target: &str,
    coefficient_names: &[String],
) -> Result<Box<dyn Extension>, DiagnoseError> {
    let surface = || -> Result<String, DiagnoseError> {
        match target {
            "elevator" | "aileron" | "rudder" | "throttle" => Ok(target.to_string()),
            _ => Err(DiagnoseError::UnknownExtension(format!(
                "{effect} needs a surface target (elevator, aileron, rudder, throttle), got '{target}'"
            ))),
        }
    };
    Ok(match effect {
        "input_delay" => Box::new(InputDelay(surface()?)),
        "actuator_lag" => Box::new(ActuatorLag(surface()?)),
        "control_effectiveness" => Box::new(ControlEffectiveness(surface()?)),
        "sensor_bias" => Box::new(SensorBias(target.to_string())),
        "sensor_scale" => Box::new(SensorScale(target.to_string())),
        "aero_derivative" => {
            let knob = DERIVATIVE_KNOBS
                .iter()
                .find(|(n, _)| *n == target)
                .map(|(_, k)| k.to_string())
                .unwrap_or_else(|| target.to_string());
            if !coefficient_names.contains(&knob) {
                return Err(DiagnoseError::UnknownExtension(format!(
                    "the simulation has no aerodynamic coefficient for '{target}'"
                )));
            }
            Box::new(AeroDerivative {
                name: target.to_string(),
                knob,
            })
        }
        "aero_nonlinearity" => Box::new(AeroNonlinearity(target.to_string())),
        other => {
            return Err(DiagnoseError::UnknownExtension(format!(
            "unknown effect '{other}' (known: input_delay, actuator_lag, control_effectiveness, \
                 sensor_bias, sensor_scale, aero_derivative, aero_nonlinearity)"
        )))
        }
    })
}

/// A catalogue entry left out: (effect, target, reason).
pub type SkippedEntry = (String, String, String);

/// The full catalogue for a record and a simulation: signal path per surface, sensors per column,
/// derivative scales the simulation offers. Returns the usable extensions and the skipped ones with the reason.
pub fn catalogue(
    record: &FlightRecord,
    coefficient_names: &[String],
    added_terms: &[String],
) -> (Vec<Box<dyn Extension>>, Vec<SkippedEntry>) {
    let mut all: Vec<Box<dyn Extension>> = Vec::new();
    for s in ["elevator", "aileron", "rudder", "throttle"] {
        all.push(Box::new(InputDelay(s.into())));
        all.push(Box::new(ActuatorLag(s.into())));
        all.push(Box::new(ControlEffectiveness(s.into())));
    }
    for c in SENSOR_COLUMNS {
        all.push(Box::new(SensorBias(c.into())));
        all.push(Box::new(SensorScale(c.into())));
    }
    let mut skipped = Vec::new();
    for (name, knob) in DERIVATIVE_KNOBS {
        if coefficient_names.iter().any(|k| k == knob) {
            all.push(Box::new(AeroDerivative {
                name: name.into(),
                knob: knob.into(),
            }));
        } else {
            skipped.push((
                "aero_derivative".to_string(),
                name.to_string(),
                format!("the simulation has no coefficient knob '{knob}'"),
            ));
        }
    }
    for t in added_terms {
        all.push(Box::new(AeroNonlinearity(t.clone())));
    }
    let mut usable = Vec::new();
    for e in all {
        let missing: Vec<String> = e
            .required_columns()
            .into_iter()
            .filter(|c| record.column(c).is_none())
            .collect();
        if !missing.is_empty() {
            skipped.push((
                e.effect().to_string(),
                e.target().to_string(),
                format!("the data have no column {}", missing.join(", ")),
            ));
            continue;
        }
        usable.push(e);
    }
    (usable, skipped)
}

/// Extensions built from a file, each with its parameter values.
pub type BuiltEffects = Vec<(Box<dyn Extension>, Vec<f64>)>;

/// A fitted effect as written to and read from an extension file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FittedEffect {
    /// Effect name.
    pub effect: String,
    /// Target name.
    pub target: String,
    /// Fitted value (first parameter).
    pub value: f64,
    /// Cramér–Rao standard error of the value.
    #[serde(default)]
    pub std_error: f64,
}

/// The extended model: fitted signal-path, sensor and coefficient-scale effects on top of an aircraft.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ExtensionFile {
    /// Aircraft the effects were fitted for.
    pub aircraft: String,
    /// The effects, applied in this order.
    pub effects: Vec<FittedEffect>,
    /// Effects already written into an exported aircraft's XML (documentation only: never applied again).
    #[serde(default)]
    pub model_effects: Vec<FittedEffect>,
    /// Free-form provenance (data file, date).
    #[serde(default)]
    pub notes: BTreeMap<String, String>,
}

impl ExtensionFile {
    /// Reads an extension file (JSON).
    pub fn read(path: &std::path::Path) -> Result<Self, DiagnoseError> {
        let text = std::fs::read_to_string(path).map_err(|e| DiagnoseError::ExtensionFile {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        serde_json::from_str(&text).map_err(|e| DiagnoseError::ExtensionFile {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    }

    /// Builds the extensions with their values.
    pub fn build(&self, coefficient_names: &[String]) -> Result<BuiltEffects, DiagnoseError> {
        self.effects
            .iter()
            .map(|f| {
                Ok((
                    make(&f.effect, &f.target, coefficient_names)?,
                    vec![f.value],
                ))
            })
            .collect()
    }
}
