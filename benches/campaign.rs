//! Campaign throughput on two campaigns: the example `campaigns/c172x_737.toml` (36 short cases:
//! 20 s at 60 Hz) and `campaigns/throughput.toml` (24 flight-test-length cases: 60 s at 120 Hz), each with 1 and
//! 2 jobs, against the bare JSBSim stepping time of the same flights (the `fly` calls only: same steps, same
//! recorded properties; trims, process starts and identification excluded and reported beside it).
//!
//! Run: `cargo bench --bench campaign` (`-- c172x_737` or `-- throughput` for one campaign). Prints wall-clock
//! and CPU seconds; a plain `main` (harness = false) because each measurement takes seconds and runs once.

use flightid::campaign::{run_campaign, CampaignSpec, RunOptions};
use flightid::compare::{paper_options, perturbations, single_surface_plan};
use flightid::ident::identify;
use flightid::sim::{JsbsimSim, Simulator, TrimPoint};
use std::path::Path;
use std::time::Instant;

/// CPU seconds of this process and its reaped children (the JSBSim bridges), from /proc/self/stat: a figure
/// that, unlike wall-clock time, does not depend on what else the machine runs.
fn tree_cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    let ticks = std::process::Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(100.0);
    // fields 14-17 of stat (utime, stime, cutime, cstime) are 11-14 after the command name
    f.get(11..15)
        .map(|v| v.iter().sum::<f64>())
        .unwrap_or(f64::NAN)
        / ticks
}

fn main() {
    let only: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    for name in ["c172x_737", "throughput"] {
        if only.is_empty() || only.iter().any(|o| o == name) {
            bench_campaign(name);
        }
    }
}

