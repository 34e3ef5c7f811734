//! `flightid identify` on flight-data CSVs: a clean record is identified; bad input gives a one-line error naming
//! the problem and exit code 2.

use std::path::Path;
use std::process::Command;

fn flightid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
}

/// θ/δe of the paper (eq. 65) under a 1 s doublet, 100 Hz, 30 s, written as a flight-data CSV.
fn write_record(path: &Path, n: usize, corrupt: Option<usize>, still: bool) {
    let tf = flightid::lti::TransferFunction::new(
        vec![-24.7885, -18.2186, -0.4659],
        vec![1.0, 2.0072, 32.5269, 0.8638, 0.0179],
    );
    let dt = 0.01;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            if still {
                0.0
            } else if (1.0..2.0).contains(&t) {
                0.02
            } else if (2.0..3.0).contains(&t) {
                -0.02
            } else {
                0.0
            }
        })
        .collect();
    let y = flightid::lti::lsim(&tf, &u, dt);
    let mut s = String::from("time_s,elevator_rad,theta_rad\n");
    for k in 0..n {
        let theta = if corrupt == Some(k) {
            "NaN".to_string()
        } else {
            // At rest the attitude still moves a little (an exactly constant one is a stuck sensor).
            let rest = if still {
                1e-4 * (k as f64 * 0.37).sin()
            } else {
                0.0
            };
            format!("{}", 0.05 + y[k] + rest)
        };
        s.push_str(&format!("{},{},{}\n", k as f64 * dt, -0.01 + u[k], theta));
    }
    std::fs::write(path, s).unwrap();
}

fn identify(path: &Path, extra: &[&str]) -> std::process::Output {
    flightid()
        .args(["identify", "--data"])
        .arg(path)
        .args(["--input", "elevator", "--output", "theta_rad"])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn identify_recovers_the_short_period_from_a_clean_csv_and_emits_json() {
    // Noise-free record of eq. 65: srivc gives the short-period ωn = √32.5 ≈ 5.70 rad/s to 0.1 %.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("d.csv");
    write_record(&csv, 3001, None, false);
    let out = identify(&csv, &["--method", "srivc", "--json", "-"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["input"], "elevator_rad");
    let den = v["result"]["tf"]["den"].as_array().unwrap();
    assert!(
        (den[2].as_f64().unwrap() - 32.5269).abs() / 32.5269 < 1e-3,
        "{den:?}"
    );
    assert!((v["result"]["u_offset"].as_f64().unwrap() + 0.01).abs() < 1e-12);
    // estimator notes travel with the result (empty: srivc converged as designed)
    assert_eq!(v["result"]["warnings"], serde_json::json!([]));
    // the text form names coefficients, fits and the residual tests
    let text = identify(&csv, &["--method", "ls"]);
    let s = String::from_utf8_lossy(&text.stdout);
    assert!(text.status.success());
    for needle in [
        "a2 (s^2)",
        "one-step-ahead",
        "residual whiteness",
        "wn rad/s",
    ] {
        assert!(s.contains(needle), "missing {needle}: {s}");
    }
}

/// Specification (docs/data.md, dropouts): a record with 3 s of samples missing is refused, naming the file and
/// the gap, with and without --resample-hz (interpolating over the dropout would invent the motion in it), and
/// no JSON is written; the same record without the gap is identified.
#[test]
fn identify_refuses_a_record_with_a_dropout_even_when_resampling() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.csv");
    write_record(&whole, 3001, None, false);
    let text = std::fs::read_to_string(&whole).unwrap();
    // drop the samples after t = 15.00 s up to 18.05 s: lines 1502..1806 (data row k is line k + 2)
    let gapped: String = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(1502..1807).contains(i))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let csv = dir.path().join("gap.csv");
    std::fs::write(&csv, gapped).unwrap();
    let json = dir.path().join("out.json");
    for extra in [vec![], vec!["--resample-hz", "100"]] {
        let mut args = vec!["--json", json.to_str().unwrap()];
        args.extend(extra);
        let out = identify(&csv, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("gap.csv: a dropout of 3.060 s after t = 15 s")
                && err.contains("invent the motion"),
            "{args:?}: {err}"
        );
        assert!(!json.exists(), "{args:?}: a JSON was written");
    }
    assert!(identify(&whole, &[]).status.success());
}

