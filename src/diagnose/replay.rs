//! Replay: trim the simulation at the measured initial condition and drive it with the measured
//! surface deflections (as deviations from their initial values), optionally through model extensions.

use std::collections::BTreeMap;

use super::extension::{Extension, Stage};
pub use super::simulator::ReplaySim;
use super::DiagnoseError;
use crate::data::{Channel, FlightRecord};
use crate::sim::{
    FlightPlan, LinearSim, SimError, Simulator, StateReset, SurfaceInput, TrimPoint, TrimState,
    FT_TO_M, KTS_TO_M_S,
};
use serde::Serialize;

/// Surface inputs of the CSV schema: (surface name, column).
pub const INPUTS: [(&str, &str); 4] = [
    ("elevator", "elevator_rad"),
    ("aileron", "aileron_rad"),
    ("rudder", "rudder_rad"),
    ("throttle", "throttle"),
];

/// Output columns compared between data and simulation (those present in both). Heading is compared as a
/// continuous angle (the record's is unwrapped, see [`HEADING`]); its value at each segment's start is a
/// nuisance term like the rest of the state (`initial_state::initial_state_columns`), so what it adds is the
/// turn rate: a replay banked by a φ-sensor bias turns at g·tanφ/V, which the r gyro reads like its own bias.
pub const OUTPUTS: [&str; 13] = [
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
    HEADING,
];

/// The heading column: compared only on the training record, where each segment's initial heading is
/// estimated (a replay's heading drifts without bound from the record's otherwise).
pub const HEADING: &str = "psi_rad";

/// Lowest integration rate of a replay, Hz: a record logged slower is replayed at a whole multiple of its rate.
/// JSBSim's discrete integration delays the response to a surface by about one integration step (measured on
/// the c172x: a 0.09 s rudder delay flown at 200 Hz is fitted as 0.083–0.086 s by a replay at 100 Hz (four
/// records) and 0.091 s at 200 Hz; flown at 100 Hz, as 0.090 s at 100 Hz, 0.096 s at 200 Hz, 0.099 s at
/// 400 Hz). At 200 Hz that delay, 5 ms, is a quarter of the smallest input delay worth naming; at 100 Hz it is
/// half of it, and an actuator lag then fitted a true delay better than the delay itself.
pub const MIN_SIM_RATE_HZ: f64 = 200.0;

/// The longest uninterrupted, uniformly sampled piece of a measured record (`data::uniform_pieces`), with what
/// was done to get it: an open-loop replay cannot cross a dropout, and interpolating over the missing samples
/// would invent the motion in them.
pub fn longest_uniform_piece(
    record: &FlightRecord,
) -> Result<(FlightRecord, Vec<String>), DiagnoseError> {
    let split =
        crate::data::uniform_pieces(record).map_err(|e| DiagnoseError::BadData(e.to_string()))?;
    let mut notes = split.notes;
    let pieces = split.pieces.len();
    let Some(longest) = split.pieces.into_iter().max_by_key(|p| p.len()) else {
        return Err(DiagnoseError::BadData("the record has no samples".into()));
    };
    if pieces > 1 {
        notes.push(format!(
            "the replay uses the longest uninterrupted piece, t = {} s to {} s",
            longest.time_s[0],
            longest.time_s[longest.len() - 1]
        ));
    }
    Ok((longest, notes))
}

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
    /// Sample indices where the record's segments start (the first at 0), see [`segment_starts`]: each
    /// segment's initial state is a nuisance term of every fit.
    pub segments: Vec<usize>,
    /// What was done to the record's sampling before the replay (a dropout cut away, jittered timestamps
    /// resampled), one sentence each; empty for a uniformly sampled record.
    pub sampling_notes: Vec<String>,
}

