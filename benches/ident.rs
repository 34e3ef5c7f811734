//! Benchmarks for `ident` (performance targets):
//! - ARX least squares on 200,000 samples with 8 parameters (compare with
//!   `scripts/bench_lstsq.py`, numpy.linalg.lstsq on the same-size regressor);
//! - `srivc` and `oe` on a 60 s, 120 Hz doublet record of the paper's θ/δe with 1 % noise
//!   (target < 100 ms).

use flightid::ident::{identify, IdentOptions, Method};

fn main() {
    divan::main();
}

/// Unit doublet on [1 s, 3 s), the exact ZOH response of θ/δe (Şahin & Kalyon 2021, eq. 65)
/// and deterministic pseudo-noise of 1 % of std(y).
fn record(seconds: f64, dt_s: f64) -> (Vec<f64>, Vec<f64>) {
    let n = (seconds / dt_s).round() as usize + 1;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * dt_s;
            if (1.0..2.0).contains(&t) {
                1.0
            } else if (2.0..3.0).contains(&t) {
                -1.0
            } else {
                0.0
            }
        })
        .collect();
    let y = flightid::ident::simulate_tf(
        &[-24.7885, -18.2186, -0.4659],
        &[1.0, 2.0072, 32.5269, 0.8638, 0.0179],
        &u,
        dt_s,
    );
    let mean = y.iter().sum::<f64>() / n as f64;
    let sd = (y.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64).sqrt();
    // xorshift noise, uniform with the same standard deviation as N(0, (0.01 sd)²)
    let mut state = 0x9E3779B97F4A7C15_u64;
    let y = y
        .iter()
        .map(|v| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let uni = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            v + 0.01 * sd * uni * 12f64.sqrt()
        })
        .collect();
    (u, y)
}

#[divan::bench]
fn arx_ls_200k_samples_8_params(bencher: divan::Bencher) {
    // 200,000 rows × 8 columns: ARX(4, 4) on a 2000 s record at 100 Hz
    let (u, y) = record(1999.99, 0.01);
    assert_eq!(u.len(), 200_000);
    bencher.bench(|| flightid::ident::arx_least_squares(&u, &y, 4, 4).unwrap());
}

#[divan::bench(args = [Method::Srivc, Method::Oe])]
fn continuous_60s_120hz(bencher: divan::Bencher, method: Method) {
    let (u, y) = record(60.0, 1.0 / 120.0);
    let opts = IdentOptions {
        method,
        poles: 4,
        zeros: 2,
        estimate_delay: false,
    };
    bencher.bench(|| identify(&u, &y, 1.0 / 120.0, &opts).unwrap());
}
