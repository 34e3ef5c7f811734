//! Aerodynamic derivatives from real JSBSim c172x doublet flights, scored against the model's own values.

use flightid::aero::score::{score_equation_error, score_tf_fit, table1, table3};
use flightid::aero::spec::{model_from_truth, truth_derivatives, Structure};
use flightid::aero::trials::{
    equation_error_on, fly_doublets, identify_paper_tfs, SensorNoise, TrialOptions,
};
use flightid::aero::{estimate_derivatives, Derivative as D, FitOptions};
use flightid::aircraft;
use flightid::sim::{JsbsimSim, Simulator, TrimPoint};

#[test]
fn explore() {
    let opts = TrialOptions::default();
    let mut sim = JsbsimSim::start(&aircraft::load("c172x").unwrap(), opts.rate_hz).unwrap();
    let point = TrimPoint::level(4000.0, 100.0);
    sim.trim(&point).unwrap();
    let truth = sim.aero_truth().unwrap();
    for (noise, method) in [
        (None, flightid::ident::Method::Srivc),
        (None, flightid::ident::Method::Oe),
        (
            Some(SensorNoise::realistic()),
            flightid::ident::Method::Srivc,
        ),
    ] {
        let opts = TrialOptions {
            noise,
            method,
            ..TrialOptions::default()
        };
        let flights = fly_doublets(&mut sim, &point, &opts).unwrap();
        let (tfs, results) = identify_paper_tfs(&flights, &opts).unwrap();
        for (o, r) in &results {
            println!(
                "{} fit {:.2} num {:?} den {:?}",
                o.label(),
                r.fit_sim_percent,
                r.tf.num,
                r.tf.den
            );
        }
        for structure in [Structure::Paper, Structure::Full] {
            let model = model_from_truth(&truth, structure.assumptions()).unwrap();
            let mut prior = model.clone();
            let free: Vec<D> = vec![
                D::Cmalpha,
                D::Cmq,
                D::Cmalphadot,
                D::Cmde,
                D::Clp,
                D::Clda,
                D::Clbeta,
                D::Cnbeta,
                D::Cnr,
            ];
            for &d in &free {
                prior.derivatives.set(d, 1.2 * model.derivatives.get(d));
            }
            let mut tfs = tfs.clone();
            tfs.tfs
                .retain(|(o, _)| *o != flightid::aero::TfOutput::PHI_RUDDER);
            let est = estimate_derivatives(&prior, &tfs, &free, FitOptions::default()).unwrap();
            let card = score_tf_fit(&est, &model.derivatives, structure);

            for r in &card.rows {
                println!(
                    "{:<18} {:>9.4} {:>9.4} {:>8.1}% {:?} {}",
                    r.name, r.truth, r.estimate, r.error_percent, r.covered_3sigma, r.verdict
                );
            }
        }
        let ee = flightid::aero::trials::equation_error_flights(&flights, &truth).unwrap();
        let model = model_from_truth(&truth, Structure::Full.assumptions()).unwrap();
        let card = score_equation_error(&[&ee], &truth_derivatives(&truth), &model);
        for r in &card.rows {
            println!(
                "{:<18} {:>9.4} {:>9.4} {:>8.1}% {:?} {}",
                r.name, r.truth, r.estimate, r.error_percent, r.covered_3sigma, r.verdict
            );
        }
    }
}

#[test]
fn explore_noise() {
    let opts = TrialOptions::default();
    let mut sim = JsbsimSim::start(&aircraft::load("c172x").unwrap(), opts.rate_hz).unwrap();
    let point = TrimPoint::level(4000.0, 100.0);
    sim.trim(&point).unwrap();
    let truth = sim.aero_truth().unwrap();
    let z = SensorNoise {
        flow_angle_rad: 0.0,
        attitude_rad: 0.0,
        rate_rad_s: 0.0,
        airspeed_m_s: 0.0,
        surface_rad: 0.0,
        accel_m_s2: 0.0,
    };
    let r = SensorNoise::realistic();
    for (label, noise) in [
        (
            "flow",
            SensorNoise {
                flow_angle_rad: r.flow_angle_rad,
                ..z
            },
        ),
        (
            "att",
            SensorNoise {
                attitude_rad: r.attitude_rad,
                ..z
            },
        ),
        (
            "rate",
            SensorNoise {
                rate_rad_s: r.rate_rad_s,
                ..z
            },
        ),
        (
            "v",
            SensorNoise {
                airspeed_m_s: r.airspeed_m_s,
                ..z
            },
        ),
        (
            "surf",
            SensorNoise {
                surface_rad: r.surface_rad,
                ..z
            },
        ),
        (
            "acc",
            SensorNoise {
                accel_m_s2: r.accel_m_s2,
                ..z
            },
        ),
        ("all", r),
    ] {
        let opts = TrialOptions {
            noise: Some(noise),
            ..TrialOptions::default()
        };
        let flights = fly_doublets(&mut sim, &point, &opts).unwrap();
        let lat = equation_error_on(&flights.lateral, &truth).unwrap();
        let model = model_from_truth(&truth, Structure::Full.assumptions()).unwrap();
        let card = score_equation_error(&[&lat], &truth_derivatives(&truth), &model);
        let r = card.row("Cl_p").unwrap();
        println!("{label}: Cl_p {:.1}% ", r.error_percent);
    }
}
