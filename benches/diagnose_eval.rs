//! Acceptance evaluation of `diagnose` on records it never saw the making of: `scripts/gen_diagnose_records.py`
//! flies JSBSim's c172x (or its 737) through JSBSim's own Python API with its own conventions and hides 0–3
//! effects drawn from the whole catalogue. Each case is diagnosed (training + validation record, two JSBSim
//! workers) and scored: the named set exactly right (effect and target), values within 15 % of the hidden
//! effect's size (|v − v_true| ≤ 0.15 |v_true − null|), no cause named on a clean record.
//!
//! Run: `cargo bench --bench diagnose_eval -- [--cases 40] [--seed 1] [--turbulence] [--clean] [--false-alarm]
//! [--first K] [--random-mix] [--process-noise] [--noise-weights] [--backward-elimination] [--estimate-rate]
//! [--without COLUMNS] [--reverse COLUMNS] [--log-from S] [--aircraft c172x|c182|c310|737] [--out DIR]`
//! - `--aircraft 737`: records of JSBSim's 737 in cruise, diagnosed with flightid's `737` configuration.
//! - `--aircraft c182`, `--aircraft c310`: records of JSBSim's c182 or c310, diagnosed with the configuration
//!   flightid derives from the model (it has none of its own).
//! - `--process-noise`: search on the filter error method's innovations where the records carry process noise
//!   (`flightid diagnose --process-noise`).
//! - `--noise-weights`: weight every channel by its sensor noise only (`flightid diagnose --noise-weights`).
//! - `--backward-elimination`: after forward selection, test every named effect again against the model without
//!   it (`flightid diagnose --backward-elimination`).
//! - `--estimate-rate`: choose the replay's integration rate from the record (`flightid diagnose
//!   --estimate-rate`).
//! - `--without alpha_rad,beta_rad,ax_m_s2,ay_m_s2,az_m_s2`: records that leave those sensor columns out (a log
//!   without vanes or accelerometers); no effect is hidden on them.
//! - `--reverse elevator_rad,aileron_rad`: records whose surface columns have the other sign convention (as a
//!   servo output or an aileron logged right minus left has); `diagnose` must reverse them and name the same set.
//! - `--log-from 14`: records logged from that many seconds into their flight, as a data system that starts
//!   recording mid-flight writes them (inside a maneuver or the transient after one).
//! - the mix is stratified by case index (i mod 4 = 0 clean, 3 two or three effects, else one: 40 cases give
//!   10 clean, 20 single, 10 multiple); `--random-mix` draws it by chance (a quarter clean, a quarter multiple).
//! - `--clean`: every case clean (the acceptance's maneuver sequence, lengths 30–90 s).
//! - `--false-alarm`: the false-alarm Monte Carlo: every case clean, a random maneuver plan (the full sequence,
//!   longitudinal only, lateral only, the 3-2-1-1 alone, the sequence reversed), lengths 15–90 s, noise levels
//!   0.5–2 × the level-1 noise, random trim points, headings, latitudes and rates. Prints the false-alarm rate
//!   with its one-sided 95 % upper bound (Clopper–Pearson).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use flightid::data::read_csv;
use flightid::diagnose::search::Worker;
use flightid::diagnose::{diagnose, replay::ReplayCase, DiagnoseOptions, Diagnosis};
use flightid::sim::JsbsimSim;

struct Args {
    cases: usize,
    seed: u64,
    turbulence: bool,
    clean: bool,
    false_alarm: bool,
    random_mix: bool,
    process_noise: bool,
    noise_weights: bool,
    backward_elimination: bool,
    estimate_rate: bool,
    out: PathBuf,
    first: usize,
    without: String,
    reverse: String,
    log_from: String,
    aircraft: String,
}

