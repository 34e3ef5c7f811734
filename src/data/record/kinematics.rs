//! The kinematic unit and sign checks of [`super::unit_warnings`]: a logged angle, vane or airspeed set against
//! what the body rates and specific forces make of it over short windows.

use super::{FlightRecord, G0_M_S2};
use crate::data::channel::Channel;
use crate::data::error::{Warning, WarningKind};
use crate::signal::slope_and_correlation;

/// Slope and correlation of an angle's change over half-second windows against its rate's integral over the
/// same windows (trapezoids). A differentiated angle is too noisy: on a 50 Hz record with 0.05° of attitude
/// noise dθ/dt correlates with q by 0.63 only, the windowed increments by 0.99.
fn windowed_slope(rec: &FlightRecord, x: &[f64], rate: &[f64]) -> Option<(f64, f64)> {
    let t = &rec.time_s;
    let dt = rec.dt_s()?;
    let span = ((0.5 / dt).round() as usize).max(1);
    if rec.len() < 20 || rec.len() <= 2 * span {
        return None;
    }
    let mut integral = vec![0.0; rec.len()];
    for i in 1..rec.len() {
        integral[i] = integral[i - 1] + 0.5 * (rate[i] + rate[i - 1]) * (t[i] - t[i - 1]);
    }
    let (kin, dx): (Vec<f64>, Vec<f64>) = (span..rec.len())
        .map(|i| (integral[i] - integral[i - span], x[i] - x[i - span]))
        .unzip();
    Some(slope_and_correlation(&kin, &dx))
}

/// Flags an α or β of the other sign convention: its change over half-second windows anticorrelated
/// (r < −0.8, slope near −1) with the integral of the rate the kinematics give (flat earth; β ≈ 0 in α̇):
/// α̇ = q + [a_z cos α − a_x sin α + g (cos φ cos θ cos α + sin θ sin α)]/V,
/// β̇ = p sin α − r cos α + (a_y + g cos θ sin φ)/V (Klein & Morelli eq. 3.32–3.33, specific forces).
/// A missing attitude is taken as level.
pub(super) fn aero_angle_sign_warning(rec: &FlightRecord, angle: Channel) -> Option<Warning> {
    let x = rec.column(angle)?;
    let v = rec.column(Channel::Airspeed)?;
    let zero = vec![0.0; rec.len()];
    let col = |c: Channel| rec.column(c).unwrap_or(&zero);
    let (theta, phi) = (col(Channel::Theta), col(Channel::Phi));
    let g = G0_M_S2;
    let rate: Vec<f64> = match angle {
        Channel::Alpha => {
            let (q, ax, az) = (
                rec.column(Channel::Q)?,
                rec.column(Channel::Ax)?,
                rec.column(Channel::Az)?,
            );
            (0..rec.len())
                .map(|i| {
                    let (sa, ca) = x[i].sin_cos();
                    let grav = g * (phi[i].cos() * theta[i].cos() * ca + theta[i].sin() * sa);
                    q[i] + (az[i] * ca - ax[i] * sa + grav) / v[i].max(1.0)
                })
                .collect()
        }
        Channel::Beta => {
            let (p, r, ay) = (
                rec.column(Channel::P)?,
                rec.column(Channel::R)?,
                rec.column(Channel::Ay)?,
            );
            let alpha = col(Channel::Alpha);
            (0..rec.len())
                .map(|i| {
                    let (sa, ca) = alpha[i].sin_cos();
                    p[i] * sa - r[i] * ca
                        + (ay[i] + g * theta[i].cos() * phi[i].sin()) / v[i].max(1.0)
                })
                .collect()
        }
        _ => return None,
    };
    let (k, corr) = windowed_slope(rec, x, &rate)?;
    (corr < -0.8 && (k + 1.0).abs() < 0.3).then(|| Warning {
        kind: WarningKind::OppositeSign,
        column: Some(angle.to_string()),
        message: format!(
            "its change is {k:.3} × what the body rates and specific forces make of it (correlation {corr:.2}): \
             the other sign convention (flightid: α positive nose up, β positive with the wind from the \
             right); map it with scale = -1.0"
        ),
    })
}

