//! [`Simulator`] backed by the official JSBSim through the bridge process.

use super::bridge::Bridge;
use super::protocol::{
    DriveInput, EmptyReply, ExportReply, FlyReply, LoadReply, ProbeReply, PropertyValues, Request,
    ResetState, StateResetAt, SurfaceReads, ValuesReply,
};
use super::{
    FlightPlan, Linearization, SimError, Simulator, StateReset, TrimMethod, TrimPoint, TrimState,
    FT_TO_M,
};
use crate::aircraft::{AircraftConfig, Drive};
use crate::data::{Channel, FlightRecord};
use std::collections::BTreeMap;

/// Perturbation of each aero input in the bridge's probe: rad for angles and surfaces, rad/s for rates.
pub(super) fn probe_steps() -> PropertyValues {
    [
        ("alpha", 1e-3),
        ("beta", 1e-3),
        ("p", 1e-2),
        ("q", 1e-2),
        ("r", 1e-2),
        ("alphadot", 1e-2),
        ("betadot", 1e-2),
        ("surface:elevator", 1e-3),
        ("surface:aileron", 1e-3),
        ("surface:rudder", 1e-3),
    ]
    .into_iter()
    .map(|(input, h)| (input.to_string(), h))
    .collect()
}

/// Recorded channels: (schema column, JSBSim property, factor to SI). Surfaces are added per aircraft.
const RECORDED: &[(Channel, &str, f64)] = &[
    (Channel::Throttle, "fcs/throttle-pos-norm", 1.0),
    (Channel::Phi, "attitude/phi-rad", 1.0),
    (Channel::Theta, "attitude/theta-rad", 1.0),
    (Channel::Psi, "attitude/psi-rad", 1.0),
    (Channel::P, "velocities/p-rad_sec", 1.0),
    (Channel::Q, "velocities/q-rad_sec", 1.0),
    (Channel::R, "velocities/r-rad_sec", 1.0),
    (Channel::Alpha, "aero/alpha-rad", 1.0),
    (Channel::Beta, "aero/beta-rad", 1.0),
    (Channel::Airspeed, "velocities/vt-fps", FT_TO_M),
    (Channel::Altitude, "position/h-sl-ft", FT_TO_M),
    (Channel::Ax, "accelerations/a-pilot-x-ft_sec2", FT_TO_M),
    (Channel::Ay, "accelerations/a-pilot-y-ft_sec2", FT_TO_M),
    (Channel::Az, "accelerations/a-pilot-z-ft_sec2", FT_TO_M),
];

/// The trim reply's key that says which trim found the state: 1 flightid's Newton trim, 0 JSBSim's full trim.
const TRIM_METHOD_KEY: &str = "flightid/trim-method";

/// Surfaces in CSV column order.
pub const SURFACES: [&str; 3] = ["elevator", "aileron", "rudder"];

/// JSBSim (one bridge process, one aircraft loaded).
pub struct JsbsimSim {
    pub(super) bridge: Bridge,
    config: AircraftConfig,
    rate_hz: f64,
    pub(super) trim: Option<TrimState>,
    knob_values: BTreeMap<String, f64>,
    /// Trim once per trim point and restore the snapshot on later trims (see [`JsbsimSim::set_trim_reuse`]).
    reuse_trims: bool,
    /// Names of the aerodynamic coefficient functions that carry a scale knob (`flightid/knob/NAME`).
    pub coefficient_knobs: Vec<String>,
    /// Added aerodynamic terms the private copy offers (`flightid/added/NAME`, default 0), e.g. `Cm_alpha2`.
    pub added_terms: Vec<String>,
    /// Coefficient function name → the `<axis>` it belongs to (`LIFT`, `DRAG`, `SIDE`, `ROLL`, `PITCH`, `YAW`).
    pub coefficient_axes: BTreeMap<String, String>,
    /// Extra JSBSim properties every `fly` records, each as a column named by its property path (JSBSim
    /// units), e.g. `aero/coefficient/Clr` for the error attribution of `study::attribution`.
    pub extra_record: Vec<String>,
}

