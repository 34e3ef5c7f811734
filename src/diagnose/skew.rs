//! A time skew common to every surface: the record's convention, not a cause.
//!
//! A data system that stamps its sensor channels later than its surface channels (a logging skew, a sensor's
//! latency), or an aircraft whose every surface lags its command alike, gives a record in which the response
//! follows every surface by the same time. The search names that as an input delay on each surface that moves, with
//! one value: on clean c172x records of the independent generator with the sensor channels logged one and two
//! samples late (20–50 ms), delays of 0.028/0.027/0.030 s and 0.040/0.040/0.041 s on the elevator, aileron and
//! rudder. One hidden delay on one surface, as the catalogue draws them, leaves the other surfaces without one.
//!
//! The catalogue's `time_skew` (one delay on every surface at once) is that finding in one parameter: a skew costs
//! every surface that moves alike, so the search names it ahead of a delay on one surface where the record has
//! one. It also takes sensor filters that lag every channel alike: on the same records with every sensor through
//! a 5 Hz first-order filter (32 ms of lag), the search named an elevator delay of 22 ms alone, the aileron's and
//! rudder's (22 ms too, each at z ≈ 20) set aside as explained by an elevator lag below its resolution. The skew
//! may be negative: a data system that stamps its surfaces later than its sensors, or logs the surfaces at a lower
//! rate and holds them, gives a response that leads them (with the surfaces two samples late, −39.8 ms).
//!
//! So where `time_skew` is named, or every surface that moves (at least two) is named with an input delay and the
//! delays agree within three of their standard errors or 15 % of their mean, that is one finding about the
//! record's timing: the delays stay in the fitted model (the validation, the extension file and the model carry
//! them), and they are reported as a warning instead of as named causes.

use super::extension::TIME_SKEW;
use super::lever_arm;
use super::prepare::Prepared;
use super::NamedCause;

/// The share of the delays' mean within which delays on every surface are one skew.
const AGREE_SHARE: f64 = 0.15;

/// Takes input delays that [`super`]'s selection named on every surface that moves, alike (module doc), out of
/// `named`, and returns the warning that reports them as the record's timing, with the delays; `None` (and
/// `named` unchanged) otherwise.
pub fn common_skew(p: &Prepared, named: &mut Vec<NamedCause>) -> Option<(String, Vec<NamedCause>)> {
    if let Some(i) = named.iter().position(|n| n.effect == TIME_SKEW) {
        let skew = named.remove(i);
        let each = format!(
            "{} {:.4} ± {:.4} s",
            skew.target, skew.value, skew.std_error
        );
        return Some((warning(skew.value, &each), vec![skew]));
    }
    let mut moving = p.case.moving_inputs(1e-3);
    moving.retain(|s| *s != "throttle");
    let delays: Vec<&NamedCause> = moving
        .iter()
        .filter_map(|s| {
            named
                .iter()
                .find(|n| n.effect == "input_delay" && n.target == *s)
        })
        .collect();
    if moving.len() < 2 || delays.len() != moving.len() {
        return None;
    }
    let values: Vec<f64> = delays.iter().map(|n| n.value).collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let spread = values.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v))
        - values.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    let sigma = delays
        .iter()
        .map(|n| {
            if n.std_error.is_finite() {
                n.std_error
            } else {
                0.0
            }
        })
        .fold(0.0, f64::max);
    if spread > (3.0 * sigma).max(AGREE_SHARE * mean) {
        return None;
    }
    let each: Vec<String> = delays
        .iter()
        .map(|n| format!("{} {:.4} s", n.target, n.value))
        .collect();
    let timing: Vec<NamedCause> = delays.into_iter().cloned().collect();
    named.retain(|n| !(n.effect == "input_delay" && moving.contains(&n.target.as_str())));
    let note = warning(mean, &each.join(", "));
    Some((note, timing))
}

/// The warning that reports a skew of `mean_s` seconds, with its `detail` (the delays as fitted).
fn warning(mean_s: f64, detail: &str) -> String {
    let (verb, why) = if mean_s >= 0.0 {
        (
            "follows",
            "its data system's timing, or sensor filters that lag every channel alike), or a delay common to \
             every surface",
        )
    } else {
        (
            "leads",
            "its data system stamps the surfaces later than the sensors, or logs them at a lower rate and holds \
             them, or filters them)",
        )
    };
    format!(
        "the response {verb} every surface that moves by the same {:.0} ms ({detail}): a time skew between the \
         record's surface and sensor channels ({why}. It is taken as the record's timing, not named as a cause; \
         the validation and the extension carry it",
        1000.0 * mean_s.abs()
    )
}

/// What the selection named about the record's conventions rather than about the aircraft, taken out of the
/// causes: the record's timing ([`common_skew`]) and the accelerometers' position ([`lever_arm::take_positions`]).
pub struct Conventions {
    /// The warnings that report them.
    pub notes: Vec<String>,
    /// The delays taken as the record's timing.
    pub timing: Vec<NamedCause>,
    /// The accelerometers' position.
    pub position: Vec<NamedCause>,
}

/// Takes the record's conventions out of `named` ([`Conventions`]).
pub fn record_conventions(p: &Prepared, named: &mut Vec<NamedCause>) -> Conventions {
    let (timing_note, timing) = common_skew(p, named).unzip();
    let (position_note, position) = lever_arm::take_positions(named).unzip();
    Conventions {
        notes: timing_note.into_iter().chain(position_note).collect(),
        timing: timing.unwrap_or_default(),
        position: position.unwrap_or_default(),
    }
}
