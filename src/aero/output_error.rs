//! Output error (and, through the same core, filter error) on measured records of any aircraft: the built-in
//! nondimensional flight models of [`super::flight_models`] fitted by [`crate::estimate::fit`]
//! (`derivatives --data … --airframe … --method oe`).
//!
//! The models are [`StateModel`]s of the estimation core; nothing here optimises, integrates or computes a
//! covariance. What this module decides is the estimation problem (Jategaonkar, *Flight Vehicle System
//! Identification*, 2nd ed., §4.3–4.5 and §8.3; Morelli & Klein, *Aircraft System Identification*, 2nd ed.,
//! §6.1–6.3):
//!
//! - **Longitudinal**: states x = (V, α, θ, q) at the CG; inputs δe, `thrust_n` when every record has it, and
//!   the record's air density (a constant column: ρ = mean 2 q̄/V², ISA or the airframe's); outputs V, α (at
//!   the vane), θ, q, a_x, a_z (at the IMU) and q̇, as far as every record carries them. The α vane's time
//!   skew τ_α is a model parameter (α_vane = α − q x_v/V − τ_α α̇).
//! - **Lateral-directional**: states (β, p, r, φ); inputs δa, δr and the measured V, α, θ, q as pseudo-inputs
//!   (Jategaonkar §8.3.2: the decoupled lateral model driven by the measured longitudinal motion) and ρ;
//!   outputs β (at the vane), p, r, φ, a_y (at the IMU), ṗ, ṙ.
//! - **Nuisance terms per record** (Jategaonkar §4.5.1): every initial state, and additive biases on the
//!   rate gyros and accelerometers (q, a_x, a_z, q̇; p, r, a_y, ṗ, ṙ). Biases of α, θ, β and φ are not
//!   estimated: with the zero terms C_L0, C_m0, C_D0 (C_Y0, C_l0, C_n0) free and the initial states
//!   estimated they are (nearly) linear combinations of those, and they move only the zero terms.
//! - **Start values** from equation error on the same records (Morelli & Klein §6.3: equation-error
//!   estimates are the usual start of the output-error iterations); the drag terms, which equation error
//!   does not estimate, from the trim: C_D ≈ (T cos(α + ε) − m g sin γ)/(q̄S) and the induced-drag slope
//!   C_Dα ≈ 2 C_L C_Lα/(π A e), e = 0.8.
//! - **Free or fixed** ([`FreeChoice`]): by default the zero terms, C_Lα, C_Lδe, C_Dα, C_mα, C_mq, C_mδe,
//!   the lateral β, p, r and control derivatives (not C_Yp, C_Yr, C_Yδa) and the vane skews are free; the
//!   speed derivatives (C_LV, C_DV, C_mV), the α̇ terms, C_Lq, C_Dδe and the curvature terms C_Lα², C_mα²
//!   are held (at 0, or a zero term at its equation-error value); the structure checks (`checks.rs`) free them
//!   on evidence. A surface no record moves has its derivatives held at 0.
//!
//! - **Filter error** adds to the longitudinal model the vertical gust states of [`super::flight_models`]
//!   (α_g and the rotary q_g, gain `gust_q_gain` estimated within ±1.5) with process noise on α_g and V; the
//!   lateral model keeps process noise on every state. Once C_Lq and C_mα̇ are free it ties the held C_Lα̇ to
//!   them by the tail's ratio, C_Lα̇ = C_Lq C_mα̇/C_mq (`lift_alphadot_tied`).
//! - **A held C_mα̇** is a consider parameter, 0 ± 0.2 |C_mq| (`free.rs`): where the records cannot separate it
//!   from C_mα, C_mq and C_mδe, their σ carry it. The α̇ check frees it where they can (filter error in gusts,
//!   once a vane skew is taken off the data: `checks.rs`).
//! - **Filter error and a vane skew**: a skew the skew check adopted is taken off the vane's data and the fit
//!   repeated with it held (`checks.rs`, `skew_taken_off`).
//!
//! Modes (short period, phugoid; Dutch roll, roll, spiral) are the eigenvalues of the model's Jacobian at the
//! mean flight condition, with σ by first-order propagation of the estimates' covariance through
//! central-difference derivatives of the eigenvalues (Jategaonkar §4.17; [`super::measured::modes_with_uncertainty`]).

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};

