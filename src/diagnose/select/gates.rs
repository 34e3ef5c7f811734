//! The tests a fully fitted candidate must pass to be named, and the reasons a candidate is turned down.

use super::profiled_information;
use crate::diagnose::extension::Extension;
use crate::diagnose::residual::{cross_validated, segment_halves, HeldOut};
use crate::diagnose::search::FitOutcome;
use crate::diagnose::{Candidate, DiagnoseOptions};

/// The χ² margin a change that the filter error refit adds or keeps must earn on the record's held-out half:
/// the χ²₁ point at 1 % (one parameter, the change's size, sized on the other half).
pub(in crate::diagnose) const HELD_OUT_CHI2: f64 = 6.63;

/// Why a candidate that a later stage adds (output error did not name it) or keeps on other residuals (the
/// filter error refit's backward test) is not confirmed by a split of the training record in time (None: it
/// is, or the split cannot test it). The record is split into the first and
/// the second half of every segment (`residual::segment_halves`); along the fitted change, residual `r_base`
/// (the model without the candidate) to `r_fit` (with it), its size is estimated on one half and the cost it
/// removes on the other is summed over both (two-fold cross-validation; Stone, J. R. Stat. Soc. B 36, 1974),
/// and expressed in the candidate's own significance: χ = z² · (held-out reduction / in-sample reduction),
/// since the in-sample reduction is worth z² in the coloured-residual metric of its standard error. The change
/// must earn [`HELD_OUT_CHI2`] there. `c.held_out_share` is set to that split's share. A half that carries
/// less than a quarter of the change (an input effect whose response lies in each maneuver's first half) is
/// not held out; where neither can be, the candidate passes, as the segments' own hold-out lets pass an effect
/// that one maneuver alone excites.
pub(in crate::diagnose) fn unconfirmed_in_time(
    c: &mut Candidate,
    r_base: &[f64],
    r_fit: &[f64],
    segments: &[usize],
    len: usize,
) -> Option<String> {
    let folds = segment_halves(segments, len);
    let share = cross_validated(r_base, r_fit, &folds, len).and_then(HeldOut::share)?;
    c.held_out_share = Some(share);
    let chi2 = share * c.z * c.z;
    (chi2 <= HELD_OUT_CHI2).then(|| {
        format!(
            "{NOT_HELD_OUT_IN_TIME}: sized on one half of every segment it earns χ² {chi2:.1} ≤ {HELD_OUT_CHI2} \
             on the other (held-out share {share:.2})"
        )
    })
}

/// How many standard errors a named change must stand beyond its resolution ([`beyond_resolution`]).
pub(in crate::diagnose) const RESOLUTION_CONFIDENCE: f64 = 2.0;

/// Whether a fitted change `change` (value − null) with standard error `std_error` exceeds the resolution, the
/// smallest effect worth naming on the record, with confidence: |change| − 2σ ≥ resolution, the one-sided
/// 97.7 % test of "the effect is larger than the resolution" against "it lies within it" (an interval test
/// against a region of practical equivalence; Schuirmann, J. Pharmacokin. Biopharm. 15, 1987, the two
/// one-sided tests turned around). A change just past the resolution whose interval reaches into it is what a
/// gust or a small model error draws (an a_x scale ×0.963 ± 0.007 on a turbulent record whose resolution is
/// 0.03), not an effect the record shows to be there.
/// A σ that is not known (NaN: a sensor bias the filter error refit holds at its output-error value) leaves the
/// value alone to decide, as it did before the interval test.
pub(in crate::diagnose) fn beyond_resolution(change: f64, std_error: f64, resolution: f64) -> bool {
    let sigma = if std_error.is_finite() {
        std_error
    } else {
        0.0
    };
    change.abs() - RESOLUTION_CONFIDENCE * sigma >= resolution
}

