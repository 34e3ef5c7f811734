//! The record moved to the CG: dynamic pressure and density from the record's own air data (ISA from
//! `altitude_m`, or the airframe's density), sensors away from the CG moved there (module doc of
//! [`super`]), and the time skews of α and β removed.

use super::*;

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
    /// `qbar_pa`, `altitude_m (ISA)` or `airframe flight.density_kg_m3`.
    pub source: String,
}

/// The record's air density: from `qbar_pa` and `airspeed_m_s` (ρ = 2 q̄/V², averaged), else ISA at the mean
/// `altitude_m`, else the airframe's `flight.density_kg_m3`.
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

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
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
            let w = [p[i], q[i], r[i]];
            let tangential = cross([pd[i], qd[i], rd[i]], imu);
            let centripetal = cross(w, cross(w, imu));
            for (k, a) in acc.iter_mut().enumerate() {
                if let Some(a) = a {
                    a[i] -= tangential[k] + centripetal[k];
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
