//! Modes of the built-in flight models at a reference condition, with standard errors by first-order
//! propagation of the estimates' covariance through the eigenvalues (Jategaonkar §4.17), and the airframe
//! constants those models need.

use super::*;

/// A mode with the standard errors of its numbers (first-order propagation of the parameter covariance
/// through the model's eigenvalues, Jategaonkar §4.17).
#[derive(Debug, Clone, Serialize)]
pub struct ModeEstimate {
    /// The mode and its numbers.
    #[serde(flatten)]
    pub mode: crate::aero::flight_models::NamedMode,
    /// σ of ωn (oscillatory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_n_std: Option<f64>,
    /// σ of ζ (oscillatory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zeta_std: Option<f64>,
    /// σ of the pole (real).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pole_std: Option<f64>,
}

/// Modes of `modes_of(θ)` with σ from the covariance `cov` of the entries `free` of θ (delta method with
/// central differences, steps of 1e-3 σ; modes matched by name and order).
pub fn modes_with_uncertainty(
    theta: &[f64],
    free: &[usize],
    cov: &[Vec<f64>],
    modes_of: impl Fn(&[f64]) -> Vec<crate::aero::flight_models::NamedMode>,
) -> Vec<ModeEstimate> {
    let base = modes_of(theta);
    let numbers = |m: &crate::aero::flight_models::NamedMode| {
        [
            m.omega_n_rad_s.unwrap_or(f64::NAN),
            m.zeta.unwrap_or(f64::NAN),
            m.pole_1_s.unwrap_or(f64::NAN),
        ]
    };
    // Jacobian rows: d(mode number)/dθ_j for each free j.
    let mut grads: Vec<Vec<[f64; 3]>> = vec![Vec::new(); base.len()];
    for (j, &k) in free.iter().enumerate() {
        let h = (1e-3 * cov[j][j].max(0.0).sqrt()).max(1e-9 * theta[k].abs().max(1e-6));
        let (mut up, mut dn) = (theta.to_vec(), theta.to_vec());
        up[k] += h;
        dn[k] -= h;
        let (mu, md) = (modes_of(&up), modes_of(&dn));
        for (i, m) in base.iter().enumerate() {
            let same = |v: &Vec<crate::aero::flight_models::NamedMode>| {
                v.iter()
                    .filter(|x| x.mode == m.mode)
                    .nth(base[..i].iter().filter(|x| x.mode == m.mode).count())
                    .map(numbers)
            };
            let g = match (same(&mu), same(&md)) {
                (Some(a), Some(b)) => [0, 1, 2].map(|q| (a[q] - b[q]) / (2.0 * h)),
                _ => [f64::NAN; 3],
            };
            grads[i].push(g);
        }
    }
    base.into_iter()
        .zip(grads)
        .map(|(mode, g)| {
            let sd = |q: usize| {
                let mut var = 0.0;
                for a in 0..g.len() {
                    for b in 0..g.len() {
                        var += g[a][q] * cov[a][b] * g[b][q];
                    }
                }
                var.max(0.0).sqrt()
            };
            ModeEstimate {
                omega_n_std: mode.omega_n_rad_s.map(|_| sd(0)),
                zeta_std: mode.zeta.map(|_| sd(1)),
                pole_std: mode.pole_1_s.map(|_| sd(2)),
                mode,
            }
        })
        .collect()
}

