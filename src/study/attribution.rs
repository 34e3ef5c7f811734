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

use std::collections::BTreeMap;

use faer::Mat;
use serde::Serialize;

use crate::aero::fit::{estimate_derivatives, FitOptions, IdentifiedTfs};
use crate::aero::params::{Assumptions, Derivative, Derivatives, ThrustModel};
use crate::aero::regression::{
    half_sample_lag, regressor_filter, EquationErrorOptions, RegressionResult,
};
use crate::aero::AeroError;
use crate::data;
use crate::signal::cross;
use crate::sim::aero_truth::{
    coefficient_property, reference_arm_ft, wind_to_body, ARM_PROPERTIES,
};
use crate::sim::JsbsimSim;
use crate::study::score::{Scorecard, TermShare, CMQ_SUM};
use crate::study::spec::full_assumptions;

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
fn errors(values: &[f64], free: &[Derivative], truth: &Derivatives) -> Vec<(String, f64)> {
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
    prior: &crate::aero::AeroModel,
    tfs: &IdentifiedTfs,
    linearization: Option<&IdentifiedTfs>,
    free: &[Derivative],
    truth: &Derivatives,
) -> Result<Vec<RowAttribution>, AeroError> {
    let fit = |model: &crate::aero::AeroModel,
               t: &IdentifiedTfs|
     -> Result<Vec<(String, f64)>, AeroError> {
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
        lift_rate_terms: pick(
            current.lift_rate_terms,
            released.lift_rate_terms,
            base.lift_rate_terms,
        ),
        drag_in_z_alpha: pick(
            current.drag_in_z_alpha,
            released.drag_in_z_alpha,
            base.drag_in_z_alpha,
        ),
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
        ixz_coupling: pick(
            current.ixz_coupling,
            released.ixz_coupling,
            base.ixz_coupling,
        ),
        level_flight: pick(
            current.level_flight,
            released.level_flight,
            base.level_flight,
        ),
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
        let alias = r
            .note
            .starts_with("α̇ not a regressor")
            .then(|| r.note.clone());
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
        if let Some(alias) = alias {
            r.note = format!("{}; {alias}", r.note);
        }
    }
}

/// What the equation-error attribution needs from JSBSim at the trim (JSBSim's English units).
#[derive(Debug, Clone)]
pub struct CoefficientProbe {
    /// Coefficient function name → the axis it belongs to (`LIFT`, `DRAG`, `SIDE`, `ROLL`, `PITCH`, `YAW`).
    pub axes: BTreeMap<String, String>,
    /// Value at the trim of each coefficient function, lbf or lbf·ft.
    pub base: BTreeMap<String, f64>,
    /// Probe variable (`alpha`, `q`, `surface:elevator`, …) → coefficient function → slope per rad or rad/s.
    pub slopes: BTreeMap<String, BTreeMap<String, f64>>,
    /// Aero reference point relative to the CG in body axes (x forward, y right, z down), ft.
    pub arm_ft: [f64; 3],
    /// Wing area, ft².
    pub wing_area_ft2: f64,
    /// Span, ft.
    pub span_ft: f64,
    /// Mean aerodynamic chord, ft.
    pub chord_ft: f64,
    /// Trim angle of attack, rad.
    pub alpha_rad: f64,
    /// Trim sideslip, rad.
    pub beta_rad: f64,
    /// Trim true airspeed, ft/s.
    pub airspeed_fps: f64,
    /// Trim dynamic pressure, psf.
    pub qbar_psf: f64,
}

/// Propulsion forces and moments (body axes, about the CG) recorded as the `propulsion` term.
const PROPULSION: [&str; 6] = [
    "forces/fbx-prop-lbs",
    "forces/fby-prop-lbs",
    "forces/fbz-prop-lbs",
    "moments/l-prop-lbsft",
    "moments/m-prop-lbsft",
    "moments/n-prop-lbsft",
];

/// The properties a flight must record for [`attribute_equation_error`]: dynamic pressure, every coefficient
/// function, the propulsion forces and moments.
pub fn recorded_properties(axes: &BTreeMap<String, String>) -> Vec<String> {
    let mut out = vec!["aero/qbar-psf".to_string()];
    out.extend(axes.keys().map(|k| coefficient_property(k)));
    out.extend(PROPULSION.iter().map(|p| p.to_string()));
    out
}

