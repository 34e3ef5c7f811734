//! Diagnose: show what the simulation gets wrong on measured data, name the cause from a catalogue of
//! model extensions, and measure the gain on a validation record (JSON contract: docs/diagnose.md).
//!
//! Stages, one file each: [`prepare`] (records, compared channels, weights, the catalogue entries the record
//! can identify) → [`baseline`] (the unextended model) → [`select`] (output-error fits of the [`extension`]
//! catalogue by [`search`], forward selection) → [`kinematic`] (sensor errors from the flight-path
//! reconstruction) → [`validate`] (the named effects on both records, the traces)
//! → [`export`] (the extension file).

pub mod baseline;
pub mod cache;
pub mod equilibrium;
pub mod export;
pub mod extension;
pub mod initial_state;
pub mod kinematic;
pub mod lever_arm;
pub mod model;
pub mod prepare;
pub mod process_noise;
pub mod progress;
pub mod projection;
pub mod rate;
pub mod refit;
pub mod relax;
pub mod replay;
pub mod report;
pub mod residual;
pub mod residual_filter;
pub mod search;
pub mod select;
pub mod simulator;
pub mod skew;
pub mod start;
pub mod validate;
pub mod workers;

use std::collections::BTreeMap;

use serde::Serialize;

use crate::data::FlightRecord;
use crate::sim::SimError;
pub use baseline::{analyse_replay, ReplayAnalysis};
use replay::TrimMismatch;
use residual::ChannelResidual;
use search::Worker;

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
    /// A linear-model file (`--linear`, `flightid linearize --json` output) that cannot be read.
    #[error("linear-model file {path}: {message}")]
    LinearModelFile { path: String, message: String },
    /// The aircraft configuration cannot be loaded.
    #[error(transparent)]
    Aircraft(#[from] crate::aircraft::AircraftError),
    /// The report could not be written.
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
    /// The simulation failed (trim at the measured condition, bridge error).
    #[error("simulation during {during}: {source}")]
    Sim { during: String, source: SimError },
}

