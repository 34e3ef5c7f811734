//! The estimation experiment behind `flightid derivatives`: fly doublets on a simulator, identify the paper's transfer functions
//! (θ/δe, φ/δa, φ/δr) and read the same flights as full-state records for equation-error regression.
//!
//! Four flights from one trim, each a doublet (±A for one pulse each, from t = `start_s`): elevator, aileron,
//! rudder (the SISO records of the paper's transfer functions), and aileron followed by rudder (the lateral
//! record for equation error, so that C_lδa and C_lδr are not collinear). Sensor noise, when asked for, is added
//! to every measured channel after the flight, white and Gaussian, seeded.

use crate::aero::fit::{IdentifiedTf, IdentifiedTfs};
use crate::aero::model::TfOutput;
use crate::aero::regression::{
    equation_error, EquationErrorOptions, EquationErrorResult, FlightRecord,
};
use crate::aero::AeroError;
use crate::data;
use crate::ident::{self, IdentOptions, IdentResult, Method};
use crate::signal::{self, Maneuver};
use crate::sim::aero_truth::AeroTruth;
use crate::sim::{FlightPlan, Simulator, SurfaceInput, TrimPoint};
use crate::study::spec::{truth_geometry, truth_mass_body};
use faer::Mat;

/// Whether equation error on these JSBSim flights models the half-sample lag of the differentiated rates
/// behind the regressors ([`EquationErrorOptions::response_lags_half_sample`]); the attribution
/// (`study`) must use the same setting.
pub const JSBSIM_RESPONSE_LAG: bool = true;

/// White sensor noise, one standard deviation per channel kind.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SensorNoise {
    /// Angle of attack and sideslip vanes.
    pub flow_angle_rad: f64,
    /// Euler angles (AHRS).
    pub attitude_rad: f64,
    /// Body rates (rate gyros).
    pub rate_rad_s: f64,
    /// True airspeed.
    pub airspeed_m_s: f64,
    /// Surface position transducers.
    pub surface_rad: f64,
    /// Accelerometers.
    pub accel_m_s2: f64,
}

impl SensorNoise {
    /// Typical light-aircraft flight-test instrumentation: vanes 0.1°, AHRS 0.05°, MEMS rate gyros 0.1°/s,
    /// airspeed 0.2 m/s, surface potentiometers 0.05°, accelerometers 0.02 m/s².
    pub fn realistic() -> Self {
        Self {
            flow_angle_rad: 0.1f64.to_radians(),
            attitude_rad: 0.05f64.to_radians(),
            rate_rad_s: 0.1f64.to_radians(),
            airspeed_m_s: 0.2,
            surface_rad: 0.05f64.to_radians(),
            accel_m_s2: 0.02,
        }
    }

    /// The standard deviation for a flight-data column (docs/data.md names), 0 for unmeasured ones.
    fn std_of(&self, column: &str) -> f64 {
        match column {
            "alpha_rad" | "beta_rad" => self.flow_angle_rad,
            "phi_rad" | "theta_rad" | "psi_rad" => self.attitude_rad,
            "p_rad_s" | "q_rad_s" | "r_rad_s" => self.rate_rad_s,
            "airspeed_m_s" => self.airspeed_m_s,
            "elevator_rad" | "aileron_rad" | "rudder_rad" => self.surface_rad,
            "ax_m_s2" | "ay_m_s2" | "az_m_s2" => self.accel_m_s2,
            _ => 0.0,
        }
    }
}

