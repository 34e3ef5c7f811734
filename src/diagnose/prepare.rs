//! Stage 1, prepare: the records on a uniform grid with their trim points, the channels the simulation can be
//! compared on, the noise weights, and the catalogue entries the record can identify.

use super::extension::{self, Extension, Stage};
use super::replay::{self, ReplayCase};
use super::search::{self, Worker};
use super::{residual, sim_err, DiagnoseError, Skipped};
use crate::data::{control_moments, Channel, ControlMoment, FlightRecord, SIGN_T_RATIO};
use crate::sim::{SimError, TrimPoint};
use serde::Serialize;

/// Everything the later stages need about the records and the catalogue.
pub struct Prepared {
    /// The training record prepared for replay.
    pub case: ReplayCase,
    /// Noise standard deviation per compared channel of the training record (order of `case.outputs`).
    pub sigma: Vec<f64>,
    /// The validation record and its noise standard deviations.
    pub valid: Option<(ReplayCase, Vec<f64>)>,
    /// Catalogue entries that are evaluated.
    pub catalogue: Vec<Box<dyn Extension>>,
    /// Catalogue entries left out, with the reason.
    pub skipped: Vec<Skipped>,
    /// Conditions that limit what the verdict can be trusted for.
    pub warnings: Vec<String>,
    /// The nuisance terms of the training record's fits (`initial_state::initial_state_columns`,
    /// orthonormalised; set by `diagnose`).
    pub nuisance: Vec<Vec<f64>>,
    /// The filter error method's filter on the training record's residuals when it flew in turbulence
    /// (`process_noise::estimate`; set by `diagnose`).
    pub filter: Option<super::process_noise::ResidualFilter>,
    /// The measurement noise standard deviation per compared channel (`sigma` before any relaxation).
    pub noise_sigma: Vec<f64>,
    /// The surface columns of the other sign convention, reversed for the replay ([`reversed_surfaces`]).
    pub reversed_inputs: Vec<ReversedInput>,
    /// What the CSV readers find in the records as given ([`record_warnings`]).
    pub record_warnings: Vec<String>,
}

/// A surface column the record logs with the other sign than the model reads it: its control moment (the body
/// rate's acceleration per radian, [`control_moments`]) on the record and on the unextended replay.
#[derive(Debug, Clone, Serialize)]
pub struct ReversedInput {
    /// The column, e.g. `elevator_rad`.
    pub column: String,
    /// The moment on the record, rad/s² per rad, and its standard error.
    pub record: f64,
    pub record_std_error: f64,
    /// The moment on the replay, and its standard error.
    pub model: f64,
    pub model_std_error: f64,
}

impl Prepared {
    /// The training residual's cost at the measurement noise in the weights `sigma` (see `search::Weighted`):
    /// Σ over channels of the samples × (noise σ / weight σ)².
    pub fn noise_cost(&self) -> f64 {
        let len = self.case.len() as f64;
        self.noise_sigma
            .iter()
            .zip(&self.sigma)
            .map(|(n, s)| len * (n / s).powi(2))
            .sum()
    }

    /// The evaluated catalogue entries as references.
    pub fn entries(&self) -> Vec<&dyn Extension> {
        self.catalogue.iter().map(|b| b.as_ref()).collect()
    }

    /// The training record's weighted residual: its noise weights, nuisance terms and (in turbulence) filter.
    pub fn training(&self) -> search::Weighted<'_> {
        search::Weighted {
            case: &self.case,
            sigma: self.sigma.clone(),
            nuisance: &self.nuisance,
            filter: self.filter.as_ref(),
            correction: None,
            noise_cost: self.noise_cost(),
        }
    }

    /// The validation record's weighted residual: its noise weights only (no nuisance terms, no filter).
    pub fn validation(&self) -> Option<search::Weighted<'_>> {
        self.valid.as_ref().map(|(case, sigma)| search::Weighted {
            case,
            sigma: sigma.clone(),
            nuisance: &[],
            filter: None,
            correction: None,
            noise_cost: (case.len() * case.outputs.len()) as f64,
        })
    }
}

