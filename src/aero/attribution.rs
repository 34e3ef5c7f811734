//! Why an estimate misses the truth: its error attributed term by term.
//!
//! - Transfer-function route ([`attribute_tf_fit`]): the fit is nonlinear in the data, so the attribution is by
//!   experiment. Each simplifying assumption of the structure is released in turn (the omitted term included at
//!   its truth value, e.g. C_Lq and C_Lα̇ in the lift equation), the fit repeated on the same identified transfer
//!   functions, and the error it removes, e₀ − e_released, measured. The identification itself is one more
//!   "term": the fit repeated on JSBSim's own linearization (the transfer functions a perfect identification of
//!   the linearized aircraft would give) removes the identification error.
//! - Equation-error route (`attribute_equation_error`): the least-squares estimate is linear in the response, so
//!   its error splits exactly (Morelli & Klein, *Aircraft System Identification*, 2nd ed., eq. 5.8 and §5.5 on
//!   model-structure bias): with z = X θ + Σ_k ρ_k + ε, ρ_k the part of coefficient function k the regressors do
//!   not carry (its value along the flight minus its linear approximation with the truth derivatives),
//!   θ̂ − θ = Σ_k (XᵀX)⁻¹Xᵀ ρ_k + (XᵀX)⁻¹Xᵀ ε.

use serde::Serialize;

use super::fit::{estimate_derivatives, FitOptions, IdentifiedTfs};
use super::params::{Assumptions, Derivative, Derivatives, ThrustModel};
use super::score::{Scorecard, CMQ_SUM};
use super::spec::full_assumptions;
use super::AeroError;

/// One named cause of an estimate's error and how much of it it accounts for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TermShare {
    /// The term: a coefficient function (`Clr`), an assumption (`paper: no C_Lq, C_Lα̇ in the lift equation`),
    /// `TF identification`, `propulsion`, `noise`, ….
    pub term: String,
    /// Its part of the error, in the derivative's units (the error it removes when released, TF route).
    pub contribution: f64,
    /// contribution / (estimate − truth).
    pub share: f64,
}

/// Error of one estimate (or combination) taken apart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RowAttribution {
    /// Derivative or combination name, as in the scorecard.
    pub name: String,
    /// estimate − truth.
    pub error: f64,
    /// The causes, largest share first.
    pub terms: Vec<TermShare>,
}

impl RowAttribution {
    /// The cause with the largest share of the error (only causes that reduce the error count).
    pub fn main_term(&self) -> Option<&TermShare> {
        self.terms.iter().find(|t| t.share > 0.0)
    }
}

/// The assumptions of a structure that the full model releases, each as (words, assumptions with it
/// released), and the thrust model (constant power, which neither structure uses).
fn releases(base: Assumptions) -> Vec<(String, Assumptions)> {
    let full = full_assumptions();
    let mut out = Vec::new();
    let mut push = |cond: bool, words: &str, a: Assumptions| {
        if cond {
            out.push((words.to_string(), a));
        }
    };
    push(
        base.lift_rate_terms != full.lift_rate_terms,
        "structure: no C_Lq, C_Lα̇ in the lift equation",
        Assumptions {
            lift_rate_terms: full.lift_rate_terms,
            ..base
        },
    );
    push(
        base.drag_in_z_alpha != full.drag_in_z_alpha,
        "structure: Z_α without C_D",
        Assumptions {
            drag_in_z_alpha: full.drag_in_z_alpha,
            ..base
        },
    );
    push(
        base.side_force_in_wind_axes != full.side_force_in_wind_axes,
        "structure: C_Yβ taken as stability-axis (JSBSim's is wind-axis, −C_D missing)",
        Assumptions {
            side_force_in_wind_axes: full.side_force_in_wind_axes,
            ..base
        },
    );
    push(
        base.side_force_rate_terms != full.side_force_rate_terms,
        "structure: no C_Yp, C_Yr in the side-force equation",
        Assumptions {
            side_force_rate_terms: full.side_force_rate_terms,
            ..base
        },
    );
    push(
        base.level_flight != full.level_flight,
        "structure: γ0 = θ0 = 0 in the gravity terms",
        Assumptions {
            level_flight: full.level_flight,
            ..base
        },
    );
    push(
        base.thrust == ThrustModel::Constant,
        "structure: constant thrust (a propeller's falls with speed)",
        Assumptions {
            thrust: ThrustModel::ConstantPower,
            ..base
        },
    );
    out
}

/// The errors (estimate − truth) of a fit, by scorecard name, with the pitch-damping sum.
fn errors(
    values: &[f64],
    free: &[Derivative],
    truth: &Derivatives,
) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = free
        .iter()
        .zip(values)
        .map(|(&d, v)| (d.name().to_string(), v - truth.get(d)))
        .collect();
    let idx = |d: Derivative| free.iter().position(|&f| f == d);
    if let (Some(q), Some(a)) = (idx(Derivative::Cmq), idx(Derivative::Cmalphadot)) {
        out.push((
            CMQ_SUM.to_string(),
            values[q] + values[a] - truth.get(Derivative::Cmq) - truth.get(Derivative::Cmalphadot),
        ));
    }
    out
}

