//! Stage 5, export: the named effects as an extension file (`flightid replay --extension`, and the extended
//! model written by [`super::model::write_model`]).

use std::collections::BTreeMap;

use super::extension::{ExtensionFile, FittedEffect};
use super::Diagnosis;

impl Diagnosis {
    /// The extension file of the named effects and the record's timing.
    pub fn extension_file(&self, aircraft: &str) -> ExtensionFile {
        ExtensionFile {
            aircraft: aircraft.to_string(),
            effects: self
                .named_cause
                .iter()
                .chain(&self.record_timing)
                .chain(&self.sensor_position)
                .map(|c| FittedEffect {
                    effect: c.effect.clone(),
                    target: c.target.clone(),
                    value: c.value,
                    std_error: c.std_error,
                })
                .collect(),
            model_effects: Vec::new(),
            notes: BTreeMap::new(),
            properties: BTreeMap::new(),
        }
    }
}
