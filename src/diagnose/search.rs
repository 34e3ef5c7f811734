//! Fitting extensions by output error with the simulation in the loop, and choosing among them.
//!
//! Output error: minimise J(θ) = Σ_c Σ_k (y_c[k] − ŷ_c[k](θ))² / σ_c², with σ_c the measurement-noise
//! standard deviation of channel c, by Levenberg–Marquardt with finite-difference output sensitivities;
//! standard errors from the Cramér–Rao bound s² (SᵀS)⁻¹ (Morelli & Klein, Aircraft System Identification,
//! 2nd ed., §6.2–6.3, eqs. 6.19–6.27). Modelling error leaves coloured residuals, for which the Cramér–Rao
//! bound is far too optimistic; the reported standard errors are therefore the estimation core's
//! coloured-residual bound (SᵀS)⁻¹ [Σ_c Σ_d Σ_i Σ_j s_c,i R_cd(i−j) s_d,jᵀ] (SᵀS)⁻¹ (Morelli & Klein §6.6,
//! eq. 6.86) with the channels' cross-correlations and the estimation core's lag window
//! (`covariance::cross_lag_weighted_products`).
//! Selection: BIC = n ln(J/n) + k ln n (Schwarz 1978) with the effective number of independent residuals n_eff,
//! forward selection.
//!
//! Speed: the search's sensitivities and fits integrate at a coarse rate (50 Hz for a 50 Hz record, a third of
//! the JSBSim cost of the 200 Hz replay) on residuals corrected to the replay's rate at the current model
//! ([`coarse`], output space mapping); every model the search accepts is refitted at the replay's rate
//! ([`polish`]).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::cache::{fingerprint, ReplayCache, ReplayKey};
use super::extension::{Extension, Stage};
pub use super::projection::{orthonormal_basis, project_off};
use super::replay::{replay, ReplayCase};
use super::residual::{coloured_products, effective_n};
use super::residual_filter::ResidualFilter;
use super::simulator::ReplaySim;
use crate::data::FlightRecord;
use crate::estimate::covariance;
use crate::ident::linalg;
use crate::optimise;
use crate::signal::sum_sq;
use crate::sim::{SimError, TrimState};
use faer::Mat;

/// A simulation worker: one simulator and the store of replays it shares with the other workers.
pub struct Worker {
    /// The simulator (one JSBSim process, or a linear model).
    pub sim: Box<dyn ReplaySim>,
    cache: ReplayCache,
    /// Time spent in this worker's simulations, s.
    pub sim_s: f64,
    /// Simulations this worker ran (replays found in the store not counted).
    pub simulations: usize,
    /// Simulations run by all the workers that share this one's store (see [`share_replays`]).
    shared_simulations: Arc<AtomicUsize>,
}

impl Worker {
    /// Wraps a simulator (with a store of its own until [`share_replays`]).
    pub fn new(sim: Box<dyn ReplaySim>) -> Self {
        Worker {
            sim,
            cache: ReplayCache::new(),
            sim_s: 0.0,
            simulations: 0,
            shared_simulations: Arc::new(AtomicUsize::new(0)),
        }
    }

    /// The count of simulations run by all the workers that share this one's store.
    pub fn shared_simulations(&self) -> Arc<AtomicUsize> {
        Arc::clone(&self.shared_simulations)
    }

    /// Counts a simulation that took `seconds`.
    pub(super) fn ran(&mut self, seconds: f64) {
        self.sim_s += seconds;
        self.simulations += 1;
        self.shared_simulations.fetch_add(1, Ordering::Relaxed);
    }
}

/// Gives the workers one new, empty store of replays (one per diagnosis: the workers must simulate the same
/// model at the same rate) and one new count of the simulations they run.
pub fn share_replays(workers: &mut [Worker]) {
    let cache = ReplayCache::new();
    let count = Arc::new(AtomicUsize::new(0));
    for w in workers {
        w.cache = cache.clone();
        w.shared_simulations = Arc::clone(&count);
    }
}

/// Lowest rate the output sensitivities of the nuisance terms are simulated at, Hz (see [`at_sensitivity_rate`]).
pub const SENSITIVITY_RATE_HZ: f64 = 50.0;

