//! The equilibrium the record's inputs hold, where the record does not start in it.
//!
//! The replay trims the model at the record's start and drives it with the inputs' departures from their values
//! there (`replay`), so the replay returns to that trim whenever the inputs do. A record that begins in a
//! transient (a log cut from a longer flight during a phugoid, or just after a maneuver) starts away from the
//! equilibrium its inputs hold: the aircraft flies back toward that equilibrium, the replay toward the start, and
//! the difference grows over the whole record. The segment initial states (`initial_state`) take up the start's
//! departure from the trim, not the equilibrium's. On clean c172x records of the independent generator cut 9 s
//! and 14 s in, the search named an a_z, a q and an a_x bias, and an a_x and a θ bias.
//!
//! So the trim's airspeed is fitted to the training record on the unextended model, with the segment initial
//! states projected off, by the crate's optimiser (a finite-difference sensitivity), and the fit is taken only
//! where it lowers that cost by [`GAIN`] and by [`SHARE`] of it. A record that starts in steady flight, as a flight
//! test's records do, keeps the trim at its start: the first linearisation predicts less than half the gate and
//! nothing more is simulated (two replays). The flight path is not fitted: it would take up a θ bias as a trim
//! nose-down (a 1° bias as a flight path of −0.68°, 38 % of the cost), and a record that starts in a phugoid's
//! climb is trimmed level already (`start::flight_path_deg`).

use super::prepare::Prepared;
use super::progress::Progress;
use super::search::{
    orthonormal_basis, par_map, project_off, raw_residuals, untrimmable_is_none, Worker,
};
use super::{sim_err, DiagnoseError};
use crate::optimise::{self, Linearised};
use crate::signal::sum_sq;
use crate::sim::{SimError, TrimPoint};
use faer::Mat;

/// How much lower (noise-normalised cost, χ²) the fitted equilibrium's cost must be than the start's: the ΔBIC
/// floor of the selection (Kass & Raftery 1995), as for the integration rate (`rate::COARSER_GAIN`).
pub const GAIN: f64 = super::rate::COARSER_GAIN;

/// The share of the start trim's cost the fitted equilibrium must also remove. A record that starts in steady
/// flight gains nothing from it but what a hidden effect lends; a record that begins in a transient gains most of
/// its cost (module doc): on the clean c172x records cut inside a transient 81–96 %, on the 40 records of
/// `diagnose_eval --cases 40 --seed 19`, which start in trim, at most 5.2 % (with a gate of 5 % the trim of one of
/// them moved by 1.3 kts, and an a_z bias was named beside its elevator effectiveness).
pub const SHARE: f64 = 0.2;

/// Finite-difference step of the airspeed, kts.
const STEP_KTS: f64 = 1.0;

/// How far the equilibrium's airspeed may lie from the record's start, kts.
const REACH_KTS: f64 = 15.0;

/// The training record's trim moved to the equilibrium of its inputs (module doc), with a warning saying so and
/// the equilibrium's nuisance column; `None` (the trim unchanged) where the fit does not pass the gate. `columns` are the segment initial-state
/// responses at the start's trim.
pub fn settle(
    workers: &mut [Worker],
    p: &mut Prepared,
    columns: &[Vec<f64>],
    progress: &Progress,
) -> Result<Option<Settled>, DiagnoseError> {
    if columns.is_empty() {
        return Ok(None);
    }
    progress.stage("equilibrium", 0);
    let basis = orthonormal_basis(columns);
    let start = p.case.point;
    let mut problem = Equilibrium {
        workers,
        p,
        basis: &basis,
        start,
        lower: [-REACH_KTS],
        upper: [REACH_KTS],
    };
    let r0 = match optimise::Problem::evaluate(&mut problem, &[0.0]) {
        Ok(Some(r)) => r,
        Ok(None) => return Ok(None),
        Err(e) => return Err(sim_err("replay at the record's start")(e)),
    };
    let cost0 = sum_sq(&r0);
    let gate = GAIN.max(SHARE * cost0);
    let options = optimise::Options {
        max_iterations: 8,
        tolerance: 1e-4,
        min_decrease: 0.5 * gate,
        ..Default::default()
    };
    let fit = optimise::levenberg_marquardt(&mut problem, vec![0.0], r0, &options)
        .map_err(sim_err("fitting the record's equilibrium"))?;
    let cost = sum_sq(&fit.point);
    if cost.is_nan() || cost >= cost0 - gate {
        return Ok(None);
    }
    p.case.point = at(&start, &fit.x);
    Ok(Some(Settled {
        column: speed_column(workers, p).map_err(sim_err("replay at the record's equilibrium"))?,
        note: format!(
        "the record does not start in steady flight: its inputs hold the model at {:.1} kts, its start is at \
         {:.1} kts; the replay trims at the first, and the start's departure from it is part of the initial state \
         (noise-normalised cost {cost0:.0} → {cost:.0})",
            p.case.point.speed_kts,
            start.speed_kts
        ),
    }))
}

