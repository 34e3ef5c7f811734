//! Specification of the flight-data CSV reader/writer (docs/data.md).

use flightid::data::{
    parse_csv_bytes, read_csv, resample_uniform, write_csv_atomic, DataError, FlightRecord,
    WarningKind, SCHEMA_COLUMNS,
};

fn parse(text: &str) -> Result<FlightRecord, DataError> {
    parse_csv_bytes(text.as_bytes(), "test.csv")
}

/// A 100 Hz record with every schema column holding a distinct smooth signal (airspeed and density about
/// a positive level, as the reader refuses a negative one).
fn synthetic_record(n: usize) -> FlightRecord {
    let time_s: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
    let mut rec = FlightRecord::new(time_s.clone());
    for (k, name) in SCHEMA_COLUMNS.iter().enumerate().skip(1) {
        let level = match *name {
            "airspeed_m_s" => 50.0,
            "density_kg_m3" => 1.2,
            _ => 0.0,
        };
        let values = time_s
            .iter()
            .map(|t| level + 0.1 * (k as f64 * 0.37 * t).sin() + 1e-3 * k as f64 / 3.0)
            .collect();
        rec.push_column(name, values);
    }
    rec.metadata.push(" aircraft: c172x".into());
    rec
}

#[test]
fn write_then_read_gives_bit_identical_values_metadata_and_order() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.csv");
    let mut rec = synthetic_record(500);
    rec.push_column(
        "custom_sensor",
        (0..500).map(|i| (i as f64).sqrt() / 7.0).collect(),
    );
    write_csv_atomic(&path, &rec).unwrap();
    let back = read_csv(&path).unwrap();
    // Shortest round-trip float formatting: exact equality, not a tolerance.
    assert_eq!(back, rec);
    assert_eq!(back.columns.last().unwrap().0, "custom_sensor");
    // No temporary file is left behind.
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(leftovers.len(), 1);
}

#[test]
fn column_lookup_require_and_median_step() {
    let rec = parse("#note\ntime_s,q_rad_s\n0,1\n0.01,2\n0.02,3\n0.05,4\n").unwrap();
    assert_eq!(rec.metadata, vec!["note".to_string()]);
    assert_eq!(rec.len(), 4);
    assert_eq!(rec.column("q_rad_s"), Some(&[1.0, 2.0, 3.0, 4.0][..]));
    // Steps 0.01, 0.01, 0.03: the median ignores the dropout.
    assert!((rec.dt_s().unwrap() - 0.01).abs() < 1e-12);
    let err = rec
        .require("alpha_rad", "to fit CL_alpha")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("alpha_rad") && err.contains("CL_alpha") && err.contains("q_rad_s"),
        "{err}"
    );
}

#[test]
fn time_column_may_be_anywhere_and_whitespace_and_crlf_are_tolerated() {
    let rec = parse("q_rad_s, time_s\r\n 1.5 ,0\r\n2.5, 0.1\r\n\r\n").unwrap();
    assert_eq!(rec.time_s, vec![0.0, 0.1]);
    assert_eq!(rec.column("q_rad_s"), Some(&[1.5, 2.5][..]));
}

#[test]
fn empty_file_is_refused() {
    assert!(matches!(parse(""), Err(DataError::Empty { .. })));
    assert!(matches!(
        parse("# only metadata\n\n"),
        Err(DataError::Empty { .. })
    ));
    assert!(matches!(
        parse("time_s,q_rad_s\n"),
        Err(DataError::NoRows { line: 1, .. })
    ));
}

