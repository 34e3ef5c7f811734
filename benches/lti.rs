//! Benchmarks of the LTI toolkit and input design: the inner loops of output-error fitting
//! (simulation, discretisation) and of maneuver generation.

use divan::black_box;
use flightid::lti::{c2d_tf, d2c_tf, lsim, roots, Discretization, TransferFunction};
use flightid::signal::{generate, Maneuver};

fn main() {
    divan::main();
}

/// φ/δa of Şahin & Kalyon (2021) eq. 67 (unstable spiral).
fn phi_aileron() -> TransferFunction {
    TransferFunction::new(
        vec![26.8666, 0.4725, 94.0527],
        vec![1.0, 1.8683, 3.6856, 6.2648, -0.0085],
    )
}

/// 60 s at 120 Hz of a doublet: one output-error cost evaluation.
#[divan::bench]
fn lsim_4th_order_60s_120hz(bencher: divan::Bencher) {
    let dt = 1.0 / 120.0;
    let u = generate(&Maneuver::Doublet { pulse_s: 1.0 }, dt, 60.0, 1.0);
    let tf = phi_aileron();
    bencher.bench(|| lsim(black_box(&tf), black_box(&u), dt));
}

#[divan::bench]
fn c2d_zoh_then_d2c_4th_order(bencher: divan::Bencher) {
    let tf = phi_aileron();
    bencher.bench(|| {
        let d = c2d_tf(black_box(&tf), 0.01, Discretization::Zoh);
        d2c_tf(&d, Discretization::Zoh)
    });
}

#[divan::bench]
fn roots_of_8th_degree(bencher: divan::Bencher) {
    let p = [1.0, 3.0, 40.0, 60.0, 300.0, 200.0, 500.0, 80.0, 7.0];
    bencher.bench(|| roots(black_box(&p)));
}

#[divan::bench]
fn multisine_20_harmonics_60s_120hz(bencher: divan::Bencher) {
    let m = Maneuver::Multisine {
        f_min_hz: 0.1,
        f_max_hz: 2.0,
        n_harmonics: 20,
        period_s: 20.0,
    };
    bencher.bench(|| generate(black_box(&m), 1.0 / 120.0, 60.0, 1.0));
}
