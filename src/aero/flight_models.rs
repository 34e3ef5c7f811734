//! The built-in nondimensional aircraft models fitted to measured records: longitudinal (states V, α, θ, q)
//! and lateral-directional (states β, p, r, φ), body axes about the CG, SI units.
//!
//! Longitudinal (wings level; Klein & Morelli §3.6, Jategaonkar §8.3; forces in wind axes, T along a line
//! inclined ε to body x, V̂ = (V − V₀)/V₀, q̂ = q c̄/(2V), α̇̂ = α̇ c̄/(2V)):
//!
//! V̇ = [T cos(α + ε) − q̄S C_D]/m − g sin(θ − α)
//! α̇ = [−q̄S C_L − T sin(α + ε)]/(m V) + q + g cos(θ − α)/V
//! θ̇ = q,  q̇ = [q̄S c̄ C_m + T l_T]/I_yy
//! C_L = C_L0 + C_Lα α + C_Lq q̂ + C_Lδe δe + C_Lα̇ α̇̂ + C_LV V̂ + C_Lα² Δα²,  C_D = C_D0 + C_Dα α + C_Dδe δe + C_DV V̂,
//! C_m = C_m0 + C_mα α + C_mq q̂ + C_mδe δe + C_mα̇ α̇̂ + C_mV V̂ + C_mα² Δα²,  Δα = α − α₀
//!
//! The curvature terms C_Lα², C_mα² are the second-order terms of the Taylor (polynomial) expansion of the
//! static coefficients in α (Klein & Morelli ch. 3, the aerodynamic model as a Taylor series in the states;
//! §5.4, model structure determination, which admits such terms on the evidence of the data), taken about
//! the records' mean angle of attack α₀, so that C_Lα and C_mα stay the local slopes there. A coefficient that
//! curves over the few degrees a maneuver flies and is fitted with a straight line leaves a residual
//! quadratic in Δα; Δα² correlates with q̂ (q leads α by the short period's phase), and the linear model puts
//! part of it into C_mq (the JSBSim p51d, whose C_m(α) steepens from −0.26 to −0.45 per rad between 4° and
//! −2°: C_mq +6 % from the aero tables alone).
//!
//! (C_Lα̇ makes the α̇ equation implicit; it is solved for α̇, being linear in it.) Outputs at the sensors:
//! a_x = (−q̄S C_D cos α + q̄S C_L sin α + T cos ε)/m + q̇ z − q² x,
//! a_z = (−q̄S C_D sin α − q̄S C_L cos α − T sin ε)/m − q̇ x − q² z (IMU at (x, y, z));
//! α_vane = α − q x_v/V − τ_α α̇ (vane at x_v; τ_α its time skew, first order).
//!
//! Vertical turbulence, for the filter error method (Dryden form of MIL-F-8785C §3.7; Jategaonkar ch. 5: a
//! process-noise model of the atmosphere): two more states, the gust's angle of attack α_g and a lag ξ of it,
//! α̇_g = −α_g V/L_w (white process noise drives it), ξ̇ = (α_g − ξ)/τ_q, τ_q = 4b/(πV). The aerodynamics see
//! α + α_g and the pitch-rate gust q + q_g, q_g = k_q (α_g − ξ)/τ_q, i.e. k_q s/(1 + τ_q s) α_g, the rotary
//! term MIL-F-8785C derives from the same vertical gust; α̇, γ and the kinematics stay inertial; the vane
//! reads α + α_g. Lift and drag then act in the air's axes, rotated by α_g against the inertial velocity, so
//! V̇ and α̇ take the body forces X, Z projected on the inertial velocity: V̇ = (X cos α + Z sin α)/m − g sin γ,
//! α̇ = (Z cos α − X sin α)/(mV) + q + g cos γ/V (the wind-axis form above when α_g = 0). The form above with
//! α + α_g throughout missed the lift's push along the path, L sin α_g: on pa28 records flown through a
//! first-order vertical gust of 0.9 m/s alone, filter error then had C_mq 36 % off (6.6 % with it; C_Lα and
//! C_mα, 36 % and 22 % off either way on ideal sensors, are within 3.1 % with the logger's sensor noise).
//! The gain k_q (`gust_q_gain`) is estimated: whether the gust's pitch rate reaches the
//! aerodynamics, and with which sign, is the atmosphere's and the airframe's, not the model's to assume.
//! JSBSim's milspec turbulence has it (std 0.0056 rad/s on the c310 in light turbulence, a quarter of a
//! ±0.1 doublet's pitch rate); without it, filter error put C_mδe 18–21 % and C_mq 14–19 % low on five gusty
//! c310 records, with k_q = 1 held C_mδe came within 1.5–5.5 %, and k_q = −1 left it 13–17 % off. A record
//! generated without it (`scripts/gen_hfb_records.py`) gave C_mq 17 % off with k_q = 1 held.
//!
//! Lateral-directional (Klein & Morelli eq. 3.38–3.40 with I_xz; V, α, θ, q measured, taken as inputs;
//! p̂ = p b/(2V), r̂ = r b/(2V)):
//!
//! β̇ = [q̄S C_Y/m + g cos θ sin φ]/V + p sin α − r cos α
//! ṗ = (I_zz L' + I_xz N')/Γ,  ṙ = (I_xz L' + I_xx N')/Γ,  Γ = I_xx I_zz − I_xz²,
//! L' = q̄Sb C_l + C_lT T + (I_yy − I_zz) q r + I_xz p q,  N' = q̄Sb C_n + (I_xx − I_yy) p q − I_xz q r (Etkin & Reid eq. 4.7,5)
//! φ̇ = p + tan θ (q sin φ + r cos φ)
//! C_(Y,l,n) = C_0 + C_β β + C_p p̂ + C_r r̂ + C_δa δa + C_δr δr; C_lT T the propeller's torque reaction, C_lT
//! in m (`aero::regression::PROPELLER_TORQUE`), with the thrust T as an input where every record carries it.
//! Outputs: β_vane = β + (r x_v − p z_v)/V − τ_β β̇; a_y at the IMU = q̄S C_Y/m + (ω̇ × r)_y + (ω × (ω × r))_y.

