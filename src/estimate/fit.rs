//! Maximum-likelihood output error: bounded Levenberg–Marquardt with the measurement-noise
//! covariance estimated from the residuals between steps.
//!
//! Cost (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., eq. 4.13; Morelli & Klein,
//! *Aircraft System Identification*, 2nd ed., eq. 6.9), over all records jointly:
//!
//! `J(φ, R) = ½ Σ_k v_kᵀ R⁻¹ v_k + ½ N ln det R`,  `v_k = z_k − ŷ_k(φ)`.
//!
//! For fixed φ the minimising R is the residual covariance (Jategaonkar eq. 4.15), taken
//! diagonal here (one variance per output, pooled over records — cross-correlated sensor noise
//! is rare and a full R lets one output's unmodelled dynamics steer the others). For fixed R the
//! cost is a weighted least-squares problem solved by Gauss–Newton with Marquardt's damping
//! `(M + μ diag M) δ = g`, `M = Σ Sᵀ R⁻¹ S`, `g = Σ Sᵀ R⁻¹ v` (eq. 4.29–4.33; Marquardt 1963).
//! The two alternate (the relaxation algorithm, §4.9): every accepted step is followed by a new
//! R. Bounds are kept by projection, with the parameters at a bound whose gradient points out of
//! the box left out of the step (an active set).
//!
//! Sensitivities `S = ∂ŷ/∂φ` come from the model when it has them, otherwise from forward
//! differences during the iterations and central differences for the final covariance, the
//! perturbed simulations run in parallel (rayon). A simulation that fails or diverges rejects the
//! step (the damping grows); at the start values it is an error.
//!
//! Standard errors: Cramér–Rao bounds `M⁻¹` corrected for coloured residuals (Morelli & Klein
//! 1994, see [`super::covariance`]); both are returned.

use std::sync::RwLock;
use std::time::Instant;

use faer::{Mat, Side};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::covariance::{cross_lag_weighted_products, sandwich};
use super::fem;
use super::layout::{Layout, Nuisance, NuisanceKind, RecordTerms};
use super::model::{Model, Parameter, SimError, StateModel};
use super::record::{InputHold, InputSignal, Record, Run};
use super::EstimateError;
use crate::ident::nrmse_fit as fit_percent;
use crate::optimise;
use crate::signal::{std_dev, sum_sq};

mod result;
mod sensitivity;

/// Which estimator [`fit`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Output error: the model simulated open loop from its initial state.
    #[default]
    Oe,
    /// Filter error: a Kalman filter in the loop, process noise estimated.
    Fem,
}

impl Method {
    /// Lower-case name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Oe => "oe",
            Method::Fem => "fem",
        }
    }
}

/// Options of [`fit`].
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Output error or filter error.
    pub method: Method,
    /// Reconstruction of the inputs between samples.
    pub hold: InputHold,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when a step lowers the weighted residual sum by less than this fraction and the
    /// noise variances move by less than 0.1 %.
    pub tolerance: f64,
    /// Largest integration step, s; `None`: half the record's median sample interval.
    pub max_step_s: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            method: Method::Oe,
            hold: InputHold::Linear,
            max_iterations: 50,
            tolerance: 1e-7,
            max_step_s: None,
        }
    }
}

/// Why the iterations ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The cost and the noise covariance stopped changing.
    Converged,
    /// The iteration limit was reached first.
    MaxIterations,
    /// No damped step lowered the cost while the gradient was still significant.
    NoDescent,
}