/// Quiet time before a maneuver that lets it start a new segment, s.
pub const SEGMENT_QUIET_S: f64 = 3.0;
/// Shortest segment, s.
pub const SEGMENT_MIN_S: f64 = 5.0;
/// The segment starts this long before its maneuver's first input movement, s.
pub const SEGMENT_LEAD_S: f64 = 0.3;

/// Where the record splits into segments: just before every maneuver that follows at least
/// [`SEGMENT_QUIET_S`] of still inputs, each segment at least [`SEGMENT_MIN_S`] long (sample indices, the first
/// segment starting at 0 is not listed). An input is moving at sample k when it changed over the last half
/// second by more than a tenth of its largest deviation from its initial value (robust to sensor noise on the
/// surface columns). The state at each segment's start is estimated with every fit (a nuisance term, see
/// `initial_state::initial_state_columns`), so the slow modes (spiral, phugoid) cannot drift apart from the record over
/// more than one maneuver: drift is not taken for a cause (the idea of multiple shooting, Bock & Plitt 1984;
/// Jategaonkar, Flight Vehicle System Identification, 2nd ed., on estimating initial conditions per maneuver).
pub fn segment_starts(inputs: &[(String, Vec<f64>)], dt_s: f64) -> Vec<usize> {
    let n = inputs.first().map(|(_, d)| d.len()).unwrap_or(0);
    let moving = moving(inputs, dt_s);
    let quiet = (SEGMENT_QUIET_S / dt_s).round() as usize;
    let min_len = (SEGMENT_MIN_S / dt_s).round() as usize;
    let lead = (SEGMENT_LEAD_S / dt_s).round() as usize;
    let mut starts = Vec::new();
    let mut last = 0usize;
    let mut still = 0usize;
    for (k, &m) in moving.iter().enumerate() {
        if !m {
            still += 1;
            continue;
        }
        if still >= quiet && k >= lead {
            let b = k - lead;
            if b >= last + min_len && b + min_len <= n {
                starts.push(b);
                last = b;
            }
        }
        still = 0;
    }
    starts
}