/// Runs `f` with the workers integrating at the smallest whole multiple of the record's rate that is at least
/// [`SENSITIVITY_RATE_HZ`], when that is below their own rate, and puts their rate back afterwards. For
/// differences of two simulations at the same rate (the output sensitivities of the nuisance terms, the
/// initial state of each segment): JSBSim's integration lag of about one step (20 ms at 50 Hz) shifts such a
/// sensitivity a little, whereas it would bias a fitted delay by the whole step. Fits at this rate therefore
/// run on residuals corrected to the replay's rate ([`coarse`]) and are refitted there ([`polish`]).
pub fn at_sensitivity_rate<R>(
    workers: &mut [Worker],
    case: &ReplayCase,
    f: impl FnOnce(&mut [Worker]) -> Result<R, SimError>,
) -> Result<R, SimError> {
    let coarse = case.rate_hz * (SENSITIVITY_RATE_HZ / case.rate_hz - 1e-9).ceil().max(1.0);
    let own: Vec<Option<f64>> = workers.iter().map(|w| w.sim.rate_hz()).collect();
    let lower = |r: &Option<f64>| r.is_some_and(|r| coarse < r * (1.0 - 1e-9));
    for (w, r) in workers.iter_mut().zip(&own) {
        if lower(r) {
            w.sim.set_rate_hz(coarse)?;
        }
    }
    let out = f(workers);
    for (w, r) in workers.iter_mut().zip(&own) {
        if let (true, Some(r)) = (lower(r), r) {
            w.sim.set_rate_hz(*r)?;
        }
    }
    out
}

/// Replays `case` with `extensions` (each with its parameter values) on the worker, or takes the replay from the
/// workers' store when one with the same record and the same extensions before the outputs was simulated;
/// sensor (output-stage) extensions are applied to the returned copy.
pub fn simulate(
    worker: &mut Worker,
    case: &ReplayCase,
    extensions: &[(&dyn Extension, &[f64])],
) -> Result<(FlightRecord, TrimState), SimError> {
    let key: ReplayKey = (
        fingerprint(case, worker.sim.rate_hz()),
        extensions
            .iter()
            .filter(|(e, p)| e.stage() != Stage::Output && !is_null(*e, p))
            .map(|(e, p)| (e.key(), p.iter().map(|v| v.to_bits()).collect()))
            .collect(),
    );
    let stored = match worker.cache.get(&key) {
        Some(r) => r,
        None => {
            let before_outputs: Vec<(&dyn Extension, &[f64])> = extensions
                .iter()
                .filter(|(e, _)| e.stage() != Stage::Output)
                .copied()
                .collect();
            let t0 = std::time::Instant::now();
            let out = replay(worker.sim.as_mut(), case, &before_outputs);
            worker.ran(t0.elapsed().as_secs_f64());
            let r = Arc::new(out?);
            worker.cache.insert(key, Arc::clone(&r));
            r
        }
    };
    let (mut rec, trim) = (stored.0.clone(), stored.1.clone());
    for (e, p) in extensions
        .iter()
        .filter(|(e, _)| e.stage() == Stage::Output)
    {
        e.apply_output(p, &mut rec);
    }
    Ok((rec, trim))
}

/// An extension with its current parameter values; `free` ones are fitted.
#[derive(Clone)]
pub struct Active<'e> {
    /// The extension.
    pub ext: &'e dyn Extension,
    /// Parameter values.
    pub params: Vec<f64>,
    /// Whether the parameters are fitted.
    pub free: bool,
}

/// Channel weights (1/σ_c) of a case and the nuisance terms every residual is taken after.
pub struct Weighted<'c> {
    /// The case.
    pub case: &'c ReplayCase,
    /// Noise standard deviation per output column (same order as `case.outputs`).
    pub sigma: Vec<f64>,
    /// Orthonormal basis of the residual directions the nuisance terms explain (see
    /// [`super::initial_state::initial_state_columns`]); the residual is projected off it, which estimates the
    /// nuisance terms jointly with every fit.
    pub nuisance: &'c [Vec<f64>],
    /// The filter error method's innovations in place of the output error (turbulence; see
    /// `process_noise`): applied before the nuisance terms are projected off.
    pub filter: Option<&'c ResidualFilter>,
    /// Added to the noise-normalised residual before the filter: the difference between the replay's rate and
    /// the coarse rate the workers integrate at inside [`coarse`], at its reference model.
    pub correction: Option<&'c [f64]>,
    /// The cost of a residual at the measurement noise in these weights: the number of residuals, less where a
    /// channel's weight was relaxed below its noise's (`relax`).
    pub noise_cost: f64,
}

