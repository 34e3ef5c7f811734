//! `iv` (δ-operator instrumental variables, then continuous conversion; src/ident/iv.rs) on the paper's three
//! transfer functions (Şahin & Kalyon 2021, eq. 65, 67, 69): exact on noise-free data like the paper's least
//! squares, and consistent under output noise where that least squares collapses (tests/paper_acceptance.rs).

use flightid::ident::{self, IdentOptions, Method};
use flightid::paper::{self, PaperOptions};
use flightid::signal::{self, Maneuver};

#[test]
fn noise_free_iv_recovers_every_original_coefficient_within_half_percent() {
    // The δ-model is the exact ZOH equivalent, so noise-free data give the original back (measured ≤ 3e-8 %);
    // 0.5 % is the noise-free acceptance for the paper reproduction.
    let mut opts = PaperOptions::new(0.0);
    opts.methods = vec![Method::Iv];
    let run = paper::run(&opts).unwrap();
    for t in &run.tfs {
        let r = t.methods[0].result.as_ref().unwrap();
        assert!(r.warnings.is_empty(), "{}: {:?}", t.tf.key, r.warnings);
        for (i, e) in paper::coefficient_rel_errors(&r.tf, &t.tf.original)
            .iter()
            .enumerate()
        {
            eprintln!("{} coefficient {i}: {:.2e} %", t.tf.key, 100.0 * e);
            assert!(*e < 0.005, "{} coefficient {i}: {e}", t.tf.key);
        }
    }
}

#[test]
fn iv_places_the_dominant_poles_of_all_three_paper_tfs_within_3_percent_under_one_percent_noise() {
    // 1 % white output noise, 60 s doublet at 100 Hz, three noise seeds. The q-domain IV this replaced diverged on
    // φ/δa and φ/δr (dominant pole errors ≈ 100 %). Measured with the δ-operator IV over seeds 1-3: θ/δe
    // ≤ 0.03 %, φ/δa ≤ 0.12 %, φ/δr 1.4-2.5 % (its roll mode; φ/δr's small gain makes it the noisiest of the three).
    // Tolerance: the 3 % for noise-robust estimators. No fallback warning: the IV iterations themselves
    // converge.
    for seed in 1..=3 {
        let mut opts = PaperOptions::new(0.01);
        opts.seed = seed;
        opts.methods = vec![Method::Iv];
        let run = paper::run(&opts).unwrap();
        for t in &run.tfs {
            let r = t.methods[0].result.as_ref().unwrap();
            let err = paper::dominant_pole_error(&t.tf.original, &r.poles);
            eprintln!(
                "seed {seed} {} iv: dominant pole error {:.3} %, fit {:.2} %",
                t.tf.key,
                100.0 * err,
                r.fit_sim_percent
            );
            assert!(r.warnings.is_empty(), "{}: {:?}", t.tf.key, r.warnings);
            assert!(
                err < 0.03,
                "seed {seed} {}: dominant pole error {err}",
                t.tf.key
            );
        }
    }
}

#[test]
fn when_the_iv_iterations_fail_iv_returns_its_srivc_start_with_a_warning() {
    // A 2nd-order system (ωn 2 rad/s, ζ 0.25) fitted with 4 poles and 2 zeros, noise-free: the extra pole pair
    // cancels against the zeros, the IV iterate's numerator regression is singular, and iv falls back to the SRIVC
    // estimate it started from — which fits these data exactly — saying so in `warnings`.
    let dt_s = 0.01;
    let mut u = signal::generate(&Maneuver::Doublet { pulse_s: 1.0 }, dt_s, 30.0, 1.0);
    u.resize(3000, 0.0);
    let y = ident::simulate_tf(&[4.0], &[1.0, 1.0, 4.0], &u, dt_s);
    let opts = IdentOptions {
        method: Method::Iv,
        ..IdentOptions::default()
    };
    let r = ident::identify(&u, &y, dt_s, &opts).unwrap();
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(
        r.warnings[0].contains("returning its starting estimate (srivc)"),
        "{}",
        r.warnings[0]
    );
    assert!(r.fit_sim_percent > 99.9, "fit {}", r.fit_sim_percent);
    let srivc = ident::identify(
        &u,
        &y,
        dt_s,
        &IdentOptions {
            method: Method::Srivc,
            ..opts
        },
    )
    .unwrap();
    assert_eq!(r.tf.den, srivc.tf.den);
    // the same record through the CLI: the warning reaches stderr, the run still succeeds
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("second_order.csv");
    let mut text = String::from("time_s,elevator_rad,theta_rad\n");
    for k in 0..u.len() {
        text.push_str(&format!("{},{},{}\n", k as f64 * dt_s, u[k], y[k]));
    }
    std::fs::write(&csv, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(["identify", "--data"])
        .arg(&csv)
        .args([
            "--input",
            "elevator",
            "--output",
            "theta_rad",
            "--method",
            "iv",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning: iv did not converge"), "{stderr}");
}
