//! What the JSBSim model itself uses at a trim point ([`AeroTruth`]): its nondimensional derivatives from its
//! own coefficient functions, flight condition, mass, inertia and geometry, and the kinks of single coefficient
//! functions at the trim. The truth the derivative study and `compare` score against.

use std::collections::BTreeMap;

use super::jsbsim::{probe_steps, JsbsimSim};
use super::protocol::{ProbeReply, Request};
use super::{SimError, FT_TO_M};
use crate::signal::cross;

/// Slug to kilogram.
const SLUG_TO_KG: f64 = 14.593_902_937;
/// Slug·ft² to kg·m².
const SLUG_FT2_TO_KG_M2: f64 = 1.355_817_948;
/// Pound-force per square foot to pascal.
const PSF_TO_PA: f64 = 47.880_258_98;
/// Slug per cubic foot to kg/m³.
const SLUG_FT3_TO_KG_M3: f64 = 515.378_818;

/// What the JSBSim model itself uses at a trim point: nondimensional stability and control derivatives
/// (evaluated from its own coefficient functions, tables included, by central differences), flight condition,
/// mass, inertia and geometry — SI units.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct AeroTruth {
    /// Derivatives by the names of docs/diagnose.md (`CL_alpha`, `Cm_q`, `Cn_beta`, …), per rad; rate derivatives
    /// nondimensionalised with c̄/2V (pitch) and b/2V (roll, yaw); moments about the CG, in the axes the model
    /// declares (c172x: lift/drag/side in wind axes, moments in body axes).
    pub derivatives: BTreeMap<String, f64>,
    /// The same derivatives about the model's aero reference point: the values written in its XML.
    pub derivatives_aero_reference: BTreeMap<String, f64>,
    /// Coefficients at trim: `CL`, `CD`, `CY`, `Cl`, `Cm`, `Cn` (about the model's aero reference point).
    pub coefficients: BTreeMap<String, f64>,
    /// True airspeed, m/s.
    pub airspeed_m_s: f64,
    /// Dynamic pressure, Pa.
    pub qbar_pa: f64,
    /// Air density, kg/m³.
    pub rho_kg_m3: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Roll inertia, kg·m².
    pub ixx_kg_m2: f64,
    /// Pitch inertia, kg·m².
    pub iyy_kg_m2: f64,
    /// Yaw inertia, kg·m².
    pub izz_kg_m2: f64,
    /// Product of inertia ∫xz dm in body axes, kg·m², as in Ixx ṗ − Ixz ṙ = L (Etkin & Reid; Stevens &
    /// Lewis). JSBSim's `inertia/ixz-slugs_ft2` has the other sign: its inertia tensor holds that property where
    /// the textbook tensor holds −Ixz (checked on the 737: Ixx ṗ − L = −19 106 ṙ with the property at +19 106).
    pub ixz_kg_m2: f64,
    /// Wing area, m².
    pub wing_area_m2: f64,
    /// Wing span, m.
    pub span_m: f64,
    /// Mean aerodynamic chord, m.
    pub chord_m: f64,
    /// Trim angle of attack, rad.
    pub alpha_rad: f64,
    /// Gravitational acceleration at the trim altitude, m/s².
    #[serde(default)]
    pub g_m_s2: f64,
    /// Coefficient functions with a kink at the trim point (see [`NonSmoothTerm`]).
    #[serde(default)]
    pub nonsmooth: Vec<NonSmoothTerm>,
}

/// A coefficient function whose slope at the trim point differs on the two sides of it: a term in `|β|` (c172x's
/// sideslip drag `CDbeta = 0.17·|β|`), a table breakpoint at the trim value. A central-difference linearization
/// (JSBSim's `FGLinearization`) sees only the mean of the two slopes, so what the term does in flight, where the
/// variable swings both ways, is missing from the linear model.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NonSmoothTerm {
    /// The model's coefficient function (`aero/coefficient/NAME`), e.g. `CDbeta`.
    pub coefficient: String,
    /// Its axis in the model (`DRAG`, `SIDE`, `LIFT`, `ROLL`, `PITCH`, `YAW`).
    pub axis: String,
    /// The variable with the kink: `alpha`, `beta`, `p`, `q`, `r` or `surface:NAME`.
    pub variable: String,
    /// Nondimensional slope just below the trim value (per rad; rates per unit of p̂ = p·b/2V, q̂ = q·c̄/2V).
    pub slope_below: f64,
    /// The same just above it.
    pub slope_above: f64,
}

