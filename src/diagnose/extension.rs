//! The catalogue of model extensions: one small type per effect (docs/diagnose.md vocabulary).
//!
//! An extension acts at one of three places of the replay: on the model before trimming (aerodynamic
//! coefficient scales), on the surface inputs before simulating (signal path), or on the simulated
//! outputs (sensors). The search in [`super::search`] only sees the [`Extension`] trait, so a new effect
//! is a new type here and one row in [`REGISTRY`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::simulator::ReplaySim;
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
    /// Smallest departure from `null` worth naming (parameter units): an effect is named only when it is at
    /// least this large and the record determines it to a third of this (Cramér–Rao bound).
    pub resolution: f64,
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
    /// The catalogue entry (effect, target) whose linear term this one refines, e.g. `aero_derivative/CL_alpha`
    /// for `CL_alpha2`. Near a trim point a refinement acts mostly as a change of that term, so its smallest
    /// effect worth naming is measured against that term's resolution on the record (see `select`).
    fn refines(&self) -> Option<(&'static str, String)> {
        None
    }
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
            resolution: 1.0,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        Vec::new()
    }
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        sim.set_added_term(&self.0, p[0])
    }
    fn refines(&self) -> Option<(&'static str, String)> {
        // `Cm_alpha2` (k α²) refines `Cm_alpha`: around α₀ it adds the slope 2kα₀ and the offset kα₀².
        self.0
            .strip_suffix('2')
            .map(|linear| ("aero_derivative", linear.to_string()))
    }
}

