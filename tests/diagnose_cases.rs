//! Diagnose names hidden effects: "measured" data are generated with JSBSim itself with one effect hidden
//! (a modified coefficient, a delayed/lagged/scaled surface, a biased sensor), realistic seeded noise, one
//! training and one validation maneuver each exciting all three axes; `diagnose` must name the effect and
//! target, recover the value within 20 % and at least halve the validation ISE. Clean data: nothing named.

use std::sync::Mutex;

use flightid::aircraft;
use flightid::data::FlightRecord;
use flightid::diagnose::search::Worker;
use flightid::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use flightid::signal::{add_white_noise, generate, Maneuver};
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};

/// The cases share the two cores: run one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

const RATE_HZ: f64 = 50.0;
const DURATION_S: f64 = 16.0;

/// Noise standard deviations of a small-aircraft air-data/AHRS suite (column, std in column units).
const NOISE: [(&str, f64); 13] = [
    ("phi_rad", 0.002),
    ("theta_rad", 0.002),
    ("psi_rad", 0.002),
    ("p_rad_s", 0.003),
    ("q_rad_s", 0.003),
    ("r_rad_s", 0.003),
    ("alpha_rad", 0.004),
    ("beta_rad", 0.004),
    ("airspeed_m_s", 0.2),
    ("altitude_m", 0.5),
    ("ax_m_s2", 0.05),
    ("ay_m_s2", 0.05),
    ("az_m_s2", 0.05),
];

