//! The JSBSim derivative study behind `flightid derivatives --aircraft`: truth from the JSBSim trim, the model
//! check against JSBSim's linearization, estimates by the transfer-function route and by equation error, and
//! their scores. The pure parametric model and its estimators live in [`crate::aero`]; this module couples
//! them to a JSBSim aircraft.
//!
//! - [`spec`]: the truth derivatives from a JSBSim trim and the study's structure (paper/full model).
//! - [`trials`]: the doublets flown and the transfer functions and equation-error records made from them.
//! - [`score`]: estimates against the truth (the paper's Tables 1 and 3).
//! - [`attribution`]: why an estimate misses the truth, term by term (TF route by releasing assumptions,
//!   equation error by projecting each JSBSim coefficient function's remainder on the regressors).

pub mod attribution;
pub mod score;
pub mod spec;
pub mod trials;

use serde::Serialize;
use serde_json::{json, Value};

use crate::aero::fit::{estimate_derivatives, FitOptions, IdentifiedTf, IdentifiedTfs};
use crate::aero::model::TfOutput;
use crate::aero::params::Derivative as D;
use crate::aero::regression::{EquationErrorOptions, EquationErrorResult};
use crate::aero::AeroError;
use crate::data;
use crate::report::{Report, Section, Table};
use crate::sim::aero_truth::AeroTruth;
use crate::sim::linear::{paper_transfer_functions, submodel_modes};
use crate::sim::Linearization;
use crate::sim::{JsbsimSim, Simulator, TrimPoint};
use crate::study::attribution::{
    attribute_equation_error, attribute_tf_fit, CoefficientProbe, EquationAttribution,
};
use crate::study::score::{
    score_equation_error, score_tf_fit, table1, table3, ScoreRow, Scorecard,
};
use crate::study::spec::{
    apply_overrides, identified_tfs_from_json, model_from_truth, truth_derivatives, Structure,
};
use crate::study::trials::{
    equation_error_flights, equation_error_with, fly_doublets, identify_paper_tfs, Flights,
    TrialOptions, JSBSIM_RESPONSE_LAG,
};

/// Where the estimates come from.
#[derive(Debug, Clone)]
pub enum Source {
    /// Fly the doublets on JSBSim (the default run).
    Fly(TrialOptions),
    /// Identified transfer functions (`flightid identify --json` documents, with their file names).
    Identified(Vec<(String, Value)>),
    /// A flight-data CSV, read by equation error; `simulated`: written by JSBSim (`flightid fly`), whose
    /// differentiated rates lag the moments by half a sample (modelled), else sensor data (not).
    Data {
        /// The record.
        record: data::FlightRecord,
        /// JSBSim-made (the half-sample lag is modelled) or measured.
        simulated: bool,
    },
}

/// What to estimate and how.
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// Data source.
    pub source: Source,
    /// Model structure of the transfer-function route.
    pub structure: Structure,
    /// Free derivatives of the transfer-function route (`None`: the pitching-moment and roll/yaw derivatives
    /// the paper's transfer functions determine, [`default_free`]).
    pub free: Option<Vec<D>>,
    /// Start of the free derivatives as a factor on the truth (1.2: 20 % off, like a handbook estimate).
    pub start_factor: f64,
}

/// The default free derivatives: C_mα, C_mq, C_mα̇, C_mδe from θ/δe; C_lβ, C_lp, C_lδa, C_nβ, C_nr from φ/δa.
/// Lift, drag and side force stay at the model's values (they come from performance and trim tests, and the
/// attitude transfer functions see them only in combination with the moment derivatives).
pub fn default_free() -> Vec<D> {
    vec![
        D::Cmalpha,
        D::Cmq,
        D::Cmalphadot,
        D::Cmde,
        D::Clbeta,
        D::Clp,
        D::Clda,
        D::Cnbeta,
        D::Cnr,
    ]
}

/// ωn and ζ of the short period and the Dutch roll: (label, model, JSBSim).
#[derive(Debug, Clone, Serialize)]
pub struct ModalCheck {
    /// `short period ωn` etc.
    pub quantity: String,
    /// The paper-structure model from the truth derivatives.
    pub paper: f64,
    /// The full-structure model.
    pub full: f64,
    /// JSBSim's linearization (decoupled 4-state submodels).
    pub jsbsim: f64,
}

