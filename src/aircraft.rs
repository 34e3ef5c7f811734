//! Per-aircraft configuration read from `aircraft/NAME.toml`: which JSBSim model, default trim point, which
//! properties are the elevator / aileron / rudder deflections the aero model reads, and their limits.
//!
//! The configurations of the repository are embedded in the binary; `FLIGHTID_AIRCRAFT_DIR` (or a path ending in
//! `.toml`) adds the user's own.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// How maneuvers reach the aircraft.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Drive {
    /// Set the deflection the aero model reads, bypassing actuators (exact per-radian inputs).
    Surface,
    /// Move the pilot command (scaled by `rad_per_norm`) and log the surface the aircraft's FCS produces.
    Command,
}

/// A control surface: its command property, what the aero model reads, and limits.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SurfaceConfig {
    /// Normalised pilot command property (e.g. `fcs/elevator-cmd-norm`).
    pub command: String,
    /// Properties the aero model reads as this surface's deflection in radians.
    pub aero_reads: Vec<String>,
    /// Properties the aero model reads as the magnitude of this deflection.
    #[serde(default)]
    pub aero_reads_abs: Vec<String>,
    /// Lower deflection limit, rad.
    pub min_rad: f64,
    /// Upper deflection limit, rad.
    pub max_rad: f64,
    /// Nominal surface deflection per unit command near trim, rad.
    pub rad_per_norm: f64,
}

/// Default trim point.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrimDefaults {
    /// Altitude above sea level, ft.
    pub altitude_ft: f64,
    /// True airspeed, kts.
    pub speed_kts: f64,
}

/// One aircraft configuration.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AircraftConfig {
    /// Name flightid knows it by (file stem).
    #[serde(default)]
    pub name: String,
    /// JSBSim model directory name.
    pub model: String,
    /// One line for humans.
    pub description: String,
    /// How maneuvers are applied.
    pub drive: Drive,
    /// Start the engines before trimming.
    pub engine_running: bool,
    /// Retract the gear before trimming.
    pub gear_up: bool,
    /// Number of engines (throttle inputs drive all of them).
    #[serde(default = "one")]
    pub engines: usize,
    /// Default trim point.
    pub trim: TrimDefaults,
    /// Surfaces by name: `elevator`, `aileron`, `rudder`.
    pub surfaces: BTreeMap<String, SurfaceConfig>,
    /// The loading, where it is not the model's own: JSBSim properties set before every trim, e.g.
    /// `"propulsion/tank[0]/contents-lbs" = 30.0` or `"inertia/pointmass-weight-lbs[1]" = 0.0`. A record flown
    /// lighter or with the CG elsewhere trims at another α and elevator, which a replay with the model's loading
    /// takes for an aerodynamic error (docs/diagnose.md, "Loading").
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub properties: BTreeMap<String, f64>,
}

/// Problems finding or reading an aircraft configuration.
#[derive(Debug, thiserror::Error)]
pub enum AircraftError {
    /// Name not among the embedded configs and no file of that name.
    #[error("unknown aircraft '{name}' (known: {known}; or give a path to an aircraft .toml)")]
    Unknown { name: String, known: String },
    /// TOML syntax or schema error.
    #[error("aircraft configuration {file}: {detail}")]
    Malformed { file: String, detail: String },
    /// A surface name flightid does not know for this aircraft.
    #[error("aircraft '{aircraft}' has no surface '{surface}' (it has: {known})")]
    UnknownSurface {
        aircraft: String,
        surface: String,
        known: String,
    },
    /// A JSBSim model without a configuration whose configuration cannot be derived from the model
    /// (`sim::derived`).
    #[error("aircraft '{name}' has no configuration, and none can be derived from its JSBSim model: {why}; write \
             one (docs/airframe.md, \"Any JSBSim model\") and give its path")]
    NotDerived { name: String, why: String },
    /// A `--property` setting that is not `NAME=VALUE` with a finite value.
    #[error("--property {setting}: {why}")]
    BadProperty { setting: String, why: String },
}

fn one() -> usize {
    1
}

const EMBEDDED: &[(&str, &str)] = &[
    ("c172x", include_str!("../aircraft/c172x.toml")),
    ("737", include_str!("../aircraft/737.toml")),
    ("f16", include_str!("../aircraft/f16.toml")),
];

/// Names of the embedded aircraft configurations.
pub fn known() -> Vec<&'static str> {
    EMBEDDED.iter().map(|(n, _)| *n).collect()
}

fn parse(name: &str, file: &str, text: &str) -> Result<AircraftConfig, AircraftError> {
    let mut cfg: AircraftConfig = toml::from_str(text).map_err(|e| AircraftError::Malformed {
        file: file.to_string(),
        detail: e.to_string(),
    })?;
    cfg.name = name.to_string();
    for s in ["elevator", "aileron", "rudder"] {
        if !cfg.surfaces.contains_key(s) {
            return Err(AircraftError::Malformed {
                file: file.to_string(),
                detail: format!("missing [surfaces.{s}]"),
            });
        }
    }
    validate(&cfg).map_err(|e| AircraftError::Malformed {
        file: file.to_string(),
        detail: e.to_string(),
    })?;
    Ok(cfg)
}

