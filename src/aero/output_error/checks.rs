//! Structure checks of an output-error fit: each refits the adopted structure with a few more parameters
//! free (the vane skews, the α̇ terms, the speed derivatives) and adopts the wider fit only on evidence — a
//! likelihood-ratio test (Klein & Morelli §5.4), significant parameters, a converged fit that keeps the key
//! derivatives plausible — and the process-noise check, which refits by filter error and says when output
//! error was the wrong method for the records.

use super::{fit_lateral, fit_longitudinal, AxisFit, FitSetup, FreeChoice, OutputErrorOptions};
use crate::aero::flight_models::{LATERAL_PARAMETERS, LONGITUDINAL_PARAMETERS};
use crate::aero::measured::{advanced, MeasuredError};
use crate::data::{self, Channel};
use crate::estimate::{self, Method};

/// A wider fit of an axis: `names` freed on top of the options' choices. Returns the fit, the fall
/// in cost from `held` (J is the negative log-likelihood, so 2 ΔJ is the likelihood-ratio statistic, Klein &
/// Morelli §5.4), whether it converged to an interior optimum, and whether the user named any of `names` in
/// `--free` (then a check only reports). `None` when the wider fit fails.
struct Wider {
    fit: AxisFit,
    drop: f64,
    /// Converged, with no parameter pushed onto a bound ([`drove_onto_bound`]).
    interior: bool,
    user_chose: bool,
}

fn wider_fit(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
    names: &[&'static str],
) -> Option<Wider> {
    let options = setup.options;
    let user_chose = options
        .free
        .iter()
        .any(|c| c.names.iter().any(|n| names.contains(n)));
    let mut wider = options.clone();
    wider.free.push(FreeChoice {
        names: names.to_vec(),
        free: true,
    });
    let mut wider_notes = Vec::new();
    let wider_setup = FitSetup {
        options: &wider,
        ..setup
    };
    let lateral = held.estimate.parameter("Cn_beta").is_some();
    let fit = if lateral {
        fit_lateral(records, wider_setup, &mut wider_notes).ok()?
    } else {
        fit_longitudinal(records, wider_setup, &mut wider_notes).ok()?
    };
    let drop = held.estimate.cost - fit.estimate.cost;
    let interior = fit.estimate.stop == estimate::StopReason::Converged
        && !drove_onto_bound(&held.estimate, &fit.estimate);
    Some(Wider {
        fit,
        drop,
        interior,
        user_chose,
    })
}

/// Whether the wider fit left on a bound a parameter that the held fit estimated off it (the rotary gust's
/// gain, a vane skew). The new terms then buy their fall in cost by pushing another parameter as far as it may
/// go: the model with them does not describe the records better, it trades one misfit for another, and at a
/// bound neither the likelihood-ratio test nor the Cramér–Rao σ holds (Klein & Morelli §5.4 and §6.5 assume an
/// interior optimum). On the JSBSim global5000 in light turbulence (`derivatives_eval --aircraft global5000`,
/// seed 1) filter error's α̇ check adopted C_mα̇ −14.6 ± 2.2 (JSBSim −6) with k_q driven from 0.67 to its bound
/// 1.5, and C_mq came out 44 % off and outside 3σ; output error found C_mα̇ not significant on the same records.
pub(super) fn drove_onto_bound(held: &estimate::Estimate, wider: &estimate::Estimate) -> bool {
    wider.parameters.iter().any(|w| {
        w.at_bound
            && held
                .parameter(&w.name)
                .is_some_and(|h| !h.fixed && !h.at_bound)
    })
}

/// The speed derivatives.
pub(super) const SPEED: [&str; 3] = ["CL_V", "CD_V", "Cm_V"];

/// The α̇ terms the α̇ check frees: C_mα̇, with C_Lq. Not C_Lα̇: with the accelerometer measuring the whole
/// lift, α̇ = q − q̄S C_L/(mV) + g cos γ/V turns the lift equation into C_L (1 + ρSc̄ C_Lα̇/(4m)) = C_L0 +
/// C_Lα α + (C_Lq + C_Lα̇) q̂ + …, so the records fix C_Lq + C_Lα̇ and their split only rescales every lift
/// derivative, with nothing but gravity's small share of γ̇ to pin it (Klein & Morelli §3.5). Output error
/// holds C_Lα̇ at 0: freed, it ran off to −216…−6 over five c310 gust realisations (truth 5.1) and scaled C_Lα
/// by up to 0.3; held, it biases the lift derivatives by ρSc̄ C_Lα̇/(4m), 1.6 % on the c310. Filter error
/// ties it to C_Lq by the tail's ratio, C_Lα̇ = C_Lq C_mα̇/C_mq (`lift_alphadot_tied` in the parent module):
/// freeing C_Lα̇ instead of C_Lq put C_Lα +4…+6 % off on all five c310 seeds (σ 0.8 %), freeing all three
/// ran off on two of five, and C_Lq alone left C_Lα −1.8 % and C_mq, C_mδe up to 12 % off; tied, C_Lα, C_mq
/// and C_mδe are within 2 % on all five (C_mα 3.8 %).
pub(super) const ALPHADOT: [&str; 2] = ["Cm_alphadot", "CL_q"];

/// The fit of one axis ([`fit_longitudinal`], [`fit_lateral`]).
pub(super) type AxisFitter = fn(
    &[&(String, data::FlightRecord)],
    FitSetup,
    &mut Vec<String>,
) -> Result<AxisFit, MeasuredError>;

/// A structure check: the note and, when the records support it, the wider fit to adopt.
pub(super) type Check =
    fn(&[&(String, data::FlightRecord)], FitSetup, &AxisFit) -> Option<(String, Option<AxisFit>)>;

/// A structure check of the forward selection: the check, the parameters its adopted fit frees, and those
/// whose significance is its evidence (the α̇ check frees C_Lq beside C_mα̇ but rests on C_mα̇).
pub(super) struct StructureCheck {
    pub run: Check,
    pub frees: &'static [&'static str],
    pub tested: &'static [&'static str],
}