/// The doublet flights.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TrialOptions {
    /// Simulation and sampling rate, Hz.
    pub rate_hz: f64,
    /// Time the doublets start, s (the record before it is the trim, used to take the trim values).
    pub start_s: f64,
    /// Pulse width of every doublet, s.
    pub pulse_s: f64,
    /// Length of the elevator record, s (it must hold some phugoid for θ/δe's low-order coefficients).
    pub longitudinal_s: f64,
    /// Length of each lateral record, s.
    pub lateral_s: f64,
    /// Doublet amplitudes (elevator, aileron, rudder), rad.
    pub amplitude_rad: [f64; 3],
    /// Sensor noise; `None` for the noise-free record.
    pub noise: Option<SensorNoise>,
    /// Seed of the noise.
    pub seed: u64,
    /// Estimator of the transfer functions.
    #[serde(skip)]
    pub method: Method,
}

impl Default for TrialOptions {
    fn default() -> Self {
        Self {
            rate_hz: 60.0,
            start_s: 1.0,
            pulse_s: 1.0,
            longitudinal_s: 30.0,
            lateral_s: 20.0,
            amplitude_rad: [2f64.to_radians(), 5f64.to_radians(), 5f64.to_radians()],
            noise: None,
            seed: 1,
            method: Method::Srivc,
        }
    }
}

/// The flights as measured (noise added when asked for).
#[derive(Debug, Clone)]
pub struct Flights {
    /// Elevator doublet.
    pub elevator: data::FlightRecord,
    /// Aileron doublet.
    pub aileron: data::FlightRecord,
    /// Rudder doublet.
    pub rudder: data::FlightRecord,
    /// Aileron doublet, then a rudder doublet 4 pulses later.
    pub lateral: data::FlightRecord,
    /// The same flights before the sensor noise was added (`None` when no noise was asked for).
    pub noise_free: Option<Box<Flights>>,
}

fn doublet(opts: &TrialOptions, duration_s: f64, start_s: f64, amplitude_rad: f64) -> Vec<f64> {
    let dt_s = 1.0 / opts.rate_hz;
    let n_steps = (duration_s * opts.rate_hz).round() as usize;
    let mut u = signal::generate(
        &Maneuver::Doublet {
            pulse_s: opts.pulse_s,
        },
        dt_s,
        duration_s,
        start_s,
    );
    u.resize(n_steps, 0.0);
    u.iter().map(|x| amplitude_rad * x).collect()
}

fn with_noise(
    rec: data::FlightRecord,
    noise: Option<SensorNoise>,
    seed: u64,
) -> data::FlightRecord {
    let Some(noise) = noise else { return rec };
    let mut out = rec.clone();
    for (k, (name, values)) in rec.columns.iter().enumerate() {
        let std = noise.std_of(name);
        if std > 0.0 {
            out.push_column(
                name,
                signal::add_white_noise(values, std, seed.wrapping_mul(1000) + k as u64),
            );
        }
    }
    out
}

/// Flies the four doublet flights, each from a fresh trim at `point`.
pub fn fly_doublets(
    sim: &mut dyn Simulator,
    point: &TrimPoint,
    opts: &TrialOptions,
) -> Result<Flights, AeroError> {
    if !(opts.rate_hz >= 10.0 && opts.pulse_s > 0.0 && opts.start_s >= 1.0 / opts.rate_hz) {
        return Err(AeroError::BadInput(format!(
            "doublet flights need rate_hz ≥ 10, pulse_s > 0 and a trim segment before the input \
             (start_s {} s)",
            opts.start_s
        )));
    }
    let [a_e, a_a, a_r] = opts.amplitude_rad;
    let plan = |duration_s: f64, inputs: Vec<(&str, Vec<f64>)>| FlightPlan {
        rate_hz: opts.rate_hz,
        n_steps: (duration_s * opts.rate_hz).round() as usize,
        inputs: inputs
            .into_iter()
            .map(|(s, d)| SurfaceInput {
                surface: s.to_string(),
                deflection_rad: d,
            })
            .collect(),
    };
    let (lon_s, lat_s, t0) = (opts.longitudinal_s, opts.lateral_s, opts.start_s);
    let second_s = t0 + 4.0 * opts.pulse_s;
    let plans = [
        plan(lon_s, vec![("elevator", doublet(opts, lon_s, t0, a_e))]),
        plan(lat_s, vec![("aileron", doublet(opts, lat_s, t0, a_a))]),
        plan(lat_s, vec![("rudder", doublet(opts, lat_s, t0, a_r))]),
        plan(
            lat_s,
            vec![
                ("aileron", doublet(opts, lat_s, t0, a_a)),
                ("rudder", doublet(opts, lat_s, second_s, a_r)),
            ],
        ),
    ];
    let mut raw = Vec::new();
    for p in &plans {
        sim.trim(point)?;
        raw.push(sim.fly(p)?);
    }
    let assemble = |recs: Vec<data::FlightRecord>, noise_free: Option<Box<Flights>>| {
        let mut it = recs.into_iter();
        let mut next = || it.next().unwrap_or_default();
        Flights {
            elevator: next(),
            aileron: next(),
            rudder: next(),
            lateral: next(),
            noise_free,
        }
    };
    if opts.noise.is_none() {
        return Ok(assemble(raw, None));
    }
    let noisy = raw
        .iter()
        .enumerate()
        .map(|(k, rec)| with_noise(rec.clone(), opts.noise, opts.seed + k as u64))
        .collect();
    Ok(assemble(noisy, Some(Box::new(assemble(raw, None)))))
}

