//! Regression baselines: identified modal parameters and control-derivative proxies per aircraft
//! configuration, each with its own tolerance `|new − base| ≤ abs_tol + rel_tol·|base|`.

use super::result::CaseResult;
use super::CampaignError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// One baseline quantity.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaselineEntry {
    /// Aircraft configuration id.
    pub configuration: String,
    /// `<case id>/<method>/n<noise deg>_s<seed>/<quantity>`.
    pub key: String,
    /// Stored value (units in the quantity name).
    pub value: f64,
    /// Relative tolerance.
    pub rel_tol: f64,
    /// Absolute tolerance (quantity units).
    pub abs_tol: f64,
}

/// A baseline file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Baseline {
    /// Campaign it was produced from.
    pub campaign: String,
    /// Configurations it covers.
    pub configurations: Vec<String>,
    /// Quantities.
    #[serde(rename = "quantity", default)]
    pub quantities: Vec<BaselineEntry>,
}

/// A quantity compared with its baseline.
#[derive(Debug, Clone, Serialize)]
pub struct Deviation {
    /// Configuration.
    pub configuration: String,
    /// Quantity key.
    pub key: String,
    /// Baseline value.
    pub baseline: f64,
    /// New value (`None` when the campaign no longer produces it).
    pub current: Option<f64>,
    /// Allowed absolute difference.
    pub allowed: f64,
    /// Within tolerance.
    pub ok: bool,
}

/// Default tolerances per quantity (rel, abs): 5 % on frequencies, poles and gains; ζ also ±0.02.
pub fn default_tolerance(quantity: &str) -> (f64, f64) {
    match quantity {
        "osc_zeta" => (0.05, 0.02),
        _ => (0.05, 1e-6),
    }
}

/// Every regression quantity of the results: (configuration, key, value). Noise-free and noisy
/// identifications both count (noise is seeded, so reruns are reproducible).
pub fn quantities(results: &[CaseResult]) -> Vec<(String, String, f64)> {
    let mut out = Vec::new();
    for r in results.iter().filter(|r| r.status == "ok") {
        for id in r.identifications.iter().filter(|i| i.error.is_none()) {
            let prefix = format!(
                "{}/{}/n{}_s{}",
                r.case.id, id.method, id.noise_std_deg, id.seed
            );
            for (q, v) in &id.modal {
                out.push((r.case.configuration.clone(), format!("{prefix}/{q}"), *v));
            }
            if let Some(v) = id.leading_num {
                out.push((
                    r.case.configuration.clone(),
                    format!("{prefix}/leading_num"),
                    v,
                ));
            }
        }
    }
    out
}

impl Baseline {
    /// Reads a baseline file.
    pub fn load(path: &Path) -> Result<Baseline, CampaignError> {
        super::read_toml(path)
    }

    /// A baseline of the given configurations from campaign results, default tolerances.
    pub fn from_results(
        campaign: &str,
        configurations: &[String],
        results: &[CaseResult],
    ) -> Baseline {
        let quantities = quantities(results)
            .into_iter()
            .filter(|(c, _, _)| configurations.contains(c))
            .map(|(configuration, key, value)| {
                let q = key.rsplit('/').next().unwrap_or("");
                let (rel_tol, abs_tol) = default_tolerance(q);
                BaselineEntry {
                    configuration,
                    key,
                    value,
                    rel_tol,
                    abs_tol,
                }
            })
            .collect();
        Baseline {
            campaign: campaign.to_string(),
            configurations: configurations.to_vec(),
            quantities,
        }
    }

    /// Writes the baseline atomically, with a header comment.
    pub fn save(&self, path: &Path) -> Result<(), CampaignError> {
        let body = toml::to_string(self).map_err(|e| CampaignError::Run(e.to_string()))?;
        let text = format!(
            "# flightid regression baseline, written by `flightid regress --update`.\n\
             # A quantity passes when |new - value| <= abs_tol + rel_tol * |value|; edit tolerances by hand.\n{body}"
        );
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(CampaignError::io(dir))?;
        }
        crate::report::write_atomic(path, text.as_bytes())
            .map_err(|e| CampaignError::Run(e.to_string()))
    }
}

/// Compares results with a baseline: one [`Deviation`] per baseline quantity.
pub fn compare_baseline(baseline: &Baseline, results: &[CaseResult]) -> Vec<Deviation> {
    let current: BTreeMap<(String, String), f64> = quantities(results)
        .into_iter()
        .map(|(c, k, v)| ((c, k), v))
        .collect();
    baseline
        .quantities
        .iter()
        .map(|e| {
            let now = current
                .get(&(e.configuration.clone(), e.key.clone()))
                .copied();
            let allowed = e.abs_tol + e.rel_tol * e.value.abs();
            let ok = now.is_some_and(|v| (v - e.value).abs() <= allowed);
            Deviation {
                configuration: e.configuration.clone(),
                key: e.key.clone(),
                baseline: e.value,
                current: now,
                allowed,
                ok,
            }
        })
        .collect()
}
