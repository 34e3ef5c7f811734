//! Performance of the estimation core against its targets: a 60 s record of a 4-state, 2-input,
//! 6-output linear longitudinal model with 11 parameters plus the 4 initial states, fitted from
//! perturbed start values on one core:
//! - 10 Hz: output error converges in under 150 ms;
//! - 50 Hz: under 0.5 s;
//! - the filter error method costs at most 3× output error (same record, same start).
//!
//! The record is simulated inside the bench from known parameters with white output noise (for
//! timing; accuracy is tested elsewhere). Each figure is the median of `--repeat` fits (default 5).
//!
//! Also timed: subspace identification (`--method n4sid`) of the same records, order 4, with the
//! short-period derivatives it reads off in the measured-state basis (no target; the field's Python
//! subspace package takes 25–50 ms on JSBSim records of this size).
//!
//! Run: `cargo bench --bench estimate -- [--repeat 5] [--case 'toml oe'] [--json FILE]`

use std::time::Instant;

use flightid::estimate::{
    fit, simulate_states, subspace, Entry, Estimate, InputHold, InputSignal, LinearModel, Method,
    Model, Nuisance, Options, Parameter, Record, Run, Signature, StateModel, SubspaceOptions,
    UserModel,
};
use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::StandardNormal;

/// Trim airspeed, m/s (scales the normal acceleration output).
const V0_M_S: f64 = 50.0;
const G_M_S2: f64 = 9.80665;

const NAMES: [&str; 11] = [
    "X_u", "X_alpha", "X_dt", "Z_u", "Z_alpha", "Z_de", "M_u", "M_alpha", "M_q", "M_de", "M_dt",
];
const TRUTH: [f64; 11] = [
    -0.04, 4.0, 2.5, -0.003, -1.1, -0.12, 0.002, -7.5, -2.2, -11.0, 0.3,
];

/// States u (m/s), α, q, θ; inputs elevator, throttle; outputs u, α, q, θ, a_x, a_z.
fn model() -> LinearModel {
    let sig = Signature {
        parameters: NAMES.map(String::from).to_vec(),
        states: ["u_m_s", "alpha_rad", "q_rad_s", "theta_rad"]
            .map(String::from)
            .to_vec(),
        inputs: ["elevator_rad", "throttle"].map(String::from).to_vec(),
        outputs: [
            "u_m_s",
            "alpha_rad",
            "q_rad_s",
            "theta_rad",
            "ax_m_s2",
            "az_m_s2",
        ]
        .map(String::from)
        .to_vec(),
    };
    let p = Entry::param;
    let k = Entry::constant;
    let scaled = |i: usize, c: f64| Entry {
        constant: 0.0,
        terms: vec![(i, c)],
    };
    LinearModel::new(
        sig,
        vec![
            vec![p(0), p(1), k(0.0), k(-G_M_S2)],
            vec![p(3), p(4), k(1.0), k(0.0)],
            vec![p(6), p(7), p(8), k(0.0)],
            vec![k(0.0), k(0.0), k(1.0), k(0.0)],
        ],
        vec![
            vec![k(0.0), p(2)],
            vec![p(5), k(0.0)],
            vec![p(9), p(10)],
            vec![k(0.0), k(0.0)],
        ],
        vec![
            vec![k(1.0), k(0.0), k(0.0), k(0.0)],
            vec![k(0.0), k(1.0), k(0.0), k(0.0)],
            vec![k(0.0), k(0.0), k(1.0), k(0.0)],
            vec![k(0.0), k(0.0), k(0.0), k(1.0)],
            vec![p(0), p(1), k(0.0), k(0.0)],
            vec![scaled(3, V0_M_S), scaled(4, V0_M_S), k(0.0), k(0.0)],
        ],
        vec![
            vec![k(0.0), k(0.0)],
            vec![k(0.0), k(0.0)],
            vec![k(0.0), k(0.0)],
            vec![k(0.0), k(0.0)],
            vec![k(0.0), p(2)],
            vec![scaled(5, V0_M_S), k(0.0)],
        ],
    )
    .expect("bench model")
}

