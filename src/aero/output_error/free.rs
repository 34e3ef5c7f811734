//! Which parameters of the built-in models are free and where they start: the `--free` choices and groups,
//! the default free set of each axis, and start values from equation error (Morelli & Klein §6.3) with the
//! axis's fallbacks.

use std::collections::{BTreeMap, BTreeSet};

use super::OutputErrorOptions;
use crate::aero::airframe::Airframe;
use crate::aero::flight_models::{LATERAL_PARAMETERS, LONGITUDINAL_PARAMETERS};
use crate::aero::measured::{equation_error_measured, AxisChoice};
use crate::aero::regression::CM_ALPHADOT_CONSIDER;
use crate::data;
use crate::estimate::Parameter;

/// One entry of `--free`: a parameter or a group, freed (`NAME`) or held (`-NAME`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FreeChoice {
    /// The parameters it names.
    pub names: Vec<&'static str>,
    /// Free (true) or held at its start value (false).
    pub free: bool,
}

/// Groups `--free` accepts besides parameter names.
pub const FREE_GROUPS: [(&str, &[&str]); 6] = [
    ("speed", &["CL_V", "CD_V", "Cm_V"]),
    ("curvature", &["CL_alpha2", "Cm_alpha2"]),
    ("alphadot", &["CL_alphadot", "Cm_alphadot"]),
    ("zero", &["CL_0", "CD_0", "Cm_0", "CY_0", "Cl_0", "Cn_0"]),
    ("skew", &["tau_alpha_s", "tau_beta_s"]),
    ("all", &[]),
];

/// Parses `--free` entries: a parameter of either model (`Cm_alphadot`), a group of [`FREE_GROUPS`]
/// (`speed`, `curvature`, `alphadot`, `zero`, `skew`, `all`), each optionally prefixed with `-` to hold it instead.
pub fn parse_free(entries: &[String]) -> Result<Vec<FreeChoice>, String> {
    let known = || {
        LONGITUDINAL_PARAMETERS
            .iter()
            .chain(&LATERAL_PARAMETERS)
            .copied()
    };
    entries
        .iter()
        .map(|e| {
            let e = e.trim();
            let (free, name) = match e.strip_prefix('-') {
                Some(rest) => (false, rest),
                None => (true, e.strip_prefix('+').unwrap_or(e)),
            };
            let names: Vec<&'static str> = if name == "all" {
                known().collect()
            } else if let Some((_, g)) = FREE_GROUPS.iter().find(|(g, _)| *g == name) {
                g.to_vec()
            } else if let Some(n) = known().find(|n| *n == name) {
                vec![n]
            } else {
                return Err(format!(
                    "unknown parameter or group '{name}' (groups: speed, curvature, alphadot, zero, skew, all; \
                     parameters: {})",
                    known().collect::<Vec<_>>().join(", ")
                ));
            };
            Ok(FreeChoice { names, free })
        })
        .collect()
}

/// Parameters held by default (module doc); every other parameter of the axis starts free.
pub(super) const LON_HELD: [&str; 11] = [
    "tau_alpha_s",
    "CL_q",
    "CL_alphadot",
    "CL_V",
    "CD_de",
    "CD_V",
    "Cm_alphadot",
    "Cm_V",
    "CL_alpha2",
    "Cm_alpha2",
    GUST_Q_GAIN,
];

/// The gain of the rotary gust in the filter error method's vertical gust (`flight_models` module doc): held
/// at 0 (output error has no gust); filter error leaves it out of the held set (start 0.5), and `--free`
/// can hold it.
pub(super) const GUST_Q_GAIN: &str = "gust_q_gain";

/// |k_q| at most this: MIL-F-8785C's rotary gust has gain 1; on an airframe whose C_mq is small (the p51d:
/// −10 against the c310's −80) the records barely determine k_q, and unbounded it ran off to 9–95 (σ up to
/// 120), taking the shape of other unmodelled motion.
pub(super) const GUST_Q_GAIN_BOUND: f64 = 1.5;
pub(super) const LAT_HELD: [&str; 4] = ["tau_beta_s", "CY_p", "CY_r", "CY_da"];

/// Start value and free flag of every parameter of a model (module doc), with the choices applied.
#[allow(clippy::too_many_arguments)]
pub(super) fn parameters(
    names: &[&'static str],
    default_held: &[&str],
    starts: &BTreeMap<String, f64>,
    fallback: &BTreeMap<&'static str, f64>,
    still: &BTreeSet<&'static str>,
    options: &OutputErrorOptions,
    notes: &mut Vec<String>,
) -> Vec<Parameter> {
    let mut free: BTreeSet<&str> = names
        .iter()
        .copied()
        .filter(|n| !default_held.contains(n))
        .collect();
    if options.alphadot {
        free.extend(["CL_alphadot", "Cm_alphadot"]);
    }
    for c in &options.free {
        for n in &c.names {
            if c.free {
                free.insert(n);
            } else {
                free.remove(n);
            }
        }
    }
    let mut held_still = Vec::new();
    let cm_q = starts
        .get("Cm_q")
        .copied()
        .or_else(|| fallback.get("Cm_q").copied());
    let params: Vec<Parameter> = names
        .iter()
        .map(|&n| {
            let value = starts
                .get(n)
                .copied()
                .or_else(|| fallback.get(n).copied())
                .unwrap_or(0.0);
            let mut p = Parameter::free(n, value);
            if n.starts_with("tau_") {
                p = p.bounded(-0.25, 0.25);
            } else if n == GUST_Q_GAIN {
                p = p.bounded(-GUST_Q_GAIN_BOUND, GUST_Q_GAIN_BOUND);
            }
            let is_free = free.contains(n) && !still.contains(n);
            if free.contains(n) && still.contains(n) {
                held_still.push(n);
            }
            let keeps_start = n.ends_with("_0") || n.starts_with("tau_");
            if is_free {
                p
            } else if keeps_start && !still.contains(n) {
                Parameter { fixed: true, ..p }
            } else if let Some(cm_q) = cm_q.filter(|_| n == "Cm_alphadot") {
                Parameter::fixed(n, 0.0).considered(CM_ALPHADOT_CONSIDER * cm_q.abs())
            } else {
                Parameter::fixed(n, 0.0)
            }
        })
        .collect();
    if !held_still.is_empty() {
        notes.push(format!(
            "held at 0 (a surface no record moves, or a vane the records lack): {}",
            held_still.join(", ")
        ));
    }
    params
}

/// Equation-error start values by name (empty when equation error cannot be formed).
pub(super) fn equation_error_starts(
    records: &[&(String, data::FlightRecord)],
    airframe: &Airframe,
    axis: AxisChoice,
    notes: &mut Vec<String>,
) -> BTreeMap<String, f64> {
    let owned: Vec<(String, data::FlightRecord)> = records.iter().map(|&r| r.clone()).collect();
    match equation_error_measured(&owned, airframe, axis, false) {
        Ok(ee) => ee
            .derivatives
            .into_iter()
            .filter(|(k, _)| k != "CL_q")
            .map(|(k, e)| (k, e.value))
            .collect(),
        Err(e) => {
            notes.push(format!(
                "no equation-error start values ({e}); generic ones used"
            ));
            BTreeMap::new()
        }
    }
}
