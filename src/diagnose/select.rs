//! Stage 3, select: forward selection over the catalogue.
//!
//! - Identifiability, before any fit: the Fisher information of each entry's parameter on this record after
//!   the nuisance terms, I = ‖(1 − P_N) s‖² with s = ∂r/∂θ the noise-normalised residual sensitivity at
//!   "no effect" and P_N the projection onto the sensitivities of the nuisance terms, an offset on every
//!   channel that may carry a sensor bias (the Schur complement of the information matrix: the information
//!   left once the nuisance terms are estimated jointly; Jategaonkar, Flight Vehicle System Identification,
//!   2nd ed., §4.17; Morelli & Klein §5.4 on partial correlation). An entry whose Cramér–Rao bound 1/√I
//!   exceeds a third of its resolution (the smallest effect worth naming) cannot be named from this record
//!   (an input that does not move, an output that is not measured, a term the record does not excite) and is
//!   skipped.
//! - Resolution on the record: an entry that refines a linear term (`CL_alpha2` refines `CL_alpha`) acts near
//!   the trim point mostly as a change of that term, so its smallest effect worth naming is the one whose
//!   output signature is as large as that of the linear term at a share f of its resolution:
//!   r_k = max(r_k⁰, f r_lin √(I_lin / I_k)). A record with a narrow α range thus needs a large k. The share
//!   (`DiagnoseOptions::refinement_share`, a third: the precision the linear term itself must be determined
//!   to) is checked by the false-alarm Monte Carlo of the evaluation bench.
//! - Screening, each round: the score (Lagrange-multiplier) test of every remaining entry, the cost reduction
//!   of one Gauss–Newton step from "no effect", ΔJ = (sᵀr)² / (sᵀs) (Rao 1948; the stepwise idea of Klein &
//!   Morelli, Aircraft System Identification, §5.4), with the sensitivities of the unextended model.
//! - The best few are fitted by output error jointly with the effects already selected (at the coarse rate,
//!   `search::coarse`; an accepted model is refitted at the replay's rate, `settle`), unless the score test
//!   already rules the fit out (a one-step estimate within half the resolution of "no effect" that explains
//!   less than the share of the cost a named effect must), and judged: an interior
//!   optimum, at least the resolution away from "no effect" and determined to a third of it, BIC with the
//!   effective sample count, distance from "no effect" in standard errors, a share of the cost explained.
//! - The validation record never picks: the gain of the accepted effects on it is only reported.
//! - Significant candidates that fit as well and whose sensitivities are nearly parallel to the chosen one's
//!   form its ambiguity group.

mod gates;
mod identifiability;
mod refine;
use gates::{beaten_within_resolution, rejection, unconfirmed_in_time, RESOLUTION_CONFIDENCE};
pub(super) use gates::{beyond_resolution, BEATEN_WITHIN_RESOLUTION, NOT_SIGNIFICANT, SMALL_SHARE};
pub use identifiability::profiled_information;
use identifiability::{identifiable, Identifiable};
use refine::Refiner;
pub(super) use refine::{
    determined_on, eliminate_backward, replace_ambiguous, substitute_dropped, Replacement,
};

use super::baseline::Baseline;
use super::extension::Extension;
use super::prepare::Prepared;
use super::progress::Progress;
use super::residual::effective_n;
use super::search::{self, fit, par_map, residuals, Active, FitOutcome, Weighted, Worker};
use super::{sim_err, Candidate, DiagnoseError, DiagnoseOptions, NamedCause, Skipped};

/// The outcome of the selection.
pub struct Selection<'e> {
    /// The accepted effects with their fitted values.
    pub selected: Vec<Active<'e>>,
    /// The named causes (in order of selection).
    pub named: Vec<NamedCause>,
    /// Every evaluated candidate.
    pub candidates: Vec<Candidate>,
    /// Catalogue entries the record cannot identify.
    pub unidentifiable: Vec<Skipped>,
    /// The entries of `unidentifiable` that the Fisher information turned down (not those whose input does not
    /// move), with their resolution and masks: the filter error refit tests them again on the innovations.
    pub undetermined: Entries<'e>,
    /// Per effect named in a round (`effect/target`), the other candidates that passed their own tests there:
    /// the runner-ups, and those a candidate within its resolution of "no effect" fitted better.
    pub alternatives: Vec<(String, Vec<String>)>,
    /// The identifiable catalogue entries, each with its resolution on the record and its sensor-offset mask
    /// (what a later stage needs to test a named effect as the selection did).
    pub entries: Entries<'e>,
}

