//! Campaign files (TOML): aircraft configurations × flight conditions × maneuvers × methods × noise/seeds.
//!
//! ```toml
//! name = "c172x_737"
//! rate_hz = 60.0          # simulation and sampling rate, Hz
//! duration_s = 20.0       # record length per case, s
//! start_s = 1.0           # maneuver start, s
//! methods = ["ls", "srivc"]
//! noise_std_deg = [0.0]   # white noise added to the output, deg (1 sigma)
//! seeds = [1]
//! fresh_process_per_case = false  # reuse one JSBSim process per worker and aircraft (see the field)
//!
//! [[configurations]]
//! name = "c172x"                           # the configuration's id (baselines are keyed by it)
//! aircraft = "c172x"
//! coefficient_scales = { Cmalpha = 1.0 }   # optional: factors on JSBSim aero coefficients
//! properties = { "inertia/pointmass-weight-lbs[4]" = 200.0 }  # optional: mass/CG variant, set before trim
//! conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]
//!
//! [[maneuvers]]
//! surface = "elevator"
//! shape = "doublet"       # doublet | 3211
//! pulse_s = 1.0
//! amplitudes_deg = [1.0, 3.0]
//! ```
//!
//! One case = one flight (configuration, condition, maneuver, amplitude); every method, noise level and
//! seed is applied to that flight's record.

use super::CampaignError;
use crate::ident::Method;
use crate::signal::Maneuver;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// A whole campaign file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSpec {
    /// Campaign name.
    pub name: String,
    /// Simulation and sampling rate, Hz.
    #[serde(default = "default_rate")]
    pub rate_hz: f64,
    /// Record length per case, s.
    #[serde(default = "default_duration")]
    pub duration_s: f64,
    /// Maneuver start time, s.
    #[serde(default = "default_start")]
    pub start_s: f64,
    /// Estimators (`ls`, `iv`, `srivc`, `oe`).
    pub methods: Vec<String>,
    /// Output noise levels, deg (1 σ); 0 for noise-free.
    #[serde(default = "default_noise")]
    pub noise_std_deg: Vec<f64>,
    /// Noise seeds (each noise level > 0 is run once per seed).
    #[serde(default = "default_seeds")]
    pub seeds: Vec<u64>,
    /// Start a fresh JSBSim process for every case (default false: a worker reuses one process per aircraft).
    /// A reused process trims each flight condition once and flies every case from the restored snapshot after
    /// resetting all models, so it gives the same results as a fresh one whatever ran before (tests/campaign_run.rs
    /// checks byte-identical results across `--jobs` and resumption); `true` is the belt-and-braces option and
    /// costs a process start (~0.08 s CPU, most of it importing numpy for jsbsim) and a full trim per case.
    #[serde(default = "default_fresh")]
    pub fresh_process_per_case: bool,
    /// Aircraft configurations.
    pub configurations: Vec<ConfigurationSpec>,
    /// Maneuvers.
    pub maneuvers: Vec<ManeuverSpec>,
}

fn default_rate() -> f64 {
    60.0
}
fn default_duration() -> f64 {
    20.0
}
fn default_start() -> f64 {
    1.0
}
fn default_fresh() -> bool {
    false
}
fn default_noise() -> Vec<f64> {
    vec![0.0]
}
fn default_seeds() -> Vec<u64> {
    vec![1]
}

/// An aircraft configuration and the conditions it is flown at.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigurationSpec {
    /// Configuration id (unique in the campaign; baselines are keyed by it).
    pub name: String,
    /// Aircraft name from aircraft/ (or a path to an aircraft .toml).
    pub aircraft: String,
    /// Factors on aerodynamic coefficient functions (`Cmalpha = 1.3`).
    #[serde(default)]
    pub coefficient_scales: BTreeMap<String, f64>,
    /// JSBSim properties set before every trim: mass and CG variants where the model has them (point-mass
    /// weights and locations `inertia/pointmass-weight-lbs[i]`, `inertia/pointmass-location-X-inches[i]`, fuel
    /// `propulsion/tank[i]/contents-lbs`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub properties: BTreeMap<String, f64>,
    /// Trim points.
    pub conditions: Vec<ConditionSpec>,
}

