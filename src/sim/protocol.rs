//! The messages between flightid and its JSBSim bridge (`scripts/jsbsim_bridge.py`): one [`Request`] variant per
//! command, one reply struct per command.
//!
//! Framing (done by [`super::bridge::Bridge::request`]): a request is one JSON line, `{"cmd": NAME, ...fields}`,
//! followed, when it has `"payload_f64": N`, by N little-endian float64; a reply is one JSON line with `"ok": true`
//! and the command's fields (again with an optional float64 payload), or an [`ErrorReply`]. The bridge checks each
//! command's keys against its own table (`COMMANDS` in the script): a missing or unknown key is a `protocol` error.
//!
//! Units are JSBSim's on this wire (ft, kts, deg, ft/s); the callers convert at the edge.

use super::{Linearization, SimError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A property name → value map as the bridge sends and receives it (JSBSim units).
pub type PropertyValues = BTreeMap<String, f64>;

/// One request to the bridge. Serialised with the command name under `cmd`; the field names are the wire keys.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "cmd", rename_all = "snake_case")]
pub enum Request {
    /// Makes a private copy of the aircraft (knob, override and probe properties added to its aerodynamics) in a
    /// fresh directory under `scratch_dir` and loads it into a new JSBSim instance, dropping any earlier one.
    /// Reply: [`LoadReply`].
    Load {
        /// JSBSim model name (`c172x`).
        aircraft: String,
        /// Integration step, s.
        dt_s: f64,
        /// The aircraft's surfaces by name (`elevator`, …).
        surfaces: BTreeMap<String, SurfaceReads>,
        /// Start the engines at each trim.
        engine_running: bool,
        /// Retract the gear at each trim.
        gear_up: bool,
        /// Number of engines (one throttle command each).
        engines: usize,
        /// Directory the bridge works in; flightid makes and removes it.
        scratch_dir: String,
        /// Directory holding `<aircraft>.xml` to use instead of JSBSim's own (an exported model).
        #[serde(skip_serializing_if = "Option::is_none")]
        aircraft_dir: Option<String>,
    },
    /// Integrates at another step from the next trim on; drops the trim snapshots. Reply: [`EmptyReply`].
    Rate {
        /// Integration step, s.
        dt_s: f64,
    },
    /// Reads properties of the current state. Reply: [`ValuesReply`].
    Get {
        /// JSBSim property names.
        properties: Vec<String>,
    },
    /// Sets properties of the current state. Reply: [`EmptyReply`].
    Set {
        /// JSBSim property → value.
        values: PropertyValues,
    },
    /// Resets every model, sets the initial condition and the knobs, and runs JSBSim's trim; with `reuse`, trims
    /// once per distinct request and restores that snapshot on every later one. Reply: [`ValuesReply`] (the
    /// `report` properties), or a `trim_failed` error.
    Trim {
        /// Altitude above sea level, ft.
        altitude_ft: f64,
        /// True airspeed, kts.
        speed_kts: f64,
        /// True heading, deg.
        heading_deg: f64,
        /// Flight-path angle, deg.
        gamma_deg: f64,
        /// Geodetic latitude, deg.
        latitude_deg: f64,
        /// Properties set after the model reset (coefficient factors, added terms, mass and CG variants).
        knobs: PropertyValues,
        /// Properties to read back once trimmed.
        report: Vec<String>,
        /// Restore a snapshot of an identical earlier trim instead of trimming again.
        reuse: bool,
    },
    /// Runs JSBSim's `FGLinearization` at the current trim. Reply: [`Linearization`].
    Linearize {
        /// Surfaces whose inputs are made per radian of deflection (the rest stay per normalised command).
        per_radian_surfaces: Vec<String>,
    },
    /// Perturbs one aero input at a time by ±h at the current trim with integration suspended and reads the model's
    /// per-axis coefficient sums and the `extra` properties. Reply: [`ProbeReply`].
    Probe {
        /// Aero input (`alpha`, `beta`, `p`, `q`, `r`, `alphadot`, `betadot`, `surface:NAME`) → step h, rad or
        /// rad/s.
        perturb: PropertyValues,
        /// Properties read once, unperturbed (flight condition, mass, geometry).
        condition: Vec<String>,
        /// Properties read with every perturbation besides the axis sums.
        extra: Vec<String>,
    },
    /// Flies `n_steps` from the current trim, driving properties from the request's payload; the payload of the
    /// reply holds the `record` properties after every `record_every` steps, step-major. Reply: [`FlyReply`].
    Fly {
        /// Integration steps.
        n_steps: usize,
        /// Properties driven each step from the payload.
        drives: Vec<DriveInput>,
        /// Properties recorded, in column order.
        record: Vec<String>,
        /// Properties set once before the first step (surface overrides).
        set_before: PropertyValues,
        /// State resets during the flight (multiple shooting).
        resets: Vec<StateResetAt>,
        /// Record sample 0 and every `record_every`-th step.
        record_every: usize,
    },
    /// Writes the loaded aircraft with coefficient factors and added terms baked into its XML to `dir`.
    /// Reply: [`ExportReply`].
    Export {
        /// Output directory (absolute).
        dir: String,
        /// Coefficient function name → factor.
        knobs: PropertyValues,
        /// Added term name (`Cm_alpha2`) → coefficient.
        added: PropertyValues,
    },
    /// Mass, inertia and wing of a model at its initial condition, without a trim (an airframe description from
    /// an aircraft name); drops any aircraft loaded before. Reply: [`AirframeReply`].
    Airframe {
        /// JSBSim model name (`p51d`).
        aircraft: String,
        /// Directory the bridge works in; flightid makes and removes it.
        scratch_dir: String,
        /// Directory holding `<aircraft>.xml` to use instead of JSBSim's own.
        #[serde(skip_serializing_if = "Option::is_none")]
        aircraft_dir: Option<String>,
    },
    /// Ends the bridge process (it removes its private copy first). Reply: [`EmptyReply`].
    Quit,
}

impl Request {
    /// The command name (the `cmd` tag), for error messages.
    pub fn command(&self) -> &'static str {
        match self {
            Request::Load { .. } => "load",
            Request::Rate { .. } => "rate",
            Request::Get { .. } => "get",
            Request::Set { .. } => "set",
            Request::Trim { .. } => "trim",
            Request::Linearize { .. } => "linearize",
            Request::Probe { .. } => "probe",
            Request::Fly { .. } => "fly",
            Request::Export { .. } => "export",
            Request::Airframe { .. } => "airframe",
            Request::Quit => "quit",
        }
    }
}