/// Whether any input is moving at each sample: it changed over the last half second by more than a tenth of its
/// largest deviation from its initial value (robust to sensor noise on the surface columns).
pub fn moving(inputs: &[(String, Vec<f64>)], dt_s: f64) -> Vec<bool> {
    let n = inputs.first().map(|(_, d)| d.len()).unwrap_or(0);
    let lag = ((0.5 / dt_s).round() as usize).max(1);
    let scales: Vec<f64> = inputs
        .iter()
        .map(|(_, d)| d.iter().fold(0.0_f64, |m, v| m.max(v.abs())))
        .collect();
    (0..n)
        .map(|k| {
            inputs.iter().zip(&scales).any(|((_, d), &scale)| {
                let before = d[k.saturating_sub(lag)];
                scale > 1e-6 && (d[k] - before).abs() > 0.1 * scale
            })
        })
        .collect()
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
    /// A record with dropouts is replayed on its longest uninterrupted piece (`data::uniform_pieces`): an
    /// open-loop replay cannot cross missing samples, and interpolating over them would invent the motion.
    pub fn new(record: &FlightRecord) -> Result<Self, DiagnoseError> {
        if record.len() < 50 {
            return Err(DiagnoseError::TooShort(format!(
                "{} samples; replay and identification need at least 50",
                record.len()
            )));
        }
        // A replay at the rate of a record timed in milliseconds would integrate at a fraction of a hertz.
        if let Some(why) = crate::data::time_unit_suspicion(&record.time_s) {
            return Err(DiagnoseError::BadData(format!("column `time_s`: {why}")));
        }
        let whole = record.len();
        let (longest, sampling_notes) = longest_uniform_piece(record)?;
        let record = &longest;
        let n = record.len();
        if n < 50 {
            return Err(DiagnoseError::TooShort(format!(
                "its longest uninterrupted piece (t = {} s to {} s) has {n} of its {whole} samples; replay and \
                 identification need at least 50 ({})",
                record.time_s[0],
                record.time_s[n - 1],
                sampling_notes.join("; ")
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
                "because replay trims the model at the measured airspeed and altitude",
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
        let mut sampling_notes = sampling_notes;
        let (first, start_note) = super::start::maneuver_free_start(&rec, &present_inputs);
        sampling_notes.extend(start_note);
        let rec = if first > 0 {
            let mut cut = rec.slice(first, rec.len());
            let t0 = cut.time_s[0];
            cut.time_s.iter_mut().for_each(|t| *t -= t0);
            cut
        } else {
            rec
        };
        let n = rec.len();
        if n < 50 {
            return Err(DiagnoseError::TooShort(format!(
                "{n} samples after the maneuver the record begins in; replay and identification need at least 50 ({})",
                sampling_notes.join("; ")
            )));
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
        let mut rec = rec;
        if let Some(psi) = rec.column(HEADING) {
            // continuous, starting within half a turn of zero as the simulation's heading does
            let continuous = crate::signal::heading_from_zero_rad(psi);
            rec.push_column(HEADING, continuous);
        }
        let inputs: Vec<(String, Vec<f64>)> = present_inputs
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
            gamma_deg: super::start::flight_path_deg(
                &rec,
                &present_inputs,
                initial["airspeed_m_s"],
            ),
            latitude_deg: initial
                .get(Channel::Latitude.name())
                .map_or(0.0, |l| l.to_degrees()),
            temperature_offset_k: super::start::temperature_offset_k(&initial)?,
        };
        if !(point.speed_kts > 1.0 && point.altitude_ft.is_finite()) {
            return Err(DiagnoseError::BadData(format!(
                "initial airspeed {:.2} m/s / altitude {:.1} m cannot be a trim point",
                initial["airspeed_m_s"], initial["altitude_m"]
            )));
        }
        let segments = std::iter::once(0)
            .chain(segment_starts(&inputs, dt))
            .collect();
        Ok(ReplayCase {
            sampling_notes,
            rate_hz: 1.0 / dt,
            record: rec,
            point,
            initial,
            inputs,
            outputs,
            segments,
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

    /// The surfaces whose deviation from their starting value reaches `threshold` somewhere in the record.
    pub fn moving_inputs(&self, threshold: f64) -> Vec<&str> {
        self.inputs
            .iter()
            .filter(|(_, d)| d.iter().any(|v| v.abs() >= threshold))
            .map(|(s, _)| s.as_str())
            .collect()
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.record.len()
    }

    /// The case cut to its first `len` samples (a replay of it equals the first `len` samples of the whole
    /// case's replay).
    pub fn head(&self, len: usize) -> ReplayCase {
        let len = len.min(self.len());
        ReplayCase {
            record: self.record.slice(0, len),
            sampling_notes: self.sampling_notes.clone(),
            rate_hz: self.rate_hz,
            point: self.point,
            initial: self.initial.clone(),
            inputs: self
                .inputs
                .iter()
                .map(|(s, d)| (s.clone(), d[..len.min(d.len())].to_vec()))
                .collect(),
            outputs: self.outputs.clone(),
            segments: self.segments.iter().copied().filter(|&b| b < len).collect(),
        }
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
    replay_with_resets(sim, case, extensions, &[])
}

/// [`replay`] with state resets at record samples (`StateReset::step` counts the record's samples here).
pub fn replay_with_resets(
    sim: &mut dyn ReplaySim,
    case: &ReplayCase,
    extensions: &[(&dyn Extension, &[f64])],
    resets: &[StateReset],
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
    let resets: Vec<StateReset> = resets
        .iter()
        .map(|r| StateReset {
            step: r.step * m,
            ..r.clone()
        })
        .collect();
    // Only the record's samples, every m-th step, are read and returned.
    let mut rec = sim.fly_recording_every(&plan, &resets, m)?;
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
        let err = |m: String| DiagnoseError::LinearModelFile {
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

#[cfg(test)]
mod tests {
    use super::{segment_starts, ReplayCase};
    use crate::data::{Channel, FlightRecord};

    /// A level record at 10 Hz, 10 s, with a constant elevator; `latitude_rad` when given.
    fn level_record(latitude_rad: Option<f64>) -> FlightRecord {
        let n = 100;
        let mut r = FlightRecord::new((0..n).map(|k| k as f64 / 10.0).collect());
        r.push_column(Channel::Airspeed, vec![50.0; n]);
        r.push_column(Channel::Altitude, vec![1000.0; n]);
        r.push_column(Channel::Elevator, vec![-0.02; n]);
        if let Some(l) = latitude_rad {
            r.push_column(Channel::Latitude, vec![l; n]);
        }
        r
    }

    #[test]
    fn the_trim_point_is_at_the_record_latitude() {
        let at = |l| {
            ReplayCase::new(&level_record(l))
                .unwrap()
                .point
                .latitude_deg
        };
        assert!((at(Some(51.5f64.to_radians())) - 51.5).abs() < 1e-9);
        // Without a GPS column the model trims on the equator.
        assert_eq!(at(None), 0.0);
    }

    /// A record at 10 Hz: `pulses` = (start s, length s, amplitude) on one input.
    fn input(pulses: &[(f64, f64, f64)], duration_s: f64) -> Vec<(String, Vec<f64>)> {
        let n = (duration_s * 10.0) as usize;
        let d = (0..n)
            .map(|k| {
                let t = k as f64 / 10.0;
                pulses
                    .iter()
                    .filter(|(s, l, _)| t >= *s && t < s + l)
                    .map(|(_, _, a)| a)
                    .sum()
            })
            .collect();
        vec![("elevator".to_string(), d)]
    }

    #[test]
    fn a_segment_starts_just_before_each_maneuver_after_a_quiet_stretch() {
        // Maneuvers at 2 s, 20 s and 40 s: the first is in the first segment (from trim), the other two start
        // segments 0.3 s before they move.
        let u = input(
            &[(2.0, 2.0, 0.05), (20.0, 2.0, -0.05), (40.0, 1.0, 0.03)],
            60.0,
        );
        assert_eq!(segment_starts(&u, 0.1), vec![197, 397]);
    }

    #[test]
    fn no_segment_without_quiet_before_or_room_after() {
        // 1 s of quiet between pulses is not enough; a maneuver 3 s before the end leaves too short a segment.
        let u = input(
            &[(2.0, 2.0, 0.05), (5.0, 2.0, -0.05), (27.0, 1.0, 0.05)],
            30.0,
        );
        assert!(segment_starts(&u, 0.1).is_empty());
        // An input that never moves starts nothing; noise a hundredth of the pulses does not either.
        let still = vec![("aileron".to_string(), vec![0.0; 300])];
        assert!(segment_starts(&still, 0.1).is_empty());
        let mut noisy = input(&[(2.0, 2.0, 0.05), (20.0, 2.0, -0.05)], 40.0);
        for (k, v) in noisy[0].1.iter_mut().enumerate() {
            *v += 5e-4 * ((k * 7919 % 13) as f64 / 6.0 - 1.0);
        }
        assert_eq!(segment_starts(&noisy, 0.1), vec![197]);
    }

    #[test]
    fn segments_are_at_least_five_seconds_long() {
        // Quiet from 1.5 s, maneuvers at 10 s, 14.2 s and 20 s, each after more than 3 s of still input: the one at
        // 14.2 s would start a segment only 4.2 s after the one at 10 s and does not; the one at 20 s does.
        let u = input(
            &[
                (1.0, 0.5, 0.05),
                (10.0, 0.5, 0.05),
                (14.2, 0.5, -0.05),
                (20.0, 0.5, 0.05),
            ],
            30.0,
        );
        assert_eq!(segment_starts(&u, 0.1), vec![97, 197]);
    }
}