/// One identified transfer function as used by the study.
#[derive(Debug, Clone, Serialize)]
pub struct IdentifiedSummary {
    /// `theta_rad/elevator_rad` etc.
    pub tf: String,
    /// Numerator, highest power first.
    pub num: Vec<f64>,
    /// Denominator, monic.
    pub den: Vec<f64>,
    /// Simulation fit, % (when identified here).
    pub fit_sim_percent: Option<f64>,
}

/// (short period, Dutch roll), each (ωn rad/s, ζ).
type ModePair = ((f64, f64), (f64, f64));

/// Everything the study found.
#[derive(Debug, Clone, Serialize)]
pub struct Study {
    /// The aircraft's own values at trim.
    pub truth: AeroTruth,
    /// Model check against JSBSim's linearization.
    pub modal_check: Vec<ModalCheck>,
    /// Identified transfer functions.
    pub identified: Vec<IdentifiedSummary>,
    /// One scorecard per route.
    pub scorecards: Vec<Scorecard>,
    /// The identifiability analysis of the transfer-function route, in words.
    pub identifiability: String,
    /// The equation-error estimates' errors taken apart by JSBSim coefficient function (flights only).
    pub equation_error_attribution: Vec<EquationAttribution>,
    /// Statements the reader needs (what was dropped and why, what the data cannot give).
    pub notes: Vec<String>,
}

fn modal_check(
    sim: &mut JsbsimSim,
    truth: &AeroTruth,
) -> Result<(Vec<ModalCheck>, Linearization), AeroError> {
    let lin = sim.linearize()?;
    let jsb = submodel_modes(&lin)?;
    let osc = |k: &str| {
        jsb.get(k)
            .into_iter()
            .flatten()
            .filter(|m| m.zeta < 1.0 && m.omega_n_rad_s > 0.0 && m.period_s.is_some())
            .map(|m| (m.omega_n_rad_s, m.zeta))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or((f64::NAN, f64::NAN))
    };
    let (sp_j, dr_j) = (osc("longitudinal"), osc("lateral"));
    let mut per = Vec::new();
    for s in [Structure::Paper, Structure::Full] {
        let m = model_from_truth(truth, s.assumptions())?;
        let sp = m
            .longitudinal()?
            .fastest_oscillation()?
            .unwrap_or((f64::NAN, f64::NAN));
        let dr = m
            .lateral()?
            .fastest_oscillation()?
            .unwrap_or((f64::NAN, f64::NAN));
        per.push((sp, dr));
    }
    let row = |q: &str, f: &dyn Fn(ModePair) -> f64, j: f64| ModalCheck {
        quantity: q.into(),
        paper: f(per[0]),
        full: f(per[1]),
        jsbsim: j,
    };
    Ok((
        vec![
            row("short period ωn, rad/s", &|p| p.0 .0, sp_j.0),
            row("short period ζ", &|p| p.0 .1, sp_j.1),
            row("Dutch roll ωn, rad/s", &|p| p.1 .0, dr_j.0),
            row("Dutch roll ζ", &|p| p.1 .1, dr_j.1),
        ],
        lin,
    ))
}

/// The paper's transfer functions of JSBSim's linearization (decoupled submodels, per radian of surface), as
/// identified transfer functions with the numerator lengths of `like` (what a perfect identification of the
/// linearized aircraft would give).
pub fn linearization_tfs(
    lin: &Linearization,
    like: &IdentifiedTfs,
) -> Result<IdentifiedTfs, AeroError> {
    let tfs = paper_transfer_functions(lin)?;
    let mut out = IdentifiedTfs::default();
    for (o, t) in &like.tfs {
        let key = match *o {
            TfOutput::THETA_ELEVATOR => "theta/elevator",
            TfOutput::PHI_AILERON => "phi/aileron",
            TfOutput::PHI_RUDDER => "phi/rudder",
            _ => continue,
        };
        let Some(tf) = tfs.get(key) else { continue };
        let len = t.num.len();
        let mut num = vec![0.0; len.saturating_sub(tf.num.len())];
        num.extend(&tf.num[tf.num.len().saturating_sub(len)..]);
        out.tfs.push((
            *o,
            IdentifiedTf {
                num,
                den: tf.den.clone(),
                covariance: None,
            },
        ));
    }
    Ok(out)
}

