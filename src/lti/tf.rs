//! Single-input single-output transfer functions in s (continuous) or z (discrete).

use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::poly::{polyval, polyval_complex, roots, strip_leading};

/// Relative size below which leading numerator coefficients count as round-off (JSBSim's linear
/// models give ~1e-14 leading terms after `ss2tf`, see docs/jsbsim.md).
pub const LEADING_ZERO_REL_TOL: f64 = 1e-12;

/// `num(s)/den(s)` (or in z), coefficients highest power first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransferFunction {
    /// Numerator coefficients, highest power first.
    pub num: Vec<f64>,
    /// Denominator coefficients, highest power first.
    pub den: Vec<f64>,
    /// `None`: continuous time (s); `Some(dt)`: discrete time (z) with sample period dt seconds.
    pub dt_s: Option<f64>,
}

impl TransferFunction {
    /// A continuous-time transfer function num(s)/den(s).
    pub fn new(num: Vec<f64>, den: Vec<f64>) -> Self {
        Self {
            num,
            den,
            dt_s: None,
        }
    }

    /// A discrete-time transfer function num(z)/den(z) with sample period `dt_s`.
    pub fn discrete(num: Vec<f64>, den: Vec<f64>, dt_s: f64) -> Self {
        Self {
            num,
            den,
            dt_s: Some(dt_s),
        }
    }

    /// True for a discrete-time (z-domain) transfer function.
    pub fn is_discrete(&self) -> bool {
        self.dt_s.is_some()
    }

    /// Roots of the denominator.
    pub fn poles(&self) -> Vec<Complex64> {
        roots(&self.den)
    }

    /// Roots of the numerator.
    pub fn zeros(&self) -> Vec<Complex64> {
        roots(&strip_leading(&self.num, LEADING_ZERO_REL_TOL))
    }

    /// Same system with leading denominator coefficient 1, leading zero denominator terms and
    /// round-off-sized leading numerator terms (≤ 1e-12 of the largest) removed.
    pub fn monic(&self) -> Self {
        let den = strip_leading(&self.den, 0.0);
        let lead = den[0];
        let num = strip_leading(&self.num, LEADING_ZERO_REL_TOL);
        if lead == 0.0 {
            return Self {
                num,
                den,
                dt_s: self.dt_s,
            };
        }
        Self {
            num: num.iter().map(|c| c / lead).collect(),
            den: den.iter().map(|c| c / lead).collect(),
            dt_s: self.dt_s,
        }
    }

    /// Numerator degree ≤ denominator degree (after stripping leading round-off).
    pub fn is_proper(&self) -> bool {
        let m = self.monic();
        m.num.len() <= m.den.len()
    }

    /// Steady-state gain: num(0)/den(0) in s, num(1)/den(1) in z (±∞ or NaN with a pole there).
    pub fn dc_gain(&self) -> f64 {
        let x = if self.is_discrete() { 1.0 } else { 0.0 };
        polyval(&self.num, x) / polyval(&self.den, x)
    }

    /// H(jω) (continuous) or H(e^{jωdt}) (discrete) at each angular frequency in rad/s.
    pub fn freq_response(&self, omega_rad_s: &[f64]) -> Vec<Complex64> {
        omega_rad_s
            .iter()
            .map(|&w| {
                let x = match self.dt_s {
                    None => Complex64::new(0.0, w),
                    Some(dt) => Complex64::from_polar(1.0, w * dt),
                };
                polyval_complex(&self.num, x) / polyval_complex(&self.den, x)
            })
            .collect()
    }
}

/// Bode diagram: magnitude in dB and phase in degrees, unwrapped along `omega_rad_s` and starting
/// from the principal value (−180°, 180°] at the first frequency.
pub fn bode(tf: &TransferFunction, omega_rad_s: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let h = tf.freq_response(omega_rad_s);
    let mag_db = h.iter().map(|z| 20.0 * z.norm().log10()).collect();
    let mut phase_deg: Vec<f64> = Vec::with_capacity(h.len());
    let mut prev: Option<f64> = None;
    for z in &h {
        let p = z.arg().to_degrees();
        let unwrapped = match prev {
            None => p,
            Some(q) => p + 360.0 * ((q - p) / 360.0).round(),
        };
        phase_deg.push(unwrapped);
        prev = Some(unwrapped);
    }
    (mag_db, phase_deg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_lag_has_minus_3_db_and_minus_45_deg_at_its_corner() {
        let tf = TransferFunction::new(vec![2.0], vec![0.5, 1.0]); // 2/(0.5 s + 1), corner 2 rad/s
        let (mag, ph) = bode(&tf, &[2.0]);
        assert!((mag[0] - (20.0 * 2.0_f64.log10() - 10.0 * 2.0_f64.log10())).abs() < 1e-12);
        assert!((ph[0] + 45.0).abs() < 1e-12);
        assert_eq!(tf.dc_gain(), 2.0);
    }

    #[test]
    fn phase_of_a_fourth_order_lag_unwraps_past_minus_180() {
        // 1/(s+1)^4: phase −4·atan(ω), reaching −337° at ω = 10
        let tf = TransferFunction::new(vec![1.0], vec![1.0, 4.0, 6.0, 4.0, 1.0]);
        let w: Vec<f64> = (0..200).map(|k| 0.01 * 1.05_f64.powi(k)).collect();
        let (_, ph) = bode(&tf, &w);
        for (wi, p) in w.iter().zip(ph) {
            assert!((p + 4.0 * wi.atan().to_degrees()).abs() < 1e-9, "{wi}: {p}");
        }
    }

    #[test]
    fn monic_divides_by_leading_den_and_drops_round_off_numerator_terms() {
        let tf = TransferFunction::new(vec![3e-15, 4.0, 2.0], vec![2.0, 4.0, 8.0]).monic();
        assert_eq!(tf.num, vec![2.0, 1.0]);
        assert_eq!(tf.den, vec![1.0, 2.0, 4.0]);
    }

    #[test]
    fn discrete_dc_gain_and_frequency_response_use_z_on_the_unit_circle() {
        // y[k] = 0.5 y[k-1] + u[k-1]: H(z) = 1/(z − 0.5), dc gain 2, at Nyquist 1/(−1.5)
        let tf = TransferFunction::discrete(vec![1.0], vec![1.0, -0.5], 0.1);
        assert!((tf.dc_gain() - 2.0).abs() < 1e-15);
        let h = tf.freq_response(&[std::f64::consts::PI / 0.1]);
        assert!((h[0] - Complex64::new(-1.0 / 1.5, 0.0)).norm() < 1e-12);
    }
}