/// The same model simulated by the core's RK4 (as every nonlinear model is) instead of the exact
/// discretisation `LinearModel` uses on uniform records.
struct Rk4(LinearModel);

flightid::model_from_state_model!(Rk4);

/// Only `f` and `h`, no exact transition: the filter error method's filter integrates too.
impl StateModel for Rk4 {
    fn signature(&self) -> &Signature {
        StateModel::signature(&self.0)
    }
    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]) {
        self.0.derivatives(theta, x, u, dx)
    }
    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]) {
        self.0.outputs(theta, x, u, y)
    }
}

/// The same model written as a TOML user model (expressions, RK4).
fn user_model() -> UserModel {
    let text = format!(
        r#"
states  = ["u_m_s", "alpha_rad", "q_rad_s", "theta_rad"]
inputs  = ["elevator_rad", "throttle"]
outputs = ["u_m_s", "alpha_rad", "q_rad_s", "theta_rad", "ax_m_s2", "az_m_s2"]

[parameters]
{params}

[equations]
u_m_s     = "X_u*u_m_s + X_alpha*alpha_rad - {G_M_S2}*theta_rad + X_dt*throttle"
alpha_rad = "Z_u*u_m_s + Z_alpha*alpha_rad + q_rad_s + Z_de*elevator_rad"
q_rad_s   = "M_u*u_m_s + M_alpha*alpha_rad + M_q*q_rad_s + M_de*elevator_rad + M_dt*throttle"
theta_rad = "q_rad_s"

[observations]
ax_m_s2 = "X_u*u_m_s + X_alpha*alpha_rad + X_dt*throttle"
az_m_s2 = "{V0_M_S}*(Z_u*u_m_s + Z_alpha*alpha_rad + Z_de*elevator_rad)"
"#,
        params = start()
            .iter()
            .map(|p| format!("{} = {:e}", p.name, p.value))
            .collect::<Vec<_>>()
            .join("\n")
    );
    UserModel::parse(&text, "bench.toml").expect("bench TOML model")
}

/// 60 s at `rate_hz`: elevator 3-2-1-1 and doublets, throttle steps; output noise.
fn record(rate_hz: f64, seed: u64) -> Record {
    let dt = 1.0 / rate_hz;
    let n = (60.0 * rate_hz) as usize + 1;
    let time_s: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let a = 2f64.to_radians();
    let de = |t: f64| match t % 20.0 {
        t if (1.0..2.5).contains(&t) => a,
        t if (2.5..3.5).contains(&t) => -a,
        t if (3.5..4.0).contains(&t) => a,
        t if (4.0..4.5).contains(&t) => -a,
        t if (10.0..11.0).contains(&t) => -a,
        t if (11.0..12.0).contains(&t) => a,
        _ => 0.0,
    };
    let dt_in = |t: f64| match t {
        t if (20.0..35.0).contains(&t) => 0.1,
        t if (40.0..50.0).contains(&t) => -0.1,
        _ => 0.0,
    };
    let inputs = vec![
        time_s.iter().map(|&t| de(t)).collect::<Vec<f64>>(),
        time_s.iter().map(|&t| dt_in(t)).collect::<Vec<f64>>(),
    ];
    let x0 = [0.5, 0.01, 0.0, 0.01];
    let run = Run {
        record: 0,
        time_s: &time_s,
        input: InputSignal::measured(&time_s, &inputs, InputHold::Linear),
        max_step_s: dt / 4.0,
    };
    let y = simulate_states(&model(), &TRUTH, &x0, &run).expect("truth simulates");
    let sigma = [0.05, 0.002, 0.003, 0.002, 0.02, 0.1];
    let mut rng = StdRng::seed_from_u64(seed);
    let outputs = y
        .iter()
        .zip(sigma)
        .map(|(col, s)| {
            col.iter()
                .map(|v| v + s * rng.sample::<f64, _>(StandardNormal))
                .collect()
        })
        .collect();
    Record {
        name: format!("{rate_hz} Hz"),
        time_s,
        inputs,
        outputs,
        initial_state: vec![0.0; 4],
    }
}

