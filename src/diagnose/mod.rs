//! Diagnose: show what the simulation gets wrong on measured data, name the cause from a catalogue of
//! model extensions, and measure the gain on a validation record (JSON contract: docs/diagnose.md).
//!
//! Pipeline: [`replay`] the record → [`residual`] analysis → fit every [`extension`] by output error
//! ([`search`]) → forward selection by BIC → re-simulate the validation record with the chosen effects.

pub mod extension;
pub mod model;
pub mod replay;
pub mod report;
pub mod residual;
pub mod search;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::data::FlightRecord;
use crate::sim::SimError;
use extension::{Extension, ExtensionFile, FittedEffect};
use replay::{ReplayCase, TrimMismatch};
use residual::ChannelResidual;
use search::{fit, par_map, residuals, Active, Weighted, Worker};

/// Errors of the diagnose module.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// The record is too short to identify anything.
    #[error("record too short: {0}")]
    TooShort(String),
    /// The record lacks something replay needs.
    #[error("bad flight data: {0}")]
    BadData(String),
    /// An effect/target that the catalogue does not know.
    #[error("{0}")]
    UnknownExtension(String),
    /// An extension file that cannot be read.
    #[error("extension file {path}: {message}")]
    ExtensionFile { path: String, message: String },
    /// The report could not be written.
    #[error("report: {0}")]
    Report(#[from] crate::report::ReportError),
    /// The simulation failed (trim at the measured condition, bridge error).
    #[error("simulation during {during}: {source}")]
    Sim { during: String, source: SimError },
}

/// Search settings.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// At most this many effects are named (forward selection rounds).
    pub max_effects: usize,
    /// Candidates fully fitted after the cheap 1-D pass, per round.
    pub full_fit_top: usize,
    /// ΔBIC below which an improvement counts (−10: "very strong" evidence, Kass & Raftery 1995).
    pub bic_threshold: f64,
    /// Minimum |value − null| / std error for a named effect.
    pub min_z: f64,
    /// Minimum relative cost reduction for a named effect (guards against coloured residuals).
    pub min_relative_reduction: f64,
    /// Floor of the noise-normalised residual variance in the criterion: a cost below `floor · n` (the
    /// residual already at the measurement-noise level) earns no further credit.
    pub residual_floor: f64,
    /// Minimum relative reduction of the validation ISE for a named effect (when a validation record is given):
    /// an effect that does not predict unseen data better is not a cause.
    pub min_validation_gain: f64,
    /// Correlation of sensitivities above which near-equal candidates form an ambiguous group.
    pub ambiguity_correlation: f64,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            max_effects: 3,
            full_fit_top: 4,
            bic_threshold: -10.0,
            min_z: 5.0,
            min_relative_reduction: 0.02,
            residual_floor: 1.0,
            min_validation_gain: 0.05,
            ambiguity_correlation: 0.9,
        }
    }
}

/// One evaluated candidate (docs/diagnose.md `candidates`).
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// Effect.
    pub effect: String,
    /// Target.
    pub target: String,
    /// Fitted value.
    pub value: f64,
    /// Standard error (coloured-residual sandwich, at least the Cramér–Rao bound).
    pub std_error: f64,
    /// Noise-weighted cost before (current model).
    pub cost_before: f64,
    /// Noise-weighted cost after fitting this candidate.
    pub cost_after: f64,
    /// `BIC`.
    pub criterion: String,
    /// ΔBIC = n_eff ln(max(J₁, f·n) / max(J₀, f·n)) + ln n_eff (f: residual floor, n_eff: effective sample count).
    pub criterion_delta: f64,
    /// |value − null| / std_error.
    pub z: f64,
    /// Effective number of independent residuals after the fit.
    pub n_eff: f64,
    /// Relative reduction of the validation ISE, when it was evaluated.
    pub validation_gain: Option<f64>,
    /// Why a fully fitted candidate was not named (None for the named one and the cheap-pass ones).
    pub rejected_because: Option<String>,
    /// Selection round (0 = first).
    pub round: usize,
    /// Fully fitted (true) or only the cheap 1-D pass.
    pub full_fit: bool,
}

/// A named cause (docs/diagnose.md `named_cause`).
#[derive(Debug, Clone, Serialize)]
pub struct NamedCause {
    /// Effect.
    pub effect: String,
    /// Target.
    pub target: String,
    /// Value.
    pub value: f64,
    /// Cramér–Rao standard error.
    pub std_error: f64,
    /// Other candidates the data cannot tell apart from this one ("effect/target").
    pub ambiguous_with: Vec<String>,
}

