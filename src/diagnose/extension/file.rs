//! The extension file: fitted effects written by `diagnose --extension-out` and read by `replay --extension`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{make, Extension, REGISTRY};
use crate::diagnose::DiagnoseError;

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
    /// The loading the effects were fitted with, where it was not the model's own (JSBSim properties set before
    /// every trim, as `--property` gave them).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub properties: BTreeMap<String, f64>,
}

impl ExtensionFile {
    /// Reads an extension file (JSON). A value outside its catalogue entry's range ([`ParamSpec`] `min..max`)
    /// is refused, naming the effect, the value and the range: the search never fits one, so it was not written
    /// by flightid or was edited.
    pub fn read(path: &std::path::Path) -> Result<Self, DiagnoseError> {
        let err = |message: String| DiagnoseError::ExtensionFile {
            path: path.display().to_string(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let file: Self = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
        file.check_ranges().map_err(err)?;
        Ok(file)
    }

    /// Every effect of a known kind has its value within its catalogue entry's range (unknown effects are
    /// refused by [`ExtensionFile::build`], naming the ones known).
    pub fn check_ranges(&self) -> Result<(), String> {
        for f in self.effects.iter().chain(&self.model_effects) {
            let Some(kind) = REGISTRY.iter().find(|k| k.effect == f.effect) else {
                continue;
            };
            let spec = (kind.param)(&f.target);
            if !(f.value >= spec.min && f.value <= spec.max) {
                let value = if f.value.abs() >= 1e6 {
                    format!("{:e}", f.value)
                } else {
                    f.value.to_string()
                };
                return Err(format!(
                    "{} on {}: value {value} is outside the effect's range [{}, {}]",
                    f.effect,
                    crate::text::escape_control(&f.target),
                    spec.min,
                    spec.max
                ));
            }
        }
        Ok(())
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
