//! Replay: trim the simulation at the measured initial condition and drive it with the measured
//! surface deflections (as deviations from their initial values), optionally through model extensions.

use std::collections::BTreeMap;

use super::extension::{Extension, Stage};
use super::DiagnoseError;
use crate::data::FlightRecord;
use crate::sim::{
    FlightPlan, JsbsimSim, LinearSim, SimError, Simulator, SurfaceInput, TrimPoint, TrimState,
    FT_TO_M, KTS_TO_M_S,
};
use serde::Serialize;

/// A simulation that can be replayed: JSBSim or a linear model (no coefficient knobs).
pub trait ReplaySim: Simulator + Send {
    /// Names of the aerodynamic coefficient functions that can be scaled.
    fn coefficient_names(&self) -> Vec<String>;
    /// Sets the factor on a coefficient function from the next trim on.
    fn set_coefficient_scale(&mut self, name: &str, factor: f64) -> Result<(), SimError>;
    /// Names of the added aerodynamic terms the simulation offers (e.g. `Cm_alpha2`).
    fn added_term_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Sets the coefficient of an added term from the next trim on.
    fn set_added_term(&mut self, name: &str, _coefficient: f64) -> Result<(), SimError> {
        Err(SimError::Usage(format!(
            "this simulation has no added aerodynamic term '{name}'"
        )))
    }
    /// The rate the simulation integrates at, Hz (None: it runs at whatever rate the plan asks for).
    fn rate_hz(&self) -> Option<f64> {
        None
    }
    /// Writes the model with the current coefficient factors and added terms in it to `dir`.
    fn export_model(&mut self, dir: &std::path::Path) -> Result<std::path::PathBuf, SimError> {
        Err(SimError::Usage(format!(
            "this simulation cannot be exported as a model ({})",
            dir.display()
        )))
    }
}

impl ReplaySim for JsbsimSim {
    fn rate_hz(&self) -> Option<f64> {
        Some(JsbsimSim::rate_hz(self))
    }
    fn coefficient_names(&self) -> Vec<String> {
        self.coefficient_knobs.clone()
    }
    fn set_coefficient_scale(&mut self, name: &str, factor: f64) -> Result<(), SimError> {
        JsbsimSim::set_coefficient_scale(self, name, factor)
    }
    fn added_term_names(&self) -> Vec<String> {
        self.added_terms.clone()
    }
    fn set_added_term(&mut self, name: &str, coefficient: f64) -> Result<(), SimError> {
        JsbsimSim::set_added_term(self, name, coefficient)
    }
    fn export_model(&mut self, dir: &std::path::Path) -> Result<std::path::PathBuf, SimError> {
        self.export_aircraft(dir)
    }
}

/// Surface inputs of the CSV schema: (surface name, column).
pub const INPUTS: [(&str, &str); 4] = [
    ("elevator", "elevator_rad"),
    ("aileron", "aileron_rad"),
    ("rudder", "rudder_rad"),
    ("throttle", "throttle"),
];

/// Output columns compared between data and simulation (those present in both).
/// (`psi_rad` is left out: heading wraps at 2π and drifts without bound.)
pub const OUTPUTS: [&str; 12] = [
    "phi_rad",
    "theta_rad",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "alpha_rad",
    "beta_rad",
    "airspeed_m_s",
    "altitude_m",
    "ax_m_s2",
    "ay_m_s2",
    "az_m_s2",
];

/// Lowest integration rate of a replay, Hz: a record logged slower is replayed at a whole multiple of its rate.
pub const MIN_SIM_RATE_HZ: f64 = 100.0;

/// A measured record prepared for replay: uniform grid, trim point, input deviations, compared outputs.
#[derive(Debug, Clone)]
pub struct ReplayCase {
    /// The record on a uniform time grid.
    pub record: FlightRecord,
    /// Sampling rate, Hz.
    pub rate_hz: f64,
    /// Trim point at the measured initial condition.
    pub point: TrimPoint,
    /// Measured initial values of inputs and states (mean over the quiet start of the record).
    pub initial: BTreeMap<String, f64>,
    /// Measured input deviations from their initial values, one per sample (surface name, values).
    pub inputs: Vec<(String, Vec<f64>)>,
    /// Output columns compared.
    pub outputs: Vec<String>,
}