/// Catalogue entries with their resolution on the record and their channel masks.
#[derive(Clone, Default)]
pub struct Entries<'e> {
    /// The entries.
    pub catalogue: Vec<&'e dyn Extension>,
    /// Each entry's smallest effect worth naming on the record.
    pub resolution: Vec<f64>,
    /// Each entry's channels on which a sensor offset is a nuisance term.
    pub masks: Vec<Vec<bool>>,
}

impl<'e> Entries<'e> {
    /// These entries followed by `more`'s.
    pub fn joined(&self, more: &Entries<'e>) -> Entries<'e> {
        let mut out = self.clone();
        out.catalogue.extend(more.catalogue.iter().copied());
        out.resolution.extend(more.resolution.iter().copied());
        out.masks.extend(more.masks.iter().cloned());
        out
    }

    /// A backward-elimination context on `workers` and the weighting `w`.
    pub(super) fn refiner<'a>(
        &'a self,
        workers: &'a mut [Worker],
        w: &'a Weighted<'a>,
        opts: &'a DiagnoseOptions,
        progress: &'a Progress,
    ) -> Refiner<'a, 'e> {
        Refiner {
            workers,
            w,
            catalogue: &self.catalogue,
            resolution: &self.resolution,
            masks: &self.masks,
            opts,
            progress,
        }
    }
}

/// The selected effects (free or held) plus one candidate, free, starting at `start` (its first parameter,
/// clamped into its range; the others at their null values).
fn with_candidate<'e>(
    selected: &[Active<'e>],
    e: &'e dyn Extension,
    start: f64,
    free_selected: bool,
) -> Vec<Active<'e>> {
    let mut a = with_freedom(selected, free_selected);
    let mut params: Vec<f64> = e.params().iter().map(|p| p.null).collect();
    let spec = e.params()[0];
    if start.is_finite() {
        params[0] = start.clamp(spec.min, spec.max);
    }
    a.push(Active {
        ext: e,
        params,
        free: true,
    });
    a
}

/// The selected effects, each free (fitted) or held as `free` says.
fn with_freedom<'e>(selected: &[Active<'e>], free: bool) -> Vec<Active<'e>> {
    selected
        .iter()
        .map(|s| Active { free, ..s.clone() })
        .collect()
}

/// Makes `fitted` the selection, every effect held at its fitted values.
fn adopt<'e>(selected: &mut Vec<Active<'e>>, fitted: Vec<Active<'e>>) {
    *selected = fitted;
    for s in selected.iter_mut() {
        s.free = false;
    }
}

/// The noise-normalised cost per residual above which a round that names nothing screens wide: clean records of
/// the independent generator stay at 1.0–1.3 (the noise), and a hidden `Cn_beta` ×0.41 left 150.
const WIDE_SCREEN_COST: f64 = 4.0;

/// Wide screening: the cost of the model with each entry at two values, halfway from "no effect" to either end
/// of its range (one where "no effect" is an end), the selected effects held; for each entry its better trial
/// (value, cost), `None` where no trial could be replayed. The score test linearises at "no effect", and a large
/// change of a mode's frequency takes the response far from where that holds: a hidden `Cn_beta` ×0.41 did not
/// rank among the best eight (its one-step estimate ×0.84), and nothing was named. A trial is a simulation, so
/// the screen runs only when the score test's round has named nothing and the residual says something is
/// still unexplained.
fn wide_screen(
    workers: &mut [Worker],
    w: &Weighted,
    selected: &[Active],
    entries: &[&dyn Extension],
) -> Result<Vec<Option<(f64, f64)>>, crate::sim::SimError> {
    let mut items: Vec<(usize, f64)> = Vec::new();
    for (k, e) in entries.iter().enumerate() {
        let p = e.params()[0];
        for end in [p.min, p.max] {
            if end != p.null {
                items.push((k, p.null + 0.5 * (end - p.null)));
            }
        }
    }
    let costs = par_map(workers, &items, |wk, &(k, value)| {
        search::cost_or_untrimmable(residuals(
            wk,
            w,
            &with_candidate(selected, entries[k], value, false),
        ))
    });
    let mut best: Vec<Option<(f64, f64)>> = vec![None; entries.len()];
    for (&(k, value), cost) in items.iter().zip(costs) {
        let cost = cost?;
        if cost.is_finite() && best[k].is_none_or(|(_, c)| cost < c) {
            best[k] = Some((value, cost));
        }
    }
    Ok(best)
}