use super::airframe::Airframe;
use super::flight_models::{
    self as fm, Constants, LatInputs, LatOutput, LonInputs, LonOutput, LATERAL_PARAMETERS,
    LATERAL_STATES, LONGITUDINAL_PARAMETERS, LONGITUDINAL_STATES,
};
use super::measured::{
    air_data, dimensional, equation_error_measured, lateral_modes_at, longitudinal_modes_at,
    model_constants, modes_with_uncertainty, moved_to_cg, reference_condition, structure_screen,
    AirData, AxisChoice, Estimate, MeasuredError, MeasuredReport, ModeEstimate, Nonlinearity,
    ReferenceCondition,
};
use super::regression::{held_alphadot_note, PROPELLER_TORQUE};
use crate::data::{self, Channel, G0_M_S2};
use crate::estimate::{self, Method, Model, Nuisance, Parameter, Record, Signature, StateModel};

mod checks;
mod free;
mod records;
mod tie;
use checks::{
    alphadot_check, beta_skew_check, curvature_check, process_noise_note, run_checks,
    side_force_rate_check, skew_check, skew_taken_off, speed_check, AxisFitter, Check,
    StructureCheck, ALPHADOT, BETA_SKEW, CURVATURE, SIDE_RATES_AND_SKEW, SKEW, SPEED,
};
use free::{equation_error_starts, parameters, GUST_Q_GAIN, LAT_HELD, LON_HELD};
pub use free::{parse_free, FreeChoice, FREE_GROUPS};
use records::{
    core_record, derivatives_of_still_surfaces, mean_over_records, need, outputs_in_every_record,
    records_for, states_and_biases,
};
use tie::{
    lift_alphadot_indices, lift_alphadot_tied, tied_lift_alphadot, tied_lift_alphadot_sigma,
};

/// The modes of one axis's model at θ (the flight-model constants and the reference condition given).
type ModesAt = fn(&Constants, &ReferenceCondition, &[f64]) -> Vec<fm::NamedMode>;

/// Column of the air density input (a constant per record).
const DENSITY: &str = "density_kg_m3";

/// The longitudinal flight model as the estimation core sees it.
#[derive(Debug, Clone)]
pub struct LongitudinalModel {
    constants: Constants,
    signature: Signature,
    outputs: Vec<LonOutput>,
    /// Whether input 1 is `thrust_n` (else the density is input 1 and T = 0).
    thrust: bool,
    /// With the vertical gust states ([`fm::VerticalGust`]): their scale length L_w, m.
    gust_scale_m: Option<f64>,
    /// C_Lα̇ tied to C_Lq by the tail's ratio ([`lift_alphadot_tied`]); its own θ entry is then ignored.
    tied_lift_alphadot: bool,
}

impl LongitudinalModel {
    /// The model with these outputs; inputs `elevator_rad`, (`thrust_n`), `density_kg_m3`; with the vertical
    /// gust states after the four flight states when `gust_scale_m` is given (for the filter error method).
    pub fn new(
        constants: Constants,
        outputs: Vec<LonOutput>,
        thrust: bool,
        gust_scale_m: Option<f64>,
    ) -> Self {
        let mut inputs = vec!["elevator_rad".to_string()];
        if thrust {
            inputs.push("thrust_n".into());
        }
        inputs.push(DENSITY.into());
        let mut states: Vec<String> = LONGITUDINAL_STATES.map(String::from).to_vec();
        if gust_scale_m.is_some() {
            states.extend(fm::VerticalGust::STATES.map(String::from));
        }
        LongitudinalModel {
            constants,
            signature: Signature {
                parameters: LONGITUDINAL_PARAMETERS.map(String::from).to_vec(),
                states,
                inputs,
                outputs: outputs.iter().map(|o| o.column().to_string()).collect(),
            },
            outputs,
            thrust,
            gust_scale_m,
            tied_lift_alphadot: false,
        }
    }