/// Probes every coefficient function of the simulator at its current trim ([`CoefficientProbe`]).
pub fn probe_coefficients(sim: &mut JsbsimSim) -> Result<CoefficientProbe, AeroError> {
    let axes = sim.coefficient_axes.clone();
    let props: Vec<String> = axes.keys().map(|k| coefficient_property(k)).collect();
    let (base, slopes) = sim.probe_slopes(&props)?;
    let names: Vec<&str> = [
        "metrics/Sw-sqft",
        "metrics/bw-ft",
        "metrics/cbarw-ft",
        "aero/alpha-rad",
        "aero/beta-rad",
        "velocities/vt-fps",
        "aero/qbar-psf",
    ]
    .into_iter()
    .chain(ARM_PROPERTIES)
    .collect();
    let c = sim.get_properties(&names)?;
    let g = |k: &str| c.get(k).copied().unwrap_or(f64::NAN);
    let strip = |m: BTreeMap<String, f64>| -> BTreeMap<String, f64> {
        m.into_iter()
            .filter_map(|(k, v)| Some((k.strip_prefix("aero/coefficient/")?.to_string(), v)))
            .collect()
    };
    Ok(CoefficientProbe {
        base: strip(base),
        slopes: slopes.into_iter().map(|(v, m)| (v, strip(m))).collect(),
        axes,
        // the same arm `JsbsimSim::aero_truth` uses
        arm_ft: reference_arm_ft(g),
        wing_area_ft2: g("metrics/Sw-sqft"),
        span_ft: g("metrics/bw-ft"),
        chord_ft: g("metrics/cbarw-ft"),
        alpha_rad: g("aero/alpha-rad"),
        beta_rad: g("aero/beta-rad"),
        airspeed_fps: g("velocities/vt-fps"),
        qbar_psf: g("aero/qbar-psf"),
    })
}

/// Body-axis force (lbf) and moment about the CG (lbf·ft) of one coefficient function of value `value` on
/// `axis` at (α, β).
fn force_moment(
    axis: &str,
    value: f64,
    alpha_rad: f64,
    beta_rad: f64,
    arm_ft: [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    let moment_only = |k: usize| {
        let mut m = [0.0; 3];
        m[k] = value;
        ([0.0; 3], m)
    };
    let wind = match axis {
        "ROLL" => return moment_only(0),
        "PITCH" => return moment_only(1),
        "YAW" => return moment_only(2),
        "DRAG" => [-value, 0.0, 0.0],
        "SIDE" => [0.0, value, 0.0],
        "LIFT" => [0.0, 0.0, -value],
        _ => return ([0.0; 3], [0.0; 3]),
    };
    let f = wind_to_body(alpha_rad, beta_rad, wind);
    (f, cross(arm_ft, f))
}

/// The coefficient equation's response from a body force and moment: the same normalisation as
/// `aero::regression` (C_m = M/(q̄Sc̄), C_l, C_n = L, N/(q̄Sb), C_Y = F_y/(q̄S), C_L = −F_z/(q̄S cos α)).
fn response_of(
    eq: &str,
    f: [f64; 3],
    m: [f64; 3],
    qbar_psf: f64,
    alpha_rad: f64,
    p: &CoefficientProbe,
) -> f64 {
    let qs = qbar_psf * p.wing_area_ft2;
    match eq {
        "Cm" => m[1] / (qs * p.chord_ft),
        "Cl" => m[0] / (qs * p.span_ft),
        "Cn" => m[2] / (qs * p.span_ft),
        "CY" => f[1] / qs,
        "CL" => -f[2] / (qs * alpha_rad.cos()),
        _ => f64::NAN,
    }
}

/// The probe variables behind a regressor (by its term-name suffix) with the factor from d/d(variable) to
/// d/d(regressor): rates enter nondimensionalised (q̂ = q c̄/2V, p̂ = p b/2V). In the C_m equation without an
/// α̇ regressor the q column carries C_mq + C_mα̇ (the scored combination), so α̇ maps onto it too.
fn regressor_variables(
    eq: &str,
    suffix: &str,
    alphadot_free: bool,
    p: &CoefficientProbe,
) -> Vec<(&'static str, f64)> {
    let pitch = 2.0 * p.airspeed_fps / p.chord_ft;
    let lat = 2.0 * p.airspeed_fps / p.span_ft;
    match suffix {
        "alpha" => vec![("alpha", 1.0)],
        "beta" => vec![("beta", 1.0)],
        "q" if eq == "Cm" && !alphadot_free => vec![("q", pitch), ("alphadot", pitch)],
        "q" => vec![("q", pitch)],
        "alphadot" => vec![("alphadot", pitch)],
        "p" => vec![("p", lat)],
        "r" => vec![("r", lat)],
        "de" => vec![("surface:elevator", 1.0)],
        "da" => vec![("surface:aileron", 1.0)],
        "dr" => vec![("surface:rudder", 1.0)],
        _ => Vec::new(),
    }
}

/// Least-squares solution of X θ = y (X by columns), by the SVD (the same solve as `aero::regression`).
fn ls_solve(columns: &[Vec<f64>], y: &[f64]) -> Result<Vec<f64>, AeroError> {
    let n = y.len();
    let p = columns.len();
    let x = Mat::from_fn(n, p, |i, j| columns[j][i]);
    let svd = x
        .thin_svd()
        .map_err(|_| AeroError::Numerical("SVD of the regressor matrix"))?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let (u, v) = (svd.U(), svd.V());
    let uy: Vec<f64> = (0..p)
        .map(|k| (0..n).map(|i| u[(i, k)] * y[i]).sum::<f64>() / s[k])
        .collect();
    Ok((0..p)
        .map(|a| (0..p).map(|k| v[(a, k)] * uy[k]).sum())
        .collect())
}

/// One equation's error decomposition (see [`attribute_equation_error`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EquationAttribution {
    /// `Cm`, `Cl`, `Cn`, `CY`, `CL`.
    pub coefficient: String,
    /// Regression terms (columns), e.g. `Cm_alpha`.
    pub terms: Vec<String>,
    /// Noisy (or clean) estimate − truth, per term; NaN for the bias column.
    pub error: Vec<f64>,
    /// Per cause: (cause, contribution per term). Coefficient functions, `propulsion`, `other`, `noise`,
    /// `probe mismatch`.
    pub parts: Vec<(String, Vec<f64>)>,
}