/// Slopes of properties with respect to the aero inputs: input (`alpha`, `q`, `surface:elevator`, …) →
/// property → d(property)/d(input), per rad or rad/s.
pub type PropertySlopes = BTreeMap<String, BTreeMap<String, f64>>;

fn surface_property(surface: &str) -> String {
    format!("flightid/aero/{surface}-rad")
}

impl JsbsimSim {
    /// Starts a bridge and loads the aircraft (a private copy, see `scripts/jsbsim_bridge.py`) at `rate_hz`.
    pub fn start(config: &AircraftConfig, rate_hz: f64) -> Result<Self, SimError> {
        Self::start_with_model(config, rate_hz, None)
    }

    /// Like [`JsbsimSim::start`], with the aircraft XML taken from `model_dir` (an exported model, see
    /// [`JsbsimSim::export_aircraft`]) instead of JSBSim's own.
    pub fn start_with_model(
        config: &AircraftConfig,
        rate_hz: f64,
        model_dir: Option<&std::path::Path>,
    ) -> Result<Self, SimError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(SimError::Usage(format!(
                "simulation rate must be positive, got {rate_hz} Hz"
            )));
        }
        Self::load(Bridge::spawn()?, config, rate_hz, model_dir)
    }

    /// Loads another aircraft (or the same one afresh) into this simulator's bridge process: a new JSBSim
    /// instance and private aircraft copy, as after [`JsbsimSim::start`], without the process start (Python
    /// start and `import jsbsim`, ~0.15 s CPU). Knobs, pre-trim properties and trim snapshots are not carried over.
    pub fn reload(self, config: &AircraftConfig, rate_hz: f64) -> Result<Self, SimError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(SimError::Usage(format!(
                "simulation rate must be positive, got {rate_hz} Hz"
            )));
        }
        Self::load(self.bridge, config, rate_hz, None)
    }

    /// Sends `load` (aircraft, rate, surfaces, model directory) to a bridge.
    fn load(
        mut bridge: Bridge,
        config: &AircraftConfig,
        rate_hz: f64,
        model_dir: Option<&std::path::Path>,
    ) -> Result<Self, SimError> {
        let surfaces = config
            .surfaces
            .iter()
            .map(|(name, s)| {
                let reads = SurfaceReads {
                    command: s.command.clone(),
                    aero_reads: s.aero_reads.clone(),
                    aero_reads_abs: s.aero_reads_abs.clone(),
                };
                (name.clone(), reads)
            })
            .collect();
        let aircraft_dir = match model_dir {
            Some(dir) => {
                let abs = std::fs::canonicalize(dir).map_err(|e| {
                    SimError::UnknownModel(format!("model directory {}: {e}", dir.display()))
                })?;
                Some(abs.display().to_string())
            }
            None => None,
        };
        let req = Request::Load {
            aircraft: config.model.clone(),
            dt_s: 1.0 / rate_hz,
            surfaces,
            engine_running: config.engine_running,
            gear_up: config.gear_up,
            engines: config.engines,
            scratch_dir: bridge.scratch_dir().display().to_string(),
            aircraft_dir,
        };
        let loaded: LoadReply = bridge.request(&req, &[])?.reply;
        let mut sim = JsbsimSim {
            bridge,
            config: config.clone(),
            rate_hz,
            trim: None,
            knob_values: BTreeMap::new(),
            reuse_trims: false,
            coefficient_knobs: loaded.knobs,
            added_terms: loaded.added_terms,
            coefficient_axes: loaded.axes,
            extra_record: Vec::new(),
        };
        // The configuration's loading: each property must exist in the model, or the load fails naming it.
        for (property, value) in &config.properties {
            sim.set_pre_trim_property(property, *value).map_err(|e| {
                SimError::Loading(format!(
                    "the loading of aircraft '{}' ({property} = {value}): {e}",
                    config.name
                ))
            })?;
        }
        Ok(sim)
    }

    /// Values of `properties` at the current trim and their slopes with respect to each aero input (α, β, p, q,
    /// r, α̇, β̇, surfaces), from the bridge's probe: integration suspended, central differences, the same
    /// perturbations as [`JsbsimSim::aero_truth`].
    pub fn probe_slopes(
        &mut self,
        properties: &[String],
    ) -> Result<(BTreeMap<String, f64>, PropertySlopes), SimError> {
        if self.trim.is_none() {
            return Err(SimError::Usage(
                "probe_slopes needs a successful trim first".into(),
            ));
        }
        let req = Request::Probe {
            perturb: probe_steps(),
            condition: vec![],
            extra: properties.to_vec(),
        };
        let probe: ProbeReply = self.bridge.request(&req, &[])?.reply;
        let slopes = probe
            .perturbed
            .iter()
            .map(|(var, p)| {
                let row = properties
                    .iter()
                    .map(|prop| {
                        let slope = p.central_difference(prop).unwrap_or(f64::NAN);
                        (prop.clone(), slope)
                    })
                    .collect();
                (var.clone(), row)
            })
            .collect();
        Ok((probe.base, slopes))
    }

    /// The bridge's process id (for supervision and tests).
    pub fn bridge_pid(&self) -> u32 {
        self.bridge.pid()
    }

    /// The aircraft configuration in use.
    pub fn config(&self) -> &AircraftConfig {
        &self.config
    }

    /// Simulation rate, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Integrates at `rate_hz` from the next trim on (the same process and aircraft; a trim is needed before
    /// the next flight).
    pub fn set_rate_hz(&mut self, rate_hz: f64) -> Result<(), SimError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(SimError::Usage(format!(
                "simulation rate must be positive, got {rate_hz} Hz"
            )));
        }
        let req = Request::Rate {
            dt_s: 1.0 / rate_hz,
        };
        self.bridge.request::<EmptyReply>(&req, &[])?;
        self.rate_hz = rate_hz;
        self.trim = None;
        Ok(())
    }

    /// Sets the factor on an aerodynamic coefficient function (e.g. `Cmalpha`), applied from the next trim on.
    pub fn set_coefficient_scale(
        &mut self,
        coefficient: &str,
        factor: f64,
    ) -> Result<(), SimError> {
        if !self.coefficient_knobs.iter().any(|k| k == coefficient) {
            return Err(SimError::Usage(format!(
                "aircraft '{}' has no aerodynamic coefficient '{coefficient}' (it has: {})",
                self.config.name,
                self.coefficient_knobs.join(", ")
            )));
        }
        self.knob_values
            .insert(format!("flightid/knob/{coefficient}"), factor);
        Ok(())
    }

    /// Sets a JSBSim property before every trim, after the models are reset (a mass/CG variant such as
    /// `inertia/pointmass-weight-lbs[4]` or `propulsion/tank[0]/contents-lbs`). Unknown properties are refused.
    pub fn set_pre_trim_property(&mut self, property: &str, value: f64) -> Result<(), SimError> {
        if !value.is_finite() {
            return Err(SimError::Usage(format!(
                "property '{property}': value {value} is not finite"
            )));
        }
        self.get_properties(&[property])?;
        self.knob_values.insert(property.to_string(), value);
        Ok(())
    }

    /// Trim each point (with the current knobs) once per process and restore that trimmed state on every later
    /// trim at the same point, instead of a full JSBSim trim (campaigns: ~0.5 ms instead of 3-9 ms per case).
    /// Every trim, the first included, then leaves the restored snapshot, so the state does not depend on what
    /// the process flew before (bit for bit); it flies like a live trim to ~1e-8 rad (c172x: max |Δθ| 8e-9 rad
    /// over a 20 s doublet, engine temperatures JSBSim cannot set; 737: 1e-15). See `Sim.restore` in the bridge.
    pub fn set_trim_reuse(&mut self, on: bool) {
        self.reuse_trims = on;
    }

    /// Forgets every coefficient scale, pre-trim property and added term: from the next trim on the aircraft is
    /// the configured one again, with the configuration's own loading (the bridge puts every other property back
    /// to its value in a fresh process), so one process can serve several configurations of an aircraft.
    pub fn clear_configuration(&mut self) {
        self.knob_values.clear();
        for (property, value) in &self.config.properties {
            self.knob_values.insert(property.clone(), *value);
        }
    }

    /// The properties a trim at `point` sets after the model reset: the knobs, and the day's temperature where the
    /// point has one (in °R, JSBSim's unit; it replaces a `--property atmosphere/delta-T`).
    fn trim_knobs(&self, point: &TrimPoint) -> BTreeMap<String, f64> {
        let mut knobs = self.knob_values.clone();
        if point.temperature_offset_k != 0.0 {
            knobs.insert(
                "atmosphere/delta-T".into(),
                1.8 * point.temperature_offset_k,
            );
        }
        knobs
    }

    /// Reads arbitrary JSBSim properties (current state).
    pub fn get_properties(&mut self, names: &[&str]) -> Result<BTreeMap<String, f64>, SimError> {
        let req = Request::Get {
            properties: names.iter().map(|n| n.to_string()).collect(),
        };
        let got: ValuesReply = self.bridge.request(&req, &[])?.reply;
        Ok(got.values)
    }
}

