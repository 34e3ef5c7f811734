//! Parameters of the parametric model: flight condition, mass, geometry, derivatives and assumptions.
//!
//! All quantities are SI: m, s, kg, kg·m², rad. Nondimensional rate derivatives use the usual reference rates
//! q c̄/(2V) for pitch and p b/(2V), r b/(2V) for roll and yaw; α̇ derivatives use α̇ c̄/(2V).

use std::fmt;
use std::str::FromStr;

use super::AeroError;

fn positive(name: &'static str, value: f64) -> Result<(), AeroError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(AeroError::BadParameter { name, value })
    }
}

/// The steady trim the model is linearised about (stability axes: x along the trim airspeed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightCondition {
    /// True airspeed at trim.
    pub airspeed_m_s: f64,
    /// Air density at trim.
    pub air_density_kg_m3: f64,
    /// Lift coefficient at trim (C_L0).
    pub cl_trim: f64,
    /// Flight-path angle at trim, γ0 (0 in level flight).
    pub flight_path_angle_rad: f64,
    /// Gravitational acceleration.
    pub g_m_s2: f64,
}

impl FlightCondition {
    /// Dynamic pressure q̄ = ½ ρ V².
    pub fn dynamic_pressure_pa(&self) -> f64 {
        0.5 * self.air_density_kg_m3 * self.airspeed_m_s * self.airspeed_m_s
    }

    /// A condition given by dynamic pressure instead of density (ρ = 2 q̄ / V²).
    pub fn from_dynamic_pressure(
        airspeed_m_s: f64,
        dynamic_pressure_pa: f64,
        cl_trim: f64,
        g_m_s2: f64,
    ) -> Self {
        Self {
            airspeed_m_s,
            air_density_kg_m3: 2.0 * dynamic_pressure_pa / (airspeed_m_s * airspeed_m_s),
            cl_trim,
            flight_path_angle_rad: 0.0,
            g_m_s2,
        }
    }

    /// Steady level flight: C_L0 = m g / (q̄ S).
    pub fn level(
        airspeed_m_s: f64,
        air_density_kg_m3: f64,
        mass: &MassProperties,
        geometry: &Geometry,
        g_m_s2: f64,
    ) -> Self {
        let qbar = 0.5 * air_density_kg_m3 * airspeed_m_s * airspeed_m_s;
        Self {
            airspeed_m_s,
            air_density_kg_m3,
            cl_trim: mass.mass_kg * g_m_s2 / (qbar * geometry.wing_area_m2),
            flight_path_angle_rad: 0.0,
            g_m_s2,
        }
    }

    /// Check that speed, density and gravity are usable.
    pub fn validate(&self) -> Result<(), AeroError> {
        positive("airspeed_m_s", self.airspeed_m_s)?;
        positive("air_density_kg_m3", self.air_density_kg_m3)?;
        positive("g_m_s2", self.g_m_s2)?;
        if !self.cl_trim.is_finite() || !self.flight_path_angle_rad.is_finite() {
            return Err(AeroError::BadParameter {
                name: "cl_trim / flight_path_angle_rad",
                value: self.cl_trim,
            });
        }
        Ok(())
    }
}

/// Mass and inertia. Products of inertia use I_xz = ∫ x z dm (Etkin & Reid §4.2), in the axes the
/// derivatives are given in (see [`MassProperties::to_stability_axes`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Aircraft mass.
    pub mass_kg: f64,
    /// Roll moment of inertia.
    pub ixx_kg_m2: f64,
    /// Pitch moment of inertia.
    pub iyy_kg_m2: f64,
    /// Yaw moment of inertia.
    pub izz_kg_m2: f64,
    /// Product of inertia ∫ x z dm.
    pub ixz_kg_m2: f64,
}

impl MassProperties {
    /// Check that mass and the principal inertias are positive.
    pub fn validate(&self) -> Result<(), AeroError> {
        positive("mass_kg", self.mass_kg)?;
        positive("ixx_kg_m2", self.ixx_kg_m2)?;
        positive("iyy_kg_m2", self.iyy_kg_m2)?;
        positive("izz_kg_m2", self.izz_kg_m2)?;
        if !self.ixz_kg_m2.is_finite() {
            return Err(AeroError::BadParameter {
                name: "ixz_kg_m2",
                value: self.ixz_kg_m2,
            });
        }
        Ok(())
    }