/// One estimated quantity (a model parameter or a nuisance term).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParameterEstimate {
    /// Parameter name, or the nuisance term's target (state, output or input).
    pub name: String,
    /// Nuisance kind (None for a model parameter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<NuisanceKind>,
    /// Record the nuisance term belongs to (None for model parameters and skews).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record: Option<String>,
    /// Estimate (the start value when fixed).
    pub value: f64,
    /// Cramér–Rao bound corrected for coloured residuals (0 when fixed).
    pub std_error: f64,
    /// Cramér–Rao bound assuming white residuals (0 when fixed).
    pub std_error_white: f64,
    /// |value| / std_error (0 when fixed or σ = 0).
    pub t: f64,
    /// Held at its start value.
    pub fixed: bool,
    /// Ended on one of its bounds.
    pub at_bound: bool,
}

impl ParameterEstimate {
    /// σ in percent of |value| (0 for a zero value).
    pub fn std_error_percent(&self) -> f64 {
        if self.value == 0.0 {
            0.0
        } else {
            100.0 * self.std_error / self.value.abs()
        }
    }
}

/// Measured and predicted outputs of one record at the estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordFit {
    /// Record name.
    pub name: String,
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Measured outputs `[output][k]`.
    pub measured: Vec<Vec<f64>>,
    /// Model outputs (biases included) `[output][k]`.
    pub predicted: Vec<Vec<f64>>,
    /// Fit percent per output, 100 (1 − ‖z − ŷ‖ / ‖z − z̄‖).
    pub fit_percent: Vec<f64>,
}

/// The result of [`fit`].
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Method that produced it.
    pub method: Method,
    /// Output names (order of `residual_covariance` and the records' outputs).
    pub outputs: Vec<String>,
    /// Model parameters in signature order (fixed ones included).
    pub parameters: Vec<ParameterEstimate>,
    /// Nuisance terms, per record then skews.
    pub nuisance: Vec<ParameterEstimate>,
    /// Names of the free quantities, in the order of `covariance` and `correlation`: free model
    /// parameters, then nuisance terms as `kind:target@record`.
    pub free: Vec<String>,
    /// Covariance of the free quantities (coloured-residual corrected).
    pub covariance: Vec<Vec<f64>>,
    /// Correlation matrix of the free quantities.
    pub correlation: Vec<Vec<f64>>,
    /// Estimated measurement-noise (OE) or innovation (FEM) covariance R.
    pub residual_covariance: Vec<Vec<f64>>,
    /// Fit per record.
    pub records: Vec<RecordFit>,
    /// Iterations taken.
    pub iterations: usize,
    /// True when the iterations converged.
    pub converged: bool,
    /// Why they stopped.
    pub stop: StopReason,
    /// Final cost `J = ½ Σ vᵀR⁻¹v + ½ N ln det R`.
    pub cost: f64,
    /// Cost after each iteration (the start first).
    pub cost_history: Vec<f64>,
    /// Wall time of the fit, s.
    pub wall_s: f64,
    /// Name of the covariance correction used.
    pub covariance_method: &'static str,
    /// Things the user should know (unidentifiable directions, parameters at bounds).
    pub warnings: Vec<String>,
    /// Held parameters whose uncertainty the covariance carries ([`Parameter::considered`]): name and σ.
    pub considered: Vec<(String, f64)>,
}

impl Estimate {
    /// Whether the fit is an estimate: [`EstimateError::Diverged`] for a cost that is not finite,
    /// [`EstimateError::NotConverged`] for iterations that stopped before converging, else `Ok`.
    pub fn outcome(&self) -> Result<(), EstimateError> {
        if !self.cost.is_finite() {
            return Err(EstimateError::Diverged {
                cost: self.cost,
                iterations: self.iterations,
            });
        }
        if !self.converged {
            return Err(EstimateError::NotConverged {
                stop: self.stop,
                iterations: self.iterations,
                cost: self.cost,
            });
        }
        Ok(())
    }

    /// Fit percent of output `o` over all records together.
    pub fn fit_percent(&self, o: usize) -> f64 {
        let z: Vec<f64> = self
            .records
            .iter()
            .flat_map(|r| r.measured[o].clone())
            .collect();
        let y: Vec<f64> = self
            .records
            .iter()
            .flat_map(|r| r.predicted[o].clone())
            .collect();
        fit_percent(&z, &y)
    }