/// Noise standard deviation per output channel, floored at 10⁻³ of the channel's spread (noise-free data).
pub fn weights(case: &ReplayCase) -> Vec<f64> {
    case.outputs
        .iter()
        .map(|c| {
            let y = case.measured(c);
            let m = y.iter().sum::<f64>() / y.len() as f64;
            let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
            residual::noise_std(y).max(1e-3 * sd).max(1e-9)
        })
        .collect()
}

/// Airspeed offsets tried, in order, when the model cannot trim at a record's measured initial airspeed, kts.
const TRIM_SPEED_NUDGES_KTS: [f64; 6] = [-0.5, 0.5, -1.0, 1.0, -2.0, 2.0];

/// Replays `case` unextended (the replay is kept in the workers' store); where JSBSim's trim fails at the
/// record's initial condition, at the nearest airspeed of [`TRIM_SPEED_NUDGES_KTS`] that trims, which becomes
/// the case's trim point (returned as a warning). The
/// measured initial airspeed is a mean over the record's first quiet second, a gust or a pitot error away from
/// the air-relative speed; near the edge of the envelope a knot decides whether the trim converges (the c172x
/// at 2830 ft: 113.5 kts fails, 112.5 kts trims). Every segment's initial body velocities are nuisance terms of
/// the fits, so a trim a knot or two off the record changes its replay only by what they absorb. The first
/// failure is returned when no nudge trims either.
fn trimmable_point(
    worker: &mut Worker,
    case: &mut ReplayCase,
    which: &str,
) -> Result<Option<String>, DiagnoseError> {
    let first = match search::simulate(worker, case, &[]) {
        Ok(_) => return Ok(None),
        Err(e @ SimError::TrimFailed(_)) => e,
        Err(e) => return Err(sim_err("replay")(e)),
    };
    let measured = case.point;
    for nudge in TRIM_SPEED_NUDGES_KTS {
        case.point = TrimPoint {
            speed_kts: measured.speed_kts + nudge,
            ..measured
        };
        match search::simulate(worker, case, &[]) {
            Ok(_) => {
                return Ok(Some(format!(
                    "the model cannot trim at the {which} record's initial condition ({:.2} kts, {:.0} ft); it was \
                     trimmed at {:.2} kts instead, and the segment initial states absorb the difference",
                    measured.speed_kts, measured.altitude_ft, case.point.speed_kts
                )));
            }
            Err(SimError::TrimFailed(_)) => case.point = measured,
            Err(e) => return Err(sim_err("replay")(e)),
        }
    }
    Err(sim_err("replay")(first))
}

/// Prepares the training and validation records and the catalogue for the simulation of `worker`.
pub fn prepare(
    worker: &mut Worker,
    train: &FlightRecord,
    valid: Option<&FlightRecord>,
) -> Result<Prepared, DiagnoseError> {
    let mut logged = prepare_as_logged(worker, train, valid)?;
    logged.record_warnings = record_warnings(train, valid);
    if logged.reversed_inputs.is_empty() {
        return Ok(logged);
    }
    let reverse = |rec: &FlightRecord| {
        let mut rec = rec.clone();
        for (name, column) in rec.columns.iter_mut() {
            if logged.reversed_inputs.iter().any(|r| &r.column == name) {
                column.iter_mut().for_each(|v| *v = -*v);
            }
        }
        rec
    };
    let mut p = prepare_as_logged(worker, &reverse(train), valid.map(reverse).as_ref())?;
    p.warnings.extend(logged.reversed_inputs.iter().map(|r| {
        format!(
            "{}: the record's body rate follows it the other way round from the model's (control moment \
             {:+.2} ± {:.2} rad/s² per rad on the record, {:+.2} ± {:.2} on the replay): it is logged with the \
             other sign convention, and the replay reverses it; declare it in the --columns map with scale = -1.0",
            r.column, r.record, r.record_std_error, r.model, r.model_std_error
        )
    }));
    p.reversed_inputs = logged.reversed_inputs;
    p.record_warnings = logged.record_warnings;
    Ok(p)
}

