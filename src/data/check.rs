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
//! `V = |(u,v,w)|`, `α = atan2(w, u)`, `β = asin(v/V)`, φ, θ, ψ are compared with the measured ones through the
//! output model `y_m(t) = (1 + s) · y(t − τ) + b` (scale factor s, time skew τ, bias b, for V, α and β; a scale
//! factor also for φ and θ, against the attitude the rates integrate to, so that a roll or pitch gyro's scale
//! error shows as the inverse scale factor on φ or θ). Biases, scale factors, skews and the initial state are
//! estimated by output-error Gauss–Newton (Levenberg–Marquardt damped) with the residual covariance
//! re-estimated every iteration (Klein & Morelli §6.2, eq. 6.51–6.56). Standard errors are Cramér–Rao bounds
//! corrected for coloured residuals (Morelli & Klein, "Accounting for the effects of colored residuals", J.
//! Aircraft 1997; Klein & Morelli §6.5): `Cov = M⁻¹ S M⁻¹` with `M = Σ Jᵀ R⁻¹ J` and `S` built from the
//! Bartlett-windowed residual autocorrelation over the lags where it is correlated (the estimation core's rule,
//! `estimate::covariance`). The plain bound `M⁻¹` (white residuals) is optimistic by factors of 2–5 on flight
//! data.
//!
//! Integration: classical Runge–Kutta 4 over each sample interval, measured inputs linear in time.

mod fit;
mod kinematics;

use serde::Serialize;

use super::channel::Channel;
use super::error::DataError;
use super::record::FlightRecord;
use crate::signal::{std_dev, sum_sq};
use fit::{coloured_residual_covariance, fit, invert, jacobian};
use kinematics::{Data, Param, N_OUT, OUT_NAMES, PHI, THETA};

/// Options of [`check_compatibility`].
#[derive(Debug, Clone)]
pub struct CheckOptions {
    /// Also estimate scale factors on V, α and β, and on φ and θ.
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

/// Fewest samples a piece between dropouts needs to start from its own initial state.
const MIN_PIECE_SAMPLES: usize = 20;

/// Result of [`check_compatibility`].
#[derive(Debug, Clone, Serialize)]
pub struct CheckReport {
    /// Pieces of the record between dropouts, each reconstructed from its own initial state (1 without).
    pub pieces: usize,
    /// Instrument errors: biases, scale factors, time skews.
    pub instrument: Vec<Estimate>,
    /// Estimated initial state (u, v, w in m/s, φ, θ, ψ in rad, altitude in m), and that of every further piece
    /// after a dropout (`initial_…_piece2`, …).
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

impl CheckReport {
    /// The time skews (`skew_*`) the reconstruction found significant.
    pub fn significant_skews(&self) -> impl Iterator<Item = &Estimate> {
        self.instrument
            .iter()
            .filter(|e| e.name.starts_with("skew_") && e.significant)
    }

    /// The significant time skews longer than a data system can put between the channels of `rec`
    /// ([`skew_bound_s`]): a vane reading gusts the kinematics do not see, or sitting behind a filter.
    pub fn implausible_skews<'a>(
        &'a self,
        rec: &FlightRecord,
    ) -> impl Iterator<Item = &'a Estimate> {
        let bound_s = skew_bound_s(rec);
        self.significant_skews()
            .filter(move |e| e.value.abs() > bound_s)
    }
}

/// How clearly an air-data signal must move beyond its own noise before a scale factor or a time skew on it
/// is estimated: its variance about the mean must exceed the noise variance (from
/// [`crate::signal::noise_std`]) by this many standard errors of a variance estimate over n samples
/// (σ²·√(2/n)). Below that, the factor times the signal is indistinguishable from a bias plus noise, and a
/// "significant" scale factor on an axis the maneuver does not move is an artefact (Klein & Morelli §10.3: a
/// parameter is identified only through the excitation of the signal it multiplies).
const EXCITATION_Z: f64 = 5.0;

/// How many times the motion the kinematics explain must exceed what they leave unexplained ([`excitation`]).
const EXPLAINED_RATIO: f64 = 2.0;

/// Smallest movement that counts at all, rms in the signal's unit (noise-free records): 0.05 m/s for V,
/// 0.05° for the angles.
fn excitation_floor(output: usize) -> f64 {
    if output == 0 {
        0.05
    } else {
        0.05_f64.to_radians()
    }
}

