//! Airframe descriptions: the mass, inertia, geometry, thrust line and sensor positions of an aircraft that
//! has no JSBSim model (`--airframe FILE.toml`), or of one that has (`--airframe NAME`: the CLI fills it from
//! the model's trim).
//!
//! The file format is documented in `docs/airframe.md`. A quantity a command needs and the file does not give
//! is an error naming the key ([`AirframeError::Missing`]); nothing falls back to another aircraft. Inertias
//! of 0 mean "unknown" (I_xz = 0 is taken as a value: most aircraft are close to it and it cannot be told
//! apart from "unknown").

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::params::{Geometry, MassProperties};

/// Why an airframe description cannot serve a command.
#[derive(Debug, thiserror::Error)]
pub enum AirframeError {
    /// The file cannot be read.
    #[error("{file}: cannot read the airframe description: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a valid airframe description.
    #[error("{file}: {message}")]
    Invalid {
        /// The file.
        file: String,
        /// What is wrong (TOML error, negative mass, …).
        message: String,
    },
    /// A key the command needs is absent (or 0 = unknown).
    #[error("{file}: the airframe description lacks `{key}`, which {needed_for} needs")]
    Missing {
        /// The file (or JSBSim aircraft name).
        file: String,
        /// The TOML key, e.g. `inertia_kg_m2.iyy`.
        key: &'static str,
        /// What needs it, e.g. `the pitching-moment equation`.
        needed_for: String,
    },
}

/// Body-axis inertia about the CG; 0 = unknown.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Inertia {
    /// Roll inertia I_xx, kg m².
    #[serde(default)]
    pub ixx: f64,
    /// Pitch inertia I_yy, kg m².
    #[serde(default)]
    pub iyy: f64,
    /// Yaw inertia I_zz, kg m².
    #[serde(default)]
    pub izz: f64,
    /// Product of inertia I_xz = ∫ x z dm, kg m².
    #[serde(default)]
    pub ixz: f64,
}

/// Wing reference geometry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wing {
    /// Reference area S, m².
    pub area_m2: Option<f64>,
    /// Span b, m.
    pub span_m: Option<f64>,
    /// Mean aerodynamic chord c̄, m.
    pub mac_m: Option<f64>,
}

/// How a measured `thrust_n` acts on the airframe.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrustLine {
    /// Thrust line vs body x, positive nose up, rad.
    #[serde(default)]
    pub inclination_rad: f64,
    /// Pitching moment per newton of thrust (positive nose up), m.
    #[serde(default)]
    pub moment_arm_m: f64,
}

/// Sensor positions relative to the CG, body axes (x forward, y right, z down), m.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorPositions {
    /// Accelerometers (the `ax/ay/az` columns).
    #[serde(default)]
    pub imu_m: [f64; 3],
    /// α vane.
    #[serde(default)]
    pub alpha_vane_m: [f64; 3],
    /// β vane.
    #[serde(default)]
    pub beta_vane_m: [f64; 3],
}

/// Flight condition values used when a record lacks the column.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlightDefaults {
    /// Air density, kg/m³ (when the record has neither `qbar_pa` nor `altitude_m`).
    pub density_kg_m3: Option<f64>,
}

/// An airframe description (`docs/airframe.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Airframe {
    /// Name, for reports.
    pub name: String,
    /// Mass, kg.
    pub mass_kg: Option<f64>,
    /// Inertia about the CG, body axes.
    #[serde(default)]
    pub inertia_kg_m2: Inertia,
    /// Wing reference geometry.
    #[serde(default)]
    pub wing: Wing,
    /// Thrust line, when a record carries `thrust_n`.
    pub thrust: Option<ThrustLine>,
    /// Sensor positions.
    #[serde(default)]
    pub sensors: SensorPositions,
    /// Flight-condition fallbacks.
    #[serde(default)]
    pub flight: FlightDefaults,
    /// Where it came from (file path or `JSBSim NAME`), for messages.
    #[serde(skip)]
    pub source: String,
}

/// The `source` of an airframe taken from a JSBSim model by name (`JSBSim p51d`).
pub const JSBSIM_SOURCE_PREFIX: &str = "JSBSim ";

