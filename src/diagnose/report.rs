//! The diagnose report: named causes, candidates, trim comparison, residual statistics per channel, and
//! overlays (measured / model / extended model) with residual plots on the validation record (the training
//! record when there is none). Written with the shared [`crate::report`] helpers: index.html, report.md, SVGs,
//! report.json (the diagnosis itself).

use std::path::{Path, PathBuf};

use super::replay::ReplayCase;
use super::{DiagnoseError, Diagnosis};
use crate::data::FlightRecord;
use crate::report::{write_report_dir as write_files, LinePlot, Report, Section, Series, Table};

fn f(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        "–".into()
    }
}

fn summary_section(d: &Diagnosis, aircraft: &str) -> Section {
    let mut s = Section {
        heading: "Named cause".into(),
        ..Default::default()
    };
    if d.named_cause.is_empty() {
        s.paragraphs.push(format!(
            "No significant model error found for {aircraft}: no extension passes the criterion \
             (ΔBIC with the effective sample count below the threshold, |z| > 5 with coloured-residual standard \
             errors, a real share of the cost explained, and a gain on the validation record)."
        ));
    }
    s.tables.push(Table::new(
        "Named effects (value ± coloured-residual standard error)",
        &[
            "effect",
            "target",
            "value",
            "std error",
            "cannot be told apart from",
        ],
        d.named_cause
            .iter()
            .map(|c| {
                vec![
                    c.effect.clone(),
                    c.target.clone(),
                    format!("{:.5}", c.value),
                    format!("{:.5}", c.std_error),
                    c.ambiguous_with.join(", "),
                ]
            })
            .collect(),
    ));
    if let Some(v) = &d.validation {
        s.paragraphs.push(format!(
            "Validation record (never fitted): noise-weighted ISE {:.1} → {:.1} ({:.0} % less).",
            v.ise_before,
            v.ise_after,
            100.0 * (1.0 - v.ise_after / v.ise_before)
        ));
        s.tables.push(Table::new(
            "Validation per channel",
            &[
                "channel",
                "fit % before",
                "fit % after",
                "ISE before",
                "ISE after",
            ],
            v.fit_percent_before
                .iter()
                .map(|(c, b)| {
                    let get = |m: &std::collections::BTreeMap<String, f64>| {
                        m.get(c).copied().unwrap_or(f64::NAN)
                    };
                    vec![
                        c.clone(),
                        format!("{b:.1}"),
                        format!("{:.1}", get(&v.fit_percent_after)),
                        format!("{:.4e}", get(&v.ise_per_channel_before)),
                        format!("{:.4e}", get(&v.ise_per_channel_after)),
                    ]
                })
                .collect(),
        ));
    } else {
        s.paragraphs
            .push("No validation record: the gain on unseen data was not measured.".into());
    }
    s
}

fn candidates_section(d: &Diagnosis) -> Section {
    let mut rows: Vec<_> = d.candidates.iter().filter(|c| c.full_fit).collect();
    rows.sort_by_key(|c| c.round);
    let mut s = Section {
        heading: "Candidates fully fitted per selection round".into(),
        ..Default::default()
    };
    s.paragraphs.push(format!(
        "{} candidates evaluated ({} simulations, {:.1} s); the table lists the fully fitted ones, \
         the others are in report.json.",
        d.candidates.len(),
        d.simulations,
        d.wall_s
    ));
    s.tables.push(Table::new(
        "Candidates",
        &[
            "round",
            "effect",
            "target",
            "value",
            "std error",
            "ΔBIC",
            "|z|",
            "held-out share",
            "validation gain",
            "verdict",
        ],
        rows.iter()
            .map(|c| {
                vec![
                    c.round.to_string(),
                    c.effect.clone(),
                    c.target.clone(),
                    f(c.value),
                    f(c.std_error),
                    format!("{:.1}", c.criterion_delta),
                    format!("{:.1}", c.z),
                    c.held_out_share
                        .map(|h| format!("{h:.2}"))
                        .unwrap_or_default(),
                    c.validation_gain
                        .map(|g| format!("{:.1} %", 100.0 * g))
                        .unwrap_or_default(),
                    c.rejected_because
                        .clone()
                        .unwrap_or_else(|| "significant".into()),
                ]
            })
            .collect(),
    ));
    s
}

