//! The accelerometers' position: a finding about the record's installation, not a cause.
//!
//! A data system's accelerometers are seldom where the model reads its accelerations (JSBSim's eyepoint for
//! flightid's replay; the CG, or wherever the IMU is mounted, for a real log). At r = (x, y, z) from that point
//! (body axes: forward, right, down) they read a_s = a + ω̇ × r + ω × (ω × r) (`signal::lever_arm_acceleration`).
//! The catalogue's `accelerometer_position` (`extension::AccelerometerPosition`) is r along one axis; it competes in the selection like any sensor
//! effect, so a model error that the pitch or yaw dynamics explain better is named first and the position is not
//! fitted to it. Named, it is the record's installation: [`take_positions`] moves it out of the causes into a
//! warning and the JSON's `sensor_position`.
//!
//! A clean c172x record of the independent generator (seed 41, 40 s) with the accelerometers 0.8 m ahead of the
//! eyepoint and 0.2 m below it (`gen_diagnose_records.py --imu-offset 0.8,0,0.2`; up to 1.1 m/s² on a_z and
//! 0.5 m/s² on a_y) had an a_y scale ×0.45 named before the position was in the catalogue.

use super::extension::ACCELEROMETER_POSITION;
use super::NamedCause;

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
