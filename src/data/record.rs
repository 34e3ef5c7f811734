//! The in-memory flight record (docs/data.md), its validation and unit-sanity checks.

use super::channel::Channel;
use super::error::{DataError, Warning, WarningKind, IN_MEMORY};

mod control_sign;
mod kinematics;
pub use control_sign::{control_moments, ControlMoment, SIGN_T_RATIO};
use kinematics::{aero_angle_sign_warning, angle_rate_warning, speed_kinematics_warning};

/// The schema columns of docs/data.md, in their canonical order.
pub const SCHEMA_COLUMNS: &[&str] = &super::channel::names(Channel::ALL);

/// Standard gravity, m/s² (ISO 80000-3).
pub const G0_M_S2: f64 = 9.80665;

/// A flight record: a time vector and named columns of equal length, SI units.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FlightRecord {
    /// Sample times, seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// Data columns in file order, excluding `time_s`.
    pub columns: Vec<(String, Vec<f64>)>,
    /// Metadata: the `#` lines before the header, without the `#`.
    pub metadata: Vec<String>,
}

impl FlightRecord {
    /// An empty record over the given time vector.
    pub fn new(time_s: Vec<f64>) -> Self {
        Self {
            time_s,
            columns: Vec::new(),
            metadata: Vec::new(),
        }
    }

    /// Every `step`-th sample (the first one included), with the metadata: a record logged at a fraction of
    /// the rate it was simulated at. No anti-alias filter (docs/data.md: the logger samples, it does not filter).
    pub fn every_nth(&self, step: usize) -> FlightRecord {
        let keep = |v: &[f64]| v.iter().step_by(step.max(1)).copied().collect::<Vec<_>>();
        let mut out = FlightRecord::new(keep(&self.time_s));
        for (name, values) in &self.columns {
            out.push_column(name, keep(values));
        }
        out.metadata = self.metadata.clone();
        out
    }

    /// Adds a column, or replaces the values of an existing column of the same name.
    pub fn push_column(&mut self, name: impl AsRef<str>, values: Vec<f64>) {
        let name = name.as_ref();
        if let Some(slot) = self.columns.iter_mut().find(|(n, _)| n == name) {
            slot.1 = values;
        } else {
            self.columns.push((name.to_string(), values));
        }
    }