/// Runs the structure checks by forward selection (Klein & Morelli §5.4, stepwise): every check still pending
/// is tried from the current structure, the one whose wider fit it adopts lowers the cost most is taken (its
/// fit replaces `f`, its parameters are freed in the options returned), and the others are tried again from
/// there, until none adopts. Each check's note, from its last trial, goes into `notes`, in the checks' order.
/// A fixed order let a weaker widening tried first take the shape of a stronger one: on gusty HFB-320
/// records, whose model has no α̇ terms, C_mα̇ (the cost falls by 187) was adopted before the speed
/// derivatives (569), which the records carry.
///
/// A widening that the records cannot tell from one adopted before it is not taken ([`confounded`]): on
/// noise-free c310 records C_mα̇ was adopted first (−12.8 ± 0.3, JSBSim −12.7; the cost fell by 12 700), and
/// the speed derivatives adopted after it (3 200) left C_mα̇ at +22 ± 10, with C_mq 42 % and C_mα 51 % off;
/// refused, C_mq and C_mα are within 1.1 %.
pub(super) fn run_checks(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    f: &mut AxisFit,
    checks: &[StructureCheck],
    notes: &mut Vec<String>,
) -> OutputErrorOptions {
    let mut options = setup.options.clone();
    let mut last_notes: Vec<Option<String>> = vec![None; checks.len()];
    let mut pending: Vec<usize> = (0..checks.len()).collect();
    let mut adopted: Vec<usize> = Vec::new();
    loop {
        let mut best: Option<(usize, AxisFit)> = None;
        for &i in &pending {
            let setup = FitSetup {
                options: &options,
                ..setup
            };
            let Some((note, wider)) = (checks[i].run)(records, setup, f) else {
                continue;
            };
            let wider = match wider {
                Some(w) => match confounded(f, &w, checks, &adopted, checks[i].frees) {
                    Some(lost) => {
                        last_notes[i] = Some(format!(
                            "{note}; overruled: {lost}, so the records cannot tell the two apart and the one \
                             adopted first (the larger fall in cost) stays alone"
                        ));
                        continue;
                    }
                    None => w,
                },
                None => {
                    last_notes[i] = Some(note);
                    continue;
                }
            };
            last_notes[i] = Some(note);
            if best
                .as_ref()
                .is_none_or(|(_, b)| wider.estimate.cost < b.estimate.cost)
            {
                best = Some((i, wider));
            }
        }
        let Some((i, wider)) = best else {
            break;
        };
        *f = wider;
        options.free.push(FreeChoice {
            names: checks[i].frees.to_vec(),
            free: true,
        });
        pending.retain(|&j| j != i);
        adopted.push(i);
    }
    notes.extend(last_notes.into_iter().flatten());
    options
}

/// Largest |t| of `names` in `fit` (0 when none is free).
fn largest_t(fit: &AxisFit, names: &[&str]) -> f64 {
    names
        .iter()
        .filter_map(|n| fit.estimate.parameter(n))
        .filter(|p| !p.fixed)
        .map(|p| (p.value / p.std_error.max(f64::MIN_POSITIVE)).abs())
        .fold(0.0, f64::max)
}

