//! Derivatives from measured records of any aircraft: the record's own air data, sensor positions moved to the
//! CG, the axis the record excites, and equation error over one or several records (`derivatives --data …
//! --airframe …`).
//!
//! Unlike the JSBSim study ([`super::study`]), nothing here comes from a trim or a simulator: mass, inertia,
//! geometry, thrust line and sensor positions come from an [`Airframe`]; dynamic pressure from the record's
//! `qbar_pa`, else ½ρV² with ρ from the logged `density_kg_m3`, `altitude_m` (ISA) or the airframe's
//! `flight.density_kg_m3`.
//!
//! Sensors away from the CG (Morelli & Klein §9.3, Jategaonkar §10.2): with r the sensor position in body axes,
//! - accelerometers: a_CG = a_IMU − ω̇ × r − ω × (ω × r);
//! - α vane: α_CG = α_v + (q x − p y)/V; β vane: β_CG = β_v − (r x − p z)/V
//!   (the local flow at the vane carries ω × r; first order in the rates).

use std::collections::BTreeMap;

use serde::Serialize;

use super::airframe::{Airframe, AirframeError, SensorPositions};
use super::regression::{
    consider_held_terms, equation_error, held_alphadot_note, lesq, savitzky_golay_derivative,
    EquationErrorOptions, FlightRecord as Channels, RegressionResult,
};
use super::AeroError;
use crate::data::{self, G0_M_S2};

mod air_data;
mod modes;
mod signs;
mod structure;
pub use air_data::{
    advanced, air_data, deskewed, moved_to_cg, skew_from_force_equation, standard_density_kg_m3,
    AirData, FORCE_EQUATION_SKEWS,
};
pub use modes::{
    lateral_modes_at, longitudinal_modes_at, model_constants, modes_with_uncertainty, theta_from,
    ModeEstimate,
};
pub use signs::sign_convention_notes;
pub use structure::{screen as structure_screen, Nonlinearity};

/// Why a measured-data estimate cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum MeasuredError {
    /// The airframe description lacks something the estimate needs (bad input).
    #[error(transparent)]
    Airframe(#[from] AirframeError),
    /// The record lacks a channel or is unusable (bad input).
    #[error("{file}: {message}")]
    Record {
        /// Which record.
        file: String,
        /// What is missing or wrong.
        message: String,
    },
    /// The estimation itself failed.
    #[error(transparent)]
    Aero(#[from] AeroError),
    /// The output-error or filter-error fit failed (or its problem is inconsistent).
    #[error(transparent)]
    Estimate(#[from] crate::estimate::EstimateError),
}

/// Which axis to estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisChoice {
    /// C_L, C_D, C_m (states V, α, θ, q).
    Longitudinal,
    /// C_Y, C_l, C_n (states β, p, r, φ).
    Lateral,
    /// Both.
    Both,
}

impl AxisChoice {
    /// Whether the longitudinal axis is included.
    pub fn longitudinal(self) -> bool {
        matches!(self, AxisChoice::Longitudinal | AxisChoice::Both)
    }

    /// Whether the lateral-directional axis is included.
    pub fn lateral(self) -> bool {
        matches!(self, AxisChoice::Lateral | AxisChoice::Both)
    }
}

/// A surface moves in a record when its peak-to-peak excursion exceeds both 0.5° and 20× its sample noise
/// (noise: [`crate::signal::difference_noise_std`], which the steps of a pulse train leave alone; the RMS
/// of the first differences counted each step as noise, and a 3-2-1-1 of ±1.6° logged at 25 Hz read as still).
pub fn surface_moves(values: &[f64]) -> bool {
    if values.len() < 3 {
        return false;
    }
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    hi - lo
        > 0.5f64
            .to_radians()
            .max(20.0 * crate::signal::difference_noise_std(values))
}

/// The axes a record excites: longitudinal when the elevator moves, lateral when the aileron or rudder moves.
pub fn excited_axis(rec: &data::FlightRecord) -> Option<AxisChoice> {
    let moves = |c: &str| rec.column(c).is_some_and(surface_moves);
    match (
        moves("elevator_rad"),
        moves("aileron_rad") || moves("rudder_rad"),
    ) {
        (true, true) => Some(AxisChoice::Both),
        (true, false) => Some(AxisChoice::Longitudinal),
        (false, true) => Some(AxisChoice::Lateral),
        (false, false) => None,
    }
}

/// Indices of the records that excite an axis (its surfaces move, [`excited_axis`]), or of all records when
/// none does (an axis forced with `--axis`).
pub fn records_exciting(
    records: &[(String, data::FlightRecord)],
    longitudinal: bool,
) -> Vec<usize> {
    let chosen: Vec<usize> = (0..records.len())
        .filter(|&i| {
            excited_axis(&records[i].1).is_some_and(|a| {
                if longitudinal {
                    a.longitudinal()
                } else {
                    a.lateral()
                }
            })
        })
        .collect();
    if chosen.is_empty() {
        (0..records.len()).collect()
    } else {
        chosen
    }
}

/// One estimated derivative.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// Value (nondimensional, per rad or per reference rate).
    pub value: f64,
    /// Standard error (equation error: coloured-residual corrected; output error: Cramér–Rao bound).
    pub std_error: f64,
}