/// What the bridge needs to know of one surface to rewrite the aero model around it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceReads {
    /// The FCS command property (normalised).
    pub command: String,
    /// Properties the aero model reads for the deflection; replaced by `flightid/aero/<surface>-rad`.
    pub aero_reads: Vec<String>,
    /// Properties it reads for the magnitude of the deflection; replaced by `flightid/aero/<surface>-mag-rad`.
    pub aero_reads_abs: Vec<String>,
}

/// A property driven during `fly`: its value at step k is payload element `offset + k`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DriveInput {
    /// JSBSim property.
    pub property: String,
    /// Start of its `n_steps` values in the request's payload.
    pub offset: usize,
}

/// A state reset during `fly`: after step `step` (0: before the first) the state is set to `state`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StateResetAt {
    /// Steps flown before the reset.
    pub step: usize,
    /// The values set.
    pub state: ResetState,
}

/// The state a reset sets, JSBSim units; a field left out keeps its simulated value.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ResetState {
    /// Roll angle, rad.
    #[serde(rename = "phi", skip_serializing_if = "Option::is_none")]
    pub phi_rad: Option<f64>,
    /// Pitch angle, rad.
    #[serde(rename = "theta", skip_serializing_if = "Option::is_none")]
    pub theta_rad: Option<f64>,
    /// Roll rate, rad/s.
    #[serde(rename = "p", skip_serializing_if = "Option::is_none")]
    pub p_rad_s: Option<f64>,
    /// Pitch rate, rad/s.
    #[serde(rename = "q", skip_serializing_if = "Option::is_none")]
    pub q_rad_s: Option<f64>,
    /// Yaw rate, rad/s.
    #[serde(rename = "r", skip_serializing_if = "Option::is_none")]
    pub r_rad_s: Option<f64>,
    /// Body-axis velocity u, ft/s.
    #[serde(rename = "u", skip_serializing_if = "Option::is_none")]
    pub u_fps: Option<f64>,
    /// Body-axis velocity v, ft/s.
    #[serde(rename = "v", skip_serializing_if = "Option::is_none")]
    pub v_fps: Option<f64>,
    /// Body-axis velocity w, ft/s.
    #[serde(rename = "w", skip_serializing_if = "Option::is_none")]
    pub w_fps: Option<f64>,
    /// Altitude above sea level, ft.
    #[serde(rename = "h", skip_serializing_if = "Option::is_none")]
    pub altitude_ft: Option<f64>,
    /// The values are increments to the simulated state.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub relative: bool,
}