#[test]
fn missing_time_column_is_named() {
    let err = parse("t,q_rad_s\n0,1\n").unwrap_err();
    assert!(
        matches!(err, DataError::MissingTime { line: 1, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("time_s"));
}

#[test]
fn duplicated_time_reports_the_line_of_the_repeat() {
    // Line 1 metadata, line 2 header, rows on lines 3, 4, 5.
    let err = parse("# m\ntime_s,q_rad_s\n0,1\n0.1,2\n0.1,3\n").unwrap_err();
    match err {
        DataError::TimeNotIncreasing {
            line,
            previous_line,
            relation,
            ..
        } => {
            assert_eq!((line, previous_line, relation), (5, 4, "repeats"));
        }
        e => panic!("wrong error {e}"),
    }
    let err = parse("time_s,q\n0,1\n0.2,2\n0.1,3\n")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("test.csv:4") && err.contains("goes back"),
        "{err}"
    );
}

#[test]
fn nan_inf_and_non_numeric_cells_name_file_line_and_column() {
    let err = parse("time_s,q_rad_s\n0,1\n0.1,NaN\n").unwrap_err();
    assert!(
        matches!(&err, DataError::NonFinite { line: 3, column, .. } if column == "q_rad_s"),
        "{err}"
    );
    let err = parse("time_s,q_rad_s\n0,inf\n").unwrap_err();
    assert!(matches!(err, DataError::NonFinite { line: 2, .. }));
    let err = parse("time_s,q_rad_s\n0,1\n0.1,1.2.3\n").unwrap_err();
    assert!(
        matches!(&err, DataError::NonNumeric { line: 3, column, cell, .. } if column == "q_rad_s" && cell == "1.2.3"),
        "{err}"
    );
    let msg = err.to_string();
    assert!(msg.starts_with("test.csv:3: column `q_rad_s`"), "{msg}");
    let err = parse("time_s,q_rad_s\n0,\n").unwrap_err();
    assert!(matches!(err, DataError::NonNumeric { line: 2, .. }));
}

#[test]
fn ragged_rows_report_expected_and_found_field_counts() {
    let err = parse("time_s,a,b\n0,1,2\n0.1,1\n").unwrap_err();
    assert!(
        matches!(
            err,
            DataError::Ragged {
                line: 3,
                expected: 3,
                found: 2,
                ..
            }
        ),
        "{err}"
    );
    let err = parse("time_s,a\n0,1,2\n").unwrap_err();
    assert!(matches!(
        err,
        DataError::Ragged {
            line: 2,
            expected: 2,
            found: 3,
            ..
        }
    ));
}

#[test]
fn duplicate_and_empty_column_names_are_refused() {
    assert!(matches!(
        parse("time_s,a,a\n0,1,2\n"),
        Err(DataError::DuplicateColumn { .. })
    ));
    assert!(matches!(
        parse("time_s,a,\n0,1,2\n"),
        Err(DataError::Parse { .. })
    ));
}

#[test]
fn degrees_in_a_rad_column_are_flagged_with_evidence() {
    // theta in degrees: 5° trim with a ±10° doublet; in radians it would be 860°.
    let time_s: Vec<f64> = (0..200).map(|i| i as f64 * 0.02).collect();
    let mut rec = FlightRecord::new(time_s.clone());
    rec.push_column(
        "theta_rad",
        time_s
            .iter()
            .map(|t| 5.0 + 10.0 * (t * 2.0).sin())
            .collect(),
    );
    rec.push_column("q_rad_s", time_s.iter().map(|t| 0.1 * t.cos()).collect());
    let warnings = rec.validate().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_eq!(warnings[0].kind, WarningKind::LooksLikeDegrees);
    assert_eq!(warnings[0].column.as_deref(), Some("theta_rad"));
    assert!(
        warnings[0].message.contains("reaches 14.99"),
        "evidence names the peak: {}",
        warnings[0]
    );
}

#[test]
fn accelerations_in_g_are_flagged_and_m_s2_are_not() {
    let time_s: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
    let mut rec = FlightRecord::new(time_s.clone());
    rec.push_column("ax_m_s2", vec![0.05; 100]);
    rec.push_column(
        "az_m_s2",
        time_s.iter().map(|t| -1.0 + 0.1 * t.sin()).collect(),
    );
    let w = rec.validate().unwrap();
    assert!(w.iter().any(|w| w.kind == WarningKind::LooksLikeG), "{w:?}");
    rec.push_column("ax_m_s2", vec![0.5; 100]);
    rec.push_column("az_m_s2", vec![-9.81; 100]);
    assert!(rec.validate().unwrap().is_empty());
}

#[test]
fn a_load_factor_az_and_a_rate_of_the_other_sign_are_flagged() {
    // 50 Hz, 20 s of pitching: θ with 0.05° of attitude-like jitter (which makes dθ/dt too noisy to compare),
    // q its rate with the other sign (a nose-down-positive gyro), a_z a load factor (+g in level flight).
    let time_s: Vec<f64> = (0..1000).map(|i| i as f64 * 0.02).collect();
    let jitter = |t: f64| 0.0009 * (97.0 * t).sin();
    let theta: Vec<f64> = time_s
        .iter()
        .map(|t| 0.05 + 0.03 * (1.3 * t).sin() + jitter(*t))
        .collect();
    let q: Vec<f64> = time_s.iter().map(|t| 0.039 * (1.3 * t).cos()).collect();
    let az: Vec<f64> = time_s
        .iter()
        .map(|t| -9.81 - 0.5 * (1.3 * t).sin())
        .collect();
    let record = |sign_q: f64, sign_az: f64| {
        let mut rec = FlightRecord::new(time_s.clone());
        rec.push_column("theta_rad", theta.clone());
        rec.push_column("q_rad_s", q.iter().map(|v| sign_q * v).collect());
        rec.push_column("az_m_s2", az.iter().map(|v| sign_az * v).collect());
        rec
    };
    assert!(record(1.0, 1.0).validate().unwrap().is_empty());
    let w = record(-1.0, -1.0).validate().unwrap();
    for column in ["q_rad_s", "az_m_s2"] {
        let found = w
            .iter()
            .find(|w| w.column.as_deref() == Some(column))
            .unwrap_or_else(|| panic!("no warning on {column}: {w:?}"));
        assert_eq!(found.kind, WarningKind::OppositeSign, "{found}");
        assert!(found.message.contains("scale = -1.0"), "{found}");
    }
}

/// A record timed in milliseconds (20 Hz written as steps of 50) is named as such; a 1 Hz recorder's steps of
/// 1 s and a 100 Hz record in seconds are not.
#[test]
fn time_in_milliseconds_is_a_unit_warning() {
    let record = |step: f64, n: usize| {
        let time_s: Vec<f64> = (0..n).map(|i| i as f64 * step).collect();
        let mut rec = FlightRecord::new(time_s.clone());
        rec.push_column(
            "q_rad_s",
            time_s.iter().map(|t| 0.01 * (t / step).sin()).collect(),
        );
        rec.validate().unwrap()
    };
    let w = record(50.0, 1310);
    let ms: Vec<_> = w
        .iter()
        .filter(|w| w.kind == WarningKind::LooksLikeMilliseconds)
        .collect();
    assert_eq!(ms.len(), 1, "{w:?}");
    let text = ms[0].to_string();
    assert!(
        text.starts_with("column `time_s`: steps of 50 look like milliseconds")
            && text.contains("at 0.02 Hz"),
        "{text}"
    );
    for (step, n) in [(1.0, 3600), (0.01, 1000), (0.5, 100)] {
        let w = record(step, n);
        assert!(
            w.iter()
                .all(|w| w.kind != WarningKind::LooksLikeMilliseconds),
            "{step}: {w:?}"
        );
    }
    let us = record(20_000.0, 100);
    assert!(
        us.iter()
            .any(|w| w.to_string().contains("look like microseconds")),
        "{us:?}"
    );
}

#[test]
fn irregular_sampling_is_detected_and_resampled_linearly() {
    // 50 Hz with jittered times; a ramp survives linear interpolation exactly.
    let time_s: Vec<f64> = (0..101)
        .map(|i| i as f64 * 0.02 + if i % 7 == 3 { 0.008 } else { 0.0 })
        .collect();
    let mut rec = FlightRecord::new(time_s.clone());
    rec.push_column("q_rad_s", time_s.iter().map(|t| 0.3 * t - 0.1).collect());
    let w = rec.validate().unwrap();
    assert!(
        w.iter().any(|w| w.kind == WarningKind::IrregularSampling),
        "{w:?}"
    );
    let u = resample_uniform(&rec, 50.0).unwrap();
    assert_eq!(u.len(), 101, "0..2 s at 50 Hz");
    assert!(u.validate().unwrap().is_empty());
    for (t, q) in u.time_s.iter().zip(u.column("q_rad_s").unwrap()) {
        assert!((q - (0.3 * t - 0.1)).abs() < 1e-12);
    }
    assert!(u.metadata.last().unwrap().contains("linear interpolation"));
    assert!(resample_uniform(&rec, 0.0).is_err());
}

/// A body of `rows` data lines (about 20 bytes each) after a metadata line and the header, with
/// one blank line at line 1000; big enough (> 2 MB) to be parsed in parallel chunks.
fn big_csv(rows: usize, edit: impl Fn(usize, &mut String)) -> Vec<u8> {
    let mut s = String::from("# big\ntime_s,a,b\n");
    let mut line = 3;
    for i in 0..rows {
        if line == 1000 {
            s.push('\n');
            line += 1;
        }
        let mut row = format!("{},{},{}", i as f64 * 0.01, 0.5 + i as f64 * 1e-6, -2.25);
        edit(line, &mut row);
        s.push_str(&row);
        s.push('\n');
        line += 1;
    }
    s.into_bytes()
}

/// A data system that writes a frame twice (same time, every value the same) loses nothing by it: the repeat
/// is dropped and a warning names its line. A repeated time with other values stays an error
/// (`duplicated_time_reports_the_line_of_the_repeat`): which of the two rows is the sample is not known.
#[test]
fn rows_a_data_system_wrote_twice_are_dropped_with_a_warning() {
    let rec = parse("# m\ntime_s,q_rad_s\n0,1\n0.1,2\n0.1,2\n0.2,3\n").unwrap();
    assert_eq!(rec.time_s, vec![0.0, 0.1, 0.2]);
    assert_eq!(rec.column("q_rad_s").unwrap(), &[1.0, 2.0, 3.0]);
    let w: Vec<_> = rec
        .warnings()
        .into_iter()
        .filter(|w| w.kind == WarningKind::RepeatedRows)
        .collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].message.contains("1 repeated row(s) dropped") && w[0].message.contains("line 5"),
        "{}",
        w[0].message
    );
    // Written back and read again, the note is history, not a warning about the new file.
    let dir = tempfile::tempdir().unwrap();
    let again = dir.path().join("again.csv");
    write_csv_atomic(&again, &rec).unwrap();
    let reread = read_csv(&again).unwrap();
    assert!(reread
        .warnings()
        .iter()
        .all(|w| w.kind != WarningKind::RepeatedRows));
    assert!(
        reread
            .metadata
            .iter()
            .any(|m| m.contains("(when read before) 1 repeated row(s) dropped")),
        "{:?}",
        reread.metadata
    );
    // Every row written twice in a file read in parallel chunks: the repeats that straddle a chunk boundary
    // go as well.
    let mut text = String::from("time_s,a,b\n");
    for i in 0..150_000 {
        let row = format!("{},{},{}\n", i as f64 * 0.01, 0.5 + i as f64 * 1e-6, -2.25);
        text.push_str(&row);
        text.push_str(&row);
    }
    assert!(text.len() > 3 << 20, "the body must span several chunks");
    let rec = parse_csv_bytes(text.as_bytes(), "twice.csv").unwrap();
    assert_eq!(rec.len(), 150_000);
    assert!(rec.time_s.windows(2).all(|t| t[1] > t[0]));
    let note = rec
        .warnings()
        .into_iter()
        .find(|w| w.kind == WarningKind::RepeatedRows)
        .expect("a repeated-rows warning");
    assert!(
        note.message.starts_with("150000 repeated row(s) dropped")
            && note.message.contains("line 3, 5, 7"),
        "{}",
        note.message
    );
}