/// Equation-error estimates from measured records.
#[derive(Debug, Clone)]
pub struct MeasuredEquationError {
    /// The axis estimated.
    pub axis: AxisChoice,
    /// Estimates by name (`Cm_alpha`, `Cm_0`, …).
    pub derivatives: BTreeMap<String, Estimate>,
    /// The stacked regressions.
    pub equations: Vec<RegressionResult>,
    /// Air data per record.
    pub air: Vec<AirData>,
    /// Equations left out and why.
    pub skipped: Vec<(String, String)>,
    /// Vane time skews removed before the regression: (record, column, skew s, what found it).
    pub skews: Vec<(String, String, f64, &'static str)>,
    /// Apparent vane lags the reconstruction found but that are longer than a data system's skew can be
    /// ([`data::skew_bound_s`]), left in: (record, column, lag s).
    pub refused_skews: Vec<(String, String, f64)>,
    /// Per coefficient, the angle of attack of its regression's rows (records stacked as the rows are) where
    /// every record has one: the structure screen's cross terms ([`structure_screen`]).
    pub alpha: BTreeMap<String, Vec<f64>>,
    /// Terms held at 0 whose physical range the σ carry ([`consider_held_terms`]): name and σ.
    pub considered: Vec<(String, f64)>,
}

/// One coefficient's regression over all records, each column the records' rows one after another.
struct Stacked {
    /// Term names.
    names: Vec<String>,
    /// Regressor columns.
    columns: Vec<Vec<f64>>,
    /// Response.
    response: Vec<f64>,
    /// The terms held and considered ([`RegressionResult::considered`]): the same for every record, since
    /// the options that decide them are.
    considered: Vec<(String, Vec<f64>)>,
}

/// Equation error (Morelli & Klein §5.1, [`equation_error`]) over several measured records: each record's
/// coefficients are reconstructed with its own airspeed, dynamic pressure and density and its sensors moved
/// to the CG; the regressions of all records are stacked into one least-squares problem per coefficient.
/// `records` pairs a name (for messages) with the record.
pub fn equation_error_measured(
    records: &[(String, data::FlightRecord)],
    airframe: &Airframe,
    axis: AxisChoice,
    include_alphadot: bool,
) -> Result<MeasuredEquationError, MeasuredError> {
    let lon = axis.longitudinal();
    let lat = axis.lateral();
    let purpose = |what: &str| format!("equation error on the {what} axis");
    // Mass and inertia: the axis's own must be known; the other inertias only scale the inertial coupling
    // terms, (I_xx − I_zz) p r in C_m and (I_zz − I_yy) q r, (I_yy − I_xx) p q in C_l, C_n. When unknown they
    // are set equal to a known one, which drops the coupling (small on a maneuver of one axis).
    let mut mass =
        airframe.mass_properties(lon, &purpose(if lon { "longitudinal" } else { "lateral" }))?;
    if lat {
        let m = airframe.mass_properties(false, &purpose("lateral"))?;
        mass.ixx_kg_m2 = m.ixx_kg_m2;
        mass.izz_kg_m2 = m.izz_kg_m2;
    }
    if mass.iyy_kg_m2 <= 0.0 {
        mass.iyy_kg_m2 = mass.izz_kg_m2;
    }
    if mass.ixx_kg_m2 <= 0.0 || mass.izz_kg_m2 <= 0.0 {
        mass.ixx_kg_m2 = mass.iyy_kg_m2;
        mass.izz_kg_m2 = mass.iyy_kg_m2;
    }
    let mut geometry = airframe.geometry(lon, &purpose("longitudinal"))?;
    if lat {
        geometry.span_m = airframe.geometry(false, &purpose("lateral"))?.span_m;
    }
    if !geometry.span_m.is_finite() {
        geometry.span_m = geometry.chord_m;
    }
    if !geometry.chord_m.is_finite() {
        geometry.chord_m = geometry.span_m;
    }
    let mut stacked: BTreeMap<&'static str, Stacked> = BTreeMap::new();
    // α along each coefficient's rows; None once a record without it was stacked
    let mut alpha_rows: BTreeMap<&'static str, Option<Vec<f64>>> = BTreeMap::new();
    let mut air = Vec::new();
    let mut skipped = Vec::new();
    let mut skews = Vec::new();
    let mut refused_skews = Vec::new();
    let wanted: &[&str] = match axis {
        AxisChoice::Longitudinal => &["Cm", "CL"],
        AxisChoice::Lateral => &["Cl", "Cn", "CY"],
        AxisChoice::Both => &["Cm", "CL", "Cl", "Cn", "CY"],
    };
    // Each axis from the records that excite it: a lateral record's incidental pitch motion, stacked into the
    // C_m regression, biases C_mq by 20–30 % on the generated p51d and c310 records.
    let lon_records = records_exciting(records, true);
    let lat_records = records_exciting(records, false);
    for (i, (name, raw)) in records.iter().enumerate() {
        let wanted: Vec<&str> = wanted
            .iter()
            .copied()
            .filter(|c| {
                if matches!(*c, "Cm" | "CL") {
                    lon_records.contains(&i)
                } else {
                    lat_records.contains(&i)
                }
            })
            .collect();
        let ad = air_data(raw, airframe)?;
        if wanted.is_empty() {
            air.push(ad);
            continue;
        }
        let bad = |message: String| MeasuredError::Record {
            file: name.clone(),
            message,
        };
        let rec = moved_to_cg(raw, &airframe.sensors).map_err(|e| bad(e.to_string()))?;
        let (mut rec, found, mut refused) = deskewed(&rec);
        let thrust = if rec.column("thrust_n").is_some() {
            Some(airframe.thrust_line("a record with thrust_n")?)
        } else {
            None
        };
        let options = EquationErrorOptions {
            air_density_kg_m3: ad.density_kg_m3,
            g_m_s2: G0_M_S2,
            include_alphadot,
            consider_alphadot: true,
            thrust_inclination_rad: thrust.map_or(0.0, |t| t.inclination_rad),
            thrust_moment_arm_m: thrust.map_or(0.0, |t| t.moment_arm_m),
            propeller_torque: true,
            half_window: 3,
            ..EquationErrorOptions::default()
        };
        // A skew the reconstruction did not find (it cannot beside gusts the vane reads and the kinematics do
        // not), or refused as too long, is looked for in the force equation of the axis the record feeds.
        for (vane, coefficient, source) in FORCE_EQUATION_SKEWS {
            let feeds = if vane == data::Channel::Alpha {
                wanted.contains(&"CL")
            } else {
                wanted.contains(&"CY")
            };
            if !feeds || found.iter().any(|(c, _)| c.as_str() == vane.name()) {
                continue;
            }
            let fit = |r: &data::FlightRecord| {
                let res =
                    equation_error(&Channels::from_columns(r), &mass, &geometry, &options).ok()?;
                res.equations
                    .into_iter()
                    .find(|e| e.coefficient == coefficient)
            };
            if let Some((shifted, tau_s)) = skew_from_force_equation(&rec, vane, fit) {
                rec = shifted;
                refused.retain(|(c, _)| c.as_str() != vane.name());
                skews.push((name.clone(), vane.name().to_string(), tau_s, source));
            }
        }
        skews.extend(
            found
                .into_iter()
                .map(|(c, v)| (name.clone(), c, v, "flight-path reconstruction")),
        );
        refused_skews.extend(refused.into_iter().map(|(c, v)| (name.clone(), c, v)));
        let res = equation_error(&Channels::from_columns(&rec), &mass, &geometry, &options)
            .map_err(|e| match e {
                AeroError::BadRecord(m) => bad(m),
                other => MeasuredError::Aero(other),
            })?;
        for (c, why) in res.skipped {
            if wanted.contains(&c) {
                skipped.push((c.to_string(), format!("{name}: {why}")));
            }
        }
        for eq in res.equations {
            if !wanted.contains(&eq.coefficient) {
                continue;
            }
            let names: Vec<String> = eq.terms.iter().map(|t| t.name.clone()).collect();
            let entry = stacked.entry(eq.coefficient).or_insert_with(|| Stacked {
                names: names.clone(),
                columns: vec![Vec::new(); names.len()],
                response: Vec::new(),
                considered: eq
                    .considered
                    .iter()
                    .map(|(c, _)| (c.clone(), Vec::new()))
                    .collect(),
            });
            if entry.names != names {
                skipped.push((
                    eq.coefficient.to_string(),
                    format!(
                        "{name}: regressors {names:?} differ from the first record's; left out"
                    ),
                ));
                continue;
            }
            for (col, x) in entry.columns.iter_mut().zip(&eq.regressors) {
                col.extend_from_slice(x);
            }
            entry.response.extend_from_slice(&eq.response);
            for (col, (_, x)) in entry.considered.iter_mut().zip(&eq.considered) {
                col.1.extend_from_slice(x);
            }
            let rows = alpha_rows.entry(eq.coefficient).or_insert(Some(Vec::new()));
            match (rows.as_mut(), rec.column(data::Channel::Alpha)) {
                (Some(a), Some(alpha)) if alpha.len() == eq.response.len() => {
                    a.extend_from_slice(alpha)
                }
                _ => *rows = None,
            }
        }
        air.push(ad);
    }
    let mut equations = Vec::new();
    let mut derivatives = BTreeMap::new();
    let mut considered = Vec::new();
    for (coefficient, st) in stacked {
        let mut res = lesq(coefficient, &st.names, &st.columns, &st.response, None)?;
        res.considered = st.considered;
        considered.extend(consider_held_terms(&mut res));
        for t in &res.terms {
            derivatives.insert(
                t.name.clone(),
                Estimate {
                    value: t.value,
                    std_error: t.std_error_colored,
                },
            );
        }
        equations.push(res);
    }
    if equations.is_empty() {
        let why = skipped
            .iter()
            .map(|(c, w)| format!("{c}: {w}"))
            .collect::<Vec<_>>()
            .join("; ");
        return Err(MeasuredError::Record {
            file: names_of(records),
            message: format!("no coefficient equation could be formed ({why})"),
        });
    }
    Ok(MeasuredEquationError {
        axis,
        derivatives,
        equations,
        air,
        skipped,
        skews,
        refused_skews,
        alpha: alpha_rows
            .into_iter()
            .filter_map(|(c, a)| Some((c.to_string(), a?)))
            .collect(),
        considered,
    })
}

/// Mean flight condition of the records: the reference point of the dimensional derivatives and modes.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ReferenceCondition {
    /// Mean true airspeed, m/s.
    pub airspeed_m_s: f64,
    /// Mean air density, kg/m³.
    pub density_kg_m3: f64,
    /// Mean angle of attack (at the CG), rad.
    pub alpha_rad: f64,
    /// Mean pitch attitude, rad.
    pub theta_rad: f64,
    /// Mean elevator, rad.
    pub elevator_rad: f64,
    /// Mean thrust, N (0 when not measured).
    pub thrust_n: f64,
}

