//! The nuisance terms of every fit: the state at the start of each segment of the record, linearised once at
//! the unextended model (multiple shooting), and projected off every residual (`projection`).

use super::replay::{replay_with_resets, ReplayCase};
use super::search::{at_sensitivity_rate, par_map, simulate, Worker};
use crate::sim::{SimError, StateReset};

/// State perturbations whose output effect spans a segment's initial-state error: (roll, pitch, body rates,
/// body velocities, altitude), each a small step of that state alone (SI).
fn state_perturbations() -> Vec<StateReset> {
    let one = |f: &dyn Fn(&mut StateReset)| {
        let mut r = StateReset {
            relative: true,
            ..Default::default()
        };
        f(&mut r);
        r
    };
    vec![
        one(&|r| r.phi_rad = Some(0.01)),
        one(&|r| r.theta_rad = Some(0.005)),
        one(&|r| r.rates_rad_s = Some([0.005, 0.0, 0.0])),
        one(&|r| r.rates_rad_s = Some([0.0, 0.005, 0.0])),
        one(&|r| r.rates_rad_s = Some([0.0, 0.0, 0.005])),
        one(&|r| r.uvw_m_s = Some([0.5, 0.0, 0.0])),
        one(&|r| r.uvw_m_s = Some([0.0, 0.5, 0.0])),
        one(&|r| r.uvw_m_s = Some([0.0, 0.0, 0.3])),
        one(&|r| r.altitude_m = Some(3.0)),
    ]
}

/// The nuisance terms of every fit: the state at the start of each of the case's segments (roll and pitch
/// angles, body rates and velocities, altitude; `ReplayCase::segments`). Their effect on the noise-normalised
/// residual is linearised once at the unextended model (one simulation per segment and state, in parallel on
/// the workers, flown to the segment's end) and returned column by column (nine per segment, in segment order,
/// then the heading's where it is compared: `heading_columns`); [`super::search::residuals`] projects their
/// [`super::search::orthonormal_basis`] off. A column ends with its segment, as in multiple shooting: what a
/// state error at one segment's start does after the next one starts is the response to a state error there,
/// which the next segment's columns span (to first order; engine and actuator states are not among the nine).
/// Estimating the initial state per segment keeps the slow modes' drift, grown from small state errors over a
/// long record, from being taken for a cause (Jategaonkar, Flight Vehicle System Identification, 2nd ed.,
/// initial conditions as unknowns per maneuver; multiple shooting). Empty when the simulation cannot set its
/// state mid-flight.
pub fn initial_state_columns(
    workers: &mut [Worker],
    case: &ReplayCase,
    sigma: &[f64],
) -> Result<Vec<Vec<f64>>, SimError> {
    if !workers.first().is_some_and(|w| w.sim.supports_resets()) {
        return Ok(Vec::new());
    }
    let simulated =
        at_sensitivity_rate(workers, case, |workers| state_columns(workers, case, sigma))?;
    let heading = heading_columns(case, sigma);
    if heading.is_empty() {
        return Ok(simulated);
    }
    let per = simulated.len() / case.segments.len().max(1);
    Ok(simulated
        .chunks(per.max(1))
        .zip(heading)
        .flat_map(|(states, h)| states.iter().cloned().chain(std::iter::once(h)))
        .collect())
}

/// How many of [`initial_state_columns`]' columns each segment has: the nine states, and the heading where it is
/// compared. Nuisance columns appended after them (the equilibrium's airspeed, `equilibrium`) are not a segment's.
pub fn columns_per_segment(case: &ReplayCase) -> usize {
    state_perturbations().len()
        + usize::from(case.outputs.iter().any(|o| o == super::replay::HEADING))
}

/// Size of the heading step of [`heading_columns`], rad (the roll angle's step).
const HEADING_STEP_RAD: f64 = 0.01;

/// The heading at each segment's start, one column per segment: a step of [`HEADING_STEP_RAD`] moves the
/// replayed heading by the step over that segment and nothing else (in the replay's still air no force or
/// moment depends on heading), so the column is known without a simulation. Empty when heading is not compared.
fn heading_columns(case: &ReplayCase, sigma: &[f64]) -> Vec<Vec<f64>> {
    let Some(h) = case
        .outputs
        .iter()
        .position(|o| o == super::replay::HEADING)
    else {
        return Vec::new();
    };
    let len = case.len();
    case.segments
        .iter()
        .enumerate()
        .map(|(s, &b)| {
            let end = case.segments.get(s + 1).copied().unwrap_or(len);
            let mut col = vec![0.0; len * case.outputs.len()];
            col[h * len + b..h * len + end].fill(HEADING_STEP_RAD / sigma[h]);
            col
        })
        .collect()
}

/// [`initial_state_columns`] simulated at the workers' current rate.
fn state_columns(
    workers: &mut [Worker],
    case: &ReplayCase,
    sigma: &[f64],
) -> Result<Vec<Vec<f64>>, SimError> {
    let Some(first) = workers.first_mut() else {
        return Ok(Vec::new());
    };
    let (base, _) = simulate(first, case, &[])?;
    // (reset, end of its segment): the next segment's start, or the record's end.
    let items: Vec<(StateReset, usize)> = case
        .segments
        .iter()
        .enumerate()
        .flat_map(|(s, &b)| {
            let end = case.segments.get(s + 1).copied().unwrap_or(case.len());
            state_perturbations()
                .into_iter()
                .map(move |r| (StateReset { step: b, ..r }, end))
        })
        .collect();
    let columns = par_map(workers, &items, |wk, (reset, end)| {
        let t0 = std::time::Instant::now();
        let out = replay_with_resets(
            wk.sim.as_mut(),
            &case.head(*end),
            &[],
            std::slice::from_ref(reset),
        );
        wk.ran(t0.elapsed().as_secs_f64());
        let (rec, _) = out?;
        let mut col = Vec::with_capacity(case.len() * case.outputs.len());
        for (c, name) in case.outputs.iter().enumerate() {
            let (Some(y), Some(y0)) = (rec.column(name), base.column(name)) else {
                return Err(SimError::Protocol(format!(
                    "the simulation does not produce column {name}"
                )));
            };
            col.extend(y.iter().zip(y0).map(|(a, b)| (a - b) / sigma[c]));
            col.resize((c + 1) * case.len(), 0.0);
        }
        Ok(col)
    });
    columns.into_iter().collect()
}
