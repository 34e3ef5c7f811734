//! The signs a conventional aircraft's derivatives have, and the notes on estimates that have the other one:
//! a surface or rate recorded in another sign convention fits as well, with the derivative's sign turned.

use std::collections::BTreeMap;

use super::Estimate;

/// The signs a conventional aircraft's derivatives have in flightid's conventions (JSBSim's: positive
/// elevator trailing edge down, positive aileron right wing down, positive rudder nose left; body rates
/// positive nose up, right wing down, nose right), and what the other sign usually means.
const EXPECTED_SIGNS: [(&str, f64, &str); 6] = [
    (
        "Cm_de",
        -1.0,
        "the elevator column may have the other sign convention (or the aircraft is a canard)",
    ),
    (
        "Cl_da",
        1.0,
        "the aileron column may have the other sign convention",
    ),
    (
        "Cn_dr",
        -1.0,
        "the rudder column may have the other sign convention",
    ),
    (
        "Cm_q",
        -1.0,
        "pitch damping of this sign is implausible: check the sign of q_rad_s",
    ),
    (
        "Cl_p",
        -1.0,
        "roll damping of this sign is implausible: check the sign of p_rad_s",
    ),
    (
        "Cn_r",
        -1.0,
        "yaw damping of this sign is implausible: check the sign of r_rad_s",
    ),
];

/// Notes on estimates whose sign, significantly (|t| > 3), is not the conventional one ([`EXPECTED_SIGNS`]):
/// a surface or rate recorded in another sign convention fits just as well with the derivative's sign
/// turned, so only the sign can tell. A note, not an error: a canard's C_mδe is positive.
pub fn sign_convention_notes(derivatives: &BTreeMap<String, Estimate>) -> Vec<String> {
    EXPECTED_SIGNS
        .iter()
        .filter_map(|&(name, sign, why)| {
            let e = derivatives.get(name)?;
            let t = e.value / e.std_error.max(f64::MIN_POSITIVE);
            (t * sign < -3.0).then(|| {
                format!(
                    "{name} = {:.4} ± {:.4} has the unconventional sign: {why} (map it with scale = -1.0 in \
                     --columns)",
                    e.value, e.std_error
                )
            })
        })
        .collect()
}