/// Why a fully fitted candidate is not significant (None: it is).
pub(in crate::diagnose) fn rejection(
    c: &Candidate,
    e: &dyn Extension,
    o: &FitOutcome,
    base_cost: f64,
    opts: &DiagnoseOptions,
    mask: &[bool],
) -> Option<String> {
    let rel = 1.0 - o.cost_after / base_cost;
    let spec = e.params()[0];
    let resolution = c.resolution;
    let at_bound = (c.value - spec.min).abs() <= 1e-9 * spec.min.abs().max(1.0)
        || (c.value - spec.max).abs() <= 1e-9 * spec.max.abs().max(1.0);
    // Cramér–Rao σ of the candidate with the other free parameters and the sensor offsets as nuisance terms.
    let crb = match o.sensitivities.split_last() {
        Some((s, others)) => {
            let n = s.len() as f64;
            let s2 = o.cost_after / (n - o.values.len() as f64).max(1.0);
            let info = profiled_information(s, others, mask);
            (s2 / info).sqrt()
        }
        None => f64::INFINITY,
    }
    .max(o.crb_std_errors.last().copied().unwrap_or(f64::INFINITY));
    if at_bound {
        // No interior optimum: the effect explains something else (a missing input, another effect).
        Some(format!(
            "value at the bound of its range [{}, {}]",
            spec.min, spec.max
        ))
    } else if !beyond_resolution(c.value - spec.null, c.std_error, resolution) {
        Some(format!(
            "{WITHIN_RESOLUTION} {resolution:.3} of the effect on this record, at {RESOLUTION_CONFIDENCE} \
             standard errors"
        ))
    } else if 3.0 * crb > resolution {
        Some(format!(
            "not determined by the record (Cramér–Rao σ {crb:.3e} after the nuisance terms > a third of \
             the resolution {resolution:.3})"
        ))
    } else if c.criterion_delta >= opts.bic_threshold {
        Some(format!(
            "ΔBIC {:.1} ≥ {}",
            c.criterion_delta, opts.bic_threshold
        ))
    } else if c.z <= opts.min_z {
        Some(format!("{NOT_SIGNIFICANT} {:.1} ≤ {}", c.z, opts.min_z))
    } else if rel <= opts.min_relative_reduction {
        Some(format!("{SMALL_SHARE} {:.1} % of the cost", 100.0 * rel))
    } else {
        // The record's own hold-out: the change fits some maneuvers at the others' expense (a drift, a gust
        // in one segment), and estimated from the other segments it makes each held-out one no better.
        c.held_out_share.filter(|&h| h <= 0.0).map(|share| {
            format!(
                "{NOT_HELD_OUT}: sized from the other segments it removes no cost from the held-out ones \
                 (held-out share {share:.2})"
            )
        })
    }
}

/// Why a significant candidate `c` is not named although it passes its own tests (None: nothing beats it): a
/// fully fitted candidate of the same round whose fitted change is within its own resolution of "no effect"
/// explains the record better (a lower ΔBIC with as many parameters). The record is then explained at least as
/// well by a model that is right within its resolution, and `c` took the place of a mismatch no entry names
/// (a record's input timing, a small error spread over several terms): a derivative whose moment is small
/// reaches a large factor from a small moment error. Among non-nested models with equal parameter counts BIC
/// prefers the lower cost (Schwarz 1978; Burnham & Anderson, Model Selection and Multimodel Inference, §6.4).
pub(in crate::diagnose) fn beaten_within_resolution(
    round: &[Candidate],
    c: &Candidate,
) -> Option<String> {
    let within = |x: &&Candidate| {
        x.full_fit
            && x.rejected_because
                .as_deref()
                .is_some_and(|r| r.starts_with(WITHIN_RESOLUTION))
    };
    let best = round
        .iter()
        .filter(within)
        .min_by(|a, b| a.criterion_delta.total_cmp(&b.criterion_delta))?;
    (best.criterion_delta < c.criterion_delta).then(|| {
        format!(
            "{BEATEN_WITHIN_RESOLUTION}: {} on {} at {:.4}, within its resolution {:.3} of no effect \
             (ΔBIC {:.1} against {:.1})",
            best.effect, best.target, best.value, best.resolution, best.criterion_delta, c.criterion_delta
        )
    })
}

/// The start of the rejection reason of a fitted change within the resolution of "no effect".
pub(in crate::diagnose) const WITHIN_RESOLUTION: &str = "smaller than the resolution";
/// How the reason of a candidate that the coloured-residual significance test turned down starts.
pub(in crate::diagnose) const NOT_SIGNIFICANT: &str = "|z|";
/// How the reason of a candidate that explains too small a share of the cost starts.
pub(in crate::diagnose) const SMALL_SHARE: &str = "explains";
/// Start of the rejection of a change the filter error refit adds that the halves of the segments do not agree on.
pub(in crate::diagnose) const NOT_HELD_OUT_IN_TIME: &str =
    "not confirmed by the held-out half of the record";
/// Start of the rejection of a fit that the record's segments do not agree on.
pub(in crate::diagnose) const NOT_HELD_OUT: &str = "not confirmed by the held-out segments";
/// How the reason of a candidate that passed its own tests but lost to a fit within its resolution starts
/// ([`beaten_within_resolution`]).
pub(in crate::diagnose) const BEATEN_WITHIN_RESOLUTION: &str =
    "a model right within its resolution explains the record better";