use super::airframe::SensorPositions;
use super::params::{Geometry, MassProperties};

/// Longitudinal model parameters, in θ order.
pub const LONGITUDINAL_PARAMETERS: [&str; 20] = [
    "CL_0",
    "CL_alpha",
    "CL_q",
    "CL_de",
    "CL_alphadot",
    "CL_V",
    "CD_0",
    "CD_alpha",
    "CD_de",
    "CD_V",
    "Cm_0",
    "Cm_alpha",
    "Cm_q",
    "Cm_de",
    "Cm_alphadot",
    "Cm_V",
    "tau_alpha_s",
    "CL_alpha2",
    "Cm_alpha2",
    "gust_q_gain",
];

/// Lateral-directional model parameters, in θ order.
pub const LATERAL_PARAMETERS: [&str; 20] = [
    "CY_0",
    "CY_beta",
    "CY_p",
    "CY_r",
    "CY_da",
    "CY_dr",
    "Cl_0",
    "Cl_beta",
    "Cl_p",
    "Cl_r",
    "Cl_da",
    "Cl_dr",
    "Cn_0",
    "Cn_beta",
    "Cn_p",
    "Cn_r",
    "Cn_da",
    "Cn_dr",
    "tau_beta_s",
    "Cl_T",
];

/// Longitudinal states.
pub const LONGITUDINAL_STATES: [&str; 4] = ["airspeed_m_s", "alpha_rad", "theta_rad", "q_rad_s"];
/// Lateral-directional states.
pub const LATERAL_STATES: [&str; 4] = ["beta_rad", "p_rad_s", "r_rad_s", "phi_rad"];

/// What every built-in model needs besides θ: the airframe and the reference speed of the speed derivatives.
#[derive(Debug, Clone, Copy)]
pub struct Constants {
    /// Mass and inertia (body axes).
    pub mass: MassProperties,
    /// Reference geometry.
    pub geometry: Geometry,
    /// Thrust line vs body x, nose up, rad.
    pub thrust_inclination_rad: f64,
    /// Pitching moment per newton of thrust, m.
    pub thrust_moment_arm_m: f64,
    /// Sensor positions relative to the CG.
    pub sensors: SensorPositions,
    /// Reference airspeed V₀ of the speed derivatives, m/s.
    pub v_ref_m_s: f64,
    /// Reference angle of attack α₀ of the curvature terms C_Lα², C_mα² (the records' mean), rad.
    pub alpha_ref_rad: f64,
    /// Gravity, m/s².
    pub g_m_s2: f64,
}