/// Validation on a record the fit never saw (docs/diagnose.md `validation`).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    /// Noise-weighted ISE, Σ_c ISE_c / σ_c², without the named effects.
    pub ise_before: f64,
    /// The same with the named effects.
    pub ise_after: f64,
    /// Fit % per channel before.
    pub fit_percent_before: BTreeMap<String, f64>,
    /// Fit % per channel after.
    pub fit_percent_after: BTreeMap<String, f64>,
    /// Raw ISE per channel before (column units² · s).
    pub ise_per_channel_before: BTreeMap<String, f64>,
    /// Raw ISE per channel after.
    pub ise_per_channel_after: BTreeMap<String, f64>,
}

/// A skipped catalogue entry and why.
#[derive(Debug, Clone, Serialize)]
pub struct Skipped {
    /// Effect.
    pub effect: String,
    /// Target.
    pub target: String,
    /// Reason.
    pub reason: String,
}

/// The whole diagnosis (docs/diagnose.md keys first, extras after).
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// Significant effects, in order of selection; empty when nothing is significant.
    pub named_cause: Vec<NamedCause>,
    /// Every evaluated candidate.
    pub candidates: Vec<Candidate>,
    /// Validation gain (absent without a validation record).
    pub validation: Option<Validation>,
    /// Residual statistics per channel of the unextended model on the training record.
    pub residuals: BTreeMap<String, ChannelResidual>,
    /// Residual statistics with the named effects.
    pub residuals_after: BTreeMap<String, ChannelResidual>,
    /// Model trim vs measured initial condition.
    pub trim_mismatch: Vec<TrimMismatch>,
    /// Catalogue entries not evaluated.
    pub skipped: Vec<Skipped>,
    /// Conditions that limit what the verdict can be trusted for (e.g. a surface column missing).
    pub warnings: Vec<String>,
    /// Noise standard deviation estimated per channel (the cost weights).
    pub noise_std: BTreeMap<String, f64>,
    /// Number of residual values (samples × channels).
    pub n_residuals: usize,
    /// Simulations run.
    pub simulations: usize,
    /// Wall time, s.
    pub wall_s: f64,
}

impl Diagnosis {
    /// The extension file of the named effects.
    pub fn extension_file(&self, aircraft: &str) -> ExtensionFile {
        ExtensionFile {
            aircraft: aircraft.to_string(),
            effects: self
                .named_cause
                .iter()
                .map(|c| FittedEffect {
                    effect: c.effect.clone(),
                    target: c.target.clone(),
                    value: c.value,
                    std_error: c.std_error,
                })
                .collect(),
            model_effects: Vec::new(),
            notes: BTreeMap::new(),
        }
    }
}

fn sim_err(during: &str) -> impl FnOnce(SimError) -> DiagnoseError + '_ {
    move |source| DiagnoseError::Sim {
        during: match source {
            SimError::TrimFailed(_) => {
                format!(
                    "{during}: the model cannot trim at the record's measured initial condition"
                )
            }
            _ => during.to_string(),
        },
        source,
    }
}

/// Noise standard deviation per output channel, floored at 10⁻³ of the channel's spread (noise-free data).
fn weights(case: &ReplayCase) -> Vec<f64> {
    case.outputs
        .iter()
        .map(|c| {
            let y = case.measured(c);
            let m = y.iter().sum::<f64>() / y.len() as f64;
            let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
            residual::noise_std(y).max(1e-3 * sd).max(1e-9)
        })
        .collect()
}

/// A replayed record, its residual statistics per channel and the trim comparison.
pub type ReplayAnalysis = (
    FlightRecord,
    BTreeMap<String, ChannelResidual>,
    Vec<TrimMismatch>,
);

/// Replays a case with extensions and analyses every channel.
pub fn analyse_replay(
    worker: &mut Worker,
    case: &ReplayCase,
    extensions: &[(&dyn Extension, &[f64])],
) -> Result<ReplayAnalysis, DiagnoseError> {
    let (rec, trim) =
        replay::replay(worker.sim.as_mut(), case, extensions).map_err(sim_err("replay"))?;
    let stats = case
        .outputs
        .iter()
        .filter_map(|c| {
            rec.column(c).map(|yhat| {
                (
                    c.clone(),
                    residual::analyse(case.measured(c), yhat, case.dt_s(), &case.inputs),
                )
            })
        })
        .collect();
    Ok((rec, stats, case.trim_mismatch(&trim)))
}

