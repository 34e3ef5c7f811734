//! Equation-error regression of aerodynamic coefficients on the full measured state (SIDPAC `lesq` style).
//!
//! Morelli & Klein, *Aircraft System Identification* (2nd ed.), §5.1–5.2 and §6.2: the aerodynamic force and
//! moment coefficients are reconstructed from the measured motion through the rigid-body equations, and
//! regressed on the measured states and controls by ordinary least squares,
//!
//! θ̂ = (XᵀX)⁻¹ Xᵀ z,   Cov(θ̂) = s² (XᵀX)⁻¹,   s² = vᵀv/(N − n_p),
//!
//! with the coloured-residual correction (Morelli & Klein eq. 5.73; Morelli, *J. Aircraft* 2005)
//! Cov(θ̂) = D [Σ_i Σ_j x(i) R_vv(i − j) x(j)ᵀ] D, D = (XᵀX)⁻¹, R_vv the residual autocorrelation estimate,
//! which is the honest uncertainty when the residuals are not white (they rarely are in flight data).
//!
//! Moment coefficients (body axes, Etkin & Reid eq. 4.7,5):
//! C_l = [I_xx ṗ − I_xz (ṙ + p q) + (I_zz − I_yy) q r] / (q̄ S b),
//! C_m = [I_yy q̇ + (I_xx − I_zz) p r + I_xz (p² − r²)] / (q̄ S c̄),
//! C_n = [I_zz ṙ − I_xz (ṗ − q r) + (I_yy − I_xx) p q] / (q̄ S b).
//! Force coefficients use the specific-force channels when present (Y/m = a_y, Z/m = a_z), otherwise the
//! body velocities u = V cos α cos β, v = V sin β, w = V sin α cos β differentiated numerically:
//! Y/m = v̇ + r u − p w − g cos θ sin φ, Z/m = ẇ + p v − q u − g cos θ cos φ. Lift is taken as
//! C_L = −Z/(q̄ S cos α), neglecting D tan α (thrust along body x makes X unusable without a thrust model).
//!
//! Time derivatives come from [`savitzky_golay_derivative`], a local polynomial fit (Savitzky & Golay 1964).
//! It lives here until `crate::signal` provides a differentiator; it assumes uniform sampling.

use faer::Mat;

use crate::estimate::covariance;
use crate::signal::{sum_sq, LeastSquares, LeastSquaresError};

use super::params::{Derivative, Geometry, MassProperties};
use super::AeroError;

mod held;
mod smoothing;
use held::kinematic_alphadot;
pub use held::{consider_held_terms, held_alphadot_note, CM_ALPHADOT_CONSIDER};
use smoothing::central_difference;
pub use smoothing::{savitzky_golay_derivative, savitzky_golay_smooth};

/// Measured time histories in SI units (radians), all the same length as `time_s`; absent channels `None`.
#[derive(Debug, Clone, Copy, Default)]
pub struct FlightRecord<'a> {
    /// Time, uniformly sampled.
    pub time_s: &'a [f64],
    /// Angle of attack.
    pub alpha_rad: Option<&'a [f64]>,
    /// Sideslip.
    pub beta_rad: Option<&'a [f64]>,
    /// Body roll rate.
    pub p_rad_s: Option<&'a [f64]>,
    /// Body pitch rate.
    pub q_rad_s: Option<&'a [f64]>,
    /// Body yaw rate.
    pub r_rad_s: Option<&'a [f64]>,
    /// Bank angle.
    pub phi_rad: Option<&'a [f64]>,
    /// Pitch attitude.
    pub theta_rad: Option<&'a [f64]>,
    /// True airspeed.
    pub airspeed_m_s: Option<&'a [f64]>,
    /// Elevator deflection.
    pub elevator_rad: Option<&'a [f64]>,
    /// Aileron deflection.
    pub aileron_rad: Option<&'a [f64]>,
    /// Rudder deflection.
    pub rudder_rad: Option<&'a [f64]>,
    /// Body lateral specific force at the CG.
    pub ay_m_s2: Option<&'a [f64]>,
    /// Body normal specific force at the CG (≈ −g in level flight).
    pub az_m_s2: Option<&'a [f64]>,
    /// Body axial specific force at the CG (used with `thrust_n` for the lift equation).
    pub ax_m_s2: Option<&'a [f64]>,
    /// Measured dynamic pressure; without it q̄ = ½ ρ V² with [`EquationErrorOptions::air_density_kg_m3`].
    pub qbar_pa: Option<&'a [f64]>,
    /// Total thrust along the thrust line ([`EquationErrorOptions::thrust_inclination_rad`]).
    pub thrust_n: Option<&'a [f64]>,
}

