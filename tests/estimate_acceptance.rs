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
    let out = Command::new(python())
        .arg(script("gen_short_period_records.py"))
        .arg(dir.path())
        .arg("1")
        .arg("20")
        .output()
        .expect("run the generator");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth = read_json(&dir.path().join("truth.json"));
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