/// Smallest sensor bias worth naming, by the column's unit: 0.3° for an angle, 0.17°/s for a rate,
/// 0.05 m/s² for an acceleration.
fn bias_resolution(column: &str) -> f64 {
    if column.ends_with("_rad_s") {
        0.003
    } else if column.ends_with("_rad") {
        0.005
    } else if column.ends_with("_m_s2") {
        0.05
    } else {
        1e-3
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
            resolution: 0.02,
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
            resolution: 0.03,
        }]
    }
    fn required_columns(&self) -> Vec<String> {
        vec![surface_column(&self.0)]
    }
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], dt_s: f64) {
        if surface != self.0 || p[0] <= 0.0 {
            return;
        }
        // τ ẋ = δ − x, discretised exactly for the input the replay applies, straight lines between the
        // samples (the triangle-hold equivalent; Franklin, Powell & Workman, Digital Control of Dynamic
        // Systems, §6.3.2): x_k = a x_{k−1} + (1 − a) δ_{k−1} + b (δ_k − δ_{k−1}),
        // a = e^{−Δt/τ}, b = 1 − (τ/Δt)(1 − a).
        let a = (-dt_s / p[0]).exp();
        let b = 1.0 - p[0] / dt_s * (1.0 - a);
        let (mut x, mut prev) = (0.0, 0.0);
        for v in dev.iter_mut() {
            let u = *v;
            x = a * x + (1.0 - a) * prev + b * (u - prev);
            prev = u;
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
            resolution: 0.1,
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
            resolution: bias_resolution(&self.0),
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
            resolution: 0.03,
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
            resolution: 0.15,
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
pub const DERIVATIVE_KNOBS: [(&str, &str); 18] = [
    ("CL_alpha", "CLwbh"),
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

/// Which targets an effect applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Targets {
    /// The surfaces of the schema (elevator, aileron, rudder, throttle).
    Surfaces,
    /// The columns that may carry a sensor error ([`SENSOR_COLUMNS`]).
    SensorColumns,
    /// The derivatives of [`DERIVATIVE_KNOBS`] whose coefficient the simulation can scale.
    Derivatives,
    /// The added terms the simulation offers.
    AddedTerms,
}

/// One row of the catalogue: an effect name, its targets and how to build it for one target
/// (the target name and, for derivatives, the simulation's coefficient name).
pub struct EffectKind {
    /// Effect name of the vocabulary.
    pub effect: &'static str,
    /// Targets it applies to.
    pub targets: Targets,
    /// Builds the extension for a target.
    pub build: fn(&str, &str) -> Box<dyn Extension>,
}

/// The catalogue: a new effect is one type implementing [`Extension`] and one row here.
pub const REGISTRY: [EffectKind; 7] = [
    EffectKind {
        effect: "input_delay",
        targets: Targets::Surfaces,
        build: |t, _| Box::new(InputDelay(t.into())),
    },
    EffectKind {
        effect: "actuator_lag",
        targets: Targets::Surfaces,
        build: |t, _| Box::new(ActuatorLag(t.into())),
    },
    EffectKind {
        effect: "control_effectiveness",
        targets: Targets::Surfaces,
        build: |t, _| Box::new(ControlEffectiveness(t.into())),
    },
    EffectKind {
        effect: "sensor_bias",
        targets: Targets::SensorColumns,
        build: |t, _| Box::new(SensorBias(t.into())),
    },
    EffectKind {
        effect: "sensor_scale",
        targets: Targets::SensorColumns,
        build: |t, _| Box::new(SensorScale(t.into())),
    },
    EffectKind {
        effect: "aero_derivative",
        targets: Targets::Derivatives,
        build: |t, knob| {
            Box::new(AeroDerivative {
                name: t.into(),
                knob: knob.into(),
            })
        },
    },
    EffectKind {
        effect: "aero_nonlinearity",
        targets: Targets::AddedTerms,
        build: |t, _| Box::new(AeroNonlinearity(t.into())),
    },
];

/// The surfaces of the schema.
pub const SURFACES: [&str; 4] = ["elevator", "aileron", "rudder", "throttle"];

/// The simulation's coefficient name of a derivative (the name itself when it is not in the table).
fn knob_of(target: &str) -> String {
    DERIVATIVE_KNOBS
        .iter()
        .find(|(n, _)| *n == target)
        .map(|(_, k)| k.to_string())
        .unwrap_or_else(|| target.to_string())
}

/// Builds one extension from its effect and target names (the `--extension` file and the catalogue use it).
pub fn make(
    effect: &str,
    target: &str,
    coefficient_names: &[String],
) -> Result<Box<dyn Extension>, DiagnoseError> {
    let Some(kind) = REGISTRY.iter().find(|k| k.effect == effect) else {
        let known: Vec<&str> = REGISTRY.iter().map(|k| k.effect).collect();
        return Err(DiagnoseError::UnknownExtension(format!(
            "unknown effect '{effect}' (known: {})",
            known.join(", ")
        )));
    };
    match kind.targets {
        Targets::Surfaces if !SURFACES.contains(&target) => {
            Err(DiagnoseError::UnknownExtension(format!(
                "{effect} needs a surface target (elevator, aileron, rudder, throttle), got '{target}'"
            )))
        }
        Targets::Derivatives if !coefficient_names.contains(&knob_of(target)) => {
            Err(DiagnoseError::UnknownExtension(format!(
                "the simulation has no aerodynamic coefficient for '{target}'"
            )))
        }
        _ => Ok((kind.build)(target, &knob_of(target))),
    }
}

/// A catalogue entry left out: (effect, target, reason).
pub type SkippedEntry = (String, String, String);

/// The full catalogue for a record and a simulation: every row of [`REGISTRY`] on each of its targets.
/// Returns the usable extensions and the skipped ones with the reason.
pub fn catalogue(
    record: &FlightRecord,
    coefficient_names: &[String],
    added_terms: &[String],
) -> (Vec<Box<dyn Extension>>, Vec<SkippedEntry>) {
    let mut all: Vec<Box<dyn Extension>> = Vec::new();
    let mut skipped = Vec::new();
    for kind in &REGISTRY {
        let targets: Vec<(String, String)> = match kind.targets {
            Targets::Surfaces => SURFACES
                .iter()
                .map(|s| (s.to_string(), String::new()))
                .collect(),
            Targets::SensorColumns => SENSOR_COLUMNS
                .iter()
                .map(|c| (c.to_string(), String::new()))
                .collect(),
            Targets::Derivatives => DERIVATIVE_KNOBS
                .iter()
                .filter(|(name, knob)| {
                    let has = coefficient_names.iter().any(|k| k == knob);
                    if !has {
                        skipped.push((
                            kind.effect.to_string(),
                            name.to_string(),
                            format!("the simulation has no coefficient knob '{knob}'"),
                        ));
                    }
                    has
                })
                .map(|(n, k)| (n.to_string(), k.to_string()))
                .collect(),
            Targets::AddedTerms => added_terms
                .iter()
                .map(|t| (t.clone(), String::new()))
                .collect(),
        };
        all.extend(targets.iter().map(|(t, k)| (kind.build)(t, k)));
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