impl<'a> FlightRecord<'a> {
    /// The channels of a schema record (docs/data.md), borrowed by column name; absent columns `None`.
    pub fn from_columns(rec: &'a crate::data::FlightRecord) -> Self {
        let col = |c: &str| rec.column(c);
        Self {
            time_s: &rec.time_s,
            alpha_rad: col("alpha_rad"),
            beta_rad: col("beta_rad"),
            p_rad_s: col("p_rad_s"),
            q_rad_s: col("q_rad_s"),
            r_rad_s: col("r_rad_s"),
            phi_rad: col("phi_rad"),
            theta_rad: col("theta_rad"),
            airspeed_m_s: col("airspeed_m_s"),
            elevator_rad: col("elevator_rad"),
            aileron_rad: col("aileron_rad"),
            rudder_rad: col("rudder_rad"),
            ay_m_s2: col("ay_m_s2"),
            az_m_s2: col("az_m_s2"),
            ax_m_s2: col("ax_m_s2"),
            qbar_pa: col("qbar_pa"),
            thrust_n: col("thrust_n"),
        }
    }
}

/// Tuning of the equation-error regression.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquationErrorOptions {
    /// Savitzky–Golay half window, samples (window = 2 h + 1).
    pub half_window: usize,
    /// Savitzky–Golay polynomial order.
    pub poly_order: usize,
    /// Smooth every regressor with the differentiator's own polynomial fit, so that the differentiated
    /// outputs and the regressors see the same filter (otherwise fast surface motion biases the estimates).
    pub smooth_regressors: bool,
    /// Add α̇ c̄/(2V) as a C_m regressor, α̇ the differentiated α (separates C_mq from C_mα̇ only with rich,
    /// clean data).
    pub include_alphadot: bool,
    /// Without the α̇ regressor, keep its column in [`RegressionResult::considered`], so that
    /// [`consider_held_terms`] can carry the held C_mα̇'s physical range into the σ of the others. α̇ there
    /// from the flight-path kinematics ([`kinematic_alphadot`]) when a_x, a_z and θ are measured, else
    /// differentiated.
    pub consider_alphadot: bool,
    /// Residual autocorrelation lags used by the coloured-residual correction. `None`: up to the first
    /// zero crossing of the residual autocorrelation (summing all lags of an estimated autocorrelation of
    /// zero-mean residuals gives zero by construction, so the tail must be cut).
    pub max_lag: Option<usize>,
    /// Air density, assumed constant over the record.
    pub air_density_kg_m3: f64,
    /// Gravitational acceleration.
    pub g_m_s2: f64,
    /// Delay every regressor by half a sample ([`half_sample_lag`]) to match a response that lags by that
    /// much: on JSBSim records the rates are integrated before the aero model runs, so the central-difference
    /// derivative at row k is the mean of the moments at rows k−1 and k (measured on c172x: the C_m residual
    /// drops 7× with the shift). Real sensor data have no such lag: leave it off for them.
    pub response_lags_half_sample: bool,
    /// Thrust line vs body x, positive nose up (with a `thrust_n` channel).
    pub thrust_inclination_rad: f64,
    /// Pitching moment per newton of thrust, positive nose up (with a `thrust_n` channel).
    pub thrust_moment_arm_m: f64,
    /// With a `thrust_n` channel, add the propeller's torque reaction to the C_l regression: the term
    /// `Cl_T` · T/(q̄ S b), `Cl_T` the rolling moment per newton of thrust, m ([`PROPELLER_TORQUE`]).
    pub propeller_torque: bool,
}