/// Indices into the longitudinal θ.
mod lon {
    pub const CL0: usize = 0;
    pub const CLA: usize = 1;
    pub const CLQ: usize = 2;
    pub const CLDE: usize = 3;
    pub const CLAD: usize = 4;
    pub const CLV: usize = 5;
    pub const CD0: usize = 6;
    pub const CDA: usize = 7;
    pub const CDDE: usize = 8;
    pub const CDV: usize = 9;
    pub const CM0: usize = 10;
    pub const CMA: usize = 11;
    pub const CMQ: usize = 12;
    pub const CMDE: usize = 13;
    pub const CMAD: usize = 14;
    pub const CMV: usize = 15;
    pub const TAU: usize = 16;
    pub const CLA2: usize = 17;
    pub const CMA2: usize = 18;
    pub const KQG: usize = 19;
}

/// The inputs the longitudinal equations read at one instant.
#[derive(Debug, Clone, Copy)]
pub struct LonInputs {
    /// Elevator, rad.
    pub elevator_rad: f64,
    /// Thrust, N (0 when not measured).
    pub thrust_n: f64,
    /// Air density, kg/m³.
    pub density_kg_m3: f64,
}

/// The longitudinal model's derivatives and the quantities its outputs need.
#[derive(Debug, Clone, Copy)]
pub struct LonEval {
    /// ẋ = (V̇, α̇, θ̇, q̇).
    pub dx: [f64; 4],
    /// Body specific forces at the CG (a_x, a_z), m/s².
    pub accel_cg: [f64; 2],
}

/// Longitudinal right-hand side (module doc).
pub fn longitudinal(c: &Constants, theta: &[f64], x: &[f64], u: &LonInputs) -> LonEval {
    use lon::*;
    let (v, alpha_inertial, pitch, q_inertial) = (x[0].max(1.0), x[1], x[2], x[3]);
    let gust = VerticalGust::of(c, theta, x);
    // what the aerodynamics see (module doc); the kinematics below keep the inertial α and q
    let (alpha, q) = (alpha_inertial + gust.alpha_rad, q_inertial + gust.q_rad_s);
    let (m, s, cbar) = (c.mass.mass_kg, c.geometry.wing_area_m2, c.geometry.chord_m);
    let qbar_s = 0.5 * u.density_kg_m3 * v * v * s;
    let k = cbar / (2.0 * v);
    let vhat = (v - c.v_ref_m_s) / c.v_ref_m_s;
    let de = u.elevator_rad;
    let t = u.thrust_n;
    let eps = c.thrust_inclination_rad;
    let g = c.g_m_s2;
    let gamma = pitch - alpha_inertial;
    let da2 = (alpha - c.alpha_ref_rad).powi(2);
    // The aerodynamic force acts in the air's wind axes (α_air = α + α_g), the kinematics in the inertial
    // velocity's: the body forces X, Z are projected onto the inertial velocity (V̇) and its normal (α̇). In
    // still air this is the usual wind-axis form, V̇ = (T cos(α + ε) − D)/m − g sin γ and
    // α̇ = (−L − T sin(α + ε))/(mV) + q + g cos γ/V; in a gust the lift leans by α_g and pushes along the
    // flight path (L sin α_g, a twentieth of the weight for a 3° gust).
    let (sg, cg) = gust.alpha_rad.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    // C_L without its α̇ term, then α̇ solved from α̇ (1 + q̄S C_Lα̇ k cos α_g/(mV)) = rest.
    let cl_static = theta[CL0]
        + theta[CLA] * alpha
        + theta[CLQ] * q * k
        + theta[CLDE] * de
        + theta[CLV] * vhat
        + theta[CLA2] * da2;
    let cd = theta[CD0] + theta[CDA] * alpha + theta[CDDE] * de + theta[CDV] * vhat;
    // Thrust along the body's x axis inclined by ε; its normal and tangential shares of the inertial velocity.
    let thrust_normal = -t * (alpha_inertial + eps).sin();
    let thrust_along = t * (alpha_inertial + eps).cos();
    let rest = (-qbar_s * (cl_static * cg + cd * sg) + thrust_normal) / (m * v)
        + q_inertial
        + g * gamma.cos() / v;
    let alphadot = rest / (1.0 + qbar_s * theta[CLAD] * k * cg / (m * v));
    let cl = cl_static + theta[CLAD] * alphadot * k;
    let cm = theta[CM0]
        + theta[CMA] * alpha
        + theta[CMQ] * q * k
        + theta[CMDE] * de
        + theta[CMAD] * alphadot * k
        + theta[CMV] * vhat
        + theta[CMA2] * da2;
    let vdot = (thrust_along + qbar_s * (cl * sg - cd * cg)) / m - g * gamma.sin();
    let qdot = (qbar_s * cbar * cm + t * c.thrust_moment_arm_m) / c.mass.iyy_kg_m2;
    let ax = (-qbar_s * cd * ca + qbar_s * cl * sa + t * eps.cos()) / m;
    let az = (-qbar_s * cd * sa - qbar_s * cl * ca - t * eps.sin()) / m;
    LonEval {
        dx: [vdot, alphadot, q_inertial, qdot],
        accel_cg: [ax, az],
    }
}

