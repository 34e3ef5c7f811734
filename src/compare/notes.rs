//! Notes beside the numbers of a comparison: each method named in full, each mode named, and every number that
//! looks wrong explained where it stands (an unstable pole, the paper's least squares drifting in simulation,
//! output error repeating SRIVC to the last digit). The reasoning behind each note is in `docs/methods.md`.

use super::{CompareOutcome, ModelFit};
use crate::ident::IdentResult;
use crate::report::text::{wrap, TERMINAL_WIDTH};

/// Each model of a comparison in full, for the first mention in a report or on the terminal.
pub const MODELS_IN_FULL: &[(&str, &str)] = &[
    (
        "jsbsim_linearization",
        "JSBSim's own linearization at the trim, reduced to the decoupled 4-state submodels (the reference)",
    ),
    (
        "ls",
        "the paper's equation-error ARX least squares (Sahin & Kalyon 2021, eq. 59-64), converted to continuous time",
    ),
    (
        "iv",
        "discrete instrumental variables with auxiliary-model instruments (Soderstrom & Stoica 1989)",
    ),
    (
        "srivc",
        "Young's simplified refined instrumental variable for continuous-time models (Young & Jakeman 1980)",
    ),
    (
        "oe",
        "output error: Levenberg-Marquardt on the simulated response, started from srivc, Cramer-Rao standard errors",
    ),
];

/// The model named in full, or the short name when it is not one of [`MODELS_IN_FULL`].
pub fn in_full(model: &str) -> &str {
    MODELS_IN_FULL
        .iter()
        .find(|(k, _)| *k == model)
        .map(|(_, v)| *v)
        .unwrap_or(model)
}

/// The aircraft modes behind a transfer function's summary columns: (fastest oscillatory mode, fastest real
/// pole). θ/δe: short period (its real pole, if any, is not an aircraft mode); φ/δa and φ/δr: Dutch roll and
/// roll subsidence.
pub fn mode_names(tf_key: &str) -> (&'static str, &'static str) {
    if tf_key.starts_with("theta") {
        ("short period", "real pole")
    } else {
        ("Dutch roll", "roll subsidence")
    }
}

/// How far (points of fit %) the paper's least squares must fall below the best other identified model before its
/// simulation drift is explained on its row.
const LS_DRIFT_MARGIN_PERCENT: f64 = 20.0;

/// Largest relative coefficient difference at which `oe` is said to repeat `srivc`.
const SAME_AS_SRIVC_REL: f64 = 1e-3;

/// Notes on one identified model: its unstable poles, with their standard errors when the method gives them.
pub fn model_notes(r: &IdentResult) -> Vec<String> {
    let mut notes = Vec::new();
    for (i, p) in r.poles.iter().enumerate() {
        if p.re <= 0.0 || p.im < 0.0 {
            continue;
        }
        let doubling_s = std::f64::consts::LN_2 / p.re;
        let kind = if p.im > 0.0 {
            format!("unstable pole pair {:+.4}±{:.4}j rad/s", p.re, p.im)
        } else {
            format!("unstable pole {:+.4} rad/s", p.re)
        };
        let sigma = r.pole_std.get(i).map(|s| s.re).filter(|s| *s > 0.0);
        notes.push(match sigma {
            Some(s) => format!(
                "{kind}: doubles in {doubling_s:.0} s; standard error {s:.4}, {:.1} sigma from stable{}",
                p.re / s,
                if p.re < 2.0 * s {
                    " (the record cannot tell it from a slow stable mode)"
                } else {
                    ""
                }
            ),
            None => format!("{kind}: doubles in {doubling_s:.0} s"),
        });
    }
    notes
}

/// When the paper's least squares simulates far worse than the other identified models, says why on its row.
pub fn note_ls_drift(fits: &mut [ModelFit], one_step_percent: Option<f64>) {
    let best_other = fits
        .iter()
        .filter(|f| f.model != "ls" && f.model != "jsbsim_linearization" && f.error.is_none())
        .map(|f| f.fit_percent)
        .fold(f64::NEG_INFINITY, f64::max);
    let Some(ls) = fits
        .iter_mut()
        .find(|f| f.model == "ls" && f.error.is_none())
    else {
        return;
    };
    if ls.fit_percent < best_other - LS_DRIFT_MARGIN_PERCENT {
        let one_step = one_step_percent
            .map(|p| format!(" ({p:.2} % one step ahead)"))
            .unwrap_or_default();
        ls.notes.push(format!(
            "equation error fits one-step predictions{one_step}, not the simulated response; the nonlinear \
             flight's unmodelled part is not white noise, so it biases the slow poles and the simulation drifts. \
             That is the method: its discrete ARX model simulates alike (docs/methods.md)"
        ));
    }
}

