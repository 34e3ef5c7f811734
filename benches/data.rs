//! Reader throughput: CSV of 1,000,000 rows × 18 schema columns (target < 1 s) and a
//! `.tlog` of 1,000,000 MAVLink messages (target ≥ 1 M messages/s). The CSV is read twice: with
//! full round-trip precision (17 significant digits, the worst case) and rounded to 7 digits.
//! The bench files are written to the temp dir and removed at the end.
//!
//! Run: `cargo bench --bench data`.

use std::path::PathBuf;
use std::sync::OnceLock;

use flightid::data::{read_csv, write_csv_atomic, FlightRecord, SCHEMA_COLUMNS};

fn main() {
    divan::main();
    for p in [csv_path(), csv_path_7_digits()] {
        let _ = std::fs::remove_file(p);
    }
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

/// The same flight rounded to 7 significant digits, as flight-test instrumentation exports it.
fn csv_path_7_digits() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let path = std::env::temp_dir().join(format!("flightid-bench7-{}.csv", std::process::id()));
        let full = read_csv(csv_path()).expect("full-precision bench CSV");
        let round7 = |v: &f64| format!("{v:.6e}").parse::<f64>().unwrap_or(*v);
        let mut rec = FlightRecord::new(full.time_s.clone());
        for (name, values) in &full.columns {
            rec.push_column(name, values.iter().map(round7).collect());
        }
        write_csv_atomic(&path, &rec).expect("write bench CSV");
        path
    })
}

#[divan::bench(sample_count = 5)]
fn read_csv_1m_rows_18_columns_7_digits(bencher: divan::Bencher) {
    let path = csv_path_7_digits();
    bencher.bench(|| {
        let rec = read_csv(path).expect("bench CSV reads");
        assert_eq!(rec.len(), ROWS);
        rec
    });
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

const MESSAGES: usize = 1_000_000;

/// 1,000,000 MAVLink records (v1/v2 mix: ATTITUDE, SCALED_IMU, VFR_HUD, SERVO_OUTPUT_RAW,
/// HEARTBEAT) as a `.tlog` byte stream, 200 Hz of records.
fn tlog_bytes() -> &'static Vec<u8> {
    use mavlink::dialects::ardupilotmega::*;
    use mavlink::{MavHeader, MavlinkVersion};
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let mut out = Vec::with_capacity(MESSAGES * 50);
        let header = MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 0,
        };
        for k in 0..MESSAGES {
            let t = k as f32 * 0.005;
            let msg = match k % 5 {
                0 => MavMessage::ATTITUDE(ATTITUDE_DATA {
                    roll: 0.1 * t.sin(),
                    pitch: 0.05 * t.cos(),
                    yaw: 1.0,
                    rollspeed: 0.01,
                    pitchspeed: 0.02,
                    yawspeed: 0.03,
                    time_boot_ms: k as u32,
                }),
                1 => MavMessage::SCALED_IMU(SCALED_IMU_DATA {
                    xacc: 40,
                    zacc: -1000,
                    ..Default::default()
                }),
                2 => MavMessage::VFR_HUD(VFR_HUD_DATA {
                    airspeed: 50.0,
                    alt: 1200.0,
                    throttle: 60,
                    ..Default::default()
                }),
                3 => MavMessage::SERVO_OUTPUT_RAW(SERVO_OUTPUT_RAW_DATA {
                    servo1_raw: 1500,
                    servo2_raw: 1480,
                    servo3_raw: 1600,
                    servo4_raw: 1510,
                    ..Default::default()
                }),
                _ => MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()),
            };
            out.extend_from_slice(&(1_700_000_000_000_000u64 + k as u64 * 1000).to_be_bytes());
            let v = if k % 2 == 0 {
                MavlinkVersion::V2
            } else {
                MavlinkVersion::V1
            };
            mavlink::write_versioned_msg(&mut out, v, header, &msg).expect("encode");
        }
        out
    })
}

#[divan::bench(sample_count = 5)]
fn read_tlog_1m_messages(bencher: divan::Bencher) {
    use flightid::data::{parse_tlog_bytes, ServoMap, TlogOptions};
    let bytes = tlog_bytes();
    let map_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("aircraft/servo_maps/c172x.toml");
    let servo_map = ServoMap::load(&map_path).expect("c172x mapping");
    bencher.bench(|| {
        let rep = parse_tlog_bytes(bytes, "bench", Some(&servo_map), &TlogOptions::default())
            .expect("bench tlog reads");
        assert_eq!(rep.stats.frames, MESSAGES);
        rep
    });
}