/// Flags an angle and its body rate that disagree by the degree factor (see [`super::unit_warnings`]).
pub(super) fn angle_rate_warning(
    rec: &FlightRecord,
    angle: Channel,
    rate: Channel,
) -> Option<Warning> {
    let (x, w) = (rec.column(angle)?, rec.column(rate)?);
    if rec.len() < 20 {
        return None;
    }
    // The Euler-angle rate the body rates give (small-angle terms dropped where columns lack).
    let rate_of_angle: Vec<f64> = match angle {
        Channel::Theta => {
            let phi = rec.column(Channel::Phi);
            let r = rec.column(Channel::R);
            (0..rec.len())
                .map(|i| match (phi, r) {
                    (Some(phi), Some(r)) => w[i] * phi[i].cos() - r[i] * phi[i].sin(),
                    _ => w[i],
                })
                .collect()
        }
        _ => w.to_vec(),
    };
    let (k, corr) = windowed_slope(rec, x, &rate_of_angle)?;
    let deg = 180.0 / std::f64::consts::PI;
    let near = |k: f64, target: f64| (k / target - 1.0).abs() < 0.3;
    if corr < -0.8 && [-1.0, -deg, -1.0 / deg].iter().any(|&t| near(k, t)) {
        return Some(Warning {
            kind: WarningKind::OppositeSign,
            column: Some(rate.to_string()),
            message: format!(
                "d{angle}/dt = {k:.4} × {rate} (correlation {corr:.2}): the two have opposite signs; \
                 flightid's body rates are positive nose up, right wing down and nose right, like the \
                 angles they turn: map the one of the other convention with scale = -1.0"
            ),
        });
    }
    if corr < 0.8 {
        return None;
    }
    let (column, what) = if near(k, deg) {
        (angle, "the angle is in degrees")
    } else if near(k, 1.0 / deg) {
        (rate, "the rate is in deg/s")
    } else {
        return None;
    };
    Some(Warning {
        kind: if column == angle {
            WarningKind::LooksLikeDegrees
        } else {
            WarningKind::LooksLikeDegreesPerSecond
        },
        column: Some(column.to_string()),
        message: format!(
            "d{angle}/dt = {k:.4} × {rate} (correlation {corr:.2}); radians would give 1, so {what}"
        ),
    })
}

/// The units an airspeed may be logged in, as the factor from m/s to each: what the kinematic airspeed check
/// tells apart.
const SPEED_UNITS: [(f64, &str); 3] = [
    (1.0, "m/s"),
    (1.0 / 0.514_444, "knots"),
    (1.0 / 0.3048, "ft/s"),
];

/// The fewest 1 s windows on which the kinematic airspeed check decides. On fewer, one maneuver fills the fit
/// and its model error with it: on the first 4 to 6 s of records from the independent generator
/// (`scripts/gen_diagnose_records.py`, c172x, an elevator 3-2-1-1 first, accelerations logged at the pilot's
/// station rather than the CG) an airspeed in m/s changed 1.47 to 1.57 times as fast as the specific forces
/// say, at a correlation of 0.98 to 1.00, which no standard error of five windows reveals. With 8 windows or
/// more and the 2-standard-error band of [`speed_kinematics_warning`], no m/s airspeed was taken for knots or
/// ft/s on 32 such records (seed 4, cases 1 to 16, training and validation), cut to 8, 10, 12, 15, 20 or 30 s
/// from every few seconds or taken whole; of the 32 whole records 29 were named in knots, 30 in ft/s.
const MIN_SPEED_WINDOWS: usize = 8;

