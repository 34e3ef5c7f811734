//! Linear vs nonlinear truth: fly doublets on JSBSim, identify θ/δe, φ/δa, φ/δr with several estimators and
//! compare them with JSBSim's own linearization at the same trim point (modal parameters, Bode, time
//! responses, ISE and fit %), plus an amplitude sweep that shows where the linear model stops holding.

use crate::ident::{self, IdentOptions, IdentResult, Method};
use crate::lti::{self, Mode, TransferFunction};
use crate::report::{LinePlot, Report, Section, Series, Table};
use crate::signal::Maneuver;
use crate::sim::linear::{paper_transfer_functions, tf_json, PAPER_TFS};
use crate::sim::{FlightPlan, SimError, Simulator, TrimPoint};
use serde::Serialize;

pub mod kinks;
pub mod notes;
pub use kinks::{compare_and_explain, ExplainedComparison};
use serde_json::json;
use std::collections::BTreeMap;

/// Failures of a comparison run.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The simulator failed (start, trim, linearize, fly).
    #[error("{during}: {source}")]
    Sim {
        /// What was being done.
        during: String,
        /// The simulator's error.
        source: SimError,
    },
    /// The record lacks a column the comparison needs.
    #[error("flight record: {0}")]
    Data(#[from] crate::data::DataError),
    /// Bad options.
    #[error("{0}")]
    Options(String),
}

/// Output state column of each paper transfer function.
pub fn output_column(tf_key: &str) -> &'static str {
    if tf_key.starts_with("theta") {
        "theta_rad"
    } else {
        "phi_rad"
    }
}

/// The transfer-function key excited by a surface (`elevator` → `theta/elevator`, ...).
pub fn tf_key_for(surface: &str) -> Option<&'static str> {
    PAPER_TFS
        .iter()
        .find(|(_, _, s, _)| *s == surface)
        .map(|(k, _, _, _)| *k)
}

/// A single-surface flight plan: the unit-peak `maneuver` scaled to `amplitude_deg`, starting at `start_s`.
pub fn single_surface_plan(
    surface: &str,
    maneuver: &Maneuver,
    amplitude_deg: f64,
    start_s: f64,
    duration_s: f64,
    rate_hz: f64,
) -> FlightPlan {
    FlightPlan::maneuver(
        &[surface],
        maneuver,
        amplitude_deg.to_radians(),
        start_s,
        duration_s,
        rate_hz,
    )
}

/// Surface deflection and output state of a record as perturbations from the first (trim) sample, rad.
pub fn perturbations(
    rec: &crate::data::FlightRecord,
    surface: &str,
    tf_key: &str,
) -> Result<(Vec<f64>, Vec<f64>), CompareError> {
    let u = rec.require(format!("{surface}_rad"), "the identification input")?;
    let y = rec.require(output_column(tf_key), "the identification output")?;
    Ok((
        u.iter().map(|x| x - u[0]).collect(),
        y.iter().map(|x| x - y[0]).collect(),
    ))
}

/// Model orders used for every paper transfer function (4 poles, 2 zeros, as in `flightid demo`).
pub fn paper_options(method: Method) -> IdentOptions {
    IdentOptions {
        method,
        poles: 4,
        zeros: 2,
        estimate_delay: false,
    }
}

/// Named modal parameters of a set of modes: the fastest oscillatory mode (`osc_omega_n_rad_s`, `osc_zeta`)
/// and the fastest real pole (`real_pole_rad_s`, negative when stable).
pub fn modal_summary(modes: &[Mode]) -> BTreeMap<String, f64> {
    let mut out = BTreeMap::new();
    let modes: Vec<&Mode> = modes
        .iter()
        .filter(|m| m.pole.re.is_finite() && m.pole.im.is_finite())
        .collect();
    if let Some(m) = modes
        .iter()
        .filter(|m| m.oscillatory)
        .max_by(|a, b| a.omega_n_rad_s.total_cmp(&b.omega_n_rad_s))
    {
        out.insert("osc_omega_n_rad_s".into(), m.omega_n_rad_s);
        out.insert("osc_zeta".into(), m.zeta);
    }
    if let Some(m) = modes
        .iter()
        .filter(|m| !m.oscillatory)
        .max_by(|a, b| a.pole.re.abs().total_cmp(&b.pole.re.abs()))
    {
        out.insert("real_pole_rad_s".into(), m.pole.re);
    }
    out
}

