//! The record moved to the CG: dynamic pressure and density from the record's own air data (ISA from
//! `altitude_m`, or the airframe's density), sensors away from the CG moved there (module doc of
//! [`super`]), and the time skews of α and β removed.

use super::*;
use crate::estimate::covariance;
use crate::signal::lever_arm_acceleration;

/// Air density of the 1976 US / ICAO standard atmosphere below 11 km: ρ = ρ0 (1 − L h/T0)^(g/(R L) − 1).
pub fn standard_density_kg_m3(altitude_m: f64) -> f64 {
    const RHO0: f64 = 1.225;
    const T0: f64 = 288.15;
    const LAPSE: f64 = 0.0065;
    const R: f64 = 287.052_87;
    let h = altitude_m.clamp(-1000.0, 11_000.0);
    RHO0 * (1.0 - LAPSE * h / T0).powf(G0_M_S2 / (R * LAPSE) - 1.0)
}

/// Where the record's air density comes from.
#[derive(Debug, Clone, Serialize)]
pub struct AirData {
    /// Mean density over the record, kg/m³.
    pub density_kg_m3: f64,
    /// `qbar_pa`, `density_kg_m3`, `altitude_m (ISA)` or `airframe flight.density_kg_m3`.
    pub source: String,
}

/// The record's air density: from `qbar_pa` and `airspeed_m_s` (ρ = 2 q̄/V², averaged), else the logged
/// `density_kg_m3` (averaged), else ISA at the mean `altitude_m`, else the airframe's `flight.density_kg_m3`.
pub fn air_data(rec: &data::FlightRecord, airframe: &Airframe) -> Result<AirData, AirframeError> {
    if let (Some(q), Some(v)) = (rec.column("qbar_pa"), rec.column("airspeed_m_s")) {
        let rho: Vec<f64> = q
            .iter()
            .zip(v)
            .filter(|(_, v)| **v > 1.0)
            .map(|(q, v)| 2.0 * q / (v * v))
            .collect();
        if !rho.is_empty() {
            return Ok(AirData {
                density_kg_m3: rho.iter().sum::<f64>() / rho.len() as f64,
                source: "qbar_pa".into(),
            });
        }
    }
    if let Some(rho) = rec.column("density_kg_m3").filter(|r| !r.is_empty()) {
        return Ok(AirData {
            density_kg_m3: rho.iter().sum::<f64>() / rho.len() as f64,
            source: "density_kg_m3".into(),
        });
    }
    if let Some(h) = rec.column("altitude_m").filter(|h| !h.is_empty()) {
        let mean = h.iter().sum::<f64>() / h.len() as f64;
        return Ok(AirData {
            density_kg_m3: standard_density_kg_m3(mean),
            source: "altitude_m (ISA)".into(),
        });
    }
    Ok(AirData {
        density_kg_m3: airframe.density("a record without qbar_pa or altitude_m")?,
        source: "airframe flight.density_kg_m3".into(),
    })
}

