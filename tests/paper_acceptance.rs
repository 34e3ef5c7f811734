//! Acceptance on the paper's three transfer functions (Şahin & Kalyon 2021, Section 4), through the
//! `flightid::paper` library and the `flightid paper` binary.

mod common;

use flightid::ident::Method;
use flightid::paper::{self, derivatives, PaperInput, PaperOptions, PaperRun};
use num_complex::Complex64;
use std::process::Command;

/// Largest |p̂ − p| / σ over the slow poles (phugoid, spiral) of every TF for `method`, with σ = √(σ_re² + σ_im²).
fn slow_pole_sigmas(run: &PaperRun, method: Method) -> Vec<(String, Complex64, Complex64, f64)> {
    let mut out = Vec::new();
    for t in &run.tfs {
        let m = t.methods.iter().find(|m| m.method == method).unwrap();
        let r = m.result.as_ref().unwrap();
        assert_eq!(
            r.pole_std.len(),
            r.poles.len(),
            "{} {method}: pole std",
            t.tf.key
        );
        for p in paper::slow_poles(&t.tf.original) {
            let k = paper::nearest_pole(&r.poles, p).unwrap();
            out.push((t.tf.key.to_string(), p, r.poles[k], r.pole_std[k].norm()));
        }
    }
    out
}

#[test]
fn noise_free_paper_run_recovers_every_original_coefficient_within_half_percent() {
    // Acceptance: noise-free doublet, 100 Hz, 60 s; ls gives every coefficient within 0.5 % (measured: ≤ 0.003 %),
    // while the paper's own printed estimates miss φ/δr's a0 by 63.5 %.
    let run = paper::run(&PaperOptions::new(0.0)).unwrap();
    for t in &run.tfs {
        let r = t.methods[0].result.as_ref().unwrap();
        for (i, e) in paper::coefficient_rel_errors(&r.tf, &t.tf.original)
            .iter()
            .enumerate()
        {
            assert!(*e < 0.005, "{} coefficient {i}: {e}", t.tf.key);
        }
        assert!(
            t.methods[0].ise < 1e-9,
            "{}: ISE {}",
            t.tf.key,
            t.methods[0].ise
        );
        assert!(
            t.ise_paper_lsm > 1e-6,
            "{}: paper ISE {}",
            t.tf.key,
            t.ise_paper_lsm
        );
    }
    let (worst, tf, coef) = paper::paper_lsm_worst_error();
    assert!((worst - 0.635).abs() < 0.001 && tf == "phi/rudder" && coef == "a0");
    assert!(run.paper_lsm_text().contains("up to 64 %"));
}

#[test]
fn noise_free_ls_recovers_the_dimensional_control_derivatives_within_half_percent() {
    // The paper gives TF coefficients only, so M_δe, L'_δa, L'_δr (the s² numerator coefficient of
    // θ/δe, φ/δa, φ/δr) are what can be backed out. Truth must be the printed coefficient it comes from; the ls
    // estimate from the simulated doublet (not from the printed TF) within 0.5 % (measured ≤ 0.0001 %).
    let run = paper::run(&PaperOptions::new(0.0)).unwrap();
    let rows = derivatives::derivative_rows(&run);
    let names: Vec<_> = rows.iter().map(|r| r.spec.name).collect();
    assert_eq!(names, ["M_de", "L'_da", "L'_dr"]);
    for (r, printed) in rows.iter().zip([-24.7885, 26.8666, 0.5749]) {
        assert_eq!(r.truth, printed, "{}", r.spec.name);
        let ls = r.estimates.iter().find(|e| e.source == "ls").unwrap();
        assert!(
            ls.rel_error < 0.005,
            "{}: ls {} vs {}",
            r.spec.name,
            ls.value,
            r.truth
        );
        assert!(((ls.value - r.truth) / r.truth).abs() == ls.rel_error);
    }
    let json = run.to_json();
    assert_eq!(json["derivatives"]["rows"][0]["truth"], -24.7885);
    assert!(json["derivatives"]["paper_omits"]
        .as_str()
        .unwrap()
        .contains("mass"));
}

#[test]
fn with_one_percent_noise_ls_collapses_and_srivc_oe_hold_the_dominant_poles() {
    // Acceptance: 1 % white output noise, 60 s doublet. ls misplaces the dominant poles by > 20 % (measured 36-116 %);
    // srivc and oe within 3 % (measured ≤ 0.6 %, φ/δr's roll mode).
    let run = paper::run(&PaperOptions::new(0.01)).unwrap();
    for t in &run.tfs {
        for m in &t.methods {
            let r = m.result.as_ref().unwrap();
            let err = paper::dominant_pole_error(&t.tf.original, &r.poles);
            if m.method == Method::Ls {
                assert!(err > 0.2, "{}: ls unexpectedly good ({err})", t.tf.key);
            } else {
                assert!(
                    err < 0.03,
                    "{} {}: dominant pole error {err}",
                    t.tf.key,
                    m.method
                );
            }
        }
    }
    // The control derivatives follow the poles: srivc and oe within 1 % (measured ≤ 0.17 %, L'_δr), ls off by > 50 %
    // (measured 65 % on M_δe, ~3300 % on L'_δa and L'_δr).
    for r in derivatives::derivative_rows(&run) {
        for e in r.estimates.iter().filter(|e| e.source != "paper_lsm") {
            if e.source == "ls" {
                assert!(
                    e.rel_error > 0.5,
                    "{}: ls unexpectedly good {}",
                    r.spec.name,
                    e.value
                );
            } else {
                assert!(
                    e.rel_error < 0.01,
                    "{} {}: {} vs {}",
                    r.spec.name,
                    e.source,
                    e.value,
                    r.truth
                );
            }
        }
    }
    let json = run.to_json();
    for key in ["theta/elevator", "phi/aileron", "phi/rudder"] {
        for entry in ["original", "paper_lsm", "ls", "srivc", "oe"] {
            assert_eq!(json[key][entry]["den"][0], 1.0, "{key} {entry}");
            assert_eq!(json[key][entry]["num"].as_array().unwrap().len(), 3);
        }
        assert!(json[key]["ise"]["oe"].as_f64().unwrap() < 1e-3);
    }
}

