//! Data compatibility check by flight-path reconstruction (SIDPAC `dcmp`; Klein & Morelli,
//! *Aircraft System Identification*, AIAA 2006, ch. 10).
//!
//! The measured body rates and specific forces drive the rigid-body kinematic equations (flat
//! earth, body axes; Klein & Morelli eq. 10.1–10.3):
//!
//! ```text
//! u̇ = r v − q w − g sinθ + ax          φ̇ = p + tanθ (q sinφ + r cosφ)
//! v̇ = p w − r u + g cosθ sinφ + ay     θ̇ = q cosφ − r sinφ
//! ẇ = q u − p v + g cosθ cosφ + az     ψ̇ = (q sinφ + r cosφ) / cosθ
//! ```
//!
//! with `p = p_m − b_p`, …, `ax = ax_m − b_ax`, … (instrument biases). The reconstructed outputs
//! `V = |(u,v,w)|`, `α = atan2(w, u)`, `β = asin(v/V)`, φ, θ, ψ are compared with the measured
//! ones through the output model `y_m(t) = (1 + s) · y(t − τ) + b` (scale factor s, time skew τ,
//! bias b, for V, α and β). Biases, scale factors, skews and the initial state are estimated by
//! output-error Gauss–Newton (Levenberg–Marquardt damped) with the residual covariance re-estimated
//! every iteration (Klein & Morelli §6.2, eq. 6.51–6.56). Standard errors are Cramér–Rao bounds
//! corrected for coloured residuals (Morelli & Klein, "Accounting for the effects of colored
//! residuals", J. Aircraft 1997; Klein & Morelli §6.5): `Cov = M⁻¹ S M⁻¹` with
//! `M = Σ Jᵀ R⁻¹ J` and `S` built from the residual autocorrelation up to a 2 s lag. The plain
//! bound `M⁻¹` (white residuals) is optimistic by factors of 2–5 on flight data.
//!
//! Integration: classical Runge–Kutta 4 over each sample interval, measured inputs linear in time.

use serde::Serialize;

use super::error::DataError;
use super::record::{FlightRecord, G0_M_S2};
use crate::optimise;
use faer::Mat;

/// Options of [`check_compatibility`].
#[derive(Debug, Clone)]
pub struct CheckOptions {
    /// Also estimate scale factors on V, α and β.
    pub scale_factors: bool,
    /// Also estimate time skews on α and β.
    pub time_skews: bool,
    /// Gauss–Newton iteration limit.
    pub max_iterations: usize,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            scale_factors: true,
            time_skews: true,
            max_iterations: 50,
        }
    }
}

/// One estimated quantity.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// Parameter name, e.g. `bias_q_rad_s`, `skew_alpha_s`, `scale_alpha`.
    pub name: String,
    /// The column it applies to.
    pub column: String,
    /// Estimated value (units in the name).
    pub value: f64,
    /// Cramér–Rao standard error.
    pub std_error: f64,
    /// |value| > 3 standard errors and above the practical floor for its kind.
    pub significant: bool,
}

/// Result of [`check_compatibility`].
#[derive(Debug, Clone, Serialize)]
pub struct CheckReport {
    /// Instrument errors: biases, scale factors, time skews.
    pub instrument: Vec<Estimate>,
    /// Estimated initial state (u, v, w in m/s, φ, θ, ψ in rad).
    pub initial_state: Vec<Estimate>,
    /// RMS of the output residuals after the fit, per measured column.
    pub residual_rms: Vec<(String, f64)>,
    /// Gauss–Newton iterations used.
    pub iterations: usize,
    /// Whether the relative cost change fell below 1e-9.
    pub converged: bool,
    /// True when accelerations and air data were present and the translational part was checked.
    pub translational: bool,
    /// Parameters dropped because the data cannot determine them (e.g. a β scale with β ≈ 0).
    pub not_identifiable: Vec<String>,
    /// Scale factors and time skews not estimated because the maneuver does not move their signal
    /// (e.g. β on a longitudinal-only record), each with the evidence.
    pub not_excited: Vec<String>,
}