/// Whether the wider fit of a candidate check takes away the evidence of a check adopted before it: a
/// group significant in `held` (|t| > 3) that is not significant in `wider`, or whose leading parameter
/// changes sign. Groups the candidate frees itself are its own business (the side-force check frees τ_β
/// with C_Yp and C_Yr). Returns what was lost, for the note.
fn confounded(
    held: &AxisFit,
    wider: &AxisFit,
    checks: &[StructureCheck],
    adopted: &[usize],
    frees: &[&str],
) -> Option<String> {
    adopted
        .iter()
        .map(|&j| checks[j].tested)
        .filter(|tested| !tested.iter().any(|n| frees.contains(n)))
        .find_map(|tested| {
            let (before, after) = (largest_t(held, tested), largest_t(wider, tested));
            let lead = tested[0];
            let value = |fit: &AxisFit| fit.estimate.parameter(lead).map_or(0.0, |p| p.value);
            let flipped = value(held) * value(wider) < 0.0;
            (before > 3.0 && (after < 3.0 || flipped)).then(|| {
                format!(
                    "with them free {lead} (adopted before, |t| {before:.1}) goes to {:.3} (|t| {after:.1})",
                    value(wider)
                )
            })
        })
}

/// Whether a wider fit keeps the key derivatives of the held one plausible (C_mα, C_mq, C_mδe; C_lp, C_lβ,
/// C_nr, C_nβ): the same signs, and within a factor of three. A wider fit that runs off into another minimum
/// (a positive C_mq, a C_mα twenty times the held one) is not adopted, whatever its cost.
fn key_derivatives_plausible(held: &AxisFit, wider: &AxisFit) -> bool {
    // the lateral axis's damping and stiffness derivatives are held to the same rule
    [
        "Cm_alpha", "Cm_q", "Cm_de", "Cl_p", "Cl_beta", "Cn_r", "Cn_beta",
    ]
    .iter()
    .all(
        |n| match (held.estimate.parameter(n), wider.estimate.parameter(n)) {
            (Some(a), Some(b)) => {
                let ratio = b.value / a.value;
                ratio > 1.0 / 3.0 && ratio < 3.0
            }
            _ => true,
        },
    )
}

/// The α vane's time skew.
pub(super) const SKEW: [&str; 1] = ["tau_alpha_s"];

/// The β vane's time skew.
pub(super) const BETA_SKEW: [&str; 1] = ["tau_beta_s"];

/// χ²₁ at 1 %: the likelihood-ratio threshold of a one-parameter widening.
const CHI2_1_1PCT: f64 = 6.63;

/// χ²₂ at 1 %: the likelihood-ratio threshold of a two-parameter widening.
const CHI2_2_1PCT: f64 = 9.21;

/// χ²₃ at 1 %: the likelihood-ratio threshold of a three-parameter widening.
const CHI2_3_1PCT: f64 = 11.34;

/// When the speed derivatives were held by default: the same fit with C_LV, C_DV and C_mV free (Jategaonkar
/// §4.11's HFB-320 model; Klein & Morelli §3.5). A record that excites the phugoid carries them, and holding
/// them at 0 then puts the speed's share of the pitching moment and lift into C_mq, C_mδe and C_Lα (on the
/// HFB-320 flight record C_mq came out half the published value). Adopted when the likelihood-ratio test
/// passes at 1 % (2 ΔJ > χ²₃ = 11.34), at least one of them is significant (|t| > 3), the wider fit converged,
/// and the short-period derivatives it brings stay within the held fit's own plausible range: C_mα, C_mq and
/// C_mδe keep their signs and move by less than a factor of three (a wider fit that runs off into another
/// minimum does not). When the user named them in `--free`, the check only reports.
pub(super) fn speed_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    let g = group_check(records, setup, held, &SPEED, &SPEED)?;
    let verdict = g.verdict(
        "the records carry them (the phugoid is excited): C_LV, C_DV and C_mV are estimated (hold them with \
         --free=-speed)",
        "the wider fit is not trusted (it did not converge, drove another parameter onto its bound, or moved \
         C_mα, C_mq or C_mδe off their range): the speed derivatives stay held",
        "not significant: the speed derivatives stay held",
    );
    let note = format!(
        "longitudinal: with C_LV, C_DV, C_mV free the cost falls by {:.1} (largest |t| {:.1}): {verdict}",
        g.wider.drop, g.t_max
    );
    Some((note, g.adopted()))
}

