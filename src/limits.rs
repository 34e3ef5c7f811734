//! The documented range of every number a user gives flightid — on the command line or in an aircraft, campaign
//! or model file — and the memory bound on the records it builds from them.
//!
//! One mechanism: a [`Range`] names a quantity, its unit and its closed interval; [`Range::check`] is used by the
//! file readers and [`Range::parser`] by the command line (a `clap` value parser), so a bad number is refused the
//! same way everywhere, with what was given and what is allowed, before anything is allocated or started.
//! Records are bounded by [`MAX_RECORD_SAMPLES`] ([`check_samples`]): a duration times a rate is estimated before a
//! buffer of that length exists.

/// A closed interval `[min, max]` for one named quantity in one unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// What the number is (a flag or a file field), e.g. `duration_s`.
    pub name: &'static str,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// Unit shown in messages (`s`, `Hz`, `ft`, ...).
    pub unit: &'static str,
}

/// A number outside its range, or a record that would be too large.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LimitError {
    /// The value is not finite or outside `[min, max]`.
    #[error("{name} must be a finite number within [{min}, {max}] {unit}, got {value}")]
    OutOfRange {
        name: String,
        value: f64,
        min: f64,
        max: f64,
        unit: String,
    },
    /// Two values in the wrong order (`from_s` after `to_s`, `min_rad` above `max_rad`).
    #[error("{low_name} ({low}) must be below {high_name} ({high})")]
    Order {
        low_name: String,
        low: f64,
        high_name: String,
        high: f64,
    },
    /// More samples than a [`SampleBudget`] allows.
    #[error("{what}: {samples:.0} samples exceed the limit of {max} per {scope} (each sample holds {holds}, \
             ~{bytes_per_sample} bytes; the limit keeps it under ~{max_mb} MB); {advice}")]
    TooManySamples {
        what: String,
        samples: f64,
        max: usize,
        scope: &'static str,
        holds: &'static str,
        bytes_per_sample: usize,
        max_mb: usize,
        advice: &'static str,
    },
}

/// Most samples (rows) one record may hold: 2.3 h at 120 Hz. A record holds ~40 channels of f64 and the
/// estimators keep a few copies, so this keeps one record's working set under ~2 GB.
pub const MAX_RECORD_SAMPLES: usize = RECORD.max;

/// How many samples one piece of work may hold, and why: the memory per sample and what it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleBudget {
    /// Most samples.
    pub max: usize,
    /// Memory per sample, bytes.
    pub bytes_per_sample: usize,
    /// What is bounded (`record`, `flight-path reconstruction`).
    pub scope: &'static str,
    /// What each sample holds in memory.
    pub holds: &'static str,
    /// What the user can do instead.
    pub advice: &'static str,
}

impl SampleBudget {
    /// `samples` (a count, or an estimate before allocating) within the budget, else
    /// [`LimitError::TooManySamples`] naming `what`.
    pub fn check(&self, what: &str, samples: f64) -> Result<(), LimitError> {
        if samples.is_finite() && samples >= 0.0 && samples <= self.max as f64 {
            Ok(())
        } else {
            Err(LimitError::TooManySamples {
                what: what.to_string(),
                samples,
                max: self.max,
                scope: self.scope,
                holds: self.holds,
                bytes_per_sample: self.bytes_per_sample,
                max_mb: self.max * self.bytes_per_sample / 1_000_000,
                advice: self.advice,
            })
        }
    }
}

/// A record held in memory: every channel as f64, and the few copies the estimators keep.
pub const RECORD: SampleBudget = SampleBudget {
    max: 1_000_000,
    bytes_per_sample: 40 * 8,
    scope: "record",
    holds: "every channel",
    advice: "cut the record (e.g. `flightid segments`) or lower the rate",
};

/// The flight-path reconstruction of `check`: per sample the six reconstructed outputs' sensitivities
/// to every parameter (~20), once as the fit's Jacobian and once weighted for the step (measured: 144 MB
/// for 60 000 samples, 1.6 GB for 1 000 000), and a few seconds of computing per 10 000 samples. A
/// compatibility check is meant for maneuver segments of tens of seconds to minutes; 250 000 samples are
/// 42 min at 100 Hz.
pub const RECONSTRUCTION: SampleBudget = SampleBudget {
    max: 250_000,
    bytes_per_sample: 2_000,
    scope: "flight-path reconstruction",
    holds: "the six reconstructed outputs' sensitivities to every parameter",
    advice: "check a stretch of it (--from-s/--to-s; `flightid segments` lists the maneuvers) or resample \
             it to a lower rate (--resample-hz)",
};

impl Range {
    /// A range for `name` in `unit`.
    pub const fn new(name: &'static str, min: f64, max: f64, unit: &'static str) -> Self {
        Range {
            name,
            min,
            max,
            unit,
        }
    }

    /// The same range under another name (a file field instead of a flag).
    pub const fn named(self, name: &'static str) -> Self {
        Range { name, ..self }
    }

    /// `value` when finite and within the range.
    pub fn check(&self, value: f64) -> Result<f64, LimitError> {
        if value.is_finite() && value >= self.min && value <= self.max {
            Ok(value)
        } else {
            Err(LimitError::OutOfRange {
                name: self.name.to_string(),
                value,
                min: self.min,
                max: self.max,
                unit: self.unit.to_string(),
            })
        }
    }