/// The reply to a command that returns nothing but success (`rate`, `set`, `quit`).
#[derive(Debug, Clone, Deserialize)]
pub struct EmptyReply {}

/// The reply to `load`.
#[derive(Debug, Clone, Deserialize)]
pub struct LoadReply {
    /// Coefficient functions that carry a scale knob (`flightid/knob/NAME`).
    pub knobs: Vec<String>,
    /// Coefficient function name → its `<axis>` (`LIFT`, `DRAG`, `SIDE`, `ROLL`, `PITCH`, `YAW`).
    pub axes: BTreeMap<String, String>,
    /// Added aerodynamic terms the private copy offers (`flightid/added/NAME`).
    pub added_terms: Vec<String>,
}

/// The reply to `get` and `trim`: property values, JSBSim units.
#[derive(Debug, Clone, Deserialize)]
pub struct ValuesReply {
    /// Property → value.
    pub values: PropertyValues,
}

/// The reply to `airframe`: the model's mass, inertia and wing properties (JSBSim units) and its engines' mean
/// thrust line about the CG (absent for a model without a located thruster).
#[derive(Debug, Clone, Deserialize)]
pub struct AirframeReply {
    /// Property → value.
    pub values: PropertyValues,
    /// The thrust line.
    pub thrust: Option<ThrustLineReply>,
    /// What a configuration of the model needs.
    pub model: ModelFacts,
}

/// What an aircraft configuration needs from a JSBSim model's XML and its flight control system (`model_facts`
/// and `command_responses` in the bridge).
#[derive(Debug, Clone, Deserialize)]
pub struct ModelFacts {
    /// The model's own name for itself (`<fdm_config name=…>`).
    pub name: String,
    /// The `fcs/…` properties its aerodynamics read.
    pub aero_reads: Vec<String>,
    /// Engines in its propulsion section.
    pub engines: usize,
    /// Whether a landing gear contact retracts.
    pub retractable_gear: bool,
    /// The command levels of `responses`.
    pub levels: Vec<f64>,
    /// Per pilot command (`elevator`, `aileron`, `rudder`): the values of `aero_reads` once the FCS has followed
    /// the command held at each of `levels`, the other commands at 0.
    pub responses: BTreeMap<String, Vec<PropertyValues>>,
}

/// The engines' mean thrust line (`thrust_line` in the bridge).
#[derive(Debug, Clone, Copy, Deserialize)]
pub struct ThrustLineReply {
    /// Pitching moment per unit thrust about the CG, positive nose up, m.
    pub moment_arm_m: f64,
    /// The line's angle above body x, rad.
    pub inclination_rad: f64,
    /// Engines with a located thruster.
    pub engines: usize,
}

/// The reply to `probe`.
#[derive(Debug, Clone, Deserialize)]
pub struct ProbeReply {
    /// Unperturbed per-axis coefficient sums (`LIFT`, `PITCH`, …, force and moment units) and `extra` properties.
    pub base: PropertyValues,
    /// Aero input → the same values at ±h.
    pub perturbed: BTreeMap<String, Perturbation>,
    /// The `condition` properties.
    pub condition: PropertyValues,
}

/// The values read with one aero input perturbed by +h and by −h.
#[derive(Debug, Clone, Deserialize)]
pub struct Perturbation {
    /// Values at +h.
    pub plus: PropertyValues,
    /// Values at −h.
    pub minus: PropertyValues,
    /// The step, rad or rad/s.
    pub h: f64,
}

impl Perturbation {
    /// Central difference of `key`, (f(x+h) − f(x−h)) / 2h; `None` when it was not read.
    pub fn central_difference(&self, key: &str) -> Option<f64> {
        Some((self.plus.get(key)? - self.minus.get(key)?) / (2.0 * self.h))
    }
}

/// The reply to `fly` (the record itself is its payload).
#[derive(Debug, Clone, Deserialize)]
pub struct FlyReply {
    /// Recorded samples (rows of the payload).
    pub n_records: usize,
    /// Wall time of the simulation loop, s.
    pub loop_s: f64,
}

/// The reply to `export`.
#[derive(Debug, Clone, Deserialize)]
pub struct ExportReply {
    /// The written aircraft XML.
    pub path: std::path::PathBuf,
}

/// The reply to `linearize` is the [`Linearization`] itself.
pub type LinearizeReply = Linearization;