    /// θ as the equations read it: with C_Lα̇ tied to C_Lq when [`lift_alphadot_tied`].
    fn theta<'a>(&self, theta: &'a [f64]) -> Cow<'a, [f64]> {
        if !self.tied_lift_alphadot {
            return Cow::Borrowed(theta);
        }
        let mut t = theta.to_vec();
        t[lift_alphadot_indices()[1]] = tied_lift_alphadot(theta);
        Cow::Owned(t)
    }

    fn inputs(&self, u: &[f64]) -> LonInputs {
        LonInputs {
            elevator_rad: u[0],
            thrust_n: if self.thrust { u[1] } else { 0.0 },
            density_kg_m3: u[if self.thrust { 2 } else { 1 }],
        }
    }
}

impl StateModel for LongitudinalModel {
    fn signature(&self) -> &Signature {
        &self.signature
    }

    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]) {
        let theta = &self.theta(theta)[..];
        let e = fm::longitudinal(&self.constants, theta, x, &self.inputs(u));
        dx[..4].copy_from_slice(&e.dx);
        if let Some(scale_m) = self.gust_scale_m {
            dx[4..6].copy_from_slice(&fm::VerticalGust::derivatives(&self.constants, scale_m, x));
        }
    }

    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]) {
        let theta = &self.theta(theta)[..];
        let e = fm::longitudinal(&self.constants, theta, x, &self.inputs(u));
        for (yo, o) in y.iter_mut().zip(&self.outputs) {
            *yo = o.value(&self.constants, theta, x, &e);
        }
    }
}

crate::model_from_state_model!(LongitudinalModel);

/// Inputs of the lateral-directional model, in order.
pub const LATERAL_INPUTS: [&str; 7] = [
    "aileron_rad",
    "rudder_rad",
    "airspeed_m_s",
    "alpha_rad",
    "theta_rad",
    "q_rad_s",
    DENSITY,
];

/// The lateral-directional flight model as the estimation core sees it.
#[derive(Debug, Clone)]
pub struct LateralModel {
    constants: Constants,
    signature: Signature,
    outputs: Vec<LatOutput>,
    /// Whether `thrust_n` follows [`LATERAL_INPUTS`] (else T = 0).
    thrust: bool,
}

impl LateralModel {
    /// The model with these outputs; inputs [`LATERAL_INPUTS`], then `thrust_n` with `thrust`.
    pub fn new(constants: Constants, outputs: Vec<LatOutput>, thrust: bool) -> Self {
        let mut inputs: Vec<String> = LATERAL_INPUTS.map(String::from).to_vec();
        if thrust {
            inputs.push("thrust_n".into());
        }
        LateralModel {
            constants,
            signature: Signature {
                parameters: LATERAL_PARAMETERS.map(String::from).to_vec(),
                states: LATERAL_STATES.map(String::from).to_vec(),
                inputs,
                outputs: outputs.iter().map(|o| o.column().to_string()).collect(),
            },
            outputs,
            thrust,
        }
    }

    fn inputs(&self, u: &[f64]) -> LatInputs {
        LatInputs {
            aileron_rad: u[0],
            rudder_rad: u[1],
            airspeed_m_s: u[2],
            alpha_rad: u[3],
            theta_rad: u[4],
            q_rad_s: u[5],
            density_kg_m3: u[6],
            thrust_n: if self.thrust { u[7] } else { 0.0 },
        }
    }
}

impl StateModel for LateralModel {
    fn signature(&self) -> &Signature {
        &self.signature
    }

    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]) {
        dx.copy_from_slice(&fm::lateral(&self.constants, theta, x, &self.inputs(u)).dx);
    }

    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]) {
        let inputs = self.inputs(u);
        let e = fm::lateral(&self.constants, theta, x, &inputs);
        for (yo, o) in y.iter_mut().zip(&self.outputs) {
            *yo = o.value(&self.constants, theta, x, &inputs, &e);
        }
    }
}

crate::model_from_state_model!(LateralModel);

/// Options of [`output_error_report`].
#[derive(Debug, Clone, Default)]
pub struct OutputErrorOptions {
    /// Output error or filter error (the core's method).
    pub method: Method,
    /// `--free` entries, applied in order after the defaults.
    pub free: Vec<FreeChoice>,
    /// Free the α̇ terms (as `--free alphadot`).
    pub alphadot: bool,
}