/// Runs the study on a trimmed simulator (`point` is re-trimmed before each flight).
pub fn run(
    sim: &mut JsbsimSim,
    point: &TrimPoint,
    opts: &StudyOptions,
) -> Result<Study, AeroError> {
    sim.trim(point)?;
    let truth = sim.aero_truth()?;
    let (modal_check, lin) = modal_check(sim, &truth)?;
    let mut notes = vec![
        "Truth: the derivatives the JSBSim model itself uses at this trim (its coefficient functions, tables \
         included, differenced; moments about the CG). TF-route scores are in stability axes, \
         equation-error scores in body axes."
            .to_string(),
    ];
    let free = match &opts.free {
        Some(f) => f.clone(),
        None => default_free(),
    };
    let mut tfs = IdentifiedTfs::default();
    let mut identified = Vec::new();
    let mut ee = None;
    let mut ee_attribution = Vec::new();
    match &opts.source {
        Source::Fly(trial) => {
            // Record every coefficient function along the flights for the error attribution.
            sim.extra_record = attribution::recorded_properties(&sim.coefficient_axes);
            let flown = fly_doublets(sim, point, trial);
            sim.extra_record.clear();
            let flights = flown?;
            sim.trim(point)?;
            let probe = attribution::probe_coefficients(sim)?;
            let (all, results) = identify_paper_tfs(&flights, trial)?;
            for (o, r) in &results {
                identified.push(IdentifiedSummary {
                    tf: o.label(),
                    num: r.tf.num.clone(),
                    den: r.tf.den.clone(),
                    fit_sim_percent: Some(r.fit_sim_percent),
                });
            }
            // φ/δa and φ/δr share the lateral poles; a rudder doublet barely excites the roll mode, so its
            // 4-pole fit often trades it for a zero. Use φ/δr only when its poles agree with φ/δa's.
            let den_of = |o: TfOutput| {
                all.tfs
                    .iter()
                    .find(|(w, _)| *w == o)
                    .map(|(_, t)| t.den.clone())
            };
            let agree = match (den_of(TfOutput::PHI_AILERON), den_of(TfOutput::PHI_RUDDER)) {
                (Some(a), Some(r)) => a
                    .iter()
                    .zip(&r)
                    .skip(1)
                    .take(3)
                    .all(|(x, y)| (x - y).abs() <= 0.1 * x.abs().max(1e-3)),
                _ => false,
            };
            tfs.tfs = all
                .tfs
                .into_iter()
                .filter(|(o, _)| agree || *o != TfOutput::PHI_RUDDER)
                .collect();
            if !agree {
                notes.push(
                    "φ/δr left out of the derivative fit: its identified denominator disagrees with φ/δa's by \
                     more than 10 % (the rudder doublet hardly excites the roll mode, so the 4-pole fit loses it)"
                        .into(),
                );
            }
            notes.push(alphadot_separation_note(
                flights.noise_free.as_deref().unwrap_or(&flights),
                &truth,
            )?);
            let noisy_ee = equation_error_flights(&flights, &truth)?;
            let clean_ee = match &flights.noise_free {
                Some(clean) => Some(equation_error_flights(clean, &truth)?),
                None => None,
            };
            let clean_flights = flights.noise_free.as_deref().unwrap_or(&flights);
            ee_attribution = attribute_flights(
                clean_ee.as_ref().unwrap_or(&noisy_ee),
                &noisy_ee,
                clean_flights,
                &probe,
                &truth,
            )?;
            ee = Some(noisy_ee);
        }
        Source::Identified(docs) => {
            identified_tfs_from_json(docs, &mut tfs)?;
            for (_, d) in docs {
                apply_overrides_note(d, &mut notes);
            }
            for (o, t) in &tfs.tfs {
                identified.push(IdentifiedSummary {
                    tf: o.label(),
                    num: t.num.clone(),
                    den: t.den.clone(),
                    fit_sim_percent: None,
                });
            }
        }
        Source::Data { record, simulated } => {
            ee = Some(equation_error_with(record, &truth, false, *simulated)?);
        }
    }
    let mut scorecards = Vec::new();
    let mut identifiability = String::new();
    if !tfs.tfs.is_empty() {
        let mut model = model_from_truth(&truth, opts.structure.assumptions())?;
        if let Source::Identified(docs) = &opts.source {
            for (source, d) in docs {
                apply_overrides(d, source, truth.alpha_rad, &mut model)?;
            }
        }
        let axes: Vec<_> = tfs.tfs.iter().map(|(o, _)| o.axis).collect();
        let free: Vec<D> = free
            .into_iter()
            .filter(|d| {
                axes.iter()
                    .any(|a| d.is_longitudinal() == (*a == crate::aero::Axis::Longitudinal))
            })
            .collect();
        let mut prior = model.clone();
        for &d in &free {
            prior
                .derivatives
                .set(d, opts.start_factor * model.derivatives.get(d));
        }
        let est = estimate_derivatives(&prior, &tfs, &free, FitOptions::default())?;
        identifiability = est.identifiability.to_text();
        let mut card = score_tf_fit(&est, &model.derivatives, opts.structure);
        let lin_tfs = linearization_tfs(&lin, &tfs)?;
        let attributions =
            attribute_tf_fit(&prior, &tfs, Some(&lin_tfs), &free, &model.derivatives)?;
        attribution::apply(&mut card, &attributions);
        scorecards.push(card);
        notes.push(format!(
            "TF route: free derivatives start at {:.0} % of the truth; the others are held at the model's values. \
             Standard errors are scaled per axis by the reduced χ² of the coefficient fit when it exceeds 1 \
             (here {}): the model reproduces the identified coefficients only to that many times their stated \
             variance, so the identified TFs' own covariance would overstate the precision.",
            100.0 * opts.start_factor,
            {
                let mut seen: Vec<String> = Vec::new();
                for (d, s) in est.free.iter().zip(&est.covariance_scale) {
                    let axis = if d.is_longitudinal() { "longitudinal" } else { "lateral" };
                    let w = format!("{axis} {s:.0}");
                    if !seen.contains(&w) {
                        seen.push(w);
                    }
                }
                seen.join(", ")
            }
        ));
        notes.push(
            "Error attribution, TF route: the fit repeated on JSBSim's linearization TFs (what a perfect \
             identification would give) takes out the identification error; then the paper's assumptions are \
             released one after another (the omitted terms at their truth values), each taking out its share. \
             Equation-error route: every JSBSim coefficient function is recorded along the flight; its remainder \
             (value minus its linearization with the truth derivatives) projected on the regressors, \
             (XᵀX)⁻¹Xᵀρ, is its exact share of the LS bias (Morelli & Klein eq. 5.8); the rest is propulsion, \
             the ½-sample skew of JSBSim's integrator between differentiated rates and regressors, the response \
             reconstruction, and noise."
                .into(),
        );
    }
    if let Some(ee) = &ee {
        let model = model_from_truth(&truth, Structure::Full.assumptions())?;
        let mut card = score_equation_error(&[ee], &truth_derivatives(&truth), &model);
        if !ee_attribution.is_empty() {
            attribution::apply(&mut card, &attribution::equation_rows(&ee_attribution));
        }
        scorecards.push(card);
        for (c, why) in &ee.skipped {
            notes.push(format!("equation error: {c} skipped: {why}"));
        }
    }
    notes.push(
        "Drag polar: C_D0 and C_D_CL² are not recoverable from these flights. They enter θ/δe only through the \
         phugoid coefficients, where the model's constant-thrust assumption is wrong for a propeller (thrust \
         falls with speed), so a fit moves C_D0 and K to absorb the missing thrust derivative (measured on \
         c172x doublets: C_D0 +80 to +130 %, C_D_CL² of the wrong sign). This is the paper's failure to estimate \
         C_D_CL², explained; a thrust model (ThrustModel::ConstantPower) or a throttle input would separate them."
            .into(),
    );
    for card in &scorecards {
        notes.push(targets_summary(card));
    }
    Ok(Study {
        truth,
        modal_check,
        identified,
        scorecards,
        identifiability,
        equation_error_attribution: ee_attribution,
        notes,
    })
}