/// Mean of `x` over the samples before `start_s`.
fn trim_mean(time_s: &[f64], x: &[f64], start_s: f64) -> f64 {
    let n = time_s.iter().take_while(|t| **t < start_s).count().max(1);
    x[..n].iter().sum::<f64>() / n as f64
}

/// Identifies one transfer function (4 poles, 2 zeros) from a record.
///
/// `ident::identify` takes the trim from the samples before the input first moves; with a noisy surface
/// measurement that is only the first sample, and a noisy trim drifts φ through the spiral pole. The trim is
/// therefore taken here as the mean over the trim segment before `start_s`, written into the first sample.
pub fn identify_tf(
    rec: &data::FlightRecord,
    input: &str,
    output: &str,
    opts: &TrialOptions,
) -> Result<IdentResult, AeroError> {
    let tf = format!("{output}/{input}");
    let missing = |c: &str| AeroError::BadRecord(format!("{tf}: no column {c}"));
    let mut u = rec.column(input).ok_or_else(|| missing(input))?.to_vec();
    let mut y = rec.column(output).ok_or_else(|| missing(output))?.to_vec();
    if u.is_empty() {
        return Err(AeroError::BadRecord(format!("{tf}: empty record")));
    }
    u[0] = trim_mean(&rec.time_s, &u, opts.start_s);
    y[0] = trim_mean(&rec.time_s, &y, opts.start_s);
    let dt_s = 1.0 / opts.rate_hz;
    let id_opts = IdentOptions {
        method: opts.method,
        poles: 4,
        zeros: 2,
        estimate_delay: false,
    };
    ident::identify(&u, &y, dt_s, &id_opts).map_err(|source| AeroError::Ident { tf, source })
}

/// An identification as the derivative fit wants it: monic coefficients and, when the estimator gives standard
/// errors, their diagonal covariance ordered [den₁…den₄, num…].
pub fn to_identified_tf(r: &IdentResult) -> IdentifiedTf {
    let stds: Vec<f64> = r
        .den_std
        .iter()
        .skip(1)
        .chain(&r.num_std)
        .copied()
        .collect();
    let usable = r.den_std.len() == r.tf.den.len()
        && r.num_std.len() == r.tf.num.len()
        && stds.iter().all(|s| s.is_finite() && *s > 0.0);
    IdentifiedTf {
        num: r.tf.num.clone(),
        den: r.tf.den.clone(),
        covariance: usable.then(|| {
            Mat::from_fn(stds.len(), stds.len(), |i, j| {
                if i == j {
                    stds[i] * stds[i]
                } else {
                    0.0
                }
            })
        }),
    }
}