/// What `flightid compare` does.
#[derive(Debug, Clone)]
pub struct CompareOptions {
    /// Trim point.
    pub point: TrimPoint,
    /// Doublet amplitude of the main comparison, deg.
    pub amplitude_deg: f64,
    /// Doublet pulse width, s.
    pub pulse_s: f64,
    /// Record length, s.
    pub duration_s: f64,
    /// Estimators.
    pub methods: Vec<Method>,
    /// Amplitudes of the sweep, deg.
    pub sweep_amplitudes_deg: Vec<f64>,
    /// Simulation and sampling rate, Hz.
    pub rate_hz: f64,
}

/// One model's agreement with the nonlinear flight.
#[derive(Debug, Clone, Serialize)]
pub struct ModelFit {
    /// `jsbsim_linearization` or a method name.
    pub model: String,
    /// Modal summary (see [`modal_summary`]).
    pub modal: BTreeMap<String, f64>,
    /// Relative error of each modal quantity against the linearization, % (absent for the linearization).
    pub modal_error_percent: BTreeMap<String, f64>,
    /// Simulation fit against the nonlinear response, NRMSE %.
    pub fit_percent: f64,
    /// Integral of squared error of the simulated response, rad² s.
    pub ise_rad2_s: f64,
    /// Transfer function with poles and zeros.
    pub tf: Option<crate::sim::linear::TfJson>,
    /// Why the estimator failed, if it did.
    pub error: Option<String>,
    /// What a reader needs to know about these numbers (unstable poles, why a method drifts, ...).
    pub notes: Vec<String>,
}

/// The whole comparison, as JSON and as a report.
#[derive(Debug, Clone, Serialize)]
pub struct CompareOutcome {
    /// Aircraft name.
    pub aircraft: String,
    /// Trim state.
    pub trim: crate::sim::TrimState,
    /// Per transfer function, one entry per model.
    pub models: BTreeMap<String, Vec<ModelFit>>,
    /// Amplitude sweep: per transfer function, per model, (amplitude deg, fit %).
    pub sweep: BTreeMap<String, BTreeMap<String, Vec<(f64, f64)>>>,
    /// Largest amplitude at which the linearization still fits the flight within 5 points of its best fit.
    pub linear_up_to_deg: BTreeMap<String, f64>,
}

fn sim_err(during: &str) -> impl FnOnce(SimError) -> CompareError + '_ {
    move |source| CompareError::Sim {
        during: during.to_string(),
        source,
    }
}