/// Does measuring α separate C_mq from C_mα̇? The C_m equation error on the (noise-free) elevator flight with
/// α̇ c̄/(2V) as a regressor, checked numerically: both estimates against the truth and the correlation of the two estimates,
/// ρ = D_qα̇/√(D_qq D_α̇α̇) with D = (XᵀX)⁻¹ (Morelli & Klein eq. 5.12).
fn alphadot_separation_note(flights: &Flights, truth: &AeroTruth) -> Result<String, AeroError> {
    let r = trials::equation_error_with(&flights.elevator, truth, true, JSBSIM_RESPONSE_LAG)?;
    let Some(cm) = r.equations.iter().find(|e| e.coefficient == "Cm") else {
        return Ok("C_m equation with α̇ could not be formed on the elevator flight".into());
    };
    let (Some(iq), Some(ia)) = (
        cm.terms.iter().position(|t| t.derivative == Some(D::Cmq)),
        cm.terms
            .iter()
            .position(|t| t.derivative == Some(D::Cmalphadot)),
    ) else {
        return Ok("C_m equation with α̇: no C_mq or C_mα̇ column".into());
    };
    let x = &cm.regressors;
    let p = x.len();
    let xtx = faer::Mat::from_fn(p, p, |a, b| {
        x[a].iter().zip(&x[b]).map(|(u, v)| u * v).sum::<f64>()
    });
    let d = faer::prelude::Solve::solve(&xtx.partial_piv_lu(), faer::Mat::<f64>::identity(p, p));
    let rho = d[(iq, ia)] / (d[(iq, iq)] * d[(ia, ia)]).sqrt();
    let body = truth_derivatives(truth);
    let pct = |est: f64, t: f64| 100.0 * (est - t) / t.abs();
    let (q, a) = (&cm.terms[iq], &cm.terms[ia]);
    Ok(format!(
        "Separating C_mq from C_mα̇ by measuring α (equation error on the elevator doublet with α̇ c̄/(2V) as a \
         regressor, checked numerically): C_mq {:.2} ({:+.0} %), C_mα̇ {:.2} ({:+.0} %), estimate correlation \
         ρ = {rho:+.3}, σ(C_mα̇) = {:.2}. {}",
        q.value,
        pct(q.value, body.get(D::Cmq)),
        a.value,
        pct(a.value, body.get(D::Cmalphadot)),
        a.std_error_colored,
        if rho.abs() > 0.9 {
            "On this doublet α̇ and q move together (|ρ| > 0.9): measuring α does not separate them; the manoeuvre \
             itself would have to move α̇ independently of q (not checked here)."
        } else if (a.value - body.get(D::Cmalphadot)).abs() > 3.0 * a.std_error_colored {
            "The columns are separable (|ρ| ≤ 0.9), yet C_mα̇ misses its 3σ interval: differentiating α and the \
             ½-sample skew between differentiated rates and regressors bias it, so α measured does not separate \
             them reliably on this record."
        } else {
            "The columns are separable (|ρ| ≤ 0.9) and both estimates cover the truth: α measured separates them."
        }
    ))
}