    /// Body-axis inertia rotated into stability axes at trim angle of attack α0 (Etkin & Reid eq. 4.11,1 form:
    /// J_s = R J Rᵀ with R the rotation by α0 about y).
    pub fn to_stability_axes(&self, alpha0_rad: f64) -> Self {
        let (s, c) = alpha0_rad.sin_cos();
        let s2 = (2.0 * alpha0_rad).sin();
        Self {
            mass_kg: self.mass_kg,
            ixx_kg_m2: self.ixx_kg_m2 * c * c + self.izz_kg_m2 * s * s - self.ixz_kg_m2 * s2,
            iyy_kg_m2: self.iyy_kg_m2,
            izz_kg_m2: self.ixx_kg_m2 * s * s + self.izz_kg_m2 * c * c + self.ixz_kg_m2 * s2,
            ixz_kg_m2: 0.5 * (self.ixx_kg_m2 - self.izz_kg_m2) * s2
                + self.ixz_kg_m2 * (2.0 * alpha0_rad).cos(),
        }
    }
}

/// Reference geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Wing reference area S.
    pub wing_area_m2: f64,
    /// Wing span b.
    pub span_m: f64,
    /// Mean aerodynamic chord c̄.
    pub chord_m: f64,
}

impl Geometry {
    /// Check that all reference lengths and the area are positive.
    pub fn validate(&self) -> Result<(), AeroError> {
        positive("wing_area_m2", self.wing_area_m2)?;
        positive("span_m", self.span_m)?;
        positive("chord_m", self.chord_m)
    }
}

macro_rules! derivatives {
    ($( $variant:ident => $name:literal, $doc:literal; )*) => {
        /// A named nondimensional derivative (names as in docs/diagnose.md: `Cm_q`, `Cl_beta`, …).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Derivative { $( #[doc = $doc] $variant, )* }

        impl Derivative {
            /// Every derivative the model knows, in a fixed order.
            pub const ALL: &'static [Derivative] = &[$(Derivative::$variant,)*];

            /// The flightid name (`CL_alpha`, `Cm_q`, …).
            pub fn name(self) -> &'static str {
                match self { $(Derivative::$variant => $name,)* }
            }
        }
    };
}

derivatives! {
    CD0 => "CD_0", "Zero-lift drag coefficient of the polar C_D = C_D0 + K C_L².";
    CDCL2 => "CD_CL2", "Induced-drag factor K of the polar C_D = C_D0 + K C_L².";
    CLalpha => "CL_alpha", "Lift-curve slope, per rad.";
    CLde => "CL_de", "Lift due to elevator, per rad.";
    CLq => "CL_q", "Lift due to pitch rate, per q c̄/(2V) (not in the paper's model).";
    CLalphadot => "CL_alphadot", "Lift due to α̇, per α̇ c̄/(2V) (not in the paper's model).";
    Cmalpha => "Cm_alpha", "Pitching moment due to α, per rad.";
    Cmalphadot => "Cm_alphadot", "Pitching moment due to α̇, per α̇ c̄/(2V).";
    Cmq => "Cm_q", "Pitch damping, per q c̄/(2V).";
    Cmde => "Cm_de", "Pitching moment due to elevator, per rad.";
    CYbeta => "CY_beta", "Side force due to sideslip, per rad.";
    CYp => "CY_p", "Side force due to roll rate, per p b/(2V) (not in the paper's model).";
    CYr => "CY_r", "Side force due to yaw rate, per r b/(2V) (not in the paper's model).";
    CYda => "CY_da", "Side force due to aileron, per rad (not in the paper's model).";
    CYdr => "CY_dr", "Side force due to rudder, per rad.";
    Clbeta => "Cl_beta", "Rolling moment due to sideslip (dihedral effect), per rad.";
    Clp => "Cl_p", "Roll damping, per p b/(2V).";
    Clr => "Cl_r", "Rolling moment due to yaw rate, per r b/(2V).";
    Clda => "Cl_da", "Rolling moment due to aileron, per rad.";
    Cldr => "Cl_dr", "Rolling moment due to rudder, per rad.";
    Cnbeta => "Cn_beta", "Yawing moment due to sideslip (weathercock stability), per rad.";
    Cnp => "Cn_p", "Yawing moment due to roll rate, per p b/(2V).";
    Cnr => "Cn_r", "Yaw damping, per r b/(2V).";
    Cnda => "Cn_da", "Yawing moment due to aileron (adverse yaw), per rad.";
    Cndr => "Cn_dr", "Yawing moment due to rudder, per rad.";
}