/// The numbers of a configuration within their documented ranges ([`crate::limits`]): trim point, surface limits
/// (`min_rad < 0 < max_rad`, within ±π), `|rad_per_norm|` within 0.001..=10 rad, 1..=16 engines.
/// Checks a configuration's numbers against their physical ranges (trim point, engines, surface limits).
pub fn validate(cfg: &AircraftConfig) -> Result<(), crate::limits::LimitError> {
    use crate::limits::{check_order, Range, ALTITUDE_FT, SPEED_KTS, SURFACE_RAD};
    ALTITUDE_FT
        .named("trim.altitude_ft")
        .check(cfg.trim.altitude_ft)?;
    SPEED_KTS
        .named("trim.speed_kts")
        .check(cfg.trim.speed_kts)?;
    Range::new("engines", 1.0, 16.0, "").check(cfg.engines as f64)?;
    for s in cfg.surfaces.values() {
        SURFACE_RAD.named("min_rad").check(s.min_rad)?;
        SURFACE_RAD.named("max_rad").check(s.max_rad)?;
        check_order("min_rad", s.min_rad, "max_rad", s.max_rad)?;
        check_order("min_rad", s.min_rad, "zero deflection", 0.0)?;
        check_order("zero deflection", 0.0, "max_rad", s.max_rad)?;
        Range::new("|rad_per_norm|", 1e-3, 10.0, "rad").check(s.rad_per_norm.abs())?;
    }
    Ok(())
}

/// Loads an aircraft by name (embedded or in `FLIGHTID_AIRCRAFT_DIR`) or from a `.toml` path.
pub fn load(name: &str) -> Result<AircraftConfig, AircraftError> {
    if name.ends_with(".toml") {
        let path = Path::new(name);
        let text = std::fs::read_to_string(path).map_err(|e| AircraftError::Malformed {
            file: name.to_string(),
            detail: e.to_string(),
        })?;
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or(name);
        return parse(stem, name, &text);
    }
    if let Some(dir) = std::env::var_os("FLIGHTID_AIRCRAFT_DIR") {
        let path = Path::new(&dir).join(format!("{name}.toml"));
        if let Ok(text) = std::fs::read_to_string(&path) {
            return parse(name, &path.display().to_string(), &text);
        }
    }
    match EMBEDDED.iter().find(|(n, _)| *n == name) {
        Some((n, text)) => parse(n, &format!("aircraft/{n}.toml"), text),
        None => Err(AircraftError::Unknown {
            name: name.to_string(),
            known: known().join(", "),
        }),
    }
}

impl AircraftConfig {
    /// Adds `NAME=VALUE` settings (command-line `--property`) to the loading; a later one replaces an earlier one
    /// of the same property. An entry without `=` or with a value that is not a finite number is refused, naming it.
    pub fn with_properties(mut self, settings: &[String]) -> Result<Self, AircraftError> {
        for s in settings {
            let (name, value) = parse_property(s)?;
            self.properties.insert(name, value);
        }
        Ok(self)
    }

    /// The configuration of one surface, or an error naming the known ones.
    pub fn surface(&self, name: &str) -> Result<&SurfaceConfig, AircraftError> {
        self.surfaces
            .get(name)
            .ok_or_else(|| AircraftError::UnknownSurface {
                aircraft: self.name.clone(),
                surface: name.to_string(),
                known: self.surfaces.keys().cloned().collect::<Vec<_>>().join(", "),
            })
    }
}

/// `NAME=VALUE` (white space around either part ignored) as a property and a finite value.
fn parse_property(setting: &str) -> Result<(String, f64), AircraftError> {
    let bad = |why: &str| AircraftError::BadProperty {
        setting: setting.to_string(),
        why: why.to_string(),
    };
    let (name, value) = setting
        .split_once('=')
        .ok_or_else(|| bad("expected NAME=VALUE"))?;
    let (name, value) = (name.trim(), value.trim());
    if name.is_empty() {
        return Err(bad("the property name is empty"));
    }
    match value.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((name.to_string(), v)),
        _ => Err(bad("the value is not a finite number")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_embedded_aircraft_parses_with_three_surfaces() {
        for name in known() {
            let cfg = load(name).expect(name);
            assert_eq!(cfg.surfaces.len(), 3, "{name}");
            for (s, sc) in &cfg.surfaces {
                assert!(sc.min_rad < 0.0 && sc.max_rad > 0.0, "{name} {s} limits");
            }
        }
    }

    #[test]
    fn unknown_aircraft_names_the_known_ones() {
        let e = load("concorde-x").unwrap_err().to_string();
        assert!(
            e.contains("unknown aircraft 'concorde-x'") && e.contains("c172x"),
            "{e}"
        );
    }
}