/// The vertical gust of the longitudinal model's states 4 and 5 (module doc); zero without them.
#[derive(Debug, Clone, Copy, Default)]
pub struct VerticalGust {
    /// Gust angle of attack α_g, rad.
    pub alpha_rad: f64,
    /// Pitch-rate gust q_g = k_q (α_g − ξ)/τ_q, rad/s (0 without a span).
    pub q_rad_s: f64,
}

impl VerticalGust {
    /// The gust states' names, after [`LONGITUDINAL_STATES`].
    pub const STATES: [&'static str; 2] = ["gust_alpha_rad", "gust_alpha_lag_rad"];

    /// The gust at state `x` (zero when `x` has only the four flight states), k_q = θ's `gust_q_gain`.
    pub fn of(c: &Constants, theta: &[f64], x: &[f64]) -> VerticalGust {
        if x.len() < 6 {
            return VerticalGust::default();
        }
        let tau = Self::rotary_lag_s(c, x[0]);
        let gain = theta.get(lon::KQG).copied().unwrap_or(0.0);
        VerticalGust {
            alpha_rad: x[4],
            q_rad_s: if tau > 0.0 {
                gain * (x[4] - x[5]) / tau
            } else {
                0.0
            },
        }
    }

    /// τ_q = 4b/(πV), s (0 when the span is unknown).
    fn rotary_lag_s(c: &Constants, v: f64) -> f64 {
        let b = c.geometry.span_m;
        if b.is_finite() && b > 0.0 {
            4.0 * b / (std::f64::consts::PI * v.max(1.0))
        } else {
            0.0
        }
    }

    /// (α̇_g, ξ̇) without the process noise: α_g relaxes over L_w/V, ξ follows α_g over τ_q.
    pub fn derivatives(c: &Constants, scale_length_m: f64, x: &[f64]) -> [f64; 2] {
        let v = x[0].max(1.0);
        let tau = Self::rotary_lag_s(c, v);
        [
            -x[4] * v / scale_length_m,
            if tau > 0.0 { (x[4] - x[5]) / tau } else { 0.0 },
        ]
    }

    /// MIL-F-8785C's vertical scale length L_w, m: the altitude below 1000 ft, 1750 ft above 2000 ft, linear
    /// between; 1750 ft when the altitude is not known.
    pub fn scale_length_m(altitude_m: Option<f64>) -> f64 {
        const FT: f64 = 0.3048;
        match altitude_m {
            Some(h) if h.is_finite() => {
                let h_ft = (h / FT).max(10.0);
                let l_ft = if h_ft <= 1000.0 {
                    h_ft
                } else if h_ft >= 2000.0 {
                    1750.0
                } else {
                    1000.0 + (h_ft - 1000.0) * 0.75
                };
                l_ft * FT
            }
            _ => 1750.0 * FT,
        }
    }
}

/// A longitudinal output, as measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LonOutput {
    /// `airspeed_m_s`.
    Airspeed,
    /// `alpha_rad` at the vane.
    Alpha,
    /// `theta_rad`.
    Theta,
    /// `q_rad_s`.
    Q,
    /// `ax_m_s2` at the IMU.
    Ax,
    /// `az_m_s2` at the IMU.
    Az,
    /// `qdot_rad_s2`.
    Qdot,
}

