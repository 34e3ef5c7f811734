//! Where a measured record starts, and in what: the first still stretch when it begins inside a maneuver, the
//! flight path of its still start, and the day's atmosphere from its air data. The replay trims there.

use std::collections::BTreeMap;

use super::DiagnoseError;
use crate::data::{Channel, FlightRecord};

/// Longest window over which the start's climb rate is fitted, s.
const CLIMB_WINDOW_MAX_S: f64 = 10.0;
/// Shortest still start from which a climb rate is taken, s.
const CLIMB_WINDOW_MIN_S: f64 = 1.0;
/// Smallest flight-path angle the replay trims at, deg: below it the record is taken as level (a slope of the
/// altimeter's noise does not move the trim, and the segment initial states absorb a small climb).
const CLIMB_MIN_DEG: f64 = 0.5;

/// The record's flight-path angle at its start, deg: γ = asin(ḣ/V) with ḣ the least-squares slope of
/// `altitude_m` over the still start (until an input leaves its initial value by more than 1 mrad or five times its
/// sample-to-sample noise, at most 10 s), V the initial airspeed. 0 (level) where the still start is shorter than
/// 1 s, the angle is below 0.5° or within four standard errors of the slope, or θ − α over the same start differs
/// from it by more than 0.5° or a quarter of it. A record that starts in a steady
/// climb or descent replayed from a level trim departs from it at once (a clean c172x record climbing at 3°: an
/// a_x bias of 0.50 m/s² and a θ bias of 1° named).
pub(super) fn flight_path_deg(
    rec: &FlightRecord,
    inputs: &[(&str, &str)],
    airspeed_m_s: f64,
) -> f64 {
    let (Some(h), n) = (rec.column("altitude_m"), rec.len()) else {
        return 0.0;
    };
    let dt = rec.time_s.get(1).map_or(f64::NAN, |t1| t1 - rec.time_s[0]);
    let limit = ((CLIMB_WINDOW_MAX_S / dt) as usize).min(n);
    let mut end = limit;
    for (_, c) in inputs {
        let x = rec.column(c).unwrap_or(&[]);
        let tol = rest_tolerance(&x[..limit]);
        if let Some(k) = x[..limit].iter().position(|v| (v - x[0]).abs() > tol) {
            end = end.min(k);
        }
    }
    if !(end as f64 * dt >= CLIMB_WINDOW_MIN_S && airspeed_m_s > 1.0) {
        return 0.0;
    }
    // least-squares line through (t, h) over the still start; its t statistic r √(m − 2) / √(1 − r²)
    let (slope, r) = crate::signal::slope_and_correlation(&rec.time_s[..end], &h[..end]);
    let m = end as f64;
    let t_stat = r.abs() * ((m - 2.0).max(1.0) / (1.0 - r * r).max(f64::MIN_POSITIVE)).sqrt();
    let gamma = (slope / airspeed_m_s).clamp(-1.0, 1.0).asin().to_degrees();
    // The air-relative path θ − α (wings level) must agree: a record in sinking or rising air descends or climbs
    // against the ground while it flies level through the air, and is trimmed level (in gusts a validation record
    // descended at 0.73° over its 3.9 s still start with θ − α at +0.47°).
    let air_path = match (rec.column("theta_rad"), rec.column("alpha_rad")) {
        (Some(th), Some(al)) => {
            let mean = th[..end]
                .iter()
                .zip(&al[..end])
                .map(|(t, a)| t - a)
                .sum::<f64>()
                / m;
            Some(mean.to_degrees())
        }
        _ => None,
    };
    let agrees =
        air_path.is_none_or(|g| (g - gamma).abs() <= (0.25 * gamma.abs()).max(CLIMB_MIN_DEG));
    // A steady climb holds its speed; a phugoid's climb pays for its height with speed, V̇ ≈ −g ḣ/V (the total
    // energy V²/2 + g h constant). A record that starts in a phugoid (a clean c172x record logged from 14 s on, a
    // climb of 2° with the speed falling) is no steady climb: the replay trims level, and the equilibrium stage
    // finds the speed its inputs hold.
    let speed_slope = rec.column("airspeed_m_s").map_or(0.0, |v| {
        crate::signal::slope_and_correlation(&rec.time_s[..end], &v[..end]).0
    });
    let trades_speed = speed_slope * slope < 0.0
        && speed_slope.abs() > 0.5 * crate::data::G0_M_S2 * slope.abs() / airspeed_m_s;
    if gamma.abs() < CLIMB_MIN_DEG || t_stat < 4.0 || !agrees || trades_speed {
        return 0.0;
    }
    gamma
}