/// Attributes the errors of a transfer-function fit (module doc): `prior` is the model the fit started from
/// (its assumptions are the structure, its free derivatives the start values), `truth` the derivatives in the
/// same axes, `linearization` the same transfer functions from JSBSim's linearization, if available.
///
/// The parts add up exactly to estimate − truth: with e₀ the error on the identified transfer functions, e_L
/// the error of the same fit on the linearization's, and e_i the error on those after releasing assumptions
/// 1…i cumulatively (in the order of [`releases`]),
/// e₀ = (e₀ − e_L) + Σ_i (e_{i−1} − e_i) + e_last: identification, one share per assumption, and what the
/// fully released model still misses against the linearization. (Sequential release: a term's share can depend
/// on the order when assumptions interact; the one-at-a-time effect is within a few % for these.)
pub fn attribute_tf_fit(
    prior: &super::AeroModel,
    tfs: &IdentifiedTfs,
    linearization: Option<&IdentifiedTfs>,
    free: &[Derivative],
    truth: &Derivatives,
) -> Result<Vec<RowAttribution>, AeroError> {
    let fit = |model: &super::AeroModel, t: &IdentifiedTfs| -> Result<Vec<(String, f64)>, AeroError> {
        let est = estimate_derivatives(model, t, free, FitOptions::default())?;
        Ok(errors(&est.values, free, truth))
    };
    let base = fit(prior, tfs)?;
    // (words, errors after this step); the contribution of a step is previous − this.
    let mut steps: Vec<(String, Vec<(String, f64)>)> = Vec::new();
    let reference = match linearization {
        Some(lin) => {
            let e = fit(prior, lin)?;
            steps.push((
                "TF identification (identified TFs ≠ JSBSim's linearization: nonlinear response, finite record)"
                    .to_string(),
                e,
            ));
            lin
        }
        None => tfs,
    };
    let mut model = prior.clone();
    for (words, a) in releases(prior.assumptions) {
        let mut m = model.clone();
        m.assumptions = Assumptions {
            ..a_merge(m.assumptions, a, prior.assumptions)
        };
        // A released structure that does not fit (e.g. a singular model) is skipped.
        if let Ok(e) = fit(&m, reference) {
            steps.push((words, e));
            model = m;
        }
    }
    let last_words = if linearization.is_some() {
        "model vs JSBSim's linearization with every assumption released (propeller thrust and torque, engine \
         and actuator states the 4-state model lacks)"
    } else {
        "left after releasing every assumption (identification error and unmodelled dynamics)"
    };
    Ok(base
        .iter()
        .map(|(name, e0)| {
            let at = |errs: &[(String, f64)]| {
                errs.iter()
                    .find(|(n, _)| n == name)
                    .map_or(f64::NAN, |x| x.1)
            };
            let mut previous = *e0;
            let mut terms = Vec::new();
            for (words, errs) in &steps {
                let e = at(errs);
                terms.push(TermShare {
                    term: words.clone(),
                    contribution: previous - e,
                    share: if *e0 != 0.0 { (previous - e) / e0 } else { 0.0 },
                });
                previous = e;
            }
            terms.push(TermShare {
                term: last_words.to_string(),
                contribution: previous,
                share: if *e0 != 0.0 { previous / e0 } else { 0.0 },
            });
            terms.sort_by(|a, b| b.share.total_cmp(&a.share));
            RowAttribution {
                name: name.clone(),
                error: *e0,
                terms,
            }
        })
        .collect())
}

/// `current` with the one assumption that `released` changes relative to `base` taken from `released`.
fn a_merge(current: Assumptions, released: Assumptions, base: Assumptions) -> Assumptions {
    let pick = |c: bool, r: bool, b: bool| if r != b { r } else { c };
    Assumptions {
        lift_rate_terms: pick(current.lift_rate_terms, released.lift_rate_terms, base.lift_rate_terms),
        drag_in_z_alpha: pick(current.drag_in_z_alpha, released.drag_in_z_alpha, base.drag_in_z_alpha),
        side_force_in_wind_axes: pick(
            current.side_force_in_wind_axes,
            released.side_force_in_wind_axes,
            base.side_force_in_wind_axes,
        ),
        side_force_rate_terms: pick(
            current.side_force_rate_terms,
            released.side_force_rate_terms,
            base.side_force_rate_terms,
        ),
        elevator_drag_from_polar: pick(
            current.elevator_drag_from_polar,
            released.elevator_drag_from_polar,
            base.elevator_drag_from_polar,
        ),
        thrust: if released.thrust != base.thrust {
            released.thrust
        } else {
            current.thrust
        },
        ixz_coupling: pick(current.ixz_coupling, released.ixz_coupling, base.ixz_coupling),
        level_flight: pick(current.level_flight, released.level_flight, base.level_flight),
    }
}

/// Writes the attribution into a scorecard: every row keeps its causes, and a row whose 3σ interval misses the
/// truth (or that misses its target) says "not covered because of <term> (<share> of the error)".
pub fn apply(card: &mut Scorecard, attributions: &[RowAttribution]) {
    for r in &mut card.rows {
        let Some(a) = attributions.iter().find(|a| a.name == r.name) else {
            continue;
        };
        r.attribution = a.terms.clone();
        let missed = r.covered_3sigma == Some(false) || r.meets_target() == Some(false);
        if !missed {
            continue;
        }
        let what = if r.covered_3sigma == Some(false) {
            "not covered by 3σ"
        } else {
            "misses its target"
        };
        r.note = match a.main_term() {
            Some(t) => {
                let others: Vec<String> = a
                    .terms
                    .iter()
                    .skip_while(|x| !std::ptr::eq(*x, t))
                    .skip(1)
                    .filter(|x| x.share >= 0.1)
                    .take(2)
                    .map(|x| format!("{} ({:.0} %)", x.term, 100.0 * x.share))
                    .collect();
                format!(
                    "{what} because of {} ({:.0} % of the error){}",
                    t.term,
                    100.0 * t.share,
                    if others.is_empty() {
                        String::new()
                    } else {
                        format!("; also {}", others.join(", "))
                    }
                )
            }
            None => format!(
                "{what}: no single term examined reduces the error ({}); the rest is nonlinearity of the \
                 identified response",
                r.note
            ),
        };
    }
}