impl Simulator for JsbsimSim {
    fn trim(&mut self, point: &TrimPoint) -> Result<TrimState, SimError> {
        self.trim = None;
        let mut report: Vec<String> = [
            "aero/alpha-rad",
            "attitude/theta-rad",
            "attitude/phi-rad",
            "aero/beta-rad",
            "velocities/vt-fps",
            "position/h-sl-ft",
            "fcs/throttle-pos-norm",
            "fcs/throttle-cmd-norm",
            "fcs/pitch-trim-cmd-norm",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for (name, s) in &self.config.surfaces {
            report.push(surface_property(name));
            report.push(s.command.clone());
        }
        let req = Request::Trim {
            altitude_ft: point.altitude_ft,
            speed_kts: point.speed_kts,
            heading_deg: point.heading_deg,
            gamma_deg: point.gamma_deg,
            latitude_deg: point.latitude_deg,
            knobs: self.trim_knobs(point),
            report,
            reuse: self.reuse_trims,
        };
        let trimmed: ValuesReply = self.bridge.request(&req, &[])?.reply;
        let v = trimmed.values;
        let get = |k: &str| v.get(k).copied().unwrap_or(f64::NAN);
        let mut surfaces_rad = BTreeMap::new();
        let mut commands_norm = BTreeMap::new();
        for (name, s) in &self.config.surfaces {
            surfaces_rad.insert(name.clone(), get(&surface_property(name)));
            commands_norm.insert(name.clone(), get(&s.command));
        }
        commands_norm.insert("pitch-trim".into(), get("fcs/pitch-trim-cmd-norm"));
        commands_norm.insert("throttle".into(), get("fcs/throttle-cmd-norm"));
        let state = TrimState {
            aircraft: self.config.name.clone(),
            point: *point,
            alpha_rad: get("aero/alpha-rad"),
            theta_rad: get("attitude/theta-rad"),
            phi_rad: get("attitude/phi-rad"),
            beta_rad: get("aero/beta-rad"),
            airspeed_m_s: get("velocities/vt-fps") * FT_TO_M,
            altitude_m: get("position/h-sl-ft") * FT_TO_M,
            throttle: get("fcs/throttle-pos-norm"),
            surfaces_rad,
            commands_norm,
            method: if get(TRIM_METHOD_KEY) == 1.0 {
                TrimMethod::Newton
            } else {
                TrimMethod::JsbsimFull
            },
        };
        let all_finite = [
            state.alpha_rad,
            state.theta_rad,
            state.airspeed_m_s,
            state.throttle,
        ]
        .iter()
        .chain(state.surfaces_rad.values())
        .all(|x| x.is_finite());
        if !all_finite {
            return Err(SimError::TrimFailed(format!(
                "{} at {} ft, {} kts: JSBSim reported a non-finite trim state",
                self.config.name, point.altitude_ft, point.speed_kts
            )));
        }
        self.trim = Some(state.clone());
        Ok(state)
    }

    fn linearize(&mut self) -> Result<Linearization, SimError> {
        if self.trim.is_none() {
            return Err(SimError::Usage(
                "linearize needs a successful trim first".into(),
            ));
        }
        let per_radian_surfaces = match self.config.drive {
            Drive::Surface => SURFACES.iter().map(|s| s.to_string()).collect(),
            Drive::Command => vec![],
        };
        let req = Request::Linearize {
            per_radian_surfaces,
        };
        let mut lin: Linearization = self.bridge.request(&req, &[])?.reply;
        // JSBSim names its inputs ThtlCmd, DaCmd, DeCmd, DrCmd; make them per radian of surface deflection.
        for (j, name) in lin.inputs.clone().iter().enumerate() {
            let surface = match name.as_str() {
                "DaCmd" => "aileron",
                "DeCmd" => "elevator",
                "DrCmd" => "rudder",
                _ => continue,
            };
            let scale = match self.config.drive {
                Drive::Surface => 1.0,
                Drive::Command => {
                    1.0 / self
                        .config
                        .surface(surface)
                        .map_err(|e| SimError::Usage(e.to_string()))?
                        .rad_per_norm
                }
            };
            for row in lin.b.iter_mut().chain(lin.d.iter_mut()) {
                row[j] *= scale;
            }
            lin.inputs[j] = surface.to_string();
            lin.input_units[j] = "rad".to_string();
        }
        Ok(lin)
    }

    fn fly(&mut self, plan: &FlightPlan) -> Result<FlightRecord, SimError> {
        self.fly_with_resets(plan, &[])
    }
}

impl JsbsimSim {
    /// Flies `plan` from the current trim and sets the state at each of `resets` (multiple shooting: each
    /// reset starts a segment from a given state). With no resets this is [`Simulator::fly`].
    pub fn fly_with_resets(
        &mut self,
        plan: &FlightPlan,
        resets: &[StateReset],
    ) -> Result<FlightRecord, SimError> {
        self.fly_recording_every(plan, resets, 1)
    }