/// The day's temperature offset from the standard atmosphere, K, from the record's air density at its quiet start
/// (`density_kg_m3`, else ρ = 2 q̄/V² from `qbar_pa` and `airspeed_m_s`) at its altitude; 0 (the standard day)
/// without either. A density no day between ±80 K gives at that altitude is bad data, named.
pub(super) fn temperature_offset_k(initial: &BTreeMap<String, f64>) -> Result<f64, DiagnoseError> {
    let get = |c: Channel| initial.get(c.name()).copied();
    let density = get(Channel::Density).or_else(|| {
        let (q, v) = (get(Channel::Qbar)?, get(Channel::Airspeed)?);
        (v > 1.0).then(|| 2.0 * q / (v * v))
    });
    let (Some(rho), Some(h)) = (density, get(Channel::Altitude)) else {
        return Ok(0.0);
    };
    crate::sim::atmosphere::offset_for_density_k(h, rho).ok_or_else(|| {
        DiagnoseError::BadData(format!(
            "the air density {rho:.4} kg/m³ at {h:.0} m (from {}) is no day's between 80 K colder and 80 K warmer than \
             the standard atmosphere: check its unit (kg/m³, or q̄ in Pa)",
            if get(Channel::Density).is_some() { "density_kg_m3" } else { "qbar_pa and airspeed_m_s" }
        ))
    })
}

/// How far an input may wander and still be at rest: five times its sample-to-sample noise, at least 1 mrad.
fn rest_tolerance(x: &[f64]) -> f64 {
    (5.0 * crate::signal::difference_noise_std(x)).max(1e-3)
}

/// How long the inputs must rest at their usual values for a record that begins inside a maneuver to be taken up
/// there, s; the replay starts halfway through, when the short period has died out.
const STILL_STRETCH_S: f64 = 2.0;
/// Length of the record's first samples whose mean says where the inputs start, s.
const START_WINDOW_S: f64 = 0.2;