/// Diagnoses `train` (and validates on `valid`) with one simulation per worker.
pub fn diagnose(
    workers: &mut [Worker],
    train: &FlightRecord,
    valid: Option<&FlightRecord>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let t0 = std::time::Instant::now();
    if workers.is_empty() {
        return Err(DiagnoseError::BadData("no simulation worker".into()));
    }
    let mut case = ReplayCase::new(train)?;
    let mut vcase = valid.map(ReplayCase::new).transpose()?;
    if let Some(v) = &vcase {
        if (v.rate_hz - case.rate_hz).abs() > 1e-6 * case.rate_hz {
            return Err(DiagnoseError::BadData(format!(
                "validation record rate {:.3} Hz differs from the training record rate {:.3} Hz",
                v.rate_hz, case.rate_hz
            )));
        }
    }
    // A surface without a column is held at its trim in the replay: if it moved in flight, its effect is
    // unmodelled and any cause named on the axes it drives is suspect.
    let mut warnings: Vec<String> = replay::INPUTS
        .iter()
        .filter(|(_, c)| train.column(c).is_none())
        .map(|(s, c)| {
            format!(
                "no {c} column: the replay holds the {s} at its trim value; if it moved in flight, \
                 causes named on the axes it drives are not trustworthy"
            )
        })
        .collect();
    // Compare only the channels the simulation produces (a linear model may lack accelerations).
    let (probe, _) =
        replay::replay(workers[0].sim.as_mut(), &case, &[]).map_err(sim_err("replay"))?;
    let missing: Vec<String> = case
        .outputs
        .iter()
        .filter(|c| probe.column(c).is_none())
        .cloned()
        .collect();
    if !missing.is_empty() {
        warnings.push(format!(
            "the simulation does not produce {}: not compared",
            missing.join(", ")
        ));
        for c in [Some(&mut case), vcase.as_mut()].into_iter().flatten() {
            c.outputs.retain(|o| !missing.contains(o));
        }
    }
    let w = Weighted {
        case: &case,
        sigma: weights(&case),
    };
    let n = w.n();
    let coeffs = workers[0].sim.coefficient_names();
    let added = workers[0].sim.added_term_names();
    let (catalogue, skipped_raw) = extension::catalogue(&case.record, &coeffs, &added);
    let mut skipped: Vec<Skipped> = skipped_raw
        .into_iter()
        .map(|(effect, target, reason)| Skipped {
            effect,
            target,
            reason,
        })
        .collect();
    // Inputs that do not move cannot reveal signal-path effects.
    let still: Vec<String> = case
        .inputs
        .iter()
        .filter(|(_, d)| d.iter().all(|v| v.abs() < 1e-6))
        .map(|(s, _)| s.clone())
        .collect();
    let catalogue: Vec<&dyn Extension> = catalogue
        .iter()
        .map(|b| b.as_ref())
        .filter(|e| {
            let unexcited =
                e.stage() == extension::Stage::Input && still.iter().any(|s| s == e.target());
            if unexcited {
                skipped.push(Skipped {
                    effect: e.effect().into(),
                    target: e.target().into(),
                    reason: "the input does not move in the record".into(),
                });
            }
            !unexcited
        })
        .collect();

    let (_, residuals_before, trim_mismatch) = analyse_replay(&mut workers[0], &case, &[])?;
    let simulations = AtomicCounter::default();
    let mut selected: Vec<Active> = Vec::new();
    let mut named: Vec<NamedCause> = Vec::new();
    let mut candidates = Vec::new();
    let mut base_cost = {
        let r = residuals(&mut workers[0], &w, &[]).map_err(sim_err("replay"))?;
        r.iter().map(|v| v * v).sum::<f64>()
    };
    let vweights = vcase.as_ref().map(|v| Weighted {
        case: v,
        sigma: weights(v),
    });
    let mut valid_cost = match &vweights {
        Some(vw) => {
            let r = residuals(&mut workers[0], vw, &[]).map_err(sim_err("validation replay"))?;
            Some(r.iter().map(|v| v * v).sum::<f64>())
        }
        None => None,
    };
    for round in 0..opts.max_effects {
        let pool: Vec<&dyn Extension> = catalogue
            .iter()
            .copied()
            .filter(|e| {
                !selected
                    .iter()
                    .any(|s| s.ext.effect() == e.effect() && s.ext.target() == e.target())
            })
            .collect();
        // Cheap pass: each candidate alone (selected effects held), two LM iterations.
        let quick = par_map(workers, &pool, |wk, e| {
            let mut a = with_candidate(&selected, *e, false);
            let out = fit(wk, &w, &mut a, 2, false);
            if let Ok(o) = &out {
                simulations.add(o.evaluations);
            }
            out
        });
        let mut order: Vec<(usize, f64)> = quick
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.as_ref().ok().map(|o| (i, o.cost_after)))
            .filter(|(_, c)| c.is_finite())
            .collect();
        order.sort_by(|a, b| a.1.total_cmp(&b.1));
        let top: Vec<usize> = order.iter().take(opts.full_fit_top).map(|x| x.0).collect();
        // Full pass: the top candidates jointly with the selected effects.
        let top_exts: Vec<&dyn Extension> = top.iter().map(|&i| pool[i]).collect();
        let full = par_map(workers, &top_exts, |wk, e| {
            let mut a = with_candidate(&selected, *e, true);
            let out = fit(wk, &w, &mut a, 10, true);
            if let Ok(o) = &out {
                simulations.add(o.evaluations);
            }
            out.map(|o| (o, a))
        });
        let floor = opts.residual_floor * n as f64;
        // One more parameter per candidate (the selected effects are counted in the base model).
        let bic = |e: &dyn Extension, o: &search::FitOutcome| {
            let k = e.params().len() as f64;
            o.n_eff * (o.cost_after.max(floor) / base_cost.max(floor)).ln() + k * o.n_eff.ln()
        };
        let candidate = |e: &dyn Extension, o: &search::FitOutcome, full_fit: bool| {
            let k = o.values.len() - 1;
            Candidate {
                effect: e.effect().into(),
                target: e.target().into(),
                value: o.values[k],
                std_error: o.std_errors[k],
                cost_before: base_cost,
                cost_after: o.cost_after,
                criterion: "BIC".into(),
                criterion_delta: bic(e, o),
                z: (o.values[k] - e.params()[0].null).abs() / o.std_errors[k].max(1e-300),
                n_eff: o.n_eff,
                validation_gain: None,
                rejected_because: None,
                round,
                full_fit,
            }
        };
        for (i, r) in quick.iter().enumerate() {
            if top.contains(&i) {
                continue;
            }
            if let Ok(o) = r {
                candidates.push(candidate(pool[i], o, false));
            }
        }
        // Significance of each fully fitted candidate: strong BIC evidence with the effective sample count,
        // a value many (sandwich) standard errors from "no effect", and a real share of the cost explained.
        let mut sig: Vec<(usize, f64, usize)> = Vec::new(); // (index in top, cost, index in candidates)
        for (t, r) in full.iter().enumerate() {
            let Ok((o, _)) = r else { continue };
            let mut c = candidate(top_exts[t], o, true);
            let rel = 1.0 - o.cost_after / base_cost;
            let spec = top_exts[t].params()[0];
            let at_bound = (c.value - spec.min).abs() <= 1e-9 * spec.min.abs().max(1.0)
                || (c.value - spec.max).abs() <= 1e-9 * spec.max.abs().max(1.0);
            c.rejected_because = if at_bound {
                // No interior optimum: the effect explains something else (a missing input, another effect).
                Some(format!(
                    "value at the bound of its range [{}, {}]",
                    spec.min, spec.max
                ))
            } else if c.criterion_delta >= opts.bic_threshold {
                Some(format!(
                    "ΔBIC {:.1} ≥ {}",
                    c.criterion_delta, opts.bic_threshold
                ))
            } else if c.z <= opts.min_z {
                Some(format!("|z| {:.1} ≤ {}", c.z, opts.min_z))
            } else if rel <= opts.min_relative_reduction {
                Some(format!("explains {:.1} % of the cost", 100.0 * rel))
            } else {
                None
            };
            if c.rejected_because.is_none() {
                sig.push((t, o.cost_after, candidates.len()));
            }
            candidates.push(c);
        }
        sig.sort_by(|a, b| a.1.total_cmp(&b.1));
        // Prediction: the best significant candidate that also predicts the validation record better.
        let mut chosen = None;
        for &(t, cost_t, ci) in &sig {
            let Ok((_, a)) = &full[t] else { continue };
            if let (Some(vw), Some(before)) = (&vweights, valid_cost) {
                let r = residuals(&mut workers[0], vw, a).map_err(sim_err("validation replay"))?;
                simulations.add(1);
                let gain = 1.0 - r.iter().map(|v| v * v).sum::<f64>() / before;
                candidates[ci].validation_gain = Some(gain);
                if gain < opts.min_validation_gain {
                    candidates[ci].rejected_because = Some(format!(
                        "validation ISE {:.1} % lower (needs {:.0} %)",
                        100.0 * gain,
                        100.0 * opts.min_validation_gain
                    ));
                    continue;
                }
                valid_cost = Some(before * (1.0 - gain));
            }
            chosen = Some((t, cost_t));
            break;
        }
        let Some((best, best_cost)) = chosen else {
            break;
        };
        let sig: Vec<(usize, f64)> = sig.iter().map(|&(t, c, _)| (t, c)).collect();
        let Ok((best_fit, best_active)) = &full[best] else {
            break;
        };
        let kb = best_fit.values.len() - 1;
        let mut ambiguous_with = Vec::new();
        for &(t, c) in &sig {
            if t == best {
                continue;
            }
            let Ok((o, _)) = &full[t] else { continue };
            let rho = search::correlation(
                &best_fit.sensitivities[kb],
                &o.sensitivities[o.values.len() - 1],
            );
            if best_fit.n_eff * (c / best_cost).ln() < 10.0
                && rho.abs() > opts.ambiguity_correlation
            {
                ambiguous_with.push(format!("{}/{}", top_exts[t].effect(), top_exts[t].target()));
            }
        }
        // Accept: the joint fit updates the values of the effects already selected.
        selected = best_active.clone();
        for s in selected.iter_mut() {
            s.free = false;
        }
        named = selected
            .iter()
            .enumerate()
            .map(|(i, s)| NamedCause {
                effect: s.ext.effect().into(),
                target: s.ext.target().into(),
                value: s.params[0],
                std_error: best_fit.std_errors.get(i).copied().unwrap_or(f64::NAN),
                ambiguous_with: named
                    .get(i)
                    .map(|c: &NamedCause| c.ambiguous_with.clone())
                    .unwrap_or_else(|| ambiguous_with.clone()),
            })
            .collect();
        base_cost = best_cost;
    }

    let sel: Vec<(&dyn Extension, &[f64])> = selected
        .iter()
        .map(|a| (a.ext, a.params.as_slice()))
        .collect();
    let (_, residuals_after, _) = analyse_replay(&mut workers[0], &case, &sel)?;
    let validation = match &vcase {
        Some(v) => {
            let sigma = weights(v);
            let (_, before, _) = analyse_replay(&mut workers[0], v, &[])?;
            let (_, after, _) = analyse_replay(&mut workers[0], v, &sel)?;
            let wise = |m: &BTreeMap<String, ChannelResidual>| -> f64 {
                v.outputs
                    .iter()
                    .zip(&sigma)
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
    Ok(Diagnosis {
        named_cause: named,
        candidates,
        validation,
        residuals: residuals_before,
        residuals_after,
        trim_mismatch,
        skipped,
        warnings,
        noise_std: case
            .outputs
            .iter()
            .cloned()
            .zip(w.sigma.iter().copied())
            .collect(),
        n_residuals: n,
        simulations: simulations.get(),
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// The selected effects (free or held) plus one candidate at its null values, free.
fn with_candidate<'e>(
    selected: &[Active<'e>],
    e: &'e dyn Extension,
    free_selected: bool,
) -> Vec<Active<'e>> {
    let mut a: Vec<Active<'e>> = selected
        .iter()
        .map(|s| Active {
            free: free_selected,
            ..s.clone()
        })
        .collect();
    a.push(Active {
        ext: e,
        params: e.params().iter().map(|p| p.null).collect(),
        free: true,
    });
    a
}

#[derive(Default)]
struct AtomicCounter(std::sync::atomic::AtomicUsize);

impl AtomicCounter {
    fn add(&self, k: usize) {
        self.0.fetch_add(k, std::sync::atomic::Ordering::Relaxed);
    }
    fn get(&self) -> usize {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}