impl<'c> Weighted<'c> {
    /// Number of residual values.
    pub fn n(&self) -> usize {
        self.case.len() * self.case.outputs.len()
    }
}

fn is_null(e: &dyn Extension, p: &[f64]) -> bool {
    e.params().iter().zip(p).all(|(s, v)| *v == s.null)
}

/// Simulates with the active extensions ([`simulate`]: a replay already in the workers' store is not run
/// again) and returns the noise-normalised residual vector, channel-major.
pub fn residuals(
    worker: &mut Worker,
    w: &Weighted,
    active: &[Active],
) -> Result<Vec<f64>, SimError> {
    let mut r = raw_residuals(worker, w.case, &w.sigma, active)?;
    if let Some(d) = w.correction {
        r.iter_mut().zip(d).for_each(|(v, d)| *v += d);
    }
    if let Some(f) = w.filter {
        f.apply(&mut r);
    }
    project_off(&mut r, w.nuisance);
    Ok(r)
}

/// The noise-normalised residual (y − ŷ)/σ of `case` with the noise weights `sigma`, channel-major, with no
/// correction, filter or nuisance terms: what the process-noise estimate works on.
pub fn raw_residuals(
    worker: &mut Worker,
    case: &ReplayCase,
    sigma: &[f64],
    active: &[Active],
) -> Result<Vec<f64>, SimError> {
    let exts: Vec<(&dyn Extension, &[f64])> = active
        .iter()
        .map(|a| (a.ext, a.params.as_slice()))
        .collect();
    let (rec, _) = simulate(worker, case, &exts)?;
    let mut r = Vec::with_capacity(case.len() * case.outputs.len());
    for (c, name) in case.outputs.iter().enumerate() {
        let y = case.measured(name);
        let yhat = rec.column(name).ok_or_else(|| {
            SimError::Protocol(format!("the simulation does not produce column {name}"))
        })?;
        let heading = name == super::replay::HEADING;
        for k in 0..y.len() {
            let d = y[k] - yhat[k];
            // a heading error is an angle: a turn apart is no error
            let d = if heading {
                d - std::f64::consts::TAU * (d / std::f64::consts::TAU).round()
            } else {
                d
            };
            let e = d / sigma[c];
            r.push(if e.is_finite() { e } else { 1e6 });
        }
    }
    Ok(r)
}

/// Runs `f` with the workers integrating at the coarse rate of [`at_sensitivity_rate`] and `w`'s residuals
/// corrected to the replay's rate at the `reference` model: r̃(θ) = r_c(θ) + [r(θ_ref) − r_c(θ_ref)], the
/// output correction of space mapping (Bandler et al., "Space mapping: the state of the art", IEEE Trans.
/// Microwave Theory Tech. 52, 2004, §V; Koziel, Bandler & Madsen 2006). r̃ equals the replay's residual r at
/// the reference and moves with the coarse integration's output sensitivities: its error is the change of
/// JSBSim's integration error (a lag of about one step) with θ, second order in the step and in θ − θ_ref,
/// whereas the integration error itself, about one coarse step of lag, would bias a fitted delay by the whole
/// step and name passengers (a Cl_r ×1.5 beside an actuator lag in place of a delay, replayed at 50 Hz). Two
/// replays of the reference (one at each rate); for a 50 Hz record a coarse replay costs a third of one at the
/// 200 Hz default. The caller refits at the replay's rate what it reports ([`polish`]).
pub fn coarse<R>(
    workers: &mut [Worker],
    w: &Weighted,
    reference: &[Active],
    f: impl FnOnce(&mut [Worker], &Weighted) -> R,
) -> Result<R, SimError> {
    let Some(first) = workers.first_mut() else {
        return Ok(f(workers, w));
    };
    let at_rate = raw_residuals(first, w.case, &w.sigma, reference)?;
    at_sensitivity_rate(workers, w.case, |ws| {
        let at_coarse = raw_residuals(&mut ws[0], w.case, &w.sigma, reference)?;
        let d: Vec<f64> = at_rate.iter().zip(&at_coarse).map(|(a, b)| a - b).collect();
        let corrected = Weighted {
            case: w.case,
            sigma: w.sigma.clone(),
            nuisance: w.nuisance,
            filter: w.filter,
            correction: Some(&d),
            noise_cost: w.noise_cost,
        };
        Ok(f(ws, &corrected))
    })
}

