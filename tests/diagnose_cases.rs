//! Diagnose names hidden effects. "Measured" data are generated with JSBSim itself with one
//! effect hidden — a modified coefficient, a delayed/lagged/scaled surface, a biased sensor — whose size is a
//! seeded random draw (uniform over a physically sensible range, both directions where both exist), plus the noise
//! of a small-aircraft sensor suite. Each case has one training and one validation maneuver, each exciting all
//! three axes. `diagnose` must name exactly the hidden effect(s) (effect and target), recover the value within
//! 20 % and at least halve the validation ISE; on clean data it must name nothing.
//!
//! The 20 % tolerance is the issue's; with this noise the estimates land within ~2 % (sandwich standard errors
//! of 0.5–1 %), so a failure means a wrong structure, not bad luck of the draw.

use flightid::aircraft;
use flightid::data::FlightRecord;
use flightid::diagnose::search::Worker;
use flightid::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use flightid::signal::{add_white_noise, generate, Maneuver};
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};
use rand::{rngs::StdRng, Rng, SeedableRng};

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
#[derive(Clone, Debug)]
enum Hidden {
    /// Factor on a JSBSim coefficient function (knob name).
    Coefficient(&'static str, f64),
    /// Surface delay, s (a whole number of samples).
    Delay(&'static str, f64),
    /// First-order surface lag, s.
    Lag(&'static str, f64),
    /// Factor on a surface deflection.
    Effectiveness(&'static str, f64),
    /// Additive sensor bias on a column.
    Bias(&'static str, f64),
    /// An added aerodynamic term the stock model lacks (e.g. `Cm_alpha2`: ΔC_m = k α²).
    Added(&'static str, f64),
}

/// Input shapes: step-like (3211 and doublets, staggered per axis) or multisines on all three axes at once.
#[derive(Clone, Copy, PartialEq)]
enum Shape {
    Steps,
    Multisine,
}

/// A seeded draw: magnitude uniform in `[lo, hi]`, sign random when `both_ways`.
fn draw(rng: &mut StdRng, lo: f64, hi: f64, both_ways: bool) -> f64 {
    let m = rng.gen_range(lo..hi);
    if both_ways && rng.gen_bool(0.5) {
        -m
    } else {
        m
    }
}

/// Training and validation maneuvers: different shapes, amplitudes and timing; each moves all three surfaces.
fn inputs(shape: Shape, validation: bool) -> Vec<(&'static str, Vec<f64>)> {
    let dt = 1.0 / RATE_HZ;
    let n = (DURATION_S * RATE_HZ).round() as usize;
    let gen = |m: Maneuver, amp: f64, start: f64| -> Vec<f64> {
        generate(&m, dt, DURATION_S, start)
            .into_iter()
            .take(n)
            .map(|v| amp * v)
            .collect()
    };
    let ms =
        |f_min_hz: f64, f_max_hz: f64, n_harmonics: usize, period_s: f64| Maneuver::Multisine {
            f_min_hz,
            f_max_hz,
            n_harmonics,
            period_s,
        };
    match (shape, validation) {
        (Shape::Steps, false) => vec![
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
        ],
        (Shape::Steps, true) => vec![
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
        ],
        (Shape::Multisine, false) => vec![
            ("elevator", gen(ms(0.2, 1.5, 6, 10.0), 0.02, 1.0)),
            ("aileron", gen(ms(0.15, 1.2, 5, 12.0), 0.03, 1.0)),
            ("rudder", gen(ms(0.1, 1.0, 5, 14.0), 0.03, 1.0)),
        ],
        (Shape::Multisine, true) => vec![
            ("elevator", gen(ms(0.25, 1.2, 5, 8.0), 0.02, 1.0)),
            ("aileron", gen(ms(0.1, 1.0, 5, 14.0), 0.03, 1.0)),
            ("rudder", gen(ms(0.15, 1.2, 5, 10.0), 0.03, 1.0)),
        ],
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
fn measure(
    sim: &mut JsbsimSim,
    hidden: &[Hidden],
    shape: Shape,
    validation: bool,
    seed: u64,
) -> FlightRecord {
    for name in sim.coefficient_knobs.clone() {
        sim.set_coefficient_scale(&name, 1.0).unwrap();
    }
    for name in sim.added_terms.clone() {
        sim.set_added_term(&name, 0.0).unwrap();
    }
    for h in hidden {
        if let Hidden::Coefficient(c, f) = h {
            sim.set_coefficient_scale(c, *f).unwrap();
        }
        if let Hidden::Added(t, k) = h {
            sim.set_added_term(t, *k).unwrap();
        }
    }
    let trim = sim.trim(&TrimPoint::level(4000.0, 100.0)).unwrap();
    let measured = inputs(shape, validation);
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

fn run(hidden: &[Hidden], shape: Shape, seed: u64) -> Diagnosis {
    let cfg = aircraft::load("c172x").unwrap();
    let mut gen = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    let train = measure(&mut gen, hidden, shape, false, seed);
    let valid = measure(&mut gen, hidden, shape, true, seed + 1);
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
    let mut log = format!(
        "hidden: {hidden:?}\nnamed: {}\nvalidation ISE: {:?} -> {:?}; {} simulations, {:.1} s\n",
        serde_json::to_string(&d.named_cause).unwrap(),
        d.validation.as_ref().map(|v| v.ise_before),
        d.validation.as_ref().map(|v| v.ise_after),
        d.simulations,
        d.wall_s
    );
    let mut full: Vec<_> = d.candidates.iter().filter(|c| c.full_fit).collect();
    full.sort_by_key(|c| c.round);
    for c in full {
        log += &format!(
            "  round {} {}/{} = {:.4} ± {:.4}, ΔBIC {:.1}, z {:.1}, n_eff {:.0}, validation gain {:?}, rejected: {:?}\n",
            c.round,
            c.effect,
            c.target,
            c.value,
            c.std_error,
            c.criterion_delta,
            c.z,
            c.n_eff,
            c.validation_gain,
            c.rejected_because
        );
    }
    eprint!("{log}");
    d
}

/// Exactly the expected effects are named, each within 20 % of the truth, and the validation ISE is at least halved.
fn assert_named(d: &Diagnosis, expected: &[(&str, &str, f64)]) {
    assert_eq!(
        d.named_cause.len(),
        expected.len(),
        "expected {expected:?}, named {:?}",
        d.named_cause
    );
    for (effect, target, truth) in expected {
        let c = d
            .named_cause
            .iter()
            .find(|c| c.effect == *effect && c.target == *target)
            .unwrap_or_else(|| panic!("{effect}/{target} not named; named: {:?}", d.named_cause));
        assert!(
            ((c.value - truth) / truth).abs() < 0.2,
            "{effect}/{target}: {} vs truth {truth} (20 % allowed)",
            c.value
        );
    }
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
    let d = run(&[], Shape::Steps, 11);
    assert!(d.named_cause.is_empty(), "named: {:?}", d.named_cause);
}

#[test]
fn pitch_stiffness_cm_alpha_error_is_named() {
    let mut rng = StdRng::seed_from_u64(21);
    let f = 1.0 + draw(&mut rng, 0.2, 0.4, true);
    let d = run(&[Hidden::Coefficient("Cmalpha", f)], Shape::Steps, 21);
    assert_named(&d, &[("aero_derivative", "Cm_alpha", f)]);
}

#[test]
fn elevator_delay_is_named() {
    // 3..7 samples at 50 Hz: 60–140 ms.
    let mut rng = StdRng::seed_from_u64(31);
    let tau = rng.gen_range(3..=7) as f64 / RATE_HZ;
    let d = run(&[Hidden::Delay("elevator", tau)], Shape::Steps, 31);
    assert_named(&d, &[("input_delay", "elevator", tau)]);
}

#[test]
fn q_gyro_bias_is_named() {
    let mut rng = StdRng::seed_from_u64(41);
    let b = draw(&mut rng, 0.01, 0.03, true);
    let d = run(&[Hidden::Bias("q_rad_s", b)], Shape::Steps, 41);
    assert_named(&d, &[("sensor_bias", "q_rad_s", b)]);
}

#[test]
fn aileron_actuator_lag_is_named() {
    let mut rng = StdRng::seed_from_u64(51);
    let tau = rng.gen_range(0.06..0.2);
    let d = run(&[Hidden::Lag("aileron", tau)], Shape::Steps, 51);
    assert_named(&d, &[("actuator_lag", "aileron", tau)]);
}

#[test]
fn rudder_effectiveness_error_is_named() {
    let mut rng = StdRng::seed_from_u64(61);
    let k = 1.0 + draw(&mut rng, 0.2, 0.4, true);
    let d = run(&[Hidden::Effectiveness("rudder", k)], Shape::Steps, 61);
    assert_named(&d, &[("control_effectiveness", "rudder", k)]);
}

#[test]
fn directional_stability_cn_beta_error_is_named() {
    let mut rng = StdRng::seed_from_u64(71);
    let f = 1.0 + draw(&mut rng, 0.25, 0.45, true);
    let d = run(&[Hidden::Coefficient("Cnb", f)], Shape::Steps, 71);
    assert_named(&d, &[("aero_derivative", "Cn_beta", f)]);
}

#[test]
fn dihedral_effect_cl_beta_error_is_named_from_multisines() {
    // Generalisation: another lateral derivative, and multisines on all axes instead of steps.
    let mut rng = StdRng::seed_from_u64(91);
    let f = 1.0 + draw(&mut rng, 0.25, 0.45, true);
    let d = run(&[Hidden::Coefficient("Clb", f)], Shape::Multisine, 91);
    assert_named(&d, &[("aero_derivative", "Cl_beta", f)]);
}

#[test]
fn two_effects_at_once_are_both_named() {
    // A roll-damping error and a pitch-attitude bias in the same record: forward selection must find both,
    // and nothing else.
    let mut rng = StdRng::seed_from_u64(81);
    let f = 1.0 + draw(&mut rng, 0.2, 0.35, true);
    let b = draw(&mut rng, 0.015, 0.04, true);
    let d = run(
        &[Hidden::Coefficient("Clp", f), Hidden::Bias("theta_rad", b)],
        Shape::Steps,
        81,
    );
    assert_named(
        &d,
        &[
            ("aero_derivative", "Cl_p", f),
            ("sensor_bias", "theta_rad", b),
        ],
    );
}

#[test]
fn hidden_pitch_nonlinearity_cm_alpha2_is_named() {
    // Generalisation beyond derivative scales: the data come from an aircraft with ΔC_m = k α² added, |k| in
    // 3..8 (at α = 0.1 rad a ΔC_m of 0.03–0.08, a 15–40 % change of the local pitch stiffness).
    let mut rng = StdRng::seed_from_u64(101);
    let k = draw(&mut rng, 3.0, 8.0, true);
    let d = run(&[Hidden::Added("Cm_alpha2", k)], Shape::Steps, 101);
    assert_named(&d, &[("aero_nonlinearity", "Cm_alpha2", k)]);
}