/// Hidden effect used to generate the data.
#[derive(Clone)]
enum Hidden {
    Coefficient(&'static str, f64),
    Delay(&'static str, f64),
    Lag(&'static str, f64),
    Effectiveness(&'static str, f64),
    Bias(&'static str, f64),
}

/// Training: 3211 on elevator, then doublets on aileron and rudder. Validation: other shapes and timing.
fn inputs(validation: bool) -> Vec<(&'static str, Vec<f64>)> {
    let dt = 1.0 / RATE_HZ;
    let n = (DURATION_S * RATE_HZ).round() as usize;
    let gen = |m: Maneuver, amp: f64, start: f64| -> Vec<f64> {
        generate(&m, dt, DURATION_S, start)
            .into_iter()
            .take(n)
            .map(|v| amp * v)
            .collect()
    };
    if !validation {
        vec![
            (
                "elevator",
                gen(Maneuver::ThreeTwoOneOne { pulse_s: 0.5 }, 0.03, 1.0),
            ),
            (
                "aileron",
                gen(Maneuver::Doublet { pulse_s: 1.0 }, 0.05, 6.0),
            ),
            (
                "rudder",
                gen(Maneuver::Doublet { pulse_s: 1.0 }, 0.05, 10.0),
            ),
        ]
    } else {
        vec![
            (
                "elevator",
                gen(Maneuver::Doublet { pulse_s: 0.8 }, 0.035, 1.0),
            ),
            (
                "aileron",
                gen(Maneuver::ThreeTwoOneOne { pulse_s: 0.4 }, 0.04, 5.0),
            ),
            (
                "rudder",
                gen(Maneuver::Doublet { pulse_s: 0.7 }, 0.06, 10.5),
            ),
        ]
    }
}

/// The surface the aircraft really sees for a measured deviation sequence (independent of the library).
fn hidden_input(h: &Hidden, surface: &str, u: &[f64]) -> Vec<f64> {
    let dt = 1.0 / RATE_HZ;
    match *h {
        Hidden::Delay(s, tau) if s == surface => {
            let k = (tau / dt).round() as usize;
            (0..u.len())
                .map(|i| if i >= k { u[i - k] } else { 0.0 })
                .collect()
        }
        Hidden::Lag(s, tau) if s == surface => {
            // Euler with 20 sub-steps per sample of τ ẋ = u − x.
            let mut x = 0.0;
            u.iter()
                .map(|&ui| {
                    for _ in 0..20 {
                        x += dt / 20.0 / tau * (ui - x);
                    }
                    x
                })
                .collect()
        }
        Hidden::Effectiveness(s, k) if s == surface => u.iter().map(|v| k * v).collect(),
        _ => u.to_vec(),
    }
}

/// Flies one maneuver with the hidden effects and returns the noisy "measured" record.
fn measure(sim: &mut JsbsimSim, hidden: &[Hidden], validation: bool, seed: u64) -> FlightRecord {
    for name in sim.coefficient_knobs.clone() {
        sim.set_coefficient_scale(&name, 1.0).unwrap();
    }
    for h in hidden {
        if let Hidden::Coefficient(c, f) = h {
            sim.set_coefficient_scale(c, *f).unwrap();
        }
    }
    let trim = sim.trim(&TrimPoint::level(4000.0, 100.0)).unwrap();
    let measured = inputs(validation);
    let plan = FlightPlan {
        rate_hz: RATE_HZ,
        n_steps: measured[0].1.len(),
        inputs: measured
            .iter()
            .map(|(s, u)| {
                let mut seen = u.clone();
                for h in hidden {
                    seen = hidden_input(h, s, &seen);
                }
                SurfaceInput {
                    surface: s.to_string(),
                    deflection_rad: seen,
                }
            })
            .collect(),
    };
    let mut rec = sim.fly(&plan).unwrap();
    // The recorded surfaces are the measured (pre-effect) deflections: sample k+1 shows step k.
    for (s, u) in &measured {
        let base = trim.surfaces_rad[*s];
        let col: Vec<f64> = std::iter::once(base)
            .chain(u.iter().map(|v| base + v))
            .collect();
        let (_, c) = rec
            .columns
            .iter_mut()
            .find(|(n, _)| *n == format!("{s}_rad"))
            .unwrap();
        *c = col;
    }
    for h in hidden {
        if let Hidden::Bias(col, b) = h {
            let (_, c) = rec.columns.iter_mut().find(|(n, _)| n == col).unwrap();
            c.iter_mut().for_each(|v| *v += b);
        }
    }
    for (i, (col, std)) in NOISE.iter().enumerate() {
        let (_, c) = rec.columns.iter_mut().find(|(n, _)| n == col).unwrap();
        *c = add_white_noise(c, *std, seed * 100 + i as u64);
    }
    rec
}

fn run(hidden: &[Hidden], seed: u64) -> Diagnosis {
    let _guard = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cfg = aircraft::load("c172x").unwrap();
    let mut gen = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    let train = measure(&mut gen, hidden, false, seed);
    let valid = measure(&mut gen, hidden, true, seed + 1);
    drop(gen);
    let mut workers: Vec<Worker> = (0..2)
        .map(|_| Worker::new(Box::new(JsbsimSim::start(&cfg, RATE_HZ).unwrap())))
        .collect();
    let d = diagnose(
        &mut workers,
        &train,
        Some(&valid),
        &DiagnoseOptions::default(),
    )
    .unwrap();
    eprintln!(
        "named: {}\nvalidation: {:?} -> {:?}; {} simulations, {:.1} s",
        serde_json::to_string(&d.named_cause).unwrap(),
        d.validation.as_ref().map(|v| v.ise_before),
        d.validation.as_ref().map(|v| v.ise_after),
        d.simulations,
        d.wall_s
    );
    let mut top: Vec<_> = d.candidates.iter().filter(|c| c.round == 0).collect();
    top.sort_by(|a, b| a.cost_after.total_cmp(&b.cost_after));
    for c in top.iter().take(6) {
        eprintln!(
            "  {}/{} = {:.4} ± {:.4}, dBIC {:.1}",
            c.effect, c.target, c.value, c.std_error, c.criterion_delta
        );
    }
    d
}

/// Named effect with value within 20 % of the truth, and a validation ISE at least halved.
fn assert_named(d: &Diagnosis, effect: &str, target: &str, truth: f64) {
    let c = d
        .named_cause
        .iter()
        .find(|c| c.effect == effect && c.target == target)
        .unwrap_or_else(|| panic!("{effect}/{target} not named; named: {:?}", d.named_cause));
    assert!(
        ((c.value - truth) / truth).abs() < 0.2,
        "{effect}/{target}: {} vs truth {truth} (20 % allowed)",
        c.value
    );
    let v = d.validation.as_ref().unwrap();
    assert!(
        v.ise_after <= 0.5 * v.ise_before,
        "validation ISE {} -> {} is not halved",
        v.ise_before,
        v.ise_after
    );
}

#[test]
fn clean_data_names_no_cause() {
    let d = run(&[], 11);
    assert!(d.named_cause.is_empty(), "named: {:?}", d.named_cause);
}

#[test]
fn pitch_stiffness_cm_alpha_25_percent_high_is_named() {
    let d = run(&[Hidden::Coefficient("Cmalpha", 1.25)], 21);
    assert_named(&d, "aero_derivative", "Cm_alpha", 1.25);
}

#[test]
fn elevator_delay_of_80_ms_is_named() {
    let d = run(&[Hidden::Delay("elevator", 0.08)], 31);
    assert_named(&d, "input_delay", "elevator", 0.08);
}

#[test]
fn q_gyro_bias_is_named() {
    let d = run(&[Hidden::Bias("q_rad_s", 0.02)], 41);
    assert_named(&d, "sensor_bias", "q_rad_s", 0.02);
}

#[test]
fn aileron_actuator_lag_of_100_ms_is_named() {
    let d = run(&[Hidden::Lag("aileron", 0.1)], 51);
    assert_named(&d, "actuator_lag", "aileron", 0.1);
}

#[test]
fn rudder_effectiveness_30_percent_low_is_named() {
    let d = run(&[Hidden::Effectiveness("rudder", 0.7)], 61);
    assert_named(&d, "control_effectiveness", "rudder", 0.7);
}

#[test]
fn directional_stability_cn_beta_40_percent_high_is_named() {
    let d = run(&[Hidden::Coefficient("Cnb", 1.4)], 71);
    assert_named(&d, "aero_derivative", "Cn_beta", 1.4);
}

#[test]
fn two_effects_at_once_are_both_named() {
    // A roll-damping error and a pitch-gyro bias in the same record: forward selection must find both.
    let d = run(
        &[
            Hidden::Coefficient("Clp", 0.7),
            Hidden::Bias("theta_rad", 0.03),
        ],
        81,
    );
    assert_named(&d, "aero_derivative", "Cl_p", 0.7);
    assert_named(&d, "sensor_bias", "theta_rad", 0.03);
}