/// Whether a signal (`output` 0 = V, 1 = α, 2 = β, 3 = φ, 4 = θ) moves clearly enough for a scale factor or a
/// time skew on it to be estimated, given the residual of a fit without them (`with_it` false: tests 1 and
/// 2) or with them (true: all three; the residual of a fit without the skew still holds the skew's own
/// effect): (1) the measured signal's
/// variance about its mean exceeds its noise variance (from [`crate::signal::noise_std`]) by
/// [`EXCITATION_Z`] standard errors of a variance estimate, (2) the motion the kinematics reconstruct
/// (measured minus residual) is at least [`excitation_floor`] rms, and (3) it is [`EXPLAINED_RATIO`] times the
/// coloured part of the residual (its rms beyond the white sensor noise), the motion they do not explain. A
/// scale factor is in effect the regression of the residual on the explained motion; with coloured residuals
/// (gusts) of only a few independent events its error is about (unexplained / explained) / √n_eff, which the
/// coloured-residual bound still underrates. A longitudinal maneuver flown in turbulence moves β through
/// gusts and a little lateral drift: the measured β passes (1); fitted with a scale factor, the reconstructed
/// β moves 0.23° against 0.21° left beyond the noise and fails (3), so no β scale factor is named (it was,
/// −0.36 ± 0.08, on the HFB-320 flight record). `Err` carries the evidence.
fn excitation(
    output: usize,
    signal: &[f64],
    residual: &[f64],
    with_it: bool,
) -> Result<(), String> {
    let floor = excitation_floor(output);
    let (k, unit) = if output == 0 {
        (1.0, "m/s")
    } else {
        (1f64.to_degrees(), "°")
    };
    let moved = std_dev(signal);
    let noise = crate::signal::noise_std(signal);
    let n = signal.len().max(1) as f64;
    let z = (moved * moved - noise * noise) / (noise * noise * (2.0 / n).sqrt()).max(1e-300);
    let explained: Vec<f64> = signal.iter().zip(residual).map(|(m, r)| m - r).collect();
    let explained = std_dev(&explained);
    // what they leave beyond the white sensor noise: gusts, unmodelled motion
    let unexplained = (std_dev(residual).powi(2) - noise * noise).max(0.0).sqrt();
    if z <= EXCITATION_Z || moved < floor {
        return Err(format!(
            "moves {:.3} {unit} rms against a noise of {:.3} {unit}, not clearly beyond it (variance excess \
             z = {z:.1}, needs more than {EXCITATION_Z} and at least {:.2} {unit} rms)",
            moved * k,
            noise * k,
            floor * k
        ));
    }
    if explained < floor || (with_it && explained < EXPLAINED_RATIO * unexplained) {
        return Err(format!(
            "moves {:.3} {unit} rms, but the kinematics explain only {:.3} {unit} rms of it and leave {:.3} \
             {unit} beyond the sensor noise (gusts, unmodelled motion): the motion they explain is not clearly \
             beyond what they leave (needs {EXPLAINED_RATIO}× as much)",
            moved * k,
            explained * k,
            unexplained * k
        ));
    }
    Ok(())
}