/// A level-flight trim point.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConditionSpec {
    /// Altitude, ft.
    pub altitude_ft: f64,
    /// True airspeed, kts.
    pub speed_kts: f64,
}

/// A maneuver family: one surface, one shape, several amplitudes.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManeuverSpec {
    /// `elevator`, `aileron` or `rudder`.
    pub surface: String,
    /// `doublet` or `3211`.
    pub shape: String,
    /// Pulse width T, s.
    #[serde(default = "default_pulse")]
    pub pulse_s: f64,
    /// Peak deflections, deg.
    pub amplitudes_deg: Vec<f64>,
}

fn default_pulse() -> f64 {
    1.0
}

/// One flight of the campaign, fully specified.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CaseSpec {
    /// File-name-safe id, unique in the campaign.
    pub id: String,
    /// Configuration id.
    pub configuration: String,
    /// Aircraft name or path.
    pub aircraft: String,
    /// Coefficient factors.
    pub coefficient_scales: BTreeMap<String, f64>,
    /// Properties set before trim (mass/CG variant).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub properties: BTreeMap<String, f64>,
    /// Altitude, ft.
    pub altitude_ft: f64,
    /// True airspeed, kts.
    pub speed_kts: f64,
    /// Surface.
    pub surface: String,
    /// Transfer function identified (`theta/elevator`, ...).
    pub tf_key: String,
    /// Input shape.
    pub maneuver: Maneuver,
    /// Peak deflection, deg.
    pub amplitude_deg: f64,
}

fn num_id(x: f64) -> String {
    let s = format!("{x}");
    s.replace('.', "p").replace('-', "m")
}

impl CampaignSpec {
    /// Reads and validates a campaign file.
    pub fn load(path: &Path) -> Result<CampaignSpec, CampaignError> {
        let spec: CampaignSpec = super::read_toml(path)?;
        spec.validate().map_err(|message| CampaignError::Invalid {
            path: path.to_path_buf(),
            message,
        })?;
        Ok(spec)
    }

    /// The estimators, parsed.
    pub fn parsed_methods(&self) -> Result<Vec<Method>, String> {
        self.methods
            .iter()
            .map(|m| m.parse::<Method>().map_err(|e| e.to_string()))
            .collect()
    }