/// What [`settle`] found where it moved the trim.
pub struct Settled {
    /// The warning that says so.
    pub note: String,
    /// The equilibrium's airspeed as a nuisance term of every fit: the unextended model's noise-normalised
    /// output change per knot of the trim's airspeed, channel-major like the segment initial states' columns.
    /// The fit above is made on the unextended model, and a hidden effect moves the equilibrium the record
    /// holds (a `Cm_q` ×1.6 on a record logged from 14 s: 109.3 kts fitted against the generator's 109.8, and a
    /// `CD_0` ×1.47 named beside `Cm_q`); with the airspeed estimated jointly with every fit, as the initial
    /// states are, the effect's fit carries its own equilibrium.
    pub column: Vec<f64>,
}

/// The unextended model's noise-normalised output change per knot of the trim's airspeed at `p`'s trim.
fn speed_column(workers: &mut [Worker], p: &Prepared) -> Result<Vec<f64>, SimError> {
    let trials = [p.case.point, at(&p.case.point, &[STEP_KTS])];
    let outs = par_map(workers, &trials, |w, point| {
        let mut case = p.case.clone();
        case.point = *point;
        raw_residuals(w, &case, &p.sigma, &[])
    });
    let [base, moved]: [Vec<f64>; 2] = outs
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?
        .try_into()
        .map_err(|_| SimError::Protocol("two replays expected".into()))?;
    // r = (y − ŷ)/σ, so ŷ's change is the residual's, negated
    Ok(base
        .iter()
        .zip(&moved)
        .map(|(b, m)| (b - m) / STEP_KTS)
        .collect())
}

/// The trim point with its airspeed moved by `x[0]` kts.
fn at(start: &TrimPoint, x: &[f64]) -> TrimPoint {
    TrimPoint {
        speed_kts: start.speed_kts + x[0],
        ..*start
    }
}

/// The unextended model's projected residual as a function of the trim's airspeed.
struct Equilibrium<'a> {
    workers: &'a mut [Worker],
    p: &'a mut Prepared,
    basis: &'a [Vec<f64>],
    start: TrimPoint,
    lower: [f64; 1],
    upper: [f64; 1],
}

impl Equilibrium<'_> {
    /// The projected residuals at each trial `x`, in parallel on the workers (None where the model cannot trim).
    fn residuals_at(&mut self, xs: &[Vec<f64>]) -> Result<Vec<Option<Vec<f64>>>, SimError> {
        let (p, basis, start) = (&*self.p, self.basis, self.start);
        par_map(self.workers, xs, |w, x| {
            let mut case = p.case.clone();
            case.point = at(&start, x);
            let r = untrimmable_is_none(raw_residuals(w, &case, &p.sigma, &[]))?;
            Ok(r.map(|mut r| {
                project_off(&mut r, basis);
                r
            }))
        })
        .into_iter()
        .collect()
    }
}

impl optimise::Problem for Equilibrium<'_> {
    type Point = Vec<f64>;
    type Error = SimError;

    fn evaluate(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, SimError> {
        Ok(self.residuals_at(&[x.to_vec()])?.pop().flatten())
    }

    fn cost(&self, r: &Vec<f64>) -> f64 {
        sum_sq(r)
    }

    fn linearise(&mut self, x: &[f64], r: &Vec<f64>) -> Result<Option<Linearised>, SimError> {
        // a forward difference, stepping inward at the upper bound
        let h = if x[0] + STEP_KTS > self.upper[0] {
            -STEP_KTS
        } else {
            STEP_KTS
        };
        let Some(rh) = self.residuals_at(&[vec![x[0] + h]])?.pop().flatten() else {
            return Ok(None);
        };
        // the residual is z − ŷ: its sensitivity is −∂r/∂x
        Ok(Some(Linearised {
            sensitivities: Mat::from_fn(r.len(), 1, |i, _| -(rh[i] - r[i]) / h),
            residuals: r.clone(),
        }))
    }

    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lower, &self.upper)
    }
}