/// What the CSV readers find in the records as given (`FlightRecord::warnings`: repeated rows they dropped,
/// units, a surface's sign, irregular sampling), each prefixed with the record it concerns. A command prints
/// them when it reads a file; the diagnosis carries them too, so that a script reading its JSON sees them.
fn record_warnings(train: &FlightRecord, valid: Option<&FlightRecord>) -> Vec<String> {
    [(Some(train), "training"), (valid, "validation")]
        .into_iter()
        .filter_map(|(r, which)| r.map(|r| (r, which)))
        .flat_map(|(r, which)| {
            r.warnings()
                .into_iter()
                .map(move |w| format!("{which} record: {w}"))
        })
        .collect()
}

/// The surfaces whose control moment (the equation error of [`control_moments`]) has one sign on the record and
/// the other on the unextended replay, each by more than [`SIGN_T_RATIO`] standard errors. The replay is given
/// the record's surface columns, so both regressions see the same inputs.
fn reversed_surfaces(record: &FlightRecord, replayed: &FlightRecord) -> Vec<ReversedInput> {
    let mut model_rec = replayed.clone();
    for c in [Channel::Elevator, Channel::Aileron, Channel::Rudder] {
        if let (Some(logged), Some(sim)) = (record.column(c), model_rec.column_mut(c)) {
            sim.copy_from_slice(logged);
        }
    }
    let decided = |m: &ControlMoment| m.t_ratio() > SIGN_T_RATIO;
    let model = control_moments(&model_rec);
    control_moments(record)
        .into_iter()
        .filter(decided)
        .filter_map(|m| {
            let s = model
                .iter()
                .find(|s| s.surface == m.surface && decided(s))?;
            (m.value * s.value < 0.0).then(|| ReversedInput {
                column: m.surface.to_string(),
                record: m.value,
                record_std_error: m.std_error,
                model: s.value,
                model_std_error: s.std_error,
            })
        })
        .collect()
}