    /// A command-line value parser: the number, or a message naming the allowed range (clap adds the flag).
    pub fn parser(self) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
        move |text: &str| {
            let value: f64 = text
                .trim()
                .parse()
                .map_err(|_| format!("'{text}' is not a number"))?;
            self.check(value).map_err(|_| {
                format!(
                    "must be a finite number within [{}, {}] {}",
                    self.min, self.max, self.unit
                )
            })
        }
    }
}

/// `low < high`, else an [`LimitError::Order`] naming both.
pub fn check_order(low_name: &str, low: f64, high_name: &str, high: f64) -> Result<(), LimitError> {
    if low < high {
        Ok(())
    } else {
        Err(LimitError::Order {
            low_name: low_name.to_string(),
            low,
            high_name: high_name.to_string(),
            high,
        })
    }
}

/// The sample count of `duration_s` at `rate_hz` (plus the first sample), refused above
/// [`MAX_RECORD_SAMPLES`] before anything of that length is allocated.
pub fn check_samples(what: &str, duration_s: f64, rate_hz: f64) -> Result<usize, LimitError> {
    let samples = duration_s * rate_hz + 1.0;
    RECORD.check(what, samples)?;
    Ok(samples as usize)
}

/// A record read from a file, refused above [`MAX_RECORD_SAMPLES`] rows before the work on it starts (the
/// commands that hold several copies of a record: check, diagnose, replay).
pub fn check_rows(what: &str, rows: usize) -> Result<(), LimitError> {
    RECORD.check(what, rows as f64)
}

/// Record length, s: up to 10 h (with [`MAX_RECORD_SAMPLES`] bounding length × rate).
pub const DURATION_S: Range = Range::new("--duration-s", 0.01, 36_000.0, "s");
/// Maneuver start after the trim state, s.
pub const START_S: Range = Range::new("--start-s", 0.0, 36_000.0, "s");
/// Pulse width of a doublet / 3-2-1-1, s (at least two samples is checked against the rate).
pub const PULSE_S: Range = Range::new("--pulse-s", 0.005, 600.0, "s");
/// Simulation rate, Hz.
pub const RATE_HZ: Range = Range::new("--rate-hz", 10.0, 2000.0, "Hz");
/// Rate a record is resampled to, Hz.
pub const RESAMPLE_HZ: Range = Range::new("--resample-hz", 0.1, 2000.0, "Hz");
/// Frequencies of multisines and chirps, Hz.
pub const FREQUENCY_HZ: Range = Range::new("frequency", 0.001, 1000.0, "Hz");
/// Surface deflection amplitude relative to trim, deg.
pub const AMPLITUDE_DEG: Range = Range::new("--amplitude-deg", -30.0, 30.0, "deg");
/// Smallest input that counts as a maneuver (`segments`), deg.
pub const MIN_AMPLITUDE_DEG: Range = Range::new("--min-amplitude-deg", 0.0, 30.0, "deg");
/// Trim altitude above sea level, ft.
pub const ALTITUDE_FT: Range = Range::new("--altitude-ft", 0.0, 100_000.0, "ft");
/// Trim true airspeed, kts.
pub const SPEED_KTS: Range = Range::new("--speed-kts", 1.0, 2_000.0, "kts");
/// A time within a record, s (`--from-s`, `--to-s`).
pub const TIME_S: Range = Range::new("time", -1e9, 1e9, "s");
/// A surface deflection limit, rad (a full turn either way).
pub const SURFACE_RAD: Range = Range::new(
    "surface limit",
    -std::f64::consts::PI,
    std::f64::consts::PI,
    "rad",
);
/// A scale factor on a model coefficient.
pub const SCALE: Range = Range::new("scale", -1e3, 1e3, "");
/// Measurement noise standard deviation, deg.
pub const NOISE_DEG: Range = Range::new("noise_std_deg", 0.0, 30.0, "deg");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_non_finite_and_outside_values_and_name_the_range() {
        assert_eq!(DURATION_S.check(30.0), Ok(30.0));
        for bad in [f64::NAN, f64::INFINITY, -1.0, 1e9, 1e308] {
            let e = DURATION_S.check(bad).unwrap_err().to_string();
            assert!(e.contains("--duration-s") && e.contains("36000"), "{e}");
        }
        let parse = PULSE_S.parser();
        assert_eq!(parse("1.5"), Ok(1.5));
        assert!(parse("0").unwrap_err().contains("[0.005, 600] s"));
        assert!(parse("inf").is_err() && parse("x").is_err());
    }

    #[test]
    fn record_size_is_estimated_before_allocation() {
        assert_eq!(check_samples("fly", 30.0, 120.0), Ok(3601));
        assert!(check_samples("fly", 1e9, 120.0).is_err());
        assert!(check_samples("fly", 1e308, f64::INFINITY).is_err());
        assert!(check_samples("resample", 10.0, 1e9).is_err());
        assert!(check_order("--from-s", 30.0, "--to-s", 10.0).is_err());
    }
}