/// The longest time skew a data system can put between its channels, s: one sample interval (the record's
/// median step), at least 50 ms. A data system samples its channels within one frame; what remains is
/// sampling phase and filter mismatch, a fraction of a sample to about one (Klein & Morelli §10.2). A longer
/// apparent lag of a vane behind the inertial data is something else — in turbulence the vane reads gusts the
/// kinematics do not see, and the reconstruction takes their response for a lag (0.22 s on the HFB-320 flight
/// record at 10 Hz) — so the commands that correct for skews (`derivatives`) do not apply a longer one.
pub fn skew_bound_s(rec: &FlightRecord) -> f64 {
    rec.dt_s().unwrap_or(0.0).max(0.05)
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
        rec.require(Channel::P, why)?.to_vec(),
        rec.require(Channel::Q, why)?.to_vec(),
        rec.require(Channel::R, why)?.to_vec(),
    ];
    let phi = rec.require(Channel::Phi, "as the attitude reference of the check")?;
    let theta = rec.require(Channel::Theta, "as the attitude reference of the check")?;
    if rec.len() < 20 {
        return Err(DataError::InvalidArgument(format!(
            "the compatibility check needs at least 20 samples, got {}",
            rec.len()
        )));
    }
    let accel = match (
        rec.column(Channel::Ax),
        rec.column(Channel::Ay),
        rec.column(Channel::Az),
    ) {
        (Some(a), Some(b), Some(c)) => Some([a.to_vec(), b.to_vec(), c.to_vec()]),
        _ => None,
    };
    let air = [Channel::Airspeed, Channel::Alpha, Channel::Beta]
        .map(|c| rec.column(c).map(<[f64]>::to_vec));
    let translational = accel.is_some() && air.iter().all(Option::is_some);
    let psi = rec.column(Channel::Psi).map(crate::signal::unwrap_rad);
    // air data and altitude only with the translational kinematics
    let altitude = rec.column(Channel::Altitude).map(<[f64]>::to_vec);
    let ([v_m, a_m, b_m], altitude) = if translational {
        (air, altitude)
    } else {
        ([None, None, None], None)
    };
    let out: [Option<Vec<f64>>; N_OUT] = [
        v_m,
        a_m,
        b_m,
        Some(phi.to_vec()),
        Some(theta.to_vec()),
        psi,
        altitude,
    ];
    // A piece after a dropout starts from its own initial state; a piece of fewer than MIN_PIECE_SAMPLES
    // samples could not determine one and is integrated over as before.
    let starts = super::dropout_starts(&rec.time_s);
    let piece_starts: Vec<usize> = starts
        .iter()
        .enumerate()
        .filter(|&(i, &k)| starts.get(i + 1).copied().unwrap_or(rec.len()) - k >= MIN_PIECE_SAMPLES)
        .map(|(_, &k)| k)
        .collect();
    let data = Data {
        t: rec.time_s.clone(),
        gyro,
        accel: if translational { accel } else { None },
        out,
        piece_starts,
    };

    // Parameter set: biases and the initial state first; scale factors and skews after a first fit shows
    // which signals the kinematics move (below).
    let mut params: Vec<Param> = (0..3).map(Param::GyroBias).collect();
    let mut not_excited = Vec::new();
    let mut wanted = Vec::new();
    if translational {
        params.extend((0..3).map(Param::AccelBias));
        params.extend([Param::OutBias(1), Param::OutBias(2)]);
        if opts.time_skews {
            wanted.extend([Param::OutSkew(1), Param::OutSkew(2)]);
        }
        if opts.scale_factors {
            wanted.extend([Param::OutScale(0), Param::OutScale(1), Param::OutScale(2)]);
        }
        params.extend((0..3).map(Param::Init));
    }
    if opts.scale_factors {
        // φ and θ against the attitude the rates integrate to: what a gyro's scale error would look like too
        wanted.extend([Param::OutScale(PHI), Param::OutScale(THETA)]);
    }
    params.extend(
        (3..N_OUT)
            .filter(|&k| data.out[k].is_some())
            .map(Param::Init),
    );
    let initial: Vec<usize> = params.iter().filter_map(|p| p.initial_state()).collect();
    for piece in 1..=data.piece_starts.len() {
        params.extend(initial.iter().map(|&k| Param::PieceInit(piece, k)));
    }

    // Initial guess: zero instrument errors, the initial state of every piece from its first measurements.
    let mut theta_p: Vec<f64> = params
        .iter()
        .map(|p| {
            let at = match *p {
                Param::PieceInit(piece, _) => data.piece_starts[piece - 1],
                _ => 0,
            };
            let first = |j: usize| data.out[j].as_ref().map_or(0.0, |x| x[at]);
            match p.initial_state() {
                Some(k) if k < 3 => {
                    let (v, a, b) = (first(0), first(1), first(2));
                    [v * a.cos() * b.cos(), v * b.sin(), v * a.sin() * b.cos()][k]
                }
                Some(k) => first(k),
                None => 0.0,
            }
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
                None,
            ],
            piece_starts: data.piece_starts.clone(),
        };
        let att_params: Vec<Param> = params
            .iter()
            .copied()
            .filter(|p| {
                matches!(p, Param::GyroBias(_))
                    || p.initial_state().is_some_and(|k| (3..6).contains(&k))
            })
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
    // Stage 2: biases and initial state only, a start for stage 3 and the first test of the scale factors and
    // skews: their signal must move beyond its noise, and the kinematics must reconstruct some of that motion.
    // Stage 3: with the candidates in, each must still leave less unexplained than the kinematics explain
    // ([`excitation`]); the ones that do not are dropped and the fit repeated.
    let mut result = None;
    if !wanted.is_empty() {
        let base = fit(&data, &params, theta_p.clone(), opts.max_iterations);
        theta_p = base.theta;
        // the fit's residuals come one per output present, in output order
        let at = |j: usize| (0..j).filter(|&k| data.out[k].is_some()).count();
        let mut candidates = Vec::new();
        for p in wanted {
            let (Param::OutSkew(j) | Param::OutScale(j)) = p else {
                continue;
            };
            let signal = data.out[j].as_deref().unwrap_or(&[]);
            match excitation(j, signal, &base.residuals[at(j)], false) {
                Ok(()) => candidates.push((p, j)),
                Err(evidence) => {
                    not_excited.push(format!("{}: {} {evidence}", p.name().0, OUT_NAMES[j]))
                }
            }
        }
        if !candidates.is_empty() {
            let base_params = params.clone();
            let base_theta = theta_p.clone();
            params.extend(candidates.iter().map(|(p, _)| *p));
            theta_p.extend(candidates.iter().map(|_| 0.0));
            let trial = fit(&data, &params, theta_p.clone(), opts.max_iterations);
            let mut kept = Vec::new();
            for (p, j) in candidates {
                let signal = data.out[j].as_deref().unwrap_or(&[]);
                match excitation(j, signal, &trial.residuals[at(j)], true) {
                    Ok(()) => kept.push(p),
                    Err(evidence) => {
                        not_excited.push(format!("{}: {} {evidence}", p.name().0, OUT_NAMES[j]))
                    }
                }
            }
            if kept.len() + base_params.len() == params.len() {
                theta_p = trial.theta.clone();
                result = Some(trial);
            } else {
                params = base_params;
                theta_p = base_theta;
                params.extend(kept.iter().copied());
                theta_p.extend(kept.iter().map(|_| 0.0));
            }
        }
    }
    let mut result =
        result.unwrap_or_else(|| fit(&data, &params, theta_p.clone(), opts.max_iterations));
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
                start.push(
                    if p.initial_state().is_some() || matches!(p, Param::GyroBias(_)) {
                        theta_p[k]
                    } else {
                        0.0
                    },
                );
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
    let outputs: Vec<usize> = (0..N_OUT).filter(|&j| data.out[j].is_some()).collect();
    let np = params.len();
    // Cramér–Rao bounds at the solution, corrected for coloured residuals.
    let cov = match invert(&fisher, np) {
        Some(m_inv) => {
            let j = jacobian(&data, &params, &theta_p, &outputs, &r);
            coloured_residual_covariance(&m_inv, &j, &r, np)
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
        if p.initial_state().is_some() {
            initial_state.push(Estimate {
                significant: false,
                ..est
            });
        } else {
            instrument.push(est);
        }
    }
    let residual_rms: Vec<(String, f64)> = outputs
        .iter()
        .zip(&r)
        .map(|(&j, rj)| (OUT_NAMES[j].to_string(), (sum_sq(rj) / n as f64).sqrt()))
        .collect();
    // A fit whose cost is not finite has not converged, whatever the optimiser's stop says.
    let diverged: Vec<&str> = residual_rms
        .iter()
        .filter(|(_, rms)| !rms.is_finite())
        .map(|(c, _)| c.as_str())
        .collect();
    if !diverged.is_empty() || theta_p.iter().any(|x| !x.is_finite()) {
        return Err(DataError::Diverged {
            what: "the flight-path reconstruction".into(),
            columns: if diverged.is_empty() {
                "the estimates".into()
            } else {
                diverged.join(", ")
            },
        });
    }
    Ok(CheckReport {
        pieces: data.piece_starts.len() + 1,
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

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(name: &str, value: f64, significant: bool) -> Estimate {
        Estimate {
            name: name.into(),
            column: name
                .trim_start_matches("skew_")
                .trim_end_matches("_s")
                .into(),
            value,
            std_error: 0.01,
            significant,
        }
    }

    #[test]
    fn a_significant_skew_beyond_one_sample_interval_is_implausible() {
        // 10 Hz record: the bound is one sample, 0.1 s (above the 50 ms floor)
        let rec = FlightRecord::new((0..50).map(|k| k as f64 * 0.1).collect());
        let report = CheckReport {
            pieces: 1,
            instrument: vec![
                estimate("bias_q_rad_s", 0.5, true),
                estimate("skew_alpha_s", 0.05, true),
                estimate("skew_beta_s", -0.22, true),
                estimate("skew_alpha_s", 0.3, false),
            ],
            initial_state: Vec::new(),
            residual_rms: Vec::new(),
            iterations: 1,
            converged: true,
            translational: true,
            not_identifiable: Vec::new(),
            not_excited: Vec::new(),
        };
        let values =
            |it: &mut dyn Iterator<Item = &Estimate>| it.map(|e| e.value).collect::<Vec<_>>();
        assert_eq!(values(&mut report.significant_skews()), vec![0.05, -0.22]);
        assert_eq!(values(&mut report.implausible_skews(&rec)), vec![-0.22]);
    }
}