    /// The values of a column (`time_s` included), if present: a schema [`Channel`] or any other name.
    pub fn column(&self, name: impl AsRef<str>) -> Option<&[f64]> {
        let name = name.as_ref();
        if name == Channel::Time.name() {
            return Some(&self.time_s);
        }
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// The values of a data column (not `time_s`), to change in place.
    pub fn column_mut(&mut self, name: impl AsRef<str>) -> Option<&mut Vec<f64>> {
        let name = name.as_ref();
        self.columns
            .iter_mut()
            .find(|(n, _)| n == name)
            .map(|(_, c)| c)
    }

    /// The values of a column, or an error saying which tool needs it and why.
    pub fn require(&self, name: impl AsRef<str>, why: &str) -> Result<&[f64], DataError> {
        let name = name.as_ref();
        self.column(name).ok_or_else(|| DataError::MissingColumn {
            column: name.to_string(),
            why: why.to_string(),
            present: self.column_names().join(", "),
        })
    }

    /// All column names, `time_s` first.
    pub fn column_names(&self) -> Vec<&str> {
        std::iter::once(Channel::Time.name())
            .chain(self.columns.iter().map(|(n, _)| n.as_str()))
            .collect()
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when the record holds no samples.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The median time step, seconds (robust to a few dropouts); `None` with fewer than 2 samples.
    pub fn dt_s(&self) -> Option<f64> {
        let mut steps = time_steps(&self.time_s);
        if steps.is_empty() {
            return None;
        }
        Some(median_in_place(&mut steps))
    }

    /// The samples with `from_s ≤ t ≤ to_s` (empty when none lies there).
    pub fn between(&self, from_s: f64, to_s: f64) -> FlightRecord {
        let start = self.time_s.partition_point(|&t| t < from_s);
        let end = self.time_s.partition_point(|&t| t <= to_s);
        self.slice(start, end)
    }

    /// The samples in `[start, end)` as a new record (metadata kept).
    pub fn slice(&self, start: usize, end: usize) -> FlightRecord {
        let end = end.min(self.len());
        let start = start.min(end);
        FlightRecord {
            time_s: self.time_s[start..end].to_vec(),
            columns: self
                .columns
                .iter()
                .map(|(n, v)| (n.clone(), v[start..end].to_vec()))
                .collect(),
            metadata: self.metadata.clone(),
        }
    }

    /// Checks the hard rules (equal lengths, finite values, strictly increasing time, not empty)
    /// and returns the soft findings (unit sanity, irregular sampling) as warnings.
    pub fn validate(&self) -> Result<Vec<Warning>, DataError> {
        let file = IN_MEMORY.to_string();
        if self.time_s.is_empty() {
            return Err(DataError::NoRows { file, line: 1 });
        }
        for (name, values) in &self.columns {
            if values.len() != self.time_s.len() {
                return Err(DataError::LengthMismatch {
                    file,
                    column: name.clone(),
                    expected: self.time_s.len(),
                    found: values.len(),
                });
            }
        }
        // In-memory rows are numbered like a file with one header line: sample i is line i + 2.
        let columns = std::iter::once((Channel::Time.name(), self.time_s.as_slice()))
            .chain(self.columns.iter().map(|(n, v)| (n.as_str(), v.as_slice())));
        for (name, values) in columns {
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(DataError::NonFinite {
                    file,
                    line: i + 2,
                    column: name.to_string(),
                    cell: values[i].to_string(),
                });
            }
        }
        check_time_increasing(&self.time_s, &file, |i| i + 2)?;
        Ok(self.warnings())
    }

    /// Soft findings only: unit sanity, sampling regularity (see [`unit_warnings`]) and the repeated rows the
    /// reader dropped (its metadata line, [`REPEATED_ROWS_NOTE`]).
    pub fn warnings(&self) -> Vec<Warning> {
        let mut w: Vec<Warning> = self
            .metadata
            .iter()
            .filter_map(|m| m.strip_prefix(REPEATED_ROWS_NOTE))
            .map(|m| Warning {
                kind: WarningKind::RepeatedRows,
                column: None,
                message: m.to_string(),
            })
            .collect();
        w.extend(unit_warnings(self));
        if let Some(s) = sampling_warning(&self.time_s) {
            w.push(s);
        }
        w
    }
}

/// The start of the metadata line in which a reader records the repeated rows it dropped (not a `#` line of
/// the file's own): [`FlightRecord::warnings`] reports it.
pub const REPEATED_ROWS_NOTE: &str = " flightid read: ";

/// Differences between consecutive times.
fn time_steps(time_s: &[f64]) -> Vec<f64> {
    time_s.windows(2).map(|w| w[1] - w[0]).collect()
}

pub(crate) use crate::signal::median_in_place;

/// Fails on the first time sample that does not exceed its predecessor.
pub(crate) fn check_time_increasing(
    time_s: &[f64],
    file: &str,
    line_of: impl Fn(usize) -> usize,
) -> Result<(), DataError> {
    for i in 1..time_s.len() {
        if time_s[i] <= time_s[i - 1] {
            return Err(DataError::time_not_increasing(
                file,
                (line_of(i), time_s[i]),
                (line_of(i - 1), time_s[i - 1]),
            ));
        }
    }
    Ok(())
}

/// Largest |value| and its index.
fn max_abs(values: &[f64]) -> Option<(usize, f64)> {
    values
        .iter()
        .enumerate()
        .map(|(i, v)| (i, v.abs()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Unit-sanity heuristics, each with its evidence:
/// - a `_rad` angle (except `psi_rad`, which may be unwrapped) beyond ±π rad (180°) is implausible in
///   radians and typical of degrees; so is an angle of attack, sideslip, pitch angle or surface
///   deflection whose 95th percentile of |value| exceeds 0.7 rad (40°), or a bank angle or latitude whose
///   95th percentile exceeds π/2; `psi_rad` is flagged only when it stays within 0..360 and exceeds 2π;
/// - a `_rad_s` rate beyond 10 rad/s (573 °/s), or a pitch or yaw rate whose 99th percentile of
///   |value| exceeds 2 rad/s (115 °/s), is implausible for an aircraft and typical of deg/s;
/// - an angle and its rate that disagree by 180/π: θ's change over half-second windows against the
///   integral of q cos φ − r sin φ, φ's against that of p (Euler kinematics, Klein & Morelli eq. 3.34),
///   fitted by least squares when they correlate (r > 0.8): a slope near 57.3 says the angle is in
///   degrees, near 1/57.3 the rate; anticorrelated (r < −0.8) with a slope near −1, the rate has the other
///   sign convention;
/// - an α or β anticorrelated in the same way with the rate the flight-path kinematics give it: the vane
///   has the other sign convention ([`aero_angle_sign_warning`]);
/// - a surface whose moment on its axis, by equation error on the rates' increments, has the sign opposite to
///   flightid's convention by more than ten standard errors ([`control_moments`]);
/// - a median `az_m_s2` of +0.5..+2 (g) or +0.5 g..+2 g: a load factor (positive up), not the body-axis
///   specific force (about −g in level flight);
/// - a median airspeed above 300 m/s, or airspeed changing 1.94 (knots) or 3.28 (ft/s) times as
///   fast as the specific force along the flight path says (dV/dt = ax cos α + az sin α − g sin γ,
///   fitted over 1 s windows when they correlate, on 8 windows or more, and only when the slope ± 2
///   standard errors lies wholly nearer one of those factors than 1: [`kinematics::speed_kinematics_warning`]);
/// - a median specific-force magnitude of 0.5..2 means g (in m/s² it is ≈ 9.81 in 1-g flight);
/// - `throttle` outside −0.05..1.05 is not a 0..1 fraction (percent?);
/// - `time_s` steps of a whole number of 2 or more: milliseconds ([`time_unit_suspicion`]);
/// - a flight-state sensor that never moves: a stuck or unplugged sensor ([`stuck_sensor_warnings`]); the
///   column checks above pass over its column (the kinematic ones find nothing in a constant).
pub fn unit_warnings(rec: &FlightRecord) -> Vec<Warning> {
    let mut out: Vec<Warning> = Vec::new();
    if let Some(message) = time_unit_suspicion(&rec.time_s) {
        out.push(Warning {
            kind: WarningKind::LooksLikeMilliseconds,
            column: Some(Channel::Time.to_string()),
            message,
        });
    }
    let stuck = stuck_sensor_warnings(rec);
    let flagged = |out: &[Warning], c: &str| out.iter().any(|w| w.column.as_deref() == Some(c));
    let at = |i: usize| rec.time_s.get(i).copied().unwrap_or(f64::NAN);
    for (name, values) in &rec.columns {
        // A stuck sensor's constant says nothing of its unit.
        if flagged(&stuck, name) {
            continue;
        }
        let Some((i, m)) = max_abs(values) else {
            continue;
        };
        if name.ends_with("_rad") {
            let (suspicious, evidence) = if name == Channel::Psi.name() {
                let min = values.iter().copied().fold(f64::INFINITY, f64::min);
                (
                    m > 2.0 * std::f64::consts::PI * 1.01 && min >= -360.0 && m <= 360.0,
                    None,
                )
            } else if m > std::f64::consts::PI {
                (true, None)
            } else {
                // a bank angle or a latitude may stay beyond 40° for a whole record
                let limit = if name == Channel::Phi.name() || name == Channel::Latitude.name() {
                    std::f64::consts::FRAC_PI_2
                } else {
                    0.7
                };
                let p95 = abs_percentile(values, 0.95);
                (
                    p95 > limit,
                    Some(format!(
                        "95 % of |value| lies below {p95:.4}, but as radians that is {:.0}°, implausible \
                         for this angle over so much of a record",
                        p95.to_degrees()
                    )),
                )
            };
            if suspicious {
                out.push(Warning {
                    kind: WarningKind::LooksLikeDegrees,
                    column: Some(name.clone()),
                    message: evidence.unwrap_or_else(|| {
                        format!(
                            "values look like degrees: |value| reaches {m:.4} at sample {} (t = {} s), \
                             which would be {:.0}° if it were radians",
                            i + 1,
                            at(i),
                            m.to_degrees()
                        )
                    }),
                });
            }
        } else if name.ends_with("_rad_s") {
            let p99 = abs_percentile(values, 0.99);
            let rate_limit = if name == Channel::P.name() { 10.0 } else { 2.0 };
            if m > 10.0 || p99 > rate_limit {
                out.push(Warning {
                    kind: WarningKind::LooksLikeDegreesPerSecond,
                    column: Some(name.clone()),
                    message: format!(
                        "values look like deg/s: |value| reaches {m:.4} at sample {} (t = {} s), \
                         which would be {:.0} °/s if it were rad/s",
                        i + 1,
                        at(i),
                        m.to_degrees()
                    ),
                });
            }
        } else if name == Channel::Airspeed.name() {
            let mut v = values.clone();
            let med = median_in_place(&mut v);
            if med > 300.0 {
                out.push(Warning {
                    kind: WarningKind::LooksLikeKnotsOrFeet,
                    column: Some(name.clone()),
                    message: format!(
                        "median airspeed is {med:.1}, which as m/s would be Mach {:.1} at sea level: \
                         knots or ft/s?",
                        med / 340.3
                    ),
                });
            }
        } else if name == Channel::Throttle.name() {
            let min = values.iter().copied().fold(f64::INFINITY, f64::min);
            let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if min < -0.05 || max > 1.05 {
                out.push(Warning {
                    kind: WarningKind::ThrottleOutOfRange,
                    column: Some(name.clone()),
                    message: format!(
                        "throttle spans {min}..{max}, expected a fraction 0..1 (percent?)"
                    ),
                });
            }
        }
    }
    for w in [
        angle_rate_warning(rec, Channel::Theta, Channel::Q),
        angle_rate_warning(rec, Channel::Phi, Channel::P),
        aero_angle_sign_warning(rec, Channel::Alpha),
        aero_angle_sign_warning(rec, Channel::Beta),
        speed_kinematics_warning(rec),
        accel_g_warning(rec),
    ]
    .into_iter()
    .flatten()
    .chain(control_sign::control_sign_warnings(rec))
    {
        let already = w
            .column
            .as_deref()
            .is_some_and(|c| c.split('/').any(|c| flagged(&out, c)));
        if !already {
            out.push(w);
        }
    }
    out.extend(stuck);
    out
}

/// The flight-state sensors that move in any record of flight: attitude, body rates, air data, altitude and
/// specific forces. Not the inputs (a surface or the throttle the maneuver leaves alone is constant), nor thrust,
/// dynamic pressure, density, latitude or the angular accelerations, which a record may hold constant or derive.
/// (The thirteen schema columns from `phi_rad` to `az_m_s2`.)
pub(crate) const MOVING_SENSORS: [Channel; 13] = Channel::run_from(Channel::Phi);

/// How little a stuck sensor's samples spread, as a fraction of the width of its plausible range
/// ([`Channel::plausible_range`]): 2·10⁻⁸ rad/s for a gyro, 10⁻⁷ m for an altimeter, 3·10⁻⁹ m/s for an
/// airspeed. Far below any sensor's noise or resolution; a constant written with a rounding error stays within.
const STUCK_SPREAD: f64 = 1e-12;

/// The fewest samples, and the shortest span in seconds, on which a sensor is called stuck: a handful of equal
/// samples, or a second or two of them, may be a quiet moment logged at a coarse resolution.
const STUCK_MIN_SAMPLES: usize = 20;
const STUCK_MIN_SPAN_S: f64 = 5.0;

/// Flags each of the [`MOVING_SENSORS`] whose samples all lie within [`STUCK_SPREAD`] of its plausible range
/// of each other, on a record of [`STUCK_MIN_SAMPLES`] or more over [`STUCK_MIN_SPAN_S`] or longer: a stuck or
/// unplugged sensor (a gyro reading 0 while the elevator moves). In flight none of them holds still to that
/// degree. An airspeed of 0 on every row never gets here: the readers refuse it ([`DataError::NoAirspeed`]).
pub(crate) fn stuck_sensor_warnings(rec: &FlightRecord) -> Vec<Warning> {
    let span_s = rec
        .time_s
        .last()
        .zip(rec.time_s.first())
        .map_or(0.0, |(b, a)| b - a);
    MOVING_SENSORS
        .into_iter()
        .filter_map(|c| {
            let values = rec.column(c)?;
            let (lo, hi) = c.plausible_range()?;
            if values.len() < STUCK_MIN_SAMPLES || span_s < STUCK_MIN_SPAN_S {
                return None;
            }
            let min = values.iter().copied().fold(f64::INFINITY, f64::min);
            let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let spread = max - min;
            if spread.is_nan() || spread > STUCK_SPREAD * (hi - lo) {
                return None;
            }
            let value = values[0];
            let held = if spread == 0.0 {
                format!("{value} on every one of its {} rows", values.len())
            } else {
                format!("within {spread:.1e} of {value} on every one of its {} rows", values.len())
            };
            Some(Warning {
                kind: WarningKind::StuckSensor,
                column: Some(c.to_string()),
                message: format!(
                    "{held} ({span_s} s): a stuck or unplugged sensor (no flight holds a measured state this \
                     still); fix the column, or leave it out of the file"
                ),
            })
        })
        .collect()
}

/// The `q`-quantile of |values| (nearest rank).
fn abs_percentile(values: &[f64], q: f64) -> f64 {
    let mut a: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    if a.is_empty() {
        return 0.0;
    }
    let k = ((q * (a.len() - 1) as f64).round() as usize).min(a.len() - 1);
    *a.select_nth_unstable_by(k, |x, y| x.total_cmp(y)).1
}

/// Flags accelerations recorded in g: the median specific-force magnitude is 0.5..2.
fn accel_g_warning(rec: &FlightRecord) -> Option<Warning> {
    let axes: Vec<(Channel, &[f64])> = Channel::SPECIFIC_FORCES
        .into_iter()
        .filter_map(|c| rec.column(c).map(|v| (c, v)))
        .collect();
    if axes.is_empty() || rec.is_empty() {
        return None;
    }
    let mut mags: Vec<f64> = (0..rec.len())
        .map(|i| axes.iter().map(|(_, v)| v[i] * v[i]).sum::<f64>().sqrt())
        .collect();
    let med = median_in_place(&mut mags);
    // The body z axis points down: in flight a_z is about −g cos θ cos φ. A positive median of that size
    // is a load factor (n_z, positive up), in either unit.
    if let Some(az) = rec.column(Channel::Az) {
        let mut v = az.to_vec();
        let az_med = median_in_place(&mut v);
        let in_g = (0.5..2.0).contains(&az_med);
        let in_m_s2 = (0.5 * G0_M_S2..2.0 * G0_M_S2).contains(&az_med);
        if in_g || in_m_s2 {
            return Some(Warning {
                kind: WarningKind::OppositeSign,
                column: Some(Channel::Az.to_string()),
                message: format!(
                    "the median of {} is +{az_med:.3}: flightid's a_z is the body-axis specific force, z \
                     down, about −{G0_M_S2} m/s² in level flight; this looks like a load factor (positive \
                     up): map it with scale = -1.0 (and unit = \"g\" if it is in g)",
                    Channel::Az
                ),
            });
        }
    }
    // Only meaningful when the vertical axis is there: ax/ay alone are near zero in either unit.
    if axes.iter().any(|(c, _)| *c == Channel::Az) && (0.5..2.0).contains(&med) {
        let names: Vec<&str> = axes.iter().map(|(c, _)| c.name()).collect();
        return Some(Warning {
            kind: WarningKind::LooksLikeG,
            column: Some(names.join("/")),
            message: format!(
                "accelerations look like g: median specific-force magnitude is {med:.3}, \
                 but 1-g flight gives ≈ {G0_M_S2} m/s²; multiply by {G0_M_S2} if they are in g"
            ),
        });
    }
    None
}

/// What makes `time_s` look like milliseconds (or microseconds), in a sentence, or `None`: a median step that
/// is a whole number of 2 s or more. A logger's clock in ms at 500 Hz down to 20 Hz writes steps of 2 to 50, and
/// no record meant for identification samples every 2 s or slower (a light aircraft's short period lasts about a
/// second). A median step of exactly 1 s is left alone: 1 Hz flight-data recorders exist, as do 1 kHz loggers.
pub fn time_unit_suspicion(time_s: &[f64]) -> Option<String> {
    let mut steps = time_steps(time_s);
    if steps.is_empty() {
        return None;
    }
    let median = median_in_place(&mut steps);
    if !(median >= 2.0 && (median - median.round()).abs() <= 1e-9 * median) {
        return None;
    }
    let (unit, factor) = if median >= 1000.0 {
        ("microseconds", 1e6)
    } else {
        ("milliseconds", 1e3)
    };
    Some(format!(
        "steps of {median} look like {unit}: in seconds the record would last {:.1} h at {} Hz; \
         convert it with a column map (`time_s = {{ to = \"time_s\", unit = \"{}\" }}`)",
        (time_s[time_s.len() - 1] - time_s[0]) / 3600.0,
        short_rate(1.0 / median),
        if factor == 1e6 { "us" } else { "ms" }
    ))
}

/// A sampling rate for a message: a few significant digits.
fn short_rate(rate_hz: f64) -> String {
    format!("{:.3}", rate_hz)
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
}

/// Flags non-uniform sampling: steps deviating more than 10 % from the median step.
pub fn sampling_warning(time_s: &[f64]) -> Option<Warning> {
    irregular_sampling(time_s).map(|found| Warning {
        kind: WarningKind::IrregularSampling,
        column: Some(Channel::Time.to_string()),
        message: format!(
            "{found}; resample onto a uniform grid (--resample-hz) before identification"
        ),
    })
}

/// What is irregular about the sampling, in a sentence (steps deviating more than 10 % from the median step),
/// or None for a uniform record.
pub(crate) fn irregular_sampling(time_s: &[f64]) -> Option<String> {
    let steps = time_steps(time_s);
    if steps.len() < 2 {
        return None;
    }
    let mut sorted = steps.clone();
    let median = median_in_place(&mut sorted);
    let off: Vec<usize> = steps
        .iter()
        .enumerate()
        .filter(|(_, s)| ((*s - median) / median).abs() > 0.1)
        .map(|(i, _)| i)
        .collect();
    if off.is_empty() {
        return None;
    }
    let min = steps.iter().copied().fold(f64::INFINITY, f64::min);
    let max = steps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some(format!(
        "irregular sampling: {} of {} steps differ from the median step {median:.6} s by more than 10 % \
         (steps range {min:.6} .. {max:.6} s; first at t = {:.4} s)",
        off.len(),
        steps.len(),
        time_s[off[0]]
    ))
}
