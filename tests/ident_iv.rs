//! `iv` (δ-operator instrumental variables, then continuous conversion; src/ident/iv.rs) on the paper's three
//! transfer functions (Şahin & Kalyon 2021, eq. 65, 67, 69): exact on noise-free data like the paper's least
//! squares, and consistent under output noise where that least squares collapses (tests/paper_acceptance.rs).

mod common;

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
fn an_iv_fit_s_warnings_reach_stderr_and_the_run_still_succeeds() {
    // A slowly divergent first-order system, 1/(s − 0.2), over 30 s (e^6 ≈ 400-fold growth): iv finds the
    // unstable pole and the identification warns that the model grows over the record. (iv's own fallback to its
    // SRIVC start is unit-tested in src/ident/iv.rs: a near-singular scenario that triggers it end to end depends
    // on the last bits of the SRIVC start.)
    let dt_s = 0.01;
    let mut u = signal::generate(&Maneuver::Doublet { pulse_s: 1.0 }, dt_s, 30.0, 1.0);
    u.resize(3000, 0.0);
    let y = ident::simulate_tf(&[1.0], &[1.0, -0.2], &u, dt_s);
    let opts = IdentOptions {
        method: Method::Iv,
        poles: 1,
        zeros: 0,
        estimate_delay: false,
    };
    let r = ident::identify(&u, &y, dt_s, &opts).unwrap();
    assert!((r.tf.den[1] + 0.2).abs() < 1e-6, "{:?}", r.tf.den);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("grows"), "{}", r.warnings[0]);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("divergent.csv");
    let mut text = String::from("time_s,elevator_rad,theta_rad\n");
    for k in 0..u.len() {
        text.push_str(&format!("{},{},{}\n", k as f64 * dt_s, u[k], y[k]));
    }
    std::fs::write(&csv, text).unwrap();
    let out = common::run_ok(
        std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args(["identify", "--data"])
            .arg(&csv)
            .args([
                "--input",
                "elevator",
                "--output",
                "theta_rad",
                "--method",
                "iv",
                "--poles",
                "1",
                "--zeros",
                "0",
            ]),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("warning: pole"), "{stderr}");
    assert!(stderr.contains("grows"), "{stderr}");
}