impl LonOutput {
    /// All, in output order.
    pub const ALL: [LonOutput; 7] = [
        LonOutput::Airspeed,
        LonOutput::Alpha,
        LonOutput::Theta,
        LonOutput::Q,
        LonOutput::Ax,
        LonOutput::Az,
        LonOutput::Qdot,
    ];

    /// The schema column.
    pub fn column(self) -> &'static str {
        match self {
            LonOutput::Airspeed => "airspeed_m_s",
            LonOutput::Alpha => "alpha_rad",
            LonOutput::Theta => "theta_rad",
            LonOutput::Q => "q_rad_s",
            LonOutput::Ax => "ax_m_s2",
            LonOutput::Az => "az_m_s2",
            LonOutput::Qdot => "qdot_rad_s2",
        }
    }

    /// The output's value from the state, its derivative and the CG accelerations (module doc).
    pub fn value(self, c: &Constants, theta: &[f64], x: &[f64], e: &LonEval) -> f64 {
        let (v, q) = (x[0].max(1.0), x[3]);
        let qdot = e.dx[3];
        let [ix, _, iz] = c.sensors.imu_m;
        match self {
            LonOutput::Airspeed => x[0],
            LonOutput::Alpha => {
                x[1] + VerticalGust::of(c, theta, x).alpha_rad
                    - q * c.sensors.alpha_vane_m[0] / v
                    - theta[lon::TAU] * e.dx[1]
            }
            LonOutput::Theta => x[2],
            LonOutput::Q => q,
            LonOutput::Ax => e.accel_cg[0] + qdot * iz - q * q * ix,
            LonOutput::Az => e.accel_cg[1] - qdot * ix - q * q * iz,
            LonOutput::Qdot => qdot,
        }
    }
}

/// Indices into the lateral θ.
mod lat {
    pub const CY: usize = 0;
    pub const CL: usize = 6;
    pub const CN: usize = 12;
    pub const TAU: usize = 18;
    pub const TORQUE: usize = 19;
}

/// The inputs the lateral equations read at one instant (V, α, θ, q measured).
#[derive(Debug, Clone, Copy)]
pub struct LatInputs {
    /// Aileron, rad.
    pub aileron_rad: f64,
    /// Rudder, rad.
    pub rudder_rad: f64,
    /// True airspeed, m/s.
    pub airspeed_m_s: f64,
    /// Angle of attack, rad.
    pub alpha_rad: f64,
    /// Pitch attitude, rad.
    pub theta_rad: f64,
    /// Pitch rate, rad/s.
    pub q_rad_s: f64,
    /// Air density, kg/m³.
    pub density_kg_m3: f64,
    /// Total thrust, N (0 when the records carry none).
    pub thrust_n: f64,
}

/// The lateral model's derivatives and side force.
#[derive(Debug, Clone, Copy)]
pub struct LatEval {
    /// ẋ = (β̇, ṗ, ṙ, φ̇).
    pub dx: [f64; 4],
    /// Body lateral specific force at the CG, m/s².
    pub ay_cg: f64,
}