fn args() -> Args {
    let mut a = Args {
        cases: 40,
        seed: 1,
        turbulence: false,
        clean: false,
        false_alarm: false,
        random_mix: false,
        process_noise: false,
        noise_weights: false,
        backward_elimination: false,
        estimate_rate: false,
        out: std::env::temp_dir().join("flightid-diagnose-eval"),
        first: 0,
        without: String::new(),
        reverse: String::new(),
        log_from: String::new(),
        aircraft: "c172x".to_string(),
    };
    let v: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < v.len() {
        let next = |i: usize| v.get(i + 1).cloned().unwrap_or_default();
        match v[i].as_str() {
            "--cases" => a.cases = next(i).parse().unwrap_or(40),
            "--seed" => a.seed = next(i).parse().unwrap_or(1),
            "--first" => a.first = next(i).parse().unwrap_or(0),
            "--out" => a.out = PathBuf::from(next(i)),
            "--without" => a.without = next(i),
            "--reverse" => a.reverse = next(i),
            "--log-from" => a.log_from = next(i),
            "--aircraft" => a.aircraft = next(i),
            "--turbulence" => {
                a.turbulence = true;
                i += 1;
                continue;
            }
            "--clean" => {
                a.clean = true;
                i += 1;
                continue;
            }
            "--false-alarm" => {
                a.false_alarm = true;
                i += 1;
                continue;
            }
            "--random-mix" => {
                a.random_mix = true;
                i += 1;
                continue;
            }
            "--process-noise" => {
                a.process_noise = true;
                i += 1;
                continue;
            }
            "--noise-weights" => {
                a.noise_weights = true;
                i += 1;
                continue;
            }
            "--backward-elimination" => {
                a.backward_elimination = true;
                i += 1;
                continue;
            }
            "--estimate-rate" => {
                a.estimate_rate = true;
                i += 1;
                continue;
            }
            _ => {
                i += 1;
                continue;
            }
        }
        i += 2;
    }
    a
}

fn null_of(effect: &str) -> f64 {
    match effect {
        "control_effectiveness" | "sensor_scale" | "aero_derivative" => 1.0,
        _ => 0.0,
    }
}

/// How a diagnosis scores against the hidden effects.
struct Score {
    /// Exactly the right set named.
    exact: bool,
    /// Exactly the right set, every value within 15 % of the effect size.
    values: bool,
    /// As `values`, a hidden effect also matched by a named cause that lists it as ambiguous with itself (an
    /// actuator lag named as the input delay it cannot be told from, with the lag in its ambiguity group).
    grouped: bool,
}