    /// The model parameter called `name`.
    pub fn parameter(&self, name: &str) -> Option<&ParameterEstimate> {
        self.parameters.iter().find(|p| p.name == name)
    }
}

/// Name of the covariance correction used (in results and reports).
pub const COVARIANCE_METHOD: &str =
    "Cramér-Rao bound with the coloured-residual correction of Morelli & Klein (1994) over the outputs' \
     cross-correlations, Bartlett lag window";

/// Fits `model` to `records` (jointly: one parameter vector, nuisance terms per record).
///
/// `parameters` lists every model parameter in signature order with its start value, bounds and
/// whether it is fixed.
pub fn fit(
    model: &dyn Model,
    parameters: &[Parameter],
    records: &[Record],
    nuisance: &Nuisance,
    options: &Options,
) -> Result<Estimate, EstimateError> {
    let started = Instant::now();
    let mut layout = Layout::new(model.signature(), parameters, records, nuisance)?;
    let max_step_s: Vec<f64> = records
        .iter()
        .map(|r| options.max_step_s.unwrap_or(0.5 * r.median_dt_s()))
        .collect();
    let problem = |layout: Layout, method: Method| Problem {
        model,
        layout,
        records,
        hold: options.hold,
        max_step_s: max_step_s.clone(),
        method,
        gain_noise: RwLock::new(Vec::new()),
    };
    if options.method == Method::Fem {
        let Some(sm) = model.state_model() else {
            return Err(EstimateError::Invalid(
                "the filter error method needs a model with a state-space form (ẋ = f, y = h)"
                    .into(),
            ));
        };
        // start from the output-error estimate (the filter error method's usual start,
        // Jategaonkar §5.7): at q = 0 the two coincide, and the process noise is then only what
        // the output-error residuals cannot explain
        let oe = problem(layout.clone(), Method::Oe).minimise(options)?;
        layout.start = oe.phi;
        let theta = layout.theta(&layout.start);
        let scale = process_noise_scale(sm, &theta, &records[0], options.hold);
        layout.add_process_noise(
            &model.signature().states,
            nuisance.process_noise.as_deref(),
            &scale,
        );
    }
    let problem = problem(layout, options.method);
    let solution = problem.minimise(options)?;
    Ok(problem.summarise(solution, options.method, started))
}

/// Typical process-noise variance of each state: the `q` at which a random walk's increment over
/// one sample, `q Δt`, matches (1 % of the spread of) the outputs that observe the state
/// (finite-difference steps are relative to it). 1e-6 for an unobserved state.
fn process_noise_scale(
    sm: &dyn StateModel,
    theta: &[f64],
    rec: &Record,
    hold: InputHold,
) -> Vec<f64> {
    let input = InputSignal::measured(&rec.time_s, &rec.inputs, hold);
    let mut u = vec![0.0; rec.inputs.len()];
    input.at(rec.time_s[0], &mut u);
    let (_, c) = fem::linearise(sm, theta, &rec.initial_state, &u);
    let dt = rec.median_dt_s().max(f64::MIN_POSITIVE);
    (0..c.ncols())
        .map(|i| {
            (0..c.nrows())
                .filter(|&o| c[(o, i)].abs() > 1e-12)
                .map(|o| (1e-2 * std_dev(&rec.outputs[o]) / c[(o, i)].abs()).powi(2) / dt)
                .filter(|v| v.is_finite() && *v > 0.0)
                .fold(f64::INFINITY, f64::min)
        })
        .map(|v| if v.is_finite() { v } else { 1e-6 })
        .collect()
}

/// Outputs of every record, `[record][output][k]`.
type Predictions = Vec<Vec<Vec<f64>>>;