/// Start values 30 % off the truth.
fn start() -> Vec<Parameter> {
    NAMES
        .iter()
        .zip(TRUTH)
        .enumerate()
        .map(|(i, (n, v))| Parameter::free(*n, v * if i % 2 == 0 { 1.3 } else { 0.7 }))
        .collect()
}

struct Timing {
    label: String,
    median_s: f64,
    iterations: usize,
    converged: bool,
    worst_error_sigma: f64,
}

fn time_fit(
    label: &str,
    model: &dyn Model,
    rec: &Record,
    method: Method,
    repeat: usize,
) -> Result<Timing, String> {
    // start values by name (a TOML model orders its parameters as written)
    let start: Vec<Parameter> = Model::signature(model)
        .parameters
        .iter()
        .map(|name| {
            start()
                .into_iter()
                .find(|p| &p.name == name)
                .expect("parameter named in the bench")
        })
        .collect();
    let nuisance = Nuisance {
        initial_state: vec![0, 1, 2, 3],
        ..Nuisance::default()
    };
    let options = Options {
        method,
        ..Options::default()
    };
    let mut times = Vec::new();
    let mut last: Option<Estimate> = None;
    for _ in 0..repeat {
        let t0 = Instant::now();
        let est = fit(
            model,
            &start,
            std::slice::from_ref(rec),
            &nuisance,
            &options,
        )
        .map_err(|e| e.to_string())?;
        times.push(t0.elapsed().as_secs_f64());
        last = Some(est);
    }
    times.sort_by(f64::total_cmp);
    let est = last.expect("at least one repeat");
    let worst = est
        .parameters
        .iter()
        .map(|p| {
            let t = TRUTH[NAMES.iter().position(|n| *n == p.name).unwrap_or(0)];
            (p.value - t).abs() / p.std_error.max(f64::MIN_POSITIVE)
        })
        .fold(0.0, f64::max);
    Ok(Timing {
        label: label.into(),
        median_s: times[times.len() / 2],
        iterations: est.iterations,
        converged: est.converged,
        worst_error_sigma: worst,
    })
}

