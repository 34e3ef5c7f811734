//! Stage 4, validate: the model with the named effects on the training record and on the validation record
//! the selection never fitted; the traces of both models for the report.

use std::collections::BTreeMap;

use super::baseline::{analyse_replay, Baseline};
use super::extension::Extension;
use super::prepare::Prepared;
use super::residual::ChannelResidual;
use super::search::{Active, Worker};
use super::{DiagnoseError, Traces, Validation};

/// Residuals with the named effects, the validation gain and the simulated traces.
pub struct Validated {
    /// Residual statistics with the named effects on the training record.
    pub residuals_after: BTreeMap<String, ChannelResidual>,
    /// The validation gain (without a validation record: None).
    pub validation: Option<Validation>,
    /// Simulated traces of the model without and with the named effects.
    pub traces: Traces,
}

/// Re-simulates the records with the selected effects.
pub fn validate(
    worker: &mut Worker,
    p: &Prepared,
    base: &Baseline,
    selected: &[Active],
) -> Result<Validated, DiagnoseError> {
    let sel: Vec<(&dyn Extension, &[f64])> = selected
        .iter()
        .map(|a| (a.ext, a.params.as_slice()))
        .collect();
    let (train_after, residuals_after, _) = analyse_replay(worker, &p.case, &sel)?;
    let mut traces = Traces {
        train_before: base.trace.clone(),
        train_after,
        valid_before: None,
        valid_after: None,
    };
    let validation = match &p.valid {
        Some((v, sigma)) => {
            let (tb, before, _) = analyse_replay(worker, v, &[])?;
            let (ta, after, _) = analyse_replay(worker, v, &sel)?;
            traces.valid_before = Some(tb);
            traces.valid_after = Some(ta);
            let wise = |m: &BTreeMap<String, ChannelResidual>| -> f64 {
                v.outputs
                    .iter()
                    .zip(sigma)
                    .filter_map(|(c, s)| m.get(c).map(|r| r.ise / (s * s)))
                    .sum()
            };
            let pick = |m: &BTreeMap<String, ChannelResidual>, f: fn(&ChannelResidual) -> f64| {
                m.iter().map(|(k, r)| (k.clone(), f(r))).collect()
            };
            Some(Validation {
                ise_before: wise(&before),
                ise_after: wise(&after),
                fit_percent_before: pick(&before, |r| r.fit_percent),
                fit_percent_after: pick(&after, |r| r.fit_percent),
                ise_per_channel_before: pick(&before, |r| r.ise),
                ise_per_channel_after: pick(&after, |r| r.ise),
            })
        }
        None => None,
    };
    Ok(Validated {
        residuals_after,
        validation,
        traces,
    })
}
