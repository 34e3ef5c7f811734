//! Specification of the MAVLink `.tlog` reader and the pymavlink fixture
//! round trip.

use std::path::{Path, PathBuf};
use std::process::Command;

use flightid::data::tlog::{StretchChoice, TlogOptions};
use flightid::data::{
    parse_tlog_bytes, read_tlog, write_csv_atomic, AirspeedKind, DataError, FlightRecord, ServoMap,
};
use mavlink::dialects::ardupilotmega::{MavMessage, ATTITUDE_DATA, HEARTBEAT_DATA};
use mavlink::{MavHeader, MavlinkVersion};

fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn c172x() -> ServoMap {
    ServoMap::load(&repo_root().join("aircraft/servo_maps/c172x.toml")).unwrap()
}

/// Appends one `.tlog` record: big-endian µs timestamp + frame encoded by the `mavlink` crate.
fn push(out: &mut Vec<u8>, time_us: u64, sysid: u8, version: MavlinkVersion, msg: &MavMessage) {
    out.extend_from_slice(&time_us.to_be_bytes());
    let header = MavHeader {
        system_id: sysid.into(),
        component_id: 1,
        sequence: 0,
    };
    mavlink::write_versioned_msg(out, version, header, msg).unwrap();
}

fn attitude(roll: f32) -> MavMessage {
    MavMessage::ATTITUDE(ATTITUDE_DATA {
        roll,
        pitch: 0.05,
        yaw: 3.1,
        rollspeed: 0.01,
        pitchspeed: -0.02,
        yawspeed: 0.03,
        ..Default::default()
    })
}

/// 100 ATTITUDE records at 50 Hz from system 1, alternating v1/v2, with roll = 0.001·k.
fn simple_records() -> Vec<Vec<u8>> {
    (0..100u64)
        .map(|k| {
            let v = if k % 2 == 0 {
                MavlinkVersion::V1
            } else {
                MavlinkVersion::V2
            };
            let mut out = Vec::new();
            push(
                &mut out,
                1_000_000 + 20_000 * k,
                1,
                v,
                &attitude(0.001 * k as f32),
            );
            out
        })
        .collect()
}

fn simple_log() -> Vec<u8> {
    simple_records().concat()
}

#[test]
fn clean_log_gives_every_frame_and_a_50_hz_grid() {
    let bytes = simple_log();
    let rep = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default()).unwrap();
    assert_eq!(rep.stats.frames, 100);
    assert_eq!((rep.stats.frames_v1, rep.stats.frames_v2), (50, 50));
    assert_eq!(rep.stats.skipped_bytes, 0);
    let rec = &rep.record;
    assert_eq!(rec.len(), 100);
    assert!((rec.dt_s().unwrap() - 0.02).abs() < 1e-12);
    let phi = rec.column("phi_rad").unwrap();
    // float32 field: agreement to f32 rounding.
    assert!((phi[37] - 0.037).abs() < 1e-7, "{}", phi[37]);
    assert!(rec.validate().is_ok());
}

#[test]
fn yaw_crossing_pi_is_unwrapped() {
    let mut out = Vec::new();
    for k in 0..20u64 {
        let yaw = 3.0 + 0.05 * k as f64; // crosses π at k ≈ 3
        let wrapped = (yaw.sin()).atan2(yaw.cos()) as f32;
        let msg = MavMessage::ATTITUDE(ATTITUDE_DATA {
            yaw: wrapped,
            ..Default::default()
        });
        push(&mut out, 10_000 * k, 1, MavlinkVersion::V2, &msg);
    }
    let rep = parse_tlog_bytes(&out, "mem", None, &TlogOptions::default()).unwrap();
    let psi = rep.record.column("psi_rad").unwrap();
    assert!(
        (psi[19] - 3.95).abs() < 1e-6,
        "continuous heading, got {}",
        psi[19]
    );
}

#[test]
fn corrupt_bytes_are_skipped_and_counted() {
    let mut records = simple_records();
    // Flip a payload byte of record 50: its CRC fails, so the whole record is skipped.
    records[50][8 + 12] ^= 0xFF;
    let damaged_len = records[50].len();
    let mut bytes = records[..10].concat();
    bytes.extend_from_slice(&[0xFD, 0x00, 0x13, 0x37, 0xFE]); // 5 bytes of junk between records
    bytes.extend_from_slice(&records[10..].concat());
    let rep = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default()).unwrap();
    assert_eq!(rep.stats.frames, 99);
    assert_eq!(rep.stats.skipped_bytes, 5 + damaged_len);
    assert_eq!(rep.stats.corrupt_regions, 2);
    assert!(rep.warnings.iter().any(|w| w.message.contains("skipped")));
    // The lost sample is bridged by interpolation on the uniform grid.
    assert_eq!(rep.record.len(), 100);
}