impl ReferenceCondition {
    /// Dynamic pressure ½ρV², Pa.
    pub fn qbar_pa(&self) -> f64 {
        0.5 * self.density_kg_m3 * self.airspeed_m_s * self.airspeed_m_s
    }
}

/// The mean condition over records (each already moved to the CG) and their densities.
pub fn reference_condition(recs: &[data::FlightRecord], air: &[AirData]) -> ReferenceCondition {
    let mean = |c: &str| {
        let (mut sum, mut n) = (0.0, 0usize);
        for r in recs {
            if let Some(v) = r.column(c) {
                sum += v.iter().sum::<f64>();
                n += v.len();
            }
        }
        if n > 0 {
            sum / n as f64
        } else {
            0.0
        }
    };
    ReferenceCondition {
        airspeed_m_s: mean("airspeed_m_s"),
        density_kg_m3: air.iter().map(|a| a.density_kg_m3).sum::<f64>() / air.len().max(1) as f64,
        alpha_rad: mean("alpha_rad"),
        theta_rad: mean("theta_rad"),
        elevator_rad: mean("elevator_rad"),
        thrust_n: mean("thrust_n"),
    }
}

/// Dimensional derivatives (Etkin & Reid §4.9 / Klein & Morelli Table 3.x conventions) from nondimensional
/// estimates at the reference condition: M_α = q̄Sc̄ C_mα/I_yy, M_q = q̄Sc̄² C_mq/(2V I_yy),
/// M_δe = q̄Sc̄ C_mδe/I_yy, Z_α = −q̄S C_Lα/(mV), L_β, L_p = q̄Sb² C_lp/(2V I_xx), L_r, L_δa, L_δr, N_β, N_p,
/// N_r, N_δa, N_δr likewise with I_zz, Y_β = q̄S C_Yβ/m. σ scales by the same factor.
///
/// And the primed roll and yaw derivatives (`Lprime_p`, `Nprime_da`, …), the inertia coupling I_xz folded in
/// so that ṗ = Σ L′_x x and ṙ = Σ N′_x x (McRuer, Ashkenas & Graham, *Aircraft Dynamics and Automatic
/// Control*, ch. 4): with
/// Γ = 1 − I_xz²/(I_xx I_zz), L′ = (L + (I_xz/I_xx) N)/Γ and N′ = (N + (I_xz/I_zz) L)/Γ. These are what a
/// model written as ṗ = L_p p + … estimates (Jategaonkar's lateral test cases). A derivative held at 0 counts
/// as 0; σ is |1/Γ| σ_L + |I_xz/(I_xx Γ)| σ_N (and likewise), an upper bound, as the correlation of the
/// two estimates is not carried here.
pub fn dimensional(
    est: &BTreeMap<String, Estimate>,
    airframe: &Airframe,
    cond: &ReferenceCondition,
) -> BTreeMap<String, Estimate> {
    let qs = cond.qbar_pa() * airframe.wing.area_m2.unwrap_or(f64::NAN);
    let v = cond.airspeed_m_s;
    let c = airframe.wing.mac_m.unwrap_or(f64::NAN);
    let b = airframe.wing.span_m.unwrap_or(f64::NAN);
    let i = airframe.inertia_kg_m2;
    let m = airframe.mass_kg.unwrap_or(f64::NAN);
    let table: [(&str, &str, f64); 18] = [
        ("M_alpha", "Cm_alpha", qs * c / i.iyy),
        ("M_q", "Cm_q", qs * c * c / (2.0 * v * i.iyy)),
        ("M_alphadot", "Cm_alphadot", qs * c * c / (2.0 * v * i.iyy)),
        ("M_de", "Cm_de", qs * c / i.iyy),
        ("Z_alpha", "CL_alpha", -qs / (m * v)),
        ("Z_de", "CL_de", -qs / (m * v)),
        ("X_u", "CD_V", -qs / (m * v)),
        ("Y_beta", "CY_beta", qs / m),
        ("L_beta", "Cl_beta", qs * b / i.ixx),
        ("L_p", "Cl_p", qs * b * b / (2.0 * v * i.ixx)),
        ("L_r", "Cl_r", qs * b * b / (2.0 * v * i.ixx)),
        ("L_da", "Cl_da", qs * b / i.ixx),
        ("L_dr", "Cl_dr", qs * b / i.ixx),
        ("N_beta", "Cn_beta", qs * b / i.izz),
        ("N_p", "Cn_p", qs * b * b / (2.0 * v * i.izz)),
        ("N_r", "Cn_r", qs * b * b / (2.0 * v * i.izz)),
        ("N_da", "Cn_da", qs * b / i.izz),
        ("N_dr", "Cn_dr", qs * b / i.izz),
    ];
    let mut out: BTreeMap<String, Estimate> = table
        .iter()
        .filter(|(_, _, k)| k.is_finite() && *k != 0.0)
        .filter_map(|(name, nondim, k)| {
            est.get(*nondim).map(|e| {
                (
                    name.to_string(),
                    Estimate {
                        value: e.value * k,
                        std_error: e.std_error * k.abs(),
                    },
                )
            })
        })
        .collect();
    let gamma = 1.0 - i.ixz * i.ixz / (i.ixx * i.izz);
    if i.ixx > 0.0 && i.izz > 0.0 && gamma.is_finite() {
        let zero = Estimate {
            value: 0.0,
            std_error: 0.0,
        };
        for x in ["beta", "p", "r", "da", "dr"] {
            let (l, n) = (out.get(&format!("L_{x}")), out.get(&format!("N_{x}")));
            if l.is_none() && n.is_none() {
                continue;
            }
            let (l, n) = (*l.unwrap_or(&zero), *n.unwrap_or(&zero));
            let combine = |own: Estimate, other: Estimate, k: f64| Estimate {
                value: (own.value + k * other.value) / gamma,
                std_error: (own.std_error + (k * other.std_error).abs()) / gamma.abs(),
            };
            out.insert(format!("Lprime_{x}"), combine(l, n, i.ixz / i.ixx));
            out.insert(format!("Nprime_{x}"), combine(n, l, i.ixz / i.izz));
        }
    }
    out
}

