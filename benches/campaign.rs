//! Campaign throughput on two campaigns: the example `campaigns/c172x_737.toml` (36 short cases:
//! 20 s at 60 Hz) and `campaigns/throughput.toml` (24 flight-test-length cases: 60 s at 120 Hz), each with 1 and
//! 2 jobs, against the bare JSBSim stepping time of the same flights (the `fly` calls only: same steps, same
//! recorded properties; trims, process starts and identification excluded and reported beside it).
//!
//! Run: `cargo bench --bench campaign` (`-- c172x_737` or `-- throughput` for one campaign). Prints wall-clock
//! and CPU seconds; a plain `main` (harness = false) because each measurement takes seconds and runs once.
//!
//! `cargo bench --bench campaign -- scale` (never part of the default run: ~5 min) generates a 1,000-case campaign
//! of short flights and runs it through Slurm (`campaign submit --slurm --wait`, several task counts) on the
//! cluster `SLURM_CONF` names (`scripts/slurm-local.sh start`), against a local `--jobs 2` run and the bare JSBSim
//! runs of the same flights; it also times empty array tasks (Slurm's own per-task cost) and derives the
//! per-task start overhead of a flightid task.

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
    if only.iter().any(|o| o == "scale") {
        bench_scale();
    }
}

/// Bare JSBSim work of a campaign's flights, s (one sequential process per aircraft).
struct Bare {
    fly_s: f64,
    trim_s: f64,
    start_s: f64,
}

impl Bare {
    /// Process starts + trims + stepping: what flying these cases costs JSBSim at the least.
    fn runs_s(&self) -> f64 {
        self.fly_s + self.trim_s + self.start_s
    }
}

/// Runs `spec` locally into a fresh directory: (wall s, process-tree CPU s).
fn local_run(spec: &CampaignSpec, jobs: usize) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let t = Instant::now();
    let c0 = tree_cpu_s();
    let s = run_campaign(
        spec,
        dir.path(),
        &RunOptions {
            jobs,
            progress: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(s.failed, 0, "{:?}", s.failed_ids);
    (t.elapsed().as_secs_f64(), tree_cpu_s() - c0)
}

/// Profile by phase, then the campaign with 1 and 2 jobs (reused processes), for `campaigns/NAME.toml`.
fn bench_campaign(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("campaigns/{name}.toml"));
    let spec = CampaignSpec::load(&path).expect("campaign file");
    let bare = profile(name, &spec);
    let fly_s = bare.fly_s;
    let mut wall = Vec::new();
    let mut cpu_s = Vec::new();
    for jobs in [1, 2] {
        let (el, cpu) = local_run(&spec, jobs);
        println!(
            "[{name}] campaign, {jobs} job(s): {el:.2} s wall ({:.2} cases/s), {cpu:.2} s CPU",
            spec.cases().len() as f64 / el
        );
        wall.push(el);
        cpu_s.push(cpu);
    }
    println!(
        "[{name}] scaling 1 -> 2 jobs: {:.2}x (target >= 1.8x); 2-job wall / (bare stepping / 2): {:.2}x; \
         CPU 1 job {:.2} s, 2 jobs {:.2} s",
        wall[0] / wall[1],
        wall[1] / (fly_s / 2.0),
        cpu_s[0],
        cpu_s[1]
    );
    // The same ratio against what flying these cases costs JSBSim at the least (a process per aircraft, a trim
    // per condition, the stepping), and the floor that CPU sets on 2 cores: work that is not stepping cannot hide.
    println!(
        "[{name}] 2-job wall / (bare JSBSim runs incl. process starts and trims / 2): {:.2}x (target <= 1.2x); \
         floor on 2 cores = 2-job CPU / 2 = {:.2} s = {:.2}x bare stepping / 2",
        wall[1] / (bare.runs_s() / 2.0),
        cpu_s[1] / 2.0,
        cpu_s[1] / fly_s
    );
}

/// The bare JSBSim runs of a campaign's flights, with a profile of what the campaign adds, printed.
fn profile(name: &str, spec: &CampaignSpec) -> Bare {
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

    Bare {
        fly_s,
        trim_s,
        start_s,
    }
}

