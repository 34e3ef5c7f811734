//! The extended model on disk: an aircraft exported with fitted coefficient factors and added terms written into
//! its XML must fly exactly like the original aircraft with the same factors set through knobs, and a model
//! directory must carry the signal-path effects that do not belong in the XML.

use flightid::aircraft;
use flightid::diagnose::extension::{ExtensionFile, FittedEffect};
use flightid::diagnose::model::{write_model, ExtendedModel};
use flightid::diagnose::replay::circular_mean;
use flightid::signal::{generate, Maneuver};
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};

const RATE_HZ: f64 = 50.0;

fn plan() -> FlightPlan {
    let n = 400;
    let u = |m: Maneuver, amp: f64, start: f64| -> Vec<f64> {
        generate(&m, 1.0 / RATE_HZ, 8.0, start)
            .into_iter()
            .take(n)
            .map(|v| amp * v)
            .collect()
    };
    FlightPlan {
        rate_hz: RATE_HZ,
        n_steps: n,
        inputs: vec![
            SurfaceInput {
                surface: "elevator".into(),
                deflection_rad: u(Maneuver::Doublet { pulse_s: 0.8 }, 0.04, 0.5),
            },
            SurfaceInput {
                surface: "aileron".into(),
                deflection_rad: u(Maneuver::Doublet { pulse_s: 1.0 }, 0.05, 3.0),
            },
        ],
    }
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn exported_aircraft_flies_like_the_knobs_it_was_exported_from() {
    // Scenario: Cm_alpha ×0.8, Cl_p ×1.3 and an added ΔC_m = −4 α², set through knobs, then exported. The
    // exported XML, loaded without any knob, must give the same trim and response: the factors are exact
    // numbers in the XML, so agreement is at round-off (1e-9 rad, 1e-6 m/s after 8 s).
    let cfg = aircraft::load("c172x").unwrap();
    let point = TrimPoint::level(4000.0, 100.0);
    let mut knobbed = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    assert!(knobbed.added_terms.iter().any(|t| t == "Cm_alpha2"));
    knobbed.set_coefficient_scale("Cmalpha", 0.8).unwrap();
    knobbed.set_coefficient_scale("Clp", 1.3).unwrap();
    knobbed.set_added_term("Cm_alpha2", -4.0).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let xml = knobbed.export_aircraft(dir.path()).unwrap();
    let text = std::fs::read_to_string(&xml).unwrap();
    assert!(
        text.contains("flightid/fitted/Cm_alpha2-term"),
        "added term missing"
    );
    let t1 = knobbed.trim(&point).unwrap();
    let r1 = knobbed.fly(&plan()).unwrap();

    let mut exported = JsbsimSim::start_with_model(&cfg, RATE_HZ, Some(dir.path())).unwrap();
    let t2 = exported.trim(&point).unwrap();
    let r2 = exported.fly(&plan()).unwrap();
    assert!((t1.alpha_rad - t2.alpha_rad).abs() < 1e-9);
    assert!((t1.surfaces_rad["elevator"] - t2.surfaces_rad["elevator"]).abs() < 1e-9);
    for (c, tol) in [("q_rad_s", 1e-9), ("p_rad_s", 1e-9), ("airspeed_m_s", 1e-6)] {
        let d = max_abs_diff(r1.column(c).unwrap(), r2.column(c).unwrap());
        assert!(d < tol, "{c}: exported model differs by {d}");
    }

    // And the stock aircraft differs (the test can fail): the trim elevator moves with Cm_alpha and α².
    let mut stock = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    let t0 = stock.trim(&point).unwrap();
    assert!((t0.surfaces_rad["elevator"] - t1.surfaces_rad["elevator"]).abs() > 1e-4);
}

#[test]
fn model_directory_keeps_signal_path_effects_outside_the_xml() {
    // A diagnosis with a Cm_alpha factor and an elevator delay: the factor goes into the XML, the delay into
    // extension.json; reading the directory back yields only the delay as an effect to apply.
    let cfg = aircraft::load("c172x").unwrap();
    let mut sim = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    let file = ExtensionFile {
        aircraft: "c172x".into(),
        effects: vec![
            FittedEffect {
                effect: "aero_derivative".into(),
                target: "Cm_alpha".into(),
                value: 0.75,
                std_error: 0.001,
            },
            FittedEffect {
                effect: "input_delay".into(),
                target: "elevator".into(),
                value: 0.08,
                std_error: 0.0003,
            },
        ],
        model_effects: vec![],
        notes: Default::default(),
        properties: Default::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    write_model(&mut sim, &file, dir.path()).unwrap();
    let m = ExtendedModel::read(dir.path()).unwrap();
    assert_eq!(m.extension.effects.len(), 1);
    assert_eq!(m.extension.effects[0].effect, "input_delay");
    assert_eq!(m.extension.model_effects[0].target, "Cm_alpha");
    let effects = m.effects(&sim.coefficient_knobs).unwrap();
    assert_eq!(effects.len(), 1);
    let xml = std::fs::read_to_string(dir.path().join("c172x.xml")).unwrap();
    assert!(xml.contains("<value>0.75</value>"), "factor not in the XML");
}

#[test]
fn initial_heading_is_the_circular_mean_across_north() {
    // Samples at 359.9° and 0.1°: the arithmetic mean says 180°, the true heading is 0°.
    let psi = [
        359.9_f64.to_radians(),
        0.1_f64.to_radians(),
        359.8_f64.to_radians(),
        0.2_f64.to_radians(),
    ];
    let m = circular_mean(&psi);
    assert!(m.abs() < 1e-9, "circular mean {m} rad");
}