/// Every start fitted by output error (its free effects refitted), in parallel on the workers; each fit's
/// model evaluations are counted on `progress`.
fn fit_starts<'e>(
    workers: &mut [Worker],
    w: &Weighted,
    starts: &[Vec<Active<'e>>],
    progress: &Progress,
) -> Vec<FullFit<'e>> {
    par_map(workers, starts, |wk, active| {
        let mut a = active.clone();
        let out = backtrack_start(wk, w, &mut a).and_then(|()| fit(wk, w, &mut a, 10, true));
        progress.fitted();
        out.map(|o| (o, a))
    })
}

/// Pulls the start of the last (candidate) effect of `active` back toward "no effect" until the record is
/// explained better there than with no effect, halving the step at most four times. The score test's one-step
/// estimate extrapolates the residual's sensitivity at "no effect"; for a large effect it can land at or beyond
/// the bound, where the replay departs and the fit has no gradient to come back along (a hidden C_mα ×0.43 in
/// gusts started at the bound ×0.2 and stayed there). Halving the Gauss–Newton step
/// until the cost falls is the backtracking line search (Dennis & Schnabel, *Numerical Methods for
/// Unconstrained Optimization and Nonlinear Equations*, §6.3). Both costs are usually in the workers' store
/// already (the round's model and the fit's own first replay).
fn backtrack_start(
    worker: &mut Worker,
    w: &Weighted,
    active: &mut [Active],
) -> Result<(), crate::sim::SimError> {
    let Some(k) = active.len().checked_sub(1) else {
        return Ok(());
    };
    let (null, start) = (active[k].ext.params()[0].null, active[k].params[0]);
    if start == null {
        return Ok(());
    }
    // A start whose model cannot trim explains nothing: the step is halved as for any worse one.
    let mut cost_at = |x: f64, active: &mut [Active]| {
        active[k].params[0] = x;
        search::cost_or_untrimmable(residuals(worker, w, active))
    };
    let no_effect = cost_at(null, active)?;
    let mut x = start;
    for _ in 0..4 {
        if cost_at(x, active)? < no_effect {
            break;
        }
        x = null + 0.5 * (x - null);
    }
    active[k].params[0] = x;
    Ok(())
}

/// Costs a round's criterion is measured against.
struct RoundContext {
    round: usize,
    base_cost: f64,
    floor: f64,
}

impl RoundContext {
    /// ΔBIC = n_eff ln(max(J₁, f·n) / max(J₀, f·n)) + k ln n_eff (Schwarz 1978; one more parameter per
    /// candidate, the selected effects being counted in the base model).
    fn bic(&self, e: &dyn Extension, o: &FitOutcome) -> f64 {
        let k = e.params().len() as f64;
        o.n_eff * (o.cost_after.max(self.floor) / self.base_cost.max(self.floor)).ln()
            + k * o.n_eff.ln()
    }

    fn candidate(
        &self,
        e: &dyn Extension,
        o: &FitOutcome,
        full_fit: bool,
        resolution: f64,
    ) -> Candidate {
        let k = o.values.len() - 1;
        Candidate {
            effect: e.effect().into(),
            target: e.target().into(),
            value: o.values[k],
            std_error: o.std_errors[k],
            cost_before: self.base_cost,
            cost_after: o.cost_after,
            criterion: "BIC".into(),
            criterion_delta: self.bic(e, o),
            z: (o.values[k] - e.params()[0].null).abs() / o.std_errors[k].max(1e-300),
            n_eff: o.n_eff,
            resolution,
            validation_gain: None,
            rejected_because: None,
            round: self.round,
            full_fit,
            held_out_share: None,
        }
    }
}

