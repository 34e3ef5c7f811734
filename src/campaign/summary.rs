//! `flightid campaign report`: modal parameters and control derivatives across flight conditions, and where each
//! method fails.

use super::result::CaseResult;
use super::store::load_results;
use super::CampaignError;
use crate::report::{LinePlot, Report, Section, Series, Table};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::Path;

/// A fit below this (NRMSE %) counts as a method failure in the summary.
pub const POOR_FIT_PERCENT: f64 = 50.0;

/// Builds the summary report of a campaign directory (reads `DIR/cases/*.json`).
pub fn campaign_report(dir: &Path) -> Result<(Report, serde_json::Value), CampaignError> {
    let results = load_results(dir)?;
    if results.is_empty() {
        return Err(CampaignError::Run(format!(
            "{} holds no case results (run `flightid campaign run` first)",
            dir.join("cases").display()
        )));
    }
    let mut report = Report {
        title: format!("Campaign summary: {} cases", results.len()),
        sections: Vec::new(),
    };
    report.sections.push(failures_section(&results));
    let tf_keys: std::collections::BTreeSet<&str> =
        results.iter().map(|r| r.case.tf_key.as_str()).collect();
    for key in tf_keys {
        report.sections.push(modal_section(&results, key));
    }
    let json = json!({
        "cases": results.len(),
        "failed_cases": results.iter().filter(|r| r.status != "ok")
            .map(|r| json!({"id": r.case.id, "error": r.error})).collect::<Vec<_>>(),
        "method_failures": method_failures(&results),
        "results": results,
    });
    Ok((report, json))
}

/// Per method: identifications, estimator errors, poor fits.
fn method_failures(results: &[CaseResult]) -> BTreeMap<String, [usize; 3]> {
    let mut m: BTreeMap<String, [usize; 3]> = BTreeMap::new();
    for id in results.iter().flat_map(|r| &r.identifications) {
        let e = m.entry(id.method.clone()).or_default();
        e[0] += 1;
        if id.error.is_some() {
            e[1] += 1;
        } else if id.fit_sim_percent.is_none_or(|f| f < POOR_FIT_PERCENT) {
            e[2] += 1;
        }
    }
    m
}

fn failures_section(results: &[CaseResult]) -> Section {
    let failed: Vec<Vec<String>> = results
        .iter()
        .filter(|r| r.status != "ok")
        .map(|r| vec![r.case.id.clone(), r.error.clone().unwrap_or_default()])
        .collect();
    let rows = method_failures(results)
        .into_iter()
        .map(|(m, [n, err, poor])| vec![m, n.to_string(), err.to_string(), poor.to_string()])
        .collect();
    let mut tables = vec![Table::new(
        format!("Failures per method (poor fit: simulation fit below {POOR_FIT_PERCENT} %)"),
        &["method", "identifications", "estimator errors", "poor fits"],
        rows,
    )];
    if !failed.is_empty() {
        tables.push(Table::new(
            "Cases that failed (trim or flight)",
            &["case", "error"],
            failed.clone(),
        ));
    }
    Section {
        heading: "Failures".into(),
        paragraphs: vec![format!(
            "{} of {} cases failed before identification.",
            failed.len(),
            results.len()
        )],
        tables,
        plots: vec![],
    }
}