/// The model constants of an airframe for an axis (missing keys named).
pub fn model_constants(
    airframe: &Airframe,
    longitudinal: bool,
    v_ref_m_s: f64,
) -> Result<crate::aero::flight_models::Constants, AirframeError> {
    let purpose = if longitudinal {
        "the longitudinal model"
    } else {
        "the lateral-directional model"
    };
    let mut mass = airframe.mass_properties(longitudinal, purpose)?;
    if longitudinal {
        // I_xx, I_zz do not enter the longitudinal equations.
        mass.ixx_kg_m2 = mass.iyy_kg_m2;
        mass.izz_kg_m2 = mass.iyy_kg_m2;
    } else if mass.iyy_kg_m2 <= 0.0 {
        // I_yy only enters the (I_yy − I_zz) q r coupling: taken as I_zz (coupling dropped) when unknown.
        mass.iyy_kg_m2 = mass.izz_kg_m2;
    }
    let thrust = airframe.thrust.unwrap_or_default();
    Ok(crate::aero::flight_models::Constants {
        mass,
        geometry: airframe.geometry(longitudinal, purpose)?,
        thrust_inclination_rad: thrust.inclination_rad,
        thrust_moment_arm_m: thrust.moment_arm_m,
        sensors: airframe.sensors,
        v_ref_m_s,
        alpha_ref_rad: 0.0,
        g_m_s2: G0_M_S2,
    })
}

/// Longitudinal modes of θ at the reference condition: the full model's Jacobian, or (`short_period_only`:
/// no drag terms estimated) the short period of its α–q block.
pub fn longitudinal_modes_at(
    c: &crate::aero::flight_models::Constants,
    cond: &ReferenceCondition,
    theta: &[f64],
    short_period_only: bool,
) -> Vec<crate::aero::flight_models::NamedMode> {
    use crate::aero::flight_models as fm;
    let u = fm::LonInputs {
        elevator_rad: cond.elevator_rad,
        thrust_n: cond.thrust_n,
        density_kg_m3: cond.density_kg_m3,
    };
    let f = |x: &[f64; 4]| fm::longitudinal(c, theta, x, &u).dx;
    let x0 = [cond.airspeed_m_s, cond.alpha_rad, cond.theta_rad, 0.0];
    if short_period_only {
        // α–q block: x = (α, q) with V and θ frozen.
        let g = |y: &[f64; 4]| {
            let d = f(&[x0[0], y[0], x0[2], y[1]]);
            [d[1], d[3], -y[2], -y[3]]
        };
        let ev = fm::jacobian_eigenvalues(g, [x0[1], 0.0, 0.0, 0.0]).unwrap_or_default();
        let sp: Vec<(f64, f64)> = ev
            .into_iter()
            .filter(|e| e.0 > -0.999 || e.1 != 0.0)
            .collect();
        return fm::longitudinal_modes(&sp)
            .into_iter()
            .filter(|m| m.mode.starts_with("short_period"))
            .collect();
    }
    fm::longitudinal_modes(&fm::jacobian_eigenvalues(f, x0).unwrap_or_default())
}

/// Lateral-directional modes of θ at the reference condition (wings level, β = p = r = 0).
pub fn lateral_modes_at(
    c: &crate::aero::flight_models::Constants,
    cond: &ReferenceCondition,
    theta: &[f64],
) -> Vec<crate::aero::flight_models::NamedMode> {
    use crate::aero::flight_models as fm;
    let u = fm::LatInputs {
        aileron_rad: 0.0,
        rudder_rad: 0.0,
        airspeed_m_s: cond.airspeed_m_s,
        alpha_rad: cond.alpha_rad,
        theta_rad: cond.theta_rad,
        q_rad_s: 0.0,
        density_kg_m3: cond.density_kg_m3,
        // the torque is a moment the thrust sets, not the lateral states: no part of the modes
        thrust_n: 0.0,
    };
    let f = |x: &[f64; 4]| fm::lateral(c, theta, x, &u).dx;
    fm::lateral_modes(&fm::jacobian_eigenvalues(f, [0.0; 4]).unwrap_or_default())
}

/// θ of a built-in model from named estimates (absent names 0), and the indices present.
pub fn theta_from(names: &[&str], est: &BTreeMap<String, Estimate>) -> (Vec<f64>, Vec<usize>) {
    let theta = names
        .iter()
        .map(|n| est.get(*n).map_or(0.0, |e| e.value))
        .collect();
    let free = (0..names.len())
        .filter(|&k| est.contains_key(names[k]))
        .collect();
    (theta, free)
}
