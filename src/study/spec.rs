//! What a derivative estimate needs besides the data: flight condition, mass, geometry and the truth to score
//! against (from a JSBSim trim, [`AeroTruth`]), the identified transfer functions (from `flightid identify
//! --json`), and the user's choice of free derivatives and model structure.

use std::str::FromStr;

use faer::Mat;
use serde_json::Value;

use crate::aero::fit::{IdentifiedTf, IdentifiedTfs};
use crate::aero::model::{AeroModel, TfOutput};
use crate::aero::params::{
    Assumptions, Derivative, Derivatives, FlightCondition, Geometry, MassProperties,
};
use crate::aero::AeroError;
use crate::sim::aero_truth::AeroTruth;

/// Which model structure the transfer-function route fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Structure {
    /// The paper's simplifying assumptions ([`Assumptions::paper`]).
    Paper,
    /// Every term the model knows, with JSBSim's wind-axis side force ([`full_assumptions`]).
    Full,
}

impl Structure {
    /// The assumptions of this structure.
    pub fn assumptions(self) -> Assumptions {
        match self {
            Structure::Paper => Assumptions::paper(),
            Structure::Full => full_assumptions(),
        }
    }
}

/// Every term the model knows, and C_Y on the wind-axis side force as JSBSim defines it: the structure whose
/// modes match JSBSim's linearization (short period 0.1 %, Dutch roll ωn 0.1 %, ζ 2.5 %).
pub fn full_assumptions() -> Assumptions {
    Assumptions {
        side_force_in_wind_axes: true,
        ..Assumptions::textbook()
    }
}

/// The truth derivatives about the CG, body axes (lateral) and wind axes (lift, drag, side force), by name.
pub fn truth_derivatives(truth: &AeroTruth) -> Derivatives {
    let mut d = Derivatives::default();
    for &k in Derivative::ALL {
        if let Some(v) = truth.derivatives.get(k.name()) {
            d.set(k, *v);
        }
    }
    d
}

/// Body-axis mass and inertia of the truth.
pub fn truth_mass_body(truth: &AeroTruth) -> MassProperties {
    MassProperties {
        mass_kg: truth.mass_kg,
        ixx_kg_m2: truth.ixx_kg_m2,
        iyy_kg_m2: truth.iyy_kg_m2,
        izz_kg_m2: truth.izz_kg_m2,
        ixz_kg_m2: truth.ixz_kg_m2,
    }
}

/// Reference geometry of the truth.
pub fn truth_geometry(truth: &AeroTruth) -> Geometry {
    Geometry {
        wing_area_m2: truth.wing_area_m2,
        span_m: truth.span_m,
        chord_m: truth.chord_m,
    }
}

/// The parametric model at the truth's trim (level flight), lateral derivatives and inertia rotated into
/// stability axes at the trim α.
pub fn model_from_truth(
    truth: &AeroTruth,
    assumptions: Assumptions,
) -> Result<AeroModel, AeroError> {
    let g_m_s2 = if truth.g_m_s2 > 0.0 {
        truth.g_m_s2
    } else {
        9.80665
    };
    let model = AeroModel {
        flight: FlightCondition {
            airspeed_m_s: truth.airspeed_m_s,
            air_density_kg_m3: truth.rho_kg_m3,
            cl_trim: truth.coefficients.get("CL").copied().unwrap_or(f64::NAN),
            flight_path_angle_rad: 0.0,
            g_m_s2,
        },
        mass: truth_mass_body(truth).to_stability_axes(truth.alpha_rad),
        geometry: truth_geometry(truth),
        derivatives: truth_derivatives(truth).body_to_stability(truth.alpha_rad),
        assumptions,
    };
    model.validate()?;
    Ok(model)
}

/// Parses derivative names (`Cm_alpha`, `Cl_p`, …); an unknown name is an error that lists the known ones.
pub fn parse_derivatives(names: &[String]) -> Result<Vec<Derivative>, AeroError> {
    let mut out = Vec::new();
    for n in names {
        let d = Derivative::from_str(n.trim())?;
        if !out.contains(&d) {
            out.push(d);
        }
    }
    Ok(out)
}

/// Which paper transfer function an identification (input column, output column) is.
fn tf_output(input: &str, output: &str) -> Option<TfOutput> {
    match (input.trim_end_matches("_rad"), output) {
        ("elevator", "theta_rad") => Some(TfOutput::THETA_ELEVATOR),
        ("aileron", "phi_rad") => Some(TfOutput::PHI_AILERON),
        ("rudder", "phi_rad") => Some(TfOutput::PHI_RUDDER),
        _ => None,
    }
}

fn numbers(v: &Value, what: &str, source: &str) -> Result<Vec<f64>, AeroError> {
    v.as_array()
        .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<_>>>())
        .ok_or_else(|| {
            AeroError::BadInput(format!("{source}: `{what}` must be an array of numbers"))
        })
}