/// Lateral-directional right-hand side (module doc).
pub fn lateral(c: &Constants, theta: &[f64], x: &[f64], u: &LatInputs) -> LatEval {
    let (beta, p, r, phi) = (x[0], x[1], x[2], x[3]);
    let v = u.airspeed_m_s.max(1.0);
    let (m, s, b) = (c.mass.mass_kg, c.geometry.wing_area_m2, c.geometry.span_m);
    let qbar_s = 0.5 * u.density_kg_m3 * v * v * s;
    let (ph, rh) = (p * b / (2.0 * v), r * b / (2.0 * v));
    let coef = |k: usize| {
        theta[k]
            + theta[k + 1] * beta
            + theta[k + 2] * ph
            + theta[k + 3] * rh
            + theta[k + 4] * u.aileron_rad
            + theta[k + 5] * u.rudder_rad
    };
    let (cy, cl, cn) = (coef(lat::CY), coef(lat::CL), coef(lat::CN));
    let mp = &c.mass;
    let (ixx, iyy, izz, ixz) = (mp.ixx_kg_m2, mp.iyy_kg_m2, mp.izz_kg_m2, mp.ixz_kg_m2);
    let q = u.q_rad_s;
    let l1 = qbar_s * b * cl + theta[lat::TORQUE] * u.thrust_n + (iyy - izz) * q * r + ixz * p * q;
    let n1 = qbar_s * b * cn + (ixx - iyy) * p * q - ixz * q * r;
    let gam = ixx * izz - ixz * ixz;
    let pdot = (izz * l1 + ixz * n1) / gam;
    let rdot = (ixz * l1 + ixx * n1) / gam;
    let ay = qbar_s * cy / m;
    let (sa, ca) = u.alpha_rad.sin_cos();
    let betadot = (ay + c.g_m_s2 * u.theta_rad.cos() * phi.sin()) / v + p * sa - r * ca;
    let phidot = p + u.theta_rad.tan() * (q * phi.sin() + r * phi.cos());
    LatEval {
        dx: [betadot, pdot, rdot, phidot],
        ay_cg: ay,
    }
}

/// A lateral output, as measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LatOutput {
    /// `beta_rad` at the vane.
    Beta,
    /// `p_rad_s`.
    P,
    /// `r_rad_s`.
    R,
    /// `phi_rad`.
    Phi,
    /// `ay_m_s2` at the IMU.
    Ay,
    /// `pdot_rad_s2`.
    Pdot,
    /// `rdot_rad_s2`.
    Rdot,
}

impl LatOutput {
    /// All, in output order.
    pub const ALL: [LatOutput; 7] = [
        LatOutput::Beta,
        LatOutput::P,
        LatOutput::R,
        LatOutput::Phi,
        LatOutput::Ay,
        LatOutput::Pdot,
        LatOutput::Rdot,
    ];

    /// The schema column.
    pub fn column(self) -> &'static str {
        match self {
            LatOutput::Beta => "beta_rad",
            LatOutput::P => "p_rad_s",
            LatOutput::R => "r_rad_s",
            LatOutput::Phi => "phi_rad",
            LatOutput::Ay => "ay_m_s2",
            LatOutput::Pdot => "pdot_rad_s2",
            LatOutput::Rdot => "rdot_rad_s2",
        }
    }

    /// The output's value (module doc).
    pub fn value(self, c: &Constants, theta: &[f64], x: &[f64], u: &LatInputs, e: &LatEval) -> f64 {
        let (p, r) = (x[1], x[2]);
        let q = u.q_rad_s;
        let v = u.airspeed_m_s.max(1.0);
        match self {
            LatOutput::Beta => {
                let [xv, _, zv] = c.sensors.beta_vane_m;
                x[0] + (r * xv - p * zv) / v - theta[lat::TAU] * e.dx[0]
            }
            LatOutput::P => p,
            LatOutput::R => r,
            LatOutput::Phi => x[3],
            LatOutput::Ay => {
                let [ix, iy, iz] = c.sensors.imu_m;
                let (pd, rd) = (e.dx[1], e.dx[2]);
                // (ω̇ × r)_y = ṙ x − ṗ z (q̇ ≈ 0 here); (ω × (ω × r))_y = q (ω·r) − y |ω|².
                e.ay_cg + rd * ix - pd * iz + q * (p * ix + q * iy + r * iz)
                    - iy * (p * p + q * q + r * r)
            }
            LatOutput::Pdot => e.dx[1],
            LatOutput::Rdot => e.dx[2],
        }
    }
}

/// Eigenvalues (re, im) of the Jacobian ∂f/∂x of a 4-state right-hand side at `x`, by central differences
/// (steps 1e-6 relative, at least 1e-7).
pub fn jacobian_eigenvalues(
    f: impl Fn(&[f64; 4]) -> [f64; 4],
    x: [f64; 4],
) -> Option<Vec<(f64, f64)>> {
    let mut jac = faer::Mat::<f64>::zeros(4, 4);
    for j in 0..4 {
        let h = (1e-6 * x[j].abs()).max(1e-7);
        let (mut up, mut dn) = (x, x);
        up[j] += h;
        dn[j] -= h;
        let (fu, fd) = (f(&up), f(&dn));
        for i in 0..4 {
            jac[(i, j)] = (fu[i] - fd[i]) / (2.0 * h);
        }
    }
    let ev = jac.eigenvalues().ok()?;
    Some(ev.iter().map(|z| (z.re, z.im)).collect())
}