/// When `oe` ended where `srivc` did, says so and why on the `oe` row.
pub fn note_oe_repeating_srivc(fits: &mut [ModelFit]) {
    let coefficients = |f: &ModelFit| {
        f.tf.as_ref()
            .map(|tf| tf.num.iter().chain(&tf.den).copied().collect::<Vec<f64>>())
    };
    let find = |name: &str| {
        fits.iter()
            .position(|f| f.model == name && f.error.is_none())
    };
    let (Some(s), Some(o)) = (find("srivc"), find("oe")) else {
        return;
    };
    let (Some(a), Some(b)) = (coefficients(&fits[s]), coefficients(&fits[o])) else {
        return;
    };
    if a.len() != b.len() {
        return;
    }
    let rel = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-300))
        .fold(0.0, f64::max);
    if rel < SAME_AS_SRIVC_REL {
        fits[o].notes.push(format!(
            "same model as srivc (coefficients within {rel:.0e} relative): a converged SRIVC estimate already \
             satisfies the output-error optimality condition, so oe, started from it, stays (docs/methods.md)"
        ));
    }
}

/// The comparison's terminal summary: the models in full, one row per model with its oscillatory mode named,
/// each row's notes wrapped beneath it, and `verdicts` (paragraphs) wrapped; no line wider than
/// [`TERMINAL_WIDTH`].
pub fn terminal_summary(
    outcome: &CompareOutcome,
    duration_s: f64,
    rate_hz: f64,
    verdicts: &[String],
) -> Vec<String> {
    let w = TERMINAL_WIDTH;
    let mut out = Vec::new();
    let trim = &outcome.trim;
    out.extend(wrap(
        &format!(
            "{} trimmed at {} ft, {} kts: alpha {:.3} deg, throttle {:.3}. One doublet per surface, {duration_s} s \
             recorded at {rate_hz} Hz (fit % of slow modes depends on the record length: demo flies 30 s, compare \
             20 s by default).",
            trim.aircraft,
            trim.point.altitude_ft,
            trim.point.speed_kts,
            trim.alpha_rad.to_degrees(),
            trim.throttle
        ),
        w,
        "",
        "",
    ));
    let mut named: Vec<&str> = Vec::new();
    for fits in outcome.models.values() {
        for f in fits {
            if !named.contains(&f.model.as_str()) {
                named.push(&f.model);
            }
        }
    }
    out.push(String::new());
    for m in named {
        out.extend(wrap(&format!("{m} = {}", in_full(m)), w, "  ", "      "));
    }
    out.push(String::new());
    out.push(format!(
        "{:<15} {:<21} {:<16} {:>9} {:>8} {:>11} {:>10}",
        "transfer fn", "model", "oscillatory mode", "wn rad/s", "zeta", "real pole", "fit %"
    ));
    let cell = |v: Option<&f64>, width: usize, d: usize| match v {
        Some(x) if x.is_finite() => format!("{x:>width$.d$}"),
        _ => format!("{:>width$}", "-"),
    };
    for (key, fits) in &outcome.models {
        for f in fits {
            match &f.error {
                Some(e) => out.extend(wrap(
                    &format!("{key:<15} {:<21} failed: {e}", f.model),
                    w,
                    "",
                    "      ",
                )),
                None => out.push(format!(
                    "{key:<15} {:<21} {:<16} {} {} {} {}",
                    f.model,
                    mode_names(key).0,
                    cell(f.modal.get("osc_omega_n_rad_s"), 9, 4),
                    cell(f.modal.get("osc_zeta"), 8, 4),
                    cell(f.modal.get("real_pole_rad_s"), 11, 4),
                    cell(Some(&f.fit_percent), 10, 2),
                )),
            }
            for n in &f.notes {
                out.extend(wrap(n, w, "      note: ", "            "));
            }
        }
    }
    for v in verdicts {
        out.push(String::new());
        out.extend(wrap(v, w, "", ""));
    }
    out
}