impl Derivative {
    /// The derivatives the paper's model carries (the list), in model order.
    pub const PAPER: &'static [Derivative] = &[
        Derivative::CD0,
        Derivative::CDCL2,
        Derivative::CLalpha,
        Derivative::CLde,
        Derivative::Cmalpha,
        Derivative::Cmalphadot,
        Derivative::Cmq,
        Derivative::Cmde,
        Derivative::CYbeta,
        Derivative::CYdr,
        Derivative::Clbeta,
        Derivative::Clp,
        Derivative::Clr,
        Derivative::Clda,
        Derivative::Cldr,
        Derivative::Cnbeta,
        Derivative::Cnp,
        Derivative::Cnr,
        Derivative::Cnda,
        Derivative::Cndr,
    ];

    /// True for derivatives of the longitudinal model (drag, lift, pitching moment).
    pub fn is_longitudinal(self) -> bool {
        matches!(
            self,
            Derivative::CD0
                | Derivative::CDCL2
                | Derivative::CLalpha
                | Derivative::CLde
                | Derivative::CLq
                | Derivative::CLalphadot
                | Derivative::Cmalpha
                | Derivative::Cmalphadot
                | Derivative::Cmq
                | Derivative::Cmde
        )
    }

    fn index(self) -> usize {
        Derivative::ALL.iter().position(|&d| d == self).unwrap_or(0)
    }
}

impl fmt::Display for Derivative {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Derivative {
    type Err = AeroError;

    /// Parse a flightid derivative name (case-sensitive, as in docs/diagnose.md).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Derivative::ALL
            .iter()
            .copied()
            .find(|d| d.name() == s)
            .ok_or_else(|| AeroError::UnknownDerivative(s.to_string()))
    }
}

/// Values of all nondimensional derivatives (unset ones are 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Derivatives {
    values: Vec<f64>,
}

impl Default for Derivatives {
    fn default() -> Self {
        Self {
            values: vec![0.0; Derivative::ALL.len()],
        }
    }
}

impl Derivatives {
    /// Build from (derivative, value) pairs; the rest are 0.
    pub fn from_pairs(pairs: &[(Derivative, f64)]) -> Self {
        let mut d = Self::default();
        for &(k, v) in pairs {
            d.set(k, v);
        }
        d
    }

    /// Value of one derivative.
    pub fn get(&self, d: Derivative) -> f64 {
        self.values[d.index()]
    }

    /// Set one derivative.
    pub fn set(&mut self, d: Derivative, value: f64) {
        self.values[d.index()] = value;
    }

    /// Lateral-directional derivatives given in body axes rotated into stability axes at trim α0
    /// (Etkin & Reid §4.4 / Roskam Part VI §1.3: moments and rates both rotate by α0 about y). Longitudinal
    /// derivatives are unchanged (the rotation is about their own axis).
    pub fn body_to_stability(&self, alpha0_rad: f64) -> Self {
        use Derivative as D;
        let (s, c) = alpha0_rad.sin_cos();
        let g = |d: D| self.get(d);
        let mut out = self.clone();
        out.set(D::Clbeta, g(D::Clbeta) * c + g(D::Cnbeta) * s);
        out.set(D::Cnbeta, g(D::Cnbeta) * c - g(D::Clbeta) * s);
        out.set(
            D::Clp,
            g(D::Clp) * c * c + (g(D::Clr) + g(D::Cnp)) * s * c + g(D::Cnr) * s * s,
        );
        out.set(
            D::Clr,
            g(D::Clr) * c * c - (g(D::Clp) - g(D::Cnr)) * s * c - g(D::Cnp) * s * s,
        );
        out.set(
            D::Cnp,
            g(D::Cnp) * c * c - (g(D::Clp) - g(D::Cnr)) * s * c - g(D::Clr) * s * s,
        );
        out.set(
            D::Cnr,
            g(D::Cnr) * c * c - (g(D::Clr) + g(D::Cnp)) * s * c + g(D::Clp) * s * s,
        );
        for (l, n) in [(D::Clda, D::Cnda), (D::Cldr, D::Cndr)] {
            out.set(l, g(l) * c + g(n) * s);
            out.set(n, g(n) * c - g(l) * s);
        }
        out.set(D::CYp, g(D::CYp) * c + g(D::CYr) * s);
        out.set(D::CYr, g(D::CYr) * c - g(D::CYp) * s);
        out
    }
}