#[test]
fn truncated_final_frame_is_dropped() {
    let mut bytes = simple_log();
    let mut extra = Vec::new();
    push(&mut extra, 9_000_000, 1, MavlinkVersion::V2, &attitude(0.5));
    bytes.extend_from_slice(&extra[..extra.len() - 7]);
    let rep = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default()).unwrap();
    assert_eq!(rep.stats.frames, 100);
    assert_eq!(rep.stats.truncated_tail_bytes, extra.len() - 7);
    assert_eq!((rep.stats.skipped_bytes, rep.stats.corrupt_regions), (0, 0));
}

#[test]
fn systems_are_separated_and_the_busiest_is_the_default() {
    let mut bytes = simple_log();
    for k in 0..30u64 {
        push(
            &mut bytes,
            1_000_000 + 60_000 * k,
            7,
            MavlinkVersion::V2,
            &attitude(-0.3),
        );
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        push(
            &mut bytes,
            1_000_000 + 60_000 * k,
            7,
            MavlinkVersion::V2,
            &hb,
        );
    }
    let rep = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default()).unwrap();
    assert_eq!(rep.sysid, 1);
    assert_eq!(rep.systems.len(), 2);
    assert!(rep
        .record
        .column("phi_rad")
        .unwrap()
        .iter()
        .all(|&p| p >= 0.0));
    let opts = TlogOptions {
        sysid: Some(7),
        rate_hz: Some(10.0),
        ..Default::default()
    };
    let rep7 = parse_tlog_bytes(&bytes, "mem", None, &opts).unwrap();
    assert_eq!(rep7.sysid, 7);
    assert!(rep7
        .record
        .column("phi_rad")
        .unwrap()
        .iter()
        .all(|&p| (p + 0.3).abs() < 1e-6));
    assert!((rep7.record.dt_s().unwrap() - 0.1).abs() < 1e-9);
    let err = parse_tlog_bytes(
        &bytes,
        "mem",
        None,
        &TlogOptions {
            sysid: Some(9),
            rate_hz: None,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("system id 9") && err.contains("1 (100 ATTITUDE)"),
        "{err}"
    );
}

/// `simple_records` with the timestamps of records `from..` shifted by `shift_us` (may be negative).
fn shifted(from: usize, shift_us: i64) -> Vec<Vec<u8>> {
    let mut records = simple_records();
    for r in records.iter_mut().skip(from) {
        let t = u64::from_be_bytes(r[..8].try_into().unwrap()).wrapping_add_signed(shift_us);
        r[..8].copy_from_slice(&t.to_be_bytes());
    }
    records
}

fn stretch(k: usize) -> TlogOptions {
    TlogOptions {
        stretch: Some(StretchChoice::Index(k)),
        ..Default::default()
    }
}

#[test]
fn a_corrupt_timestamp_is_dropped_and_a_logging_gap_splits_the_log() {
    // Records 60..: the log resumes 120 s later (link lost and regained); record 30: high timestamp byte
    // flipped (the frame itself stays valid).
    let mut records = shifted(60, 120_000_000);
    records[30][2] ^= 0x40;
    let bytes = records.concat();
    // Nothing is interpolated across the gap: without a choice the log is refused, naming both stretches.
    let err = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("2 stretches") && err.contains("--stretch"),
        "{err}"
    );
    assert!(err.contains("0.00 to 1.18 s, 59 ATTITUDE samples"), "{err}");
    assert!(
        err.contains("121.20 to 121.98 s, 40 ATTITUDE samples (after a gap of 120.020 s)"),
        "{err}"
    );
    let first = parse_tlog_bytes(&bytes, "mem", None, &stretch(1)).unwrap();
    assert_eq!(first.stats.bad_timestamps, 1);
    assert_eq!(first.record.len(), 60);
    assert!((first.record.time_s[59] - 1.18).abs() < 1e-9);
    let second = parse_tlog_bytes(&bytes, "mem", None, &stretch(2)).unwrap();
    assert_eq!(second.record.len(), 40);
    // roll = 0.001·k: the second stretch starts at record 60
    assert!((second.record.column("phi_rad").unwrap()[0] - 0.060).abs() < 1e-6);
    let longest = TlogOptions {
        stretch: Some(StretchChoice::Longest),
        ..Default::default()
    };
    assert_eq!(
        parse_tlog_bytes(&bytes, "mem", None, &longest)
            .unwrap()
            .stretch,
        0
    );
    let err = parse_tlog_bytes(&bytes, "mem", None, &stretch(3)).unwrap_err();
    assert!(matches!(err, DataError::InvalidArgument(_)), "{err}");
}