/// How clearly an air-data signal must move beyond its own noise before a scale factor or a time skew on it
/// is estimated: its variance about the mean must exceed the noise variance (from
/// [`crate::signal::noise_std`]) by this many standard errors of a variance estimate over n samples
/// (σ²·√(2/n)). Below that, the factor times the signal is indistinguishable from a bias plus noise, and a
/// "significant" scale factor on an axis the maneuver does not move is an artefact (Klein & Morelli §10.3: a
/// parameter is identified only through the excitation of the signal it multiplies).
const EXCITATION_Z: f64 = 5.0;

/// Smallest movement that counts at all, rms in the signal's unit (noise-free records): 0.05 m/s for V,
/// 0.05° for α and β.
fn excitation_floor(output: usize) -> f64 {
    if output == 0 {
        0.05
    } else {
        0.05_f64.to_radians()
    }
}

/// Root-mean-square deviation from the mean.
fn rms_about_mean(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt()
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Param {
    GyroBias(usize),
    AccelBias(usize),
    OutBias(usize),
    OutScale(usize),
    OutSkew(usize),
    Init(usize),
}

/// Output indices: V, α, β, φ, θ, ψ.
const OUT_NAMES: [&str; 6] = [
    "airspeed_m_s",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
];
const GYRO: [&str; 3] = ["p_rad_s", "q_rad_s", "r_rad_s"];
const ACCEL: [&str; 3] = ["ax_m_s2", "ay_m_s2", "az_m_s2"];
const STATE_NAMES: [&str; 6] = ["u_m_s", "v_m_s", "w_m_s", "phi_rad", "theta_rad", "psi_rad"];

impl Param {
    fn name(self) -> (String, String) {
        match self {
            Param::GyroBias(i) => (format!("bias_{}", GYRO[i]), GYRO[i].into()),
            Param::AccelBias(i) => (format!("bias_{}", ACCEL[i]), ACCEL[i].into()),
            Param::OutBias(j) => (format!("bias_{}", OUT_NAMES[j]), OUT_NAMES[j].into()),
            Param::OutScale(j) => (
                format!("scale_{}", OUT_NAMES[j].split('_').next().unwrap_or("")),
                OUT_NAMES[j].into(),
            ),
            Param::OutSkew(j) => (
                format!("skew_{}_s", OUT_NAMES[j].split('_').next().unwrap_or("")),
                OUT_NAMES[j].into(),
            ),
            Param::Init(k) => (format!("initial_{}", STATE_NAMES[k]), STATE_NAMES[k].into()),
        }
    }

    /// Finite-difference step and practical significance floor.
    fn step_and_floor(self) -> (f64, f64) {
        match self {
            // 0.05 °/s: below the resolution a flight-test engineer acts on.
            Param::GyroBias(_) => (1e-6, 0.05_f64.to_radians()),
            Param::AccelBias(_) => (1e-5, 0.02),
            Param::OutBias(0) => (1e-5, 0.1),
            Param::OutBias(_) => (1e-7, 0.1_f64.to_radians()),
            Param::OutScale(_) => (1e-6, 0.01),
            Param::OutSkew(_) => (1e-4, 0.01),
            Param::Init(k) if k < 3 => (1e-5, 0.0),
            Param::Init(_) => (1e-7, 0.0),
        }
    }
}

/// Measured data laid out for the reconstruction.
struct Data {
    t: Vec<f64>,
    gyro: [Vec<f64>; 3],
    accel: Option<[Vec<f64>; 3]>,
    /// Measured outputs; `None` when the column is absent.
    out: [Option<Vec<f64>>; 6],
}

/// Checks the kinematic consistency of a record and estimates instrument errors.
///
/// Needs `p_rad_s q_rad_s r_rad_s phi_rad theta_rad`; with `ax/ay/az_m_s2`, `airspeed_m_s`,
/// `alpha_rad` and `beta_rad` present the translational part (accelerometer biases, air-data
/// errors) is checked too. Use a maneuver segment of some tens of seconds: accelerometer
/// integration drifts over long spans.
pub fn check_compatibility(
    rec: &FlightRecord,
    opts: &CheckOptions,
) -> Result<CheckReport, DataError> {
    rec.validate()?;
    let why = "for flight-path reconstruction (rates drive the attitude kinematics)";
    let gyro = [
        rec.require("p_rad_s", why)?.to_vec(),
        rec.require("q_rad_s", why)?.to_vec(),
        rec.require("r_rad_s", why)?.to_vec(),
    ];
    let phi = rec.require("phi_rad", "as the attitude reference of the check")?;
    let theta = rec.require("theta_rad", "as the attitude reference of the check")?;
    if rec.len() < 20 {
        return Err(DataError::InvalidArgument(format!(
            "the compatibility check needs at least 20 samples, got {}",
            rec.len()
        )));
    }
    let accel = match (
        rec.column("ax_m_s2"),
        rec.column("ay_m_s2"),
        rec.column("az_m_s2"),
    ) {
        (Some(a), Some(b), Some(c)) => Some([a.to_vec(), b.to_vec(), c.to_vec()]),
        _ => None,
    };
    let air = ["airspeed_m_s", "alpha_rad", "beta_rad"].map(|n| rec.column(n).map(<[f64]>::to_vec));
    let translational = accel.is_some() && air.iter().all(Option::is_some);
    let psi = rec.column("psi_rad").map(crate::signal::unwrap_rad);
    let [v_m, a_m, b_m] = air;
    let out: [Option<Vec<f64>>; 6] = if translational {
        [v_m, a_m, b_m, Some(phi.to_vec()), Some(theta.to_vec()), psi]
    } else {
        [
            None,
            None,
            None,
            Some(phi.to_vec()),
            Some(theta.to_vec()),
            psi,
        ]
    };
    let data = Data {
        t: rec.time_s.clone(),
        gyro,
        accel: if translational { accel } else { None },
        out,
    };

    // Parameter set.
    let mut params: Vec<Param> = (0..3).map(Param::GyroBias).collect();
    let mut not_excited = Vec::new();
    if translational {
        params.extend((0..3).map(Param::AccelBias));
        params.extend([Param::OutBias(1), Param::OutBias(2)]);
        // Scale factors and skews only on what the maneuver moves.
        let mut wanted = Vec::new();
        if opts.time_skews {
            wanted.extend([Param::OutSkew(1), Param::OutSkew(2)]);
        }
        if opts.scale_factors {
            wanted.extend([Param::OutScale(0), Param::OutScale(1), Param::OutScale(2)]);
        }
        for p in wanted {
            let (Param::OutSkew(j) | Param::OutScale(j)) = p else {
                continue;
            };
            let signal = data.out[j].as_deref().unwrap_or(&[]);
            let moved = rms_about_mean(signal);
            let noise = crate::signal::noise_std(signal);
            let n = signal.len().max(1) as f64;
            let z =
                (moved * moved - noise * noise) / (noise * noise * (2.0 / n).sqrt()).max(1e-300);
            if moved >= excitation_floor(j) && z > EXCITATION_Z {
                params.push(p);
            } else {
                let k = if j == 0 { 1.0 } else { 1f64.to_degrees() };
                let unit = if j == 0 { "m/s" } else { "°" };
                not_excited.push(format!(
                    "{}: {} moves {:.3} {unit} rms against a noise of {:.3} {unit}, not clearly beyond it \
                     (variance excess z = {z:.1}, needs more than {EXCITATION_Z} and at least {:.2} {unit} rms)",
                    p.name().0,
                    OUT_NAMES[j],
                    moved * k,
                    noise * k,
                    excitation_floor(j) * k                ));
            }
        }
        params.extend((0..3).map(Param::Init));
    }
    params.extend((3..6).filter(|&k| data.out[k].is_some()).map(Param::Init));

    // Initial guess: zero instrument errors, initial state from the first measurements.
    let mut theta_p: Vec<f64> = params
        .iter()
        .map(|p| match *p {
            Param::Init(k) if k < 3 => {
                let v = data.out[0].as_ref().map_or(0.0, |x| x[0]);
                let a = data.out[1].as_ref().map_or(0.0, |x| x[0]);
                let b = data.out[2].as_ref().map_or(0.0, |x| x[0]);
                [v * a.cos() * b.cos(), v * b.sin(), v * a.sin() * b.cos()][k]
            }
            Param::Init(k) => data.out[k].as_ref().map_or(0.0, |x| x[0]),
            _ => 0.0,
        })
        .collect();

    let n = data.t.len();
    // Stage 1: attitude kinematics only (gyro biases, initial attitude) — a good start for the
    // translational fit, whose cost surface has poor local minima far from the solution.
    if translational {
        let att_data = Data {
            t: data.t.clone(),
            gyro: data.gyro.clone(),
            accel: None,
            out: [
                None,
                None,
                None,
                data.out[3].clone(),
                data.out[4].clone(),
                data.out[5].clone(),
            ],
        };
        let att_params: Vec<Param> = params
            .iter()
            .copied()
            .filter(|p| matches!(p, Param::GyroBias(_)) || matches!(p, Param::Init(k) if *k >= 3))
            .collect();
        let start: Vec<f64> = att_params
            .iter()
            .map(|p| theta_p[params.iter().position(|q| q == p).unwrap_or(0)])
            .collect();
        let stage1 = fit(&att_data, &att_params, start, opts.max_iterations);
        for (p, v) in att_params.iter().zip(&stage1.theta) {
            if let Some(k) = params.iter().position(|q| q == p) {
                theta_p[k] = *v;
            }
        }
    }
    let mut result = fit(&data, &params, theta_p.clone(), opts.max_iterations);
    // Parameters the data cannot determine (e.g. a β scale factor when β never moves) are fixed
    // at zero and the fit repeated without them.
    let mut not_identifiable = Vec::new();
    let np = params.len();
    let cov = invert(&result.fisher, np).unwrap_or_else(|| vec![f64::NAN; np * np]);
    let keep: Vec<bool> = params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let se = cov[k * np + k].sqrt();
            let (_, floor) = p.step_and_floor();
            // NaN standard errors (singular information) count as not identifiable.
            floor <= 0.0 || se.partial_cmp(&(10.0 * floor)) == Some(std::cmp::Ordering::Less)
        })
        .collect();
    if keep.iter().any(|k| !k) {
        let mut kept_params = Vec::new();
        let mut start = Vec::new();
        for (k, p) in params.iter().enumerate() {
            if keep[k] {
                kept_params.push(*p);
                start.push(if matches!(p, Param::Init(_) | Param::GyroBias(_)) {
                    theta_p[k]
                } else {
                    0.0
                });
            } else {
                not_identifiable.push(p.name().0);
            }
        }
        params = kept_params;
        result = fit(&data, &params, start, opts.max_iterations);
    }
    let theta_p = result.theta.clone();
    let fisher = result.fisher.clone();
    let r = result.residuals.clone();
    let (iterations, converged) = (result.iterations, result.converged);
    let outputs: Vec<usize> = (0..6).filter(|&j| data.out[j].is_some()).collect();
    let np = params.len();
    // Cramér–Rao bounds at the solution, corrected for coloured residuals.
    let cov = match invert(&fisher, np) {
        Some(m_inv) => {
            let j = jacobian(&data, &params, &theta_p, &outputs, &r);
            coloured_residual_covariance(&m_inv, &j, &r, np, data.t.len())
        }
        None => vec![f64::NAN; np * np],
    };
    let mut instrument = Vec::new();
    let mut initial_state = Vec::new();
    for (k, p) in params.iter().enumerate() {
        let (name, column) = p.name();
        let se = cov[k * np + k].max(0.0).sqrt();
        let (_, floor) = p.step_and_floor();
        let value = theta_p[k];
        let est = Estimate {
            name,
            column,
            value,
            std_error: se,
            significant: value.abs() > 3.0 * se && value.abs() > floor,
        };
        match p {
            Param::Init(_) => initial_state.push(Estimate {
                significant: false,
                ..est
            }),
            _ => instrument.push(est),
        }
    }
    let residual_rms = outputs
        .iter()
        .zip(&r)
        .map(|(&j, rj)| {
            (
                OUT_NAMES[j].to_string(),
                (rj.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt(),
            )
        })
        .collect();
    Ok(CheckReport {
        instrument,
        initial_state,
        residual_rms,
        iterations,
        converged,
        translational,
        not_identifiable,
        not_excited,
    })
}

