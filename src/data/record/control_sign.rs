//! The sign of each surface's control moment, from the record alone: which way the logged elevator, aileron
//! and rudder turn the aircraft. A log whose surface has the other sign convention (a servo output, an
//! aileron logged as right minus left) passes every unit check, and a model replayed on it is driven the wrong
//! way round.

use super::FlightRecord;
use crate::data::channel::Channel;
use crate::data::error::{Warning, WarningKind};
use crate::signal::{difference_noise_std, LeastSquares};

/// A surface's moment on its own axis: the angular acceleration per radian of deflection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlMoment {
    /// The surface.
    pub surface: Channel,
    /// The body rate it drives (q for the elevator, p for the aileron, r for the rudder).
    pub rate: Channel,
    /// The rate's acceleration per radian of deflection, rad/s² per rad (M_δe, L_δa, N_δr).
    pub value: f64,
    /// Its standard error (white residuals).
    pub std_error: f64,
}

impl ControlMoment {
    /// |value| / std_error: how far the record determines the sign.
    pub fn t_ratio(&self) -> f64 {
        self.value.abs() / self.std_error
    }
}

/// Each surface, the rate it drives and the sign of its moment in flightid's convention (docs/data.md):
/// elevator positive trailing edge down (nose down), aileron positive rolling right, rudder positive trailing
/// edge left (nose left).
const AXES: [(Channel, Channel, f64); 3] = [
    (Channel::Elevator, Channel::Q, -1.0),
    (Channel::Aileron, Channel::P, 1.0),
    (Channel::Rudder, Channel::R, -1.0),
];

/// The motion regressors besides the surfaces.
const MOTION: [Channel; 5] = [
    Channel::P,
    Channel::Q,
    Channel::R,
    Channel::Alpha,
    Channel::Beta,
];

/// Length of the windows over which the rates' increments are regressed, s: short beside a pulse of a doublet
/// or 3-2-1-1 (0.3 s and longer), long beside a 50 Hz sample, so the rate's noise is not differentiated.
const WINDOW_S: f64 = 0.1;

/// How far a surface must move from its median, rad (0.11°), and in multiples of its sample noise, to enter the
/// regression: a surface held still is a constant, collinear with the windows' intercept.
const MIN_MOTION_RAD: f64 = 0.002;
const MIN_MOTION_NOISE: f64 = 10.0;

/// How many standard errors away from zero a moment must lie for its sign to be called. On the independent
/// generators' records (`gen_diagnose_records.py`: the c172x in still air and light turbulence, the 737;
/// `gen_foreign_records.py`: p51d, c310, pa28, 737, T37 in light turbulence) the weakest is the 737's elevator, at
/// 12.7 standard errors on a `gen_foreign_records.py` record; a surface that barely moves stays far below.
pub const SIGN_T_RATIO: f64 = 10.0;

/// The control moment of every moving surface whose rate is logged, by equation error on the rates' increments
/// (Klein & Morelli, *Aircraft System Identification*, ch. 5: the moment equation ω̇ = Σ cⱼ xⱼ + c₀ with the
/// surfaces, p, q, r, α and β as regressors, integrated over windows of [`WINDOW_S`]: Δω = Σ cⱼ ∫xⱼ dt + c₀ Δt,
/// which needs no differentiated rate). Empty when no surface moves or the regressors are collinear.
pub fn control_moments(rec: &FlightRecord) -> Vec<ControlMoment> {
    let t = &rec.time_s;
    let Some(dt) = rec.dt_s().filter(|dt| *dt > 0.0) else {
        return Vec::new();
    };
    let span = ((WINDOW_S / dt).round() as usize).max(1);
    let windows = (rec.len().saturating_sub(1)) / span;
    let ends: Vec<usize> = (0..=windows).map(|k| k * span).collect();
    let moving = |c: Channel| {
        rec.column(c).filter(|x| {
            let mut v = x.to_vec();
            let median = crate::signal::median_in_place(&mut v);
            let reach = x.iter().map(|v| (v - median).abs()).fold(0.0, f64::max);
            reach > MIN_MOTION_RAD && reach > MIN_MOTION_NOISE * difference_noise_std(x)
        })
    };
    let surfaces: Vec<Channel> = AXES
        .iter()
        .map(|a| a.0)
        .filter(|&c| moving(c).is_some())
        .collect();
    let regressors: Vec<Channel> = surfaces
        .iter()
        .copied()
        .chain(
            MOTION
                .into_iter()
                .filter(|&c| rec.column(c).is_some_and(|x| x.iter().any(|v| *v != x[0]))),
        )
        .collect();
    if surfaces.is_empty() || windows < 4 * (regressors.len() + 1) {
        return Vec::new();
    }
    // ∫x dt over each window by trapezoids, the windows' lengths for the intercept.
    let integral = |x: &[f64]| -> Vec<f64> {
        ends.windows(2)
            .map(|w| {
                (w[0]..w[1])
                    .map(|i| 0.5 * (x[i] + x[i + 1]) * (t[i + 1] - t[i]))
                    .sum()
            })
            .collect()
    };
    let mut columns: Vec<Vec<f64>> = regressors
        .iter()
        .map(|&c| integral(rec.column(c).unwrap_or_default()))
        .collect();
    columns.push(ends.windows(2).map(|w| t[w[1]] - t[w[0]]).collect());
    AXES.iter()
        .filter(|(s, _, _)| surfaces.contains(s))
        .filter_map(|&(surface, rate, _)| {
            let w = rec.column(rate)?;
            let increments: Vec<f64> = ends.windows(2).map(|e| w[e[1]] - w[e[0]]).collect();
            let ls = LeastSquares::fit(&columns, &increments).ok()?;
            let k = regressors.iter().position(|&c| c == surface)?;
            Some(ControlMoment {
                surface,
                rate,
                value: ls.theta[k],
                std_error: ls.std_errors()[k],
            })
        })
        .collect()
}