/// The paper's three transfer functions identified from the SISO flights.
pub fn identify_paper_tfs(
    flights: &Flights,
    opts: &TrialOptions,
) -> Result<(IdentifiedTfs, Vec<(TfOutput, IdentResult)>), AeroError> {
    let mut tfs = IdentifiedTfs::default();
    let mut results = Vec::new();
    for (which, rec, input) in [
        (TfOutput::THETA_ELEVATOR, &flights.elevator, "elevator_rad"),
        (TfOutput::PHI_AILERON, &flights.aileron, "aileron_rad"),
        (TfOutput::PHI_RUDDER, &flights.rudder, "rudder_rad"),
    ] {
        let output = if which == TfOutput::THETA_ELEVATOR {
            "theta_rad"
        } else {
            "phi_rad"
        };
        let r = identify_tf(rec, input, output, opts)?;
        tfs.tfs.push((which, to_identified_tf(&r)));
        results.push((which, r));
    }
    Ok((tfs, results))
}

/// Equation-error regression (body axes, about the CG) on a record, with the truth's mass, geometry and air.
pub fn equation_error_on(
    rec: &data::FlightRecord,
    truth: &AeroTruth,
) -> Result<EquationErrorResult, AeroError> {
    equation_error_with(rec, truth, false, JSBSIM_RESPONSE_LAG)
}

/// [`equation_error_on`] with α̇ c̄/(2V) as a C_m regressor when `include_alphadot` (α measured and
/// differentiated: the measurement that could separate C_mq from C_mα̇), and the half-sample lag of JSBSim
/// records modelled when `simulated` ([`EquationErrorOptions::response_lags_half_sample`]).
pub fn equation_error_with(
    rec: &data::FlightRecord,
    truth: &AeroTruth,
    include_alphadot: bool,
    simulated: bool,
) -> Result<EquationErrorResult, AeroError> {
    let record = FlightRecord {
        // The recorded specific forces are at the pilot/IMU, not the CG: let the regression use the
        // differentiated body velocities instead.
        ay_m_s2: None,
        az_m_s2: None,
        ax_m_s2: None,
        qbar_pa: None,
        thrust_n: None,
        ..FlightRecord::from_columns(rec)
    };
    let options = EquationErrorOptions {
        air_density_kg_m3: truth.rho_kg_m3,
        g_m_s2: if truth.g_m_s2 > 0.0 {
            truth.g_m_s2
        } else {
            data::G0_M_S2
        },
        include_alphadot,
        response_lags_half_sample: simulated,
        ..EquationErrorOptions::default()
    };
    equation_error(
        &record,
        &truth_mass_body(truth),
        &truth_geometry(truth),
        &options,
    )
}

/// Equation error on the doublet flights: C_m and C_L from the elevator flight, C_l, C_n and C_Y from the
/// lateral flight (an axis the flight does not excite would only regress noise).
pub fn equation_error_flights(
    flights: &Flights,
    truth: &AeroTruth,
) -> Result<EquationErrorResult, AeroError> {
    let lon = equation_error_on(&flights.elevator, truth)?;
    let lat = equation_error_on(&flights.lateral, truth)?;
    let keep = |r: EquationErrorResult, wanted: &[&str]| {
        r.equations
            .into_iter()
            .filter(|e| wanted.contains(&e.coefficient))
            .collect::<Vec<_>>()
    };
    let mut skipped: Vec<_> = lon
        .skipped
        .iter()
        .filter(|(c, _)| ["Cm", "CL"].contains(c))
        .cloned()
        .collect();
    skipped.extend(
        lat.skipped
            .iter()
            .filter(|(c, _)| ["Cl", "Cn", "CY"].contains(c))
            .cloned(),
    );
    let mut equations = keep(lon, &["Cm", "CL"]);
    equations.extend(keep(lat, &["Cl", "Cn", "CY"]));
    Ok(EquationErrorResult { equations, skipped })
}
