//! The parametric small-perturbation model in descriptor form `C ẋ = A x + B u` and its transfer functions.
//!
//! Longitudinal (paper eq. 21–33), stability axes, x = (u m/s, α rad, q rad/s, θ rad), input δe:
//!
//! ```text
//!  u̇                 = X_u u + X_α α − g cos γ0 θ + X_δe δe
//! (1 − Z_α̇) α̇        = Z_u u + Z_α α + (1 + Z_q) q − (g/V) sin γ0 θ + Z_δe δe
//! −M_α̇ α̇ + q̇         = M_α α + M_q q + M_δe δe                   (c32 = −M_α̇)
//!  θ̇                 = q
//! ```
//! with (Etkin & Reid §4.9, Nelson §3.6; α-equation terms divided by V):
//! X_u = −2 q̄S C_D/(mV) (+ thrust), X_α = g cos γ0 − q̄S C_Dα/m, C_Dα = 2 K C_L0 C_Lα, X_δe = −q̄S C_Dδe/m,
//! Z_u = −2 q̄S C_L0/(mV²), Z_α = −q̄S (C_Lα [+ C_D])/(mV), Z_q = −q̄S c̄ C_Lq/(2mV²), Z_α̇ = −q̄S c̄ C_Lα̇/(2mV²),
//! Z_δe = −q̄S C_Lδe/(mV), M_α = q̄Sc̄ C_mα/I_yy, M_q = q̄Sc̄² C_mq/(2V I_yy), M_α̇ = q̄Sc̄² C_mα̇/(2V I_yy),
//! M_δe = q̄Sc̄ C_mδe/I_yy; C_D = C_D0 + K C_L0² is the trim drag coefficient.
//!
//! Lateral (paper eq. 38–53), stability axes, x = (β rad, p, r rad/s, φ rad), inputs (δa, δr):
//!
//! ```text
//!  β̇                 = Y_β β + Y_p p + (Y_r − 1) r + (g/V) cos γ0 φ + Y_δa δa + Y_δr δr
//!  ṗ − (I_xz/I_xx) ṙ = L_β β + L_p p + L_r r + L_δa δa + L_δr δr      (c23 = −I_xz/I_xx)
//! −(I_xz/I_zz) ṗ + ṙ = N_β β + N_p p + N_r r + N_δa δa + N_δr δr      (c32 = −I_xz/I_zz)
//!  φ̇                 = p + tan γ0 r
//! ```
//! with Y_β = q̄S C_Yβ/(mV), Y_p = q̄Sb C_Yp/(2mV²), L_β = q̄Sb C_lβ/I_xx, L_p = q̄Sb² C_lp/(2V I_xx), etc.
//!
//! Transfer functions come from the state space through `crate::lti::ss2tf` (matrix determinant
//! lemma on Hessenberg characteristic polynomials), the one SS→TF conversion of the crate.

use faer::prelude::Solve;
use faer::Mat;

use crate::lti::{ss2tf, StateSpace};

use super::params::{
    Assumptions, Derivative as D, Derivatives, FlightCondition, Geometry, MassProperties,
    ThrustModel,
};
use super::AeroError;

/// The full parametric model: trim, mass, geometry, derivatives and assumptions.
#[derive(Debug, Clone, PartialEq)]
pub struct AeroModel {
    /// Trim flight condition.
    pub flight: FlightCondition,
    /// Mass and inertia (stability axes).
    pub mass: MassProperties,
    /// Reference geometry.
    pub geometry: Geometry,
    /// Nondimensional derivatives (stability axes).
    pub derivatives: Derivatives,
    /// Simplifying assumptions.
    pub assumptions: Assumptions,
}

/// Which decoupled submodel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// States u, α, q, θ; input δe.
    Longitudinal,
    /// States β, p, r, φ; inputs δa, δr.
    Lateral,
}

impl Axis {
    /// State names with units, in model order.
    pub fn state_names(self) -> [&'static str; 4] {
        match self {
            Axis::Longitudinal => ["u_m_s", "alpha_rad", "q_rad_s", "theta_rad"],
            Axis::Lateral => ["beta_rad", "p_rad_s", "r_rad_s", "phi_rad"],
        }
    }

    /// Input names, in model order.
    pub fn input_names(self) -> &'static [&'static str] {
        match self {
            Axis::Longitudinal => &["elevator_rad"],
            Axis::Lateral => &["aileron_rad", "rudder_rad"],
        }
    }
}

/// One transfer function of the model: output state over input, by index into [`Axis::state_names`] and
/// [`Axis::input_names`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TfOutput {
    /// Submodel.
    pub axis: Axis,
    /// Output state index (0..4).
    pub state: usize,
    /// Input index.
    pub input: usize,
}