#[test]
fn errors_deep_in_a_chunked_file_report_their_true_line() {
    let ok = big_csv(200_000, |_, _| {});
    assert!(
        ok.len() > 3 << 20,
        "the body must span several parallel chunks"
    );
    let rec = parse_csv_bytes(&ok, "big.csv").unwrap();
    assert_eq!(rec.len(), 200_000);
    assert_eq!(rec.column("a").unwrap()[199_999], 0.5 + 199_999.0 * 1e-6);

    let bad = big_csv(200_000, |line, row| {
        if line == 187_654 {
            *row = row.replace("-2.25", "NaN");
        }
    });
    let err = parse_csv_bytes(&bad, "big.csv").unwrap_err();
    assert!(
        matches!(err, DataError::NonFinite { line: 187_654, .. }),
        "{err}"
    );

    let bad = big_csv(200_000, |line, row| {
        if line == 123_456 {
            *row = "0.5,1,1".into(); // time goes back
        }
    });
    let err = parse_csv_bytes(&bad, "big.csv").unwrap_err();
    assert!(
        matches!(
            err,
            DataError::TimeNotIncreasing {
                line: 123_456,
                previous_line: 123_455,
                ..
            }
        ),
        "{err}"
    );
    // The same check across every chunk boundary: a repeated time at each of many lines.
    for target in [50_001, 100_003, 150_007, 199_999] {
        let bad = big_csv(200_000, |line, row| {
            if line == target {
                *row = "0,0,0".into();
            }
        });
        match parse_csv_bytes(&bad, "big.csv").unwrap_err() {
            DataError::TimeNotIncreasing { line, .. } => assert_eq!(line, target),
            e => panic!("{e}"),
        }
    }
}