/// What every fit of an axis reads besides its records: the air data per record, the airframe, the mean
/// flight condition and the options.
#[derive(Clone, Copy)]
struct FitSetup<'a> {
    air: &'a BTreeMap<String, AirData>,
    airframe: &'a Airframe,
    cond: &'a ReferenceCondition,
    options: &'a OutputErrorOptions,
}

/// The result of one axis's fit.
struct AxisFit {
    estimate: estimate::Estimate,
    theta: Vec<f64>,
    constants: Constants,
}

/// Fits the longitudinal model to the records (module doc).
fn fit_longitudinal(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    notes: &mut Vec<String>,
) -> Result<AxisFit, MeasuredError> {
    let cond = setup.cond;
    let mut constants = model_constants(setup.airframe, true, cond.airspeed_m_s)?;
    // the curvature terms are expanded about the records' mean α (flight_models module doc)
    constants.alpha_ref_rad = cond.alpha_rad;
    let thrust = records.iter().all(|(_, r)| r.column("thrust_n").is_some());
    if thrust {
        setup.airframe.thrust_line("records with thrust_n")?;
    } else if records.iter().any(|(_, r)| r.column("thrust_n").is_some()) {
        notes.push("longitudinal: thrust_n is not in every record; thrust left out (T = 0; C_D0 absorbs it)".into());
    }
    let outputs =
        outputs_in_every_record(&LonOutput::ALL, LonOutput::column, records, "longitudinal")?;
    let gust_scale_m = (setup.options.method == Method::Fem)
        .then(|| fm::VerticalGust::scale_length_m(mean_over_records(records, "altitude_m")));
    let mut recs = Vec::new();
    for (name, raw) in records {
        let why = "the longitudinal model's states";
        let cg = moved_to_cg(raw, &setup.airframe.sensors).map_err(MeasuredError::Aero)?;
        // A state the record lacks starts from the others (α = θ, θ = α: γ ≈ 0; q = 0) and is estimated.
        let first = |c: &str| cg.column(c).map(|v| v[0]);
        let v0 = need(name, &cg, "airspeed_m_s", why)?[0];
        let (alpha0, theta0) =
            match (first("alpha_rad"), first("theta_rad")) {
                (Some(a), Some(t)) => (a, t),
                (Some(a), None) => (a, a),
                (None, Some(t)) => (t, t),
                (None, None) => return Err(MeasuredError::Record {
                    file: name.clone(),
                    message:
                        "neither alpha_rad nor theta_rad: the longitudinal model needs one of them"
                            .into(),
                }),
            };
        let mut x0 = vec![v0, alpha0, theta0, first("q_rad_s").unwrap_or(0.0)];
        if gust_scale_m.is_some() {
            // the gust starts calm; the filter's first corrections find it
            x0.extend([0.0; 2]);
        }
        let n = raw.len();
        let mut inputs =
            vec![need(name, raw, "elevator_rad", "the longitudinal model's input")?.to_vec()];
        if thrust {
            inputs.push(need(name, raw, "thrust_n", "")?.to_vec());
        }
        inputs.push(vec![setup.air[name.as_str()].density_kg_m3; n]);
        let columns: Vec<&str> = outputs.iter().map(|o| o.column()).collect();
        recs.push(core_record(name, raw, inputs, &columns, x0)?);
    }
    // Start values: equation error, then the trim (module doc).
    let starts = equation_error_starts(records, setup.airframe, AxisChoice::Longitudinal, notes);
    let qs = cond.qbar_pa() * constants.geometry.wing_area_m2;
    let span = constants.geometry.span_m;
    let aspect = if span.is_finite() {
        span * span / constants.geometry.wing_area_m2
    } else {
        7.0
    };
    let cl_alpha = starts
        .get("CL_alpha")
        .copied()
        .unwrap_or(2.0 * std::f64::consts::PI * aspect / (aspect + 2.0));
    let gamma = cond.theta_rad - cond.alpha_rad;
    let cl_ref = constants.mass.mass_kg * G0_M_S2 * gamma.cos() / qs;
    let cd_alpha = 2.0 * cl_ref * cl_alpha / (std::f64::consts::PI * aspect * 0.8);
    let cd_ref = if thrust {
        (cond.thrust_n * (cond.alpha_rad + constants.thrust_inclination_rad).cos()
            - constants.mass.mass_kg * G0_M_S2 * gamma.sin())
            / qs
    } else {
        0.03
    };
    let cm_alpha = starts.get("Cm_alpha").copied().unwrap_or(-0.5);
    let cm_de = starts.get("Cm_de").copied().unwrap_or(-1.0);
    let fallback: BTreeMap<&'static str, f64> = [
        ("CL_alpha", cl_alpha),
        ("CL_0", cl_ref - cl_alpha * cond.alpha_rad),
        ("CD_alpha", cd_alpha),
        ("CD_0", cd_ref - cd_alpha * cond.alpha_rad),
        ("Cm_alpha", cm_alpha),
        ("Cm_q", -10.0),
        ("Cm_de", cm_de),
        (GUST_Q_GAIN, 0.5),
        (
            "Cm_0",
            -(cm_alpha * cond.alpha_rad + cm_de * cond.elevator_rad),
        ),
    ]
    .into_iter()
    .collect();
    let mut still =
        derivatives_of_still_surfaces(records, &[(Channel::Elevator, ["CL_de", "CD_de", "Cm_de"])]);
    if !outputs.contains(&LonOutput::Alpha) {
        still.insert("tau_alpha_s");
    }
    // filter error estimates the rotary gust's gain; output error has no gust to hold it for
    let held: Vec<&str> = LON_HELD
        .iter()
        .copied()
        .filter(|&n| gust_scale_m.is_none() || n != GUST_Q_GAIN)
        .collect();
    let params = parameters(
        &LONGITUDINAL_PARAMETERS,
        &held,
        &starts,
        &fallback,
        &still,
        setup.options,
        notes,
    );
    let mut model = LongitudinalModel::new(constants, outputs.clone(), thrust, gust_scale_m);
    model.tied_lift_alphadot = lift_alphadot_tied(setup.options.method, |n| {
        params.iter().any(|p| p.name == n && !p.fixed)
    });
    let bias = [LonOutput::Q, LonOutput::Ax, LonOutput::Az, LonOutput::Qdot];
    let mut nuisance = states_and_biases(&outputs, &bias);
    if gust_scale_m.is_some() {
        // the atmosphere's process noise: the vertical gust, and the horizontal one on the airspeed
        nuisance.process_noise = Some(vec![0, 4]);
    }
    let mut fit = fit_model(&model, &params, &recs, &nuisance, setup.options, constants)?;
    if model.tied_lift_alphadot {
        // the held entry takes the tied value, for the modes and the report
        let clad = lift_alphadot_indices()[1];
        let v = tied_lift_alphadot(&fit.theta);
        fit.theta[clad] = v;
        fit.estimate.parameters[clad].value = v;
    }
    Ok(fit)
}

