//! The extended model on disk: a directory holding a private copy of the JSBSim aircraft with
//! the fitted coefficient factors and added terms written into its XML, plus `extension.json` with the
//! signal-path and sensor effects, which live outside the aerodynamic model. `flightid fly --model DIR` and
//! `flightid replay --model DIR` load it.

use std::path::{Path, PathBuf};

use super::extension::{BuiltEffects, ExtensionFile, FittedEffect, Stage};
use super::simulator::ReplaySim;
use super::DiagnoseError;
use crate::aircraft::AircraftConfig;
use crate::data::FlightRecord;
use crate::sim::{FlightPlan, JsbsimSim, SimError};

/// File name of the signal-path and sensor effects inside a model directory.
pub const EXTENSION_FILE: &str = "extension.json";

/// An extended model directory.
#[derive(Debug, Clone)]
pub struct ExtendedModel {
    /// The directory.
    pub dir: PathBuf,
    /// Its extension file: `effects` are applied around the simulation, `model_effects` are in the XML.
    pub extension: ExtensionFile,
}

fn file_err(path: &Path, message: impl std::fmt::Display) -> DiagnoseError {
    DiagnoseError::ExtensionFile {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

/// Writes the extended model of `file`'s effects to `dir`: model-stage effects (coefficient factors, added terms)
/// are set on `sim` and written into its exported aircraft XML; the others go to `dir/extension.json`.
pub fn write_model(
    sim: &mut dyn ReplaySim,
    file: &ExtensionFile,
    dir: &Path,
) -> Result<ExtendedModel, DiagnoseError> {
    let built = file.build(&sim.coefficient_names())?;
    for name in sim.coefficient_names() {
        sim.set_coefficient_scale(&name, 1.0)
            .map_err(|e| file_err(dir, e))?;
    }
    for name in sim.added_term_names() {
        sim.set_added_term(&name, 0.0)
            .map_err(|e| file_err(dir, e))?;
    }
    let mut signal = Vec::new();
    let mut in_model = Vec::new();
    for ((ext, p), f) in built.iter().zip(&file.effects) {
        if ext.stage() == Stage::Model {
            ext.apply_model(p, sim).map_err(|e| file_err(dir, e))?;
            in_model.push(f.clone());
        } else {
            signal.push(f.clone());
        }
    }
    let extension = ExtensionFile {
        aircraft: file.aircraft.clone(),
        effects: signal,
        model_effects: [file.model_effects.clone(), in_model].concat(),
        notes: file.notes.clone(),
        properties: file.properties.clone(),
    };
    let text = serde_json::to_string_pretty(&extension).map_err(|e| file_err(dir, e))?;
    // the whole directory is replaced at once, and only when it is new or an earlier flightid output
    crate::report::replace_output_dir(dir, |tmp| -> Result<(), DiagnoseError> {
        sim.export_model(tmp).map_err(|e| file_err(dir, e))?;
        crate::report::write_atomic(&tmp.join(EXTENSION_FILE), text.as_bytes())
            .map_err(|e| file_err(dir, e))
    })?;
    Ok(ExtendedModel {
        dir: dir.to_path_buf(),
        extension,
    })
}

impl ExtendedModel {
    /// Reads a model directory written by [`write_model`].
    pub fn read(dir: &Path) -> Result<Self, DiagnoseError> {
        let path = dir.join(EXTENSION_FILE);
        if !path.is_file() {
            return Err(file_err(
                dir,
                format!("not a flightid model directory (no {EXTENSION_FILE})"),
            ));
        }
        Ok(ExtendedModel {
            dir: dir.to_path_buf(),
            extension: ExtensionFile::read(&path)?,
        })
    }

    /// The configuration of the model's aircraft with the loading it was fitted with, then `settings`
    /// (`--property NAME=VALUE`) over it.
    pub fn config(
        &self,
        settings: &[String],
    ) -> Result<AircraftConfig, crate::aircraft::AircraftError> {
        let mut cfg = crate::sim::derived::aircraft_config(&self.extension.aircraft)?;
        cfg.properties.extend(self.extension.properties.clone());
        cfg.with_properties(settings)
    }

    /// Starts JSBSim on the exported aircraft.
    pub fn start(&self, config: &AircraftConfig, rate_hz: f64) -> Result<JsbsimSim, SimError> {
        JsbsimSim::start_with_model(config, rate_hz, Some(&self.dir))
    }

    /// The signal-path and sensor effects with their values (model effects are already in the aircraft).
    pub fn effects(&self, coefficient_names: &[String]) -> Result<BuiltEffects, DiagnoseError> {
        let built = self.extension.build(coefficient_names)?;
        if let Some((e, _)) = built.iter().find(|(e, _)| e.stage() == Stage::Model) {
            return Err(file_err(
                &self.dir,
                format!(
                    "{}/{} belongs in the aircraft XML, not in {EXTENSION_FILE}",
                    e.effect(),
                    e.target()
                ),
            ));
        }
        Ok(built)
    }
}

/// Applies input-stage effects to a flight plan (per-step deviations from trim) and returns them for
/// [`apply_to_record`]: `fly --model` flies the extended model this way.
pub fn apply_to_plan(effects: &BuiltEffects, plan: &mut FlightPlan) {
    let dt = 1.0 / plan.rate_hz;
    for input in plan.inputs.iter_mut() {
        // Sample 0 is the trim (deviation 0); step k shows as sample k+1 (see `replay::replay`).
        let mut dev: Vec<f64> = std::iter::once(0.0)
            .chain(input.deflection_rad.iter().copied())
            .collect();
        for (e, p) in effects {
            if e.stage() == Stage::Input {
                e.apply_input(p, &input.surface, &mut dev, dt);
            }
        }
        input.deflection_rad = dev[1..].to_vec();
    }
}

/// Applies output-stage (sensor) effects to a simulated record.
pub fn apply_to_record(effects: &BuiltEffects, rec: &mut FlightRecord) {
    for (e, p) in effects {
        if e.stage() == Stage::Output {
            e.apply_output(p, rec);
        }
    }
}

/// The fitted effects of a file that are signal-path or sensor effects (for display).
pub fn describe(effects: &[FittedEffect]) -> String {
    effects
        .iter()
        .map(|f| format!("{}/{} = {:.5}", f.effect, f.target, f.value))
        .collect::<Vec<_>>()
        .join(", ")
}