fn modal_section(results: &[CaseResult], key: &str) -> Section {
    let stem = key.replace('/', "_");
    let mut plots = Vec::new();
    let mut rows = Vec::new();
    // noise-free identifications at the smallest amplitude of each case family
    let min_amp: BTreeMap<(String, String), f64> =
        results.iter().fold(BTreeMap::new(), |mut m, r| {
            let k = (r.case.configuration.clone(), r.case.surface.clone());
            let e = m.entry(k).or_insert(f64::INFINITY);
            *e = e.min(r.case.amplitude_deg);
            m
        });
    let picked: Vec<&CaseResult> = results
        .iter()
        .filter(|r| r.status == "ok" && r.case.tf_key == key)
        .filter(|r| {
            min_amp.get(&(r.case.configuration.clone(), r.case.surface.clone()))
                == Some(&r.case.amplitude_deg)
        })
        .collect();
    // one plot per aircraft (their ranges differ by an order of magnitude), one series per configuration and
    // method joining its flight conditions
    let aircraft: std::collections::BTreeSet<&str> =
        picked.iter().map(|r| r.case.aircraft.as_str()).collect();
    for ac in aircraft {
        // the leading numerator coefficient is the control derivative of the transfer function
        // (Mδe for θ/δe, L'δa for φ/δa, L'δr for φ/δr; Morelli & Klein 2016 §3.6), per rad
        let control_derivative = match key {
            "theta/elevator" => "control derivative Mδe (leading numerator), 1/s²",
            "phi/aileron" => "control derivative L'δa (leading numerator), 1/s²",
            "phi/rudder" => "control derivative L'δr (leading numerator), 1/s²",
            _ => "leading numerator coefficient",
        };
        for (quantity, label) in [
            ("osc_omega_n_rad_s", "oscillatory mode ωn, rad/s"),
            ("osc_zeta", "oscillatory mode ζ"),
            ("leading_num", control_derivative),
        ] {
            for (axis, axis_label) in [
                ("speed", "true airspeed, kts"),
                ("altitude", "altitude, ft"),
            ] {
                let mut series: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
                for r in picked.iter().filter(|r| r.case.aircraft == ac) {
                    for id in r.identifications.iter().filter(|i| i.noise_std_deg == 0.0) {
                        let value = match quantity {
                            "leading_num" => id.leading_num,
                            _ => id.modal.get(quantity).copied(),
                        };
                        let Some(v) = value else {
                            continue;
                        };
                        let x = if axis == "speed" {
                            r.case.speed_kts
                        } else {
                            r.case.altitude_ft
                        };
                        series
                            .entry(format!("{} {}", r.case.configuration, id.method))
                            .or_default()
                            .push((x, v));
                    }
                }
                if series.is_empty() {
                    continue;
                }
                plots.push((
                    format!("{stem}_{ac}_{quantity}_vs_{axis}"),
                    LinePlot {
                        title: format!("{ac} {key}: {label} vs {axis}"),
                        x_label: axis_label.into(),
                        y_label: label.into(),
                        series: series
                            .into_iter()
                            .map(|(name, mut pts)| {
                                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                                Series::new(
                                    name,
                                    pts.iter().map(|p| p.0).collect(),
                                    pts.iter().map(|p| p.1).collect(),
                                )
                            })
                            .collect(),
                        log_x: false,
                    },
                ));
            }
        }
    }
    for r in results.iter().filter(|r| r.case.tf_key == key) {
        for id in &r.identifications {
            let g = |q: &str| {
                id.modal
                    .get(q)
                    .map(|v| format!("{v:.4}"))
                    .unwrap_or_else(|| "-".into())
            };
            rows.push(vec![
                r.case.configuration.clone(),
                format!("{}", r.case.altitude_ft),
                format!("{}", r.case.speed_kts),
                format!("{}", r.case.amplitude_deg),
                id.method.clone(),
                format!("{}", id.noise_std_deg),
                g("osc_omega_n_rad_s"),
                g("osc_zeta"),
                g("real_pole_rad_s"),
                id.leading_num
                    .map(|v| format!("{v:.4}"))
                    .unwrap_or_else(|| "-".into()),
                id.fit_sim_percent
                    .map(|v| format!("{v:.1}"))
                    .unwrap_or_else(|| id.error.clone().unwrap_or_else(|| "-".into())),
            ]);
        }
    }
    Section {
        heading: key.to_string(),
        paragraphs: vec![
            "Plots: noise-free identifications at each family's smallest amplitude, one plot per aircraft; each \
             curve joins one configuration's flight conditions (which may change speed and altitude together), \
             a single marker is a configuration flown at one condition."
                .into(),
        ],
        tables: vec![Table::new(
            format!("{key}: identified modal parameters"),
            &[
                "configuration",
                "altitude ft",
                "speed kts",
                "amplitude deg",
                "method",
                "noise deg",
                "ωn rad/s",
                "ζ",
                "real pole rad/s",
                "leading num",
                "fit %",
            ],
            rows,
        )],
        plots,
    }
}