#[test]
fn a_jump_back_in_log_time_splits_the_log_instead_of_merging_two_stretches() {
    // Records 60..: the clock steps back 1.5 s, so sorting would interleave them with records 0..59.
    let bytes = shifted(60, -1_500_000).concat();
    let err = parse_tlog_bytes(&bytes, "mem", None, &TlogOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("after a jump back of 1.480 s"), "{err}");
    let second = parse_tlog_bytes(&bytes, "mem", None, &stretch(2)).unwrap();
    assert_eq!(second.record.len(), 40);
    assert!((second.record.column("phi_rad").unwrap()[0] - 0.060).abs() < 1e-6);
}

#[test]
fn a_short_dropout_is_bridged_but_a_pause_of_more_than_five_intervals_is_not() {
    // 3 records missing (80 ms between two ATTITUDE, 4 intervals): one stretch, interpolated.
    let mut records = simple_records();
    records.drain(40..43);
    let rep = parse_tlog_bytes(&records.concat(), "mem", None, &TlogOptions::default()).unwrap();
    assert_eq!(rep.stretches.len(), 1);
    assert_eq!(rep.record.len(), 100);
    // 6 records missing (140 ms, 7 intervals): two stretches.
    let mut records = simple_records();
    records.drain(40..46);
    let err = parse_tlog_bytes(&records.concat(), "mem", None, &TlogOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("after a gap of 0.140 s"), "{err}");
}

/// `simple_records` with each timestamp rewritten by `f(k, original)` as 8 raw bytes.
fn retimed(f: impl Fn(usize, u64) -> [u8; 8]) -> Vec<u8> {
    let mut records = simple_records();
    for (k, r) in records.iter_mut().enumerate() {
        let t = u64::from_be_bytes(r[..8].try_into().unwrap());
        r[..8].copy_from_slice(&f(k, t));
    }
    records.concat()
}

#[test]
fn millisecond_little_endian_and_reversed_time_bases_are_refused() {
    let read = |bytes: &[u8]| {
        parse_tlog_bytes(bytes, "mem", None, &TlogOptions::default())
            .unwrap_err()
            .to_string()
    };
    // Milliseconds since the epoch written where microseconds belong: 20 ms steps read as 20 µs.
    let ms = retimed(|k, _| (1_700_000_000_000 + 20 * k as u64).to_be_bytes());
    let err = read(&ms);
    assert!(
        err.contains("not microseconds") && err.contains("50000 Hz"),
        "{err}"
    );
    // Microseconds since the epoch, little-endian.
    let le = retimed(|k, _| (1_700_000_000_000_000 + 20_000 * k as u64).to_le_bytes());
    let err = read(&le);
    assert!(err.contains("little-endian"), "{err}");
    // The records in reverse order.
    let mut records = simple_records();
    records.reverse();
    let err = read(&records.concat());
    assert!(err.contains("runs backwards in 99 of 99 steps"), "{err}");
}