/// One sentence: which of the accuracy targets a route meets, which it misses, and the 3σ coverage.
pub fn targets_summary(card: &Scorecard) -> String {
    let with_target: Vec<&ScoreRow> = card
        .rows
        .iter()
        .filter(|r| r.target_percent.is_some())
        .collect();
    let list = |ok: bool| {
        with_target
            .iter()
            .filter(|r| r.meets_target() == Some(ok))
            .map(|r| {
                format!(
                    "{} {:+.1} % (≤ {:.0} %)",
                    r.name,
                    r.error_percent,
                    r.target_percent.unwrap_or(f64::NAN)
                )
            })
            .collect::<Vec<_>>()
    };
    let (met, missed) = (list(true), list(false));
    let covered = card
        .rows
        .iter()
        .filter(|r| r.covered_3sigma == Some(true))
        .count();
    let judged = card
        .rows
        .iter()
        .filter(|r| r.covered_3sigma.is_some())
        .count();
    format!(
        "Targets, {}: met {}; missed {}. 3σ covers the truth for {covered} of {judged} estimates; each miss \
         names its term (error attribution table).",
        card.route,
        if met.is_empty() { "none".to_string() } else { met.join(", ") },
        if missed.is_empty() { "none".to_string() } else { missed.join(", ") },
    )
}