/// The fitted problem: model, records and the φ layout.
struct Problem<'a> {
    model: &'a dyn Model,
    layout: Layout,
    records: &'a [Record],
    hold: InputHold,
    max_step_s: Vec<f64>,
    method: Method,
    /// Filter error: the innovation variances the gain is computed with (held fixed during a
    /// parameter update, replaced by the relaxation step).
    gain_noise: RwLock<Vec<f64>>,
}

/// Where the iterations ended.
struct Solution {
    phi: Vec<f64>,
    predictions: Predictions,
    noise: Vec<f64>,
    iterations: usize,
    stop: StopReason,
    cost_history: Vec<f64>,
}

impl Problem<'_> {
    fn n_outputs(&self) -> usize {
        self.model.signature().outputs.len()
    }

    /// Record `r` as the model simulates it with the nuisance terms `terms`.
    fn run(&self, r: usize, terms: &RecordTerms) -> Run<'_> {
        let rec = &self.records[r];
        Run {
            record: r,
            time_s: &rec.time_s,
            input: InputSignal::new(
                &rec.time_s,
                &rec.inputs,
                terms.input_bias.clone(),
                terms.input_skew_s.clone(),
                self.hold,
            ),
            max_step_s: self.max_step_s[r],
        }
    }

    /// Model outputs (output biases added) of record `r` for φ.
    fn predict(&self, phi: &[f64], r: usize) -> Result<Vec<Vec<f64>>, SimError> {
        self.predict_at(phi, &self.layout.theta(phi), r)
    }

    /// [`Problem::predict`] with the model parameters `theta` given (a held one perturbed).
    fn predict_at(&self, phi: &[f64], theta: &[f64], r: usize) -> Result<Vec<Vec<f64>>, SimError> {
        let terms = self.layout.record_terms(phi, r);
        let rec = &self.records[r];
        let run = self.run(r, &terms);
        if self.method == Method::Fem {
            return self.filter(phi, theta, &terms, &run);
        }
        let mut y = self.model.simulate(theta, &terms.x0, &run)?;
        let outputs = &self.model.signature().outputs;
        if y.len() != outputs.len() || y.iter().any(|c| c.len() != rec.len()) {
            return Err(SimError::Failed(format!(
                "the model returned {} outputs of {} samples, expected {} of {}",
                y.len(),
                y.first().map_or(0, Vec::len),
                outputs.len(),
                rec.len()
            )));
        }
        for (o, col) in y.iter_mut().enumerate() {
            if let Some(k) = col.iter().position(|v| !v.is_finite()) {
                return Err(SimError::Diverged {
                    time_s: rec.time_s[k] - rec.time_s[0],
                    what: format!("output {}", outputs[o]),
                });
            }
            let b = terms.output_bias[o];
            if b != 0.0 {
                col.iter_mut().for_each(|v| *v += b);
            }
        }
        Ok(y)
    }

    /// Filter error: the one-step-ahead predictions of record `run.record` (see [`fem`]).
    fn filter(
        &self,
        phi: &[f64],
        theta: &[f64],
        terms: &RecordTerms,
        run: &Run<'_>,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let sm = self
            .model
            .state_model()
            .ok_or_else(|| SimError::Failed("no state-space form".into()))?;
        let rec = &self.records[run.record];
        let gain = self.gain(phi, run.record)?;
        fem::filter(
            sm,
            theta,
            &terms.x0,
            run,
            &terms.output_bias,
            &rec.outputs,
            &gain,
        )
    }

    /// Filter error: whether the gains at φ keep `diag(K C) ≤ 1` on every record (see [`fem`]);
    /// always true for output error.
    fn constraint_holds(&self, phi: &[f64]) -> bool {
        if self.method != Method::Fem {
            return true;
        }
        (0..self.records.len()).all(|r| self.gain(phi, r).is_ok_and(|g| g.kc_max <= 1.0))
    }

    /// Filter error: scales every process-noise entry of φ by the largest common factor s ∈ [0, 1] (to
    /// 1e-4, by bisection) under which diag(KC) ≤ 1 holds (with no process noise K = 0 and it always
    /// does). Halving instead threw away up to half of an estimate that sat on the constraint, so the
    /// relaxation cycled: the cost rose at every halving and the iterations climbed back.
    fn scale_into_constraint(&self, phi: &mut [f64]) {
        if self.constraint_holds(phi) {
            return;
        }
        let entries = self.layout.process_noise_entries();
        let scaled = |s: f64| {
            let mut t = phi.to_vec();
            entries.iter().for_each(|&j| t[j] *= s);
            t
        };
        let (mut holds, mut breaks) = (0.0, 1.0);
        while breaks - holds > 1e-4 {
            let mid = 0.5 * (holds + breaks);
            if self.constraint_holds(&scaled(mid)) {
                holds = mid;
            } else {
                breaks = mid;
            }
        }
        phi.copy_from_slice(&scaled(holds));
    }

    /// Filter error: the steady-state gain of record `r` at φ.
    fn gain(&self, phi: &[f64], r: usize) -> Result<fem::Gain, SimError> {
        let sm = self
            .model
            .state_model()
            .ok_or_else(|| SimError::Failed("no state-space form".into()))?;
        let theta = self.layout.theta(phi);
        let terms = self.layout.record_terms(phi, r);
        let run = self.run(r, &terms);
        let rec = &self.records[r];
        let mut u = vec![0.0; rec.inputs.len()];
        run.input.at(rec.time_s[0], &mut u);
        let (a, c) = fem::linearise(sm, &theta, &terms.x0, &u);
        let q = self.layout.process_noise(phi, a.nrows());
        let noise = self
            .gain_noise
            .read()
            .map_err(|_| SimError::Failed("the filter's noise estimate is unavailable".into()))?
            .clone();
        fem::gain(&a, &c, &q, &noise, rec.median_dt_s())
    }

    /// Filter error: F–R compensation of φ's process-noise variances for R moving from `old` to
    /// `new` (see [`fem`]), with the output matrix linearised on the first record.
    fn compensate(&self, phi: &mut [f64], old: &[f64], new: &[f64]) {
        let Some(sm) = self.model.state_model() else {
            return;
        };
        let theta = self.layout.theta(phi);
        let terms = self.layout.record_terms(phi, 0);
        let rec = &self.records[0];
        let run = self.run(0, &terms);
        let mut u = vec![0.0; rec.inputs.len()];
        run.input.at(rec.time_s[0], &mut u);
        let (_, c) = fem::linearise(sm, &theta, &terms.x0, &u);
        let entries = self.layout.process_noise_entries();
        let mut q: Vec<f64> = entries.iter().map(|&j| phi[j]).collect();
        fem::compensate(&mut q, &c, old, new);
        for (&j, v) in entries.iter().zip(q) {
            phi[j] = v;
        }
    }

    /// Outputs of every record (in parallel when the model allows it).
    fn predict_all(&self, phi: &[f64]) -> Result<Predictions, (usize, SimError)> {
        let one = |r: usize| self.predict(phi, r).map_err(|e| (r, e));
        if self.model.parallel() && self.records.len() > 1 {
            (0..self.records.len()).into_par_iter().map(one).collect()
        } else {
            (0..self.records.len()).map(one).collect()
        }
    }

    /// Residuals `z − ŷ`, `[record][output][k]`.
    fn residuals(&self, pred: &Predictions) -> Predictions {
        self.records
            .iter()
            .zip(pred)
            .map(|(rec, p)| {
                rec.outputs
                    .iter()
                    .zip(p)
                    .map(|(z, y)| z.iter().zip(y).map(|(a, b)| a - b).collect())
                    .collect()
            })
            .collect()
    }

    /// The maximum-likelihood R for fixed φ: per-output residual variance pooled over records
    /// (Jategaonkar eq. 4.15, diagonal), floored at 1e-16 of the output's own mean square so a
    /// noise-free record does not divide by zero.
    fn noise(&self, res: &Predictions) -> Vec<f64> {
        (0..self.n_outputs())
            .map(|o| {
                let (mut s, mut z2, mut n) = (0.0, 0.0, 0usize);
                for (rec, rr) in self.records.iter().zip(res) {
                    s += sum_sq(&rr[o]);
                    z2 += sum_sq(&rec.outputs[o]);
                    n += rr[o].len();
                }
                let n = n.max(1) as f64;
                (s / n).max(1e-16 * z2 / n).max(1e-300)
            })
            .collect()
    }

    /// `Σ vᵀ R⁻¹ v` for diagonal R.
    fn weighted_sse(res: &Predictions, noise: &[f64]) -> f64 {
        res.iter()
            .map(|rr| {
                rr.iter()
                    .zip(noise)
                    .map(|(v, r)| sum_sq(v) / r)
                    .sum::<f64>()
            })
            .sum()
    }

    /// The likelihood cost `J = ½ Σ vᵀR⁻¹v + ½ N ln det R`.
    fn cost(&self, res: &Predictions, noise: &[f64]) -> f64 {
        let n: usize = self.records.iter().map(Record::len).sum();
        0.5 * Self::weighted_sse(res, noise)
            + 0.5 * n as f64 * noise.iter().map(|r| r.ln()).sum::<f64>()
    }

    /// Row of sample k of output o of record r in the stacked residual vector.
    fn offsets(&self) -> Vec<usize> {
        let ny = self.n_outputs();
        let mut off = vec![0];
        for rec in self.records {
            off.push(off.last().unwrap() + ny * rec.len());
        }
        off
    }

    /// Bounded Levenberg–Marquardt with R relaxation (module doc).
    fn minimise(&self, options: &Options) -> Result<Solution, EstimateError> {
        let mut phi = self.layout.start.clone();
        self.layout.clamp(&mut phi);
        let start_diverges = |(r, source): (usize, SimError)| EstimateError::StartDiverges {
            record: self.records[r].name.clone(),
            source,
        };
        let mut pred = self.predict_all(&phi).map_err(start_diverges)?;
        let mut res = self.residuals(&pred);
        let noise = self.noise(&res);
        self.set_gain_noise(&noise);
        if self.method == Method::Fem {
            // q = 0 at the start: the filter is the simulation, the first R is the output-error R
            pred = self.predict_all(&phi).map_err(start_diverges)?;
            res = self.residuals(&pred);
        }
        let mut relaxed = Relaxed {
            history: vec![self.cost(&res, &noise)],
            problem: self,
            noise,
        };
        let lm = optimise::Options {
            max_iterations: options.max_iterations,
            tolerance: options.tolerance,
            ..optimise::Options::default()
        };
        let Ok(min) =
            optimise::levenberg_marquardt(&mut relaxed, phi, Evaluated { pred, res }, &lm);
        Ok(Solution {
            phi: min.x,
            predictions: min.point.pred,
            noise: relaxed.noise,
            iterations: min.iterations,
            stop: match min.stop {
                optimise::Stop::Converged => StopReason::Converged,
                optimise::Stop::MaxIterations => StopReason::MaxIterations,
                optimise::Stop::NoDescent => StopReason::NoDescent,
            },
            cost_history: relaxed.history,
        })
    }

    /// The innovation variances the filter's gain uses from now on.
    fn set_gain_noise(&self, noise: &[f64]) {
        if let Ok(mut g) = self.gain_noise.write() {
            *g = noise.to_vec();
        }
    }
}