impl Airframe {
    /// What the reader of an estimate should know about this description: an airframe taken from a JSBSim model
    /// by name puts every sensor at the CG, which a model cannot know.
    pub fn assumptions(&self) -> Vec<String> {
        if self.source.starts_with(JSBSIM_SOURCE_PREFIX)
            && self.sensors == SensorPositions::default()
        {
            vec![format!(
                "airframe from the {} model: mass, inertia, wing{} from the model; the accelerometers and vanes \
                 are taken at the CG (a model knows no data system): where they are elsewhere, give their \
                 positions in an airframe description (FILE.toml, [sensors]; docs/airframe.md)",
                self.source,
                if self.thrust.is_some() { " and thrust line" } else { "" }
            )]
        } else {
            Vec::new()
        }
    }

    /// Parses a description; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, AirframeError> {
        let mut af: Airframe = toml::from_str(text).map_err(|e| AirframeError::Invalid {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        af.source = file.to_string();
        let i = af.inertia_kg_m2;
        let checks = [
            ("mass_kg", af.mass_kg),
            ("inertia_kg_m2.ixx", Some(i.ixx)),
            ("inertia_kg_m2.iyy", Some(i.iyy)),
            ("inertia_kg_m2.izz", Some(i.izz)),
            ("wing.area_m2", af.wing.area_m2),
            ("wing.span_m", af.wing.span_m),
            ("wing.mac_m", af.wing.mac_m),
            ("flight.density_kg_m3", af.flight.density_kg_m3),
        ];
        for (key, v) in checks {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(AirframeError::Invalid {
                        file: file.to_string(),
                        message: format!("`{key}` must be a finite number ≥ 0 (got {v})"),
                    });
                }
            }
        }
        let finite = [i.ixz]
            .into_iter()
            .chain(af.sensors.imu_m)
            .chain(af.sensors.alpha_vane_m)
            .chain(af.sensors.beta_vane_m)
            .chain(af.thrust.map(|t| t.inclination_rad))
            .chain(af.thrust.map(|t| t.moment_arm_m));
        if finite.into_iter().any(|v| !v.is_finite()) {
            return Err(AirframeError::Invalid {
                file: file.to_string(),
                message: "inertia, sensor positions and thrust line must be finite".into(),
            });
        }
        Ok(af)
    }

    /// Reads a description file.
    pub fn load(path: &Path) -> Result<Self, AirframeError> {
        let text = std::fs::read_to_string(path).map_err(|source| AirframeError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    fn missing(&self, key: &'static str, needed_for: &str) -> AirframeError {
        AirframeError::Missing {
            file: self.source.clone(),
            key,
            needed_for: needed_for.to_string(),
        }
    }

    fn known(
        &self,
        value: Option<f64>,
        key: &'static str,
        needed_for: &str,
    ) -> Result<f64, AirframeError> {
        match value {
            Some(v) if v > 0.0 => Ok(v),
            _ => Err(self.missing(key, needed_for)),
        }
    }

    /// Mass, kg.
    pub fn mass(&self, needed_for: &str) -> Result<f64, AirframeError> {
        self.known(self.mass_kg, "mass_kg", needed_for)
    }

    /// Mass and the inertias an axis needs: longitudinal needs I_yy; lateral I_xx and I_zz (I_xz as given).
    /// The inertias the axis does not need are left at the file's value (possibly 0).
    pub fn mass_properties(
        &self,
        longitudinal: bool,
        needed_for: &str,
    ) -> Result<MassProperties, AirframeError> {
        let i = self.inertia_kg_m2;
        let mass_kg = self.mass(needed_for)?;
        let (ixx, iyy, izz) = if longitudinal {
            (
                i.ixx,
                self.known(Some(i.iyy), "inertia_kg_m2.iyy", needed_for)?,
                i.izz,
            )
        } else {
            (
                self.known(Some(i.ixx), "inertia_kg_m2.ixx", needed_for)?,
                i.iyy,
                self.known(Some(i.izz), "inertia_kg_m2.izz", needed_for)?,
            )
        };
        Ok(MassProperties {
            mass_kg,
            ixx_kg_m2: ixx,
            iyy_kg_m2: iyy,
            izz_kg_m2: izz,
            ixz_kg_m2: i.ixz,
        })
    }

    /// Wing area and the reference length an axis needs (c̄ longitudinal, b lateral); the other length is
    /// the file's value or NaN.
    pub fn geometry(
        &self,
        longitudinal: bool,
        needed_for: &str,
    ) -> Result<Geometry, AirframeError> {
        let area = self.known(self.wing.area_m2, "wing.area_m2", needed_for)?;
        let (span, mac) = if longitudinal {
            (
                self.wing.span_m.unwrap_or(f64::NAN),
                self.known(self.wing.mac_m, "wing.mac_m", needed_for)?,
            )
        } else {
            (
                self.known(self.wing.span_m, "wing.span_m", needed_for)?,
                self.wing.mac_m.unwrap_or(f64::NAN),
            )
        };
        Ok(Geometry {
            wing_area_m2: area,
            span_m: span,
            chord_m: mac,
        })
    }

    /// The thrust line, required when a record carries `thrust_n`.
    pub fn thrust_line(&self, needed_for: &str) -> Result<ThrustLine, AirframeError> {
        self.thrust
            .ok_or_else(|| self.missing("thrust", needed_for))
    }

    /// Air density when the record gives neither `qbar_pa` nor `altitude_m`.
    pub fn density(&self, needed_for: &str) -> Result<f64, AirframeError> {
        self.known(
            self.flight.density_kg_m3,
            "flight.density_kg_m3",
            needed_for,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "my-aircraft"
mass_kg = 7472.0
inertia_kg_m2 = { ixx = 0.0, iyy = 91400.0, izz = 0.0, ixz = 0.0 }
wing = { area_m2 = 30.1, span_m = 14.5, mac_m = 2.43 }
[thrust]
inclination_rad = 0.0524
moment_arm_m = -0.641
[sensors]
imu_m = [0.5, 0.0, 0.1]
alpha_vane_m = [4.0, 0.0, 0.0]
[flight]
density_kg_m3 = 0.792
"#;

    #[test]
    fn a_full_description_gives_the_longitudinal_quantities_and_names_the_unknown_lateral_inertia()
    {
        let af = Airframe::from_toml_str(FULL, "my.toml").unwrap();
        let m = af.mass_properties(true, "Cm").unwrap();
        assert_eq!((m.mass_kg, m.iyy_kg_m2), (7472.0, 91400.0));
        assert_eq!(af.geometry(true, "Cm").unwrap().chord_m, 2.43);
        assert_eq!(af.sensors.imu_m, [0.5, 0.0, 0.1]);
        assert_eq!(af.thrust_line("x").unwrap().moment_arm_m, -0.641);
        // I_xx = 0 means unknown: the lateral axis cannot be formed, and the message names the key.
        let err = af
            .mass_properties(false, "the rolling-moment equation")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("inertia_kg_m2.ixx") && err.contains("my.toml") && err.contains("rolling"),
            "{err}"
        );
    }

    #[test]
    fn missing_keys_are_named_and_bad_values_rejected() {
        let af =
            Airframe::from_toml_str("name = \"x\"\nwing = { area_m2 = 10.0 }", "x.toml").unwrap();
        assert!(af.mass("m").unwrap_err().to_string().contains("`mass_kg`"));
        assert!(af
            .geometry(false, "Cl")
            .unwrap_err()
            .to_string()
            .contains("`wing.span_m`"));
        assert!(af
            .thrust_line("t")
            .unwrap_err()
            .to_string()
            .contains("`thrust`"));
        assert!(af
            .density("d")
            .unwrap_err()
            .to_string()
            .contains("flight.density_kg_m3"));
        let bad = Airframe::from_toml_str("name = \"x\"\nmass_kg = -3.0", "x.toml").unwrap_err();
        assert!(bad.to_string().contains("mass_kg"), "{bad}");
        let typo = Airframe::from_toml_str("name = \"x\"\nmas_kg = 3.0", "x.toml").unwrap_err();
        assert!(typo.to_string().contains("mas_kg"), "{typo}");
    }
}
