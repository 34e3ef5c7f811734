//! `diagnose` on a 60 s record at 50 Hz with the full c172x catalogue, two JSBSim workers
//! (target: under 5 s wall on 2 cores). The record hides an 80 ms elevator delay and carries noise. It is
//! diagnosed twice: replayed at its own rate (50 Hz), and at the rate `flightid diagnose` uses by default.
//!
//! The record is flown at 200 Hz and logged at 50 Hz, its surfaces moving linearly between the logged samples
//! (the convention the replay declares), so that a replay at 200 Hz differs from it by the hidden delay and the
//! noise only. `--flown-at 50` flies it at 50 Hz instead (the record of the earlier figures in docs/diagnose.md:
//! JSBSim's integration at 50 Hz then differs from the 200 Hz replay by more than the delay, and the search
//! names passengers).
//!
//! Run: `cargo bench --bench diagnose [-- --flown-at HZ]`.

use flightid::aircraft;
use flightid::diagnose::workers::{start_workers, SimSource};
use flightid::diagnose::{diagnose, replay::ReplayCase, DiagnoseOptions};
use flightid::signal::{add_white_noise, generate, Maneuver};
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};
use std::time::Instant;

/// Logging rate of the record, Hz.
const RATE_HZ: f64 = 50.0;
/// Record length, s.
const DURATION_S: f64 = 60.0;
/// The hidden elevator delay, s.
const DELAY_S: f64 = 0.08;

/// A 60 s record flown at `flown_hz` (a whole multiple of [`RATE_HZ`]) and logged at [`RATE_HZ`], with white
/// noise (seeded) on every channel but the surfaces and the throttle.
fn record(sim: &mut JsbsimSim, flown_hz: f64, seed: u64) -> flightid::data::FlightRecord {
    let dt = 1.0 / RATE_HZ;
    let n = (DURATION_S * RATE_HZ) as usize;
    let m = (flown_hz / RATE_HZ).round() as usize;
    let gen = |mv: Maneuver, amp: f64, start: f64| -> Vec<f64> {
        generate(&mv, dt, DURATION_S, start)
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
    let delay_steps = (DELAY_S * flown_hz).round() as usize;
    // Logged sample k + 1 is u[k]; the surface moves linearly from one logged sample to the next over the m
    // integration steps in between (the step ending at a logged sample reads that sample).
    let fine = |u: &[f64]| -> Vec<f64> {
        let at = |k: usize| if k == 0 { 0.0 } else { u[k - 1] };
        (0..n * m)
            .map(|s| {
                let (k, f) = (s / m, (s % m + 1) as f64 / m as f64);
                (1.0 - f) * at(k) + f * at(k + 1)
            })
            .collect()
    };
    let plan = FlightPlan {
        rate_hz: flown_hz,
        n_steps: n * m,
        inputs: measured
            .iter()
            .map(|(s, u)| {
                let f = fine(u);
                SurfaceInput {
                    surface: s.to_string(),
                    deflection_rad: if *s == "elevator" {
                        (0..f.len())
                            .map(|k| {
                                if k >= delay_steps {
                                    f[k - delay_steps]
                                } else {
                                    0.0
                                }
                            })
                            .collect()
                    } else {
                        f
                    },
                }
            })
            .collect(),
    };
    let mut rec = sim.fly(&plan).unwrap().every_nth(m);
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

/// CPU time of this process and of its children that have ended (the bridges), s, from /proc/self/stat
/// (utime + stime, cutime + cstime; clock ticks of 1/100 s). Zero where /proc is missing.
fn cpu_s() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // the fields after the command name in parentheses (which may hold spaces)
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    let tick = |i: usize| f.get(i).copied().unwrap_or(0.0) / 100.0;
    // fields 14-17 of proc(5) are utime, stime, cutime, cstime: indices 11-14 after the state field
    (tick(11) + tick(12), tick(13) + tick(14))
}

/// `--flown-at HZ` (default 200).
fn flown_at_hz() -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == "--flown-at")
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(200.0)
}

fn main() {
    let cfg = aircraft::load("c172x").unwrap();
    let flown_hz = flown_at_hz();
    let mut gen = JsbsimSim::start(&cfg, flown_hz).unwrap();
    let train = record(&mut gen, flown_hz, 1);
    let valid = record(&mut gen, flown_hz, 2);
    drop(gen);
    // At the record's rate (the convention of `fly`, which made the record), then at the rate `flightid diagnose`
    // integrates a 50 Hz record at by default (ReplayCase::sim_rate_hz).
    let default_rate = ReplayCase::new(&train).unwrap().sim_rate_hz();
    for rate in [RATE_HZ, default_rate] {
        // The machine's load shares the 2 cores: print it with the figures.
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        println!(
            "load average (1, 5, 15 min): {}",
            load.split_whitespace()
                .take(3)
                .collect::<Vec<_>>()
                .join(" ")
        );
        let (cpu0, bridges_cpu0) = cpu_s();
        let t0 = Instant::now();
        // started as `flightid diagnose` starts them (in parallel)
        let mut workers = start_workers(&SimSource::Aircraft(&cfg.name, &[]), rate, 2).unwrap();
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
        drop(workers); // the bridge processes end and are waited for: their CPU time is counted
        let (cpu1, bridges_cpu1) = cpu_s();
        println!(
            "diagnose 60 s @ 50 Hz (flown at {flown_hz:.0} Hz) replayed at {rate:.0} Hz, full c172x catalogue, 2 workers: {wall:.1} s wall, {} \
             simulations, {:.1} simulations/s, {:.0} % of the workers' time inside JSBSim{}",
            d.simulations,
            d.simulations as f64 / wall,
            100.0 * d.simulation_s / (2.0 * wall),
            if rate == default_rate {
                " (target < 5 s at idle)"
            } else {
                " (for comparison: integrated at the record's own rate, uncorrected)"
            }
        );
        println!(
            "  CPU: {:.1} s in the JSBSim bridge processes, {:.1} s in flightid (2 cores: the wall time at idle is \
             at least half their sum)",
            bridges_cpu1 - bridges_cpu0,
            cpu1 - cpu0
        );
        println!("  stages (wall s, simulations):");
        for st in &d.stages {
            println!(
                "    {:<28} {:>6.2} s {:>4}",
                st.stage, st.wall_s, st.simulations
            );
        }
        if let Some(r) = &d.replay_rate {
            println!(
                "  integration rate chosen: {} Hz (rate, cost tried: {:?})",
                r.rate_hz, r.tried
            );
        }
        for c in &d.named_cause {
            println!(
                "  named {}/{} = {:.5} ± {:.5}",
                c.effect, c.target, c.value, c.std_error
            );
        }
    }
}