    /// [`JsbsimSim::fly_with_resets`] recording only every `every`-th step (sample 0 and the state after steps
    /// `every`, `2 every`, …; `plan.n_steps` must be a multiple of `every`): a replay that integrates at a multiple
    /// of its record's rate reads and transfers only the record's samples (the same values as
    /// `fly_with_resets(..).every_nth(every)`, bit for bit).
    pub fn fly_recording_every(
        &mut self,
        plan: &FlightPlan,
        resets: &[StateReset],
        every: usize,
    ) -> Result<FlightRecord, SimError> {
        if every == 0 || !plan.n_steps.is_multiple_of(every) {
            return Err(SimError::Usage(format!(
                "recording every {every} steps of a {}-step flight: the steps must be a whole multiple",
                plan.n_steps
            )));
        }
        let trim = self
            .trim
            .take()
            .ok_or_else(|| SimError::Usage("fly needs a successful trim first".into()))?;
        if (plan.rate_hz - self.rate_hz).abs() > 1e-9 {
            return Err(SimError::Usage(format!(
                "plan rate {} Hz differs from the simulation rate {} Hz",
                plan.rate_hz, self.rate_hz
            )));
        }
        let n = plan.n_steps;
        let mut drives = Vec::new();
        let mut payload = Vec::with_capacity(n * plan.inputs.len());
        let mut set_before = PropertyValues::new();
        for input in &plan.inputs {
            if input.deflection_rad.len() != n {
                return Err(SimError::Usage(format!(
                    "{} input has {} values for {} steps",
                    input.surface,
                    input.deflection_rad.len(),
                    n
                )));
            }
            if input.surface == "throttle" {
                // Throttle moves relative to its trim on every engine; values are positions 0..1 (not radians).
                let offset = payload.len();
                let base = trim.commands_norm["throttle"];
                payload.extend(
                    input
                        .deflection_rad
                        .iter()
                        .map(|d| (base + d).clamp(0.0, 1.0)),
                );
                for i in 0..self.config.engines {
                    drives.push(DriveInput {
                        property: format!("fcs/throttle-cmd-norm[{i}]"),
                        offset,
                    });
                }
                continue;
            }
            let sc = self
                .config
                .surface(&input.surface)
                .map_err(|e| SimError::Usage(e.to_string()))?;
            let offset = payload.len();
            match self.config.drive {
                Drive::Surface => {
                    let base = trim.surfaces_rad[&input.surface];
                    payload.extend(input.deflection_rad.iter().map(|d| base + d));
                    set_before.insert(format!("flightid/override/{}", input.surface), 1.0);
                    set_before.insert(format!("flightid/override/{}-rad", input.surface), base);
                    drives.push(DriveInput {
                        property: format!("flightid/override/{}-rad", input.surface),
                        offset,
                    });
                }
                Drive::Command => {
                    let base = trim.commands_norm[&input.surface];
                    payload.extend(
                        input
                            .deflection_rad
                            .iter()
                            .map(|d| base + d / sc.rad_per_norm),
                    );
                    drives.push(DriveInput {
                        property: sc.command.clone(),
                        offset,
                    });
                }
            }
        }
        if self.config.drive == Drive::Surface {
            // Bare airframe: the surfaces the plan does not move hold their trim deflection, as in the per-radian
            // linearization (which overrides every surface). Left to the FCS, feedback through them (the 737's
            // yaw damper on the rudder) would act in flight but not in the linear model: the 737's φ/δa
            // linearization fitted its own aileron flight at 77 % that way, 98.7 % in command space.
            for s in SURFACES {
                let held = format!("flightid/override/{s}");
                if set_before.contains_key(&held) {
                    continue;
                }
                if let Some(base) = trim.surfaces_rad.get(s) {
                    set_before.insert(held, 1.0);
                    set_before.insert(format!("flightid/override/{s}-rad"), *base);
                }
            }
        }
        let mut record: Vec<String> = SURFACES.iter().map(|s| surface_property(s)).collect();
        record.extend(RECORDED.iter().map(|(_, p, _)| p.to_string()));
        record.extend(self.extra_record.iter().cloned());
        let mut resets_wire = Vec::new();
        for r in resets {
            if r.step > n || (r.relative && r.airspeed_alpha_beta.is_some()) {
                return Err(SimError::Usage(format!(
                    "a state reset after step {} of a {n}-step flight{}",
                    r.step,
                    if r.relative {
                        " (an increment cannot be given as airspeed, alpha, beta)"
                    } else {
                        ""
                    }
                )));
            }
            resets_wire.push(StateResetAt {
                step: r.step,
                state: reset_state_ft(r),
            });
        }
        let width = record.len();
        let req = Request::Fly {
            n_steps: n,
            drives,
            record,
            set_before,
            resets: resets_wire,
            record_every: every,
        };
        let resp = self.bridge.request::<FlyReply>(&req, &payload)?;
        let rows = resp.payload.len() / width;
        if rows != n / every + 1 || resp.payload.len() % width != 0 || resp.reply.n_records != rows
        {
            return Err(SimError::Protocol(format!(
                "fly returned {} values in {} records, expected {}",
                resp.payload.len(),
                resp.reply.n_records,
                (n / every + 1) * width
            )));
        }
        let mut rec = FlightRecord::new(
            (0..rows)
                .map(|k| (k * every) as f64 / self.rate_hz)
                .collect(),
        );
        let column = |j: usize, factor: f64| -> Vec<f64> {
            (0..rows)
                .map(|k| resp.payload[k * width + j] * factor)
                .collect()
        };
        for (j, s) in SURFACES.iter().enumerate() {
            rec.push_column(format!("{s}_rad"), column(j, 1.0));
        }
        for (i, (name, _, factor)) in RECORDED.iter().enumerate() {
            let values = column(SURFACES.len() + i, *factor);
            if *name == Channel::Psi {
                rec.push_column(name, crate::signal::heading_from_zero_rad(&values));
            } else {
                rec.push_column(name, values);
            }
        }
        for (i, prop) in self.extra_record.iter().enumerate() {
            rec.push_column(prop, column(SURFACES.len() + RECORDED.len() + i, 1.0));
        }
        rec.metadata.push(format!(
            "aircraft: {} (JSBSim model {})",
            self.config.name, self.config.model
        ));
        rec.metadata.push(format!(
            "trim: {} ft, {} kts; alpha {:.6} rad, theta {:.6} rad",
            trim.point.altitude_ft, trim.point.speed_kts, trim.alpha_rad, trim.theta_rad
        ));
        rec.metadata.push(format!(
            "drive: {:?}; rate {} Hz",
            self.config.drive, self.rate_hz
        ));
        Ok(rec)
    }
}

/// A state reset in the bridge's units (ft, ft/s): the body velocity from `uvw_m_s` if given, else from the airspeed,
/// angle of attack and sideslip.
fn reset_state_ft(r: &StateReset) -> ResetState {
    let rates = r
        .rates_rad_s
        .map(|rates| rates.map(Some))
        .unwrap_or_default();
    let uvw_fps = match (r.uvw_m_s, r.airspeed_alpha_beta) {
        (Some(uvw), _) => Some(uvw.map(|x| x / FT_TO_M)),
        (None, Some((v_m_s, alpha, beta))) => {
            // Body axes, no wind: u = V cos α cos β, v = V sin β, w = V sin α cos β.
            let v_fps = v_m_s / FT_TO_M;
            Some([
                v_fps * alpha.cos() * beta.cos(),
                v_fps * beta.sin(),
                v_fps * alpha.sin() * beta.cos(),
            ])
        }
        (None, None) => None,
    };
    let uvw = uvw_fps.map(|uvw| uvw.map(Some)).unwrap_or_default();
    ResetState {
        phi_rad: r.phi_rad,
        theta_rad: r.theta_rad,
        p_rad_s: rates[0],
        q_rad_s: rates[1],
        r_rad_s: rates[2],
        u_fps: uvw[0],
        v_fps: uvw[1],
        w_fps: uvw[2],
        altitude_ft: r.altitude_m.map(|h| h / FT_TO_M),
        relative: r.relative,
    }
}

impl JsbsimSim {
    /// Sets the coefficient of an added aerodynamic term (e.g. `Cm_alpha2`: ΔC_m = k α²), from the next trim on.
    pub fn set_added_term(&mut self, term: &str, coefficient: f64) -> Result<(), SimError> {
        if !self.added_terms.iter().any(|t| t == term) {
            return Err(SimError::Usage(format!(
                "no added aerodynamic term '{term}' (known: {})",
                self.added_terms.join(", ")
            )));
        }
        self.knob_values
            .insert(format!("flightid/added/{term}"), coefficient);
        Ok(())
    }

    /// Writes the aircraft with the current coefficient factors and added terms written into its XML to
    /// `dir/<model>.xml` (plus the aircraft directory's other files), loadable by [`JsbsimSim::start_with_model`].
    pub fn export_aircraft(
        &mut self,
        dir: &std::path::Path,
    ) -> Result<std::path::PathBuf, SimError> {
        std::fs::create_dir_all(dir)
            .map_err(|e| SimError::Usage(format!("creating {}: {e}", dir.display())))?;
        let abs = std::fs::canonicalize(dir)
            .map_err(|e| SimError::Usage(format!("{}: {e}", dir.display())))?;
        let pick = |prefix: &str| -> PropertyValues {
            self.knob_values
                .iter()
                .filter_map(|(k, v)| k.strip_prefix(prefix).map(|n| (n.to_string(), *v)))
                .collect()
        };
        let req = Request::Export {
            dir: abs.display().to_string(),
            knobs: pick("flightid/knob/"),
            added: pick("flightid/added/"),
        };
        let exported: ExportReply = self.bridge.request(&req, &[])?.reply;
        Ok(exported.path)
    }
}