/// What `derivatives --data … --airframe …` reports, whatever the method.
#[derive(Debug, Clone, Serialize)]
pub struct MeasuredReport {
    /// `equation_error`, `output_error` or `filter_error`.
    pub method: &'static str,
    /// The axis estimated.
    pub axis: AxisChoice,
    /// Nondimensional estimates by name (flightid names: `Cm_alpha`, `Cl_p`, …; zero terms `Cm_0`, …).
    pub derivatives: BTreeMap<String, Estimate>,
    /// Dimensional derivatives at the reference condition ([`dimensional`]).
    pub dimensional: BTreeMap<String, Estimate>,
    /// Modes with σ.
    pub modes: Vec<ModeEstimate>,
    /// The mean flight condition.
    pub reference: ReferenceCondition,
    /// Air data per record: (record, density and its source).
    pub air_data: Vec<(String, AirData)>,
    /// Fit per output, % (output and filter error).
    pub fit_percent: BTreeMap<String, f64>,
    /// Whether every fit converged (output and filter error; absent for equation error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    /// Nonlinear terms the equation-error residuals follow ([`structure_screen`]); reported, not estimated.
    pub nonlinearities: Vec<Nonlinearity>,
    /// What the reader should know (skipped equations, fixed terms, convergence).
    pub notes: Vec<String>,
}

