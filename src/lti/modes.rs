//! Modal parameters of poles: natural frequency, damping, time constant, period.

use std::f64::consts::TAU;

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// One mode of a continuous-time system: a real pole or a complex-conjugate pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// The pole (the one with positive imaginary part for a pair); serialised as `[re, im]`.
    #[serde(with = "complex_as_pair")]
    pub pole: Complex64,
    /// Natural frequency |p|.
    pub omega_n_rad_s: f64,
    /// Damping ratio −Re(p)/|p| (negative when unstable; 1 for a stable real pole).
    pub zeta: f64,
    /// −1/Re(p): time to decay by 1/e; negative for a divergent mode (time to grow by e).
    /// `None` for a pole on the imaginary axis.
    pub time_constant_s: Option<f64>,
    /// Damped period 2π/Im(p) of an oscillatory mode.
    pub period_s: Option<f64>,
    /// True for a complex-conjugate pair.
    pub oscillatory: bool,
}

impl Mode {
    /// The mode of a single pole (a pair is described by either of its members).
    pub fn from_pole(pole: Complex64) -> Self {
        let pole = if pole.im < 0.0 { pole.conj() } else { pole };
        let omega_n_rad_s = pole.norm();
        let oscillatory = pole.im > REAL_POLE_REL_TOL * omega_n_rad_s;
        let zeta = if omega_n_rad_s > 0.0 {
            -pole.re / omega_n_rad_s
        } else {
            1.0
        };
        Self {
            pole,
            omega_n_rad_s,
            zeta,
            time_constant_s: (pole.re != 0.0).then(|| -1.0 / pole.re),
            period_s: oscillatory.then(|| TAU / pole.im),
            oscillatory,
        }
    }

    /// Time to half amplitude (positive, stable) or to double amplitude (negative, unstable): ln 2 · τ.
    pub fn time_to_half_s(&self) -> Option<f64> {
        self.time_constant_s.map(|tau| std::f64::consts::LN_2 * tau)
    }
}

/// Modes of discrete-time poles z with sample period `dt_s`, through s = ln(z)/dt (the pole mapping
/// of ZOH sampling). A pole at z = 0 (or non-positive real z) has no such s and is skipped.
pub fn modes_discrete(poles_z: &[Complex64], dt_s: f64) -> Vec<Mode> {
    let s: Vec<Complex64> = poles_z
        .iter()
        .filter(|z| !(z.re <= 0.0 && z.im == 0.0))
        .map(|z| z.ln() / dt_s)
        .collect();
    modes(&s)
}

/// Imaginary part, relative to |p|, below which a pole counts as real.
const REAL_POLE_REL_TOL: f64 = 1e-9;

/// Modes of a set of poles: conjugate pairs merged into one mode, sorted by ωn, fastest first.
///
/// A complex pole without its conjugate in the list still gives one mode.
pub fn modes(poles: &[Complex64]) -> Vec<Mode> {
    let mut used = vec![false; poles.len()];
    let mut out = Vec::new();
    for i in 0..poles.len() {
        if used[i] {
            continue;
        }
        used[i] = true;
        let p = poles[i];
        let scale = p.norm();
        if p.im.abs() > REAL_POLE_REL_TOL * scale {
            // consume the closest unused conjugate partner
            let partner = (0..poles.len()).filter(|&j| !used[j]).min_by(|&a, &b| {
                (poles[a] - p.conj())
                    .norm()
                    .total_cmp(&(poles[b] - p.conj()).norm())
            });
            if let Some(j) = partner {
                if (poles[j] - p.conj()).norm() <= 1e-6 * scale {
                    used[j] = true;
                }
            }
        }
        out.push(Mode::from_pole(p));
    }
    out.sort_by(|a, b| b.omega_n_rad_s.total_cmp(&a.omega_n_rad_s));
    out
}

/// Serde for a complex number as `[re, im]` (num-complex's own serde feature is not enabled).
mod complex_as_pair {
    use num_complex::Complex64;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(z: &Complex64, s: S) -> Result<S::Ok, S::Error> {
        [z.re, z.im].serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Complex64, D::Error> {
        let [re, im] = <[f64; 2]>::deserialize(d)?;
        Ok(Complex64::new(re, im))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discrete_poles_map_back_to_the_continuous_mode() {
        // s = −1 ± 2i sampled at 0.1 s: z = e^{s dt}
        let s = Complex64::new(-1.0, 2.0);
        let z = (s * 0.1).exp();
        let m = modes_discrete(&[z, z.conj()], 0.1);
        assert_eq!(m.len(), 1);
        assert!((m[0].omega_n_rad_s - 5.0_f64.sqrt()).abs() < 1e-12);
        assert!((m[0].zeta - 1.0 / 5.0_f64.sqrt()).abs() < 1e-12);
        assert!((m[0].period_s.unwrap() - std::f64::consts::PI).abs() < 1e-12);
        assert!((m[0].time_to_half_s().unwrap() - std::f64::consts::LN_2).abs() < 1e-12);
    }
}
