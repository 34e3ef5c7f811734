//! Acceptance of `flightid estimate` on records flightid did not write.
//!
//! Linear short period: `scripts/gen_short_period_records.py` (scipy's DOP853, its own noise,
//! biases and initial states, noise on the logged elevator too) writes two records per seed for
//! 20 seeds; each pair is fitted jointly with `models/short_period.toml` (initial states and output
//! biases estimated per record). Every parameter must lie within 3σ of the generator's truth in at
//! least 95 % of the seeds (19 of 20), and the σ must be honest: the RMS of the normalised errors
//! over all 100 estimates lies in [0.6, 1.6] (a σ inflated to pass would drive it towards 0).

use std::path::{Path, PathBuf};
use std::process::Command;

fn python() -> PathBuf {
    flightid::sim::env::python().expect("provisioned Python")
}

fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scripts")
        .join(name)
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn short_period_parameters_lie_within_3_sigma_of_an_independent_generators_truth() {
    let dir = tempfile::tempdir().unwrap();
    let seeds = 1..=20;
    let truth = generate("gen_short_period_records.py", dir.path(), 1, 20, &[]);
    let truth = truth.as_object().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml");
    let mut misses = std::collections::BTreeMap::<String, usize>::new();
    let mut z2 = Vec::new();
    for seed in seeds {
        let json = dir.path().join(format!("est{seed}.json"));
        let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("estimate")
            .arg("--model")
            .arg(&model)
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_a.csv")))
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_b.csv")))
            .arg("--json")
            .arg(&json)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = read_json(&json);
        assert_eq!(v["converged"], true, "seed {seed}: {v}");
        for (name, t) in truth {
            let p = &v["parameters"][name];
            let (value, sigma) = (
                p["value"].as_f64().unwrap(),
                p["std_error"].as_f64().unwrap(),
            );
            let z = (value - t.as_f64().unwrap()) / sigma;
            z2.push(z * z);
            if z.abs() > 3.0 {
                *misses.entry(name.clone()).or_default() += 1;
            }
        }
    }
    for (name, m) in &misses {
        assert!(*m <= 1, "{name} outside 3σ in {m} of 20 seeds");
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    assert!((0.6..=1.6).contains(&rms), "RMS normalised error {rms:.2}");
}

/// Runs `flightid estimate` with `method` on `csv`; the JSON estimate.
fn estimate(dir: &Path, csv: &Path, method: &str) -> serde_json::Value {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml");
    let json = dir.join(format!(
        "{}-{method}.json",
        csv.file_stem().unwrap().to_string_lossy()
    ));
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(["estimate", "--method", method, "--model"])
        .arg(&model)
        .arg("--data")
        .arg(csv)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_json(&json)
}

fn value(v: &serde_json::Value, name: &str) -> (f64, f64) {
    let p = &v["parameters"][name];
    (
        p["value"].as_f64().unwrap(),
        p["std_error"].as_f64().unwrap(),
    )
}

fn spread(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// JSBSim's c172x flown by `scripts/fly_turbulent_short_period.py` through JSBSim's own Python API:
/// an elevator 3-2-1-1 pair around trim, once in still air (the reference: output error on it) and
/// in four MIL-F-8785C turbulence seeds (`atmosphere/turb-type` 3, 25 ft/s at 20 ft, severity 3).
/// The short-period model is fitted with output error and with the filter error method, and both
/// are shown against the still-air reference.
///
/// What the numbers support (and this test asserts): the filter error method detects the
/// turbulence (process-noise variance of α̇ ten times its still-air value, t > 5), converges on
/// every seed, and its estimates of M_α and M_δe scatter less from seed to seed than output
/// error's. What they do not support: the filter error estimates are not within 3σ of the
/// still-air reference (M_q about −2.7 against −4.2, σ 0.15) — JSBSim's turbulence enters the
/// pitching moment through the aerodynamic rate (q − q_gust) and the gust's α̇, coloured and
/// correlated between the two equations, which a diagonal white F does not model. The table is
/// printed for the record.
#[test]
fn jsbsim_turbulence_output_error_and_filter_error_against_the_still_air_reference() {
    let dir = tempfile::tempdir().unwrap();
    let fly = |name: &str, args: &[&str]| {
        let csv = dir.path().join(format!("{name}.csv"));
        let out = Command::new(python())
            .arg(script("fly_turbulent_short_period.py"))
            .arg(&csv)
            .args(args)
            .output()
            .expect("run JSBSim");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        csv
    };
    let clean = fly("still", &[]);
    let reference = estimate(dir.path(), &clean, "oe");
    let clean_fem = estimate(dir.path(), &clean, "fem");
    let q_still = clean_fem["nuisance"]["process_noise:alpha_rad"]["value"]
        .as_f64()
        .unwrap();
    let names = ["Z_alpha", "Z_de", "M_alpha", "M_q", "M_de"];
    let mut by_method: std::collections::BTreeMap<(&str, &str), Vec<f64>> = Default::default();
    println!("still-air reference (oe):");
    for n in names {
        let (v, s) = value(&reference, n);
        println!("  {n:8} {v:9.3} ± {s:.3}");
    }
    for seed in 1..=4 {
        let csv = fly(
            &format!("turbulence{seed}"),
            &["--turbulence", "milspec", "--seed", &seed.to_string()],
        );
        for method in ["oe", "fem"] {
            let est = estimate(dir.path(), &csv, method);
            assert_eq!(est["converged"], true, "seed {seed} {method}: {est}");
            let row: Vec<String> = names
                .iter()
                .map(|n| {
                    let (v, s) = value(&est, n);
                    let (t, _) = value(&reference, n);
                    by_method.entry((method, n)).or_default().push(v);
                    format!("{n} {v:.2}±{s:.2} ({:+.1}σ)", (v - t) / s)
                })
                .collect();
            println!("seed {seed} {method:3}: {}", row.join("  "));
            if method == "fem" {
                let q = &est["nuisance"]["process_noise:alpha_rad"];
                let (qv, qt) = (q["value"].as_f64().unwrap(), q["t"].as_f64().unwrap());
                println!("          q_alpha {qv:.3e} (t {qt:.1}), still air {q_still:.3e}");
                assert!(
                    qv > 10.0 * q_still && qt > 5.0,
                    "turbulence not detected: {q}"
                );
            }
        }
    }
    for n in ["M_alpha", "M_de"] {
        let (oe, fem) = (
            spread(&by_method[&("oe", n)]),
            spread(&by_method[&("fem", n)]),
        );
        println!("{n}: seed-to-seed spread oe {oe:.2}, fem {fem:.2}");
        assert!(
            fem < oe,
            "{n}: filter error scatters more ({fem:.2}) than output error ({oe:.2})"
        );
    }
}

/// Runs the generator `name` (in `scripts/`) into `dir` for seeds `first..first+n` (extra
/// arguments appended); the truth it writes.
fn generate(name: &str, dir: &Path, first: u32, n: u32, extra: &[&str]) -> serde_json::Value {
    let out = Command::new(python())
        .arg(script(name))
        .arg(dir)
        .arg(first.to_string())
        .arg(n.to_string())
        .args(extra)
        .output()
        .expect("run the generator");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_json(&dir.join("truth.json"))
}

/// Fits `models/longitudinal_nonlinear.toml` (every parameter "auto") to seed `seed`'s two records.
fn fit_longitudinal(dir: &Path, seed: u32) -> serde_json::Value {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/longitudinal_nonlinear.toml");
    let json = dir.join(format!("est{seed}.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .arg("estimate")
        .arg("--model")
        .arg(&model)
        .arg("--data")
        .arg(dir.join(format!("seed{seed}_a.csv")))
        .arg("--data")
        .arg(dir.join(format!("seed{seed}_b.csv")))
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "seed {seed}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("start values from the records"),
        "the auto start values are reported: {stderr}"
    );
    let v = read_json(&json);
    assert_eq!(v["converged"], true, "seed {seed}: {v}");
    v
}

/// A nonlinear longitudinal model written as a TOML file (states V, α, θ, q; elevator and a
/// measured thrust as inputs; V, α, θ, q, ax, az measured, with an α-vane and an az bias), fitted
/// with no start value given: scipy's DOP853 flies the same equations with its own trim, noise and
/// biases (`scripts/gen_longitudinal_records.py`), 40 s at 25 Hz, two records per seed.
///
/// - Inputs logged exactly (6 seeds, 60 estimates): at least 57 within 3σ of the truth, and the
///   RMS of the normalised errors in [0.5, 1.6] (measured: 0 of 60 beyond 3σ, RMS ≈ 0.9).
/// - Inputs logged with noise, as on a real aircraft (0.02° on the elevator, 10 N on the thrust;
///   3 seeds): the well-determined derivatives stay within a few percent (measured worst: CL_α
///   0.3 %, Cm_α 0.4 %, Cm_q 1.7 %, Cm_δe 1.0 %). Their σ are then optimistic (the input noise acts
///   as process noise that output error does not model: 13 of 60 estimates beyond 3σ over 6
///   seeds), which this test does not hide: it asserts only the relative errors there.
#[test]
fn nonlinear_longitudinal_toml_model_from_auto_start_values_recovers_the_truth() {
    let exact = tempfile::tempdir().unwrap();
    let truth = generate(
        "gen_longitudinal_records.py",
        exact.path(),
        1,
        6,
        &["exact-inputs"],
    );
    let truth = truth.as_object().unwrap();
    let (mut beyond, mut z2) = (Vec::new(), Vec::new());
    for seed in 1..=6 {
        let v = fit_longitudinal(exact.path(), seed);
        for (name, t) in truth {
            let (value, sigma) = value(&v, name);
            let z = (value - t.as_f64().unwrap()) / sigma;
            z2.push(z * z);
            if z.abs() > 3.0 {
                beyond.push(format!("seed {seed} {name} z = {z:.1}"));
            }
        }
    }
    assert!(beyond.len() <= 3, "beyond 3σ: {beyond:?}");
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    assert!((0.5..=1.6).contains(&rms), "RMS normalised error {rms:.2}");

    let noisy = tempfile::tempdir().unwrap();
    let truth = generate("gen_longitudinal_records.py", noisy.path(), 1, 3, &[]);
    for seed in 1..=3 {
        let v = fit_longitudinal(noisy.path(), seed);
        for (name, tolerance) in [
            ("CL_alpha", 0.02),
            ("Cm_alpha", 0.02),
            ("Cm_q", 0.05),
            ("Cm_de", 0.03),
            ("CD_0", 0.06),
            ("CL_de", 0.15),
        ] {
            let t = truth[name].as_f64().unwrap();
            let (value, _) = value(&v, name);
            assert!(
                ((value - t) / t).abs() < tolerance,
                "seed {seed} {name} {value} against {t}"
            );
        }
    }
}

/// `estimate --method n4sid` on the independent short-period generator's records (5 seeds, two
/// records each): the subspace model, written in the basis of the measured α and q, reads as the
/// short-period derivatives; they land within 8 % of the truth (measured: within 3 % on M_α, M_q,
/// M_δe, Z_α). Z_δe is small and poorly determined and is not asserted.
#[test]
fn n4sid_reads_the_short_period_derivatives_off_independent_records() {
    let dir = tempfile::tempdir().unwrap();
    let truth = generate("gen_short_period_records.py", dir.path(), 1, 5, &[]);
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml");
    for seed in 1..=5 {
        let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args(["estimate", "--method", "n4sid", "--model"])
            .arg(&model)
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_a.csv")))
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_b.csv")))
            .args(["--json", "-"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        let v: serde_json::Value = serde_json::from_str(&text[text.find('{').unwrap()..]).unwrap();
        assert_eq!(v["order"], 2);
        assert_eq!(v["states"], serde_json::json!(["alpha_rad", "q_rad_s"]));
        let a = |i: usize, j: usize| v["a"][i][j].as_f64().unwrap();
        let b = |i: usize| v["b"][i][0].as_f64().unwrap();
        for (name, got) in [
            ("Z_alpha", a(0, 0)),
            ("M_alpha", a(1, 0)),
            ("M_q", a(1, 1)),
            ("M_de", b(1)),
        ] {
            let t = truth[name].as_f64().unwrap();
            assert!(
                ((got - t) / t).abs() < 0.08,
                "seed {seed} {name} {got} against {t}"
            );
        }
        assert!(
            (a(0, 1) - 1.0).abs() < 0.08,
            "seed {seed}: α̇ per q {}",
            a(0, 1)
        );
        let modes = v["modes"].as_array().unwrap();
        assert_eq!(modes.len(), 1, "one short-period pair: {modes:?}");
    }
}
