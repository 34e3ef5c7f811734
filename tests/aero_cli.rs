//! `flightid derivatives` from the command line: the default run prints the paper's tables, and bad input is a
//! clear error with exit code 2.

mod common;

use std::path::PathBuf;
use std::process::{Command, Output};

fn flightid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(args)
        .output()
        .unwrap()
}

/// `text` written to `name` in a fresh temporary directory (removed when the handle drops).
fn scratch(name: &str, text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

fn assert_bad_input(out: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(err.contains(needle), "expected '{needle}' in: {err}");
}

/// An identified θ/δe in the shape `flightid identify --json` writes, with a denominator of `den`.
fn identified(den: &str, extra: &str) -> String {
    format!(
        r#"{{"input": "elevator_rad", "output": "theta_rad", {extra}
            "result": {{"tf": {{"num": [-18.9, -79.4, -7.2], "den": {den}, "dt_s": null}},
                        "num_std": [], "den_std": []}}}}"#
    )
}

#[test]
fn default_run_prints_tables_1_and_3_and_writes_json() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let json = dir.join("out.json");
    let out = flightid(&[
        "derivatives",
        "--aircraft",
        "c172x",
        "--json",
        json.to_str().unwrap(),
        "--report",
        dir.join("report").to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in [
        "Table 1",
        "Table 3",
        "Cm_q+Cm_alphadot",
        "Model check",
        "Drag polar",
    ] {
        assert!(text.contains(needle), "missing '{needle}' in:\n{text}");
    }
    let v = common::read_json(&json);
    // Two routes: the transfer functions and equation error, each with Cm_de scored.
    let cards = v["scorecards"].as_array().unwrap();
    assert_eq!(cards.len(), 2);
    for c in cards {
        assert!(c["rows"]
            .as_array()
            .unwrap()
            .iter()
            .any(|r| r["name"] == "Cm_de"));
    }
    // Coverage-or-attribution in the JSON: every row outside its 3σ interval carries its attributed terms and
    // a note naming the one responsible; the equation-error decomposition is there per equation.
    for c in cards {
        for r in c["rows"].as_array().unwrap() {
            if r["covered_3sigma"] == false {
                assert!(
                    r["note"].as_str().unwrap().contains("because of")
                        && !r["attribution"].as_array().unwrap().is_empty(),
                    "{}: {}",
                    r["name"],
                    r["note"]
                );
            }
        }
    }
    assert!(!v["equation_error_attribution"]
        .as_array()
        .unwrap()
        .is_empty());
    let md = std::fs::read_to_string(dir.join("report/report.md")).unwrap();
    assert!(md.contains("error attribution of every miss"), "{md}");
    assert!(dir.join("report/index.html").exists());
}

#[test]
fn unknown_derivative_name_is_bad_input() {
    let out = flightid(&["derivatives", "--free", "Cm_alpha,Cm_foo"]);
    assert_bad_input(&out, "unknown derivative name `Cm_foo`");
}

#[test]
fn transfer_function_of_the_wrong_order_is_bad_input() {
    // A 2nd-order θ/δe (short period only) cannot be matched to the 4-state longitudinal model.
    let (_dir, p) = scratch("second_order.json", &identified("[1.0, 7.2, 37.0]", ""));
    let out = flightid(&["derivatives", "--from", p.to_str().unwrap()]);
    assert_bad_input(&out, "needs degree 4");
}

#[test]
fn missing_mass_field_is_bad_input() {
    let (_dir, p) = scratch(
        "no_inertia.json",
        &identified(
            "[1.0, 7.15, 38.3, 2.27, 1.70]",
            r#""mass": {"mass_kg": 1100.0},"#,
        ),
    );
    let out = flightid(&["derivatives", "--from", p.to_str().unwrap()]);
    assert_bad_input(&out, "ixx_kg_m2");
}

#[test]
fn non_positive_wing_area_is_bad_input() {
    let (_dir, p) = scratch(
        "no_area.json",
        &identified(
            "[1.0, 7.15, 38.3, 2.27, 1.70]",
            r#""geometry": {"wing_area_m2": 0.0, "span_m": 11.0, "chord_m": 1.5},"#,
        ),
    );
    let out = flightid(&["derivatives", "--from", p.to_str().unwrap()]);
    assert_bad_input(&out, "wing_area_m2");
}

#[test]
fn unsupported_transfer_function_is_bad_input() {
    let (_dir, p) = scratch(
        "q.json",
        r#"{"input": "elevator_rad", "output": "q_rad_s", "result": {"tf": {"num": [1.0], "den": [1.0, 1.0]}}}"#,
    );
    let out = flightid(&["derivatives", "--from", p.to_str().unwrap()]);
    assert_bad_input(&out, "not one of the model's transfer functions");
}

/// `derivatives --data` on a CSV that `flightid fly` wrote (c172x, aileron 3-2-1-1): the half-sample lag of the
/// JSBSim record is modelled by default, so the roll damping and aileron power land within 1 % (measured
/// +0.0 % and −0.0 %); read as sensor data (`--sensor-data`, no lag modelled) the roll damping is off by the
/// lag's bias (measured +2.2 %), more than twice as far.
#[test]
fn derivatives_from_a_jsbsim_csv_model_its_half_sample_lag_unless_told_it_is_sensor_data() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("lat.csv");
    let bin = env!("CARGO_BIN_EXE_flightid");
    common::run_ok(
        std::process::Command::new(bin)
            .args([
                "fly",
                "--aircraft",
                "c172x",
                "--surface",
                "aileron",
                "--maneuver",
                "3211",
            ])
            .args([
                "--amplitude-deg",
                "2",
                "--pulse-s",
                "0.5",
                "--duration-s",
                "20",
                "--out",
            ])
            .arg(&csv),
    );
    let error_percent = |extra: &[&str], name: &str| -> f64 {
        let json = tmp.path().join("d.json");
        common::run_ok(
            std::process::Command::new(bin)
                .args(["derivatives", "--aircraft", "c172x", "--data"])
                .arg(&csv)
                .args(extra)
                .arg("--json")
                .arg(&json),
        );
        let v = common::read_json(&json);
        v["scorecards"][0]["rows"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["name"] == name)
            .unwrap()["error_percent"]
            .as_f64()
            .unwrap()
    };
    let (clp, clda) = (error_percent(&[], "Cl_p"), error_percent(&[], "Cl_da"));
    assert!(
        clp.abs() < 1.0 && clda.abs() < 1.0,
        "Cl_p {clp} %, Cl_da {clda} %"
    );
    let clp_sensor = error_percent(&["--sensor-data"], "Cl_p");
    assert!(
        clp_sensor.abs() > 2.0 * clp.abs().max(0.5),
        "Cl_p as sensor data {clp_sensor} %"
    );
}