/// Profile by phase, then the campaign with 1 and 2 jobs (reused processes), for `campaigns/NAME.toml`.
fn bench_campaign(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("campaigns/{name}.toml"));
    let spec = CampaignSpec::load(&path).expect("campaign file");
    let cases = spec.cases();
    println!(
        "== campaign {name}: {} cases of {} s at {} Hz, methods {} ==",
        cases.len(),
        spec.duration_s,
        spec.rate_hz,
        spec.methods.join("+")
    );

    // Bare stepping: one process per aircraft, time only the fly() calls (trims excluded): the campaign's own
    // flights (same configurations, steps and recorded properties). The same loop also
    // times what a campaign adds on top: process starts, trims and the identifications (a profile by phase).
    let methods = spec.parsed_methods().unwrap();
    let mut fly_s = 0.0;
    let mut trim_s = 0.0;
    let mut start_s = 0.0;
    let mut ident_by_method_s = vec![0.0; methods.len()];
    // (aircraft, fly s, identification s) per aircraft: how evenly the work splits between workers
    let mut by_aircraft: Vec<(String, f64, f64)> = Vec::new();
    let cpu0 = tree_cpu_s();
    let mut current: Option<(String, JsbsimSim)> = None;
    for c in &cases {
        if current
            .as_ref()
            .map(|(a, _)| a != &c.aircraft)
            .unwrap_or(true)
        {
            let cfg = flightid::aircraft::load(&c.aircraft).unwrap();
            let t = Instant::now();
            let mut sim = JsbsimSim::start(&cfg, spec.rate_hz).unwrap();
            sim.set_trim_reuse(true); // as the campaign does: trim once per point, then restore
            current = Some((c.aircraft.clone(), sim));
            start_s += t.elapsed().as_secs_f64();
        }
        let sim = &mut current.as_mut().unwrap().1;
        // the case's configuration (mass/CG variants), so these are the campaign's flights
        sim.clear_configuration();
        for (name, factor) in &c.coefficient_scales {
            sim.set_coefficient_scale(name, *factor).unwrap();
        }
        for (property, value) in &c.properties {
            sim.set_pre_trim_property(property, *value).unwrap();
        }
        let t = Instant::now();
        sim.trim(&TrimPoint::level(c.altitude_ft, c.speed_kts))
            .unwrap();
        trim_s += t.elapsed().as_secs_f64();
        let plan = single_surface_plan(
            &c.surface,
            &c.maneuver,
            c.amplitude_deg,
            spec.start_s,
            spec.duration_s,
            spec.rate_hz,
        );
        let t = Instant::now();
        let rec = sim.fly(&plan).unwrap();
        let case_fly_s = t.elapsed().as_secs_f64();
        fly_s += case_fly_s;
        let (du, dy) = perturbations(&rec, &c.surface, &c.tf_key).unwrap();
        let mut case_ident_s = 0.0;
        for (k, &m) in methods.iter().enumerate() {
            let t = Instant::now();
            let _ = identify(&du, &dy, 1.0 / spec.rate_hz, &paper_options(m));
            let s = t.elapsed().as_secs_f64();
            ident_by_method_s[k] += s;
            case_ident_s += s;
        }
        match by_aircraft.iter_mut().find(|(a, _, _)| *a == c.aircraft) {
            Some(e) => {
                e.1 += case_fly_s;
                e.2 += case_ident_s;
            }
            None => by_aircraft.push((c.aircraft.clone(), case_fly_s, case_ident_s)),
        }
    }
    let ident_s: f64 = ident_by_method_s.iter().sum();
    drop(current); // reap the bridge, so its CPU time is counted
    let bare_cpu_s = tree_cpu_s() - cpu0;
    println!(
        "[{name}] bare loop CPU (process tree, incl. starts, trims, identification): {bare_cpu_s:.2} s"
    );
    println!(
        "[{name}] bare JSBSim stepping for {} cases: fly {:.3} s total; campaign extras: trim (once per point, then restore) {:.3} s, identification ({}) {:.3} s, \
         process starts (one per aircraft) {:.3} s",
        cases.len(),
        fly_s,
        trim_s,
        spec.methods.join("+"),
        ident_s,
        start_s
    );
    println!(
        "[{name}] identification by method: {}",
        spec.methods
            .iter()
            .zip(&ident_by_method_s)
            .map(|(m, t)| format!("{m} {t:.3} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );

    println!(
        "[{name}] by aircraft (fly + identification): {}",
        by_aircraft
            .iter()
            .map(|(a, f, i)| format!("{a} {f:.3} + {i:.3} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );

    let mut wall = Vec::new();
    let mut cpu_s = Vec::new();
    for (jobs, fresh) in [(1, false), (2, false)] {
        let dir = tempfile::tempdir().unwrap();
        let spec = CampaignSpec {
            fresh_process_per_case: fresh,
            ..spec.clone()
        };
        let t = Instant::now();
        let c0 = tree_cpu_s();
        let s = run_campaign(
            &spec,
            dir.path(),
            &RunOptions {
                jobs,
                progress: false,
            },
        )
        .unwrap();
        let el = t.elapsed().as_secs_f64();
        let cpu = tree_cpu_s() - c0;
        assert_eq!(s.failed, 0);
        println!(
            "[{name}] campaign, {jobs} job(s), fresh process per case = {fresh}: {el:.2} s wall \
             ({:.2} cases/s), {cpu:.2} s CPU",
            cases.len() as f64 / el
        );
        wall.push(el);
        cpu_s.push(cpu);
    }
    println!(
        "[{name}] scaling 1 -> 2 jobs: {:.2}x (target >= 1.8x); 2-job wall / (bare stepping / 2): {:.2}x \
         (target <= 1.2x); CPU 1 job {:.2} s, 2 jobs {:.2} s",
        wall[0] / wall[1],
        wall[1] / (fly_s / 2.0),
        cpu_s[0],
        cpu_s[1]
    );
    // The same ratio against what flying these cases costs JSBSim at the least (a process per aircraft, a trim
    // per condition, the stepping), and the floor that CPU sets on 2 cores: work that is not stepping cannot hide.
    let bare_run_s = fly_s + trim_s + start_s;
    println!(
        "[{name}] 2-job wall / (bare JSBSim runs incl. process starts and trims / 2): {:.2}x; \
         floor on 2 cores = 2-job CPU / 2 = {:.2} s = {:.2}x bare stepping / 2",
        wall[1] / (bare_run_s / 2.0),
        cpu_s[1] / 2.0,
        cpu_s[1] / fly_s
    );
}