impl EquationAttribution {
    /// Σ parts − error, per term: zero to round-off when the decomposition is exact.
    pub fn closure(&self) -> Vec<f64> {
        (0..self.terms.len())
            .map(|j| self.parts.iter().map(|(_, c)| c[j]).sum::<f64>() - self.error[j])
            .collect()
    }
}

/// Label of the part of the response no coefficient function or propulsion term carries.
pub const OTHER: &str =
    "other (response reconstruction: differentiation and smoothing, inertia terms, q̄(t) normalisation)";
/// Label of the half-sample skew between the reconstructed response and the regressors.
pub const SKEW: &str =
    "time skew: the differentiated rates lag the regressors by ½ sample (JSBSim's integrator)";
/// Label of the noise part.
pub const NOISE: &str = "sensor noise";
/// Label of the difference between the scored truth and the sum of the per-function slopes.
pub const PROBE_MISMATCH: &str = "truth vs per-function probe";

/// Attributes each equation-error estimate's error to the JSBSim coefficient functions (module doc):
/// `clean` is the regression on the noise-free record of the flight whose extra columns hold every
/// coefficient function ([`recorded_properties`]), `estimate` the regression actually scored (the noisy one, or
/// `clean` again), `record` that noise-free flight, `truth` the scored truth (body axes, about the CG).
///
/// For equation e with regressors X (as used, smoothed), response z and estimate θ̂ = (XᵀX)⁻¹Xᵀz:
/// c_k(t) = coefficient function k's share of the response (its force rotated to body axes and carried to the
/// CG, normalised like z), s_k its linearisation at the trim in the regressors (the truth derivatives it makes
/// up, Σ_k s_k = θ), ρ_k = S c_k − X s_k its remainder, S the regressors' smoother. Then exactly
/// θ̂ − θ = Σ_k (XᵀX)⁻¹Xᵀρ_k [function k] + (XᵀX)⁻¹Xᵀ(Hc − c) [time skew, c = Σ_k S c_k, H the half-sample
/// shift] + (XᵀX)⁻¹Xᵀ(z − Hc) [other, with propulsion as one of the k] + (Σ_k s_k − θ) [probe mismatch]
/// + (θ̂_noisy − θ̂_clean) [noise].
pub fn attribute_equation_error(
    clean: &RegressionResult,
    estimate: &RegressionResult,
    record: &data::FlightRecord,
    probe: &CoefficientProbe,
    truth: &Derivatives,
    options: &EquationErrorOptions,
) -> Result<EquationAttribution, AeroError> {
    let eq = clean.coefficient;
    let n = clean.response.len();
    let col = |name: &str| -> Result<&[f64], AeroError> {
        record.column(name).filter(|c| c.len() == n).ok_or_else(|| {
            AeroError::BadRecord(format!("attribution needs the recorded column `{name}`"))
        })
    };
    let alpha = col("alpha_rad")?;
    let beta = col("beta_rad")?;
    let qbar = col("aero/qbar-psf")?;
    // what the regression does to its regressors, applied to each function's share of the response
    let smooth = |c: &[f64]| regressor_filter(c, eq, options);
    let alphadot_free = clean.terms.iter().any(|t| t.name.ends_with("_alphadot"));
    let suffixes: Vec<String> = clean
        .terms
        .iter()
        .map(|t| {
            t.name
                .split_once('_')
                .map_or(String::new(), |(_, s)| s.to_string())
        })
        .collect();
    let p_cols = clean.terms.len();
    let truth_of = |j: usize| -> f64 {
        match clean.terms[j].derivative {
            Some(Derivative::Cmq) if !alphadot_free => {
                truth.get(Derivative::Cmq) + truth.get(Derivative::Cmalphadot)
            }
            Some(d) => truth.get(d),
            None => f64::NAN,
        }
    };
    // Which functions make up the scored truth of this equation (force equations: their own wind axis only).
    let counts = |axis: &str| match eq {
        "CL" => axis == "LIFT",
        "CY" => axis == "SIDE",
        _ => true,
    };
    let mut parts: Vec<(String, Vec<f64>)> = Vec::new();
    let mut sum_c = vec![0.0; n];
    let mut sum_s = vec![0.0; p_cols];
    for (name, axis) in &probe.axes {
        let series = col(&coefficient_property(name))?;
        let c: Vec<f64> = (0..n)
            .map(|i| {
                let (f, m) = force_moment(axis, series[i], alpha[i], beta[i], probe.arm_ft);
                response_of(eq, f, m, qbar[i], alpha[i], probe)
            })
            .collect();
        if c.iter().all(|v| *v == 0.0) {
            continue;
        }
        // Truth slopes of this function's share of the response at the trim (central differences through the
        // same rotation and transfer; the force turn with α, β included, as in the truth).
        let base = probe.base.get(name).copied().unwrap_or(0.0);
        let slope_of = |var: &str| -> f64 {
            if !counts(axis) {
                return 0.0;
            }
            let dv = probe
                .slopes
                .get(var)
                .and_then(|m| m.get(name))
                .copied()
                .unwrap_or(0.0);
            if matches!(eq, "CL" | "CY") {
                return dv / (probe.qbar_psf * probe.wing_area_ft2);
            }
            let h = 1e-6;
            let at = |sgn: f64| {
                let (a, b) = (
                    probe.alpha_rad + if var == "alpha" { sgn * h } else { 0.0 },
                    probe.beta_rad + if var == "beta" { sgn * h } else { 0.0 },
                );
                let (f, m) = force_moment(axis, base + sgn * h * dv, a, b, probe.arm_ft);
                response_of(eq, f, m, probe.qbar_psf, a, probe)
            };
            (at(1.0) - at(-1.0)) / (2.0 * h)
        };
        let s: Vec<f64> = suffixes
            .iter()
            .map(|suf| {
                regressor_variables(eq, suf, alphadot_free, probe)
                    .iter()
                    .map(|(var, factor)| slope_of(var) * factor)
                    .sum()
            })
            .collect();
        let sc = smooth(&c)?;
        let proj = ls_solve(&clean.regressors, &sc)?;
        let bias: Vec<f64> = (0..p_cols)
            .map(|j| {
                if suffixes[j] == "0" {
                    f64::NAN
                } else {
                    proj[j] - s[j]
                }
            })
            .collect();
        for i in 0..n {
            sum_c[i] += sc[i];
        }
        for j in 0..p_cols {
            sum_s[j] += s[j];
        }
        parts.push((format!("{name} ({axis})"), bias));
    }
    // Propulsion: no part of the truth derivatives; its whole variation is remainder.
    let prop: Result<Vec<&[f64]>, _> = PROPULSION.iter().map(|p| col(p)).collect();
    if let Ok(prop) = prop {
        let c: Vec<f64> = (0..n)
            .map(|i| {
                let f = [prop[0][i], prop[1][i], prop[2][i]];
                let m = [prop[3][i], prop[4][i], prop[5][i]];
                response_of(eq, f, m, qbar[i], alpha[i], probe)
            })
            .collect();
        let sc = smooth(&c)?;
        let proj = ls_solve(&clean.regressors, &sc)?;
        for i in 0..n {
            sum_c[i] += sc[i];
        }
        parts.push((
            "propulsion (thrust, propeller torque and gyroscopics)".to_string(),
            (0..p_cols)
                .map(|j| {
                    if suffixes[j] == "0" {
                        f64::NAN
                    } else {
                        proj[j]
                    }
                })
                .collect(),
        ));
    }
    // The response is reconstructed from differentiated rates, which JSBSim's integrator advances with
    // moments half a step old: z(t_i) ≈ ½ (M(t_{i−1}) + M(t_i)) (measured on c172x at 60 Hz: the C_m residual
    // drops 7× with that half-sample shift). Its part is the projection of the shifted minus the unshifted
    // sum; what is left after it is the rest of the reconstruction.
    // (with `response_lags_half_sample` the estimator models the shift itself: sum_c is already shifted and
    // the skew part is zero)
    let shifted: Vec<f64> = if options.lags_half_sample(eq) {
        sum_c.clone()
    } else {
        half_sample_lag(&sum_c)
    };
    let skew: Vec<f64> = (0..n).map(|i| shifted[i] - sum_c[i]).collect();
    let rest: Vec<f64> = (0..n).map(|i| clean.response[i] - shifted[i]).collect();
    for (label, y) in [(SKEW, &skew), (OTHER, &rest)] {
        let x = ls_solve(&clean.regressors, y)?;
        parts.push((
            label.to_string(),
            (0..p_cols)
                .map(|j| if suffixes[j] == "0" { f64::NAN } else { x[j] })
                .collect(),
        ));
    }
    parts.push((
        PROBE_MISMATCH.to_string(),
        (0..p_cols).map(|j| sum_s[j] - truth_of(j)).collect(),
    ));
    let same = std::ptr::eq(clean, estimate);
    if !same {
        parts.push((
            NOISE.to_string(),
            (0..p_cols)
                .map(|j| estimate.terms[j].value - clean.terms[j].value)
                .collect(),
        ));
    }
    Ok(EquationAttribution {
        coefficient: eq.to_string(),
        terms: clean.terms.iter().map(|t| t.name.clone()).collect(),
        error: (0..p_cols)
            .map(|j| estimate.terms[j].value - truth_of(j))
            .collect(),
        parts,
    })
}