impl MeasuredReport {
    /// The JSON document: `{"derivatives": {"Cm_alpha": {"value", "std_error"}}, "modes": […], …}`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }

    /// The text tables.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "{} ({}) at V = {:.1} m/s, ρ = {:.4} kg/m³, q̄ = {:.0} Pa\n\n",
            self.method.replace('_', " "),
            match self.axis {
                AxisChoice::Longitudinal => "longitudinal axis",
                AxisChoice::Lateral => "lateral-directional axis",
                AxisChoice::Both => "both axes",
            },
            self.reference.airspeed_m_s,
            self.reference.density_kg_m3,
            self.reference.qbar_pa()
        );
        out += &format!(
            "{:<14} {:>12} {:>12} {:>8}\n",
            "derivative", "value", "std error", "σ/|v| %"
        );
        for (k, e) in &self.derivatives {
            out += &format!(
                "{:<14} {:>12.5} {:>12.5} {:>8.1}\n",
                k,
                e.value,
                e.std_error,
                100.0 * e.std_error / e.value.abs().max(1e-12)
            );
        }
        if !self.dimensional.is_empty() {
            out += &format!(
                "\n{:<14} {:>12} {:>12}\n",
                "dimensional", "value", "std error"
            );
            for (k, e) in &self.dimensional {
                out += &format!("{:<14} {:>12.5} {:>12.5}\n", k, e.value, e.std_error);
            }
        }
        if !self.modes.is_empty() {
            out += "\nmodes\n";
            for m in &self.modes {
                match (m.mode.omega_n_rad_s, m.mode.zeta, m.mode.pole_1_s) {
                    (Some(w), Some(z), _) => {
                        out += &format!(
                            "{:<14} ωn {:.4} ± {:.4} rad/s, ζ {:.4} ± {:.4}\n",
                            m.mode.mode,
                            w,
                            m.omega_n_std.unwrap_or(f64::NAN),
                            z,
                            m.zeta_std.unwrap_or(f64::NAN)
                        )
                    }
                    (_, _, Some(p)) => {
                        out += &format!(
                            "{:<14} pole {:.4} ± {:.4} 1/s\n",
                            m.mode.mode,
                            p,
                            m.pole_std.unwrap_or(f64::NAN)
                        )
                    }
                    _ => {}
                }
            }
        }
        if !self.fit_percent.is_empty() {
            out += "\nfit %: ";
            out += &self
                .fit_percent
                .iter()
                .map(|(k, v)| format!("{k} {v:.1}"))
                .collect::<Vec<_>>()
                .join(", ");
            out += "\n";
        }
        for n in &self.notes {
            out += &format!("- {n}\n");
        }
        out
    }
}