/// [`prepare`] on the records as they are.
fn prepare_as_logged(
    worker: &mut Worker,
    train: &FlightRecord,
    valid: Option<&FlightRecord>,
) -> Result<Prepared, DiagnoseError> {
    let mut case = ReplayCase::new(train)?;
    // The simulation steps at a whole multiple of the training record's rate; a validation record sampled at
    // another rate is interpolated onto the training rate (linearly, no filtering) and the warning says so.
    let mut rate_note = None;
    let mut valid_notes = Vec::new();
    let valid = match valid {
        Some(v) => {
            let (v, notes) = replay::longest_uniform_piece(v)?;
            valid_notes = notes;
            let v_rate_hz = ReplayCase::new(&v)?.rate_hz;
            if (v_rate_hz - case.rate_hz).abs() > 1e-6 * case.rate_hz {
                rate_note = Some(format!(
                    "the validation record ({v_rate_hz:.3} Hz) was interpolated linearly onto the training \
                     record's rate ({:.3} Hz) for the replay",
                    case.rate_hz
                ));
                Some(
                    crate::data::resample_uniform(&v, case.rate_hz)
                        .map_err(|e| DiagnoseError::BadData(format!("validation record: {e}")))?,
                )
            } else {
                Some(v)
            }
        }
        None => None,
    };
    let mut vcase = valid.as_ref().map(ReplayCase::new).transpose()?;
    // what preparing the validation case did beyond the dropouts (a start inside a maneuver)
    for n in vcase.iter().flat_map(|v| &v.sampling_notes) {
        if !valid_notes.contains(n) {
            valid_notes.push(n.clone());
        }
    }
    // Heading is compared only where each segment's initial heading is estimated (a simulation that can set
    // its state mid-flight, the training record): elsewhere it drifts from the record's without bound.
    if let Some(v) = vcase.as_mut() {
        v.outputs.retain(|o| o != replay::HEADING);
    }
    if !worker.sim.supports_resets() {
        case.outputs.retain(|o| o != replay::HEADING);
    }
    // A surface without a column is held at its trim in the replay: if it moved in flight, its effect is
    // unmodelled and any cause named on the axes it drives is suspect.
    let mut warnings: Vec<String> = replay::INPUTS
        .iter()
        .filter(|(_, c)| train.column(c).is_none())
        .map(|(s, c)| {
            format!(
                "no {c} column: the replay holds the {s} at its trim value; if it moved in flight, \
                 causes named on the axes it drives are not trustworthy"
            )
        })
        .collect();
    warnings.extend(rate_note);
    if case.point.temperature_offset_k != 0.0 {
        warnings.push(format!(
            "the record's air density makes the day {:+.1} K off the standard atmosphere at its altitude: the model \
             flies in that atmosphere",
            case.point.temperature_offset_k
        ));
    }
    warnings.extend(
        case.sampling_notes
            .iter()
            .map(|n| format!("training record: {n}")),
    );
    warnings.extend(
        valid_notes
            .iter()
            .map(|n| format!("validation record: {n}")),
    );
    for (c, which) in [
        (Some(&mut case), "training"),
        (vcase.as_mut(), "validation"),
    ] {
        if let Some(c) = c {
            warnings.extend(trimmable_point(worker, c, which)?);
        }
    }
    // Compare only the channels the simulation produces (a linear model may lack accelerations).
    let (probe, _) = search::simulate(worker, &case, &[]).map_err(sim_err("replay"))?;
    let missing: Vec<String> = case
        .outputs
        .iter()
        .filter(|c| probe.column(c).is_none())
        .cloned()
        .collect();
    if !missing.is_empty() {
        warnings.push(format!(
            "the simulation does not produce {}: not compared",
            missing.join(", ")
        ));
        for c in [Some(&mut case), vcase.as_mut()].into_iter().flatten() {
            c.outputs.retain(|o| !missing.contains(o));
        }
    }
    let reversed_inputs = reversed_surfaces(&case.record, &probe);
    let coeffs = worker.sim.coefficient_names();
    let added = worker.sim.added_term_names();
    let (all, skipped_raw) = extension::catalogue(&case.record, &coeffs, &added);
    let mut skipped: Vec<Skipped> = skipped_raw
        .into_iter()
        .map(|(effect, target, reason)| Skipped {
            effect,
            target,
            reason,
        })
        .collect();
    // An effect that no moving input excites cannot be told from the gusts and the initial states: a
    // signal-path effect needs its surface to move, a derivative an input of its axis (`Extension::excited_by`).
    let moving = case.moving_inputs(1e-6);
    let mut catalogue = Vec::new();
    for e in all {
        let needs = e.excited_by();
        let excited = needs
            .iter()
            .filter(|n| moving.contains(&n.as_str()))
            .count();
        if needs.is_empty() || excited >= e.excited_count() {
            catalogue.push(e);
            continue;
        }
        let reason = if e.excited_count() > 1 {
            format!(
                "fewer than {} of {} move in the record",
                e.excited_count(),
                needs.join(", ")
            )
        } else if e.stage() == Stage::Input {
            "the input does not move in the record".to_string()
        } else {
            format!(
                "no input of its axis ({}) moves in the record: that axis moves only by the gusts and the \
                 initial states",
                needs.join(", ")
            )
        };
        skipped.push(Skipped {
            effect: e.effect().into(),
            target: e.target().into(),
            reason,
        });
    }
    let sigma = weights(&case);
    Ok(Prepared {
        noise_sigma: sigma.clone(),
        sigma,
        valid: vcase.map(|v| {
            let s = weights(&v);
            (v, s)
        }),
        case,
        catalogue,
        skipped,
        warnings,
        nuisance: Vec::new(),
        filter: None,
        reversed_inputs,
        record_warnings: Vec::new(),
    })
}