/// The per-row view of equation attributions, named like the equation-error scorecard's rows.
pub fn equation_rows(equations: &[EquationAttribution]) -> Vec<RowAttribution> {
    let mut out: Vec<RowAttribution> = Vec::new();
    for e in equations {
        let alphadot_free = e.terms.iter().any(|t| t.ends_with("_alphadot"));
        for (j, term) in e.terms.iter().enumerate() {
            let Ok(d) = term.parse::<Derivative>() else {
                continue;
            };
            let name = if d == Derivative::Cmq && !alphadot_free {
                CMQ_SUM.to_string()
            } else {
                d.name().to_string()
            };
            if out.iter().any(|r| r.name == name) {
                continue;
            }
            let error = e.error[j];
            let mut terms: Vec<TermShare> = e
                .parts
                .iter()
                .map(|(cause, c)| TermShare {
                    term: cause.clone(),
                    contribution: c[j],
                    share: if error != 0.0 { c[j] / error } else { 0.0 },
                })
                .filter(|t| t.contribution != 0.0)
                .collect();
            terms.sort_by(|a, b| b.share.total_cmp(&a.share));
            out.push(RowAttribution { name, error, terms });
        }
    }
    out
}

#[cfg(test)]
#[path = "attribution_tests.rs"]
mod tests;
