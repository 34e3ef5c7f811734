//! `flightid compare` on c172x: the report holds every plot inline and the numbers agree with the
//! linearization where the flight is linear.

mod common;

use std::process::Command;

#[test]
fn compare_report_holds_every_plot_and_srivc_matches_the_linearized_short_period() {
    let (_tmp, dir, v) = compare(&[
        "--duration-s",
        "12",
        "--method",
        "ls,srivc",
        "--sweep-deg",
        "1,6",
    ]);
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    // 3 transfer functions × (time overlay, Bode magnitude, Bode phase, amplitude sweep)
    for tf in ["theta_elevator", "phi_aileron", "phi_rudder"] {
        for plot in ["time", "bode_mag", "bode_phase", "sweep"] {
            let id = format!("{tf}_{plot}");
            assert!(
                html.contains(&format!("<figure id=\"{id}\"><svg")),
                "{id} inline"
            );
            assert!(dir.join(format!("{id}.svg")).exists(), "{id}.svg");
        }
    }
    assert_eq!(html.matches("<svg").count(), 12);
    assert!(
        !html.contains("src=\"http") && !html.contains("href=\"http"),
        "no network"
    );
    assert!(dir.join("report.md").exists() && dir.join("report.json").exists());
    let models = v["models"]["theta/elevator"].as_array().unwrap();
    let wn = |name: &str| {
        models.iter().find(|m| m["model"] == name).unwrap()["modal"]["osc_omega_n_rad_s"]
            .as_f64()
            .unwrap()
    };
    // docs/jsbsim.md: linearized short period 6.1 rad/s at 4000 ft, 100 kts; SRIVC on a 2 deg doublet of the
    // nonlinear model lands within 3 % (measured 1.3 %: the nonlinearity at 2 deg is small).
    assert!((wn("jsbsim_linearization") - 6.11).abs() < 0.05);
    assert!((wn("srivc") / wn("jsbsim_linearization") - 1.0).abs() < 0.03);
    // the sweep scores the linearization at both amplitudes, and it fits worse at 6 deg than at 1 deg
    let sweep = v["sweep"]["theta/elevator"]["jsbsim_linearization"]
        .as_array()
        .unwrap();
    assert_eq!(sweep.len(), 2);
    assert!(sweep[1][1].as_f64().unwrap() < sweep[0][1].as_f64().unwrap());

    // the acceptance: the HTML opens in a browser, offline, and shows every plot
    opens_in_headless_chromium_with_every_plot(&dir, 12);
}

/// The report in headless Chromium with every plot (see `common::browser_check`: a visible skip without a
/// browser, a failure under CI).
fn opens_in_headless_chromium_with_every_plot(dir: &std::path::Path, figures: usize) {
    common::browser_check(dir, figures, &[]);
}

/// `flightid compare --aircraft c172x ARGS --report DIR --json FILE`: the report directory (kept alive by the
/// returned temporary directory) and the JSON.
fn compare(args: &[&str]) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
    let tmp = tempfile::tempdir().unwrap();
    let (dir, json) = (tmp.path().join("report"), tmp.path().join("compare.json"));
    common::run_ok(
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args(["compare", "--aircraft", "c172x"])
            .args(args)
            .arg("--report")
            .arg(&dir)
            .arg("--json")
            .arg(&json),
    );
    let v = common::read_json(&json);
    (tmp, dir, v)
}

/// [`compare`] with srivc only and a one-amplitude sweep, plus `extra` arguments.
fn quick_compare(extra: &[&str]) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
    let args: Vec<&str> = ["--method", "srivc", "--sweep-deg", "1"]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    compare(&args)
}

/// Fit % of JSBSim's linearization on each transfer function of a `compare --json` output.
fn linearization_fits(v: &serde_json::Value) -> std::collections::BTreeMap<String, f64> {
    v["models"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(tf, models)| {
            let lin = models
                .as_array()
                .unwrap()
                .iter()
                .find(|m| m["model"] == "jsbsim_linearization")
                .unwrap();
            (tf.clone(), lin["fit_percent"].as_f64().unwrap())
        })
        .collect()
}

#[test]
fn the_lateral_linearization_gap_is_the_sideslip_drag_that_the_linearization_cannot_see() {
    // c172x's CDbeta = 0.17·|β| has no derivative at β = 0: JSBSim's central-difference linearization sees none
    // of it, while a rudder or aileron doublet's sideslip always adds drag, whatever its sign, and the speed lost
    // leaves the aircraft in a bank the linear model does not have (scripts/oracle_rudder_spiral.py: the held bank
    // has the same sign for +A and −A doublets and grows with |A|). Measured: φ/δr 26 % → 94.6 %, φ/δa 84 % →
    // 94.5 % with CDbeta scaled to 0. Thresholds sit halfway between, far from both.
    let (_tmp, dir, v) = quick_compare(&[]);
    let with = linearization_fits(&v);
    let without = linearization_fits(&quick_compare(&["--scale", "CDbeta=0"]).2);
    eprintln!("linearization fit %, with CDbeta: {with:?}; without: {without:?}");
    assert!(with["phi/rudder"] < 50.0, "{with:?}");
    assert!(without["phi/rudder"] > 85.0, "{without:?}");
    assert!(without["phi/aileron"] > with["phi/aileron"] + 5.0);

    // The report finds that cause itself. The probe's one-sided differences at the trim find CDbeta's kink at
    // β = 0 (slopes ∓0.17 per rad, the XML's 0.17·|β|; the trim β is within the probe step of 0, so the upper
    // slope is a little less), and nothing else of the c172x's 32 coefficient functions ...
    let terms = v["nonsmooth_terms"].as_array().unwrap();
    assert_eq!(terms.len(), 1, "{terms:?}");
    assert_eq!(terms[0]["coefficient"], "CDbeta");
    assert_eq!(terms[0]["variable"], "beta");
    let (below, above) = (
        terms[0]["slope_below"].as_f64().unwrap(),
        terms[0]["slope_above"].as_f64().unwrap(),
    );
    assert!(
        (below + 0.17).abs() < 0.01 && (above - 0.17).abs() < 0.01,
        "{below} {above}"
    );
    // ... and measures its share of the φ/δr gap rather than guessing it (the same 94.6 % as above)
    let share = v["nonsmooth_shares"][0]["fit_percent_without"]["phi/rudder"]
        .as_f64()
        .unwrap();
    assert!((share - without["phi/rudder"]).abs() < 1.0, "{share}");
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("non-smooth terms"), "{md}");
    assert!(md.contains("CDbeta explains the gap"), "{md}");
}

#[test]
fn an_unknown_coefficient_to_scale_is_a_usage_error_that_lists_the_model_s_coefficients() {
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args([
            "compare",
            "--aircraft",
            "c172x",
            "--scale",
            "CDbta=0",
            "--report",
        ])
        .arg(tmp.path().join("report"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("'CDbta'") && err.contains("CDbeta"), "{err}");
    assert!(
        !tmp.path().join("report").exists(),
        "no report for a refused run"
    );
}
