//! What the linearization cannot see: the model's kinks at the trim (terms in |β|, table breakpoints), probed
//! after a re-trim, and where the linearization fits a response poorly, each kink's measured share (the
//! linearization's fit with that term removed).

use super::{
    linearization_gaps, nonsmooth_section, outcome_json, run_compare, CompareError, CompareOptions,
    CompareOutcome, KinkShare,
};
use crate::ident::Method;
use crate::report::Report;
use crate::sim::{JsbsimSim, Simulator};

/// Kinks whose share is measured (each costs a trim, a linearization and a few flights, ~1.5 s on c172x).
const MAX_KINKS_MEASURED: usize = 4;

/// A comparison with the linearization's gaps explained.
pub struct ExplainedComparison {
    /// The comparison.
    pub outcome: CompareOutcome,
    /// Its report, with the kinks' section right after the overview.
    pub report: Report,
    /// [`outcome_json`] with `nonsmooth_terms` and `nonsmooth_shares`.
    pub json: serde_json::Value,
    /// The kinks section's verdicts, for the terminal.
    pub verdicts: Vec<String>,
}

/// [`run_compare`], then the model's kinks at the trim and, where the linearization fits poorly, each kink's
/// measured share. `user_scales` are the coefficient scales the user set (restored after each measurement).
pub fn compare_and_explain(
    sim: &mut JsbsimSim,
    opts: &CompareOptions,
    user_scales: &[(String, f64)],
) -> Result<ExplainedComparison, CompareError> {
    let (outcome, mut report) = run_compare(sim, opts)?;
    let mut json = outcome_json(&outcome);
    let aircraft = outcome.aircraft.clone();
    let during = |what: &str| format!("{what} {aircraft}");
    sim.trim(&opts.point).map_err(|source| CompareError::Sim {
        during: during("re-trimming") + " to probe its coefficient functions",
        source,
    })?;
    let truth = sim.aero_truth().map_err(|source| CompareError::Sim {
        during: during("probing the coefficient functions of"),
        source,
    })?;
    let gaps = linearization_gaps(&outcome);
    let mut shares = Vec::new();
    if !gaps.is_empty() {
        for term in truth.nonsmooth.iter().take(MAX_KINKS_MEASURED) {
            shares.push(kink_share(
                sim,
                opts,
                user_scales,
                &term.coefficient,
                &gaps,
            )?);
        }
    }
    json["nonsmooth_terms"] = serde_json::to_value(&truth.nonsmooth).unwrap_or_default();
    json["nonsmooth_shares"] = serde_json::to_value(&shares).unwrap_or_default();
    let mut verdicts = Vec::new();
    if let Some(section) = nonsmooth_section(&truth.nonsmooth, &outcome, &gaps, &shares) {
        verdicts = section
            .paragraphs
            .iter()
            .filter(|p| p.starts_with("The linearization fits"))
            .cloned()
            .collect();
        // right after the overview table that shows the poor fits
        let at = report
            .sections
            .iter()
            .position(|s| s.heading == "Overview")
            .map_or(report.sections.len(), |i| i + 1);
        report.sections.insert(at, section);
    }
    Ok(ExplainedComparison {
        outcome,
        report,
        json,
        verdicts,
    })
}

/// The linearization's fit on each gap transfer function with `coefficient` scaled to 0 (one cheap comparison:
/// least squares only, one sweep amplitude), then the user's scale restored.
fn kink_share(
    sim: &mut JsbsimSim,
    opts: &CompareOptions,
    user_scales: &[(String, f64)],
    coefficient: &str,
    gaps: &[(String, f64)],
) -> Result<KinkShare, CompareError> {
    let scale = |sim: &mut JsbsimSim, factor: f64| {
        sim.set_coefficient_scale(coefficient, factor)
            .map_err(|source| CompareError::Sim {
                during: format!("scaling {coefficient}"),
                source,
            })
    };
    let restore = user_scales
        .iter()
        .rev()
        .find(|(n, _)| n == coefficient)
        .map_or(1.0, |(_, f)| *f);
    scale(sim, 0.0)?;
    let quick = CompareOptions {
        methods: vec![Method::Ls],
        sweep_amplitudes_deg: vec![opts.amplitude_deg],
        ..opts.clone()
    };
    let outcome = run_compare(sim, &quick);
    scale(sim, restore)?;
    let (outcome, _) = outcome.map_err(|e| match e {
        CompareError::Sim { during, source } => CompareError::Sim {
            during: format!("comparing without {coefficient} to measure its share: {during}"),
            source,
        },
        other => other,
    })?;
    let fits = outcome
        .models
        .iter()
        .filter(|(k, _)| gaps.iter().any(|(g, _)| g == *k))
        .filter_map(|(k, fits)| {
            let lin = fits.iter().find(|f| f.model == "jsbsim_linearization")?;
            Some((k.clone(), lin.fit_percent))
        })
        .collect();
    Ok(KinkShare {
        coefficient: coefficient.to_string(),
        fit_percent_without: fits,
    })
}