/// The curvature terms of C_L and C_m in α.
pub(super) const CURVATURE: [&str; 2] = ["CL_alpha2", "Cm_alpha2"];

/// When the curvature terms were held by default (after the speed check, from the structure it adopted): the
/// same fit with C_Lα² and C_mα² free (C = … + C_α² (α − α₀)², α₀ the records' mean α; the flight_models
/// module doc; Klein & Morelli §5.4: a term enters the model on the evidence of the data). A static
/// coefficient that curves over the range a maneuver flies leaves, in a linear model, a residual quadratic in
/// α − α₀, which correlates with q̂ and goes partly into C_mq: the JSBSim p51d's tables give C_mq 6 % low
/// (in magnitude) from the aero moment alone, with C_m(α) steepening from −0.26 to −0.45 per rad over the
/// 6° flown. Adopted by the speed check's rule: 2 ΔJ > χ²₂(1 %) = 9.21, |t| > 3 for one of them, a
/// converged wider fit, C_mα, C_mq, C_mδe in range. With them free, C_Lα and C_mα are the slopes at α₀.
/// When the user named them in `--free`, the check only reports.
///
/// Output error only, like the α̇ check that runs before it: by filter error the α̇ terms stay held, and on
/// the c310 records (linear C_m, α̇ terms in its model) the curvature then took their place (C_mα² −9 ± 1.7,
/// |t| 5–6, adopted on four seeds of five); on the p51d's the wider filter-error fit ended above the held
/// fit's cost on three seeds of five (ΔJ −3000: it did not reach the optimum). `--free curvature` frees them
/// for filter error.
pub(super) fn curvature_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    if setup.options.method != Method::Oe {
        return None;
    }
    let g = group_check(records, setup, held, &CURVATURE, &CURVATURE)?;
    let value = |n: &str| {
        g.wider
            .fit
            .estimate
            .parameter(n)
            .map_or((f64::NAN, f64::NAN), |p| (p.value, p.std_error))
    };
    let ((cl2, cl2_sd), (cm2, cm2_sd)) = (value("CL_alpha2"), value("Cm_alpha2"));
    let verdict = g.verdict(
        "the coefficients curve over the α flown: C_Lα² and C_mα² are estimated, C_Lα and C_mα are the slopes \
         at the records' mean α (hold them with --free=-curvature)",
        "the wider fit is not trusted (it did not converge, drove another parameter onto its bound, or moved \
         C_mα, C_mq or C_mδe off their range): the curvature terms stay held",
        "not significant: the curvature terms stay held",
    );
    let note = format!(
        "longitudinal: with C_Lα², C_mα² free the cost falls by {:.1} (C_Lα² = {cl2:.2} ± {cl2_sd:.2}, C_mα² = \
         {cm2:.3} ± {cm2_sd:.3}, largest |t| {:.1}): {verdict}",
        g.wider.drop, g.t_max
    );
    Some((note, g.adopted()))
}

/// The side-force rate derivatives.
const SIDE_RATES: [&str; 2] = ["CY_p", "CY_r"];

/// What the side-force check frees: the rate derivatives with the β vane's skew, which takes their shape.
pub(super) const SIDE_RATES_AND_SKEW: [&str; 3] = ["CY_p", "CY_r", "tau_beta_s"];

/// When C_Yp and C_Yr were held by default (at 0): the same fit with them free. A fin high and far aft gives
/// C_Yr (the c310's JSBSim model: 0.21); held at 0, the r-shaped share of the side force that the lateral
/// accelerometer measures (a_y = q̄S C_Y/m, Klein & Morelli §3.2) leads β by a quarter period of the Dutch
/// roll, which the β vane's skew absorbs: filter error on the generated c310 records asked for 49–52 ms (the
/// data system's is 30 ms, refused or adopted seed by seed) and C_nr scattered by 6 % between seeds. The
/// reverse holds too (with τ_β held, C_Yr takes a 30 ms skew for itself), so the wider fit frees τ_β with them,
/// and is adopted by the speed check's rule on C_Yp and C_Yr — the likelihood-ratio test at 1 %, at least one
/// of them with |t| > 3, a converged wider fit, C_lp, C_lβ, C_nr, C_nβ in range — and a τ_β within the skew
/// bound ([`data::skew_bound_s`]). When the user named C_Yp or C_Yr in `--free`, the check only reports.
pub(super) fn side_force_rate_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    let mut g = group_check(records, setup, held, &SIDE_RATES, &SIDE_RATES_AND_SKEW)?;
    let bound_s = skew_bound_of(records);
    let skew_ok = g
        .wider
        .fit
        .estimate
        .parameter("tau_beta_s")
        .is_none_or(|p| p.value.abs() <= bound_s);
    g.trusted &= skew_ok;
    g.supported &= skew_ok;
    g.wider.user_chose = setup
        .options
        .free
        .iter()
        .any(|c| c.names.iter().any(|n| SIDE_RATES.contains(n)));
    let verdict = g.verdict(
        "the records carry them: C_Yp and C_Yr are estimated (hold them with --free=-CY_p,-CY_r)",
        "the wider fit is not trusted (it did not converge, drove another parameter onto its bound, moved C_lp, \
         C_lβ, C_nr or C_nβ off their range, or wants a β skew beyond the bound): they stay held",
        "not significant: they stay held",
    );
    let note = format!(
        "lateral: with C_Yp, C_Yr (and τ_β) free the cost falls by {:.1} (largest |t| {:.1}): {verdict}",
        g.wider.drop, g.t_max
    );
    Some((note, g.adopted()))
}