/// Search settings.
#[derive(Debug, Clone)]
pub struct DiagnoseOptions {
    /// At most this many effects are named (forward selection rounds; a round whose effect a later joint fit
    /// drops is given back, up to this many times).
    pub max_effects: usize,
    /// Candidates fully fitted after the score-test screening, per round (six: a hidden `Cn_beta` ×0.58 ranked
    /// fifth by the score test, whose linearisation at "no effect" underrates a large change of a mode's frequency).
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
    /// Share of a linear term's resolution that a refinement of it (`CL_alpha2` of `CL_alpha`) must match in
    /// output signature to be worth naming (docs/diagnose.md, Selection).
    pub refinement_share: f64,
    /// Correlation of sensitivities above which near-equal candidates form an ambiguous group.
    pub ambiguity_correlation: f64,
    /// Show the search's progress on a terminal (stderr).
    pub progress: bool,
    /// Estimate the process noise (turbulence) of the training record and, when the likelihood says it is
    /// there, search on the filter error method's innovations (`process_noise`; docs/diagnose.md, Turbulence).
    pub process_noise: bool,
    /// On a record without the filter in the search: once causes are named, estimate the process noise from the
    /// extended model's residual and, when it is there, refit the named values by the filter error method
    /// (`refit::refit_in_turbulence`).
    pub filter_values: bool,
    /// After forward selection, drop every named effect that no longer passes the tests with the others in the
    /// model (`select::eliminate_backward`).
    pub backward_elimination: bool,
    /// Weight every channel whose unextended residual is far above its sensor noise by that residual instead
    /// (`relax`; docs/diagnose.md, Turbulence).
    pub relax_weights: bool,
    /// Choose the replay's integration rate from the record (`rate`; experimental, off by default: a hidden
    /// delay leans on the choice); off, the workers' rate is kept.
    pub choose_rate: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            max_effects: 3,
            full_fit_top: 6,
            bic_threshold: -10.0,
            min_z: 5.0,
            min_relative_reduction: 0.02,
            residual_floor: 1.0,
            ambiguity_correlation: 0.9,
            refinement_share: 1.0 / 3.0,
            progress: true,
            process_noise: false,
            filter_values: true,
            backward_elimination: false,
            relax_weights: true,
            choose_rate: false,
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
    /// `BIC`, or `kinematics` for a sensor error named from the flight-path reconstruction.
    pub criterion: String,
    /// ΔBIC = n_eff ln(max(J₁, f·n) / max(J₀, f·n)) + ln n_eff (f: residual floor, n_eff: effective sample count).
    pub criterion_delta: f64,
    /// |value − null| / std_error.
    pub z: f64,
    /// Effective number of independent residuals after the fit.
    pub n_eff: f64,
    /// Smallest effect worth naming on this record (parameter units; larger than the entry's own for a term
    /// that refines a linear one on a record that barely excites the difference).
    pub resolution: f64,
    /// Relative reduction of the validation ISE by the accepted effects up to this one (reported, never used
    /// to select).
    pub validation_gain: Option<f64>,
    /// Why a fully fitted candidate was not named (None for the named one and the cheap-pass ones).
    pub rejected_because: Option<String>,
    /// Selection round (0 = first).
    pub round: usize,
    /// Fully fitted (true) or only screened by the score test.
    pub full_fit: bool,
    /// Leave-one-segment-out cross-validation of the fitted change on the training record: the cost it
    /// removes on each held-out segment when its size is estimated from the others, over the cost it removes
    /// there in the fit (`None` where no segment can be held out, and for the fits after forward selection). For a
    /// cause the filter error refit adds, the same share between the first and second halves of the segments
    /// (`None` where neither half can be held out).
    pub held_out_share: Option<f64>,
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
    /// Input delays alike on every surface that moves, taken as the record's timing (a skew between its surface
    /// and sensor channels) instead of as causes (`skew`); the validation and the extension file carry them.
    pub record_timing: Vec<NamedCause>,
    /// The accelerometers' position along the body axes the selection found, taken as the record's installation
    /// instead of as causes (`lever_arm`); the validation and the extension file carry it.
    pub sensor_position: Vec<NamedCause>,
    /// Surface columns logged with the other sign convention, reversed for the replay (`prepare`).
    pub reversed_inputs: Vec<prepare::ReversedInput>,
    /// What the CSV readers find in the records as given (repeated rows dropped, units, a surface's sign),
    /// printed when a command reads them and kept here for the JSON.
    pub record_warnings: Vec<String>,
    /// Model trim vs measured initial condition.
    pub trim_mismatch: Vec<TrimMismatch>,
    /// Catalogue entries not evaluated.
    pub skipped: Vec<Skipped>,
    /// Conditions that limit what the verdict can be trusted for (e.g. a surface column missing).
    pub warnings: Vec<String>,
    /// The process noise estimated on the training record (turbulence) and whether the search used the filter
    /// error method; absent without `--process-noise` or when the simulation cannot set its state mid-flight.
    pub process_noise: Option<process_noise::ProcessNoise>,
    /// Noise standard deviation estimated per channel (the cost weights).
    pub noise_std: BTreeMap<String, f64>,
    /// Channels weighted by their unextended residual instead of their noise, with the factor on their noise
    /// variance (`relax`; empty when every channel sits near its noise).
    pub relaxed_weights: BTreeMap<String, f64>,
    /// The replay's integration rate chosen from the record, with the rates tried (`rate`; absent unless
    /// `choose_rate` asked for it and there was more than one rate to try).
    pub replay_rate: Option<rate::RateChoice>,
    /// Number of residual values (samples × channels).
    pub n_residuals: usize,
    /// Simulations run.
    pub simulations: usize,
    /// Wall time, s.
    pub wall_s: f64,
    /// Time spent inside the simulations (summed over the workers), s.
    pub simulation_s: f64,
    /// Wall time and simulations per stage, in order (a stage that runs again, such as a candidate round,
    /// once per run).
    pub stages: Vec<progress::StageTime>,
    /// Simulated traces of the model without and with the named effects (for the report; not in the JSON).
    #[serde(skip)]
    pub traces: Traces,
}

/// Simulated records of the model without and with the named effects, on the measured records' grids.
#[derive(Debug, Clone, Default)]
pub struct Traces {
    /// Training record, unextended model.
    pub train_before: FlightRecord,
    /// Training record, with the named effects.
    pub train_after: FlightRecord,
    /// Validation record, unextended model.
    pub valid_before: Option<FlightRecord>,
    /// Validation record, with the named effects.
    pub valid_after: Option<FlightRecord>,
}