fn score(d: &Diagnosis, truth: &[serde_json::Value]) -> Score {
    let hidden: Vec<(String, String, f64)> = truth
        .iter()
        .map(|t| {
            (
                t["effect"].as_str().unwrap_or("").to_string(),
                t["target"].as_str().unwrap_or("").to_string(),
                t["value"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect();
    let close = |e: &str, named: f64, truth: f64| {
        (named - truth).abs() <= 0.15 * (truth - null_of(e)).abs()
    };
    // A named cause matches a hidden effect as itself, or (grouped) through its ambiguity group.
    let matches = |grouped: bool| {
        let mut used = vec![false; d.named_cause.len()];
        let all = hidden.iter().all(|(e, t, v)| {
            let key = format!("{e}/{t}");
            let found = d.named_cause.iter().enumerate().find(|(k, c)| {
                !used[*k]
                    && ((&c.effect == e && &c.target == t)
                        || (grouped && c.ambiguous_with.contains(&key)))
            });
            found.is_some_and(|(k, c)| {
                used[k] = true;
                close(e, c.value, *v)
            })
        });
        all && d.named_cause.len() == hidden.len()
    };
    let mut want: Vec<String> = hidden.iter().map(|(e, t, _)| format!("{e}/{t}")).collect();
    let mut got: Vec<String> = d
        .named_cause
        .iter()
        .map(|c| format!("{}/{}", c.effect, c.target))
        .collect();
    want.sort();
    got.sort();
    let exact = want == got;
    Score {
        exact,
        values: exact && matches(false),
        grouped: matches(true),
    }
}

fn generate(a: &Args) {
    let python = flightid::sim::env::python().expect("the provisioned Python");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_diagnose_records.py");
    let mut cmd = Command::new(python);
    cmd.arg(script)
        .arg("--out")
        .arg(&a.out)
        .args([
            "--cases",
            &a.cases.to_string(),
            "--seed",
            &a.seed.to_string(),
        ])
        .args(["--first", &a.first.to_string()])
        .args(["--aircraft", &a.aircraft])
        .stderr(std::process::Stdio::null());
    if a.turbulence {
        cmd.arg("--turbulence");
    }
    if !a.without.is_empty() {
        cmd.args(["--without", &a.without]);
    }
    if !a.log_from.is_empty() {
        cmd.args(["--log-from", &a.log_from]);
    }
    if !a.reverse.is_empty() {
        cmd.args(["--reverse", &a.reverse]);
    }
    if !a.random_mix {
        cmd.arg("--stratified");
    }
    if a.clean || a.false_alarm {
        cmd.args(["--effects", "[]"]);
    }
    if a.false_alarm {
        cmd.args([
            "--plan",
            "random",
            "--min-duration",
            "15",
            "--max-duration",
            "90",
        ])
        .args(["--max-noise", "2"]);
    }
    let st = cmd.status().expect("running the generator");
    assert!(st.success(), "the generator failed");
}

fn main() {
    let a = args();
    let t0 = Instant::now();
    generate(&a);
    let cfg = flightid::sim::derived::aircraft_config(&a.aircraft)
        .expect("an aircraft flightid knows or JSBSim has");
    let (mut n, mut exact, mut values, mut clean, mut clean_named, mut multi, mut multi_ok) =
        (0, 0, 0, 0, 0, 0, 0);
    let mut grouped = 0;
    let mut wall = 0.0;
    let mut signs_right = 0;
    for i in a.first..a.first + a.cases {
        let p = |part: &str| a.out.join(format!("case_{i:03}_{part}"));
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p("truth.json")).expect("truth"))
                .expect("truth JSON");
        let effects = truth["effects"].as_array().cloned().unwrap_or_default();
        let train = read_csv(&p("train.csv")).expect("train CSV");
        let valid = read_csv(&p("valid.csv")).expect("valid CSV");
        let rate = ReplayCase::new(&train).expect("record").sim_rate_hz();
        let mut workers: Vec<Worker> = (0..2)
            .map(|_| Worker::new(Box::new(JsbsimSim::start(&cfg, rate).expect("JSBSim"))))
            .collect();
        let opts = DiagnoseOptions {
            progress: false,
            process_noise: a.process_noise,
            relax_weights: !a.noise_weights,
            backward_elimination: a.backward_elimination,
            choose_rate: a.estimate_rate,
            ..Default::default()
        };
        let d = match diagnose(&mut workers, &train, Some(&valid), &opts) {
            Ok(d) => d,
            Err(e) => {
                println!("case {i:3}: diagnose failed: {e}");
                n += 1;
                continue;
            }
        };
        wall += d.wall_s;
        // The whole diagnosis beside the record, for a look at the candidates afterwards.
        if let Ok(text) = serde_json::to_string_pretty(&d) {
            let _ = std::fs::write(p("diagnosis.json"), text);
        }
        let Score {
            exact: ok,
            values: ok_v,
            grouped: ok_g,
        } = score(&d, &effects);
        // The surface columns the generator logged with the other sign, against those `diagnose` reversed.
        let sorted = |mut v: Vec<String>| {
            v.sort();
            v
        };
        let want_reversed = sorted(
            truth["reversed_columns"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|c| c.as_str().map(String::from))
                .collect(),
        );
        let got_reversed = sorted(d.reversed_inputs.iter().map(|r| r.column.clone()).collect());
        signs_right += usize::from(want_reversed == got_reversed);
        let signs = if want_reversed == got_reversed {
            String::new()
        } else {
            format!(" REVERSED {got_reversed:?} (logged so: {want_reversed:?})")
        };
        n += 1;
        exact += usize::from(ok);
        values += usize::from(ok_v);
        grouped += usize::from(ok_g);
        if effects.is_empty() {
            clean += 1;
            clean_named += usize::from(!d.named_cause.is_empty());
        }
        if effects.len() >= 2 {
            multi += 1;
            multi_ok += usize::from(ok_v);
        }
        let named: Vec<String> = d
            .named_cause
            .iter()
            .map(|c| {
                let amb = if c.ambiguous_with.is_empty() {
                    String::new()
                } else {
                    format!(" ~{{{}}}", c.ambiguous_with.join(","))
                };
                format!("{}/{}={:.4}{amb}", c.effect, c.target, c.value)
            })
            .collect();
        let hidden: Vec<String> = effects
            .iter()
            .map(|e| {
                format!(
                    "{}/{}={:.4}",
                    e["effect"].as_str().unwrap_or(""),
                    e["target"].as_str().unwrap_or(""),
                    e["value"].as_f64().unwrap_or(f64::NAN)
                )
            })
            .collect();
        // The strongest evidence among round-0 full fits (calibrates the criterion's threshold on clean records).
        let min_bic = d
            .candidates
            .iter()
            .filter(|c| c.full_fit && c.round == 0)
            .map(|c| c.criterion_delta)
            .fold(f64::INFINITY, f64::min);
        // Whether the search ran on the filter's innovations (`--process-noise` and turbulence found).
        let filter = if d.process_noise.as_ref().is_some_and(|p| p.used) {
            " filter"
        } else {
            ""
        };
        println!(
            "case {i:3} [{}]{filter} {:12} {:5.1} s {:3.0} Hz noise {:3.1} {:4} sims {:5.1} s, round-0 min dBIC {min_bic:8.1}: hidden [{}] named [{}]{signs}",
            if ok_v {
                "ok "
            } else if ok_g {
                "grp"
            } else if ok {
                "set"
            } else {
                "BAD"
            },
            truth["plan"].as_str().unwrap_or("full"),
            truth["duration_s"].as_f64().unwrap_or(0.0),
            truth["log_rate_hz"].as_f64().unwrap_or(0.0),
            truth["noise_level"].as_f64().unwrap_or(0.0),
            d.simulations,
            d.wall_s,
            hidden.join(" "),
            named.join(" ")
        );
    }
    let pct = |k: usize, m: usize| 100.0 * k as f64 / m.max(1) as f64;
    println!(
        "{n} cases ({}, seed {}, turbulence {}): named set exactly right {exact}/{n} ({:.0} %), with values within 15 % \
         {values}/{n} ({:.0} %), or with a hidden effect named by the ambiguity group it is in {grouped}/{n} \
         ({:.0} %); clean records with a cause named {clean_named}/{clean} ({:.0} %); \
         cases with >= 2 effects right {multi_ok}/{multi}; surface sign conventions right {signs_right}/{n}; mean \
         diagnose wall {:.1} s; total {:.0} s",
        a.aircraft,
        a.seed,
        a.turbulence,
        pct(exact, n),
        pct(values, n),
        pct(grouped, n),
        pct(clean_named, clean),
        wall / n.max(1) as f64,
        t0.elapsed().as_secs_f64()
    );
    if clean > 0 {
        println!(
            "false-alarm rate {clean_named}/{clean} = {:.1} % (one-sided 95 % upper bound {:.1} %, Clopper-Pearson)",
            pct(clean_named, clean),
            100.0 * upper_bound_95(clean_named, clean)
        );
    }
}

/// One-sided 95 % Clopper–Pearson upper bound of a binomial proportion with `k` events in `n` trials: the p at
/// which P(X ≤ k | n, p) = 0.05 (bisection; for k = 0 it is 1 − 0.05^(1/n)).
fn upper_bound_95(k: usize, n: usize) -> f64 {
    let cdf = |p: f64| -> f64 {
        // Σ_{j≤k} C(n, j) p^j (1 − p)^(n − j), the terms built by their ratio.
        let mut term = (1.0 - p).powi(n as i32);
        let mut sum = term;
        for j in 0..k.min(n) {
            term *= (n - j) as f64 / (j + 1) as f64 * p / (1.0 - p).max(1e-300);
            sum += term;
        }
        sum
    };
    let (mut lo, mut hi) = (k as f64 / n.max(1) as f64, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if cdf(mid) > 0.05 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