/// A generated campaign of 1,000 short flights: c172x and 737, 10 trim points each, 5 maneuvers, 10 amplitudes;
/// 10 s at 60 Hz, least squares only (so per-case and per-task costs show, not the estimators).
fn scale_campaign_toml() -> String {
    let mut t =
        String::from("name = \"scale\"\nrate_hz = 60.0\nduration_s = 10.0\nmethods = [\"ls\"]\n");
    let c172x = [3000.0, 4000.0, 5000.0, 6000.0, 8000.0]
        .iter()
        .flat_map(|&h| [100.0, 110.0].map(|v| (h, v)))
        .collect::<Vec<_>>();
    let b737 = [20000.0, 25000.0, 30000.0, 22000.0, 28000.0]
        .iter()
        .flat_map(|&h| [400.0, 450.0].map(|v| (h, v)))
        .collect::<Vec<_>>();
    for (name, points) in [("c172x", c172x), ("737", b737)] {
        t += &format!(
            "[[configurations]]\nname = \"{name}\"\naircraft = \"{name}\"\nconditions = [\n"
        );
        for (h, v) in points {
            t += &format!("  {{ altitude_ft = {h:.1}, speed_kts = {v:.1} }},\n");
        }
        t += "]\n";
    }
    let amplitudes = "[0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0]";
    for (surface, shape) in [
        ("elevator", "doublet"),
        ("elevator", "3211"),
        ("aileron", "doublet"),
        ("rudder", "doublet"),
        ("rudder", "3211"),
    ] {
        t += &format!(
            "[[maneuvers]]\nsurface = \"{surface}\"\nshape = \"{shape}\"\npulse_s = 0.5\namplitudes_deg = {amplitudes}\n"
        );
    }
    t
}

/// Runs a command to success; its wall time, s.
fn timed(cmd: &mut std::process::Command) -> f64 {
    let t = Instant::now();
    let out = cmd.output().expect("command starts");
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    t.elapsed().as_secs_f64()
}

/// 1,000 cases: bare JSBSim runs, a local 2-job run, and Slurm job arrays of several sizes.
fn bench_scale() {
    let tmp = tempfile::tempdir().unwrap();
    let spec_path = tmp.path().join("scale.toml");
    std::fs::write(&spec_path, scale_campaign_toml()).unwrap();
    let spec = CampaignSpec::load(&spec_path).expect("generated campaign");
    let n = spec.cases().len();
    let bare = profile("scale", &spec);
    let cpus = std::thread::available_parallelism()
        .map(|c| c.get())
        .unwrap_or(1) as f64;
    let (local_s, local_cpu_s) = local_run(&spec, 2);
    println!(
        "[scale] local --jobs 2: {local_s:.2} s wall ({:.1} cases/s), {local_cpu_s:.2} s CPU; bare JSBSim runs \
         (starts + trims + stepping) {:.2} s sequential = {:.2} s on {cpus} CPUs: local / bare = {:.2}x",
        n as f64 / local_s,
        bare.runs_s(),
        bare.runs_s() / cpus,
        local_s / (bare.runs_s() / cpus)
    );
    let slurm_up = std::process::Command::new("sinfo")
        .args(["-h", "-o", "%t"])
        .output()
        .is_ok_and(|o| o.status.success() && !o.stdout.is_empty());
    if !slurm_up {
        println!("[scale] no Slurm cluster answers (SLURM_CONF?): scripts/slurm-local.sh start; Slurm part skipped");
        return;
    }
    // Slurm's own cost per array task: empty tasks, 2 per CPU-second of work at most
    let empty = 100;
    let empty_s = timed(std::process::Command::new("sbatch").args([
        "--wait",
        "--quiet",
        &format!("--array=0-{}", empty - 1),
        "--output=/dev/null",
        "--wrap=true",
    ]));
    let slurm_task_s = empty_s * cpus / empty as f64;
    println!(
        "[scale] {empty} empty array tasks: {empty_s:.2} s wall = {slurm_task_s:.3} s per task per CPU (Slurm's launch \
         and teardown)"
    );
    let mut rows = Vec::new();
    for tasks in [2usize, 20, 100, 500] {
        let out = tmp.path().join(format!("slurm-{tasks}"));
        let wall = timed(
            std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
                .args(["campaign", "submit"])
                .arg(&spec_path)
                .arg("--out")
                .arg(&out)
                .args(["--slurm", "--wait", "--tasks", &tasks.to_string()]),
        );
        println!(
            "[scale] slurm, {tasks} tasks ({} cases each): {wall:.2} s wall ({:.1} cases/s) = {:.2}x local --jobs 2, \
             {:.2}x bare runs / {cpus}",
            n / tasks,
            n as f64 / wall,
            wall / local_s,
            wall / (bare.runs_s() / cpus)
        );
        rows.push((tasks as f64, wall));
        let _ = std::fs::remove_dir_all(&out);
    }
    // each task costs: Slurm's launch, a flightid start, its JSBSim process start(s) and the trims of its points;
    // the slope of wall time over task count, times the CPUs working in parallel
    let (t0, w0) = rows[0];
    let (t1, w1) = rows[rows.len() - 1];
    println!(
        "[scale] per-task start overhead (slope {t0}..{t1} tasks x {cpus} CPUs): {:.3} s per task",
        (w1 - w0) / (t1 - t0) * cpus
    );
}