/// Flags an airspeed in knots or ft/s from the flight-path kinematics (see [`super::unit_warnings`]): the
/// slope of the airspeed's change over 1 s windows on the integral of the along-path specific force minus
/// gravity. It decides only on [`MIN_SPEED_WINDOWS`] windows or more, at a correlation of 0.8 or more, and
/// only when the slope ± 2 standard errors lies wholly nearer (in ratio) to the factor of knots or of ft/s
/// than to any other unit's ([`SPEED_UNITS`]; the boundaries are the geometric means of neighbouring
/// factors, 1.39 and 2.53); otherwise it stays silent rather than guess.
pub(super) fn speed_kinematics_warning(rec: &FlightRecord) -> Option<Warning> {
    let v = rec.column(Channel::Airspeed)?;
    let (ax, az) = (rec.column(Channel::Ax)?, rec.column(Channel::Az)?);
    let (theta, alpha) = (rec.column(Channel::Theta)?, rec.column(Channel::Alpha)?);
    let phi = rec.column(Channel::Phi);
    let dt = rec.dt_s()?;
    let window = (1.0 / dt).round().max(1.0) as usize;
    if rec.len() <= MIN_SPEED_WINDOWS * window {
        return None;
    }
    // Along-path specific force minus gravity (wings-level γ generalised with φ, β = 0).
    let rhs: Vec<f64> = (0..rec.len())
        .map(|i| {
            let (ca, sa) = (alpha[i].cos(), alpha[i].sin());
            let cphi = phi.map_or(1.0, |p| p[i].cos());
            let sin_gamma = ca * theta[i].sin() - sa * cphi * theta[i].cos();
            ax[i] * ca + az[i] * sa - G0_M_S2 * sin_gamma
        })
        .collect();
    let (mut dv, mut integral) = (Vec::new(), Vec::new());
    let mut i = 0;
    while i + window < rec.len() {
        dv.push(v[i + window] - v[i]);
        let s: f64 = (i..i + window)
            .map(|k| 0.5 * (rhs[k] + rhs[k + 1]) * (rec.time_s[k + 1] - rec.time_s[k]))
            .sum();
        integral.push(s);
        i += window;
    }
    let n = dv.len();
    let (k, corr) = slope_and_correlation(&integral, &dv);
    if n < MIN_SPEED_WINDOWS || corr < 0.8 {
        return None;
    }
    // The slope's standard error from the correlation (least squares with an intercept, n − 2 dof).
    let two_se = 2.0 * k * ((1.0 - corr * corr) / ((n - 2) as f64 * corr * corr)).sqrt();
    let nearest = (0..SPEED_UNITS.len())
        .min_by(|&a, &b| {
            let off = |j: usize| (k / SPEED_UNITS[j].0).ln().abs();
            off(a).total_cmp(&off(b))
        })
        .filter(|&j| j > 0)?;
    let boundary = |a: usize, b: usize| (SPEED_UNITS[a].0 * SPEED_UNITS[b].0).sqrt();
    let lower = boundary(nearest - 1, nearest);
    let upper = SPEED_UNITS
        .get(nearest + 1)
        .map_or(f64::INFINITY, |_| boundary(nearest, nearest + 1));
    if k - two_se <= lower || k + two_se >= upper {
        return None;
    }
    let unit = SPEED_UNITS[nearest].1;
    Some(Warning {
        kind: WarningKind::LooksLikeKnotsOrFeet,
        column: Some(Channel::Airspeed.to_string()),
        message: format!(
            "airspeed changes {k:.2} ± {two_se:.2} times as fast as the specific force along the flight path \
             says (correlation {corr:.2} over {n} windows of 1 s); m/s would give 1: it looks like {unit}"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Level flight (α = θ = φ = 0) at 50 Hz whose airspeed swings as its specific force says, exactly:
    /// V = 50 + 2 sin(0.3 t) m/s, a_x = dV/dt, logged × `factor`.
    fn exact_record(duration_s: f64, factor: f64) -> FlightRecord {
        let time_s: Vec<f64> = (0..=(duration_s * 50.0).round() as usize)
            .map(|i| i as f64 * 0.02)
            .collect();
        let mut rec = FlightRecord::new(time_s.clone());
        let zero = vec![0.0; time_s.len()];
        rec.push_column(
            Channel::Airspeed,
            time_s
                .iter()
                .map(|t| factor * (50.0 + 2.0 * (0.3 * t).sin()))
                .collect(),
        );
        rec.push_column(
            Channel::Ax,
            time_s.iter().map(|t| 0.6 * (0.3 * t).cos()).collect(),
        );
        rec.push_column(Channel::Az, vec![-G0_M_S2; time_s.len()]);
        rec.push_column(Channel::Theta, zero.clone());
        rec.push_column(Channel::Alpha, zero);
        rec
    }

    /// Even on exact kinematics the airspeed unit is named only from 8 windows on: 8 s at 50 Hz gives 8 windows
    /// of 1 s and names knots and ft/s (m/s nothing); 7.9 s gives 7 and names nothing, whatever the unit.
    #[test]
    fn the_airspeed_unit_is_named_from_eight_windows_on() {
        let unit = |duration_s: f64, factor: f64| {
            speed_kinematics_warning(&exact_record(duration_s, factor)).map(|w| w.message)
        };
        assert_eq!(unit(8.0, 1.0), None);
        for (factor, name) in [(1.0 / 0.514_444, "knots"), (1.0 / 0.3048, "ft/s")] {
            let m = unit(8.0, factor).unwrap_or_default();
            assert!(
                m.ends_with(&format!("it looks like {name}"))
                    && m.contains("over 8 windows of 1 s"),
                "{m}"
            );
            assert_eq!(unit(7.9, factor), None, "{name}");
        }
    }
}