/// The C_l term of the propeller's torque reaction, the rolling moment per newton of thrust in metres. A shaft
/// turning at Ω and absorbing the power P = T V/η reacts on the airframe with Q = P/Ω = T V/(η Ω) about the
/// thrust line (McCormick, *Aerodynamics, Aeronautics, and Flight Mechanics*, 2nd ed., ch. 6 and §8.4), so
/// at a given speed and propeller speed the torque follows the thrust: `Cl_T` ≈ −V/(η Ω) for a propeller
/// turning clockwise seen from behind. A constant-speed propeller's thrust moves with the airspeed and the
/// governor through a lateral maneuver (standard deviation 18 % of the mean on the JSBSim pc7 at 180 kts); left
/// out, the torque's share of the rolling moment put the pc7's C_lp 9 % and C_lδa 7 % short in a regression of
/// JSBSim's total rolling moment on the records' own states, and this one term, fitted at −0.51 m, brought them
/// back to JSBSim's aerodynamic ones exactly.
pub const PROPELLER_TORQUE: &str = "Cl_T";

impl EquationErrorOptions {
    /// Whether the regressors of this equation are delayed by half a sample: the moment equations (from
    /// differentiated body rates) when [`Self::response_lags_half_sample`] is set.
    pub fn lags_half_sample(&self, coefficient: &str) -> bool {
        self.response_lags_half_sample && matches!(coefficient, "Cm" | "Cl" | "Cn")
    }
}

/// `v'_k = ½ (v_{k−1} + v_k)` (`v'_0 = v_0`): the half-sample delay of a sampled signal, exact for the
/// trapezoidal mean that a central difference of rectangular-Euler-integrated states sees.
pub fn half_sample_lag(v: &[f64]) -> Vec<f64> {
    (0..v.len())
        .map(|k| 0.5 * (v[k.saturating_sub(1)] + v[k]))
        .collect()
}

impl Default for EquationErrorOptions {
    fn default() -> Self {
        Self {
            half_window: 5,
            poly_order: 2,
            smooth_regressors: true,
            include_alphadot: false,
            consider_alphadot: false,
            max_lag: None,
            air_density_kg_m3: 1.225,
            g_m_s2: 9.80665,
            response_lags_half_sample: false,
            thrust_inclination_rad: 0.0,
            thrust_moment_arm_m: 0.0,
            propeller_torque: false,
        }
    }
}

/// One estimated term of one coefficient equation.
#[derive(Debug, Clone, PartialEq)]
pub struct RegressionTerm {
    /// Term name, e.g. `Cm_alpha`, `Cm_0` for the bias.
    pub name: String,
    /// The model derivative it estimates, if the model has one.
    pub derivative: Option<Derivative>,
    /// Estimate.
    pub value: f64,
    /// Standard error s √((XᵀX)⁻¹)_kk, white residuals assumed.
    pub std_error: f64,
    /// Standard error with the coloured-residual correction.
    pub std_error_colored: f64,
}

/// The regression of one coefficient (C_m, C_l, …).
#[derive(Debug, Clone, PartialEq)]
pub struct RegressionResult {
    /// Which coefficient: `Cm`, `Cl`, `Cn`, `CY`, `CL`.
    pub coefficient: &'static str,
    /// The estimated terms.
    pub terms: Vec<RegressionTerm>,
    /// Coefficient of determination R².
    pub r_squared: f64,
    /// Fit error standard deviation s.
    pub fit_error_std: f64,
    /// The regressor columns X as used (smoothed when the options say so), in `terms` order.
    pub regressors: Vec<Vec<f64>>,
    /// The response z (the coefficient reconstructed from the motion).
    pub response: Vec<f64>,
    /// Terms held at 0 whose physical range the σ should carry: name and regressor column (filtered as the
    /// regressors are), in the rows of `response`.
    pub considered: Vec<(String, Vec<f64>)>,
}