/// The status fields every reply carries: `ok`, the size of its payload and, on failure, what went wrong. A field
/// left out takes its default (a reply without `ok` failed; without `payload_f64` it has no payload).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct ReplyStatus {
    /// Whether the command succeeded.
    pub ok: bool,
    /// Number of float64 after the line.
    pub payload_f64: usize,
    /// Error kind (`trim_failed`, `unknown_aircraft`, `sim_stopped`, `protocol`, `jsbsim`, …).
    pub kind: Option<String>,
    /// Error message.
    pub error: Option<String>,
}

impl ReplyStatus {
    /// The error of a failed reply: `trim_failed` and `unknown_aircraft` have their own [`SimError`] variants,
    /// every other kind is a [`SimError::Bridge`].
    pub fn into_error(self) -> SimError {
        let message = self.error.unwrap_or_else(|| "unknown error".into());
        match self.kind.as_deref() {
            Some("trim_failed") => SimError::TrimFailed(message),
            Some("unknown_aircraft") => SimError::UnknownModel(message),
            kind => SimError::Bridge {
                kind: kind.unwrap_or("error").to_string(),
                message,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// The `cmd` tag and sorted keys of a request as it goes on the wire.
    fn wire(req: &Request) -> (String, Vec<String>) {
        let v = serde_json::to_value(req).unwrap();
        let obj = v.as_object().expect("a request is a JSON object");
        let cmd = obj["cmd"].as_str().expect("cmd is a string").to_string();
        assert_eq!(cmd, req.command(), "command() names the tag");
        let mut keys: Vec<String> = obj.keys().filter(|k| *k != "cmd").cloned().collect();
        keys.sort();
        (cmd, keys)
    }

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// Every variant with the key names the bridge script reads: a rename on either side fails here (the script's
    /// `COMMANDS` table lists the same keys).
    #[test]
    fn each_request_has_the_bridge_command_and_keys() {
        let values = PropertyValues::from([("fcs/elevator-cmd-norm".to_string(), 0.1)]);
        let cases = [
            (
                Request::Load {
                    aircraft: "c172x".into(),
                    dt_s: 1.0 / 120.0,
                    surfaces: BTreeMap::from([(
                        "elevator".to_string(),
                        SurfaceReads {
                            command: "fcs/elevator-cmd-norm".into(),
                            aero_reads: strings(&["fcs/elevator-pos-rad"]),
                            aero_reads_abs: vec![],
                        },
                    )]),
                    engine_running: true,
                    gear_up: false,
                    engines: 1,
                    scratch_dir: "/tmp/x".into(),
                    aircraft_dir: Some("/tmp/model".into()),
                },
                "load",
                vec![
                    "aircraft",
                    "aircraft_dir",
                    "dt_s",
                    "engine_running",
                    "engines",
                    "gear_up",
                    "scratch_dir",
                    "surfaces",
                ],
            ),
            (Request::Rate { dt_s: 0.01 }, "rate", vec!["dt_s"]),
            (
                Request::Get {
                    properties: strings(&["aero/alpha-rad"]),
                },
                "get",
                vec!["properties"],
            ),
            (
                Request::Set {
                    values: values.clone(),
                },
                "set",
                vec!["values"],
            ),
            (
                Request::Trim {
                    altitude_ft: 4000.0,
                    speed_kts: 100.0,
                    heading_deg: 0.0,
                    gamma_deg: 0.0,
                    latitude_deg: 0.0,
                    knobs: values.clone(),
                    report: strings(&["aero/alpha-rad"]),
                    reuse: false,
                },
                "trim",
                vec![
                    "altitude_ft",
                    "gamma_deg",
                    "heading_deg",
                    "knobs",
                    "latitude_deg",
                    "report",
                    "reuse",
                    "speed_kts",
                ],
            ),
            (
                Request::Linearize {
                    per_radian_surfaces: strings(&["elevator"]),
                },
                "linearize",
                vec!["per_radian_surfaces"],
            ),
            (
                Request::Probe {
                    perturb: PropertyValues::from([("alpha".to_string(), 1e-3)]),
                    condition: vec![],
                    extra: vec![],
                },
                "probe",
                vec!["condition", "extra", "perturb"],
            ),
            (
                Request::Fly {
                    n_steps: 10,
                    drives: vec![],
                    record: vec![],
                    set_before: values.clone(),
                    resets: vec![],
                    record_every: 1,
                },
                "fly",
                vec![
                    "drives",
                    "n_steps",
                    "record",
                    "record_every",
                    "resets",
                    "set_before",
                ],
            ),
            (
                Request::Export {
                    dir: "/tmp/out".into(),
                    knobs: values.clone(),
                    added: PropertyValues::new(),
                },
                "export",
                vec!["added", "dir", "knobs"],
            ),
            (Request::Quit, "quit", vec![]),
        ];
        for (req, cmd, keys) in cases {
            let (tag, got) = wire(&req);
            assert_eq!(tag, cmd);
            assert_eq!(got, strings(&keys), "keys of '{cmd}'");
        }
    }

    /// `load` without a model directory leaves the key out (the bridge then reads JSBSim's own aircraft).
    #[test]
    fn load_without_model_dir_omits_the_key() {
        let req = Request::Load {
            aircraft: "c172x".into(),
            dt_s: 0.01,
            surfaces: BTreeMap::new(),
            engine_running: true,
            gear_up: false,
            engines: 1,
            scratch_dir: "/tmp/x".into(),
            aircraft_dir: None,
        };
        assert!(!wire(&req).1.contains(&"aircraft_dir".to_string()));
    }

    /// The nested objects of `fly` carry the keys the script reads (`property`/`offset`, `step`/`state`, the
    /// state's short names), values unchanged; an absolute reset leaves `relative` out.
    #[test]
    fn fly_drives_and_resets_have_the_bridge_keys() {
        let req = Request::Fly {
            n_steps: 4,
            drives: vec![DriveInput {
                property: "flightid/override/elevator-rad".into(),
                offset: 0,
            }],
            record: strings(&["aero/alpha-rad"]),
            set_before: PropertyValues::new(),
            resets: vec![
                StateResetAt {
                    step: 2,
                    state: ResetState {
                        phi_rad: Some(0.1),
                        theta_rad: Some(0.2),
                        p_rad_s: Some(0.3),
                        q_rad_s: Some(0.4),
                        r_rad_s: Some(0.5),
                        u_fps: Some(150.0),
                        v_fps: Some(1.0),
                        w_fps: Some(5.0),
                        altitude_ft: Some(4000.0),
                        relative: true,
                    },
                },
                StateResetAt {
                    step: 3,
                    state: ResetState {
                        q_rad_s: Some(0.0),
                        ..ResetState::default()
                    },
                },
            ],
            record_every: 1,
        };
        let v = serde_json::to_value(&req).unwrap();
        assert_eq!(
            v["drives"],
            json!([{"property": "flightid/override/elevator-rad", "offset": 0}])
        );
        assert_eq!(
            v["resets"],
            json!([
                {"step": 2, "state": {"phi": 0.1, "theta": 0.2, "p": 0.3, "q": 0.4, "r": 0.5,
                                      "u": 150.0, "v": 1.0, "w": 5.0, "h": 4000.0, "relative": true}},
                {"step": 3, "state": {"q": 0.0}},
            ])
        );
    }

    /// A failed reply keeps its kind: the two kinds with their own variant map to them, others (a stopped
    /// simulation, a protocol error) stay `Bridge` errors with kind and message.
    #[test]
    fn error_replies_keep_their_kind() {
        let status = |line: Value| serde_json::from_value::<ReplyStatus>(line).unwrap();
        let e =
            status(json!({"ok": false, "kind": "trim_failed", "error": "no trim"})).into_error();
        assert!(matches!(e, SimError::TrimFailed(m) if m == "no trim"));
        let e =
            status(json!({"ok": false, "kind": "unknown_aircraft", "error": "no x"})).into_error();
        assert!(matches!(e, SimError::UnknownModel(m) if m == "no x"));
        let e = status(json!({"ok": false, "kind": "sim_stopped", "error": "step 3"})).into_error();
        assert!(
            matches!(e, SimError::Bridge { ref kind, ref message } if kind == "sim_stopped" && message == "step 3")
        );
        let e = status(json!({"ok": false})).into_error();
        assert!(
            matches!(e, SimError::Bridge { ref kind, ref message } if kind == "error" && message == "unknown error")
        );
    }

    /// A probe reply reads into its struct and gives central differences per key.
    #[test]
    fn probe_reply_central_difference() {
        let reply: ProbeReply = serde_json::from_value(json!({
            "ok": true, "base": {"PITCH": 1.0}, "condition": {},
            "perturbed": {"alpha": {"plus": {"PITCH": 3.0}, "minus": {"PITCH": -1.0}, "h": 0.5}},
        }))
        .unwrap();
        let p = &reply.perturbed["alpha"];
        assert_eq!(p.central_difference("PITCH"), Some(4.0));
        assert_eq!(p.central_difference("LIFT"), None);
    }
}