    fn validate(&self) -> Result<(), String> {
        use crate::limits::{
            self, ALTITUDE_FT, DURATION_S, NOISE_DEG, PULSE_S, RATE_HZ, SCALE, SPEED_KTS, START_S,
        };
        let text = |e: limits::LimitError| e.to_string();
        RATE_HZ.named("rate_hz").check(self.rate_hz).map_err(text)?;
        DURATION_S
            .named("duration_s")
            .check(self.duration_s)
            .map_err(text)?;
        START_S.named("start_s").check(self.start_s).map_err(text)?;
        limits::check_samples(
            "a case (duration_s × rate_hz)",
            self.duration_s,
            self.rate_hz,
        )
        .map_err(text)?;
        for n in &self.noise_std_deg {
            NOISE_DEG.check(*n).map_err(text)?;
        }
        for c in &self.configurations {
            for cond in &c.conditions {
                ALTITUDE_FT
                    .named("altitude_ft")
                    .check(cond.altitude_ft)
                    .map_err(text)?;
                SPEED_KTS
                    .named("speed_kts")
                    .check(cond.speed_kts)
                    .map_err(text)?;
            }
            for v in c.coefficient_scales.values() {
                SCALE.named("coefficient_scales").check(*v).map_err(text)?;
            }
        }
        for m in &self.maneuvers {
            PULSE_S.named("pulse_s").check(m.pulse_s).map_err(text)?;
            if m.pulse_s * self.rate_hz < 2.0 {
                return Err(format!(
                    "maneuver on {}: pulse_s {} is shorter than two samples at rate_hz {}",
                    m.surface, m.pulse_s, self.rate_hz
                ));
            }
        }
        if !(self.duration_s > self.start_s && self.start_s >= 0.0) {
            return Err(format!(
                "duration_s ({}) must exceed start_s ({}) >= 0",
                self.duration_s, self.start_s
            ));
        }
        if self.methods.is_empty() {
            return Err("methods is empty (use e.g. [\"ls\", \"srivc\"])".into());
        }
        self.parsed_methods()?;
        if self
            .noise_std_deg
            .iter()
            .any(|n| !(n.is_finite() && *n >= 0.0))
            || self.seeds.is_empty()
        {
            return Err("noise_std_deg must be >= 0 and seeds non-empty".into());
        }
        if self.configurations.is_empty() || self.maneuvers.is_empty() {
            return Err("a campaign needs at least one configuration and one maneuver".into());
        }
        let mut names = std::collections::BTreeSet::new();
        for c in &self.configurations {
            if !names.insert(c.name.clone()) {
                return Err(format!("configuration '{}' is listed twice", c.name));
            }
            if !c
                .name
                .chars()
                .all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-')
            {
                return Err(format!(
                    "configuration name '{}' may hold only letters, digits, '_' and '-'",
                    c.name
                ));
            }
            if let Err(e) = crate::sim::derived::aircraft_config(&c.aircraft) {
                return Err(format!("configuration '{}': {e}", c.name));
            }
            if c.conditions.is_empty() {
                return Err(format!("configuration '{}' has no conditions", c.name));
            }
            for (k, v) in &c.coefficient_scales {
                if !v.is_finite() {
                    return Err(format!(
                        "configuration '{}': scale of {k} is not finite",
                        c.name
                    ));
                }
            }
            for (k, v) in &c.properties {
                if !v.is_finite() {
                    return Err(format!(
                        "configuration '{}': property {k} is not finite",
                        c.name
                    ));
                }
            }
        }
        for m in &self.maneuvers {
            if crate::compare::tf_key_for(&m.surface).is_none() {
                return Err(format!(
                    "maneuver surface '{}' unknown (use elevator, aileron or rudder)",
                    m.surface
                ));
            }
            m.maneuver()?;
            if m.amplitudes_deg.is_empty()
                || m.amplitudes_deg
                    .iter()
                    .any(|a| !(a.is_finite() && *a > 0.0 && *a <= 30.0))
            {
                return Err(format!(
                    "maneuver on {}: amplitudes_deg must be non-empty, each within (0, 30]",
                    m.surface
                ));
            }
        }
        Ok(())
    }

    /// Every case, grouped by configuration (so a worker rarely has to switch aircraft).
    pub fn cases(&self) -> Vec<CaseSpec> {
        let mut out = Vec::new();
        for c in &self.configurations {
            for cond in &c.conditions {
                for m in &self.maneuvers {
                    let Ok(maneuver) = m.maneuver() else { continue };
                    for &amp in &m.amplitudes_deg {
                        out.push(CaseSpec {
                            id: format!(
                                "{}_{}ft_{}kts_{}_{}_{}deg",
                                c.name,
                                num_id(cond.altitude_ft),
                                num_id(cond.speed_kts),
                                m.surface,
                                maneuver.name(),
                                num_id(amp)
                            ),
                            configuration: c.name.clone(),
                            aircraft: c.aircraft.clone(),
                            coefficient_scales: c.coefficient_scales.clone(),
                            properties: c.properties.clone(),
                            altitude_ft: cond.altitude_ft,
                            speed_kts: cond.speed_kts,
                            surface: m.surface.clone(),
                            tf_key: crate::compare::tf_key_for(&m.surface)
                                .unwrap_or("")
                                .to_string(),
                            maneuver: maneuver.clone(),
                            amplitude_deg: amp,
                        });
                    }
                }
            }
        }
        out
    }
}

impl ManeuverSpec {
    /// The unit-peak shape.
    pub fn maneuver(&self) -> Result<Maneuver, String> {
        if !(self.pulse_s.is_finite() && self.pulse_s > 0.0) {
            return Err(format!(
                "maneuver pulse_s must be positive, got {}",
                self.pulse_s
            ));
        }
        match self.shape.as_str() {
            "doublet" => Ok(Maneuver::Doublet {
                pulse_s: self.pulse_s,
            }),
            "3211" => Ok(Maneuver::ThreeTwoOneOne {
                pulse_s: self.pulse_s,
            }),
            other => Err(format!(
                "unknown maneuver shape '{other}' on {} (use doublet or 3211)",
                self.surface
            )),
        }
    }
}