impl TfOutput {
    /// θ/δe, the paper's longitudinal transfer function.
    pub const THETA_ELEVATOR: TfOutput = TfOutput {
        axis: Axis::Longitudinal,
        state: 3,
        input: 0,
    };
    /// φ/δa, the paper's roll transfer function to aileron.
    pub const PHI_AILERON: TfOutput = TfOutput {
        axis: Axis::Lateral,
        state: 3,
        input: 0,
    };
    /// φ/δr, the paper's roll transfer function to rudder.
    pub const PHI_RUDDER: TfOutput = TfOutput {
        axis: Axis::Lateral,
        state: 3,
        input: 1,
    };

    /// A readable label such as `theta_rad/elevator_rad`.
    pub fn label(self) -> String {
        let s = self
            .axis
            .state_names()
            .get(self.state)
            .copied()
            .unwrap_or("?");
        let i = self
            .axis
            .input_names()
            .get(self.input)
            .copied()
            .unwrap_or("?");
        format!("{s}/{i}")
    }
}

/// Continuous-time transfer-function coefficients in descending powers of s; `den[0] == 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct TfCoefficients {
    /// Numerator, length n (degree ≤ n − 1).
    pub num: Vec<f64>,
    /// Monic denominator, length n + 1.
    pub den: Vec<f64>,
}

/// A mode of a linear model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// A complex pair: natural frequency and damping ratio.
    Oscillatory {
        /// Natural frequency ωn.
        omega_n_rad_s: f64,
        /// Damping ratio ζ.
        zeta: f64,
    },
    /// A real pole.
    Real {
        /// The pole, 1/s (negative is stable).
        pole_1_s: f64,
    },
}

impl Mode {
    /// (ωn, ζ) of a complex pair; `None` for a real pole.
    pub fn oscillation(self) -> Option<(f64, f64)> {
        match self {
            Mode::Oscillatory {
                omega_n_rad_s,
                zeta,
            } => Some((omega_n_rad_s, zeta)),
            Mode::Real { .. } => None,
        }
    }
}

/// A decoupled linear submodel in descriptor and in explicit form.
#[derive(Debug, Clone)]
pub struct LinearModel {
    /// Submodel.
    pub axis: Axis,
    /// Descriptor matrix C of `C ẋ = A x + B u` (paper eq. 22 and 39).
    pub c_desc: Mat<f64>,
    /// A of the descriptor form.
    pub a_desc: Mat<f64>,
    /// B of the descriptor form.
    pub b_desc: Mat<f64>,
    /// Explicit ẋ = A x + B u: A = C⁻¹ A_desc.
    pub a: Mat<f64>,
    /// Explicit B = C⁻¹ B_desc.
    pub b: Mat<f64>,
}

impl AeroModel {
    /// Validate the physical parameters (the derivatives may take any finite value).
    pub fn validate(&self) -> Result<(), AeroError> {
        self.flight.validate()?;
        self.mass.validate()?;
        self.geometry.validate()?;
        for &d in super::params::Derivative::ALL {
            let v = self.derivatives.get(d);
            if !v.is_finite() {
                return Err(AeroError::BadParameter {
                    name: d.name(),
                    value: v,
                });
            }
        }
        Ok(())
    }

    fn gamma0(&self) -> f64 {
        if self.assumptions.level_flight {
            0.0
        } else {
            self.flight.flight_path_angle_rad
        }
    }

    /// Trim drag coefficient C_D = C_D0 + K C_L0².
    pub fn cd_trim(&self) -> f64 {
        let d = &self.derivatives;
        d.get(D::CD0) + d.get(D::CDCL2) * self.flight.cl_trim * self.flight.cl_trim
    }

    /// Validates the model and gives the trim airspeed V (m/s) and q̄S (N), the scales of both submodels'
    /// dimensional derivatives.
    fn airspeed_and_qs(&self) -> Result<(f64, f64), AeroError> {
        self.validate()?;
        let qs = self.flight.dynamic_pressure_pa() * self.geometry.wing_area_m2;
        Ok((self.flight.airspeed_m_s, qs))
    }