/// Result of an output-error fit.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// Cost at the start values.
    pub cost_before: f64,
    /// Cost at the fitted values.
    pub cost_after: f64,
    /// Fitted values of the free parameters (in order of `active`).
    pub values: Vec<f64>,
    /// Standard errors of the free parameters: the coloured-residual sandwich (never below the Cramér–Rao bound).
    pub std_errors: Vec<f64>,
    /// Cramér–Rao standard errors s² (SᵀS)⁻¹ (white-residual assumption).
    pub crb_std_errors: Vec<f64>,
    /// Effective number of independent residuals at the fitted values (see [`effective_n`]).
    pub n_eff: f64,
    /// Output sensitivity column (∂r/∂θ) of each free parameter at the fitted values.
    pub sensitivities: Vec<Vec<f64>>,
    /// Simulations run.
    pub evaluations: usize,
    /// The noise-normalised residual at the fitted values (empty where no fit ran).
    pub residual: Vec<f64>,
}

/// Residual sensitivities ∂r/∂θ of the `free` parameters by forward differences from `r` (a
/// backward one at the upper bound).
fn residual_jacobian(
    worker: &mut Worker,
    w: &Weighted,
    active: &mut [Active],
    free: &[(usize, usize)],
    r: &[f64],
) -> Result<Vec<Vec<f64>>, SimError> {
    let mut cols = Vec::new();
    for &(i, j) in free {
        let spec = active[i].ext.params()[j];
        let p0 = active[i].params[j];
        let h = if p0 + spec.fd_step <= spec.max {
            spec.fd_step
        } else {
            -spec.fd_step
        };
        active[i].params[j] = p0 + h;
        let rh = residuals(worker, w, active);
        active[i].params[j] = p0;
        let rh = rh?;
        cols.push(rh.iter().zip(r).map(|(a, b)| (a - b) / h).collect());
    }
    Ok(cols)
}

/// Broyden's rank-one secant update of the sensitivities `cols` (∂r/∂θ, one column per parameter) from the
/// step `x0 → x` and the residuals `r0 → r` there: `J ← J + (Δr − J Δθ) Δθᵀ / (Δθᵀ Δθ)` (Dennis & Schnabel,
/// *Numerical Methods for Unconstrained Optimization and Nonlinear Equations*, SIAM 1996, eq. 8.1.5), the least
/// change that makes `J` reproduce the step it was last used for. With one parameter it is the secant slope,
/// and the chord iterations converge superlinearly instead of linearly. Nothing changes for a zero step.
fn secant_update(cols: &mut [Vec<f64>], x0: &[f64], x: &[f64], r0: &[f64], r: &[f64]) {
    let dx: Vec<f64> = x.iter().zip(x0).map(|(a, b)| a - b).collect();
    let dxx = linalg::dot(&dx, &dx);
    if dxx <= 0.0 || !dxx.is_finite() {
        return;
    }
    for k in 0..r.len() {
        let predicted: f64 = cols.iter().zip(&dx).map(|(c, d)| c[k] * d).sum();
        let miss = (r[k] - r0[k]) - predicted;
        for (c, d) in cols.iter_mut().zip(&dx) {
            c[k] += miss * d / dxx;
        }
    }
}