/// `M⁻¹ S M⁻¹`, `S_ab = Σ_o Σ_k Σ_l J_a[o][k] ρ_o(l) J_b[o][k+l] / σ_o⁴`, with ρ_o the biased
/// residual autocovariance of output o for |l| ≤ 2 s (Morelli & Klein 1997, eq. 20).
fn coloured_residual_covariance(
    m_inv: &[f64],
    j: &[Vec<Vec<f64>>],
    r: &[Vec<f64>],
    np: usize,
    n: usize,
) -> Vec<f64> {
    let max_lag = (n / 4).min(100);
    let mut s = vec![0.0; np * np];
    for (o, ro) in r.iter().enumerate() {
        let rho: Vec<f64> = (0..=max_lag)
            .map(|l| (0..n - l).map(|k| ro[k] * ro[k + l]).sum::<f64>() / n as f64)
            .collect();
        let var = rho[0].max(1e-300);
        // z_b[k] = Σ_l ρ(l) J_b[k+l], l = −L..L.
        let z: Vec<Vec<f64>> = (0..np)
            .map(|b| {
                let jb = &j[b][o];
                (0..n)
                    .map(|k| {
                        let lo = k.saturating_sub(max_lag);
                        let hi = (k + max_lag).min(n - 1);
                        (lo..=hi).map(|m| rho[m.abs_diff(k)] * jb[m]).sum::<f64>()
                    })
                    .collect()
            })
            .collect();
        for a in 0..np {
            for b in 0..np {
                s[a * np + b] +=
                    j[a][o].iter().zip(&z[b]).map(|(x, y)| x * y).sum::<f64>() / (var * var);
            }
        }
    }
    // M⁻¹ S M⁻¹
    let mut tmp = vec![0.0; np * np];
    for a in 0..np {
        for b in 0..np {
            tmp[a * np + b] = (0..np).map(|k| m_inv[a * np + k] * s[k * np + b]).sum();
        }
    }
    let mut cov = vec![0.0; np * np];
    for a in 0..np {
        for b in 0..np {
            cov[a * np + b] = (0..np).map(|k| tmp[a * np + k] * m_inv[k * np + b]).sum();
        }
    }
    cov
}

