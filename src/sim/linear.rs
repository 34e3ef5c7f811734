//! Reductions of a simulator [`Linearization`]: decoupled longitudinal / lateral submodels and the transfer
//! functions the paper identifies (θ/δe, φ/δa, φ/δr, per radian of surface deflection).

use super::{Linearization, SimError};
use crate::lti::{self, Mode, StateSpace, TransferFunction};
use serde::Serialize;
use std::collections::BTreeMap;

/// Longitudinal states of the decoupled submodel (JSBSim names): Vt, alpha, theta, q.
pub const LONGITUDINAL: [&str; 4] = ["Vt", "Alpha", "Theta", "Q"];
/// Lateral-directional states of the decoupled submodel: beta, phi, p, r.
pub const LATERAL: [&str; 4] = ["Beta", "Phi", "P", "R"];

/// The transfer functions flightid identifies: (key, submodel states, input, output state).
pub const PAPER_TFS: [(&str, [&str; 4], &str, &str); 3] = [
    ("theta/elevator", LONGITUDINAL, "elevator", "Theta"),
    ("phi/aileron", LATERAL, "aileron", "Phi"),
    ("phi/rudder", LATERAL, "rudder", "Phi"),
];

/// Numerator and denominator, highest power first, monic denominator.
#[derive(Debug, Clone, Serialize)]
pub struct TfJson {
    /// Numerator coefficients.
    pub num: Vec<f64>,
    /// Denominator coefficients (leading 1).
    pub den: Vec<f64>,
    /// Poles as [re, im].
    pub poles: Vec<[f64; 2]>,
    /// Zeros as [re, im].
    pub zeros: Vec<[f64; 2]>,
}

fn index(names: &[String], name: &str) -> Result<usize, SimError> {
    names.iter().position(|n| n == name).ok_or_else(|| {
        SimError::Protocol(format!(
            "linearization has no '{name}' (has: {})",
            names.join(", ")
        ))
    })
}

/// The decoupled submodel over `states` with one input and one state as output.
pub fn submodel(
    lin: &Linearization,
    states: &[&str],
    input: &str,
    output: &str,
) -> Result<StateSpace, SimError> {
    let idx: Vec<usize> = states
        .iter()
        .map(|s| index(&lin.states, s))
        .collect::<Result<_, _>>()?;
    let j = index(&lin.inputs, input)?;
    let out = states
        .iter()
        .position(|s| *s == output)
        .expect("output is one of the states");
    let a: Vec<Vec<f64>> = idx
        .iter()
        .map(|&r| idx.iter().map(|&c| lin.a[r][c]).collect())
        .collect();
    let b: Vec<Vec<f64>> = idx.iter().map(|&r| vec![lin.b[r][j]]).collect();
    let c = vec![(0..states.len())
        .map(|k| if k == out { 1.0 } else { 0.0 })
        .collect::<Vec<_>>()];
    let d = vec![vec![0.0]];
    StateSpace::from_rows(&a, &b, &c, &d).map_err(|e| SimError::Protocol(e.to_string()))
}

/// θ/δe, φ/δa, φ/δr of the decoupled 4-state submodels.
pub fn paper_transfer_functions(
    lin: &Linearization,
) -> Result<BTreeMap<String, TransferFunction>, SimError> {
    let mut out = BTreeMap::new();
    for (key, states, input, output) in PAPER_TFS {
        let ss = submodel(lin, &states, input, output)?;
        out.insert(key.to_string(), lti::ss2tf(&ss, 0, 0).monic());
    }
    Ok(out)
}

/// JSON form of a transfer function with its poles and zeros.
pub fn tf_json(tf: &TransferFunction) -> TfJson {
    let pair = |z: &num_complex::Complex64| [z.re, z.im];
    TfJson {
        num: tf.num.clone(),
        den: tf.den.clone(),
        poles: tf.poles().iter().map(pair).collect(),
        zeros: tf.zeros().iter().map(pair).collect(),
    }
}

/// The classical name of each mode of a decoupled submodel (`longitudinal` or `lateral`), in the order given.
///
/// Longitudinal: of two oscillatory pairs the faster is the short period and the slower the phugoid; a single
/// pair is the short period when faster than 1 rad/s (its real poles are then an aperiodic phugoid), else the
/// phugoid (with an aperiodic short period). Lateral: the oscillatory pair is the Dutch roll, the fastest real
/// pole the roll subsidence and the slowest the spiral (Etkin & Reid, *Dynamics of Flight*, ch. 6–7).
pub fn mode_names(submodel: &str, modes: &[Mode]) -> Vec<&'static str> {
    let osc: Vec<f64> = modes
        .iter()
        .filter(|m| m.oscillatory)
        .map(|m| m.omega_n_rad_s)
        .collect();
    let real: Vec<f64> = modes
        .iter()
        .filter(|m| !m.oscillatory)
        .map(|m| m.pole.re.abs())
        .collect();
    let fastest_osc = osc.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let fastest_real = real.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let slowest_real = real.iter().copied().fold(f64::INFINITY, f64::min);
    modes
        .iter()
        .map(|m| match (submodel, m.oscillatory) {
            ("longitudinal", true) if osc.len() >= 2 => {
                if m.omega_n_rad_s == fastest_osc {
                    "short period"
                } else {
                    "phugoid"
                }
            }
            ("longitudinal", true) if m.omega_n_rad_s > 1.0 => "short period",
            ("longitudinal", true) => "phugoid",
            ("longitudinal", false) if osc.iter().any(|w| *w > 1.0) => "phugoid (aperiodic)",
            ("longitudinal", false) => "short period (aperiodic)",
            ("lateral", true) => "Dutch roll",
            ("lateral", false) if real.len() >= 2 && m.pole.re.abs() == slowest_real => "spiral",
            ("lateral", false) if m.pole.re.abs() == fastest_real => "roll subsidence",
            _ => "other",
        })
        .collect()
}

/// Modal parameters of the decoupled longitudinal and lateral submodels.
pub fn submodel_modes(lin: &Linearization) -> Result<BTreeMap<String, Vec<Mode>>, SimError> {
    let mut out = BTreeMap::new();
    for (name, states, input, output) in [
        ("longitudinal", LONGITUDINAL, "elevator", "Theta"),
        ("lateral", LATERAL, "aileron", "Phi"),
    ] {
        let ss = submodel(lin, &states, input, output)?;
        out.insert(name.to_string(), lti::modes(&ss.poles()));
    }
    Ok(out)
}