/// The replayed case for [`optimise::levenberg_marquardt`]: `x` holds the free parameters.
struct Replayed<'a, 'c, 'e> {
    worker: &'a mut Worker,
    w: &'a Weighted<'c>,
    active: &'a mut [Active<'e>],
    free: Vec<(usize, usize)>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    evaluations: usize,
    /// ∂r/∂θ of the last linearisation.
    last_cols: Vec<Vec<f64>>,
    /// ∂r/∂θ for every linearisation in place of forward differences (the chord method, see [`polish`]),
    /// updated along each accepted step by Broyden's secant rule.
    fixed: Option<Vec<Vec<f64>>>,
    /// The parameters and residual of the last linearisation (for the secant update of `fixed`).
    previous: Option<(Vec<f64>, Vec<f64>)>,
}

impl Replayed<'_, '_, '_> {
    fn set(&mut self, x: &[f64]) {
        for (k, &(i, j)) in self.free.iter().enumerate() {
            self.active[i].params[j] = x[k];
        }
    }
}

/// `None` where the model cannot trim at the record's initial condition (outside the region the record can be
/// replayed in), the value otherwise; any other simulator error stays an error.
pub(super) fn untrimmable_is_none<T>(r: Result<T, SimError>) -> Result<Option<T>, SimError> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(SimError::TrimFailed(_)) => Ok(None),
        Err(e) => Err(e),
    }
}

/// The cost of a residual, or infinity where the model cannot trim (a trial that explains nothing).
pub(super) fn cost_or_untrimmable(r: Result<Vec<f64>, SimError>) -> Result<f64, SimError> {
    untrimmable_is_none(r).map(|r| r.map_or(f64::INFINITY, |r| sum_sq(&r)))
}

impl optimise::Problem for Replayed<'_, '_, '_> {
    type Point = Vec<f64>;
    type Error = SimError;

    fn evaluate(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, SimError> {
        self.set(x);
        self.evaluations += 1;
        // A trial at which the extended model cannot trim at the record's initial condition lies outside
        // the region the record can be replayed in: the optimiser rejects the step and shortens it.
        untrimmable_is_none(residuals(self.worker, self.w, self.active))
    }

    fn cost(&self, r: &Vec<f64>) -> f64 {
        sum_sq(r)
    }

    fn linearise(
        &mut self,
        x: &[f64],
        r: &Vec<f64>,
    ) -> Result<Option<optimise::Linearised>, SimError> {
        self.set(x);
        if let (Some(cols), Some((x0, r0))) = (self.fixed.as_mut(), self.previous.take()) {
            secant_update(cols, &x0, x, r0.as_slice(), r);
        }
        if self.fixed.is_some() {
            self.previous = Some((x.to_vec(), r.clone()));
        }
        let cols = match self.fixed.clone() {
            Some(cols) => cols,
            None => {
                // A difference step whose model cannot trim: no sensitivities here, the fit ends.
                let jacobian = residual_jacobian(self.worker, self.w, self.active, &self.free, r);
                let Some(cols) = untrimmable_is_none(jacobian)? else {
                    return Ok(None);
                };
                self.evaluations += cols.len();
                cols
            }
        };
        // ŷ moves against r = (y − ŷ)/σ: S = −∂r/∂θ
        let sensitivities = Mat::from_fn(r.len(), cols.len(), |k, j| -cols[j][k]);
        self.last_cols = cols;
        Ok(Some(optimise::Linearised {
            sensitivities,
            residuals: r.clone(),
        }))
    }

    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &self.upper)
    }
}

/// A fit ends without simulating a step that predicts a cost decrease below this share of the residual
/// variance s² = J/(n − p): the step would move the parameters by less than a tenth of their Cramér–Rao bounds
/// (Δ J / s² = Σ (δ_i/σ_i)² for uncorrelated parameters), far inside what the selection and the reported values
/// resolve, and each step is a replay.
const MIN_DECREASE_SHARE: f64 = 0.01;

/// Levenberg–Marquardt output-error fit of the free parameters of `active` (updated in place).
pub fn fit(
    worker: &mut Worker,
    w: &Weighted,
    active: &mut [Active],
    max_iter: usize,
    final_jacobian: bool,
) -> Result<FitOutcome, SimError> {
    fit_from(worker, w, active, max_iter, final_jacobian, None)
}