/// The outcome of freeing a group of derivatives held by default ([`group_check`]).
struct GroupCheck {
    wider: Wider,
    /// Largest |t| among the group.
    t_max: f64,
    /// The wider fit converged and kept the key derivatives in range.
    trusted: bool,
    /// The records support the group (and the fit is trusted).
    supported: bool,
}

impl GroupCheck {
    /// The note's verdict: `adopted`, `untrusted` or `not_significant`, or that `--free` holds them.
    fn verdict(
        &self,
        adopted: &'static str,
        untrusted: &'static str,
        not_significant: &'static str,
    ) -> &'static str {
        if self.supported && self.wider.user_chose {
            "the records carry them; held as --free asks"
        } else if self.supported {
            adopted
        } else if !self.trusted {
            untrusted
        } else {
            not_significant
        }
    }

    /// The wider fit when it is adopted (supported, and not a choice the user made with `--free`).
    fn adopted(self) -> Option<AxisFit> {
        (self.supported && !self.wider.user_chose).then_some(self.wider.fit)
    }
}

/// The rule of the speed and side-force checks: when the group `tested` is held, the fit with `freed` (the
/// group and what takes its shape) free is supported when the likelihood-ratio test passes at 1 % (2 ΔJ > χ²
/// of the number of parameters it frees), at least one of `tested` is significant (|t| > 3), the wider fit
/// converged and the key derivatives stay in range ([`key_derivatives_plausible`]).
fn group_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
    tested: &[&'static str],
    freed: &[&'static str],
) -> Option<GroupCheck> {
    if !held.estimate.parameter(tested[0]).is_some_and(|p| p.fixed) {
        return None;
    }
    let wider = wider_fit(records, setup, held, freed)?;
    let newly_free = freed
        .iter()
        .filter(|n| held.estimate.parameter(n).is_some_and(|p| p.fixed))
        .count();
    // χ² at 1 % for 1, 2, 3 degrees of freedom
    let chi2 = [CHI2_1_1PCT, CHI2_2_1PCT, CHI2_3_1PCT][newly_free.clamp(1, 3) - 1];
    let t_max = largest_t(&wider.fit, tested);
    let trusted = wider.interior && key_derivatives_plausible(held, &wider.fit);
    let supported = 2.0 * wider.drop > chi2 && t_max > 3.0 && trusted;
    Some(GroupCheck {
        wider,
        t_max,
        trusted,
        supported,
    })
}

/// When the α vane's time skew was held by default: the same fit with τ_α free (α_vane = α − τ_α α̇). A skew
/// is a property of the data system, but from a maneuver it is told apart from the α̇ and q̂ terms only by
/// the likelihood, so it is adopted, like them, on evidence: the likelihood-ratio test at 1 % (2 ΔJ > χ²₁ =
/// 6.63), |t| > 3, a converged wider fit, C_mα, C_mq, C_mδe in range ([`key_derivatives_plausible`]) —
/// and a skew within [`data::skew_bound_s`] (one sample interval, at least 50 ms). A longer apparent lag is
/// something the model does not describe: on the HFB-320 flight record (10 Hz, light turbulence) the fit
/// wants 0.24 s, the flight-path reconstruction 0.22 s, and taking it moves C_mα and C_mq by 20 % off the
/// book's values; the book's model has no skew, and records generated in
/// gusts without a skew show none. When the user named it in `--free`, the check only reports.
pub(super) fn skew_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    let (name, vane) = VANE_SKEWS[0];
    vane_skew_check(records, setup, held, name, vane)
}