/// The names of `records`, comma separated (the `file` of an error about all of them).
pub(super) fn names_of<'a>(
    records: impl IntoIterator<Item = &'a (String, data::FlightRecord)>,
) -> String {
    records
        .into_iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The equation-error report: estimates, dimensional derivatives, modes (σ from the diagonal of the
/// estimates' covariance: the equations are separate regressions), for records named by `records`.
pub fn equation_error_report(
    records: &[(String, data::FlightRecord)],
    airframe: &Airframe,
    axis: AxisChoice,
    include_alphadot: bool,
) -> Result<MeasuredReport, MeasuredError> {
    use super::flight_models as fm;
    let ee = equation_error_measured(records, airframe, axis, include_alphadot)?;
    let moved: Vec<data::FlightRecord> = records
        .iter()
        .map(|(_, r)| moved_to_cg(r, &airframe.sensors))
        .collect::<Result<_, _>>()?;
    let cond = reference_condition(&moved, &ee.air);
    let mut modes = Vec::new();
    let diag = |theta_names: &[&str], free: &[usize]| -> Vec<Vec<f64>> {
        free.iter()
            .enumerate()
            .map(|(a, &k)| {
                let s = ee.derivatives[theta_names[k]].std_error;
                (0..free.len())
                    .map(|b| if a == b { s * s } else { 0.0 })
                    .collect()
            })
            .collect()
    };
    if axis.longitudinal() && ee.derivatives.contains_key("Cm_alpha") {
        let c = model_constants(airframe, true, cond.airspeed_m_s)?;
        let (theta, free) = theta_from(&fm::LONGITUDINAL_PARAMETERS, &ee.derivatives);
        let cov = diag(&fm::LONGITUDINAL_PARAMETERS, &free);
        modes.extend(modes_with_uncertainty(&theta, &free, &cov, |t| {
            longitudinal_modes_at(&c, &cond, t, true)
        }));
    }
    if axis.lateral() && ee.derivatives.contains_key("Cl_p") && ee.derivatives.contains_key("Cn_r")
    {
        let c = model_constants(airframe, false, cond.airspeed_m_s)?;
        let (theta, free) = theta_from(&fm::LATERAL_PARAMETERS, &ee.derivatives);
        let cov = diag(&fm::LATERAL_PARAMETERS, &free);
        modes.extend(modes_with_uncertainty(&theta, &free, &cov, |t| {
            lateral_modes_at(&c, &cond, t)
        }));
    }
    let mut notes: Vec<String> = ee
        .skipped
        .iter()
        .map(|(c, why)| format!("{c} not estimated: {why}"))
        .collect();
    for (rec, col, v, source) in &ee.skews {
        notes.push(format!(
            "{rec}: {col} read {:.0} ms late ({source}); shifted back before the regression",
            1000.0 * v
        ));
    }
    for (rec, col, v) in &ee.refused_skews {
        notes.push(format!(
            "{rec}: {col} appears {:.0} ms late against the inertial data (flight-path reconstruction), longer \
             than a data system's skew can be: not shifted (in turbulence the vane reads gusts the kinematics \
             do not see)",
            1000.0 * v
        ));
    }
    for (_, sd) in &ee.considered {
        notes.push(held_alphadot_note(
            *sd,
            "add it as a regressor with --alphadot",
        ));
    }
    notes.extend(sign_convention_notes(&ee.derivatives));
    notes.extend(airframe.assumptions());
    let nonlinearities = structure_screen(&ee.equations, &ee.alpha);
    notes.extend(nonlinearities.iter().map(Nonlinearity::note));
    notes.push(
        "equation error: standard errors corrected for coloured residuals (Morelli & Klein eq. 5.73); \
         the phugoid needs the drag equation, which only output error estimates"
            .into(),
    );
    Ok(MeasuredReport {
        method: "equation_error",
        axis,
        dimensional: dimensional(&ee.derivatives, airframe, &cond),
        derivatives: ee.derivatives,
        modes,
        reference: cond,
        air_data: records
            .iter()
            .map(|(n, _)| n.clone())
            .zip(ee.air.iter().cloned())
            .collect(),
        fit_percent: BTreeMap::new(),
        converged: None,
        nonlinearities,
        notes,
    })
}

#[cfg(test)]
mod tests;