/// Diagnoses `train` (and validates on `valid`) with one simulation per worker.
pub fn diagnose(
    workers: &mut [Worker],
    train: &FlightRecord,
    valid: Option<&FlightRecord>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let t0 = std::time::Instant::now();
    let sim_s0: f64 = workers.iter().map(|w| w.sim_s).sum();
    search::share_replays(workers);
    let no_worker = || DiagnoseError::BadData("no simulation worker".into());
    let first = workers.first_mut().ok_or_else(no_worker)?;
    // The progress line is cleared when `progress` is dropped, also on an early error return.
    let progress = progress::Progress::new(opts.progress, first.shared_simulations());
    progress.stage("trim", 0);
    let mut p = prepare::prepare(first, train, valid)?;
    let reconstruction = kinematic::Reconstruction::start(train);
    let (columns, relaxed_weights, replay_rate) = nuisance(workers, &mut p, opts, &progress)?;
    let process_noise = if opts.process_noise {
        turbulence(&mut workers[0], &mut p, columns.clone())?
    } else {
        p.nuisance = search::orthonormal_basis(&columns);
        None
    };
    progress.stage("baseline replay", 0);
    let base = baseline::baseline(&mut workers[0], &p)?;
    let mut warnings = std::mem::take(&mut p.warnings);
    warnings.extend(base.loading_warning());
    let mut sel = select::select(workers, &p, &base, opts, &progress)?;
    let (process_noise, refit_note) = match process_noise {
        // Output error searched (no filter, or none used): the values may still want the filter.
        searched if opts.filter_values && !searched.as_ref().is_some_and(|n| n.used) => {
            progress.stage("values in turbulence", 0);
            let found = refit::refit_in_turbulence(
                &mut workers[0],
                &p,
                &columns,
                &mut sel,
                opts,
                &progress,
            )?
            .or(searched);
            let note = found.as_ref().filter(|n| n.used).map(refit::warning);
            (found, note)
        }
        found => (found, None),
    };
    progress.stage("kinematic findings", 0);
    kinematic::kinematic_findings(&mut workers[0], train, reconstruction, &p, &mut sel, opts)?;
    let conventions = skew::record_conventions(&p, &mut sel.named);
    warnings.extend(refit_note.into_iter().chain(conventions.notes));
    progress.stage("validation", 0);
    let v = validate::validate(&mut workers[0], &p, &base, &sel.selected)?;
    progress.finish();
    let stages = progress.stage_times();
    Ok(Diagnosis {
        named_cause: sel.named,
        candidates: sel.candidates,
        validation: v.validation,
        residuals: base.residuals,
        residuals_after: v.residuals_after,
        trim_mismatch: base.trim_mismatch,
        skipped: [p.skipped.clone(), sel.unidentifiable].concat(),
        warnings,
        record_timing: conventions.timing,
        sensor_position: conventions.position,
        reversed_inputs: p.reversed_inputs,
        record_warnings: p.record_warnings,
        process_noise,
        noise_std: p.case.outputs.iter().cloned().zip(p.noise_sigma).collect(),
        relaxed_weights,
        replay_rate,
        n_residuals: p.case.len() * p.case.outputs.len(),
        simulations: progress.simulations(),
        wall_s: t0.elapsed().as_secs_f64(),
        simulation_s: workers.iter().map(|w| w.sim_s).sum::<f64>() - sim_s0,
        stages,
        traces: v.traces,
    })
}

/// What [`nuisance`] gives: the nuisance columns, the relaxed channels' factors and the integration rate.
type Nuisance = (
    Vec<Vec<f64>>,
    BTreeMap<String, f64>,
    Option<rate::RateChoice>,
);

/// The segment initial-state responses of the training record (the nuisance columns), the channels whose
/// weights are relaxed to their residual (`relax`, which reweights `p.sigma` and the columns) and the replay's
/// integration rate chosen on those weights (`rate::choose`: the gusts' response, which no rate models, then
/// weighs no more than it does in the search).
fn nuisance(
    workers: &mut [Worker],
    p: &mut prepare::Prepared,
    opts: &DiagnoseOptions,
    progress: &progress::Progress,
) -> Result<Nuisance, DiagnoseError> {
    progress.stage("segment initial states", 0);
    let mut columns = initial_state::initial_state_columns(workers, &p.case, &p.sigma)
        .map_err(sim_err("replay"))?;
    if let Some(settled) = equilibrium::settle(workers, p, &columns, progress)? {
        p.warnings.push(settled.note);
        progress.stage("segment initial states", 0);
        columns = initial_state::initial_state_columns(workers, &p.case, &p.sigma)
            .map_err(sim_err("replay"))?;
        columns.push(settled.column);
    }
    let (columns, relaxed) = relax::relax(&mut workers[0], p, columns, opts.relax_weights)?;
    let rate = rate::choose(workers, p, &columns, opts, progress)?;
    Ok((columns, relaxed, rate))
}

/// Estimates the training record's process noise from the unextended model's residual and the segment
/// initial-state responses `columns`, sets the filter (when turbulence is found) and the nuisance basis (the
/// columns through the same filter).
fn turbulence(
    worker: &mut search::Worker,
    p: &mut prepare::Prepared,
    columns: Vec<Vec<f64>>,
) -> Result<Option<process_noise::ProcessNoise>, DiagnoseError> {
    if columns.is_empty() {
        return Ok(None);
    }
    let r0 = search::raw_residuals(worker, &p.case, &p.sigma, &[]).map_err(sim_err("replay"))?;
    let estimate = process_noise::estimate(&p.case, &columns, &r0);
    let (filter, report) = match estimate {
        // Process noise on the body rates alone is the unextended model's own error, not gusts (see
        // `refit::GUST_VARIANCE_MIN`): the search stays output error's.
        Some((_, report)) if report.velocity_variance < refit::GUST_VARIANCE_MIN => (
            None,
            Some(process_noise::ProcessNoise {
                used: false,
                ..report
            }),
        ),
        Some((f, report)) => (f, Some(report)),
        None => (None, None),
    };
    let mut columns = columns;
    if let Some(f) = &filter {
        f.apply_all(&mut columns);
        p.warnings.push(format!(
            "the record carries process noise (turbulence): the search fitted the filter error method's \
             innovations (likelihood gain {:.0} against a penalty of {:.0})",
            report.as_ref().map_or(0.0, |r| r.likelihood_gain),
            report.as_ref().map_or(0.0, |r| r.penalty),
        ));
    }
    p.nuisance = search::orthonormal_basis(&columns);
    p.filter = filter;
    Ok(report)
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