/// Outcome of one output-error fit.
struct Fit {
    theta: Vec<f64>,
    fisher: Vec<f64>,
    residuals: Vec<Vec<f64>>,
    iterations: usize,
    converged: bool,
}

/// Output-error Gauss–Newton with Levenberg–Marquardt damping ([`optimise::levenberg_marquardt`]);
/// the diagonal residual covariance is re-estimated from the residuals after every step (Klein &
/// Morelli §6.2).
fn fit(data: &Data, params: &[Param], start: Vec<f64>, max_iterations: usize) -> Fit {
    let outputs: Vec<usize> = (0..6).filter(|&j| data.out[j].is_some()).collect();
    let r = residuals(data, params, &start, &outputs);
    let np = params.len();
    let mut problem = Reconstruction {
        data,
        params,
        variances: variances(&r),
        outputs,
        fisher: vec![0.0; np * np],
    };
    let options = optimise::Options {
        max_iterations,
        tolerance: 1e-9,
        damping: optimise::Damping {
            tries: 12,
            ..optimise::Damping::default()
        },
        solver: optimise::StepSolver::Marquardt,
    };
    let Ok(min) = optimise::levenberg_marquardt(&mut problem, start, r, &options);
    // Fisher information at the final point with the final residual covariance.
    let r = min.point;
    let var = variances(&r);
    let j = jacobian(data, params, &min.x, &problem.outputs, &r);
    let (m, _) = normal_equations(&j, &r, &var, np);
    Fit {
        theta: min.x,
        fisher: if m.iter().all(|x| x.is_finite()) {
            m
        } else {
            problem.fisher
        },
        residuals: r,
        iterations: min.iterations,
        converged: min.stop != optimise::Stop::MaxIterations,
    }
}