#[test]
fn identify_bad_input_is_a_one_line_error_with_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.csv");
    write_record(&good, 3001, None, false);
    let nan = dir.path().join("nan.csv");
    write_record(&nan, 3001, Some(1500), false);
    let short = dir.path().join("short.csv");
    write_record(&short, 50, None, false);
    let still = dir.path().join("still.csv");
    write_record(&still, 3001, None, true);
    let cases: Vec<(std::process::Output, &str)> = vec![
        (
            flightid()
                .args(["identify", "--data"])
                .arg(&good)
                .args(["--input", "elevator", "--output", "q_rad_s"])
                .output()
                .unwrap(),
            "q_rad_s",
        ),
        (
            flightid()
                .args(["identify", "--data"])
                .arg(&good)
                .args(["--input", "flaps", "--output", "theta_rad"])
                .output()
                .unwrap(),
            "flaps",
        ),
        (identify(&nan, &[]), "NaN"),
        (
            identify(&short, &["--method", "oe", "--poles", "4", "--zeros", "2"]),
            "too few samples",
        ),
        (identify(&still, &[]), "never moves"),
        (identify(&good, &["--method", "bogus"]), "bogus"),
        (identify(&good, &["--poles", "2", "--zeros", "2"]), "zeros"),
        (
            identify(&dir.path().join("missing.csv"), &[]),
            "missing.csv",
        ),
    ];
    for (out, needle) in cases {
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{needle}: {err}");
        assert!(err.contains(needle), "expected '{needle}' in: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    }
}

/// Without --poles/--zeros the order comes from the data. On the independent short-period
/// generator's records (`scripts/gen_short_period_records.py`: scipy, noisy α, q and elevator,
/// biases, a random initial state; three seeds) q/δe is the short period, two poles and one zero,
/// and α/δe has two poles; the table lists every order tried with its verdict.
#[test]
fn identify_chooses_the_order_from_independent_records() {
    let dir = tempfile::tempdir().unwrap();
    let gen = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_short_period_records.py");
    let out = Command::new(flightid::sim::env::python().expect("provisioned Python"))
        .arg(gen)
        .arg(dir.path())
        .args(["1", "3"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for seed in 1..=3 {
        let csv = dir.path().join(format!("seed{seed}_a.csv"));
        for (output, poles, zeros) in [("q_rad_s", 2, Some(1)), ("alpha_rad", 2, None)] {
            let out = flightid()
                .args(["identify", "--data"])
                .arg(&csv)
                .args(["--input", "elevator", "--output", output, "--json", "-"])
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            let tf = &v["result"]["tf"];
            let n = tf["den"].as_array().unwrap().len() - 1;
            let m = tf["num"].as_array().unwrap().len() - 1;
            assert_eq!(n, poles, "seed {seed} {output}: {}", v["order_selection"]);
            if let Some(z) = zeros {
                assert_eq!(m, z, "seed {seed} {output}: {}", v["order_selection"]);
            }
            assert_eq!(v["order_selection"].as_array().unwrap().len(), 10);
        }
    }
    let text = flightid()
        .args(["identify", "--data"])
        .arg(dir.path().join("seed1_a.csv"))
        .args(["--input", "elevator", "--output", "q_rad_s"])
        .output()
        .unwrap();
    let s = String::from_utf8_lossy(&text.stdout);
    assert!(
        s.contains("order chosen from the data") && s.contains("chosen"),
        "{s}"
    );
}