/// [`fit`], with the sensitivities `fixed` (∂r/∂θ of the free parameters, in their order) for every
/// linearisation when given.
fn fit_from(
    worker: &mut Worker,
    w: &Weighted,
    active: &mut [Active],
    max_iter: usize,
    final_jacobian: bool,
    fixed: Option<Vec<Vec<f64>>>,
) -> Result<FitOutcome, SimError> {
    // Index of every free scalar parameter: (active index, parameter index).
    let free: Vec<(usize, usize)> = active
        .iter()
        .enumerate()
        .filter(|(_, a)| a.free)
        .flat_map(|(i, a)| (0..a.params.len()).map(move |j| (i, j)))
        .collect();
    let r = residuals(worker, w, active)?;
    let cost_before = sum_sq(&r);
    let x: Vec<f64> = free.iter().map(|&(i, j)| active[i].params[j]).collect();
    let specs: Vec<_> = free
        .iter()
        .map(|&(i, j)| active[i].ext.params()[j])
        .collect();
    let fixed = fixed.filter(|cols| cols.len() == free.len());
    let mut problem = Replayed {
        fixed: fixed.clone(),
        previous: None,
        worker,
        w,
        active,
        lower: specs.iter().map(|s| s.min).collect(),
        upper: specs.iter().map(|s| s.max).collect(),
        free,
        evaluations: 1,
        last_cols: Vec::new(),
    };
    let options = optimise::Options {
        max_iterations: max_iter,
        tolerance: 1e-5,
        min_decrease: MIN_DECREASE_SHARE * cost_before / (r.len() as f64 - x.len() as f64).max(1.0),
        damping: optimise::Damping {
            initial: 1e-3,
            min: 1e-6,
            decrease: 5.0,
            increase: 8.0,
            tries: 5,
        },
        solver: optimise::StepSolver::Marquardt,
    };
    let min = optimise::levenberg_marquardt(&mut problem, x, r, &options)?;
    problem.set(&min.x);
    let r = min.point;
    let c = sum_sq(&r);
    let Replayed {
        worker,
        active,
        free,
        mut evaluations,
        last_cols,
        ..
    } = problem;
    // Cramér–Rao bound at the fitted values with the residual variance estimate s² = J / (n − p).
    // (The cheap pass uses the last iteration's sensitivities instead of new ones; the chord refit, the fixed
    // sensitivities it was given, not their secant updates, which are exact along the steps taken only.)
    let cols = if let Some(given) = fixed {
        given
    } else if final_jacobian || last_cols.is_empty() {
        // At an optimum next to where the model stops trimming, a difference step can cross it: the last
        // iteration's sensitivities then stand in.
        match untrimmable_is_none(residual_jacobian(worker, w, active, &free, &r))? {
            Some(cols) => {
                evaluations += free.len();
                cols
            }
            None if !last_cols.is_empty() => last_cols,
            None => return Err(SimError::TrimFailed("no sensitivity step trims".into())),
        }
    } else {
        last_cols
    };
    let p = free.len();
    let a: Vec<f64> = (0..p * p)
        .map(|ij| linalg::dot(&cols[ij / p], &cols[ij % p]))
        .collect();
    let s2 = c / (r.len() as f64 - p as f64).max(1.0);
    let m = w.case.len();
    let (crb_std_errors, std_errors) = match linalg::inverse(&a, p) {
        Some(inv) => {
            let cov = covariance::sandwich(&inv, &coloured_products(&cols, &r, m), p);
            let crb: Vec<f64> = (0..p)
                .map(|i| (s2 * inv[i * p + i]).max(0.0).sqrt())
                .collect();
            let coloured = (0..p)
                .map(|i| cov[i * p + i].max(0.0).sqrt().max(crb[i]))
                .collect();
            (crb, coloured)
        }
        None => (vec![f64::INFINITY; p], vec![f64::INFINITY; p]),
    };
    let n_eff = effective_n(&r, m);
    // Restore the cache to the fitted values (the last simulation was a perturbed one).
    Ok(FitOutcome {
        cost_before,
        cost_after: c,
        values: free.iter().map(|&(i, j)| active[i].params[j]).collect(),
        std_errors,
        crb_std_errors,
        n_eff,
        sensitivities: cols,
        evaluations,
        residual: r,
    })
}