/// Where the replay of a record that begins inside a maneuver starts: the first sample of the first stretch of
/// [`STILL_STRETCH_S`] over which every input rests at its usual value, with a note saying so. `None` (start at
/// the first sample) where the record begins with every input at its usual value, or where no such stretch
/// follows (the note then says the trim is taken in the maneuver).
///
/// An input's usual value is its median over the record: a pilot or an autopilot returns the surfaces to the
/// trim between maneuvers, and pulse trains spend as long on either side of it. An input rests there while it
/// stays within max(1 mrad, five times its sample-to-sample noise, a tenth of its largest excursion) of it. The
/// replay trims the model at the record's start and drives it with the inputs' departures from their starting
/// values: a log cut from a longer flight in the middle of an elevator step (a clean c172x record cut 2.5 s in,
/// 7.3° of elevator against the trim's 5.4°) then flies the rest with the step's offset on the elevator, and
/// the search named an a_x and an α bias for it.
pub(super) fn maneuver_free_start(
    rec: &FlightRecord,
    inputs: &[(&str, &str)],
) -> (usize, Option<String>) {
    let n = rec.len();
    let dt = rec.time_s.get(1).map_or(f64::NAN, |t1| t1 - rec.time_s[0]);
    if n < 3 || dt.is_nan() || dt <= 0.0 {
        return (0, None);
    }
    // (column, usual value, tolerance, samples)
    let bands: Vec<(&str, f64, f64, &[f64])> = inputs
        .iter()
        .filter_map(|(_, c)| {
            let x = rec.column(c)?;
            let usual = crate::signal::median_in_place(&mut x.to_vec());
            let excursion = x.iter().fold(0.0_f64, |m, v| m.max((v - usual).abs()));
            let tol = rest_tolerance(x).max(0.1 * excursion);
            Some((*c, usual, tol, x))
        })
        .collect();
    let head = ((START_WINDOW_S / dt).round() as usize).clamp(1, n);
    let off: Vec<String> = bands
        .iter()
        .filter_map(|(c, usual, tol, x)| {
            let start = x[..head].iter().sum::<f64>() / head as f64;
            ((start - usual).abs() > *tol)
                .then(|| format!("{c} {start:+.4} against its usual {usual:+.4}"))
        })
        .collect();
    if off.is_empty() {
        return (0, None);
    }
    let at_rest = |k: usize| {
        bands
            .iter()
            .all(|(_, usual, tol, x)| (x[k] - usual).abs() <= *tol)
    };
    let need = ((STILL_STRETCH_S / dt).round() as usize).max(2);
    let mut run = 0;
    for k in 0..n {
        run = if at_rest(k) { run + 1 } else { 0 };
        if run == need {
            let first = k + 1 - need / 2;
            return (
                first,
                Some(format!(
                    "the record begins inside a maneuver ({}): the replay starts at t = {:.2} s, a second \
                     into the first {STILL_STRETCH_S} s with every input at its usual value",
                    off.join(", "),
                    rec.time_s[first]
                )),
            );
        }
    }
    (
        0,
        Some(format!(
            "the record begins inside a maneuver ({}) and its inputs never rest at their usual values for \
             {STILL_STRETCH_S} s: the model is trimmed at its first samples, away from a steady state",
            off.join(", ")
        )),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 50 Hz record of `secs` with an elevator from `elevator(t)`, the other inputs still.
    fn record(secs: f64, elevator: impl Fn(f64) -> f64) -> FlightRecord {
        let n = (secs * 50.0) as usize;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / 50.0).collect();
        let mut rec = FlightRecord::new(t.clone());
        rec.push_column("elevator_rad", t.iter().map(|&t| elevator(t)).collect());
        rec.push_column("aileron_rad", vec![-0.02; n]);
        rec
    }

    const INPUTS: [(&str, &str); 2] = [("elevator", "elevator_rad"), ("aileron", "aileron_rad")];

    #[test]
    fn a_record_that_starts_at_its_usual_inputs_is_replayed_from_its_first_sample() {
        // a doublet at 3 s from the trim
        let rec = record(30.0, |t| {
            0.09 + if (3.0..4.0).contains(&t) {
                0.03
            } else if (4.0..5.0).contains(&t) {
                -0.03
            } else {
                0.0
            }
        });
        assert_eq!(maneuver_free_start(&rec, &INPUTS), (0, None));
    }

    #[test]
    fn a_record_that_begins_in_a_step_starts_a_second_into_its_first_two_still_seconds() {
        // inside a step until 1.2 s, the opposite step until 1.8 s, still until 2.5 s (too short), a step until
        // 3 s, then still
        let rec = record(30.0, |t| {
            0.09 + match t {
                t if t < 1.2 => 0.03,
                t if t < 1.8 => -0.03,
                t if (2.5..3.0).contains(&t) => 0.03,
                _ => 0.0,
            }
        });
        let (first, note) = maneuver_free_start(&rec, &INPUTS);
        assert_eq!(first, 200, "3 s + 1 s at 50 Hz");
        let note = note.unwrap();
        assert!(
            note.contains("elevator_rad +0.1200 against its usual +0.0900"),
            "{note}"
        );
        assert!(note.contains("t = 4.00 s"), "{note}");
    }

    #[test]
    fn a_record_whose_inputs_never_rest_keeps_its_start_and_says_so() {
        // a step for the first second, then half-second pulses that never leave the elevator still for 2 s
        let rec = record(10.0, |t| {
            if t < 1.0 {
                0.12
            } else if ((t * 2.0) as usize).is_multiple_of(2) {
                0.09
            } else {
                0.06
            }
        });
        let (first, note) = maneuver_free_start(&rec, &INPUTS);
        assert_eq!(first, 0);
        assert!(note.unwrap().contains("never rest"));
    }
}