/// The surfaces whose moment has, by more than [`SIGN_T_RATIO`] standard errors, the sign opposite to
/// flightid's convention: the other sign convention, or an aircraft whose pitch control sits ahead of its CG.
pub(super) fn control_sign_warnings(rec: &FlightRecord) -> Vec<Warning> {
    control_moments(rec)
        .into_iter()
        .filter(|m| {
            let convention = AXES.iter().find(|a| a.0 == m.surface).map_or(0.0, |a| a.2);
            m.value * convention < 0.0 && m.t_ratio() > SIGN_T_RATIO
        })
        .map(|m| {
            let (axis, positive, also) = match m.surface {
                Channel::Elevator => (
                    "pitch",
                    "positive trailing edge down, a nose-down moment",
                    "; a pitch control ahead of the CG (a canard) has this sign too",
                ),
                Channel::Aileron => ("roll", "positive rolling right", ""),
                _ => ("yaw", "positive trailing edge left, a nose-left moment", ""),
            };
            Warning {
                kind: WarningKind::OppositeSign,
                column: Some(m.surface.to_string()),
                message: format!(
                    "the {axis} acceleration follows it at {:+.2} ± {:.2} rad/s² per rad (the regression of {}'s \
                     increments on the surfaces and the motion): the sign opposite to flightid's \
                     convention ({positive}); map it with scale = -1.0{also}",
                    m.value, m.std_error, m.rate
                ),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::add_white_noise;

    /// A short-period model q̇ = M_α α + M_q q + M_δe δe, α̇ = Z_α α + q (rad, s), flown through an elevator
    /// 3-2-1-1 of 0.03 rad at 1 kHz and logged at 50 Hz with 0.001 rad/s of gyro noise.
    fn short_period(m_de: f64) -> FlightRecord {
        let (m_alpha, m_q, z_alpha) = (-15.0, -3.0, -1.5);
        let elevator = |t: f64| match t {
            t if (2.0..3.5).contains(&t) => 0.03,
            t if (3.5..4.5).contains(&t) => -0.03,
            t if (4.5..5.0).contains(&t) => 0.03,
            t if (5.0..5.5).contains(&t) => -0.03,
            _ => 0.0,
        };
        let (mut alpha, mut q) = (0.0, 0.0);
        let h = 0.001;
        let mut rec = FlightRecord::new((0..1000).map(|k| k as f64 * 0.02).collect());
        let (mut de, mut qs, mut alphas) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..20_000 {
            let t = k as f64 * h;
            if k % 20 == 0 {
                de.push(elevator(t));
                qs.push(q);
                alphas.push(alpha);
            }
            let qd = m_alpha * alpha + m_q * q + m_de * elevator(t);
            alpha += h * (z_alpha * alpha + q);
            q += h * qd;
        }
        rec.push_column(Channel::Elevator, de);
        rec.push_column(Channel::Q, add_white_noise(&qs, 0.001, 7));
        rec.push_column(Channel::Alpha, alphas);
        rec.push_column(Channel::Aileron, vec![0.01; 1000]);
        rec
    }

    #[test]
    fn the_elevator_moment_and_its_sign_are_recovered() {
        for m_de in [-20.0, 20.0] {
            let rec = short_period(m_de);
            let found = control_moments(&rec);
            assert_eq!(
                found.len(),
                1,
                "only the moving elevator is judged: {found:?}"
            );
            let m = found[0];
            assert_eq!((m.surface, m.rate), (Channel::Elevator, Channel::Q));
            assert!((m.value / m_de - 1.0).abs() < 0.01, "{m:?}");
            assert!(m.t_ratio() > 5.0 * SIGN_T_RATIO, "{m:?}");
            let warned = control_sign_warnings(&rec);
            assert_eq!(warned.len(), usize::from(m_de > 0.0), "{warned:?}");
        }
    }
}