/// The property of an aerodynamic coefficient function, `aero/coefficient/NAME`.
pub fn coefficient_property(name: &str) -> String {
    format!("aero/coefficient/{name}")
}

/// JSBSim properties that place the aerodynamic reference point and the CG (structural frame, inches).
pub const ARM_PROPERTIES: [&str; 6] = [
    "metrics/aero-rp-x-in",
    "metrics/aero-rp-y-in",
    "metrics/aero-rp-z-in",
    "inertia/cg-x-in",
    "inertia/cg-y-in",
    "inertia/cg-z-in",
];

/// The arm from the CG to the aerodynamic reference point in body axes (x forward, y right, z down), ft, from
/// the values of [`ARM_PROPERTIES`] (structural frame: x aft, y right, z up, inches).
pub fn reference_arm_ft(value: impl Fn(&str) -> f64) -> [f64; 3] {
    [
        -(value("metrics/aero-rp-x-in") - value("inertia/cg-x-in")) / 12.0,
        (value("metrics/aero-rp-y-in") - value("inertia/cg-y-in")) / 12.0,
        -(value("metrics/aero-rp-z-in") - value("inertia/cg-z-in")) / 12.0,
    ]
}

/// Smallest jump between one-sided slopes reported as a kink, nondimensional per rad: smaller ones change no
/// response a report could show (CDbeta's is 0.34).
const NONSMOOTH_MIN_JUMP: f64 = 0.01;

/// Kinks of single coefficient functions at the trim, from the probe's one-sided differences: for a smooth
/// function `(f(x+h) − f(x))/h − (f(x) − f(x−h))/h = f''·h` vanishes with h, for a kink it stays the jump in
/// slope. Reported when the jump exceeds [`NONSMOOTH_MIN_JUMP`] and a quarter of the larger slope.
fn nonsmooth_terms(
    probe: &ProbeReply,
    axes: &BTreeMap<String, String>,
    norm: &dyn Fn(&str) -> f64,
    pitch_rate: f64,
    lat_rate: f64,
) -> Vec<NonSmoothTerm> {
    let mut out = Vec::new();
    for (var, scale) in [
        ("alpha", 1.0),
        ("beta", 1.0),
        ("p", lat_rate),
        ("q", pitch_rate),
        ("r", lat_rate),
        ("surface:elevator", 1.0),
        ("surface:aileron", 1.0),
        ("surface:rudder", 1.0),
    ] {
        let Some(p) = probe.perturbed.get(var) else {
            continue;
        };
        for (coefficient, axis) in axes {
            let axis = axis.as_str();
            let key = coefficient_property(coefficient);
            let (Some(plus), Some(minus), Some(at)) =
                (p.plus.get(&key), p.minus.get(&key), probe.base.get(&key))
            else {
                continue;
            };
            let per_unit = scale / (p.h * norm(axis));
            let (above, below) = ((plus - at) * per_unit, (at - minus) * per_unit);
            let jump = (above - below).abs();
            if jump > NONSMOOTH_MIN_JUMP && jump > 0.25 * above.abs().max(below.abs()) {
                out.push(NonSmoothTerm {
                    coefficient: coefficient.clone(),
                    axis: axis.to_string(),
                    variable: var.to_string(),
                    slope_below: below,
                    slope_above: above,
                });
            }
        }
    }
    out
}