/// Fits the lateral-directional model to the records (module doc).
fn fit_lateral(
    records: &[&(String, data::FlightRecord)],
    setup: FitSetup,
    notes: &mut Vec<String>,
) -> Result<AxisFit, MeasuredError> {
    let constants = model_constants(setup.airframe, false, setup.cond.airspeed_m_s)?;
    let outputs = outputs_in_every_record(&LatOutput::ALL, LatOutput::column, records, "lateral")?;
    // The propeller's torque reaction follows the thrust (`aero::regression::PROPELLER_TORQUE`).
    let thrust = records.iter().all(|(_, r)| r.column("thrust_n").is_some());
    let mut recs = Vec::new();
    let mut zero_filled = BTreeSet::new();
    for (name, raw) in records {
        let cg = moved_to_cg(raw, &setup.airframe.sensors).map_err(MeasuredError::Aero)?;
        // A state the record lacks starts at 0 (wings level, no sideslip) and is estimated.
        let x0: Vec<f64> = LATERAL_STATES
            .iter()
            .map(|s| cg.column(s).map_or(0.0, |c| c[0]))
            .collect();
        need(name, raw, "airspeed_m_s", "the lateral model's input")?;
        let n = raw.len();
        let mut inputs: Vec<Vec<f64>> = LATERAL_INPUTS
            .iter()
            .map(|&c| {
                if c == DENSITY {
                    return vec![setup.air[name.as_str()].density_kg_m3; n];
                }
                match cg.column(c) {
                    Some(v) => v.to_vec(),
                    None => {
                        zero_filled.insert(c);
                        vec![0.0; n]
                    }
                }
            })
            .collect();
        if thrust {
            inputs.push(need(name, raw, "thrust_n", "")?.to_vec());
        }
        let columns: Vec<&str> = outputs.iter().map(|o| o.column()).collect();
        recs.push(core_record(name, raw, inputs, &columns, x0)?);
    }
    if !zero_filled.is_empty() {
        notes.push(format!(
            "lateral: {} not in every record; taken as 0 there",
            zero_filled.into_iter().collect::<Vec<_>>().join(", ")
        ));
    }
    let starts = equation_error_starts(records, setup.airframe, AxisChoice::Lateral, notes);
    let fallback: BTreeMap<&'static str, f64> = [
        ("CY_beta", -0.5),
        ("Cl_beta", -0.05),
        ("Cl_p", -0.4),
        ("Cl_r", 0.1),
        ("Cl_da", 0.1),
        ("Cl_dr", 0.01),
        ("Cn_beta", 0.1),
        ("Cn_p", -0.03),
        ("Cn_r", -0.15),
        ("Cn_da", -0.01),
        ("Cn_dr", -0.08),
    ]
    .into_iter()
    .collect();
    let controls = [
        (Channel::Aileron, ["CY_da", "Cl_da", "Cn_da"]),
        (Channel::Rudder, ["CY_dr", "Cl_dr", "Cn_dr"]),
    ];
    let mut still = derivatives_of_still_surfaces(records, &controls);
    if !outputs.contains(&LatOutput::Beta) {
        still.insert("tau_beta_s");
    }
    if !thrust {
        still.insert(PROPELLER_TORQUE);
    }
    let params = parameters(
        &LATERAL_PARAMETERS,
        &LAT_HELD,
        &starts,
        &fallback,
        &still,
        setup.options,
        notes,
    );
    let model = LateralModel::new(constants, outputs.clone(), thrust);
    let bias = [
        LatOutput::P,
        LatOutput::R,
        LatOutput::Ay,
        LatOutput::Pdot,
        LatOutput::Rdot,
    ];
    let nuisance = states_and_biases(&outputs, &bias);
    fit_model(&model, &params, &recs, &nuisance, setup.options, constants)
}