/// How thrust varies with airspeed in the speed equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThrustModel {
    /// Thrust independent of speed: no thrust derivative (the paper's assumption).
    Constant,
    /// Constant power, T = P/V, so ∂T/∂V = −T0/V (a rough propeller model; T0 balances trim drag).
    ConstantPower,
}

/// The simplifying assumptions of the small-perturbation model, each switchable.
///
/// `Assumptions::paper()` is the paper's structure; `Assumptions::textbook()` keeps every term this model
/// knows. Each flag says what it switches and what it costs on the c172x check (see the module tests).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assumptions {
    /// Include C_Lq and C_Lα̇ in the lift (α̇) equation. Paper: false. c172x: short-period ωn +1.3 % when off.
    pub lift_rate_terms: bool,
    /// Z_α = −(C_Lα + C_D,trim) q̄S/(mV) (textbook, Nelson §3.6) instead of −C_Lα q̄S/(mV).
    /// c172x: 0.2 % of short-period ζ.
    pub drag_in_z_alpha: bool,
    /// The C_Y derivatives are for the wind-axis side force (JSBSim's `SIDE` axis), so the stability-axis
    /// side-force slope is C_Yβ − C_D,trim. c172x with JSBSim derivatives: Dutch-roll ζ −5.1 % when off
    /// (−2.5 % when on).
    pub side_force_in_wind_axes: bool,
    /// Include C_Yp, C_Yr, C_Yδa in the side-force equation. Paper: false (they are not in its list).
    /// c172x: Dutch-roll ωn +0.4 % when off.
    pub side_force_rate_terms: bool,
    /// Elevator drag from the polar, C_Dδe = 2 K C_L0 C_Lδe. Off: no elevator term in the speed equation.
    pub elevator_drag_from_polar: bool,
    /// Thrust variation with speed. c172x: constant thrust halves the phugoid damping against JSBSim
    /// (−50 %); constant power gives −19 %. Short period and Dutch roll are unaffected.
    pub thrust: ThrustModel,
    /// Keep the I_xz coupling terms c23, c32 of the lateral descriptor matrix (paper eq. 38–40).
    /// c172x (stability-axis I_xz = −46 kg·m²): 3 % of Dutch-roll ζ.
    pub ixz_coupling: bool,
    /// Use γ0 = θ0 = 0 in the gravity and kinematic terms even when the flight condition says otherwise.
    pub level_flight: bool,
}

impl Assumptions {
    /// The paper's structure: no lift rate terms, no thrust derivatives, level flight, I_xz kept,
    /// only the listed derivatives.
    pub fn paper() -> Self {
        Self {
            lift_rate_terms: false,
            drag_in_z_alpha: false,
            side_force_in_wind_axes: false,
            side_force_rate_terms: false,
            elevator_drag_from_polar: true,
            thrust: ThrustModel::Constant,
            ixz_coupling: true,
            level_flight: true,
        }
    }

    /// Every term the model knows (still constant thrust: thrust is the user's choice).
    pub fn textbook() -> Self {
        Self {
            lift_rate_terms: true,
            drag_in_z_alpha: true,
            side_force_in_wind_axes: false,
            side_force_rate_terms: true,
            elevator_drag_from_polar: true,
            thrust: ThrustModel::Constant,
            ixz_coupling: true,
            level_flight: false,
        }
    }
}

impl Default for Assumptions {
    fn default() -> Self {
        Self::paper()
    }
}