/// A CSV written into a folder that does not exist yet creates the folder (`fly --out
/// new/flight.csv` on a fresh checkout), and reads back the same.
#[test]
fn writing_into_a_missing_folder_creates_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("new").join("deeper").join("flight.csv");
    let mut rec = flightid::data::FlightRecord::new(vec![0.0, 0.1, 0.2]);
    rec.push_column("q_rad_s", vec![0.0, 0.5, -0.25]);
    flightid::data::write_csv_atomic(&path, &rec).unwrap();
    let back = flightid::data::read_csv(&path).unwrap();
    assert_eq!(back.column("q_rad_s").unwrap(), &[0.0, 0.5, -0.25]);
}

/// Cases 15 and 16 (seed 4, stratified) of the independent generator `scripts/gen_diagnose_records.py`
/// (JSBSim's c172x through its own Python API, airspeed in m/s, accelerations at the pilot's station), their
/// training and validation records.
fn independent_records() -> (tempfile::TempDir, Vec<FlightRecord>) {
    let dir = tempfile::tempdir().unwrap();
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_diagnose_records.py");
    let out = std::process::Command::new(flightid::sim::env::python().expect("provisioned Python"))
        .arg(script)
        .args([
            "--cases",
            "2",
            "--first",
            "15",
            "--seed",
            "4",
            "--stratified",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .expect("run the generator");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let records = ["015_train", "015_valid", "016_train", "016_valid"]
        .iter()
        .map(|r| read_csv(&dir.path().join(format!("case_{r}.csv"))).unwrap())
        .collect();
    (dir, records)
}

/// `rec` with its airspeed multiplied by `factor` (1.943844: logged in knots; 1/0.3048: in ft/s).
fn airspeed_times(rec: &FlightRecord, factor: f64) -> FlightRecord {
    let mut out = rec.clone();
    let v = rec
        .column("airspeed_m_s")
        .unwrap()
        .iter()
        .map(|v| v * factor)
        .collect();
    out.push_column("airspeed_m_s", v);
    out
}

/// The airspeed-unit warning of `rec`'s warnings, if any.
fn speed_unit_warning(rec: &FlightRecord) -> Option<String> {
    rec.warnings()
        .into_iter()
        .find(|w| w.kind == WarningKind::LooksLikeKnotsOrFeet)
        .map(|w| w.to_string())
}

/// The first 5 s of a record in m/s is not taken for knots or ft/s. Before the kinematic check needed 8 windows
/// and a decisive slope, case 15's validation record cut there read "changes 1.47 times as fast … (correlation
/// 1.00): knots", case 16's training record 2.79 (0.92): "ft/s" — an elevator 3-2-1-1 fills the five 1 s
/// windows, and the pilot-station accelerations miss part of its speed change. Five windows cannot tell m/s
/// from knots there (in knots the same cut reads 2.86), so the cut in knots draws nothing either. The whole
/// records of case 16 (65 s) are told apart: m/s nothing, knots (slope 1.96 at r = 0.94, 1.98 at 0.93) and ft/s
/// (3.30, 3.33) named as such.
#[test]
fn a_short_record_is_not_taken_for_knots_and_a_whole_one_in_knots_or_ft_s_is() {
    let (_dir, records) = independent_records();
    let cuts: Vec<FlightRecord> = records.iter().map(|r| r.between(0.0, 5.0)).collect();
    for factor in [1.0, 1.943844] {
        for (i, cut) in cuts.iter().enumerate() {
            assert!(cut.len() > 100, "{i}: {} samples", cut.len());
            let w = speed_unit_warning(&airspeed_times(cut, factor));
            assert!(
                w.is_none(),
                "record {i}, first 5 s, airspeed × {factor}: {w:?}"
            );
        }
    }
    for rec in &records[2..] {
        assert_eq!(speed_unit_warning(rec), None);
        for (factor, unit) in [
            (1.943844, "it looks like knots"),
            (1.0 / 0.3048, "it looks like ft/s"),
        ] {
            let w = speed_unit_warning(&airspeed_times(rec, factor));
            assert!(
                w.as_deref().is_some_and(|w| w.contains(unit)),
                "× {factor}: {w:?}"
            );
        }
    }
}

/// Only a flight-state sensor is called stuck, and only over 20 samples and 5 s: an elevator, a throttle, a
/// thrust or a latitude held constant draw nothing; a pitch gyro at 0 and an altimeter within 2·10⁻⁹ m of
/// 1200 m over 6 s are named with their values; the first 4.9 s of the same record draw nothing.
#[test]
fn a_stuck_sensor_is_a_flight_state_held_over_5_s_and_an_idle_input_is_not() {
    let n = 601; // 6 s at 100 Hz
    let mut rec = synthetic_record(n);
    for c in ["elevator_rad", "throttle", "thrust_n", "latitude_rad"] {
        rec.push_column(c, vec![0.3; n]);
    }
    let stuck = |rec: &FlightRecord| -> Vec<String> {
        rec.warnings()
            .into_iter()
            .filter(|w| w.kind == WarningKind::StuckSensor)
            .map(|w| w.to_string())
            .collect()
    };
    assert_eq!(stuck(&rec), Vec::<String>::new());
    rec.push_column("q_rad_s", vec![0.0; n]);
    let h = rec
        .time_s
        .iter()
        .map(|t| 1200.0 + 1e-9 * (7.0 * t).sin())
        .collect();
    rec.push_column("altitude_m", h);
    let w = stuck(&rec);
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].starts_with(
            "column `q_rad_s`: 0 on every one of its 601 rows (6 s): a stuck or unplugged sensor"
        ),
        "{w:?}"
    );
    assert!(
        w[1].starts_with("column `altitude_m`: within 2.0e-9 of 1200 on every one of its 601 rows"),
        "{w:?}"
    );
    assert_eq!(stuck(&rec.between(0.0, 4.9)), Vec::<String>::new());
}