/// Per-output residual variance (the diagonal R of the relaxation algorithm).
fn variances(r: &[Vec<f64>]) -> Vec<f64> {
    r.iter()
        .map(|rj| (rj.iter().map(|x| x * x).sum::<f64>() / rj.len().max(1) as f64).max(1e-24))
        .collect()
}

/// The flight-path reconstruction for [`optimise::levenberg_marquardt`], with the current
/// residual variances.
struct Reconstruction<'a> {
    data: &'a Data,
    params: &'a [Param],
    outputs: Vec<usize>,
    variances: Vec<f64>,
    /// Information matrix of the last linearisation.
    fisher: Vec<f64>,
}

impl optimise::Problem for Reconstruction<'_> {
    type Point = Vec<Vec<f64>>;
    type Error = std::convert::Infallible;

    fn evaluate(&mut self, th: &[f64]) -> Result<Option<Self::Point>, Self::Error> {
        Ok(Some(residuals(self.data, self.params, th, &self.outputs)))
    }

    fn cost(&self, r: &Self::Point) -> f64 {
        r.iter()
            .zip(&self.variances)
            .map(|(rj, v)| rj.iter().map(|x| x * x).sum::<f64>() / v)
            .sum()
    }

    fn linearise(
        &mut self,
        th: &[f64],
        r: &Self::Point,
    ) -> Result<Option<optimise::Linearised>, Self::Error> {
        let j = jacobian(self.data, self.params, th, &self.outputs, r);
        let np = self.params.len();
        self.fisher = normal_equations(&j, r, &self.variances, np).0;
        let n = r.first().map_or(0, Vec::len);
        let w: Vec<f64> = self.variances.iter().map(|v| 1.0 / v.sqrt()).collect();
        Ok(Some(optimise::Linearised {
            sensitivities: Mat::from_fn(r.len() * n, np, |i, a| j[a][i / n][i % n] * w[i / n]),
            residuals: (0..r.len() * n)
                .map(|i| r[i / n][i % n] * w[i / n])
                .collect(),
        }))
    }

    fn relax(
        &mut self,
        _th: &mut Vec<f64>,
        r: &mut Self::Point,
    ) -> Result<optimise::Relaxation, Self::Error> {
        self.variances = variances(r);
        Ok(optimise::Relaxation::Steady)
    }
}