/// Median time of a subspace fit of `rec` and the short-period derivatives it reads off.
fn time_subspace(rec: &Record, repeat: usize) -> String {
    let names: Vec<String> = ["u", "alpha", "q", "theta", "ax", "az"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let inputs = vec!["elevator".to_string(), "throttle".to_string()];
    let options = SubspaceOptions {
        order: Some(4),
        ..SubspaceOptions::default()
    };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeat {
        let t0 = Instant::now();
        match subspace(
            std::slice::from_ref(rec),
            &inputs,
            &names,
            Some(&[0, 1, 2, 3]),
            &options,
        ) {
            Ok(m) => last = Some(m),
            Err(e) => return format!("  n4sid {}: failed: {e}", rec.name),
        }
        times.push(t0.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let Some(m) = last else {
        return "  n4sid: no repeat".into();
    };
    let truth = |name: &str| TRUTH[NAMES.iter().position(|n| *n == name).unwrap_or(0)];
    let err = |got: f64, name: &str| 100.0 * (got / truth(name) - 1.0);
    format!(
        "  n4sid {:<12} {:>8.1} ms  M_alpha {:+.1} %  M_q {:+.1} %  M_de {:+.1} %  Z_alpha {:+.1} %",
        rec.name,
        1e3 * times[times.len() / 2],
        err(m.continuous.a[(2, 1)], "M_alpha"),
        err(m.continuous.a[(2, 2)], "M_q"),
        err(m.continuous.b[(2, 0)], "M_de"),
        err(m.continuous.a[(1, 1)], "Z_alpha"),
    )
}

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        argv.iter()
            .position(|a| a == flag)
            .and_then(|i| argv.get(i + 1).cloned())
    };
    let repeat: usize = value("--repeat").and_then(|v| v.parse().ok()).unwrap_or(5);
    let json = value("--json");
    let only = value("--case").unwrap_or_default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("one-thread pool");
    let results = pool.install(|| {
        let r10 = record(10.0, 1);
        let r50 = record(50.0, 2);
        let (linear, rk4, toml) = (model(), Rk4(model()), user_model());
        let models: [&dyn Model; 3] = [&linear, &rk4, &toml];
        let mut out = Vec::new();
        for (label, m) in ["linear", "rk4", "toml"].iter().zip(models) {
            for (method, rate, rec) in [
                (Method::Oe, 10, &r10),
                (Method::Oe, 50, &r50),
                (Method::Fem, 10, &r10),
                (Method::Fem, 50, &r50),
            ] {
                let name = format!("{label} {} {rate} Hz", method.name());
                if !name.contains(only.as_str()) {
                    out.push(Err(format!("{name}: skipped (--case {only})")));
                    continue;
                }
                out.push(time_fit(&name, m, rec, method, repeat));
            }
        }
        out
    });
    println!("estimate: 60 s, 4 states, 2 inputs, 6 outputs, 11 parameters + 4 initial states, one core, median of {repeat}");
    for r in &results {
        match r {
            Ok(t) => println!(
                "  {:<18} {:>8.1} ms  {:>3} iterations  converged {}  worst |θ − θ_true|/σ {:.2}",
                t.label,
                1e3 * t.median_s,
                t.iterations,
                t.converged,
                t.worst_error_sigma
            ),
            Err(e) if e.ends_with(&format!("skipped (--case {only})")) => {}
            Err(e) => println!("  failed: {e}"),
        }
    }
    if "n4sid".contains(only.as_str()) || only.is_empty() {
        for rate in [10.0, 50.0] {
            println!("{}", time_subspace(&record(rate, 7), repeat));
        }
    }
    let get = |i: usize| results[i].as_ref().ok().map(|t| t.median_s);
    let mut checks = Vec::new();
    for (m, label) in ["linear", "rk4", "toml"].iter().enumerate() {
        let b = 4 * m;
        checks.push((
            format!("{label} oe 10 Hz < 150 ms"),
            get(b).map(|t| t < 0.150),
        ));
        checks.push((
            format!("{label} oe 50 Hz < 0.5 s"),
            get(b + 1).map(|t| t < 0.5),
        ));
        for (rate, f, o) in [(10, b + 2, b), (50, b + 3, b + 1)] {
            let ok = get(f).zip(get(o)).map(|(f, o)| f <= 3.0 * o);
            checks.push((format!("{label} fem/oe {rate} Hz ≤ 3"), ok));
        }
    }
    for (label, ok) in &checks {
        let verdict = match ok {
            Some(true) => "pass",
            Some(false) => "FAIL",
            None => "not measured",
        };
        println!("  target {label}: {verdict}");
    }
    if let Some(path) = json {
        let rows: Vec<serde_json::Value> = results
            .iter()
            .filter_map(|r| r.as_ref().ok())
            .map(|t| {
                serde_json::json!({
                    "case": t.label, "median_s": t.median_s, "iterations": t.iterations,
                    "converged": t.converged, "worst_error_sigma": t.worst_error_sigma,
                })
            })
            .collect();
        let targets: Vec<serde_json::Value> = checks
            .iter()
            .map(|(l, ok)| serde_json::json!({"target": l, "pass": ok}))
            .collect();
        let doc = serde_json::json!({"fits": rows, "targets": targets});
        std::fs::write(
            &path,
            serde_json::to_string_pretty(&doc).unwrap_or_default(),
        )
        .expect("write --json");
    }
}