/// Model trim versus measured initial condition (a trim mismatch is evidence of a model error).
#[derive(Debug, Clone, Serialize)]
pub struct TrimMismatch {
    /// Quantity: `elevator_rad`, `alpha_rad`, ...
    pub quantity: String,
    /// Measured initial value.
    pub measured: f64,
    /// Model trim value.
    pub model: f64,
}

impl ReplayCase {
    /// Prepares a record: resamples to a uniform grid if needed, finds the quiet start, builds the trim point.
    pub fn new(record: &FlightRecord) -> Result<Self, DiagnoseError> {
        let n = record.len();
        if n < 50 {
            return Err(DiagnoseError::TooShort(format!(
                "{n} samples; replay and identification need at least 50"
            )));
        }
        let t = &record.time_s;
        let duration = t[n - 1] - t[0];
        let dt = duration / (n - 1) as f64;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(DiagnoseError::BadData("time_s does not increase".into()));
        }
        let uniform = t.windows(2).all(|w| ((w[1] - w[0]) - dt).abs() < 1e-3 * dt);
        let rec = if uniform {
            let mut r = record.clone();
            r.time_s = (0..n).map(|k| k as f64 * dt).collect();
            r
        } else {
            let grid: Vec<f64> = (0..n).map(|k| t[0] + k as f64 * dt).collect();
            let mut r = FlightRecord::new((0..n).map(|k| k as f64 * dt).collect());
            r.metadata = record.metadata.clone();
            for (name, col) in &record.columns {
                r.push_column(name, crate::signal::resample_linear(t, col, &grid));
            }
            r
        };
        for c in ["airspeed_m_s", "altitude_m"] {
            rec.require(
                c,
                "replay trims the model at the measured airspeed and altitude",
            )
            .map_err(|e| DiagnoseError::BadData(e.to_string()))?;
        }
        let present_inputs: Vec<(&str, &str)> = INPUTS
            .iter()
            .copied()
            .filter(|(_, c)| rec.column(c).is_some())
            .collect();
        if present_inputs.is_empty() {
            return Err(DiagnoseError::BadData(
                "the data have no surface column (elevator_rad, aileron_rad, rudder_rad, throttle)"
                    .into(),
            ));
        }
        // Quiet start: until any input moves by more than 1 mrad (0.001 throttle) or 0.5 s pass.
        let mut quiet = 1;
        while quiet < n && quiet as f64 * dt < 0.5 {
            let moved = present_inputs.iter().any(|(_, c)| {
                let x = rec.column(c).unwrap_or(&[]);
                (x[quiet] - x[0]).abs() > 1e-3
            });
            if moved {
                break;
            }
            quiet += 1;
        }
        let mean0 = |x: &[f64]| x[..quiet].iter().sum::<f64>() / quiet as f64;
        let mut initial = BTreeMap::new();
        for (name, col) in &rec.columns {
            // Heading wraps at 2π: an arithmetic mean of samples on both sides of north points south.
            let v = if name == "psi_rad" {
                circular_mean(&col[..quiet])
            } else {
                mean0(col)
            };
            initial.insert(name.clone(), v);
        }
        let inputs = present_inputs
            .iter()
            .map(|(s, c)| {
                let x = rec.column(c).unwrap_or(&[]);
                let x0 = initial[*c];
                (s.to_string(), x.iter().map(|v| v - x0).collect())
            })
            .collect();
        let outputs = OUTPUTS
            .iter()
            .filter(|c| rec.column(c).is_some())
            .map(|c| c.to_string())
            .collect();
        let heading_deg = initial
            .get("psi_rad")
            .map(|p| p.to_degrees())
            .unwrap_or(0.0);
        let point = TrimPoint {
            altitude_ft: initial["altitude_m"] / FT_TO_M,
            speed_kts: initial["airspeed_m_s"] / KTS_TO_M_S,
            heading_deg: heading_deg.rem_euclid(360.0),
            gamma_deg: 0.0,
        };
        if !(point.speed_kts > 1.0 && point.altitude_ft.is_finite()) {
            return Err(DiagnoseError::BadData(format!(
                "initial airspeed {:.2} m/s / altitude {:.1} m cannot be a trim point",
                initial["airspeed_m_s"], initial["altitude_m"]
            )));
        }
        Ok(ReplayCase {
            rate_hz: 1.0 / dt,
            record: rec,
            point,
            initial,
            inputs,
            outputs,
        })
    }

    /// The rate a simulation replaying this record should integrate at: the smallest whole multiple of the
    /// record's rate that is at least [`MIN_SIM_RATE_HZ`] (the record's samples are interpolated in between).
    pub fn sim_rate_hz(&self) -> f64 {
        self.rate_hz * (MIN_SIM_RATE_HZ / self.rate_hz - 1e-9).ceil().max(1.0)
    }

    /// Time step, s.
    pub fn dt_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.record.len()
    }

    /// True when the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.record.is_empty()
    }

    /// Measured column.
    pub fn measured(&self, column: &str) -> &[f64] {
        self.record.column(column).unwrap_or(&[])
    }

    /// Compares the model trim with the measured initial condition.
    pub fn trim_mismatch(&self, trim: &TrimState) -> Vec<TrimMismatch> {
        let mut out = Vec::new();
        let mut push = |q: &str, model: f64| {
            if let Some(m) = self.initial.get(q) {
                out.push(TrimMismatch {
                    quantity: q.to_string(),
                    measured: *m,
                    model,
                });
            }
        };
        for (s, c) in INPUTS {
            if s == "throttle" {
                push(c, trim.throttle);
            } else if let Some(v) = trim.surfaces_rad.get(s) {
                push(c, *v);
            }
        }
        push("alpha_rad", trim.alpha_rad);
        push("theta_rad", trim.theta_rad);
        push("phi_rad", trim.phi_rad);
        push("beta_rad", trim.beta_rad);
        out
    }
}