/// The record with α, β and the accelerations moved from their sensors to the CG (module doc). Rates not
/// in the record count as zero; angular accelerations are Savitzky–Golay derivatives of the rates.
pub fn moved_to_cg(
    rec: &data::FlightRecord,
    sensors: &SensorPositions,
) -> Result<data::FlightRecord, AeroError> {
    let n = rec.len();
    let mut out = rec.clone();
    let zeros = vec![0.0; n];
    let rate = |c: &str| rec.column(c).unwrap_or(&zeros).to_vec();
    let (p, q, r) = (rate("p_rad_s"), rate("q_rad_s"), rate("r_rad_s"));
    let dt = rec.dt_s().unwrap_or(f64::NAN);
    let imu = sensors.imu_m;
    if imu != [0.0; 3] && n > 12 {
        let d = |x: &[f64]| savitzky_golay_derivative(x, dt, 5, 2);
        let (pd, qd, rd) = (d(&p)?, d(&q)?, d(&r)?);
        let mut acc: Vec<Option<Vec<f64>>> = ["ax_m_s2", "ay_m_s2", "az_m_s2"]
            .iter()
            .map(|c| rec.column(c).map(|v| v.to_vec()))
            .collect();
        for i in 0..n {
            let extra = lever_arm_acceleration([p[i], q[i], r[i]], [pd[i], qd[i], rd[i]], imu);
            for (k, a) in acc.iter_mut().enumerate() {
                if let Some(a) = a {
                    a[i] -= extra[k];
                }
            }
        }
        for (c, a) in ["ax_m_s2", "ay_m_s2", "az_m_s2"].iter().zip(acc) {
            if let Some(a) = a {
                out.push_column(c, a);
            }
        }
    }
    if let Some(v) = rec.column("airspeed_m_s") {
        let [x, y, z] = sensors.alpha_vane_m;
        if let Some(alpha) = rec.column("alpha_rad").filter(|_| x != 0.0 || y != 0.0) {
            let a = (0..n)
                .map(|i| alpha[i] + (q[i] * x - p[i] * y) / v[i])
                .collect();
            out.push_column("alpha_rad", a);
        }
        let [x, _, z2] = sensors.beta_vane_m;
        let _ = z;
        if let Some(beta) = rec.column("beta_rad").filter(|_| x != 0.0 || z2 != 0.0) {
            let b = (0..n)
                .map(|i| beta[i] - (r[i] * x - p[i] * z2) / v[i])
                .collect();
            out.push_column("beta_rad", b);
        }
    }
    Ok(out)
}

/// The time skews of the α and β vanes (s, the vane reads late) estimated by the flight-path reconstruction
/// of [`data::check_compatibility`] on a record already moved to the CG, and the record with α and β shifted
/// back by them (α(t) = α_m(t + τ), linear interpolation; the ends hold). Skews the reconstruction does not
/// find significant are left alone, and so are skews longer than a data system can have
/// ([`data::skew_bound_s`]): those come back as the second list, for a note.
#[allow(clippy::type_complexity)]
pub fn deskewed(
    rec: &data::FlightRecord,
) -> (data::FlightRecord, Vec<(String, f64)>, Vec<(String, f64)>) {
    let opts = data::CheckOptions {
        scale_factors: false,
        time_skews: true,
        ..data::CheckOptions::default()
    };
    let Ok(report) = data::check_compatibility(rec, &opts) else {
        return (rec.clone(), Vec::new(), Vec::new());
    };
    let mut out = rec.clone();
    let mut skews = Vec::new();
    let mut refused = Vec::new();
    let bound_s = data::skew_bound_s(rec);
    for e in report.significant_skews() {
        if e.value.abs() > bound_s {
            refused.push((e.column.clone(), e.value));
            continue;
        }
        let Some(x) = rec.column(&e.column) else {
            continue;
        };
        out.push_column(&e.column, advanced(&rec.time_s, x, e.value));
        skews.push((e.column.clone(), e.value));
    }
    (out, skews, refused)
}

/// The samples `x` (at times `t`) read `tau_s` later: x(t + τ) at every t, by linear interpolation, the ends
/// held. Takes a time skew τ off a sensor that reads late.
pub fn advanced(t: &[f64], x: &[f64], tau_s: f64) -> Vec<f64> {
    t.iter().map(|&ti| interpolate(t, x, ti + tau_s)).collect()
}

/// Linear interpolation of (t, x) at `at`, holding the end values outside.
fn interpolate(t: &[f64], x: &[f64], at: f64) -> f64 {
    let k = t.partition_point(|&v| v <= at);
    if k == 0 {
        return x[0];
    }
    if k >= t.len() {
        return x[t.len() - 1];
    }
    let w = (at - t[k - 1]) / (t[k] - t[k - 1]);
    x[k - 1] + w * (x[k] - x[k - 1])
}

