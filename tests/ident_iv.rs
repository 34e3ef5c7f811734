//! `iv` (δ-operator instrumental variables, then continuous conversion; src/ident/iv.rs) on the paper's three
//! transfer functions (Şahin & Kalyon 2021, eq. 65, 67, 69): exact on noise-free data like the paper's least
//! squares, and consistent under output noise where that least squares collapses (tests/paper_acceptance.rs).

use flightid::ident::Method;
use flightid::paper::{self, PaperOptions};

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