/// Equation-error attribution of every equation of the doublet flights (C_m, C_L from the elevator flight;
/// C_l, C_n, C_Y from the lateral flight), `clean` the regressions on the noise-free flights, `scored` those
/// scored (the same when there is no noise).
fn attribute_flights(
    clean: &EquationErrorResult,
    scored: &EquationErrorResult,
    clean_flights: &Flights,
    probe: &CoefficientProbe,
    truth: &AeroTruth,
) -> Result<Vec<EquationAttribution>, AeroError> {
    let truth_body = truth_derivatives(truth);
    let options = EquationErrorOptions {
        response_lags_half_sample: trials::JSBSIM_RESPONSE_LAG,
        ..EquationErrorOptions::default()
    };
    let mut out = Vec::new();
    for c in &clean.equations {
        let Some(e) = scored
            .equations
            .iter()
            .find(|e| e.coefficient == c.coefficient)
        else {
            continue;
        };
        if e.terms
            .iter()
            .map(|t| &t.name)
            .ne(c.terms.iter().map(|t| &t.name))
        {
            continue;
        }
        let record = if ["Cm", "CL"].contains(&c.coefficient) {
            &clean_flights.elevator
        } else {
            &clean_flights.lateral
        };
        out.push(attribute_equation_error(
            c,
            e,
            record,
            probe,
            &truth_body,
            &options,
        )?);
    }
    Ok(out)
}

fn apply_overrides_note(doc: &Value, notes: &mut Vec<String>) {
    if doc.get("mass").is_some() || doc.get("geometry").is_some() {
        notes.push(
            "mass/geometry taken from the identified-TF file, not from the JSBSim model".into(),
        );
    }
}

impl Study {
    /// The model-check table.
    pub fn modal_table(&self) -> Table {
        let pct = |a: f64, b: f64| format!("{:+.2} %", 100.0 * (a / b - 1.0));
        Table::new("Model check: paper-structure and full model from the truth derivatives vs JSBSim's linearization", &["quantity", "JSBSim", "paper", "error", "full", "error"], self
                .modal_check
                .iter()
                .map(|m| {
                    vec![
                        m.quantity.clone(),
                        format!("{:.4}", m.jsbsim),
                        format!("{:.4}", m.paper),
                        pct(m.paper, m.jsbsim),
                        format!("{:.4}", m.full),
                        pct(m.full, m.jsbsim),
                    ]
                })
                .collect())
    }

    /// Table 1 and Table 3 of every route, and the error attribution of every estimate that misses its 3σ
    /// interval or its target.
    pub fn tables(&self) -> Vec<Table> {
        let mut out = vec![self.modal_table()];
        for c in &self.scorecards {
            out.push(table1(c, "derivatives"));
            out.push(table3(c, "derivatives"));
        }
        let mut rows = Vec::new();
        for c in &self.scorecards {
            for r in &c.rows {
                let missed = r.covered_3sigma == Some(false) || r.meets_target() == Some(false);
                if !missed || r.attribution.is_empty() {
                    continue;
                }
                let terms: Vec<String> = r
                    .attribution
                    .iter()
                    .filter(|t| t.share.abs() >= 0.05)
                    .take(4)
                    .map(|t| format!("{} {:+.0} %", t.term, 100.0 * t.share))
                    .collect();
                rows.push(vec![
                    r.name.clone(),
                    c.route.split(" (").next().unwrap_or(&c.route).to_string(),
                    format!("{:+.4}", r.estimate - r.truth),
                    terms.join("; "),
                ]);
            }
        }
        if !rows.is_empty() {
            out.push(Table::new(
                "derivatives — error attribution of every miss (share of estimate − truth; the \
                          parts add up to 100 %, shares of opposite sign offset each other)",
                &[
                    "derivative",
                    "route",
                    "estimate − truth",
                    "terms (share of the error)",
                ],
                rows,
            ));
        }
        out
    }

    /// JSON form.
    pub fn to_json(&self) -> Value {
        json!({
            "truth": self.truth,
            "modal_check": self.modal_check,
            "identified": self.identified,
            "scorecards": self.scorecards,
            "identifiability": self.identifiability,
            "equation_error_attribution": self.equation_error_attribution,
            "notes": self.notes,
        })
    }

    /// The report (index.html, report.md).
    pub fn report(&self) -> Report {
        let mut main = Section {
            heading: "Derivatives: truth vs estimate".into(),
            paragraphs: self.notes.clone(),
            tables: self.tables(),
            plots: Vec::new(),
        };
        if !self.identifiability.is_empty() {
            main.paragraphs.push(format!(
                "Identifiability of the TF route:\n{}",
                self.identifiability
            ));
        }
        Report {
            title: "flightid derivatives".into(),
            sections: vec![main],
        }
    }
}
