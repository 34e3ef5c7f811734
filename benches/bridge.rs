//! Bridge overhead: flying a 60 s maneuver at 120 Hz through flightid vs the same steps in a bare Python loop
//! over `fdm.run()` with the same property reads (`scripts/bench_bare_loop.py`), measured in one run; and the
//! cold start of `flightid trim` with the environment already provisioned.
//!
//! Run: `cargo bench --bench bridge`. Targets: ratio <= 1.15, cold start < 0.5 s.

use flightid::aircraft;
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};
use std::process::Command;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let repeats = 7;
    let n_steps = 7200;
    let cfg = aircraft::load("c172x").unwrap();
    let point = TrimPoint::level(4000.0, 100.0);
    let mut sim = JsbsimSim::start(&cfg, 120.0).unwrap();
    let unit = flightid::signal::generate(
        &flightid::signal::Maneuver::Doublet { pulse_s: 1.0 },
        1.0 / 120.0,
        60.0,
        1.0,
    );
    let plan = FlightPlan {
        rate_hz: 120.0,
        n_steps,
        inputs: vec![SurfaceInput {
            surface: "elevator".into(),
            deflection_rad: unit[..n_steps].iter().map(|u| 0.03 * u).collect(),
        }],
    };
    let mut ours = Vec::new();
    for _ in 0..repeats {
        sim.trim(&point).unwrap();
        let t0 = Instant::now();
        let rec = sim.fly(&plan).unwrap();
        ours.push(t0.elapsed().as_secs_f64());
        assert_eq!(rec.len(), n_steps + 1);
    }
    let py = flightid::sim::env::python().unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/bench_bare_loop.py");
    let out = Command::new(py)
        .args([
            script,
            "c172x",
            "4000",
            "100",
            &n_steps.to_string(),
            &repeats.to_string(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bare: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let bare: Vec<f64> = serde_json::from_value(bare["loop_s"].clone()).unwrap();
    let (o, b) = (median(ours), median(bare));
    println!("fly 60 s @120 Hz through flightid (request to FlightRecord): median {:.1} ms over {repeats}", o * 1e3);
    println!(
        "bare Python loop, same steps and property reads:           median {:.1} ms over {repeats}",
        b * 1e3
    );
    println!("ratio flightid / bare = {:.3}  (target <= 1.15)", o / b);

    let exe = env!("CARGO_MANIFEST_DIR").to_string() + "/target/release/flightid";
    if std::path::Path::new(&exe).exists() {
        let mut cold = Vec::new();
        for _ in 0..5 {
            let t0 = Instant::now();
            let st = Command::new(&exe)
                .args(["trim", "--aircraft", "c172x", "--json"])
                .output()
                .unwrap();
            assert!(st.status.success());
            cold.push(t0.elapsed().as_secs_f64());
        }
        println!(
            "cold start `flightid trim --aircraft c172x`: median {:.0} ms over 5 (target < 500 ms)",
            median(cold) * 1e3
        );
    } else {
        println!("(build the release binary first to time the cold start: cargo build --release)");
    }
}