/// The fit at the replay's rate that follows a fit at the coarse rate ([`coarse`]): at most three
/// Levenberg–Marquardt iterations from its optimum, every effect of `active` free, all with the coarse fit's
/// sensitivities `coarse_sensitivities` (∂r/∂θ in the order of the free parameters; the corrected residual has
/// the coarse model's sensitivities, equal to the replay's to first order). A fixed Jacobian is the chord
/// method (Kelley, *Iterative Methods for Linear and Nonlinear Equations*, SIAM 1995, §5.4): linear
/// convergence at the rate ‖I − J_c⁺J‖, small here, and one replay per iteration instead of 1 + p. Its values
/// and cost are the ones reported, its standard errors those of the coarse sensitivities.
pub fn polish(
    worker: &mut Worker,
    w: &Weighted,
    active: &mut [Active],
    coarse_sensitivities: &[Vec<f64>],
) -> Result<FitOutcome, SimError> {
    fit_from(
        worker,
        w,
        active,
        3,
        false,
        Some(coarse_sensitivities.to_vec()),
    )
}

/// The residual sensitivity ∂r/∂θ of `candidate`'s first parameter at its null value on top of the `base`
/// effects, by a forward difference from `r0`, the residual of `base` (one simulation; none for a sensor effect
/// when the worker's last simulation was of `base`).
pub fn null_sensitivity(
    worker: &mut Worker,
    w: &Weighted,
    base: &[Active],
    candidate: &dyn Extension,
    r0: &[f64],
) -> Result<Vec<f64>, SimError> {
    let spec = candidate.params()[0];
    let h = if spec.null + spec.fd_step <= spec.max {
        spec.fd_step
    } else {
        -spec.fd_step
    };
    let mut active = base.to_vec();
    let mut params: Vec<f64> = candidate.params().iter().map(|p| p.null).collect();
    params[0] += h;
    active.push(Active {
        ext: candidate,
        params,
        free: true,
    });
    let rh = residuals(worker, w, &active)?;
    Ok(rh.iter().zip(r0).map(|(a, b)| (a - b) / h).collect())
}

/// Runs `f` over `items` in parallel, one thread per slot of `workers` (simulation workers, or `()` for
/// computation only), each item on the first free slot; results in item order.
pub fn par_map<S: Send, T: Sync, R: Send>(
    workers: &mut [S],
    items: &[T],
    f: impl Fn(&mut S, &T) -> R + Sync,
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for worker in workers.iter_mut() {
            let (next, out, f) = (&next, &out, &f);
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= items.len() {
                    break;
                }
                let r = f(worker, &items[i]);
                if let Ok(mut o) = out.lock() {
                    o[i] = Some(r);
                }
            });
        }
    });
    out.into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| r.expect("every item is processed by one worker"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::secant_update;

    #[test]
    fn the_secant_update_reproduces_the_step_and_recovers_a_one_parameter_slope() {
        // r(θ) = r₀ + J θ with J = [2, −1, 0.5]; the chord starts from the coarse J_c = [1.5, −0.8, 0.4]. After
        // one step the updated column is the exact slope (one parameter: the secant), to rounding.
        let slope = [2.0, -1.0, 0.5];
        let r_at = |t: f64| -> Vec<f64> { slope.iter().map(|j| 0.3 + j * t).collect() };
        let mut cols = vec![vec![1.5, -0.8, 0.4]];
        secant_update(&mut cols, &[0.1], &[0.25], &r_at(0.1), &r_at(0.25));
        for (c, j) in cols[0].iter().zip(slope) {
            assert!((c - j).abs() < 1e-12, "{c} for {j}");
        }
        // Two parameters: the update is exact along the step and leaves the orthogonal direction as it was.
        let mut cols = vec![vec![1.0, 0.0], vec![0.0, 1.0]];
        let (x0, x1) = ([0.0, 0.0], [1.0, 0.0]);
        let (r0, r1) = (vec![0.0, 0.0], vec![3.0, 2.0]); // the first column is really [3, 2]
        secant_update(&mut cols, &x0, &x1, &r0, &r1);
        assert_eq!(cols, vec![vec![3.0, 2.0], vec![0.0, 1.0]]);
        // No step, no change.
        secant_update(&mut cols, &x1, &x1, &r1, &r0);
        assert_eq!(cols, vec![vec![3.0, 2.0], vec![0.0, 1.0]]);
    }
}