/// The same check for the β vane's skew τ_β on the lateral axis (β_vane = β + … − τ_β β̇): on the ATTAS
/// flight records of Jategaonkar's book (25 Hz, aileron and rudder doublets in light turbulence) the fits
/// want 71–96 ms, beyond the 40 ms sample interval, and taking it put C_nr −0.08 against −0.22 without it
/// (equation error −0.23, the book's output error about −0.26).
pub(super) fn beta_skew_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    let (name, vane) = VANE_SKEWS[1];
    vane_skew_check(records, setup, held, name, vane)
}

/// The longest skew a data system can have on any of `records` ([`data::skew_bound_s`]).
fn skew_bound_of(records: &[&(String, data::FlightRecord)]) -> f64 {
    records
        .iter()
        .map(|(_, r)| data::skew_bound_s(r))
        .fold(0.0, f64::max)
}

/// The skew check of the vane measuring `vane` (its skew parameter `name`); see [`skew_check`].
fn vane_skew_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
    name: &'static str,
    vane: Channel,
) -> Option<(String, Option<AxisFit>)> {
    let held_skew = held.estimate.parameter(name)?;
    if !held_skew.fixed || !records.iter().all(|(_, r)| r.column(vane).is_some()) {
        return None;
    }
    let w = wider_fit(records, setup, held, &[name])?;
    let p = w.fit.estimate.parameter(name)?;
    let t = (p.value / p.std_error.max(f64::MIN_POSITIVE)).abs();
    let plausible = key_derivatives_plausible(held, &w.fit);
    let bound_s = skew_bound_of(records);
    let within = p.value.abs() <= bound_s;
    let supported = 2.0 * w.drop > CHI2_1_1PCT && t > 3.0 && w.interior && plausible && within;
    let beyond = format!(
        "longer than a data system's skew can be (one sample interval, {:.0} ms): the lag of something the \
         model does not describe (gusts the vane reads, a filter); held — free it with --free skew if the vane \
         really lags",
        1000.0 * bound_s
    );
    let verdict = if supported && w.user_chose {
        "supported; held as --free asks"
    } else if supported {
        "supported: estimated (hold it with --free=-skew)"
    } else if 2.0 * w.drop > CHI2_1_1PCT && t > 3.0 && !within {
        beyond.as_str()
    } else if !w.interior || !plausible {
        "the wider fit is not trusted (it did not converge, drove another parameter onto its bound, or moved \
         C_mα, C_mq or C_mδe off their range): held"
    } else {
        "not significant: held"
    };
    let (axis, angle, symbol) = if vane == Channel::Alpha {
        ("longitudinal", "α", "τ_α")
    } else {
        ("lateral", "β", "τ_β")
    };
    let note = format!(
        "{axis}: with the {angle} vane's time skew free the cost falls by {:.1} and {symbol} = {:.1} ± {:.1} ms: \
         {verdict}",
        w.drop,
        1000.0 * p.value,
        1000.0 * p.std_error
    );
    Some((note, (supported && !w.user_chose).then_some(w.fit)))
}

