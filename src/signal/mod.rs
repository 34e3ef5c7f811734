//! Input design (doublet, 3-2-1-1, multisine, chirp), measurement noise, resampling, sums of squares and spread.
//!
//! Every maneuver is produced at unit peak amplitude on the sample grid `t_k = k·dt_s`; the caller
//! scales it to a surface deflection. Shapes follow Morelli & Klein, *Aircraft System Identification:
//! Theory and Practice* (2nd ed., 2016), ch. 9 (input design).

mod least_squares;
mod maneuver;
mod ops;

pub use least_squares::{LeastSquares, LeastSquaresError};
pub use maneuver::{
    generate, multisine_design, peak_factor, time_grid, Maneuver, MultisineDesign, Sweep,
};
pub use ops::{
    add_white_noise, cross, difference_noise_std, heading_from_zero_rad, lever_arm_acceleration,
    mean, median_in_place, noise_std, on_uniform_step, resample_linear, slope_and_correlation,
    std_dev, sum_sq, unwrap_rad,
};

/// What can be wrong with a maneuver definition.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalError {
    /// A duration, period or pulse width was not a positive finite number.
    #[error(
        "maneuver {maneuver}: {field} must be a positive finite number of seconds, got {value}"
    )]
    NonPositiveTime {
        maneuver: &'static str,
        field: &'static str,
        value: f64,
    },
    /// A frequency band was empty, negative or not finite.
    #[error("maneuver {maneuver}: frequency band {f_lo_hz} Hz .. {f_hi_hz} Hz is invalid ({why})")]
    BadBand {
        maneuver: &'static str,
        f_lo_hz: f64,
        f_hi_hz: f64,
        why: &'static str,
    },
    /// No harmonic of 1/period_s falls inside the multisine band.
    #[error(
        "multisine: no harmonic of 1/{period_s} s lies in {f_min_hz}..{f_max_hz} Hz; \
         lengthen the period or widen the band"
    )]
    NoHarmonics {
        period_s: f64,
        f_min_hz: f64,
        f_max_hz: f64,
    },
}
