//! `flightid paper` end to end (noise-free): simulate the three original TFs, ls, ISE, JSON and report.
//! Target (issue 3): under 1 s. Prints the median of 7 runs of the library call and of the binary.

use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let lib: Vec<f64> = (0..7)
        .map(|_| {
            let t = Instant::now();
            let run = flightid::paper::run(&flightid::paper::PaperOptions::new(0.0)).unwrap();
            let _ = std::hint::black_box(run.to_json());
            t.elapsed().as_secs_f64()
        })
        .collect();
    println!(
        "paper::run noise-free (3 TFs, 60 s at 100 Hz, ls) + JSON: median {:.1} ms",
        1e3 * median(lib)
    );
    let noisy: Vec<f64> = (0..3)
        .map(|_| {
            let t = Instant::now();
            let _ = std::hint::black_box(
                flightid::paper::run(&flightid::paper::PaperOptions::new(0.01)).unwrap(),
            );
            t.elapsed().as_secs_f64()
        })
        .collect();
    println!(
        "paper::run --noise 0.01 (ls, srivc, oe): median {:.1} ms",
        1e3 * median(noisy)
    );
    // the binary, if built alongside (cargo bench builds it into the same target directory)
    let exe = std::env::current_exe()
        .ok()
        .and_then(|p| p.parent()?.parent().map(|d| d.join("flightid")));
    if let Some(exe) = exe.filter(|e| e.exists()) {
        let dir = std::env::temp_dir().join(format!("flightid-paper-bench-{}", std::process::id()));
        let bin: Vec<f64> = (0..5)
            .map(|_| {
                let t = Instant::now();
                let out = std::process::Command::new(&exe)
                    .args(["paper", "--json"])
                    .arg(dir.join("p.json"))
                    .arg("--report")
                    .arg(&dir)
                    .output()
                    .unwrap();
                assert!(out.status.success());
                t.elapsed().as_secs_f64()
            })
            .collect();
        let _ = std::fs::remove_dir_all(&dir);
        println!("flightid paper --json --report (binary, noise-free): median {:.1} ms (target < 1000 ms)", 1e3 * median(bin));
    }
}