/// The score test of one entry: the one-step Gauss–Newton estimate from "no effect" and its cost
/// reduction, with the Cramér–Rao bound √(J/n)/√(sᵀs). On the quadratic model J(δ) = J + 2δ sᵀr + δ² sᵀs the
/// step is δ* = −sᵀr/sᵀs and the reduction (sᵀr)²/(sᵀs); where δ* leaves the parameter's range (the fit is
/// bounded) the step is held at the bound and the reduction is the model's there, sᵀs (2δδ* − δ²). A residual
/// that an entry could explain only far beyond its range (in gusts: `Cn_r` ×6, `CD_0` below zero) then ranks
/// by what the entry can explain, not by what it cannot, and the entries whose estimate lies in range get the
/// full fits.
fn score_test(e: &dyn Extension, s: &[f64], r: &[f64], cost: f64, n_eff: f64) -> FitOutcome {
    let ss: f64 = s.iter().map(|v| v * v).sum();
    let sr: f64 = s.iter().zip(r).map(|(a, b)| a * b).sum();
    let spec = e.params()[0];
    let null = spec.null;
    let (step, drop) = if ss > 0.0 {
        let free = -sr / ss;
        let step = free.clamp(spec.min - null, spec.max - null);
        (step, ss * (2.0 * step * free - step * step))
    } else {
        (0.0, 0.0)
    };
    let se = (cost / r.len().max(1) as f64).sqrt() / ss.sqrt();
    FitOutcome {
        cost_before: cost,
        cost_after: cost - drop,
        values: vec![null + step],
        std_errors: vec![se],
        crb_std_errors: vec![se],
        n_eff,
        sensitivities: Vec::new(),
        evaluations: 0,
        residual: Vec::new(),
    }
}

/// Drops every named effect that a later joint fit (the effects named before are free in each round's fits, in
/// the sequential replacement and in the filter error refit) has moved to within its resolution of "no effect":
/// the test a candidate must pass to be named holds for every named effect in the final model, not only at the
/// round it was named in. In gusts an elevator effectiveness of ×1.48 named first fell to ×1.02 once the hidden
/// C_mα ×0.43 was named beside it. The resolution is the one the effect's accepted candidate entry was tested
/// against, and that entry says why it went. Returns whether any was dropped (the model's cost must then be
/// evaluated again).
pub(super) fn drop_below_resolution(
    selected: &mut Vec<Active>,
    named: &mut Vec<NamedCause>,
    candidates: &mut [Candidate],
) -> bool {
    let mut dropped = false;
    let mut k = 0;
    while k < named.len() {
        let (effect, target) = (&named[k].effect, &named[k].target);
        let null = selected[k].ext.params()[0].null;
        let accepted = candidates.iter_mut().rev().find(|c| {
            &c.effect == effect && &c.target == target && c.full_fit && c.rejected_because.is_none()
        });
        let within = |c: &&mut Candidate| {
            !beyond_resolution(named[k].value - null, named[k].std_error, c.resolution)
        };
        let Some(c) = accepted.filter(within) else {
            k += 1;
            continue;
        };
        c.rejected_because = Some(format!(
            "dropped after a later joint fit with the other named effects: its value {:.4} ± {:.4} is within \
             the resolution {:.3} of no effect, at {RESOLUTION_CONFIDENCE} standard errors",
            named[k].value, named[k].std_error, c.resolution
        ));
        named.remove(k);
        selected.remove(k);
        dropped = true;
    }
    dropped
}

/// After a joint fit at the coarse rate ([`search::coarse`]) was adopted: the named effects refitted at the
/// replay's rate from its values and sensitivities ([`search::polish`]; the values and cost are the replay's, and
/// the next round's coarse fits are corrected at them), then [`drop_below_resolution`] and, when an effect went,
/// the model's cost evaluated again (one replay).
fn settle(
    worker: &mut Worker,
    w: &Weighted,
    progress: &Progress,
    state: Replacement<'_, '_>,
    coarse_sensitivities: &[Vec<f64>],
    held: impl Fn(&Active) -> bool,
) -> Result<(), DiagnoseError> {
    if state.selected.iter().any(|s| !held(s)) {
        progress.stage("refit at the replay's rate", 1);
        let mut active: Vec<Active> = state
            .selected
            .iter()
            .map(|s| Active {
                free: !held(s),
                ..s.clone()
            })
            .collect();
        let o = search::polish(worker, w, &mut active, coarse_sensitivities)
            .map_err(sim_err("replay"))?;
        progress.fitted();
        let mut k = 0;
        for (a, n) in active.iter().zip(state.named.iter_mut()) {
            n.value = a.params[0];
            if a.free {
                n.std_error = o.std_errors.get(k).copied().unwrap_or(f64::NAN);
                k += a.params.len();
            }
        }
        adopt(state.selected, active);
        *state.cost = o.cost_after;
    }
    if drop_below_resolution(state.selected, state.named, state.candidates) {
        let r = residuals(worker, w, state.selected).map_err(sim_err("replay"))?;
        *state.cost = crate::signal::sum_sq(&r);
    }
    Ok(())
}