/// Rigid-body kinematics: state derivative for rates ω and specific force f.
fn derivative(x: &[f64; 6], w: [f64; 3], f: [f64; 3], translational: bool) -> [f64; 6] {
    let [u, v, wv, phi, theta, _] = *x;
    let [p, q, r] = w;
    let (sphi, cphi) = phi.sin_cos();
    let (sth, cth) = theta.sin_cos();
    let g = G0_M_S2;
    let (du, dv, dw) = if translational {
        (
            r * v - q * wv - g * sth + f[0],
            p * wv - r * u + g * cth * sphi + f[1],
            q * u - p * v + g * cth * cphi + f[2],
        )
    } else {
        (0.0, 0.0, 0.0)
    };
    let cth_safe = if cth.abs() < 1e-6 {
        1e-6_f64.copysign(cth)
    } else {
        cth
    };
    [
        du,
        dv,
        dw,
        p + sth / cth_safe * (q * sphi + r * cphi),
        q * cphi - r * sphi,
        (q * sphi + r * cphi) / cth_safe,
    ]
}

/// Integrates the kinematics and returns the residuals `y_m − model` for each output used.
fn residuals(data: &Data, params: &[Param], th: &[f64], outputs: &[usize]) -> Vec<Vec<f64>> {
    let n = data.t.len();
    let mut gyro_bias = [0.0; 3];
    let mut accel_bias = [0.0; 3];
    let mut bias = [0.0; 6];
    let mut scale = [0.0; 6];
    let mut skew = [0.0; 6];
    let mut x0 = [0.0; 6];
    for (p, &v) in params.iter().zip(th) {
        match *p {
            Param::GyroBias(i) => gyro_bias[i] = v,
            Param::AccelBias(i) => accel_bias[i] = v,
            Param::OutBias(j) => bias[j] = v,
            Param::OutScale(j) => scale[j] = v,
            Param::OutSkew(j) => skew[j] = v,
            Param::Init(k) => x0[k] = v,
        }
    }
    let translational = data.accel.is_some();
    let inputs = |k: usize| -> ([f64; 3], [f64; 3]) {
        let w = [0, 1, 2].map(|i| data.gyro[i][k] - gyro_bias[i]);
        let f = match &data.accel {
            Some(a) => [0, 1, 2].map(|i| a[i][k] - accel_bias[i]),
            None => [0.0; 3],
        };
        (w, f)
    };
    // Model outputs at every sample.
    let mut y: Vec<[f64; 6]> = Vec::with_capacity(n);
    let mut x = x0;
    for k in 0..n {
        y.push(outputs_of(&x));
        if k + 1 == n {
            break;
        }
        let h = data.t[k + 1] - data.t[k];
        let (w0, f0) = inputs(k);
        let (w1, f1) = inputs(k + 1);
        let mid = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]));
        let (wm, fm) = (mid(w0, w1), mid(f0, f1));
        let k1 = derivative(&x, w0, f0, translational);
        let k2 = derivative(&add(&x, &k1, 0.5 * h), wm, fm, translational);
        let k3 = derivative(&add(&x, &k2, 0.5 * h), wm, fm, translational);
        let k4 = derivative(&add(&x, &k3, h), w1, f1, translational);
        for i in 0..6 {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if x.iter().any(|v| !v.is_finite()) {
            // Diverged: make the cost infinite so the step is rejected.
            return outputs.iter().map(|_| vec![f64::INFINITY; n]).collect();
        }
    }
    outputs
        .iter()
        .map(|&j| {
            let meas = data.out[j].as_ref().map_or(&[][..], Vec::as_slice);
            (0..n)
                .map(|k| {
                    let model =
                        (1.0 + scale[j]) * sample_at(&data.t, &y, j, data.t[k] - skew[j]) + bias[j];
                    meas[k] - model
                })
                .collect()
        })
        .collect()
}

