//! `diagnose` on a 60 s record at 50 Hz with the full c172x catalogue, two JSBSim workers
//! (target: under 5 s wall on 2 cores). The record hides an 80 ms elevator delay and carries noise. It is
//! diagnosed twice: replayed at its own rate (50 Hz), and at the rate `flightid diagnose` uses by default.
//!
//! Run: `cargo bench --bench diagnose`.

use flightid::aircraft;
use flightid::diagnose::search::Worker;
use flightid::diagnose::{diagnose, replay::ReplayCase, DiagnoseOptions};
use flightid::signal::{add_white_noise, generate, Maneuver};
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};
use std::time::Instant;

const RATE_HZ: f64 = 50.0;

fn record(sim: &mut JsbsimSim, seed: u64) -> flightid::data::FlightRecord {
    let dt = 1.0 / RATE_HZ;
    let n = (60.0 * RATE_HZ) as usize;
    let gen = |m: Maneuver, amp: f64, start: f64| -> Vec<f64> {
        generate(&m, dt, 60.0, start)
            .into_iter()
            .take(n)
            .map(|v| amp * v)
            .collect()
    };
    let measured = [
        (
            "elevator",
            gen(Maneuver::ThreeTwoOneOne { pulse_s: 0.5 }, 0.03, 2.0),
        ),
        (
            "aileron",
            gen(Maneuver::Doublet { pulse_s: 1.0 }, 0.05, 20.0),
        ),
        (
            "rudder",
            gen(Maneuver::Doublet { pulse_s: 1.0 }, 0.05, 40.0),
        ),
    ];
    let trim = sim.trim(&TrimPoint::level(4000.0, 100.0)).unwrap();
    let delay = 4; // samples = 80 ms on the elevator
    let plan = FlightPlan {
        rate_hz: RATE_HZ,
        n_steps: n,
        inputs: measured
            .iter()
            .map(|(s, u)| SurfaceInput {
                surface: s.to_string(),
                deflection_rad: if *s == "elevator" {
                    (0..n)
                        .map(|k| if k >= delay { u[k - delay] } else { 0.0 })
                        .collect()
                } else {
                    u.clone()
                },
            })
            .collect(),
    };
    let mut rec = sim.fly(&plan).unwrap();
    for (s, u) in &measured {
        let base = trim.surfaces_rad[*s];
        let col: Vec<f64> = std::iter::once(base)
            .chain(u.iter().map(|v| base + v))
            .collect();
        rec.columns
            .iter_mut()
            .find(|(c, _)| *c == format!("{s}_rad"))
            .unwrap()
            .1 = col;
    }
    for (i, (_, c)) in rec.columns.iter_mut().enumerate() {
        if !c.is_empty() && i > 3 {
            *c = add_white_noise(c, 0.002, seed + i as u64);
        }
    }
    rec
}

fn main() {
    let cfg = aircraft::load("c172x").unwrap();
    let mut gen = JsbsimSim::start(&cfg, RATE_HZ).unwrap();
    let train = record(&mut gen, 1);
    let valid = record(&mut gen, 2);
    drop(gen);
    // At the record's rate (the convention of `fly`, which made the record), then at the rate `flightid diagnose`
    // integrates a 50 Hz record at by default (ReplayCase::sim_rate_hz).
    let default_rate = ReplayCase::new(&train).unwrap().sim_rate_hz();
    for rate in [RATE_HZ, default_rate] {
        let t0 = Instant::now();
        let mut workers: Vec<Worker> = (0..2)
            .map(|_| Worker::new(Box::new(JsbsimSim::start(&cfg, rate).unwrap())))
            .collect();
        let d = diagnose(
            &mut workers,
            &train,
            Some(&valid),
            &DiagnoseOptions {
                progress: false,
                ..Default::default()
            },
        )
        .unwrap();
        let wall = t0.elapsed().as_secs_f64();
        println!(
            "diagnose 60 s @ 50 Hz replayed at {rate:.0} Hz, full c172x catalogue, 2 workers: {wall:.1} s wall, {} \
             simulations, {:.1} simulations/s, {:.0} % of the workers' time inside JSBSim (target < 5 s)",
            d.simulations,
            d.simulations as f64 / wall,
            100.0 * d.simulation_s / (2.0 * wall)
        );
        for c in &d.named_cause {
            println!(
                "  named {}/{} = {:.5} ± {:.5}",
                c.effect, c.target, c.value, c.std_error
            );
        }
    }
}
