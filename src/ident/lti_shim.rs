//! Temporary stand-ins for `crate::lti` items (being written on the `lti` branch) so that
//! `ident` compiles before that branch lands. Same names and fields as the agreed API.

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// A SISO transfer function, coefficients highest power first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TransferFunction {
    /// Numerator, highest power first.
    pub num: Vec<f64>,
    /// Denominator, highest power first.
    pub den: Vec<f64>,
    /// Sample time for a discrete model, `None` for continuous.
    pub dt_s: Option<f64>,
}

/// Modal parameters of one pole.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// The pole.
    #[serde(with = "super::complex_serde::one")]
    pub pole: Complex64,
    /// Natural frequency |p|.
    pub omega_n_rad_s: f64,
    /// Damping ratio −Re p / |p|.
    pub zeta: f64,
    /// Time constant −1/Re p.
    pub time_constant_s: f64,
    /// Damped period 2π/|Im p| (infinite for a real pole).
    pub period_s: f64,
    /// True for a complex pole.
    pub oscillatory: bool,
}

/// Modal parameters of the given poles.
pub fn modes(poles: &[Complex64]) -> Vec<Mode> {
    poles
        .iter()
        .map(|p| {
            let w = p.norm();
            Mode {
                pole: *p,
                omega_n_rad_s: w,
                zeta: if w > 0.0 { -p.re / w } else { 1.0 },
                time_constant_s: -1.0 / p.re,
                period_s: 2.0 * std::f64::consts::PI / p.im.abs(),
                oscillatory: p.im != 0.0,
            }
        })
        .collect()
}