/// The identified transfer function in one `flightid identify --json` output: `{input, output, result: {tf:
/// {num, den}, num_std, den_std}}`. Standard errors become a diagonal coefficient covariance.
pub fn identified_tf_from_json(
    v: &Value,
    source: &str,
) -> Result<(TfOutput, IdentifiedTf), AeroError> {
    let field = |k: &str| {
        v.get(k).and_then(Value::as_str).ok_or_else(|| {
            AeroError::BadInput(format!(
                "{source}: no `{k}`; expected the JSON of `flightid identify --json`"
            ))
        })
    };
    let (input, output) = (field("input")?, field("output")?);
    let which = tf_output(input, output).ok_or_else(|| {
        AeroError::BadInput(format!(
            "{source}: {output}/{input} is not one of the model's transfer functions \
             (theta_rad/elevator_rad, phi_rad/aileron_rad, phi_rad/rudder_rad)"
        ))
    })?;
    let result = v
        .get("result")
        .ok_or_else(|| AeroError::BadInput(format!("{source}: no `result`")))?;
    let tf = result
        .get("tf")
        .ok_or_else(|| AeroError::BadInput(format!("{source}: no `result.tf`")))?;
    let num = numbers(&tf["num"], "result.tf.num", source)?;
    let den = numbers(&tf["den"], "result.tf.den", source)?;
    let num_std = numbers(&result["num_std"], "result.num_std", source).unwrap_or_default();
    let den_std = numbers(&result["den_std"], "result.den_std", source).unwrap_or_default();
    let covariance = if num_std.len() == num.len()
        && den_std.len() == den.len()
        && den.first() == Some(&1.0)
        && den_std[1..]
            .iter()
            .chain(&num_std)
            .all(|s| s.is_finite() && *s > 0.0)
    {
        let stds: Vec<f64> = den_std[1..].iter().chain(&num_std).copied().collect();
        Some(Mat::from_fn(stds.len(), stds.len(), |i, j| {
            if i == j {
                stds[i] * stds[i]
            } else {
                0.0
            }
        }))
    } else {
        None
    };
    Ok((
        which,
        IdentifiedTf {
            num,
            den,
            covariance,
        },
    ))
}

/// All identified transfer functions in a JSON document: one `flightid identify --json` output or an array of
/// them. A transfer function given twice is an error.
pub fn identified_tfs_from_json(
    docs: &[(String, Value)],
    into: &mut IdentifiedTfs,
) -> Result<(), AeroError> {
    for (source, doc) in docs {
        let items: Vec<&Value> = match doc {
            Value::Array(a) => a.iter().collect(),
            other => vec![other],
        };
        for item in items {
            let (which, tf) = identified_tf_from_json(item, source)?;
            if into.tfs.iter().any(|(o, _)| *o == which) {
                return Err(AeroError::BadInput(format!(
                    "{source}: {} given twice",
                    which.label()
                )));
            }
            into.tfs.push((which, tf));
        }
    }
    Ok(())
}

/// Mass and inertia as a user gives them (every field required), body axes.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct MassInput {
    mass_kg: f64,
    ixx_kg_m2: f64,
    iyy_kg_m2: f64,
    izz_kg_m2: f64,
    ixz_kg_m2: f64,
}

/// Reference geometry as a user gives it (every field required).
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct GeometryInput {
    wing_area_m2: f64,
    span_m: f64,
    chord_m: f64,
}

/// Replaces the model's mass and geometry by the `mass` and `geometry` objects of an identified-TF document, if
/// it has them (a real aircraft whose JSBSim model is only approximate). Missing or unusable fields are errors
/// naming the field.
/// `alpha0_rad` is the trim α used to rotate the body-axis inertia into stability axes.
pub fn apply_overrides(
    doc: &Value,
    source: &str,
    alpha0_rad: f64,
    model: &mut AeroModel,
) -> Result<(), AeroError> {
    if let Some(m) = doc.get("mass") {
        let m: MassInput = serde_json::from_value(m.clone()).map_err(|e| {
            AeroError::BadInput(format!(
                "{source}: mass: {e} (needs mass_kg, ixx_kg_m2, iyy_kg_m2, izz_kg_m2, ixz_kg_m2, body axes)"
            ))
        })?;
        let body = MassProperties {
            mass_kg: m.mass_kg,
            ixx_kg_m2: m.ixx_kg_m2,
            iyy_kg_m2: m.iyy_kg_m2,
            izz_kg_m2: m.izz_kg_m2,
            ixz_kg_m2: m.ixz_kg_m2,
        };
        body.validate()?;
        model.mass = body.to_stability_axes(alpha0_rad);
    }
    if let Some(g) = doc.get("geometry") {
        let g: GeometryInput = serde_json::from_value(g.clone()).map_err(|e| {
            AeroError::BadInput(format!(
                "{source}: geometry: {e} (needs wing_area_m2, span_m, chord_m)"
            ))
        })?;
        model.geometry = Geometry {
            wing_area_m2: g.wing_area_m2,
            span_m: g.span_m,
            chord_m: g.chord_m,
        };
        model.geometry.validate()?;
    }
    Ok(())
}