/// Predictions and residuals at one φ.
struct Evaluated {
    pred: Predictions,
    res: Predictions,
}

/// The fitted problem for [`optimise::levenberg_marquardt`], with the R of the relaxation
/// algorithm held between steps and the likelihood cost after each.
struct Relaxed<'p, 'a> {
    problem: &'p Problem<'a>,
    noise: Vec<f64>,
    history: Vec<f64>,
}

impl optimise::Problem for Relaxed<'_, '_> {
    type Point = Evaluated;
    type Error = std::convert::Infallible;

    fn evaluate(&mut self, phi: &[f64]) -> Result<Option<Evaluated>, Self::Error> {
        Ok(self.problem.predict_all(phi).ok().map(|pred| Evaluated {
            res: self.problem.residuals(&pred),
            pred,
        }))
    }

    fn cost(&self, at: &Evaluated) -> f64 {
        Problem::weighted_sse(&at.res, &self.noise)
    }

    fn linearise(
        &mut self,
        phi: &[f64],
        at: &Evaluated,
    ) -> Result<Option<optimise::Linearised>, Self::Error> {
        Ok(self
            .problem
            .jacobian(phi, &at.pred, false)
            .ok()
            .map(|cols| {
                let (sensitivities, residuals) = self.problem.weighted(&cols, &at.res, &self.noise);
                optimise::Linearised {
                    sensitivities,
                    residuals,
                }
            }))
    }

    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.problem.layout.lower, &self.problem.layout.upper)
    }

    /// Filter error: a step whose gain breaks diag(KC) ≤ 1 is shortened towards φ (the
    /// constraint is a boundary in q; halving keeps the direction). When no shortened step holds
    /// it (φ sits on the boundary and the step leans over it), the whole step is taken with its
    /// process noise scaled back into the constraint: the model parameters then still move. Without
    /// that, a start on the boundary ended the fit at its first iteration, though the step predicted
    /// a decrease (the p51d's lateral records in three gust realisations of five).
    fn admit(&mut self, phi: &[f64], trial: &mut [f64]) -> bool {
        let full = trial.to_vec();
        for _ in 0..8 {
            if self.problem.constraint_holds(trial) {
                return true;
            }
            for (t, p) in trial.iter_mut().zip(phi) {
                *t = p + 0.5 * (*t - p);
            }
        }
        trial.copy_from_slice(&full);
        self.problem.scale_into_constraint(trial);
        self.problem.constraint_holds(trial)
    }

    /// The new R (Jategaonkar eq. 4.15); filter error: the process noise compensated for it.
    fn relax(
        &mut self,
        phi: &mut Vec<f64>,
        at: &mut Evaluated,
    ) -> Result<optimise::Relaxation, Self::Error> {
        let problem = self.problem;
        let new_noise = problem.noise(&at.res);
        let noise_change = new_noise
            .iter()
            .zip(&self.noise)
            .map(|(a, b)| (a / b - 1.0).abs())
            .fold(0.0, f64::max);
        if problem.method == Method::Fem {
            let mut compensated = phi.clone();
            problem.compensate(&mut compensated, &self.noise, &new_noise);
            problem.set_gain_noise(&new_noise);
            // with the new R the gain may break diag(KC) ≤ 1: scale the process noise back by the
            // least common factor that restores it
            problem.scale_into_constraint(&mut compensated);
            match problem.predict_all(&compensated) {
                Ok(p) => {
                    *phi = compensated;
                    at.pred = p;
                }
                // the compensated gain breaks the constraint: keep F, re-filter with new R
                Err(_) => match problem.predict_all(phi) {
                    Ok(p) => at.pred = p,
                    Err(_) => {
                        problem.set_gain_noise(&self.noise);
                        return Ok(optimise::Relaxation::Stop);
                    }
                },
            }
            at.res = problem.residuals(&at.pred);
        }
        self.noise = new_noise;
        self.history.push(problem.cost(&at.res, &self.noise));
        Ok(if noise_change < 1e-3 {
            optimise::Relaxation::Steady
        } else {
            optimise::Relaxation::Moving
        })
    }
}