impl JsbsimSim {
    /// The derivatives, mass, inertia and geometry the model uses at the current trim (see [`AeroTruth`]).
    ///
    /// Each aero input (α, β, p, q, r, α̇, β̇, surface deflections) is perturbed by ±h through the probe
    /// properties of the private copy with integration suspended, and the per-axis sums of the model's coefficient
    /// functions are differenced: dC/dx ≈ (C(x+h) − C(x−h)) / 2h. CD_CL2 is (dCD/dα) / (2 CL CL_α), CD_0 = CD − CD_CL2 CL².
    pub fn aero_truth(&mut self) -> Result<AeroTruth, SimError> {
        let trim = self
            .trim
            .clone()
            .ok_or_else(|| SimError::Usage("aero_truth needs a successful trim first".into()))?;
        let condition = [
            "aero/qbar-psf",
            "velocities/vt-fps",
            "atmosphere/rho-slugs_ft3",
            "inertia/mass-slugs",
            "inertia/ixx-slugs_ft2",
            "inertia/iyy-slugs_ft2",
            "inertia/izz-slugs_ft2",
            "inertia/ixz-slugs_ft2",
            "metrics/Sw-sqft",
            "metrics/bw-ft",
            "metrics/cbarw-ft",
            "aero/beta-rad",
            "accelerations/gravity-ft_sec2",
        ]
        .into_iter()
        .chain(ARM_PROPERTIES)
        .map(|p| p.to_string())
        .collect();
        // the CG moments, and every coefficient function on its own (for its one-sided slopes: kinks)
        let extra: Vec<String> = [
            "moments/m-aero-lbsft",
            "moments/l-aero-lbsft",
            "moments/n-aero-lbsft",
        ]
        .iter()
        .map(|p| p.to_string())
        .chain(
            self.coefficient_axes
                .keys()
                .map(|c| coefficient_property(c)),
        )
        .collect();
        let req = Request::Probe {
            perturb: probe_steps(),
            condition,
            extra,
        };
        let probe: ProbeReply = self.bridge.request(&req, &[])?.reply;
        let c = |k: &str| probe.condition.get(k).copied().unwrap_or(f64::NAN);
        let qbar_psf = c("aero/qbar-psf");
        let (s_ft2, b_ft, cbar_ft, v_fps) = (
            c("metrics/Sw-sqft"),
            c("metrics/bw-ft"),
            c("metrics/cbarw-ft"),
            c("velocities/vt-fps"),
        );
        let qs = qbar_psf * s_ft2;
        // Normalisation per axis: forces by q̄S, pitch by q̄Sc̄, roll and yaw by q̄Sb.
        let norm = |axis: &str| match axis {
            "PITCH" => qs * cbar_ft,
            "ROLL" | "YAW" => qs * b_ft,
            _ => qs,
        };
        let base = &probe.base;
        let coef = |axis: &str| base.get(axis).copied().unwrap_or(0.0) / norm(axis);
        // d(prop)/d(var) divided by n; 0 when the probe did not read it
        let slope_of = |var: &str, prop: &str, n: f64| -> f64 {
            let difference = probe
                .perturbed
                .get(var)
                .and_then(|p| p.central_difference(prop));
            difference.unwrap_or(0.0) / n
        };
        let slope = |var: &str, axis: &str| -> f64 { slope_of(var, axis, norm(axis)) };
        let pitch_rate = 2.0 * v_fps / cbar_ft;
        let lat_rate = 2.0 * v_fps / b_ft;
        // Moments about the CG (what the dynamics see) are JSBSim's own body-axis aero moments, which include the
        // transfer of the aero forces from the aero reference point to the CG.
        let cg_axis = |axis: &str| match axis {
            "PITCH" => Some("moments/m-aero-lbsft"),
            "ROLL" => Some("moments/l-aero-lbsft"),
            "YAW" => Some("moments/n-aero-lbsft"),
            _ => None,
        };
        // Force turn: the probe changes what the coefficient functions read, but JSBSim rotates the wind-axis
        // forces into body axes with the *unperturbed* α and β, so `moments/*-aero-lbsft` miss the moment of
        // the force vector turning with α (β) about the CG. In flight the lift vector turns with α; with the
        // c172x reference point ~2 ft above the CG that is worth −0.19 in Cm_α (−1.345 without, −1.535 with,
        // the value `scripts/oracle_aero.py` gets from run_ic states). Add r × (∂T_w2b/∂x) F_w.
        let arm_ft = reference_arm_ft(c);
        let force_wind_lbs = [
            -base.get("DRAG").copied().unwrap_or(0.0),
            base.get("SIDE").copied().unwrap_or(0.0),
            -base.get("LIFT").copied().unwrap_or(0.0),
        ];
        let (alpha0, beta0) = (trim.alpha_rad, c("aero/beta-rad"));
        let force_turn = |var: &str, axis: &str| -> f64 {
            let step = 1e-6;
            let moment = |a: f64, b: f64| cross(arm_ft, wind_to_body(a, b, force_wind_lbs));
            let (plus, minus) = match var {
                "alpha" => (moment(alpha0 + step, beta0), moment(alpha0 - step, beta0)),
                "beta" => (moment(alpha0, beta0 + step), moment(alpha0, beta0 - step)),
                _ => return 0.0,
            };
            let k = match axis {
                "ROLL" => 0,
                "PITCH" => 1,
                "YAW" => 2,
                _ => return 0.0,
            };
            (plus[k] - minus[k]) / (2.0 * step) / norm(axis)
        };
        let mut d = BTreeMap::new();
        let mut d_arp = BTreeMap::new();
        // Each axis' coefficient against each variable of its plane: (suffix, probed variable, scale).
        let longitudinal = [
            ("alpha", "alpha", 1.0),
            ("q", "q", pitch_rate),
            ("alphadot", "alphadot", pitch_rate),
            ("de", "surface:elevator", 1.0),
        ];
        let lateral = [
            ("beta", "beta", 1.0),
            ("p", "p", lat_rate),
            ("r", "r", lat_rate),
            ("da", "surface:aileron", 1.0),
            ("dr", "surface:rudder", 1.0),
        ];
        let planes = [
            (&[("CL", "LIFT"), ("Cm", "PITCH")][..], &longitudinal[..]),
            (
                &[("CY", "SIDE"), ("Cl", "ROLL"), ("Cn", "YAW")][..],
                &lateral[..],
            ),
        ];
        for (coefficients, variables) in planes {
            for &(coefficient, axis) in coefficients {
                for &(suffix, var, scale) in variables {
                    let name = format!("{coefficient}_{suffix}");
                    d_arp.insert(name.clone(), slope(var, axis) * scale);
                    let about_cg = match cg_axis(axis) {
                        Some(prop) => slope_of(var, prop, norm(axis)) + force_turn(var, axis),
                        None => slope(var, axis),
                    };
                    d.insert(name, about_cg * scale);
                }
            }
        }
        let nonsmooth =
            nonsmooth_terms(&probe, &self.coefficient_axes, &norm, pitch_rate, lat_rate);
        let cl = coef("LIFT");
        let cd = coef("DRAG");
        let cd_alpha = slope("alpha", "DRAG");
        let k = if cl.abs() > 1e-6 && d["CL_alpha"].abs() > 1e-9 {
            cd_alpha / (2.0 * cl * d["CL_alpha"])
        } else {
            f64::NAN
        };
        for map in [&mut d, &mut d_arp] {
            map.insert("CD_CL2".into(), k);
            map.insert("CD_0".into(), cd - k * cl * cl);
        }
        let coefficients = [
            ("CL", "LIFT"),
            ("CD", "DRAG"),
            ("CY", "SIDE"),
            ("Cl", "ROLL"),
            ("Cm", "PITCH"),
            ("Cn", "YAW"),
        ]
        .iter()
        .map(|(n, a)| (n.to_string(), coef(a)))
        .collect();
        Ok(AeroTruth {
            derivatives: d,
            derivatives_aero_reference: d_arp,
            coefficients,
            airspeed_m_s: v_fps * FT_TO_M,
            qbar_pa: qbar_psf * PSF_TO_PA,
            rho_kg_m3: c("atmosphere/rho-slugs_ft3") * SLUG_FT3_TO_KG_M3,
            mass_kg: c("inertia/mass-slugs") * SLUG_TO_KG,
            ixx_kg_m2: c("inertia/ixx-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            iyy_kg_m2: c("inertia/iyy-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            izz_kg_m2: c("inertia/izz-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            ixz_kg_m2: -c("inertia/ixz-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            wing_area_m2: s_ft2 * FT_TO_M * FT_TO_M,
            span_m: b_ft * FT_TO_M,
            chord_m: cbar_ft * FT_TO_M,
            alpha_rad: trim.alpha_rad,
            g_m_s2: c("accelerations/gravity-ft_sec2") * FT_TO_M,
            nonsmooth,
        })
    }
}

/// Mass, inertia and wing of a JSBSim model at its initial condition (no trim), SI units: what an airframe
/// description takes from an aircraft name that has no flightid configuration (`aircraft/NAME.toml`).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelMassAndWing {
    /// Mass, kg (empty weight, point masses and the tanks' initial contents).
    pub mass_kg: f64,
    /// Roll, pitch and yaw inertia and the product of inertia ∫xz dm (the sign of [`AeroTruth::ixz_kg_m2`]), kg·m².
    pub inertia_kg_m2: [f64; 4],
    /// Wing area, m².
    pub wing_area_m2: f64,
    /// Wing span, m.
    pub span_m: f64,
    /// Mean aerodynamic chord, m.
    pub chord_m: f64,
    /// The engines' mean thrust line about the CG from their thrusters' positions and orientations:
    /// (pitching moment per unit thrust, positive nose up, m; inclination above body x, rad); `None` when unknown.
    pub thrust_line: Option<(f64, f64)>,
}

impl AeroTruth {
    /// The mass, inertia and wing of the trimmed model (no thrust line: the trim's forces are not split by
    /// engine).
    pub fn mass_and_wing(&self) -> ModelMassAndWing {
        ModelMassAndWing {
            mass_kg: self.mass_kg,
            inertia_kg_m2: [
                self.ixx_kg_m2,
                self.iyy_kg_m2,
                self.izz_kg_m2,
                self.ixz_kg_m2,
            ],
            wing_area_m2: self.wing_area_m2,
            span_m: self.span_m,
            chord_m: self.chord_m,
            thrust_line: None,
        }
    }
}

/// [`ModelMassAndWing`] of the JSBSim model `aircraft`, from a bridge process of its own (the bridge's
/// `airframe` command: loaded, run to its initial condition, dropped). A name JSBSim has no model of is
/// [`SimError::UnknownModel`].
pub fn model_mass_and_wing(aircraft: &str) -> Result<ModelMassAndWing, SimError> {
    let got = model_airframe(aircraft)?;
    let c = |k: &str| got.values.get(k).copied().unwrap_or(f64::NAN);
    Ok(ModelMassAndWing {
        mass_kg: c("inertia/mass-slugs") * SLUG_TO_KG,
        inertia_kg_m2: [
            c("inertia/ixx-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            c("inertia/iyy-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            c("inertia/izz-slugs_ft2") * SLUG_FT2_TO_KG_M2,
            -c("inertia/ixz-slugs_ft2") * SLUG_FT2_TO_KG_M2,
        ],
        wing_area_m2: c("metrics/Sw-sqft") * FT_TO_M * FT_TO_M,
        span_m: c("metrics/bw-ft") * FT_TO_M,
        chord_m: c("metrics/cbarw-ft") * FT_TO_M,
        thrust_line: got.thrust.map(|t| (t.moment_arm_m, t.inclination_rad)),
    })
}

/// The bridge's `airframe` reply for the JSBSim model `aircraft`, from a bridge process of its own (loaded, run
/// to its initial condition, dropped). A name JSBSim has no model of is [`SimError::UnknownModel`].
pub fn model_airframe(aircraft: &str) -> Result<super::protocol::AirframeReply, SimError> {
    let mut bridge = super::bridge::Bridge::spawn()?;
    let req = Request::Airframe {
        aircraft: aircraft.to_string(),
        scratch_dir: bridge.scratch_dir().display().to_string(),
        aircraft_dir: None,
    };
    Ok(bridge.request(&req, &[])?.reply)
}

/// JSBSim's wind-to-body rotation (`FGAuxiliary::Tw2b`) applied to a wind-axis vector.
pub(crate) fn wind_to_body(alpha_rad: f64, beta_rad: f64, v: [f64; 3]) -> [f64; 3] {
    let (sa, ca) = alpha_rad.sin_cos();
    let (sb, cb) = beta_rad.sin_cos();
    [
        ca * cb * v[0] - ca * sb * v[1] - sa * v[2],
        sb * v[0] + cb * v[1],
        sa * cb * v[0] - sa * sb * v[1] + ca * v[2],
    ]
}