#[test]
fn ingest_refuses_a_log_with_a_gap_and_writes_nothing_then_reads_the_chosen_stretch() {
    let dir = tempfile::tempdir().unwrap();
    let (log, out) = (dir.path().join("gap.tlog"), dir.path().join("out.csv"));
    std::fs::write(&log, shifted(60, 120_000_000).concat()).unwrap();
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args([
                "ingest",
                "--tlog",
                log.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("2 stretches") && e.contains("gap.tlog"), "{e}");
    assert!(!out.exists(), "a refused log must not leave an output file");
    let o = run(&["--stretch", "2"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("read stretch 2 of 2"), "{e}");
    assert_eq!(flightid::data::read_csv(&out).unwrap().len(), 40);
    let o = run(&["--stretch", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn non_tlog_input_is_a_clear_error() {
    let err =
        parse_tlog_bytes(b"time_s,q\n0,1\n", "x.tlog", None, &TlogOptions::default()).unwrap_err();
    assert!(matches!(err, DataError::Tlog { .. }));
    assert!(err.to_string().contains("no valid MAVLink frame"), "{err}");
}

/// A 20 s, 100 Hz flight with doublets on every surface: smooth, deterministic, all 18 columns.
fn synthetic_flight() -> FlightRecord {
    let n = 2000;
    let time_s: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let doublet = |t: f64, t0: f64, amp: f64| {
        if t >= t0 && t < t0 + 1.0 {
            amp
        } else if t >= t0 + 1.0 && t < t0 + 2.0 {
            -amp
        } else {
            0.0
        }
    };
    let mut rec = FlightRecord::new(time_s.clone());
    let f = |g: &dyn Fn(f64) -> f64| time_s.iter().map(|&t| g(t)).collect::<Vec<f64>>();
    rec.push_column("elevator_rad", f(&|t| -0.02 + doublet(t, 2.0, 0.035)));
    rec.push_column("aileron_rad", f(&|t| doublet(t, 7.0, 0.05)));
    rec.push_column("rudder_rad", f(&|t| doublet(t, 12.0, 0.04)));
    rec.push_column("throttle", f(&|t| 0.6 + 0.05 * (0.3 * t).sin()));
    rec.push_column("phi_rad", f(&|t| 0.2 * (0.5 * t).sin()));
    rec.push_column("theta_rad", f(&|t| 0.03 + 0.02 * (1.1 * t).sin()));
    rec.push_column("psi_rad", f(&|t| 3.0 + 0.02 * t)); // crosses π at t ≈ 7 s
    rec.push_column("p_rad_s", f(&|t| 0.1 * (0.5 * t).cos()));
    rec.push_column("q_rad_s", f(&|t| 0.022 * (1.1 * t).cos()));
    rec.push_column("r_rad_s", f(&|t| 0.02 + 0.01 * (0.7 * t).sin()));
    rec.push_column("alpha_rad", f(&|t| 0.04 + 0.01 * (1.1 * t).sin()));
    rec.push_column("beta_rad", f(&|t| 0.005 * (0.9 * t).sin()));
    rec.push_column("airspeed_m_s", f(&|t| 51.4 + 0.3 * (0.2 * t).sin()));
    rec.push_column("altitude_m", f(&|t| 1219.2 + 2.0 * (0.1 * t).sin()));
    rec.push_column("ax_m_s2", f(&|t| 0.4 + 0.2 * (0.8 * t).sin()));
    rec.push_column("ay_m_s2", f(&|t| 0.1 * (0.6 * t).sin()));
    rec.push_column("az_m_s2", f(&|t| -9.81 + 0.5 * (1.1 * t).sin()));
    rec
}

/// The project's provisioned Python with pymavlink for the fixture script.
fn python() -> PathBuf {
    flightid::sim::env::python().expect("provisioned Python")
}

fn make_tlog(csv: &Path, tlog: &Path, extra: &[&str]) -> serde_json::Value {
    let out = Command::new(python())
        .arg(repo_root().join("scripts/make_tlog.py"))
        .arg(csv)
        .arg(tlog)
        .arg("--servo-map")
        .arg(repo_root().join("aircraft/servo_maps/c172x.toml"))
        .args(extra)
        .output()
        .expect("run scripts/make_tlog.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Writes `truth` as CSV, encodes it with pymavlink (with damage), checks the read-back and
/// returns the record read from the `.tlog`.
fn round_trip_agrees_to_field_quantisation(truth: &FlightRecord) -> FlightRecord {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("flight.csv");
    let tlog = dir.path().join("flight.tlog");
    write_csv_atomic(&csv, truth).unwrap();
    let summary = make_tlog(
        &csv,
        &tlog,
        &["--garbage", "3", "--flip", "2", "--truncate"],
    );

    let rep = read_tlog(&tlog, Some(&c172x()), &TlogOptions::default()).unwrap();
    let s = &rep.stats;
    assert_eq!(
        s.frames,
        summary["frames_written"].as_u64().unwrap() as usize - 2
    );
    assert!(s.frames_v1 > 1000 && s.frames_v2 > 1000, "{s:?}");
    assert_eq!(
        s.skipped_bytes,
        summary["skipped_bytes_expected"].as_u64().unwrap() as usize
    );
    assert_eq!(
        s.truncated_tail_bytes,
        summary["truncated_bytes"].as_u64().unwrap() as usize
    );
    assert_eq!(
        rep.sysid, 1,
        "system 2 sends ten times fewer ATTITUDE messages"
    );

    let rec = &rep.record;
    assert_eq!(rec.len(), truth.len());
    for (a, b) in rec.time_s.iter().zip(&truth.time_s) {
        assert!(
            (a - b).abs() < 1e-9,
            "µs timestamps reproduce the 100 Hz grid"
        );
    }
    // Tolerances = MAVLink field quantisation:
    // float32 fields: half an ulp of f32 (relative 6e-8), taken as 2e-7 relative + 1e-9;
    // SERVO_OUTPUT_RAW: 1 µs PWM at 1000 µs/rad → ±0.5 mrad; throttle 1/1000 → ±0.5e-3;
    // SCALED_IMU: 1 milli-g → ±0.5 mg = ±0.0049 m/s².
    let f32_tol = |v: f64| 2e-7 * v.abs() + 1e-9;
    let checks: &[(&str, &dyn Fn(f64) -> f64)] = &[
        ("phi_rad", &f32_tol),
        ("theta_rad", &f32_tol),
        ("p_rad_s", &f32_tol),
        ("q_rad_s", &f32_tol),
        ("r_rad_s", &f32_tol),
        ("airspeed_m_s", &f32_tol),
        ("altitude_m", &f32_tol),
        ("alpha_rad", &|v| 2e-7 * v.abs() + 1e-8),
        ("beta_rad", &|v| 2e-7 * v.abs() + 1e-8),
        ("elevator_rad", &|_| 0.5e-3 + 1e-12),
        ("aileron_rad", &|_| 0.5e-3 + 1e-12),
        ("rudder_rad", &|_| 0.5e-3 + 1e-12),
        ("throttle", &|_| 0.5e-3 + 1e-12),
        ("ax_m_s2", &|_| 0.5e-3 * 9.80665 + 1e-9),
        ("ay_m_s2", &|_| 0.5e-3 * 9.80665 + 1e-9),
        ("az_m_s2", &|_| 0.5e-3 * 9.80665 + 1e-9),
    ];
    for (name, tol) in checks {
        let got = rec.column(name).unwrap_or_else(|| panic!("{name} missing"));
        let want = truth.column(name).unwrap();
        for i in 0..want.len() {
            assert!(
                (got[i] - want[i]).abs() <= tol(want[i]),
                "{name}[{i}]: tlog {} vs csv {}",
                got[i],
                want[i]
            );
        }
    }
    // Heading: MAVLink carries yaw in −π..π; the reader unwraps it back to a continuous angle.
    let psi = rec.column("psi_rad").unwrap();
    for (g, w) in psi.iter().zip(truth.column("psi_rad").unwrap()) {
        assert!((g - w).abs() < 1e-6, "psi {g} vs {w}");
    }
    rep.record
}

#[test]
fn synthetic_csv_to_pymavlink_tlog_and_back_agrees_to_field_quantisation() {
    round_trip_agrees_to_field_quantisation(&synthetic_flight());
}

/// θ/δe (3 poles, 1 zero: short period + one slow real pole; SRIVC) over the elevator doublet
/// (3–3.6–4.2 s) of the oracle flight, 2…9.5 s (the aileron doublet starts at 10 s). The
/// best-determined of the structures tried on this window (simulation fit 98 %): q/δe 2/1 fits
/// only 84 % and its slow pole and numerator constant are barely determined, so quantisation
/// moves them by several percent; θ/δe 4/2 puts a phugoid (ζ ≈ 0.03) into a 7.5 s window.
fn short_period_tf(rec: &FlightRecord) -> flightid::ident::IdentResult {
    let start = rec.time_s.partition_point(|&t| t < 2.0);
    let end = rec.time_s.partition_point(|&t| t <= 9.5);
    let w = rec.slice(start, end);
    let opts = flightid::ident::IdentOptions {
        method: flightid::ident::Method::Srivc,
        poles: 3,
        zeros: 1,
        estimate_delay: false,
    };
    flightid::ident::identify(
        w.column("elevator_rad").unwrap(),
        w.column("theta_rad").unwrap(),
        w.dt_s().unwrap(),
        &opts,
    )
    .unwrap()
}

/// A JSBSim c172x flight (elevator, aileron, rudder doublets; scripts/oracle_check_flight.py).
// The lead will swap the Python for `flightid::sim::env::python()` and the script for
// `flightid fly` once they land.
#[test]
fn jsbsim_csv_to_pymavlink_tlog_and_back_agrees_to_field_quantisation() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("jsbsim.csv");
    let out = Command::new(python())
        .arg(repo_root().join("scripts/oracle_check_flight.py"))
        .arg(&csv)
        .output()
        .expect("run scripts/oracle_check_flight.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rec = flightid::data::read_csv(&csv).unwrap();
    let from_tlog = round_trip_agrees_to_field_quantisation(&rec);

    // Acceptance: identification on either record gives the same TF to 1 %. The records differ
    // by the MAVLink quantisation, dominated by the elevator's 1 µs PWM step (±0.5 mrad on a
    // ~0.05 rad doublet, ~1 %, but zero-mean over the maneuver).
    // "Same TF" is judged on the transfer function's response, max |G_csv − G_tlog| / max |G_csv|
    // over 0.3–30 rad/s, rather than coefficient by coefficient (measured: 0.08 %).
    let (a, b) = (short_period_tf(&rec), short_period_tf(&from_tlog));
    let eval = |c: &[f64], s: num_complex::Complex64| {
        c.iter()
            .fold(num_complex::Complex64::new(0.0, 0.0), |acc, v| acc * s + v)
    };
    let g = |r: &flightid::ident::IdentResult, w: f64| {
        let s = num_complex::Complex64::new(0.0, w);
        eval(&r.tf.num, s) / eval(&r.tf.den, s)
    };
    let omegas: Vec<f64> = (0..=200)
        .map(|k| 0.3 * 100f64.powf(k as f64 / 200.0))
        .collect();
    let peak = omegas.iter().map(|&w| g(&a, w).norm()).fold(0.0, f64::max);
    let d_freq = omegas
        .iter()
        .map(|&w| (g(&a, w) - g(&b, w)).norm())
        .fold(0.0, f64::max)
        / peak;
    eprintln!("csv vs tlog: frequency response {:.3} %", 100.0 * d_freq);
    assert!(d_freq < 0.01, "csv {:?}\ntlog {:?}", a.tf, b.tf);
    assert!(
        a.fit_sim_percent > 80.0,
        "the 2-pole model follows the doublet response"
    );
}

/// VFR_HUD carries an autopilot's equivalent airspeed (the committed fixture, as ArduPilot and PX4 send it): by
/// default it is made true with the standard atmosphere at the logged altitude, about ×1.06 at the fixture's
/// 1 200 m; `AirspeedKind::True` takes it as it is. Trimmed at the equivalent airspeed, the replay would fly 6 %
/// slow and 11 % short of the dynamic pressure.
#[test]
fn the_equivalent_airspeed_of_vfr_hud_is_made_true() {
    let fixture = repo_root().join("tests/fixtures/flight.tlog");
    let read = |airspeed| {
        let opts = TlogOptions {
            airspeed,
            ..TlogOptions::default()
        };
        read_tlog(&fixture, Some(&c172x()), &opts).unwrap().record
    };
    let (made_true, as_sent) = (read(AirspeedKind::Equivalent), read(AirspeedKind::True));
    let (v, eas, h) = (
        made_true.column("airspeed_m_s").unwrap(),
        as_sent.column("airspeed_m_s").unwrap(),
        made_true.column("altitude_m").unwrap(),
    );
    for k in 0..v.len() {
        let ratio = v[k] / eas[k];
        // ρ/ρ₀ = (1 − 2.25577·10⁻⁵ h)^4.25588 in the troposphere of the 1976 standard atmosphere (h in m)
        let expected = (1.0 - 2.25577e-5 * h[k]).powf(-4.25588 / 2.0);
        assert!(
            (ratio - expected).abs() < 2e-4,
            "{k}: {ratio} against {expected} at {} m",
            h[k]
        );
        assert!((1.05..1.07).contains(&ratio), "{ratio}");
    }
    assert!(made_true.metadata.iter().any(|m| m.contains("made true")));
}
