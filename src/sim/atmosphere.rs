//! JSBSim's standard atmosphere with a temperature offset (`atmosphere/delta-T`), to 20 km: what
//! density a record's altitude and an outside temperature give, and the offset that gives a measured density.
//!
//! JSBSim (`FGStandardAtmosphere`) shifts the whole temperature profile by the offset and keeps the sea-level
//! pressure, so the pressure at an altitude changes with the offset too (the hydrostatic equation integrated
//! through warmer air). At 5 000 ft and +15 K JSBSim gives 85 094.8 Pa and 1.01090 kg/m³; these formulas
//! 85 099 Pa and 1.0109 kg/m³.

/// Sea-level pressure, Pa.
const P0_PA: f64 = 101_325.0;
/// Sea-level temperature of the standard day, K.
const T0_K: f64 = 288.15;
/// Tropospheric lapse rate, K per geopotential metre.
const LAPSE_K_M: f64 = 0.0065;
/// Specific gas constant of air, J/(kg K).
const R_J_KG_K: f64 = 287.052_87;
/// Standard gravity, m/s².
const G0_M_S2: f64 = 9.806_65;
/// Earth radius for geopotential altitude, m (JSBSim's 20 855 531.5 ft).
const EARTH_RADIUS_M: f64 = 6_356_766.0;
/// Top of the troposphere, geopotential m.
const TROPOPAUSE_M: f64 = 11_000.0;
/// Top of the isothermal lower stratosphere, geopotential m.
const STRATOSPHERE_TOP_M: f64 = 20_000.0;

/// Air density at geometric altitude `altitude_m` on a day `offset_k` warmer than the standard one, kg/m³ (the
/// troposphere and the isothermal layer above it, to 20 km geopotential); `None` above, or where the temperature
/// would not be positive.
pub fn density_kg_m3(altitude_m: f64, offset_k: f64) -> Option<f64> {
    let h = EARTH_RADIUS_M * altitude_m / (EARTH_RADIUS_M + altitude_m);
    let t_sl = T0_K + offset_k;
    let t = t_sl - LAPSE_K_M * h.min(TROPOPAUSE_M);
    if !(h <= STRATOSPHERE_TOP_M && t > 0.0 && t_sl > 0.0) {
        return None;
    }
    let mut p = P0_PA * (t / t_sl).powf(G0_M_S2 / (R_J_KG_K * LAPSE_K_M));
    if h > TROPOPAUSE_M {
        p *= (-G0_M_S2 * (h - TROPOPAUSE_M) / (R_J_KG_K * t)).exp();
    }
    Some(p / (R_J_KG_K * t))
}

/// The temperature offset from the standard day, K, at which the atmosphere has `density_kg_m3` at
/// `altitude_m`: of the offsets within ±80 K that give it, the one nearest the standard day (a scan in steps of
/// 0.5 K, each sign change refined by bisection). Low down the density falls as the day warms, one offset per
/// density; from about 7 km up the pressure that a warmer day holds aloft makes up for most of the temperature
/// (JSBSim keeps the sea-level pressure), the density barely depends on the offset and two offsets can give it.
/// Where none gives it exactly, the offset whose density comes nearest, if within 3 % of it. `None` otherwise: a
/// density in other units, or an altitude above 20 km.
pub fn offset_for_density_k(altitude_m: f64, density_kg_m3: f64) -> Option<f64> {
    let f = |dt: f64| density_kg_m3_or_nan(altitude_m, dt) - density_kg_m3;
    let grid: Vec<f64> = (0..=320).map(|i| -80.0 + 0.5 * i as f64).collect();
    let values: Vec<f64> = grid.iter().map(|&dt| f(dt)).collect();
    if values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut best: Option<f64> = None;
    for k in 0..grid.len() - 1 {
        let (f_lo, f_hi) = (values[k], values[k + 1]);
        let root = if f_lo == 0.0 {
            grid[k]
        } else if f_lo.signum() != f_hi.signum() {
            let (mut lo, mut hi) = (grid[k], grid[k + 1]);
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if f(mid).signum() == f_lo.signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        } else {
            continue;
        };
        if best.is_none_or(|b| root.abs() < b.abs()) {
            best = Some(root);
        }
    }
    best.or_else(|| {
        let (k, v) = values
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
        (v.abs() <= 0.03 * density_kg_m3).then_some(grid[k])
    })
}

fn density_kg_m3_or_nan(altitude_m: f64, offset_k: f64) -> f64 {
    density_kg_m3(altitude_m, offset_k).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standard_day_and_a_warm_one_match_jsbsim() {
        // JSBSim 1.3.3, c172x at 5 000 ft: 1.05559 kg/m³ on the standard day, 1.01090 at delta-T = 27 °R.
        let h = 5000.0 * 0.3048;
        assert!((density_kg_m3(h, 0.0).unwrap() - 1.05559).abs() < 2e-4);
        assert!((density_kg_m3(h, 15.0).unwrap() - 1.01090).abs() < 2e-4);
    }

    #[test]
    fn the_offset_is_recovered_from_the_density() {
        for (h, dt) in [
            (0.0, -20.0),
            (1500.0, 15.0),
            (5000.0, -10.0),
            (8000.0, 30.0),
        ] {
            let rho = density_kg_m3(h, dt).unwrap();
            assert!(
                (offset_for_density_k(h, rho).unwrap() - dt).abs() < 1e-6,
                "{h} {dt}"
            );
        }
        // A density in slug/ft³ (515 times smaller) is no day's.
        assert_eq!(offset_for_density_k(1500.0, 1.05 / 515.4), None);
        // The 1976 standard atmosphere at 11 km and 15 km geopotential: 0.36392 and 0.19367 kg/m³.
        let geometric = |h: f64| EARTH_RADIUS_M * h / (EARTH_RADIUS_M - h);
        assert!((density_kg_m3(geometric(11_000.0), 0.0).unwrap() - 0.36392).abs() < 2e-4);
        assert!((density_kg_m3(geometric(15_000.0), 0.0).unwrap() - 0.19367).abs() < 2e-4);
    }
}
