//! Reader throughput: CSV of 1,000,000 rows × 18 schema columns (target < 1 s, issue 6) and a
//! `.tlog` of 1,000,000 MAVLink messages (target ≥ 1 M messages/s).
//!
//! Run: `cargo bench --bench data`.

use std::path::PathBuf;
use std::sync::OnceLock;

use flightid::data::{read_csv, write_csv_atomic, FlightRecord, SCHEMA_COLUMNS};

fn main() {
    divan::main();
}

const ROWS: usize = 1_000_000;

/// A 100 Hz flight of 10,000 s with realistic full-precision values, written once per run.
fn csv_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let path = std::env::temp_dir().join(format!("flightid-bench-{}.csv", std::process::id()));
        let time_s: Vec<f64> = (0..ROWS).map(|i| i as f64 * 0.01).collect();
        let mut rec = FlightRecord::new(time_s.clone());
        for (k, name) in SCHEMA_COLUMNS.iter().enumerate().skip(1) {
            let w = 0.1 + 0.05 * k as f64;
            rec.push_column(
                name,
                time_s
                    .iter()
                    .map(|t| 0.2 * (w * t).sin() + 0.01 * k as f64)
                    .collect(),
            );
        }
        write_csv_atomic(&path, &rec).expect("write bench CSV");
        path
    })
}

#[divan::bench(sample_count = 5)]
fn read_csv_1m_rows_18_columns(bencher: divan::Bencher) {
    let path = csv_path();
    bencher.bench(|| {
        let rec = read_csv(path).expect("bench CSV reads");
        assert_eq!(rec.len(), ROWS);
        rec
    });
}