fn evidence_section(d: &Diagnosis) -> Section {
    let mut s = Section {
        heading: "What the model gets wrong (training record, before extension)".into(),
        paragraphs: d
            .record_warnings
            .iter()
            .chain(&d.warnings)
            .map(|w| format!("Warning: {w}."))
            .collect(),
        ..Default::default()
    };
    s.tables.push(Table::new(
        "Trim: model vs measured initial condition",
        &["quantity", "measured", "model"],
        d.trim_mismatch
            .iter()
            .map(|m| vec![m.quantity.clone(), f(m.measured), f(m.model)])
            .collect(),
    ));
    s.tables.push(Table::new(
        "Residual per channel (before → after); peak cross-correlation with an input at its lag",
        &[
            "channel",
            "fit % before",
            "fit % after",
            "rms before",
            "rms after",
            "whiteness p before",
            "strongest input correlation",
        ],
        d.residuals
            .iter()
            .map(|(c, r)| {
                let a = d.residuals_after.get(c);
                let peak = r
                    .input_correlation
                    .iter()
                    .max_by(|x, y| x.peak.total_cmp(&y.peak))
                    .map(|x| format!("{} ρ={:.2} at {:+.2} s", x.input, x.peak, x.lag_s))
                    .unwrap_or_default();
                vec![
                    c.clone(),
                    format!("{:.1}", r.fit_percent),
                    a.map(|a| format!("{:.1}", a.fit_percent))
                        .unwrap_or_default(),
                    f(r.rms),
                    a.map(|a| f(a.rms)).unwrap_or_default(),
                    format!("{:.3}", r.whiteness_p),
                    peak,
                ]
            })
            .collect(),
    ));
    let conventions = record_conventions(d);
    if !conventions.is_empty() {
        s.tables.push(Table::new(
            "The record's conventions, taken from it (not causes)",
            &["finding", "target", "value", "how the replay takes it"],
            conventions,
        ));
    }
    if !d.skipped.is_empty() {
        s.tables.push(Table::new(
            "Catalogue entries skipped",
            &["effect", "target", "reason"],
            d.skipped
                .iter()
                .map(|k| vec![k.effect.clone(), k.target.clone(), k.reason.clone()])
                .collect(),
        ));
    }
    s
}

/// One row per convention the diagnosis took from the record: its timing, its accelerometers' position and the
/// surface columns it logs with the other sign.
fn record_conventions(d: &Diagnosis) -> Vec<Vec<String>> {
    let timing = d.record_timing.iter().map(|n| {
        vec![
            "time skew".into(),
            n.target.clone(),
            format!("{:+.1} ± {:.1} ms", 1000.0 * n.value, 1000.0 * n.std_error),
            "the surfaces shifted in time (negative: the response leads them)".into(),
        ]
    });
    let position = d.sensor_position.iter().map(|n| {
        vec![
            "accelerometer position".into(),
            n.target.clone(),
            format!("{:+.3} ± {:.3} m", n.value, n.std_error),
            "the simulated accelerations read there".into(),
        ]
    });
    let reversed = d.reversed_inputs.iter().map(|r| {
        vec![
            "other sign convention".into(),
            r.column.clone(),
            format!(
                "moment {:+.2} ± {:.2} on the record, {:+.2} ± {:.2} on the replay (rad/s² per rad)",
                r.record, r.record_std_error, r.model, r.model_std_error
            ),
            "the column reversed".into(),
        ]
    });
    timing.chain(position).chain(reversed).collect()
}

/// Overlays and residual plots of one record: measured, model and extended model per channel.
fn overlay_section(
    label: &str,
    case: &ReplayCase,
    before: &FlightRecord,
    after: &FlightRecord,
) -> Section {
    let mut s = Section {
        heading: format!("Overlays on the {label} record"),
        ..Default::default()
    };
    let t = case.record.time_s.clone();
    for c in &case.outputs {
        let (Some(b), Some(a)) = (before.column(c), after.column(c)) else {
            continue;
        };
        let y = case.measured(c);
        let mut model = Series::new("model", t.clone(), b.to_vec());
        model.reference = true;
        s.plots.push((
            format!("{label}_{c}"),
            LinePlot {
                title: format!("{c}: measured, model, extended model ({label})"),
                x_label: "time, s".into(),
                y_label: c.clone(),
                series: vec![
                    Series::new("measured", t.clone(), y.to_vec()),
                    model,
                    Series::new("extended model", t.clone(), a.to_vec()),
                ],
                log_x: false,
            },
        ));
        let res = |m: &[f64]| y.iter().zip(m).map(|(p, q)| p - q).collect::<Vec<f64>>();
        s.plots.push((
            format!("{label}_{c}_residual"),
            LinePlot {
                title: format!("{c} residual, measured − simulated ({label})"),
                x_label: "time, s".into(),
                y_label: c.clone(),
                series: vec![
                    Series::new("model", t.clone(), res(b)),
                    Series::new("extended model", t.clone(), res(a)),
                ],
                log_x: false,
            },
        ));
    }
    s
}

/// Writes the report directory for a diagnosis, with the traces it carries (validation record if there was one,
/// else the training record).
pub fn write_report(
    d: &Diagnosis,
    aircraft: &str,
    train: &FlightRecord,
    valid: Option<&FlightRecord>,
    dir: &Path,
) -> Result<PathBuf, DiagnoseError> {
    let t = &d.traces;
    let (label, record, before, after) = match (valid, &t.valid_before, &t.valid_after) {
        (Some(v), Some(b), Some(a)) => ("validation", v, b, a),
        _ => ("training", train, &t.train_before, &t.train_after),
    };
    let case = ReplayCase::new(record)?;
    let report = Report {
        title: format!("flightid diagnose — {aircraft}"),
        sections: vec![
            summary_section(d, aircraft),
            evidence_section(d),
            candidates_section(d),
            overlay_section(label, &case, before, after),
        ],
    };
    let json = serde_json::to_value(d).unwrap_or_default();
    Ok(write_files(dir, &report, &json)?)
}