/// Runs the core on one model.
fn fit_model(
    model: &dyn Model,
    params: &[Parameter],
    records: &[Record],
    nuisance: &Nuisance,
    options: &OutputErrorOptions,
    constants: Constants,
) -> Result<AxisFit, MeasuredError> {
    let opts = estimate::Options {
        method: options.method,
        max_iterations: 100,
        ..estimate::Options::default()
    };
    let estimate = estimate::fit(model, params, records, nuisance, &opts)?;
    let theta = estimate.parameters.iter().map(|p| p.value).collect();
    Ok(AxisFit {
        estimate,
        theta,
        constants,
    })
}

/// Indices (in θ order) of the free parameters and their covariance block.
fn free_block(est: &estimate::Estimate) -> (Vec<usize>, Vec<Vec<f64>>) {
    let free: Vec<usize> = (0..est.parameters.len())
        .filter(|&i| !est.parameters[i].fixed)
        .collect();
    let k = free.len();
    let cov = est.covariance[..k]
        .iter()
        .map(|row| row[..k].to_vec())
        .collect();
    (free, cov)
}

/// Output error (or filter error) on measured records: the report of `derivatives --data … --airframe …
/// --method oe|fem` (module doc). `records` pairs a name with each record.
pub fn output_error_report(
    records: &[(String, data::FlightRecord)],
    airframe: &Airframe,
    axis: AxisChoice,
    options: &OutputErrorOptions,
) -> Result<MeasuredReport, MeasuredError> {
    let mut air = BTreeMap::new();
    let mut moved = Vec::new();
    for (name, rec) in records {
        air.insert(name.clone(), air_data(rec, airframe)?);
        moved.push(moved_to_cg(rec, &airframe.sensors)?);
    }
    let air_list: Vec<AirData> = records.iter().map(|(n, _)| air[n].clone()).collect();
    let cond = reference_condition(&moved, &air_list);
    let mut notes = Vec::new();
    let mut derivatives = BTreeMap::new();
    let mut modes = Vec::new();
    let mut fit_percent = BTreeMap::new();
    let mut converged = true;
    let mut fits = Vec::new();
    // A fit whose covariance could not be computed reports σ = 0 for its free parameters: say unknown (NaN,
    // null in JSON) rather than exact.
    let no_sigma = |f: &AxisFit| {
        f.estimate
            .parameters
            .iter()
            .filter(|p| !p.fixed)
            .all(|p| p.std_error == 0.0)
    };
    let unknown_sigma = |m: Vec<ModeEstimate>| -> Vec<ModeEstimate> {
        m.into_iter()
            .map(|m| ModeEstimate {
                omega_n_std: m.omega_n_std.map(|_| f64::NAN),
                zeta_std: m.zeta_std.map(|_| f64::NAN),
                pole_std: m.pole_std.map(|_| f64::NAN),
                ..m
            })
            .collect()
    };
    let setup = FitSetup {
        air: &air,
        airframe,
        cond: &cond,
        options,
    };
    // Per axis: the fit, its structure checks in turn (longitudinal: the vane skew, the α̇ terms (short
    // period), then the speed derivatives (phugoid)), the filter-error comparison and the modes.
    let check = |run: Check, frees: &'static [&'static str], tested: &'static [&'static str]| {
        StructureCheck { run, frees, tested }
    };
    let lon_checks = [
        check(skew_check, &SKEW, &SKEW),
        check(alphadot_check, &ALPHADOT, &ALPHADOT[..1]),
        check(speed_check, &SPEED, &SPEED),
        check(curvature_check, &CURVATURE, &CURVATURE),
    ];
    // lateral: the skew, then the side-force rate terms (with the skew: each takes the other's shape)
    let lat_checks = [
        check(beta_skew_check, &BETA_SKEW, &BETA_SKEW),
        check(
            side_force_rate_check,
            &SIDE_RATES_AND_SKEW,
            &SIDE_RATES_AND_SKEW[..2],
        ),
    ];
    let lon_modes: ModesAt = |c, cond, t| longitudinal_modes_at(c, cond, t, false);
    // (name, asked for, longitudinal, fit, checks, modes)
    let axes: [(&str, bool, bool, AxisFitter, _, ModesAt); 2] = [
        (
            "longitudinal",
            axis.longitudinal(),
            true,
            fit_longitudinal,
            &lon_checks[..],
            lon_modes,
        ),
        (
            "lateral",
            axis.lateral(),
            false,
            fit_lateral,
            &lat_checks[..],
            lateral_modes_at,
        ),
    ];
    for (name, wanted, longitudinal, fit_axis, checks, modes_at) in axes {
        if !wanted {
            continue;
        }
        let recs = records_for(records, longitudinal);
        let mut f = fit_axis(&recs, setup, &mut notes)?;
        let checked = run_checks(&recs, setup, &mut f, checks, &mut notes);
        let checked_setup = FitSetup {
            options: &checked,
            ..setup
        };
        let (f, deskew_note) = skew_taken_off(&recs, checked_setup, f, fit_axis)?;
        notes.extend(deskew_note.map(|n| format!("{name}: {n}")));
        notes.extend(process_noise_note(name, &f, &recs, checked_setup, fit_axis));
        let (free, cov) = free_block(&f.estimate);
        let m = modes_with_uncertainty(&f.theta, &free, &cov, |t| modes_at(&f.constants, &cond, t));
        modes.extend(if no_sigma(&f) { unknown_sigma(m) } else { m });
        fits.push((name, f, recs.len()));
    }
    for (name, f, n_records) in &fits {
        let est = &f.estimate;
        let sigma_known = !no_sigma(f);
        let tied = lift_alphadot_tied(est.method, |n| est.parameter(n).is_some_and(|p| !p.fixed));
        let mut held = Vec::new();
        for p in &est.parameters {
            if p.name == GUST_Q_GAIN {
                if !p.fixed {
                    notes.push(format!(
                        "{name}: rotary gust gain k_q = {:.2} ± {:.2} (1: the pitch-rate gust of MIL-F-8785C \
                         from the vertical gust; 0: none reaches the aerodynamics)",
                        p.value, p.std_error
                    ));
                }
                continue;
            }
            if p.name.starts_with("tau_") {
                if !p.fixed {
                    notes.push(format!(
                        "{name}: vane time skew {} = {:.1} ± {:.1} ms",
                        p.name,
                        1000.0 * p.value,
                        1000.0 * p.std_error
                    ));
                }
                continue;
            }
            if p.name == "CL_alphadot" && tied {
                let sd = if sigma_known {
                    tied_lift_alphadot_sigma(est)
                } else {
                    f64::NAN
                };
                notes.push(format!(
                    "{name}: C_Lα̇ = C_Lq C_mα̇/C_mq = {:.2} ± {sd:.2}: the records fix only C_Lq + C_Lα̇ (the \
                     accelerometer measures the whole lift), so the split is the tail's, C_Lα̇/C_Lq = C_mα̇/C_mq \
                     = dε/dα; C_Lq carries the rest of the lift's q̂ share",
                    p.value
                ));
                derivatives.insert(
                    p.name.clone(),
                    Estimate {
                        value: p.value,
                        std_error: sd,
                    },
                );
                continue;
            }
            if p.fixed {
                held.push(format!("{} = {:.4}", p.name, p.value));
                continue;
            }
            derivatives.insert(
                p.name.clone(),
                Estimate {
                    value: p.value,
                    std_error: if sigma_known { p.std_error } else { f64::NAN },
                },
            );
        }
        for (_, sd) in &est.considered {
            let note = held_alphadot_note(*sd, "free it with --free alphadot");
            notes.push(format!("{name}: {note}"));
        }
        if !held.is_empty() {
            notes.push(format!("{name}: held (not estimated): {}", held.join(", ")));
        }
        for (o, out) in est.outputs.iter().enumerate() {
            fit_percent.insert(out.clone(), est.fit_percent(o));
        }
        notes.push(format!(
            "{name}: {} record(s) fitted jointly, {} iterations, {}",
            n_records,
            est.iterations,
            match est.stop {
                estimate::StopReason::Converged => "converged".to_string(),
                other => {
                    converged = false;
                    format!(
                        "NOT CONVERGED ({other:?}): the estimates are not a minimum of the cost"
                    )
                }
            }
        ));
        notes.extend(est.warnings.iter().map(|w| format!("{name}: {w}")));
    }
    notes.push(format!(
        "{}: σ are {}; nuisance terms estimated per record: every initial state and the gyro and \
         accelerometer biases",
        match options.method {
            Method::Oe => "output error",
            Method::Fem =>
                "filter error (a steady-state Kalman filter in the loop, process noise on every \
                           state estimated)",
        },
        fits.first()
            .map_or("Cramér-Rao bounds", |f| f.1.estimate.covariance_method)
    ));
    notes.extend(super::measured::sign_convention_notes(&derivatives));
    notes.extend(airframe.assumptions());
    // The structure screen runs on equation error's regressions (the module doc of `structure`): one more
    // regression of the same records, cheap beside the fits; where it cannot be formed nothing is screened.
    let nonlinearities = equation_error_measured(records, airframe, axis, false)
        .map(|ee| structure_screen(&ee.equations, &ee.alpha))
        .unwrap_or_default();
    notes.extend(nonlinearities.iter().map(Nonlinearity::note));
    Ok(MeasuredReport {
        method: match options.method {
            Method::Oe => "output_error",
            Method::Fem => "filter_error",
        },
        axis,
        dimensional: dimensional(&derivatives, airframe, &cond),
        derivatives,
        modes,
        reference: cond,
        air_data: records
            .iter()
            .map(|(n, _)| (n.clone(), air[n].clone()))
            .collect(),
        fit_percent,
        converged: Some(converged),
        nonlinearities,
        notes,
    })
}

#[cfg(test)]
mod tests;