/// Mean direction of angles, atan2(Σ sin θ, Σ cos θ) (Mardia & Jupp, Directional Statistics, §2.2.1), rad.
pub fn circular_mean(angles_rad: &[f64]) -> f64 {
    let (s, c) = angles_rad
        .iter()
        .fold((0.0, 0.0), |(s, c), a| (s + a.sin(), c + a.cos()));
    s.atan2(c)
}

/// Replays the case on `sim` with extensions (each with its parameter values). Returns the simulated record
/// (same grid as the measured one) and the model trim.
pub fn replay(
    sim: &mut dyn ReplaySim,
    case: &ReplayCase,
    extensions: &[(&dyn Extension, &[f64])],
) -> Result<(FlightRecord, TrimState), SimError> {
    for name in sim.coefficient_names() {
        sim.set_coefficient_scale(&name, 1.0)?;
    }
    for name in sim.added_term_names() {
        sim.set_added_term(&name, 0.0)?;
    }
    for (e, p) in extensions {
        if e.stage() == Stage::Model {
            e.apply_model(p, sim)?;
        }
    }
    // The simulation integrates at its own rate, a whole multiple m of the record's (declared convention: the
    // surfaces move linearly between the record's samples; the value set for a step is what the model reads
    // during that step, so the step ending at sample k reads the measured sample k).
    let m = match sim.rate_hz() {
        Some(r) => {
            let m = (r / case.rate_hz).round().max(1.0);
            if (m * case.rate_hz - r).abs() > 1e-6 * r {
                return Err(SimError::Usage(format!(
                    "the simulation runs at {r} Hz, not a whole multiple of the record's {} Hz",
                    case.rate_hz
                )));
            }
            m as usize
        }
        None => 1,
    };
    let trim = sim.trim(&case.point)?;
    let n_steps = (case.len() - 1) * m;
    let dt = case.dt_s();
    let mut inputs = Vec::new();
    for (surface, dev) in &case.inputs {
        let mut d = dev.clone();
        for (e, p) in extensions {
            if e.stage() == Stage::Input {
                e.apply_input(p, surface, &mut d, dt);
            }
        }
        let fine: Vec<f64> = (0..n_steps)
            .map(|s| {
                let (k, j) = (s / m, s % m + 1);
                let f = j as f64 / m as f64;
                (1.0 - f) * d[k] + f * d[(k + 1).min(d.len() - 1)]
            })
            .collect();
        inputs.push(SurfaceInput {
            surface: surface.clone(),
            deflection_rad: fine,
        });
    }
    let plan = FlightPlan {
        rate_hz: case.rate_hz * m as f64,
        n_steps,
        inputs,
    };
    let mut rec = sim.fly(&plan)?;
    if m > 1 {
        let keep: Vec<usize> = (0..case.len()).map(|k| k * m).collect();
        for (_, col) in rec.columns.iter_mut() {
            if col.len() > n_steps {
                *col = keep.iter().map(|&i| col[i]).collect();
            }
        }
    }
    rec.time_s = case.record.time_s.clone();
    for (e, p) in extensions {
        if e.stage() == Stage::Output {
            e.apply_output(p, &mut rec);
        }
    }
    Ok((rec, trim))
}