/// When the α̇ terms were held by default: the same fit with C_mα̇ and C_Lq free ([`ALPHADOT`]; C_Lα̇ stays held by
/// output error and follows C_Lq by the tail's ratio in filter error). Downwash lag at a tail behind the wing makes
/// C_mα̇ negative (Etkin & Reid §5.4; Klein & Morelli §3.5). The wider fit is adopted when C_mα̇ is negative and
/// significant (|t| > 3) and the likelihood-ratio test passes at 1 % (2 ΔJ > χ²₂ = 9.21, Klein & Morelli §5.4; J is
/// the negative log-likelihood); a positive value is another unmodelled effect taking the α̇ shape, and the terms
/// stay held. Without an α vane, or when the wider fit does not converge, it only reports. When the user named the
/// α̇ terms in `--free`, the check only reports. Returns the note and the adopted fit. Output error and filter
/// error alike: with a vane skew taken off the data ([`skew_taken_off`]) filter error finds the c310's −13.7 ± 1.9
/// in light turbulence on seed 2 (JSBSim: −12.7; −13.7…−20.4 on seeds 1–5, with C_Lα̇ tied) and the 737's −14.3 ±
/// 0.9 (−16, with C_Lα̇ free instead of C_Lq); those are the values after the deskewed refit, the check's own wider
/// fit, with the skew term, says more (c310 −18.2 on seed 2).
pub(super) fn alphadot_check(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    held: &AxisFit,
) -> Option<(String, Option<AxisFit>)> {
    if !held
        .estimate
        .parameter("Cm_alphadot")
        .is_some_and(|p| p.fixed)
    {
        return None;
    }
    let w = wider_fit(records, setup, held, &ALPHADOT)?;
    let p = w.fit.estimate.parameter("Cm_alphadot")?;
    let t = p.value / p.std_error.max(f64::MIN_POSITIVE);
    // without an α vane the split between α̇ and q rests on the accelerometer alone: report, never adopt
    let vane = records
        .iter()
        .all(|(_, r)| r.column(Channel::Alpha).is_some());
    let converged = w.interior && key_derivatives_plausible(held, &w.fit);
    let supported =
        p.value < 0.0 && t.abs() > 3.0 && 2.0 * w.drop > CHI2_2_1PCT && vane && converged;
    let partner = if setup.options.method == Method::Fem {
        "C_Lq (C_Lα̇ = C_Lq C_mα̇/C_mq)"
    } else {
        "C_Lq"
    };
    let adopted = format!(
        "negative, as downwash lag at a tail behind the wing makes it: C_mα̇ and {partner} are estimated (hold \
         them with --free -alphadot,-CL_q)"
    );
    let verdict = if supported && w.user_chose {
        "negative, as downwash lag at a tail behind the wing makes it; held as --free asks"
    } else if supported {
        adopted.as_str()
    } else if p.value < 0.0 && t.abs() > 3.0 && !(vane && converged) {
        "negative, but the wider fit is not trusted (no α vane, it did not converge, drove another parameter \
         onto its bound, or moved C_mα, C_mq or C_mδe off their range): the α̇ terms stay held"
    } else if p.value > 0.0 {
        "positive, which downwash lag does not produce: another unmodelled effect takes the α̇ shape; the \
         α̇ terms stay held"
    } else {
        "not significant: the α̇ terms stay held"
    };
    // the engineer's choice decides whatever the verdict (the supported case says it already)
    let chosen = if w.user_chose && !supported {
        "; held as --free asks"
    } else {
        ""
    };
    let note = format!(
        "longitudinal: with C_mα̇, {partner} free the cost falls by {:.1} and C_mα̇ = {:.2} ± {:.2}: \
         {verdict}{chosen}",
        w.drop, p.value, p.std_error
    );
    Some((note, (supported && !w.user_chose).then_some(w.fit)))
}

/// χ²₄ at 1 %: the likelihood-ratio threshold of the four process-noise variances of an axis.
const CHI2_4_1PCT: f64 = 13.28;

/// After an output-error fit: the same structure fitted by filter error (`refit` with the method switched).
/// When the process noise lowers the cost significantly (2 ΔJ > χ²₄(1 %) = 13.28; Jategaonkar §5.1: output
/// error assumes none) the record was flown in turbulence or carries motion the model does not describe,
/// output error's estimates are biased where the disturbance correlates with the inputs, and the note says so
/// with the filter-error values of the axis's moment derivatives beside them. On the HFB-320 flight record
/// output error puts C_mq 20 % off the published value, filter error within 1 %.
pub(super) fn process_noise_note(
    axis: &str,
    oe: &AxisFit,
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    refit: AxisFitter,
) -> Option<String> {
    let options = refit_options(oe)?;
    let setup = FitSetup {
        options: &options,
        ..setup
    };
    let fem = refit(records, setup, &mut Vec::new()).ok()?;
    let drop = oe.estimate.cost - fem.estimate.cost;
    if 2.0 * drop <= CHI2_4_1PCT {
        return None;
    }
    // the values as `--method fem` would give them: a skew the fit took taken off the data
    let (fem, _) = skew_taken_off(records, setup, fem, refit).ok()?;
    let moments: Vec<String> = fem
        .estimate
        .parameters
        .iter()
        .filter(|p| {
            !p.fixed
                && (p.name.starts_with("Cm_")
                    || p.name.starts_with("Cl_")
                    || p.name.starts_with("Cn_"))
        })
        .filter(|p| !p.name.ends_with("_0"))
        .map(|p| {
            let was = oe.estimate.parameter(&p.name).map_or(f64::NAN, |q| q.value);
            format!("{} {:.4} (output error {was:.4})", p.name, p.value)
        })
        .collect();
    Some(format!(
        "{axis}: filter error lowers the cost by {drop:.1} (2ΔJ against χ²₄ = {CHI2_4_1PCT}): the records carry \
         process noise (turbulence, or motion the model does not describe) that output error takes for \
         coloured residuals; its estimates are biased where that noise correlates with the inputs. Rerun with \
         --method fem; filter error gives {}",
        moments.join(", ")
    ))
}

