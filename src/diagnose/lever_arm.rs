//! The accelerometers' position: a finding about the record's installation, not a cause.
//!
//! A data system's accelerometers are seldom where the model reads its accelerations (JSBSim's eyepoint for
//! flightid's replay; the CG, or wherever the IMU is mounted, for a real log). At r = (x, y, z) from that point
//! (body axes: forward, right, down) they read a_s = a + ω̇ × r + ω × (ω × r) (`signal::lever_arm_acceleration`).
//! The catalogue's `accelerometer_position` is r along one axis; it competes in the selection like any sensor
//! effect, so a model error that the pitch or yaw dynamics explain better is named first and the position is not
//! fitted to it. Named, it is the record's installation: [`take_positions`] moves it out of the causes into a
//! warning and the JSON's `sensor_position`.
//!
//! A clean c172x record of the independent generator (seed 41, 40 s) with the accelerometers 0.8 m ahead of the
//! eyepoint and 0.2 m below it (`gen_diagnose_records.py --imu-offset 0.8,0,0.2`; up to 1.1 m/s² on a_z and
//! 0.5 m/s² on a_y) had an a_y scale ×0.45 named before the position was in the catalogue.

use super::extension::Effect;
use super::NamedCause;
use crate::data::{Channel, FlightRecord};
use crate::signal::lever_arm_acceleration;

/// The effect name of the accelerometers' position along one body axis.
pub const ACCELEROMETER_POSITION: &str = "accelerometer_position";

/// The columns the position needs in the record: the body rates.
pub const REQUIRED: [Channel; 3] = [Channel::P, Channel::Q, Channel::R];

/// The accelerometer channels, in the order of the components of [`lever_arm_acceleration`].
const ACCELEROMETERS: [Channel; 3] = [Channel::Ax, Channel::Ay, Channel::Az];

/// The accelerometers `value` metres along one body axis from where the model reads its accelerations. Value: m.
pub struct AccelerometerPosition {
    /// 0, 1, 2 for x (forward), y (right), z (down).
    axis: usize,
}

impl AccelerometerPosition {
    /// The position along `axis` (`x`, `y` or `z`; another name is taken as `x`, which `extension::make` never
    /// passes).
    pub fn along(axis: &str) -> Self {
        AccelerometerPosition {
            axis: ["x", "y", "z"].iter().position(|a| *a == axis).unwrap_or(0),
        }
    }
}

impl Effect for AccelerometerPosition {
    fn apply_output(&self, p: &[f64], _target: &str, rec: &mut FlightRecord) {
        let n = rec.len();
        let Some(dt) = rec.dt_s() else {
            return;
        };
        if p[0] == 0.0 || n < 3 {
            return;
        }
        let rates: Vec<Vec<f64>> = REQUIRED
            .iter()
            .map(|c| rec.column(c).map_or_else(|| vec![0.0; n], <[f64]>::to_vec))
            .collect();
        // The simulated rates are smooth: ω̇ by central differences (one-sided at the ends).
        let derivative = |x: &[f64], k: usize| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (x[b] - x[a]) / ((b - a) as f64 * dt)
        };
        let mut r = [0.0; 3];
        r[self.axis] = p[0];
        let extra: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let w = [rates[0][k], rates[1][k], rates[2][k]];
                let w_dot = [0, 1, 2].map(|i| derivative(&rates[i], k));
                lever_arm_acceleration(w, w_dot, r)
            })
            .collect();
        for (i, channel) in ACCELEROMETERS.iter().enumerate() {
            let name = channel.to_string();
            if let Some((_, column)) = rec.columns.iter_mut().find(|(c, _)| *c == name) {
                column.iter_mut().zip(&extra).for_each(|(v, e)| *v += e[i]);
            }
        }
    }
}

/// Takes the accelerometer positions the selection named out of `named`; returns the warning that reports them,
/// with them, or `None` (and `named` unchanged) where none was named.
pub fn take_positions(named: &mut Vec<NamedCause>) -> Option<(String, Vec<NamedCause>)> {
    let (positions, causes): (Vec<NamedCause>, Vec<NamedCause>) = named
        .drain(..)
        .partition(|n| n.effect == ACCELEROMETER_POSITION);
    *named = causes;
    if positions.is_empty() {
        return None;
    }
    let each: Vec<String> = positions
        .iter()
        .map(|n| format!("{} {:+.3} ± {:.3} m", n.target, n.value, n.std_error))
        .collect();
    let note = format!(
        "the accelerometers read as if away from where the model reads its accelerations ({}; body axes: x \
         forward, y right, z down): their position, not a cause; the validation and the extension carry it",
        each.join(", ")
    );
    Some((note, positions))
}