/// The vane skews [`skew_from_force_equation`] looks for where the flight-path reconstruction found none:
/// (vane, the force equation that reads it, what the note names).
pub const FORCE_EQUATION_SKEWS: [(data::Channel, &str, &str); 2] = [
    (data::Channel::Alpha, "CL", "lift equation"),
    (data::Channel::Beta, "CY", "side-force equation"),
];

/// Steps of the skew search between 0 and the longest skew a data system can have.
const SKEW_STEPS: usize = 20;

/// χ²₁ at 1 %: the likelihood-ratio threshold for one added parameter (Klein & Morelli §5.4).
const CHI2_1_1PCT: f64 = 6.63;

/// A vane's time skew from the force equation that reads it (C_L from the accelerometers against α, C_Y
/// against β): the skew τ in [0, [`data::skew_bound_s`]] that minimises the equation's residual with the
/// vane read τ later (α(t) = α_m(t + τ), [`advanced`]), a separable least-squares problem searched on a grid
/// and refined by a parabola through the least point and its neighbours. Unlike the flight-path
/// reconstruction, it holds in turbulence: the vane and the accelerometers both see the gust, which the
/// kinematics do not. `fit` gives the equation of a record. Returns the record with the vane shifted and τ,
/// when the fall in the residual passes the likelihood-ratio test at 1 % over the residual's effective
/// sample count (its autocorrelation, [`covariance::effective_samples`]) and τ lies inside the range;
/// `None` otherwise. On pa28 records with a 30 ms α skew in light turbulence, which the reconstruction cannot
/// see beside the gusts, the skew left in put C_mq 65 % off by equation error.
pub fn skew_from_force_equation(
    rec: &data::FlightRecord,
    vane: data::Channel,
    fit: impl Fn(&data::FlightRecord) -> Option<RegressionResult>,
) -> Option<(data::FlightRecord, f64)> {
    let x = rec.column(vane)?;
    let bound_s = data::skew_bound_s(rec);
    let shifted = |tau_s: f64| {
        let mut r = rec.clone();
        r.push_column(vane, advanced(&rec.time_s, x, tau_s));
        r
    };
    let cost = |tau_s: f64| -> Option<(f64, RegressionResult)> {
        let eq = fit(&shifted(tau_s))?;
        let n = eq.response.len() as f64;
        let dof = (n - eq.terms.len() as f64).max(1.0);
        Some((eq.fit_error_std.powi(2) * dof, eq))
    };
    let step = bound_s / SKEW_STEPS as f64;
    let costs: Vec<f64> = (0..=SKEW_STEPS)
        .map(|k| cost(k as f64 * step).map_or(f64::INFINITY, |c| c.0))
        .collect();
    let k = (0..costs.len()).min_by(|&a, &b| costs[a].total_cmp(&costs[b]))?;
    if k == 0 || k == SKEW_STEPS || !costs[k].is_finite() {
        return None;
    }
    let (lo, mid, hi) = (costs[k - 1], costs[k], costs[k + 1]);
    let curvature = lo - 2.0 * mid + hi;
    let offset = if curvature > 0.0 {
        0.5 * (lo - hi) / curvature
    } else {
        0.0
    };
    let tau_s = (k as f64 + offset.clamp(-0.5, 0.5)) * step;
    let (best, eq) = cost(tau_s)?;
    let residual: Vec<f64> = (0..eq.response.len())
        .map(|i| {
            eq.response[i]
                - eq.terms
                    .iter()
                    .zip(&eq.regressors)
                    .map(|(t, col)| t.value * col[i])
                    .sum::<f64>()
        })
        .collect();
    let mean = residual.iter().sum::<f64>() / residual.len() as f64;
    let centred: Vec<f64> = residual.iter().map(|v| v - mean).collect();
    let n_eff = covariance::effective_samples(&covariance::lag_weights(&centred), centred.len());
    let lr = n_eff * (costs[0] / best).ln();
    (lr > CHI2_1_1PCT).then(|| (shifted(tau_s), tau_s))
}
