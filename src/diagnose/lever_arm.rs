//! The accelerometers' position: a nuisance term of every fit.
//!
//! A data system's accelerometers are seldom at the CG. At r = (x, y, z) from it (body axes) they read
//! a_s = a_cg + ω̇ × r + ω × (ω × r) (`signal::lever_arm_acceleration`), while the replay gives the CG's
//! acceleration. The difference is linear in r, so it is three columns of the residual, one per axis of r, built
//! from the record's own rates (ω̇ by a Savitzky–Golay derivative) and projected off every fit like the segments'
//! initial states. A clean c172x record of the independent generator (seed 41, 40 s) with the accelerometers
//! moved 0.8 m ahead of the CG and 0.2 m below it (up to 1.0 m/s² on a_z, 0.5 m/s² on a_y) had an a_y scale ×0.45
//! named; with the columns, nothing.

use super::replay::ReplayCase;
use crate::aero::regression::savitzky_golay_derivative;
use crate::data::Channel;
use crate::signal::lever_arm_acceleration;

/// The accelerometer channels, in the order of the components of [`lever_arm_acceleration`].
const ACCELEROMETERS: [Channel; 3] = [Channel::Ax, Channel::Ay, Channel::Az];

/// The three residual columns (channel-major over `case.outputs`, each channel divided by its weight `sigma`) of
/// an accelerometer 1 m along the body x, y and z axes from the CG; empty when the record compares no
/// accelerometer or is too short for the rates' derivative.
pub fn columns(case: &ReplayCase, sigma: &[f64]) -> Vec<Vec<f64>> {
    let n = case.len();
    let compared: Vec<bool> = case
        .outputs
        .iter()
        .map(|o| ACCELEROMETERS.iter().any(|a| a.to_string() == *o))
        .collect();
    let Some(dt) = case.record.dt_s() else {
        return Vec::new();
    };
    if !compared.contains(&true) || n < 12 {
        return Vec::new();
    }
    let rate = |c: Channel| -> Vec<f64> {
        let v = case.measured(&c.to_string());
        if v.len() == n {
            v.to_vec()
        } else {
            vec![0.0; n]
        }
    };
    let w = [rate(Channel::P), rate(Channel::Q), rate(Channel::R)];
    let Ok(w_dot) = w
        .iter()
        .map(|x| savitzky_golay_derivative(x, dt, 5, 2))
        .collect::<Result<Vec<_>, _>>()
    else {
        return Vec::new();
    };
    (0..3)
        .map(|axis| {
            let mut r = [0.0; 3];
            r[axis] = 1.0;
            let reading: Vec<[f64; 3]> = (0..n)
                .map(|k| {
                    lever_arm_acceleration(
                        [w[0][k], w[1][k], w[2][k]],
                        [w_dot[0][k], w_dot[1][k], w_dot[2][k]],
                        r,
                    )
                })
                .collect();
            let mut col = Vec::with_capacity(n * case.outputs.len());
            for (c, name) in case.outputs.iter().enumerate() {
                match ACCELEROMETERS.iter().position(|a| a.to_string() == *name) {
                    Some(i) => col.extend(reading.iter().map(|a| a[i] / sigma[c])),
                    None => col.extend(std::iter::repeat_n(0.0, n)),
                }
            }
            col
        })
        .collect()
}
