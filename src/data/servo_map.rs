//! Per-airframe MAVLink servo mapping (`aircraft/servo_maps/NAME.toml`): PWM → surface radians.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::DataError;

/// How one control surface appears on a servo output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceMap {
    /// SERVO_OUTPUT_RAW channel, 1-based (`servoN_raw`).
    pub channel: u8,
    /// PWM at zero deflection, µs.
    pub trim_pwm_us: f64,
    /// PWM change per radian of deflection, µs/rad (positive).
    pub pwm_per_rad: f64,
    /// +1 or −1: sign from PWM increase to the JSBSim deflection convention.
    pub sign: f64,
}

impl SurfaceMap {
    /// Deflection in radians for a PWM pulse width in µs.
    pub fn to_rad(&self, pwm_us: f64) -> f64 {
        self.sign * (pwm_us - self.trim_pwm_us) / self.pwm_per_rad
    }

    /// PWM pulse width in µs for a deflection in radians (inverse of [`Self::to_rad`]).
    pub fn to_pwm_us(&self, rad: f64) -> f64 {
        self.trim_pwm_us + self.sign * rad * self.pwm_per_rad
    }
}

/// How the throttle appears on a servo output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThrottleMap {
    /// SERVO_OUTPUT_RAW channel, 1-based.
    pub channel: u8,
    /// PWM at zero throttle, µs.
    pub min_pwm_us: f64,
    /// PWM at full throttle, µs.
    pub max_pwm_us: f64,
}

impl ThrottleMap {
    /// Throttle fraction (0..1 inside the PWM range) for a PWM pulse width in µs.
    pub fn to_fraction(&self, pwm_us: f64) -> f64 {
        (pwm_us - self.min_pwm_us) / (self.max_pwm_us - self.min_pwm_us)
    }
}

/// The servo mapping of one airframe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoMap {
    /// ServoMap name (the file stem).
    pub name: String,
    /// Elevator mapping, if the elevator is on a servo output.
    pub elevator: Option<SurfaceMap>,
    /// Aileron mapping.
    pub aileron: Option<SurfaceMap>,
    /// Rudder mapping.
    pub rudder: Option<SurfaceMap>,
    /// Throttle mapping.
    pub throttle: Option<ThrottleMap>,
}

/// Highest servo channel SERVO_OUTPUT_RAW carries in this dialect build (servo1..servo8).
pub const MAX_SERVO_CHANNEL: u8 = 8;

impl ServoMap {
    /// Parses and checks a mapping from TOML text; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &Path) -> Result<Self, DataError> {
        let name = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let err = |message: String| DataError::ServoMap {
            servo_map: name.clone(),
            file: file.to_path_buf(),
            message,
        };
        let af: ServoMap = toml::from_str(text).map_err(|e| err(e.to_string()))?;
        let surfaces = [
            ("elevator", af.elevator),
            ("aileron", af.aileron),
            ("rudder", af.rudder),
        ];
        for (what, map) in surfaces {
            let Some(m) = map else { continue };
            if !(1..=MAX_SERVO_CHANNEL).contains(&m.channel) {
                return Err(err(format!(
                    "{what}: channel {} is outside 1..={MAX_SERVO_CHANNEL}",
                    m.channel
                )));
            }
            if !(m.pwm_per_rad.is_finite() && m.pwm_per_rad > 0.0) {
                return Err(err(format!(
                    "{what}: pwm_per_rad must be a positive number, got {}",
                    m.pwm_per_rad
                )));
            }
            if m.sign != 1.0 && m.sign != -1.0 {
                return Err(err(format!("{what}: sign must be 1 or -1, got {}", m.sign)));
            }
            if !m.trim_pwm_us.is_finite() {
                return Err(err(format!("{what}: trim_pwm_us must be finite")));
            }
        }
        if let Some(t) = af.throttle {
            if !(1..=MAX_SERVO_CHANNEL).contains(&t.channel) {
                return Err(err(format!(
                    "throttle: channel {} is outside 1..={MAX_SERVO_CHANNEL}",
                    t.channel
                )));
            }
            if !(t.min_pwm_us.is_finite()
                && t.max_pwm_us.is_finite()
                && t.max_pwm_us != t.min_pwm_us)
            {
                return Err(err(format!(
                    "throttle: min_pwm_us ({}) and max_pwm_us ({}) must be finite and differ",
                    t.min_pwm_us, t.max_pwm_us
                )));
            }
        }
        Ok(af)
    }

    /// Reads a mapping file.
    pub fn load(path: &Path) -> Result<Self, DataError> {
        let text = std::fs::read_to_string(path)
            .map_err(DataError::io(path, "cannot read the servo mapping"))?;
        Self::from_toml_str(&text, path)
    }

    /// Finds `NAME.toml` under `aircraft/servo_maps/` of the given root.
    pub fn path_in(root: &Path, name: &str) -> PathBuf {
        root.join("aircraft")
            .join("servo_maps")
            .join(format!("{name}.toml"))
    }

    /// Resolves an `--servo-map` argument: a path to a `.toml` file, or a name looked up under
    /// `$FLIGHTID_ROOT/aircraft/servo_maps`, `./aircraft/servo_maps`, then the source tree's.
    pub fn resolve(name_or_path: &str) -> Result<Self, DataError> {
        let as_path = Path::new(name_or_path);
        if name_or_path.ends_with(".toml") || as_path.components().count() > 1 {
            return Self::load(as_path);
        }
        let mut roots: Vec<PathBuf> = Vec::new();
        if let Some(r) = std::env::var_os("FLIGHTID_ROOT") {
            roots.push(PathBuf::from(r));
        }
        roots.push(PathBuf::from("."));
        roots.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
        for root in &roots {
            let p = Self::path_in(root, name_or_path);
            if p.is_file() {
                return Self::load(&p);
            }
        }
        Err(DataError::ServoMap {
            servo_map: name_or_path.to_string(),
            file: Self::path_in(Path::new("."), name_or_path),
            message: format!(
                "no such servo mapping (looked under {})",
                roots
                    .iter()
                    .map(|r| Self::path_in(r, name_or_path).display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
    }
}