fn add(x: &[f64; 6], d: &[f64; 6], h: f64) -> [f64; 6] {
    [0, 1, 2, 3, 4, 5].map(|i| x[i] + h * d[i])
}

/// V, α, β, φ, θ, ψ from the state.
fn outputs_of(x: &[f64; 6]) -> [f64; 6] {
    let [u, v, w, phi, theta, psi] = *x;
    let vt = (u * u + v * v + w * w).sqrt();
    let beta = if vt > 0.0 {
        (v / vt).clamp(-1.0, 1.0).asin()
    } else {
        0.0
    };
    [vt, w.atan2(u), beta, phi, theta, psi]
}

/// Output `j` of the model at time `t` (linear interpolation, held at the ends).
fn sample_at(time: &[f64], y: &[[f64; 6]], j: usize, t: f64) -> f64 {
    let n = time.len();
    if t <= time[0] {
        return y[0][j];
    }
    if t >= time[n - 1] {
        return y[n - 1][j];
    }
    let k = time
        .partition_point(|&s| s <= t)
        .saturating_sub(1)
        .min(n - 2);
    let w = (t - time[k]) / (time[k + 1] - time[k]);
    y[k][j] + w * (y[k + 1][j] - y[k][j])
}

/// Sensitivities of the residuals by forward differences: J[p][j][k] = ∂model/∂θ_p (= −∂r/∂θ).
fn jacobian(
    data: &Data,
    params: &[Param],
    th: &[f64],
    outputs: &[usize],
    r0: &[Vec<f64>],
) -> Vec<Vec<Vec<f64>>> {
    use rayon::prelude::*;
    (0..params.len())
        .into_par_iter()
        .map(|p| {
            let (step, _) = params[p].step_and_floor();
            let h = step * th[p].abs().max(1.0);
            let mut tp = th.to_vec();
            tp[p] += h;
            let rp = residuals(data, params, &tp, outputs);
            rp.iter()
                .zip(r0)
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| (y - x) / h).collect())
                .collect()
        })
        .collect()
}