impl RegressionResult {
    /// The term estimating a given derivative.
    pub fn term(&self, d: Derivative) -> Option<&RegressionTerm> {
        self.terms.iter().find(|t| t.derivative == Some(d))
    }
}

/// All coefficient regressions the record allows, and why the others were skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct EquationErrorResult {
    /// One regression per coefficient that could be formed.
    pub equations: Vec<RegressionResult>,
    /// (coefficient, reason) for those that could not.
    pub skipped: Vec<(&'static str, String)>,
}

impl EquationErrorResult {
    /// The term estimating a derivative, from whichever equation has it.
    pub fn term(&self, d: Derivative) -> Option<&RegressionTerm> {
        self.equations.iter().find_map(|e| e.term(d))
    }
}

fn channel<'a>(
    name: &str,
    ch: Option<&'a [f64]>,
    n: usize,
    equation: &str,
) -> Result<&'a [f64], String> {
    match ch {
        None => Err(format!("{equation} needs the `{name}` channel")),
        Some(c) if c.len() != n => Err(format!(
            "`{name}` has {} samples but `time_s` has {n}",
            c.len()
        )),
        Some(c) => Ok(c),
    }
}

/// What the regression does to a regressor column of `coefficient`'s equation: a non-constant one is smoothed
/// with the differentiator's fit (if the options say so) and delayed half a sample (if they say that).
pub fn regressor_filter(
    c: &[f64],
    coefficient: &str,
    options: &EquationErrorOptions,
) -> Result<Vec<f64>, AeroError> {
    if c.iter().all(|&v| v == c[0]) {
        return Ok(c.to_vec());
    }
    let s = if options.smooth_regressors {
        savitzky_golay_smooth(c, options.half_window, options.poly_order)?
    } else {
        c.to_vec()
    };
    Ok(if options.lags_half_sample(coefficient) {
        half_sample_lag(&s)
    } else {
        s
    })
}

/// [`lesq`] after smoothing every non-constant regressor with the differentiator's fit, if asked.
fn lesq_smoothed(
    coefficient: &'static str,
    names: &[String],
    columns: &[Vec<f64>],
    z: &[f64],
    options: &EquationErrorOptions,
) -> Result<RegressionResult, AeroError> {
    let smoothed = columns
        .iter()
        .map(|c| regressor_filter(c, coefficient, options))
        .collect::<Result<Vec<_>, _>>()?;
    lesq(coefficient, names, &smoothed, z, options.max_lag)
}

/// Least squares with white and coloured-residual standard errors (module doc); `columns` as given (no smoothing).
pub(crate) fn lesq(
    coefficient: &'static str,
    names: &[String],
    columns: &[Vec<f64>],
    z: &[f64],
    max_lag: Option<usize>,
) -> Result<RegressionResult, AeroError> {
    let n = z.len();
    let p = columns.len();
    let ls = LeastSquares::fit(columns, z).map_err(|e| match e {
        LeastSquaresError::TooFewSamples { .. } => AeroError::BadRecord(format!(
            "{coefficient}: {n} samples cannot determine {p} parameters"
        )),
        LeastSquaresError::Collinear { condition } => AeroError::BadRecord(format!(
            "{coefficient}: regressors are collinear (condition {condition:.1e}); the manoeuvre does not \
             excite them independently"
        )),
        LeastSquaresError::Decomposition => AeroError::Numerical("SVD of the regressor matrix"),
    })?;
    let (theta, resid, d) = (&ls.theta, &ls.residual, &ls.inverse_normal);
    let sse = sum_sq(resid);
    let s2 = ls.fit_variance();
    let mean = z.iter().sum::<f64>() / n as f64;
    let sst: f64 = z.iter().map(|v| (v - mean).powi(2)).sum();
    // Coloured residuals: M = Σ_i Σ_j x(i) R(|i−j|) x(j)ᵀ over the lags up to the first where the
    // residual autocorrelation is no longer positive (or `max_lag`), unweighted; summed by the
    // estimation core's FFT products.
    let acf = covariance::autocorrelation(resid, max_lag.map_or(n - 1, |l| l.min(n - 1)));
    let lags = match max_lag {
        Some(l) => l.min(n - 1),
        None => (1..n).find(|&k| acf[k] <= 0.0).unwrap_or(n - 1),
    };
    let cols: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
    let w = covariance::lag_weighted_products(&cols, &acf[..=lags]);
    let m = Mat::from_fn(p, p, |a, b| w[a * p + b]);
    let cov_c = d * &m * d;
    let terms = names
        .iter()
        .enumerate()
        .map(|(k, name)| RegressionTerm {
            name: name.clone(),
            derivative: name.parse().ok(),
            value: theta[k],
            std_error: (s2 * d[(k, k)]).sqrt(),
            std_error_colored: cov_c[(k, k)].max(0.0).sqrt(),
        })
        .collect();
    Ok(RegressionResult {
        coefficient,
        terms,
        r_squared: if sst > 0.0 { 1.0 - sse / sst } else { f64::NAN },
        fit_error_std: s2.sqrt(),
        regressors: columns.to_vec(),
        response: z.to_vec(),
        considered: Vec::new(),
    })
}

