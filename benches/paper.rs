//! The paper's performance targets, all in one run (`cargo bench --bench paper`):
//! 1. ARX least squares on 200,000 samples × 8 parameters against `numpy.linalg.lstsq` on the same-size ARX(4, 4)
//!    regressor of the same record type (`scripts/bench_lstsq.py`, run here with the provisioned venv's Python),
//!    with the ratio — target: flightid at least as fast (ratio ≤ 1);
//! 2. `srivc` and `oe` on a 60 s, 120 Hz doublet record of the paper's θ/δe with 1 % output noise — target < 100 ms;
//! 3. `flightid paper` end to end, noise-free — target < 1 s (library call and the binary).
//!
//! Medians of repeated runs; the 1-minute load average is printed beside them (the box is shared).

use flightid::ident::{self, IdentOptions, Method};
use flightid::signal::{self, Maneuver};
use std::time::Instant;

/// The paper's θ/δe (Şahin & Kalyon 2021, eq. 65).
const NUM: [f64; 3] = [-24.7885, -18.2186, -0.4659];
const DEN: [f64; 5] = [1.0, 2.0072, 32.5269, 0.8638, 0.0179];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median wall time of `runs` calls of `f`, in milliseconds.
fn time_ms<T>(runs: usize, mut f: impl FnMut() -> T) -> f64 {
    median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                1e3 * t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// Unit doublet (1 s pulses from t = 1 s), exact ZOH response of θ/δe, white noise of 1 % of std(y).
fn record(n: usize, dt_s: f64) -> (Vec<f64>, Vec<f64>) {
    let duration_s = n as f64 * dt_s;
    let mut u = signal::generate(&Maneuver::Doublet { pulse_s: 1.0 }, dt_s, duration_s, 1.0);
    u.resize(n, 0.0);
    let y = ident::simulate_tf(&NUM, &DEN, &u, dt_s);
    let mean = y.iter().sum::<f64>() / n as f64;
    let sd = (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
    (u, signal::add_white_noise(&y, 0.01 * sd, 1))
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".into())
}

/// `(lstsq alone, regressor build + lstsq)` in ms from `scripts/bench_lstsq.py`, or why not.
fn numpy_lstsq_ms() -> Result<(f64, f64), String> {
    let python = flightid::sim::env::python().map_err(|e| e.to_string())?;
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/bench_lstsq.py");
    let out = std::process::Command::new(python)
        .arg(script)
        .output()
        .map_err(|e| e.to_string())?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("RESULT"))
        .ok_or_else(|| format!("no RESULT line: {}", String::from_utf8_lossy(&out.stderr)))?;
    let value = |key: &str| {
        line.split_whitespace()
            .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| format!("no {key} in '{line}'"))
    };
    Ok((value("lstsq_ms")?, value("build_lstsq_ms")?))
}

fn main() {
    println!("load average (1 min) at start: {}", load_average());

    // 1. ARX LS, 200,000 rows × 8 columns: ARX(4, 4) on a 2000 s record at 100 Hz
    let (u, y) = record(200_004, 0.01);
    let rust_ms = time_ms(7, || ident::arx_least_squares(&u, &y, 4, 4).unwrap());
    println!("ARX LS 200,000 x 8, flightid (regressor build + two-thread TSQR (Householder), column-pivoted QR only if ill-conditioned): median {rust_ms:.1} ms");
    match numpy_lstsq_ms() {
        Ok((lstsq_ms, build_ms)) => {
            println!(
                "numpy.linalg.lstsq (LAPACK gelsd, SVD) 200,000 x 8 (regressor prebuilt): median {lstsq_ms:.1} ms"
            );
            println!("numpy regressor build + lstsq: median {build_ms:.1} ms");
            println!(
                "ratio flightid / numpy: {:.2} (vs lstsq alone), {:.2} (vs build + lstsq); target <= 1",
                rust_ms / lstsq_ms,
                rust_ms / build_ms
            );
        }
        Err(e) => println!("numpy comparison skipped: {e}"),
    }

    // 2. srivc and oe, 60 s at 120 Hz
    let dt_s = 1.0 / 120.0;
    let (u, y) = record(7201, dt_s);
    for method in [Method::Srivc, Method::Oe] {
        let opts = IdentOptions {
            method,
            ..IdentOptions::default()
        };
        let ms = time_ms(7, || ident::identify(&u, &y, dt_s, &opts).unwrap());
        println!("{method} on 60 s at 120 Hz (7201 samples, 4 poles / 2 zeros): median {ms:.1} ms (target < 100 ms)");
    }

    // 3. flightid paper
    let lib = time_ms(7, || {
        let run = flightid::paper::run(&flightid::paper::PaperOptions::new(0.0)).unwrap();
        run.to_json()
    });
    println!("paper::run noise-free (3 TFs, 60 s at 100 Hz, ls) + JSON: median {lib:.1} ms");
    let noisy = time_ms(3, || {
        flightid::paper::run(&flightid::paper::PaperOptions::new(0.01)).unwrap()
    });
    println!("paper::run --noise 0.01 (ls, srivc, oe): median {noisy:.1} ms");
    // the binary, if built alongside (cargo bench builds it into the same target directory)
    let exe = std::env::current_exe()
        .ok()
        .and_then(|p| p.parent()?.parent().map(|d| d.join("flightid")));
    if let Some(exe) = exe.filter(|e| e.exists()) {
        let dir = std::env::temp_dir().join(format!("flightid-paper-bench-{}", std::process::id()));
        let bin = time_ms(5, || {
            let out = std::process::Command::new(&exe)
                .args(["paper", "--json"])
                .arg(dir.join("p.json"))
                .arg("--report")
                .arg(&dir)
                .output()
                .unwrap();
            assert!(out.status.success());
        });
        let _ = std::fs::remove_dir_all(&dir);
        println!(
            "flightid paper --json --report (binary, noise-free): median {bin:.1} ms (target < 1000 ms)"
        );
    }
    println!("load average (1 min) at end: {}", load_average());
}