/// M = Σ Jᵀ R⁻¹ J and g = Σ Jᵀ R⁻¹ r (Gauss–Newton normal equations, Klein & Morelli eq. 6.56).
fn normal_equations(
    j: &[Vec<Vec<f64>>],
    r: &[Vec<f64>],
    var: &[f64],
    np: usize,
) -> (Vec<f64>, Vec<f64>) {
    let mut m = vec![0.0; np * np];
    let mut g = vec![0.0; np];
    for a in 0..np {
        for (o, v) in var.iter().enumerate() {
            g[a] += j[a][o].iter().zip(&r[o]).map(|(x, y)| x * y).sum::<f64>() / v;
        }
        for b in a..np {
            let mut s = 0.0;
            for (o, v) in var.iter().enumerate() {
                s += j[a][o]
                    .iter()
                    .zip(&j[b][o])
                    .map(|(x, y)| x * y)
                    .sum::<f64>()
                    / v;
            }
            m[a * np + b] = s;
            m[b * np + a] = s;
        }
    }
    (m, g)
}

/// Solves A x = b (Gaussian elimination with partial pivoting on an equilibrated copy).
fn solve(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    // Symmetric scaling D A D to cope with parameters of very different units.
    let d: Vec<f64> = (0..n)
        .map(|i| 1.0 / a[i * n + i].abs().sqrt().max(1e-300))
        .collect();
    let mut m: Vec<f64> = (0..n * n).map(|k| a[k] * d[k / n] * d[k % n]).collect();
    let mut x: Vec<f64> = (0..n).map(|i| b[i] * d[i]).collect();
    for c in 0..n {
        let piv = (c..n).max_by(|&i, &j| m[i * n + c].abs().total_cmp(&m[j * n + c].abs()))?;
        if m[piv * n + c].abs() < 1e-14 {
            return None;
        }
        if piv != c {
            for k in 0..n {
                m.swap(c * n + k, piv * n + k);
            }
            x.swap(c, piv);
        }
        for i in c + 1..n {
            let f = m[i * n + c] / m[c * n + c];
            if f != 0.0 {
                for k in c..n {
                    m[i * n + k] -= f * m[c * n + k];
                }
                x[i] -= f * x[c];
            }
        }
    }
    for c in (0..n).rev() {
        let s: f64 = (c + 1..n).map(|k| m[c * n + k] * x[k]).sum();
        x[c] = (x[c] - s) / m[c * n + c];
    }
    Some(x.iter().zip(&d).map(|(xi, di)| xi * di).collect())
}

/// Inverse of a symmetric positive-definite matrix (column by column through [`solve`]).
fn invert(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let mut inv = vec![0.0; n * n];
    for c in 0..n {
        let e: Vec<f64> = (0..n).map(|i| f64::from(u8::from(i == c))).collect();
        let col = solve(a, &e, n)?;
        for r in 0..n {
            inv[r * n + c] = col[r];
        }
    }
    Some(inv)
}