/// Runs the comparison on a started simulator: trim, linearize, doublets, identification, amplitude sweep.
pub fn run_compare<S: Simulator>(
    sim: &mut S,
    opts: &CompareOptions,
) -> Result<(CompareOutcome, Report), CompareError> {
    if opts.methods.is_empty() {
        return Err(CompareError::Options(
            "no identification method given".into(),
        ));
    }
    if !(opts.duration_s > 4.0 * opts.pulse_s && opts.pulse_s > 0.0) {
        return Err(CompareError::Options(format!(
            "record length {} s too short for a doublet of pulse {} s",
            opts.duration_s, opts.pulse_s
        )));
    }
    let amplitude_ok = |a: f64| a.is_finite() && a > 0.0 && a <= 30.0;
    if !amplitude_ok(opts.amplitude_deg) {
        return Err(CompareError::Options(format!(
            "doublet amplitude must be within (0, 30] deg, got {}",
            opts.amplitude_deg
        )));
    }
    if opts.sweep_amplitudes_deg.is_empty()
        || !opts.sweep_amplitudes_deg.iter().all(|a| amplitude_ok(*a))
    {
        return Err(CompareError::Options(
            "sweep amplitudes must be given, each within (0, 30] deg".into(),
        ));
    }
    if !(opts.rate_hz.is_finite() && (10.0..=2000.0).contains(&opts.rate_hz)) {
        return Err(CompareError::Options(format!(
            "rate must be within 10..2000 Hz, got {}",
            opts.rate_hz
        )));
    }
    let trim = sim.trim(&opts.point).map_err(sim_err("trim"))?;
    let lin = sim.linearize().map_err(sim_err("linearize"))?;
    let truth = paper_transfer_functions(&lin).map_err(sim_err("linearization reduction"))?;
    let rate_hz = opts.rate_hz;
    let dt_s = 1.0 / rate_hz;
    let doublet = Maneuver::Doublet {
        pulse_s: opts.pulse_s,
    };
    let mut report = Report {
        title: format!(
            "{}: identified linear models vs JSBSim at {} ft, {} kts",
            trim.aircraft, opts.point.altitude_ft, opts.point.speed_kts
        ),
        sections: Vec::new(),
    };
    report.sections.push(Section {
        heading: "Setup".into(),
        paragraphs: vec![
            format!(
                "Trim: alpha {:.3} deg, theta {:.3} deg, throttle {:.3}. Each surface gets a {} deg doublet \
                 (pulse {} s) from trim, {} s recorded at {} Hz. Identified models have 4 poles and 2 zeros; the \
                 reference is JSBSim's linearization reduced to the decoupled 4-state submodels. Fits of the \
                 slow modes depend on the record length: `flightid demo` flies 30 s records and `flightid \
                 compare` 20 s by default, so their fit % differ for the same aircraft.",
                trim.alpha_rad.to_degrees(),
                trim.theta_rad.to_degrees(),
                trim.throttle,
                opts.amplitude_deg,
                opts.pulse_s,
                opts.duration_s,
                rate_hz
            ),
            format!(
                "Models: {}.",
                std::iter::once("jsbsim_linearization")
                    .chain(opts.methods.iter().map(|m| m.name()))
                    .map(|m| format!("{m} = {}", notes::in_full(m)))
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
        ],
        ..Default::default()
    });
    let mut models = BTreeMap::new();
    let mut sweep = BTreeMap::new();
    let mut linear_up_to_deg = BTreeMap::new();
    let omega: Vec<f64> = (0..200)
        .map(|k| 10f64.powf(-2.0 + 4.0 * k as f64 / 199.0))
        .collect();
    for (key, _, surface, _) in PAPER_TFS {
        let lin_tf = &truth[key];
        sim.trim(&opts.point).map_err(sim_err("trim"))?;
        let plan = single_surface_plan(
            surface,
            &doublet,
            opts.amplitude_deg,
            1.0,
            opts.duration_s,
            rate_hz,
        );
        let rec = sim.fly(&plan).map_err(sim_err("fly"))?;
        let (du, dy) = perturbations(&rec, surface, key)?;
        let t = rec.time_s.clone();
        let lin_modal = modal_summary(&lti::modes(&lin_tf.poles()));
        let lin_y = lti::lsim(lin_tf, &du, dt_s);
        let mut fits = vec![ModelFit {
            model: "jsbsim_linearization".into(),
            modal: lin_modal.clone(),
            modal_error_percent: BTreeMap::new(),
            fit_percent: ident::nrmse_fit(&dy, &lin_y),
            ise_rad2_s: ident::ise(&dy, &lin_y, dt_s),
            tf: Some(tf_json(lin_tf)),
            error: None,
            notes: Vec::new(),
        }];
        let deg = |v: &[f64]| v.iter().map(|x| x.to_degrees()).collect::<Vec<_>>();
        let reference = |label: &str, x: &[f64], y: Vec<f64>| Series {
            reference: true,
            ..Series::new(label, x.to_vec(), y)
        };
        let mut time_series = vec![
            Series::new("JSBSim nonlinear", t.clone(), deg(&dy)),
            reference("JSBSim linearization", &t, deg(&lin_y)),
        ];
        let (mag, ph) = lti::bode(lin_tf, &omega);
        let mut bode_mag = vec![reference("JSBSim linearization", &omega, mag)];
        let mut bode_phase = vec![reference("JSBSim linearization", &omega, ph)];
        let mut identified: Vec<(String, TransferFunction)> = Vec::new();
        let mut ls_one_step_percent = None;
        for &method in &opts.methods {
            match ident::identify(&du, &dy, dt_s, &paper_options(method)) {
                Ok(r) => {
                    if method == Method::Ls {
                        ls_one_step_percent = Some(r.fit_one_step_percent);
                    }
                    let y_hat = lti::lsim(&r.tf, &du, dt_s);
                    fits.push(model_fit(&r, &lin_modal, &dy, &y_hat, dt_s));
                    let limit = 3.0 * max_abs(&deg(&dy));
                    let label = if max_abs(&deg(&y_hat)) > limit {
                        format!("{} (clipped)", method.name())
                    } else {
                        method.name().to_string()
                    };
                    time_series.push(Series::new(label, t.clone(), clip(&deg(&y_hat), limit)));
                    let (mag, ph) = lti::bode(&r.tf, &omega);
                    bode_mag.push(Series::new(method.name(), omega.clone(), mag));
                    bode_phase.push(Series::new(method.name(), omega.clone(), ph));
                    identified.push((method.name().to_string(), r.tf.clone()));
                }
                Err(e) => fits.push(ModelFit {
                    model: method.name().into(),
                    modal: BTreeMap::new(),
                    modal_error_percent: BTreeMap::new(),
                    fit_percent: f64::NAN,
                    ise_rad2_s: f64::NAN,
                    tf: None,
                    error: Some(e.to_string()),
                    notes: Vec::new(),
                }),
            }
        }
        notes::note_oe_repeating_srivc(&mut fits);
        notes::note_ls_drift(&mut fits, ls_one_step_percent);
        // amplitude sweep: the fixed linear models against fresh nonlinear flights at each amplitude
        let mut curves: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
        for &amp_deg in &opts.sweep_amplitudes_deg {
            sim.trim(&opts.point).map_err(sim_err("trim"))?;
            let plan =
                single_surface_plan(surface, &doublet, amp_deg, 1.0, opts.duration_s, rate_hz);
            let rec = match sim.fly(&plan) {
                Ok(r) => r,
                Err(_) => continue,
            };
            let (du, dy) = perturbations(&rec, surface, key)?;
            let mut push = |name: &str, tf: &TransferFunction| {
                let fit = ident::nrmse_fit(&dy, &lti::lsim(tf, &du, dt_s));
                curves
                    .entry(name.to_string())
                    .or_default()
                    .push((amp_deg, fit));
            };
            push("jsbsim_linearization", lin_tf);
            for (name, tf) in &identified {
                push(name, tf);
            }
        }
        if let Some(c) = curves.get("jsbsim_linearization") {
            let best = c.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
            let limit = c
                .iter()
                .filter(|p| p.1 >= best - 5.0)
                .map(|p| p.0)
                .fold(f64::NAN, f64::max);
            linear_up_to_deg.insert(key.to_string(), limit);
        }
        report.sections.push(tf_section(
            key,
            &fits,
            time_series,
            bode_mag,
            bode_phase,
            &curves,
            opts,
        ));
        models.insert(key.to_string(), fits);
        sweep.insert(key.to_string(), curves);
    }
    report.sections.insert(1, overview_section(&models));
    let outcome = CompareOutcome {
        aircraft: trim.aircraft.clone(),
        trim,
        models,
        sweep,
        linear_up_to_deg,
    };
    Ok((outcome, report))
}

fn model_fit(
    r: &IdentResult,
    lin_modal: &BTreeMap<String, f64>,
    dy: &[f64],
    y_hat: &[f64],
    dt_s: f64,
) -> ModelFit {
    let modal = modal_summary(&r.modes);
    let modal_error_percent = modal
        .iter()
        .filter_map(|(k, v)| {
            lin_modal
                .get(k)
                .map(|l| (k.clone(), 100.0 * (v - l) / l.abs().max(1e-12)))
        })
        .collect();
    let fit_percent = ident::nrmse_fit(dy, y_hat);
    ModelFit {
        model: r.method.clone(),
        modal,
        modal_error_percent,
        fit_percent,
        ise_rad2_s: ident::ise(dy, y_hat, dt_s),
        tf: Some(tf_json(&r.tf)),
        error: None,
        notes: notes::model_notes(r),
    }
}

/// The note column of a model's row: its failure, or its notes.
fn note_cell(f: &ModelFit) -> String {
    f.error
        .iter()
        .chain(&f.notes)
        .cloned()
        .collect::<Vec<_>>()
        .join("; ")
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Limits a plotted curve to ±`limit` so one diverging model does not flatten the others (the tables keep the
/// true numbers).
fn clip(v: &[f64], limit: f64) -> Vec<f64> {
    v.iter().map(|x| x.clamp(-limit, limit)).collect()
}

fn fmt(v: Option<&f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        _ => "-".into(),
    }
}

fn tf_section(
    key: &str,
    fits: &[ModelFit],
    time_series: Vec<Series>,
    bode_mag: Vec<Series>,
    bode_phase: Vec<Series>,
    curves: &BTreeMap<String, Vec<(f64, f64)>>,
    opts: &CompareOptions,
) -> Section {
    let stem = key.replace('/', "_");
    let (out, inp) = key.split_once('/').unwrap_or((key, ""));
    let (osc_mode, real_mode) = notes::mode_names(key);
    let quantities = [
        ("osc_omega_n_rad_s", format!("{osc_mode} ωn, rad/s")),
        ("osc_zeta", format!("{osc_mode} ζ")),
        ("real_pole_rad_s", format!("{real_mode}, rad/s")),
    ];
    let mut header = vec!["model".to_string()];
    for (_, label) in &quantities {
        header.push(label.clone());
        header.push("error %".to_string());
    }
    header.extend(["fit %".into(), "ISE, rad²·s".into(), "note".into()]);
    let rows = fits
        .iter()
        .map(|f| {
            let mut row = vec![f.model.clone()];
            for (q, _) in &quantities {
                row.push(fmt(f.modal.get(*q), 4));
                row.push(fmt(f.modal_error_percent.get(*q), 1));
            }
            row.push(fmt(Some(&f.fit_percent), 2));
            row.push(format!("{:.3e}", f.ise_rad2_s));
            row.push(note_cell(f));
            row
        })
        .collect();
    let pole_rows = fits
        .iter()
        .filter_map(|f| f.tf.as_ref().map(|tf| (f, tf)))
        .map(|(f, tf)| {
            let list = |v: &[[f64; 2]]| {
                v.iter()
                    .map(|z| format!("{:.3}{:+.3}j", z[0], z[1]))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            vec![f.model.clone(), list(&tf.poles), list(&tf.zeros)]
        })
        .collect();
    let sweep_series = curves
        .iter()
        .map(|(name, pts)| {
            let label = if name == "jsbsim_linearization" {
                "JSBSim linearization"
            } else {
                name.as_str()
            };
            Series {
                reference: name == "jsbsim_linearization",
                ..Series::new(
                    label,
                    pts.iter().map(|p| p.0).collect(),
                    pts.iter().map(|p| p.1.max(-50.0)).collect(),
                )
            }
        })
        .collect();
    Section {
        heading: format!("{out}/δ{} ({key})", &inp[..1.min(inp.len())]),
        paragraphs: vec![format!(
            "Errors are relative to JSBSim's linearization. Fit % and ISE compare each linear model's simulated \
             response with the nonlinear JSBSim flight ({} deg doublet); plotted curves are clipped at three \
             times the flight's peak and fits at -50 %. The sweep re-flies the doublet at \
             each amplitude and scores the same fixed models: where the curves fall, linearity ends.",
            opts.amplitude_deg
        )],
        tables: vec![
            Table {
                caption: format!("{key}: modal parameters, fit and ISE"),
                header,
                rows,
            },
            Table::new(format!("{key}: poles and zeros, rad/s"), &["model", "poles", "zeros"], pole_rows),
        ],
        plots: vec![
            (
                format!("{stem}_time"),
                LinePlot {
                    title: format!("{key}: nonlinear flight vs linear models"),
                    x_label: "time, s".into(),
                    y_label: format!("{out} perturbation, deg"),
                    series: time_series,
                    log_x: false,
                },
            ),
            (
                format!("{stem}_bode_mag"),
                LinePlot {
                    title: format!("{key}: Bode magnitude"),
                    x_label: "frequency, rad/s".into(),
                    y_label: "magnitude, dB (rad/rad)".into(),
                    series: bode_mag,
                    log_x: true,
                },
            ),
            (
                format!("{stem}_bode_phase"),
                LinePlot {
                    title: format!("{key}: Bode phase"),
                    x_label: "frequency, rad/s".into(),
                    y_label: "phase, deg".into(),
                    series: bode_phase,
                    log_x: true,
                },
            ),
            (
                format!("{stem}_sweep"),
                LinePlot {
                    title: format!("{key}: fit vs doublet amplitude"),
                    x_label: "doublet amplitude, deg".into(),
                    y_label: "simulation fit, %".into(),
                    series: sweep_series,
                    log_x: false,
                },
            ),
        ],
    }
}

/// One table of every model of every transfer function: the headline numbers before the details.
fn overview_section(models: &BTreeMap<String, Vec<ModelFit>>) -> Section {
    let rows = models
        .iter()
        .flat_map(|(key, fits)| {
            fits.iter().map(move |f| {
                vec![
                    key.clone(),
                    f.model.clone(),
                    notes::mode_names(key).0.to_string(),
                    fmt(f.modal.get("osc_omega_n_rad_s"), 4),
                    fmt(f.modal.get("osc_zeta"), 4),
                    fmt(f.modal.get("real_pole_rad_s"), 4),
                    fmt(Some(&f.fit_percent), 2),
                    note_cell(f),
                ]
            })
        })
        .collect();
    Section {
        heading: "Overview".into(),
        paragraphs: vec![
            "Fastest oscillatory mode and fastest real pole of each model, and how well each model's simulated \
             response fits the nonlinear JSBSim flight (NRMSE fit, 100 % = exact). Details per transfer function \
             below."
                .into(),
        ],
        tables: vec![Table::new(
            "Modal parameters and fit per model",
            &[
                "transfer function",
                "model",
                "oscillatory mode",
                "ωn osc, rad/s",
                "ζ osc",
                "real pole, rad/s",
                "fit %",
                "note",
            ],
            rows,
        )],
        plots: vec![],
    }
}

/// The JSON behind the report.
pub fn outcome_json(outcome: &CompareOutcome) -> serde_json::Value {
    serde_json::to_value(outcome).unwrap_or_else(|e| json!({"error": e.to_string()}))
}

/// A linearization fit below this (NRMSE %) is called a gap in the non-smooth-terms section.
pub const LINEARIZATION_GAP_FIT_PERCENT: f64 = 80.0;

/// Transfer functions whose linearization fits the nonlinear flight below [`LINEARIZATION_GAP_FIT_PERCENT`]:
/// (key, fit %).
pub fn linearization_gaps(outcome: &CompareOutcome) -> Vec<(String, f64)> {
    outcome
        .models
        .iter()
        .filter_map(|(key, fits)| {
            let lin = fits.iter().find(|f| f.model == "jsbsim_linearization")?;
            (lin.fit_percent < LINEARIZATION_GAP_FIT_PERCENT)
                .then(|| (key.clone(), lin.fit_percent))
        })
        .collect()
}

/// The linearization's fits with one kinked coefficient function removed from the model (flight and
/// linearization alike): how much of a gap that term explains.
#[derive(Debug, Clone, Serialize)]
pub struct KinkShare {
    /// The coefficient function scaled to 0.
    pub coefficient: String,
    /// Linearization fit %, per gap transfer function, without it.
    pub fit_percent_without: BTreeMap<String, f64>,
}

/// A term explains a gap when removing it closes at least half of the distance to a perfect fit.
fn explains(before: f64, after: f64) -> bool {
    after - before >= 0.5 * (100.0 - before)
}

/// "What the linearization cannot see": the model's coefficient functions with a kink at the trim point
/// ([`crate::sim::aero_truth::NonSmoothTerm`]), the transfer functions the linearization fits poorly (`gaps`, from
/// [`linearization_gaps`]), and for each kink the fits measured without it (`shares`), with a verdict per gap.
/// `None` when the model has no kink there.
pub fn nonsmooth_section(
    terms: &[crate::sim::aero_truth::NonSmoothTerm],
    outcome: &CompareOutcome,
    gaps: &[(String, f64)],
    shares: &[KinkShare],
) -> Option<Section> {
    if terms.is_empty() {
        return None;
    }
    let rows = terms
        .iter()
        .map(|t| {
            vec![
                t.coefficient.clone(),
                t.axis.clone(),
                t.variable.clone(),
                format!("{:+.4}", t.slope_below),
                format!("{:+.4}", t.slope_above),
                format!("{:+.4}", 0.5 * (t.slope_below + t.slope_above)),
            ]
        })
        .collect();
    let mut paragraphs = vec![
        "These coefficient functions of the JSBSim model change slope at the trim point (a term in |β|, a table \
         breakpoint). JSBSim's linearization takes central differences, so it uses the mean of the two slopes; in \
         flight the variable swings both ways and the term acts on both sides — for a term in |β| the effect has \
         the same sign whatever the input's sign, which no linear model can reproduce."
            .to_string(),
    ];
    if gaps.is_empty() {
        paragraphs.push(format!(
            "Every transfer function here fits the linearization at {LINEARIZATION_GAP_FIT_PERCENT:.0} % or \
             better, so these kinks matter little at this amplitude."
        ));
    }
    for (key, before) in gaps {
        let measured: Vec<(&str, f64)> = shares
            .iter()
            .filter_map(|k| Some((k.coefficient.as_str(), *k.fit_percent_without.get(key)?)))
            .collect();
        let effects = measured
            .iter()
            .map(|(c, after)| format!("{after:.1} % without {c}"))
            .collect::<Vec<_>>()
            .join("; ");
        let culprits: Vec<&str> = measured
            .iter()
            .filter(|(_, after)| explains(*before, *after))
            .map(|(c, _)| *c)
            .collect();
        paragraphs.push(match (measured.is_empty(), culprits.is_empty()) {
            (true, _) => format!(
                "The linearization fits {key} at {before:.1} %. To measure a term's share, rerun with it removed \
                 from the model: `flightid compare --aircraft {} --scale {}=0`.",
                outcome.aircraft, terms[0].coefficient
            ),
            (false, false) => format!(
                "The linearization fits {key} at {before:.1} % ({effects}, the model's other terms unchanged): \
                 {} explains the gap.",
                culprits.join(" and ")
            ),
            (false, true) => format!(
                "The linearization fits {key} at {before:.1} % ({effects}): no kink of the aerodynamic model \
                 explains this gap; look at the flight control system (spoilers, dampers, limits) or the slow \
                 modes."
            ),
        });
    }
    Some(Section {
        heading: "What the linearization cannot see: non-smooth terms at the trim".into(),
        paragraphs,
        tables: vec![Table::new(
            "Coefficient functions with a kink at the trim point (nondimensional slopes per rad; rates \
             per unit of p·b/2V, q·c̄/2V, r·b/2V)",
            &[
                "coefficient",
                "axis",
                "variable",
                "slope below trim",
                "slope above trim",
                "linearization uses",
            ],
            rows,
        )],
        plots: vec![],
    })
}