/// Estimate C_m, C_l, C_n, C_Y and C_L derivatives by equation-error regression (module doc).
///
/// Each equation is formed when its channels exist; the others are listed in `skipped` with the channel
/// they lack. Errors only when no equation can be formed or the record itself is unusable.
pub fn equation_error(
    record: &FlightRecord<'_>,
    mass: &MassProperties,
    geometry: &Geometry,
    options: &EquationErrorOptions,
) -> Result<EquationErrorResult, AeroError> {
    mass.validate()?;
    geometry.validate()?;
    let t = record.time_s;
    let n = t.len();
    if n < 2 * options.half_window + 2 {
        return Err(AeroError::BadRecord(format!("only {n} samples")));
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    if dt.is_nan() || dt <= 0.0 || t.windows(2).any(|w| ((w[1] - w[0]) - dt).abs() > 0.01 * dt) {
        return Err(AeroError::BadRecord(
            "time_s must be strictly increasing and uniformly sampled (resample first)".into(),
        ));
    }
    // With smoothed regressors the rates are smoothed by the same fit and then differentiated by a
    // 4th-order central difference, so that z = D(S y) = S(ẏ) sees exactly the filter S of the regressors
    // (LTI filters commute); otherwise the Savitzky–Golay derivative is used directly.
    let diff = |y: &[f64]| -> Result<Vec<f64>, AeroError> {
        if options.smooth_regressors {
            let smooth = savitzky_golay_smooth(y, options.half_window, options.poly_order)?;
            Ok(central_difference(&smooth, dt))
        } else {
            savitzky_golay_derivative(y, dt, options.half_window, options.poly_order)
        }
    };
    let zeros = vec![0.0; n];
    let ones = vec![1.0; n];
    let rho = options.air_density_kg_m3;
    let (s_ref, b, c) = (geometry.wing_area_m2, geometry.span_m, geometry.chord_m);
    let (ixx, iyy, izz, ixz) = (
        mass.ixx_kg_m2,
        mass.iyy_kg_m2,
        mass.izz_kg_m2,
        mass.ixz_kg_m2,
    );
    let mut equations = Vec::new();
    let mut skipped = Vec::new();

    // Shared channels (missing ones are reported per equation).
    let v_ch = record.airspeed_m_s;
    let measured_qbar = record.qbar_pa.filter(|x| x.len() == n);
    let qbar = |v: &[f64]| -> Vec<f64> {
        match measured_qbar {
            Some(q) => q.to_vec(),
            None => v.iter().map(|v| 0.5 * rho * v * v).collect(),
        }
    };
    // Thrust (measured or from an engine model) acts along its line: its moment leaves the aerodynamic
    // pitching moment, its x and z components the aerodynamic forces.
    let thrust = record.thrust_n.filter(|x| x.len() == n);
    let thrust_moment = |i: usize| thrust.map_or(0.0, |t| t[i] * options.thrust_moment_arm_m);

    // The channels each axis's equations regress on (a missing one skips the equation).
    let longitudinal_channels = |eq: &str| -> Result<[&[f64]; 4], String> {
        Ok([
            channel("airspeed_m_s", v_ch, n, eq)?,
            channel("alpha_rad", record.alpha_rad, n, eq)?,
            channel("q_rad_s", record.q_rad_s, n, eq)?,
            channel("elevator_rad", record.elevator_rad, n, eq)?,
        ])
    };
    let lateral_channels = |eq: &str| -> Result<[&[f64]; 6], String> {
        Ok([
            channel("airspeed_m_s", v_ch, n, eq)?,
            channel("beta_rad", record.beta_rad, n, eq)?,
            channel("p_rad_s", record.p_rad_s, n, eq)?,
            channel("r_rad_s", record.r_rad_s, n, eq)?,
            channel("aileron_rad", record.aileron_rad, n, eq)?,
            channel("rudder_rad", record.rudder_rad, n, eq)?,
        ])
    };

    // ---- C_m
    let cm = (|| -> Outcome {
        let eq = "Cm";
        let [v, alpha, q, de] = longitudinal_channels(eq)?;
        let p = record.p_rad_s.filter(|x| x.len() == n).unwrap_or(&zeros);
        let r = record.r_rad_s.filter(|x| x.len() == n).unwrap_or(&zeros);
        Ok((|| {
            let qdot = diff(q)?;
            let qb = qbar(v);
            let z: Vec<f64> = (0..n)
                .map(|i| {
                    (iyy * qdot[i] + (ixx - izz) * p[i] * r[i] + ixz * (p[i] * p[i] - r[i] * r[i])
                        - thrust_moment(i))
                        / (qb[i] * s_ref * c)
                })
                .collect();
            let qhat: Vec<f64> = (0..n).map(|i| q[i] * c / (2.0 * v[i])).collect();
            let mut names = vec!["Cm_0", "Cm_alpha", "Cm_q", "Cm_de"];
            let mut cols = vec![ones.clone(), alpha.to_vec(), qhat, de.to_vec()];
            let scaled = |adot: Vec<f64>| -> Vec<f64> {
                (0..n).map(|i| adot[i] * c / (2.0 * v[i])).collect()
            };
            if options.include_alphadot {
                names.push("Cm_alphadot");
                cols.push(scaled(diff(alpha)?));
            }
            let names: Vec<String> = names.into_iter().map(String::from).collect();
            let mut res = lesq_smoothed("Cm", &names, &cols, &z, options)?;
            if options.consider_alphadot && !options.include_alphadot {
                let adot = match kinematic_alphadot(record, v, alpha, q, options.g_m_s2) {
                    Some(adot) => adot,
                    None => diff(alpha)?,
                };
                let column = regressor_filter(&scaled(adot), "Cm", options)?;
                res.considered.push(("Cm_alphadot".to_string(), column));
            }
            Ok(res)
        })())
    })();
    file_outcome("Cm", cm, &mut equations, &mut skipped)?;

    // ---- C_l and C_n
    for eq in ["Cl", "Cn"] {
        let res = (|| -> Outcome {
            let [v, beta, p, r, da, dr] = lateral_channels(eq)?;
            let q = record.q_rad_s.filter(|x| x.len() == n).unwrap_or(&zeros);
            Ok((|| {
                let pdot = diff(p)?;
                let rdot = diff(r)?;
                let qb = qbar(v);
                let z: Vec<f64> = (0..n)
                    .map(|i| {
                        let moment = if eq == "Cl" {
                            ixx * pdot[i] - ixz * (rdot[i] + p[i] * q[i])
                                + (izz - iyy) * q[i] * r[i]
                        } else {
                            izz * rdot[i] - ixz * (pdot[i] - q[i] * r[i])
                                + (iyy - ixx) * p[i] * q[i]
                        };
                        moment / (qb[i] * s_ref * b)
                    })
                    .collect();
                let torque = thrust.filter(|_| eq == "Cl" && options.propeller_torque);
                let torque = torque.map(|t| (0..n).map(|i| t[i] / (qb[i] * s_ref * b)).collect());
                lateral_regression(eq, v, beta, p, r, da, dr, b, &z, torque, options)
            })())
        })();
        file_outcome(eq, res, &mut equations, &mut skipped)?;
    }

    // Body velocities for the force equations.
    let body_velocities = |v: &[f64], alpha: &[f64], beta: &[f64]| {
        let u: Vec<f64> = (0..n)
            .map(|i| v[i] * alpha[i].cos() * beta[i].cos())
            .collect();
        let vv: Vec<f64> = (0..n).map(|i| v[i] * beta[i].sin()).collect();
        let w: Vec<f64> = (0..n)
            .map(|i| v[i] * alpha[i].sin() * beta[i].cos())
            .collect();
        (u, vv, w)
    };
    let g = options.g_m_s2;

    // ---- C_Y
    let cy = (|| -> Outcome {
        let eq = "CY";
        let [v, beta, p, r, da, dr] = lateral_channels(eq)?;
        let specific: Vec<f64> = match record.ay_m_s2.filter(|x| x.len() == n) {
            Some(ay) => ay.to_vec(),
            None => {
                let alpha = channel("alpha_rad (or ay_m_s2)", record.alpha_rad, n, eq)?;
                let phi = channel("phi_rad (or ay_m_s2)", record.phi_rad, n, eq)?;
                let theta = channel("theta_rad (or ay_m_s2)", record.theta_rad, n, eq)?;
                let (u, vv, w) = body_velocities(v, alpha, beta);
                match diff(&vv) {
                    Ok(vdot) => (0..n)
                        .map(|i| {
                            vdot[i] + r[i] * u[i] - p[i] * w[i] - g * theta[i].cos() * phi[i].sin()
                        })
                        .collect(),
                    Err(e) => return Ok(Err(e)),
                }
            }
        };
        let qb = qbar(v);
        let z: Vec<f64> = (0..n)
            .map(|i| mass.mass_kg * specific[i] / (qb[i] * s_ref))
            .collect();
        Ok(lateral_regression(
            "CY", v, beta, p, r, da, dr, b, &z, None, options,
        ))
    })();
    file_outcome("CY", cy, &mut equations, &mut skipped)?;

    // ---- C_L
    let cl = (|| -> Outcome {
        let eq = "CL";
        let [v, alpha, q, de] = longitudinal_channels(eq)?;
        let specific: Vec<f64> = match record.az_m_s2.filter(|x| x.len() == n) {
            Some(az) => az.to_vec(),
            None => {
                let theta = channel("theta_rad (or az_m_s2)", record.theta_rad, n, eq)?;
                let beta = record.beta_rad.filter(|x| x.len() == n).unwrap_or(&zeros);
                let phi = record.phi_rad.filter(|x| x.len() == n).unwrap_or(&zeros);
                let p = record.p_rad_s.filter(|x| x.len() == n).unwrap_or(&zeros);
                let (u, vv, w) = body_velocities(v, alpha, beta);
                match diff(&w) {
                    Ok(wdot) => (0..n)
                        .map(|i| {
                            wdot[i] + p[i] * vv[i] - q[i] * u[i] - g * theta[i].cos() * phi[i].cos()
                        })
                        .collect(),
                    Err(e) => return Ok(Err(e)),
                }
            }
        };
        let qb = qbar(v);
        let (sin_e, cos_e) = options.thrust_inclination_rad.sin_cos();
        let ax = record.ax_m_s2.filter(|x| x.len() == n);
        let z: Vec<f64> = match (thrust, ax) {
            // Lift from both body forces once thrust is taken out: C_L = (−Z cos α + X sin α)/(q̄S).
            (Some(t), Some(ax)) => (0..n)
                .map(|i| {
                    let z_aero = mass.mass_kg * specific[i] + t[i] * sin_e;
                    let x_aero = mass.mass_kg * ax[i] - t[i] * cos_e;
                    (-z_aero * alpha[i].cos() + x_aero * alpha[i].sin()) / (qb[i] * s_ref)
                })
                .collect(),
            _ => (0..n)
                .map(|i| {
                    let z_aero = mass.mass_kg * specific[i] + thrust.map_or(0.0, |t| t[i] * sin_e);
                    -z_aero / (qb[i] * s_ref * alpha[i].cos())
                })
                .collect(),
        };
        let qhat: Vec<f64> = (0..n).map(|i| q[i] * c / (2.0 * v[i])).collect();
        let names: Vec<String> = ["CL_0", "CL_alpha", "CL_q", "CL_de"]
            .map(String::from)
            .to_vec();
        Ok(lesq_smoothed(
            "CL",
            &names,
            &[ones.clone(), alpha.to_vec(), qhat, de.to_vec()],
            &z,
            options,
        ))
    })();
    file_outcome("CL", cl, &mut equations, &mut skipped)?;

    if equations.is_empty() {
        return Err(AeroError::BadRecord(format!(
            "no coefficient equation can be formed: {}",
            skipped
                .iter()
                .map(|(_, w)| w.as_str())
                .collect::<Vec<_>>()
                .join("; ")
        )));
    }
    Ok(EquationErrorResult { equations, skipped })
}

/// How one coefficient equation ended: its regression (or the regression's error), or the missing channel
/// that kept it from being formed.
type Outcome = Result<Result<RegressionResult, AeroError>, String>;

/// Files one equation's [`Outcome`]: a regression into `equations`; a missing channel or collinear regressors
/// (a flight that does not excite this axis) into `skipped`, not fatal; any other error ends the regression.
fn file_outcome(
    eq: &'static str,
    outcome: Outcome,
    equations: &mut Vec<RegressionResult>,
    skipped: &mut Vec<(&'static str, String)>,
) -> Result<(), AeroError> {
    match outcome {
        Ok(Ok(res)) => equations.push(res),
        Ok(Err(AeroError::BadRecord(why))) | Err(why) => skipped.push((eq, why)),
        Ok(Err(e)) => return Err(e),
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn lateral_regression(
    coefficient: &'static str,
    v: &[f64],
    beta: &[f64],
    p: &[f64],
    r: &[f64],
    da: &[f64],
    dr: &[f64],
    span_m: f64,
    z: &[f64],
    torque: Option<Vec<f64>>,
    options: &EquationErrorOptions,
) -> Result<RegressionResult, AeroError> {
    let n = z.len();
    let phat: Vec<f64> = (0..n).map(|i| p[i] * span_m / (2.0 * v[i])).collect();
    let rhat: Vec<f64> = (0..n).map(|i| r[i] * span_m / (2.0 * v[i])).collect();
    let names: Vec<String> = ["0", "beta", "p", "r", "da", "dr"]
        .iter()
        .map(|s| format!("{coefficient}_{s}"))
        .collect();
    let mut names = names;
    let mut cols = vec![
        vec![1.0; n],
        beta.to_vec(),
        phat,
        rhat,
        da.to_vec(),
        dr.to_vec(),
    ];
    if let Some(t) = torque {
        names.push(PROPELLER_TORQUE.to_string());
        cols.push(t);
    }
    // A surface that never moves (a single-surface manoeuvre) is a copy of the bias column: leave it out
    // rather than losing the whole equation to collinearity.
    let moves = |c: &[f64]| c.iter().any(|x| *x != c[0]);
    let (names, cols): (Vec<String>, Vec<Vec<f64>>) = names
        .into_iter()
        .zip(cols)
        .enumerate()
        .filter(|(k, (_, c))| *k < 4 || moves(c))
        .map(|(_, nc)| nc)
        .unzip();
    lesq_smoothed(coefficient, &names, &cols, z, options)
}

#[cfg(test)]
#[path = "regression_tests.rs"]
mod tests;