/// A named mode: (name, ωn or pole, ζ or None).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NamedMode {
    /// `short_period`, `phugoid`, `dutch_roll`, `roll`, `spiral`.
    pub mode: &'static str,
    /// Natural frequency (oscillatory), rad/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub omega_n_rad_s: Option<f64>,
    /// Damping ratio (oscillatory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zeta: Option<f64>,
    /// Real pole, 1/s (roll, spiral; phugoid when it splits into two real poles).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pole_1_s: Option<f64>,
}

impl NamedMode {
    /// An oscillatory mode from its eigenvalue (re, im): ωn = |λ|, ζ = −re/ωn.
    fn oscillatory(mode: &'static str, (re, im): (f64, f64)) -> NamedMode {
        let wn = re.hypot(im);
        NamedMode {
            mode,
            omega_n_rad_s: Some(wn),
            zeta: Some(-re / wn),
            pole_1_s: None,
        }
    }

    /// A mode of one real pole, 1/s.
    fn real(mode: &'static str, pole_1_s: f64) -> NamedMode {
        NamedMode {
            mode,
            omega_n_rad_s: None,
            zeta: None,
            pole_1_s: Some(pole_1_s),
        }
    }
}

/// The real eigenvalues (|im| ≤ 1e-9) of `ev`, fastest (largest |pole|) first.
fn real_poles_fastest_first(ev: &[(f64, f64)]) -> Vec<f64> {
    let mut reals: Vec<f64> = ev
        .iter()
        .filter(|e| e.1.abs() <= 1e-9)
        .map(|e| e.0)
        .collect();
    reals.sort_by(|a, b| b.abs().total_cmp(&a.abs()));
    reals
}

/// Names the longitudinal eigenvalues: the faster complex pair is the short period, the slower the phugoid.
pub fn longitudinal_modes(ev: &[(f64, f64)]) -> Vec<NamedMode> {
    let mut pairs: Vec<(f64, f64)> = ev.iter().copied().filter(|e| e.1 > 1e-9).collect();
    pairs.sort_by(|a, b| b.0.hypot(b.1).total_cmp(&a.0.hypot(a.1)));
    let reals = real_poles_fastest_first(ev);
    match pairs.len() {
        2 => vec![
            NamedMode::oscillatory("short_period", pairs[0]),
            NamedMode::oscillatory("phugoid", pairs[1]),
        ],
        1 => {
            // One pair: fast pair = short period (the phugoid split into reals), or the reverse.
            let fast_real = reals
                .first()
                .is_some_and(|r| r.abs() > pairs[0].0.hypot(pairs[0].1));
            let (pair_name, real_name) = if fast_real {
                ("phugoid", "short_period_real")
            } else {
                ("short_period", "phugoid_real")
            };
            let mut out = vec![NamedMode::oscillatory(pair_name, pairs[0])];
            out.extend(reals.into_iter().map(|r| NamedMode::real(real_name, r)));
            out
        }
        _ => reals
            .into_iter()
            .map(|r| NamedMode::real("longitudinal_real", r))
            .collect(),
    }
}

/// Names the lateral eigenvalues: the complex pair is the Dutch roll, the faster real pole the roll mode,
/// the slower the spiral.
pub fn lateral_modes(ev: &[(f64, f64)]) -> Vec<NamedMode> {
    let mut out: Vec<NamedMode> = ev
        .iter()
        .filter(|e| e.1 > 1e-9)
        .map(|&e| NamedMode::oscillatory("dutch_roll", e))
        .collect();
    for (k, r) in real_poles_fastest_first(ev).into_iter().enumerate() {
        let name = match k {
            0 => "roll",
            1 => "spiral",
            _ => "lateral_real",
        };
        out.push(NamedMode::real(name, r));
    }
    out
}