#[test]
fn srivc_and_oe_report_the_slow_poles_with_three_sigma_bands_that_cover_the_truth_and_tighten_with_more_data(
) {
    // Acceptance: phugoid (θ/δe) and spiral (φ/δa, φ/δr), barely excited by one doublet, are reported with standard
    // errors whose 3σ band covers the truth. Both estimators estimate a constant output offset beside the model;
    // without it the noise in the 1 s of pre-input trim biased the spiral by up to 20σ (oe) and 5σ (srivc). srivc
    // also keeps a slow unstable spiral in its prefilter and instruments (reflecting it left the 300 s spiral 12σ off).
    // Measured (seed 1), srivc and oe alike: 60 s doublet ≤ 1.6σ; 300 s doublet ≤ 0.92σ with σ 9-16× smaller;
    // 60 s 3211 ≤ 1.54σ with σ 6-54× smaller.
    let base = paper::run(&PaperOptions::new(0.01)).unwrap();
    // A longer record (300 s) and a richer input (3211) must shrink σ of every slow pole.
    let mut longer = PaperOptions::new(0.01);
    longer.duration_s = 300.0;
    longer.methods = vec![Method::Srivc, Method::Oe];
    let mut richer = PaperOptions::new(0.01);
    richer.input = PaperInput::ThreeTwoOneOne;
    richer.methods = vec![Method::Srivc, Method::Oe];
    let longer = paper::run(&longer).unwrap();
    let richer = paper::run(&richer).unwrap();
    let mut failures = Vec::new();
    for method in [Method::Srivc, Method::Oe] {
        let short = slow_pole_sigmas(&base, method);
        for (key, p, q, sd) in &short {
            eprintln!(
                "{method} 60 s doublet {key}: slow pole {p} est {q} σ {sd:.2e} ({:.2}σ)",
                (q - p).norm() / sd
            );
            assert!(sd.is_finite() && *sd > 0.0, "{method} {key}: σ {sd}");
            if (q - p).norm() > 3.0 * sd {
                failures.push(format!(
                    "{method} 60 s doublet {key}: {q} vs {p}, 3σ = {}",
                    3.0 * sd
                ));
            }
        }
        for (label, run) in [("300 s doublet", &longer), ("60 s 3211", &richer)] {
            for ((key, p, q, sd), (_, _, _, sd0)) in
                slow_pole_sigmas(run, method).iter().zip(&short)
            {
                eprintln!(
                    "{method} {label} {key}: slow pole {p} est {q} σ {sd:.2e} ({:.2}σ; 60 s doublet σ {sd0:.2e})",
                    (q - p).norm() / sd
                );
                if sd >= sd0 {
                    failures.push(format!("{method} {label} {key}: σ {sd} not below {sd0}"));
                }
                if (q - p).norm() > 3.0 * sd {
                    failures.push(format!(
                        "{method} {label} {key}: {q} vs {p}, 3σ = {}",
                        3.0 * sd
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn paper_command_writes_json_and_a_report_with_the_three_figures() {
    let dir = tempfile::tempdir().unwrap();
    let json_path = dir.path().join("paper.json");
    let report = dir.path().join("report");
    let out = common::run_ok(
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args(["paper", "--json"])
            .arg(&json_path)
            .arg("--report")
            .arg(&report),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("up to 64 %") && stdout.contains("100 Hz"),
        "{stdout}"
    );
    let v = common::read_json(&json_path);
    assert_eq!(v["theta/elevator"]["original"]["num"][0], -24.7885);
    assert_eq!(v["phi/rudder"]["paper_lsm"]["den"][4], -0.0031);
    assert!(v["phi/aileron"]["ise"]["ls"].as_f64().unwrap() < 1e-9);
    for fig in ["fig5_theta_elevator", "fig7_phi_aileron", "fig9_phi_rudder"] {
        assert!(report.join(format!("{fig}.svg")).exists(), "{fig}");
    }
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(
        html.contains("Table 2")
            || html.contains("paper&#x27;s Table 2")
            || html.contains("Integral square error")
    );
    // bad option → exit 2
    let bad = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(["paper", "--noise", "-1"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}