    /// The longitudinal submodel (states u, α, q, θ; input δe).
    pub fn longitudinal(&self) -> Result<LinearModel, AeroError> {
        let (v, qs) = self.airspeed_and_qs()?;
        let (f, m, g) = (&self.flight, &self.mass, &self.geometry);
        let (d, a) = (&self.derivatives, &self.assumptions);
        let kc = g.chord_m / (2.0 * v);
        let cl0 = f.cl_trim;
        let k_ind = d.get(D::CDCL2);
        let cd = self.cd_trim();
        let cd_alpha = 2.0 * k_ind * cl0 * d.get(D::CLalpha);
        let cd_de = if a.elevator_drag_from_polar {
            2.0 * k_ind * cl0 * d.get(D::CLde)
        } else {
            0.0
        };
        let gamma0 = self.gamma0();
        let mass = m.mass_kg;

        let thrust_u = match a.thrust {
            ThrustModel::Constant => 0.0,
            ThrustModel::ConstantPower => {
                let t0 = qs * cd + mass * f.g_m_s2 * gamma0.sin();
                -t0 / (mass * v)
            }
        };
        let x_u = -2.0 * qs * cd / (mass * v) + thrust_u;
        let x_alpha = f.g_m_s2 * gamma0.cos() - qs * cd_alpha / mass;
        let x_de = -qs * cd_de / mass;

        let (cl_q, cl_ad) = if a.lift_rate_terms {
            (d.get(D::CLq), d.get(D::CLalphadot))
        } else {
            (0.0, 0.0)
        };
        let drag_z = if a.drag_in_z_alpha { cd } else { 0.0 };
        let z_u = -2.0 * qs * cl0 / (mass * v * v);
        let z_alpha = -qs * (d.get(D::CLalpha) + drag_z) / (mass * v);
        let z_q = -qs * kc * cl_q / (mass * v);
        let z_ad = -qs * kc * cl_ad / (mass * v);
        let z_de = -qs * d.get(D::CLde) / (mass * v);

        let qsc_i = qs * g.chord_m / m.iyy_kg_m2;
        let m_alpha = qsc_i * d.get(D::Cmalpha);
        let m_q = qsc_i * kc * d.get(D::Cmq);
        let m_ad = qsc_i * kc * d.get(D::Cmalphadot);
        let m_de = qsc_i * d.get(D::Cmde);

        let gg = f.g_m_s2;
        let mut c = Mat::<f64>::identity(4, 4);
        c[(1, 1)] = 1.0 - z_ad;
        c[(2, 1)] = -m_ad;
        let rows = [
            [x_u, x_alpha, 0.0, -gg * gamma0.cos()],
            [z_u, z_alpha, 1.0 + z_q, -(gg / v) * gamma0.sin()],
            [0.0, m_alpha, m_q, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        let a_desc = Mat::from_fn(4, 4, |i, j| rows[i][j]);
        let bv = [x_de, z_de, m_de, 0.0];
        let b_desc = Mat::from_fn(4, 1, |i, _| bv[i]);
        Ok(LinearModel::from_descriptor(
            Axis::Longitudinal,
            c,
            a_desc,
            b_desc,
        ))
    }

    /// The lateral-directional submodel (states β, p, r, φ; inputs δa, δr).
    pub fn lateral(&self) -> Result<LinearModel, AeroError> {
        let (v, qs) = self.airspeed_and_qs()?;
        let (f, m, g) = (&self.flight, &self.mass, &self.geometry);
        let (d, a) = (&self.derivatives, &self.assumptions);
        let kb = g.span_m / (2.0 * v);
        let gamma0 = self.gamma0();
        let mass = m.mass_kg;

        let cy_beta = d.get(D::CYbeta)
            - if a.side_force_in_wind_axes {
                self.cd_trim()
            } else {
                0.0
            };
        let (cy_p, cy_r, cy_da) = if a.side_force_rate_terms {
            (d.get(D::CYp), d.get(D::CYr), d.get(D::CYda))
        } else {
            (0.0, 0.0, 0.0)
        };
        let y = qs / (mass * v);
        let l = qs * g.span_m / m.ixx_kg_m2;
        let n = qs * g.span_m / m.izz_kg_m2;
        let ixz = if a.ixz_coupling { m.ixz_kg_m2 } else { 0.0 };

        let mut c = Mat::<f64>::identity(4, 4);
        c[(1, 2)] = -ixz / m.ixx_kg_m2;
        c[(2, 1)] = -ixz / m.izz_kg_m2;
        let rows = [
            [
                y * cy_beta,
                y * kb * cy_p,
                y * kb * cy_r - 1.0,
                f.g_m_s2 * gamma0.cos() / v,
            ],
            [
                l * d.get(D::Clbeta),
                l * kb * d.get(D::Clp),
                l * kb * d.get(D::Clr),
                0.0,
            ],
            [
                n * d.get(D::Cnbeta),
                n * kb * d.get(D::Cnp),
                n * kb * d.get(D::Cnr),
                0.0,
            ],
            [0.0, 1.0, gamma0.tan(), 0.0],
        ];
        let a_desc = Mat::from_fn(4, 4, |i, j| rows[i][j]);
        let brows = [
            [y * cy_da, y * d.get(D::CYdr)],
            [l * d.get(D::Clda), l * d.get(D::Cldr)],
            [n * d.get(D::Cnda), n * d.get(D::Cndr)],
            [0.0, 0.0],
        ];
        let b_desc = Mat::from_fn(4, 2, |i, j| brows[i][j]);
        Ok(LinearModel::from_descriptor(
            Axis::Lateral,
            c,
            a_desc,
            b_desc,
        ))
    }

    /// The submodel for an axis.
    pub fn submodel(&self, axis: Axis) -> Result<LinearModel, AeroError> {
        match axis {
            Axis::Longitudinal => self.longitudinal(),
            Axis::Lateral => self.lateral(),
        }
    }

    /// One transfer function of the model.
    pub fn transfer_function(&self, which: TfOutput) -> Result<TfCoefficients, AeroError> {
        self.submodel(which.axis)?
            .transfer_function(which.state, which.input)
    }

    /// The paper's three transfer functions θ/δe, φ/δa, φ/δr (numerators of length 4, s³ coefficient 0).
    pub fn paper_transfer_functions(&self) -> Result<[(TfOutput, TfCoefficients); 3], AeroError> {
        Ok([
            (
                TfOutput::THETA_ELEVATOR,
                self.transfer_function(TfOutput::THETA_ELEVATOR)?,
            ),
            (
                TfOutput::PHI_AILERON,
                self.transfer_function(TfOutput::PHI_AILERON)?,
            ),
            (
                TfOutput::PHI_RUDDER,
                self.transfer_function(TfOutput::PHI_RUDDER)?,
            ),
        ])
    }
}

impl LinearModel {
    fn from_descriptor(axis: Axis, c: Mat<f64>, a_desc: Mat<f64>, b_desc: Mat<f64>) -> Self {
        let lu = c.partial_piv_lu();
        let a = lu.solve(&a_desc);
        let b = lu.solve(&b_desc);
        Self {
            axis,
            c_desc: c,
            a_desc,
            b_desc,
            a,
            b,
        }
    }

    /// Output `state` over input `input` (see the module doc).
    pub fn transfer_function(
        &self,
        state: usize,
        input: usize,
    ) -> Result<TfCoefficients, AeroError> {
        let n = self.a.nrows();
        if state >= n || input >= self.b.ncols() {
            return Err(AeroError::WrongTfOrder {
                tf: format!("state {state} / input {input}"),
                problem: format!(
                    "the {:?} model has {n} states and {} inputs",
                    self.axis,
                    self.b.ncols()
                ),
            });
        }
        let ss = StateSpace::new(
            self.a.clone(),
            self.b.clone(),
            Mat::from_fn(1, n, |_, j| if j == state { 1.0 } else { 0.0 }),
            Mat::zeros(1, self.b.ncols()),
        )
        .map_err(|_| AeroError::Numerical("state space of the derivative model"))?;
        let tf = ss2tf(&ss, input, 0);
        // keep the historical shape: n numerator coefficients (degree n − 1), leading zeros included
        let mut num = vec![0.0; n.saturating_sub(tf.num.len())];
        num.extend_from_slice(&tf.num);
        let den = tf.den;
        Ok(TfCoefficients { num, den })
    }

    /// Eigenvalues of A as (re, im) pairs.
    pub fn poles(&self) -> Result<Vec<(f64, f64)>, AeroError> {
        let ev = self
            .a
            .eigenvalues()
            .map_err(|_| AeroError::Numerical("eigenvalues of A"))?;
        Ok(ev.iter().map(|z| (z.re, z.im)).collect())
    }

    /// Modes (complex pairs once, real poles), sorted by decreasing |pole|.
    pub fn modes(&self) -> Result<Vec<Mode>, AeroError> {
        let mut poles = self.poles()?;
        poles.sort_by(|x, y| (y.0.hypot(y.1)).total_cmp(&x.0.hypot(x.1)));
        let mut out = Vec::new();
        for (re, im) in poles {
            let mag = re.hypot(im);
            if im.abs() <= 1e-9 * mag.max(1e-12) {
                out.push(Mode::Real { pole_1_s: re });
            } else if im > 0.0 {
                out.push(Mode::Oscillatory {
                    omega_n_rad_s: mag,
                    zeta: -re / mag,
                });
            }
        }
        Ok(out)
    }

    /// The fastest oscillatory mode (short period, Dutch roll), if any.
    pub fn fastest_oscillation(&self) -> Result<Option<(f64, f64)>, AeroError> {
        Ok(self
            .modes()?
            .into_iter()
            .filter_map(Mode::oscillation)
            .max_by(|a, b| a.0.total_cmp(&b.0)))
    }
}

#[cfg(test)]
#[path = "model_tests.rs"]
pub(crate) mod tests;