/// The vanes whose time skew the longitudinal and lateral models estimate: (parameter, column).
const VANE_SKEWS: [(&str, Channel); 2] = [
    ("tau_alpha_s", Channel::Alpha),
    ("tau_beta_s", Channel::Beta),
];

/// A filter-error fit that estimated a vane's time skew, repeated on the records with that skew taken off the
/// vane's data (α(t) = α_m(t + τ̂), [`advanced`]) and the skew held at 0; any other fit comes back as it is,
/// with no note. The models' skew term (α_vane = α − … − τ α̇) is first order in the model's α̇, which is
/// exact for output error; filter error's α also moves with the process noise, whose share the term leaves
/// unlagged, and the fit makes up for it in the lift and pitch derivatives. On pa28 records with a 30 ms skew
/// (`scripts/gen_foreign_records.py`) filter error with the term put C_Lα 15–17 % and C_mα, C_mδe 9–16 % off;
/// with its own 35 ms estimate taken off the data they come within 1.3 %. A refit that does not converge, or
/// moves the key derivatives off their range ([`key_derivatives_plausible`]), is not taken.
pub(super) fn skew_taken_off(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    fem: AxisFit,
    refit: AxisFitter,
) -> Result<(AxisFit, Option<String>), MeasuredError> {
    let skews: Vec<(&'static str, Channel, f64, f64)> = VANE_SKEWS
        .iter()
        .filter_map(|&(name, vane)| {
            let p = fem.estimate.parameter(name)?;
            (!p.fixed && p.value != 0.0).then_some((name, vane, p.value, p.std_error))
        })
        .collect();
    if fem.estimate.method != Method::Fem || skews.is_empty() {
        return Ok((fem, None));
    }
    let deskewed: Vec<(String, data::FlightRecord)> = records
        .iter()
        .map(|(name, raw)| {
            let mut rec = raw.clone();
            for &(_, vane, tau_s, _) in &skews {
                if let Some(x) = raw.column(vane) {
                    let shifted = advanced(&raw.time_s, x, tau_s);
                    rec.push_column(vane, shifted);
                }
            }
            (name.clone(), rec)
        })
        .collect();
    let refs: Vec<&(String, data::FlightRecord)> = deskewed.iter().collect();
    let mut options = setup.options.clone();
    options.free.push(FreeChoice {
        names: skews.iter().map(|s| s.0).collect(),
        free: false,
    });
    let fit = refit(
        &refs,
        FitSetup {
            options: &options,
            ..setup
        },
        &mut Vec::new(),
    )?;
    let taken: Vec<String> = skews
        .iter()
        .map(|(name, vane, tau_s, sd)| {
            format!(
                "{name} = {:.1} ± {:.1} ms off {}",
                1000.0 * tau_s,
                1000.0 * sd,
                vane.name()
            )
        })
        .collect();
    // a refit that does not converge or runs off into another minimum is not taken (the guard of the checks)
    if fit.estimate.stop != estimate::StopReason::Converged
        || !key_derivatives_plausible(&fem, &fit)
    {
        let note = format!(
            "filter error: the refit with the vane skew taken off the data ({}) did not converge or moved the \
             key derivatives off their range; the model's skew term stays",
            taken.join(", ")
        );
        return Ok((fem, Some(note)));
    }
    let note = format!(
        "filter error: the vane skew it estimated is taken off the data ({}) and the fit repeated with it held: \
         the model's skew term follows only the model's own α̇ (β̇), not the part of the motion the process \
         noise carries",
        taken.join(", ")
    );
    Ok((fit, Some(note)))
}

/// The options of an output-error fit with the method switched to filter error and every choice of the fit
/// kept: the parameters it held stay held, the ones it freed stay free. `None` when `oe` is not output error.
fn refit_options(oe: &AxisFit) -> Option<OutputErrorOptions> {
    if oe.estimate.method != Method::Oe {
        return None;
    }
    let (free, held): (Vec<&'static str>, Vec<&'static str>) = LONGITUDINAL_PARAMETERS
        .iter()
        .chain(LATERAL_PARAMETERS.iter())
        .copied()
        .filter(|n| oe.estimate.parameter(n).is_some())
        .partition(|n| oe.estimate.parameter(n).is_some_and(|p| !p.fixed));
    Some(OutputErrorOptions {
        method: Method::Fem,
        free: vec![
            FreeChoice {
                names: free,
                free: true,
            },
            FreeChoice {
                names: held,
                free: false,
            },
        ],
        alphadot: false,
    })
}