type FullFit<'e> = Result<(FitOutcome, Vec<Active<'e>>), crate::sim::SimError>;

/// Forward selection over the prepared catalogue.
pub fn select<'e>(
    workers: &mut [Worker],
    p: &'e Prepared,
    base: &Baseline,
    opts: &DiagnoseOptions,
    progress: &Progress,
) -> Result<Selection<'e>, DiagnoseError> {
    let w = p.training();
    let vw = p.validation();
    let Identifiable {
        entries: catalogue,
        sensitivities: sens,
        resolution,
        masks,
        skipped: unidentifiable,
        undetermined,
    } = search::coarse(workers, &w, &[], |ws, cw| {
        identifiable(ws, cw, p, opts, progress)
    })
    .map_err(sim_err("replay"))??;
    let mut selected: Vec<Active> = Vec::new();
    let mut named: Vec<NamedCause> = Vec::new();
    let mut candidates = Vec::new();
    let mut base_cost = base.cost;
    let mut valid_cost = base.valid_cost;
    // Entries whose accepted fit left a model that cannot trim: not screened again.
    let mut untrimmable: Vec<usize> = Vec::new();
    // Per named effect (`effect/target`), the other candidates that passed every test in its round.
    let mut runner_ups: Vec<(String, Vec<String>)> = Vec::new();
    let mut alternatives: Vec<(String, Vec<String>)> = Vec::new();
    // Whether this round screens wide (see `wide_screen`), and whether a round has.
    let (mut widen, mut widened) = (false, false);
    // Rounds until `max_effects` effects are named: an effect that a later joint fit drops
    // (`drop_below_resolution`) gives its round back, with at most as many extra rounds as `max_effects`. A
    // `Cn_r` ×2.7 named first and dropped at ×1.03 once `Cn_beta` and an a_y bias were named had used up the
    // third round, and a hidden aileron delay of 0.084 s at ΔBIC −3504 was left out.
    for round in 0..2 * opts.max_effects {
        if named.len() >= opts.max_effects {
            break;
        }
        let pool: Vec<usize> = (0..catalogue.len())
            .filter(|i| !untrimmable.contains(i))
            .filter(|&i| {
                !selected.iter().any(|s| {
                    s.ext.effect() == catalogue[i].effect()
                        && s.ext.target() == catalogue[i].target()
                })
            })
            .collect();
        progress.round(round, opts.full_fit_top);
        // Screening: the score test of every remaining entry at the current model's residual.
        let r = residuals(&mut workers[0], &w, &selected).map_err(sim_err("replay"))?;
        let n_eff_now = effective_n(&r, p.case.len());
        let cost_now = crate::signal::sum_sq(&r);
        let mut quick: Vec<FitOutcome> = pool
            .iter()
            .map(|&i| score_test(catalogue[i], &sens[i], &r, cost_now, n_eff_now))
            .collect();
        if std::mem::take(&mut widen) {
            let entries: Vec<&dyn Extension> = pool.iter().map(|&i| catalogue[i]).collect();
            let trials = search::coarse(workers, &w, &selected, |ws, cw| {
                wide_screen(ws, cw, &selected, &entries)
            })
            .and_then(|t| t)
            .map_err(sim_err("replay"))?;
            for (q, trial) in quick.iter_mut().zip(trials) {
                if let Some((value, cost)) = trial.filter(|&(_, c)| c < q.cost_after) {
                    q.values[0] = value;
                    q.cost_after = cost;
                }
            }
        }
        let mut order: Vec<usize> = (0..pool.len()).collect();
        order.sort_by(|&a, &b| quick[a].cost_after.total_cmp(&quick[b].cost_after));
        // The best few by the score test are fitted, unless the test already says that a fit cannot name them:
        // a one-step estimate within half the resolution of "no effect" (the fit would have to more than double
        // the Gauss–Newton step from there) that also explains less than the share of the cost a named effect
        // must explain.
        let unpromising = |j: usize| {
            let i = pool[j];
            let step = (quick[j].values[0] - catalogue[i].params()[0].null).abs();
            step < 0.5 * resolution[i]
                && 1.0 - quick[j].cost_after / cost_now < opts.min_relative_reduction
        };
        let best_few: Vec<usize> = order.iter().take(opts.full_fit_top).copied().collect();
        let top: Vec<usize> = best_few
            .iter()
            .copied()
            .filter(|&j| !unpromising(j))
            .collect();
        let ctx = RoundContext {
            round,
            base_cost,
            floor: opts.residual_floor * w.noise_cost,
        };
        for (j, o) in quick.iter().enumerate() {
            if !top.contains(&j) {
                let mut c = ctx.candidate(catalogue[pool[j]], o, false, resolution[pool[j]]);
                if best_few.contains(&j) {
                    c.rejected_because = Some(format!(
                        "not fitted: the score test's estimate is within half the resolution {:.3} of no effect \
                         and explains {:.2} % of the cost",
                        resolution[pool[j]],
                        100.0 * (1.0 - o.cost_after / cost_now)
                    ));
                }
                candidates.push(c);
            }
        }
        // A round that fits nothing, or names nothing, while the residual stays far above the noise screens
        // once more, wide.
        let widen_now = !widened && cost_now > WIDE_SCREEN_COST * w.noise_cost;
        if top.is_empty() {
            if widen_now {
                (widen, widened) = (true, true);
                continue;
            }
            break;
        }
        // Full pass: the top candidates jointly with the selected effects, from the score test's estimate.
        let starts: Vec<Vec<Active>> = top
            .iter()
            .map(|&j| with_candidate(&selected, catalogue[pool[j]], quick[j].values[0], true))
            .collect();
        let full = search::coarse(workers, &w, &selected, |ws, cw| {
            fit_starts(ws, cw, &starts, progress)
        })
        .map_err(sim_err("replay"))?;
        // Significance of each fully fitted candidate.
        let mut sig: Vec<(usize, f64, usize)> = Vec::new(); // (index in top, cost, index in candidates)
        let first = candidates.len();
        for (t, outcome) in full.iter().enumerate() {
            let i = pool[top[t]];
            let e = catalogue[i];
            let (o, _) = match outcome {
                Ok(fitted) => fitted,
                Err(err) => {
                    // Listed with the score test's estimate and why the fit stopped, not left out.
                    let mut c = ctx.candidate(e, &quick[top[t]], false, resolution[i]);
                    c.rejected_because = Some(format!("the fit failed: {err}"));
                    candidates.push(c);
                    continue;
                }
            };
            let mut c = ctx.candidate(e, o, true, resolution[i]);
            c.held_out_share =
                super::residual::held_out_share(&r, &o.residual, &w.case.segments, w.case.len());
            c.rejected_because = rejection(&c, e, o, base_cost, opts, &masks[i]);
            if c.rejected_because.is_none() {
                sig.push((t, o.cost_after, candidates.len()));
            }
            candidates.push(c);
        }
        let passed: Vec<usize> = sig.iter().map(|&(t, _, _)| t).collect();
        sig.retain(|&(_, _, ci)| {
            let reason = beaten_within_resolution(&candidates[first..], &candidates[ci]);
            let keep = reason.is_none();
            candidates[ci].rejected_because = reason;
            keep
        });
        let top_exts: Vec<&dyn Extension> = top.iter().map(|&j| catalogue[pool[j]]).collect();
        sig.sort_by(|a, b| a.1.total_cmp(&b.1));
        let Some(&(best, best_cost, best_ci)) = sig.first() else {
            if widen_now {
                (widen, widened) = (true, true);
                continue;
            }
            break;
        };
        let Ok((best_fit, best_active)) = &full[best] else {
            break;
        };
        let others: Vec<(usize, f64)> = sig.iter().map(|&(t, c, _)| (t, c)).collect();
        // A significant candidate with which the chosen one's parameter is no longer determined (Cramér–Rao σ
        // from the information after that candidate and the offsets, above a third of the resolution).
        let ib = pool[top[best]];
        let inseparable: Vec<bool> = (0..top.len())
            .map(|t| {
                let it = pool[top[t]];
                let info = profiled_information(&sens[ib], &[sens[it].clone()], &masks[ib]);
                let determined = 3.0 / info.sqrt() <= resolution[ib]; // false for a NaN bound too
                t != best && !determined
            })
            .collect();
        let ambiguous_with = ambiguity(
            best,
            best_fit,
            best_cost,
            &others,
            &full,
            &top_exts,
            &inseparable,
            opts,
        );
        // Accept: the joint fit updates the values of the effects already selected.
        let before = (selected.clone(), named.clone(), base_cost);
        adopt(&mut selected, best_active.clone());
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
        let state = Replacement {
            selected: &mut selected,
            named: &mut named,
            candidates: &mut candidates,
            cost: &mut base_cost,
            round,
        };
        let settled = settle(
            &mut workers[0],
            &w,
            progress,
            state,
            &best_fit.sensitivities,
            |_| false,
        )
        .and_then(|()| match (&vw, valid_cost) {
            // The validation record only reports the gain of the accepted effects.
            (Some(vw), Some(_)) => residuals(&mut workers[0], vw, &selected)
                .map(|r| Some(crate::signal::sum_sq(&r)))
                .map_err(sim_err("validation replay")),
            _ => Ok(None),
        });
        match settled {
            Ok(after) => {
                let key = |t: usize| top_exts[t].key();
                let seconds = sig.iter().skip(1).map(|&(t, _, _)| key(t)).collect();
                runner_ups.push((key(best), seconds));
                let others = passed.iter().filter(|&&t| t != best).map(|&t| key(t));
                alternatives.push((key(best), others.collect()));
                if let (Some(after), Some(before)) = (after, valid_cost) {
                    candidates[best_ci].validation_gain = Some(1.0 - after / before);
                    valid_cost = Some(after);
                }
            }
            // The coarse fit trimmed, but the model with the candidate cannot trim at the replay's rate or at the
            // validation record's initial condition: a model the records cannot be replayed with is not named.
            Err(DiagnoseError::Sim {
                source: crate::sim::SimError::TrimFailed(m),
                ..
            }) => {
                (selected, named, base_cost) = before;
                candidates[best_ci].rejected_because = Some(format!(
                    "the model with it cannot trim at the records' initial conditions ({m})"
                ));
                untrimmable.push(ib);
            }
            Err(e) => return Err(e),
        }
    }
    let mut refiner = Refiner {
        workers,
        w: &w,
        catalogue: &catalogue,
        resolution: &resolution,
        masks: &masks,
        opts,
        progress,
    };
    let rounds = named.len();
    let mut state = Replacement {
        selected: &mut selected,
        named: &mut named,
        candidates: &mut candidates,
        cost: &mut base_cost,
        round: rounds,
    };
    // A runner-up lost its round to the model of that round; it is worth another fit only when an effect named
    // in a later round is still in the model.
    let in_model = |k: &String| state.selected.iter().any(|s| s.ext.key() == *k);
    let later_in_model: Vec<(String, Vec<String>)> = (0..runner_ups.len())
        .filter(|&m| runner_ups[m + 1..].iter().any(|(k, _)| in_model(k)))
        .map(|m| runner_ups[m].clone())
        .collect();
    replace_ambiguous(
        &mut refiner,
        Some(&sens),
        &later_in_model,
        state.reborrow(),
        |_| false,
    )?;
    if opts.backward_elimination {
        state.round += 1;
        eliminate_backward(&mut refiner, state, "backward elimination", false, |_| {
            false
        })?;
    }
    Ok(Selection {
        selected,
        named,
        candidates,
        unidentifiable,
        undetermined,
        alternatives,
        entries: Entries {
            catalogue,
            resolution,
            masks,
        },
    })
}

/// The significant candidates the data cannot tell apart from the chosen one: nearly the same cost
/// (n_eff ln(J/J_best) < 10) and strongly correlated output sensitivities, or `inseparable` (the record does not
/// determine the chosen one's parameter once this candidate is estimated with it).
#[allow(clippy::too_many_arguments)]
fn ambiguity(
    best: usize,
    best_fit: &FitOutcome,
    best_cost: f64,
    sig: &[(usize, f64)],
    full: &[FullFit],
    exts: &[&dyn Extension],
    inseparable: &[bool],
    opts: &DiagnoseOptions,
) -> Vec<String> {
    let kb = best_fit.values.len() - 1;
    let mut out = Vec::new();
    for &(t, c) in sig {
        if t == best {
            continue;
        }
        let Ok((o, _)) = &full[t] else { continue };
        let rho = super::residual::correlation(
            &best_fit.sensitivities[kb],
            &o.sensitivities[o.values.len() - 1],
        );
        let alike =
            best_fit.n_eff * (c / best_cost).ln() < 10.0 && rho.abs() > opts.ambiguity_correlation;
        if alike || inseparable.get(t).copied().unwrap_or(false) {
            out.push(exts[t].key());
        }
    }
    out
}

#[cfg(test)]
mod tests;