/// A linear model as the replay simulation: `flightid linearize --json` output (A, B, C, D and the `trim` it
/// was taken at). It is valid only near its own trim point, so the measured initial condition must lie within
/// [`LinearReplay::SPEED_TOLERANCE`] of its airspeed and [`LinearReplay::ALTITUDE_TOLERANCE_FT`] of its altitude;
/// the replay then runs at the model's own point. It has no coefficient knobs: only signal-path and sensor
/// effects can be fitted on it.
pub struct LinearReplay {
    sim: LinearSim,
    point: TrimPoint,
    input_names: Vec<String>,
}

impl LinearReplay {
    /// Largest relative airspeed difference between the record and the model's trim.
    pub const SPEED_TOLERANCE: f64 = 0.1;
    /// Largest altitude difference between the record and the model's trim, ft.
    pub const ALTITUDE_TOLERANCE_FT: f64 = 1000.0;

    /// Reads `flightid linearize --json` output.
    pub fn from_json(path: &std::path::Path) -> Result<Self, DiagnoseError> {
        let err = |m: String| DiagnoseError::ExtensionFile {
            path: path.display().to_string(),
            message: m,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
        let trim: TrimState = serde_json::from_value(v["trim"].clone()).map_err(|e| {
            err(format!(
                "no usable 'trim' object ({e}); expected `flightid linearize --json` output"
            ))
        })?;
        let lin: crate::sim::Linearization =
            serde_json::from_value(v).map_err(|e| err(format!("not a linearization: {e}")))?;
        Ok(LinearReplay {
            point: trim.point,
            input_names: lin.inputs.clone(),
            sim: LinearSim::new(lin, trim),
        })
    }
}

impl Simulator for LinearReplay {
    fn trim(&mut self, point: &TrimPoint) -> Result<TrimState, SimError> {
        let dv = (point.speed_kts - self.point.speed_kts).abs() / self.point.speed_kts;
        let dh = (point.altitude_ft - self.point.altitude_ft).abs();
        if dv > Self::SPEED_TOLERANCE || dh > Self::ALTITUDE_TOLERANCE_FT {
            return Err(SimError::TrimFailed(format!(
                "the record starts at {:.1} kts, {:.0} ft, but the linear model holds only near its trim point \
                 {:.1} kts, {:.0} ft (±{:.0} %, ±{:.0} ft)",
                point.speed_kts,
                point.altitude_ft,
                self.point.speed_kts,
                self.point.altitude_ft,
                100.0 * Self::SPEED_TOLERANCE,
                Self::ALTITUDE_TOLERANCE_FT
            )));
        }
        self.sim.trim(&self.point)
    }
    fn linearize(&mut self) -> Result<crate::sim::Linearization, SimError> {
        self.sim.linearize()
    }
    fn fly(&mut self, plan: &FlightPlan) -> Result<FlightRecord, SimError> {
        // JSBSim's linearization names the throttle input ThtlCmd (normalised command, as the CSV's throttle);
        // a model without a throttle input can still replay a record whose throttle does not move.
        let mut plan = plan.clone();
        let has = |n: &str| self.input_names.iter().any(|i| i == n);
        let mut kept = Vec::new();
        for mut input in plan.inputs.drain(..) {
            if input.surface == "throttle" && !has("throttle") {
                if has("ThtlCmd") {
                    input.surface = "ThtlCmd".into();
                } else if input.deflection_rad.iter().all(|v| v.abs() < 1e-9) {
                    continue;
                } else {
                    return Err(SimError::Usage(
                        "the throttle moves in the record but the linear model has no throttle input".into(),
                    ));
                }
            }
            kept.push(input);
        }
        plan.inputs = kept;
        self.sim.fly(&plan)
    }
}

impl ReplaySim for LinearReplay {
    fn coefficient_names(&self) -> Vec<String> {
        Vec::new()
    }
    fn set_coefficient_scale(&mut self, name: &str, _factor: f64) -> Result<(), SimError> {
        Err(SimError::Usage(format!(
            "a linear model has no coefficient knob '{name}'"
        )))
    }
}
