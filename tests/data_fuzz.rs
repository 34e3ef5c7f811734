//! Robustness of the readers against random and mutated input (no panic, every
//! failure a clear error, ≥ 100k cases).
//!
//! Volume comes from seeded mutation loops (130k CSV/tlog cases and 6k aircraft/campaign/model files, reproducible: the seed and case number are
//! printed on failure); proptest adds shrinking on arbitrary bytes and on the write→read round trip.
//! Beyond "no panic", every record a reader returns must pass the hard validation rules.

use std::panic::{catch_unwind, AssertUnwindSafe};

use flightid::data::tlog::TlogOptions;
use flightid::data::{parse_csv_bytes, parse_tlog_bytes, write_csv_to, FlightRecord};
use mavlink::dialects::ardupilotmega::*;
use mavlink::{MavHeader, MavlinkVersion};
use proptest::prelude::*;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// Seed CSV inputs: valid files in the shapes users send.
fn csv_seeds() -> Vec<Vec<u8>> {
    vec![
        b"# aircraft: c172x\ntime_s,elevator_rad,q_rad_s,theta_rad\n0,0.01,0.001,0.05\n0.01,0.012,-0.002,0.0501\n0.02,0.011,1e-3,0.0502\n0.03,0.0105,2.5E-4,0.05\n".to_vec(),
        b"q_rad_s,time_s\r\n1.5,0\r\n2.5,0.1\r\n3.5,0.2\r\n".to_vec(),
        b"\"time_s\",\"a,b\"\n0,\"1\"\n1,\"2\"\n".to_vec(),
        b"time_s\n0\n1\n2\n\n".to_vec(),
    ]
}

/// Bytes a mutation inserts: CSV structure, number syntax and a little noise.
const CSV_ALPHABET: &[u8] = b",,,\n\n\r\"#.-+eE0123456789 NaNinf\xff\x00";

fn mutate(rng: &mut StdRng, input: &[u8], alphabet: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..rng.gen_range(1..=4) {
        let len = b.len();
        match rng.gen_range(0..7) {
            0 if len > 0 => {
                let i = rng.gen_range(0..len);
                b[i] ^= 1 << rng.gen_range(0..8);
            }
            1 => {
                let i = rng.gen_range(0..=len);
                b.insert(i, alphabet[rng.gen_range(0..alphabet.len())]);
            }
            2 if len > 0 => {
                let i = rng.gen_range(0..len);
                let j = (i + rng.gen_range(1..=8)).min(len);
                b.drain(i..j);
            }
            3 => {
                let cut = rng.gen_range(0..=len);
                b.truncate(cut);
            }
            4 if len > 0 => {
                // Duplicate a random span (repeated rows / frames).
                let i = rng.gen_range(0..len);
                let j = (i + rng.gen_range(1..=64)).min(len);
                let span = b[i..j].to_vec();
                let at = rng.gen_range(0..=b.len());
                b.splice(at..at, span);
            }
            5 if len > 0 => {
                let i = rng.gen_range(0..len);
                b[i] = rng.gen();
            }
            _ => {
                let i = rng.gen_range(0..=len);
                let junk: Vec<u8> = (0..rng.gen_range(1..16)).map(|_| rng.gen()).collect();
                b.splice(i..i, junk);
            }
        }
    }
    b
}

/// Reads a CSV; true if accepted. Panics (caught by the caller) on any broken promise.
fn check_csv(bytes: &[u8]) -> bool {
    match parse_csv_bytes(bytes, "fuzz.csv") {
        Ok(rec) => {
            // Whatever the reader accepts obeys the hard rules.
            rec.validate().expect("accepted CSV must validate");
            true
        }
        Err(e) => {
            assert!(!e.to_string().is_empty());
            false
        }
    }
}

/// A small valid tlog: system 1 at 50 Hz plus a second system and unrelated messages.
fn tlog_seed() -> Vec<u8> {
    let mut out = Vec::new();
    let mut push = |t: u64, sys: u32, v: MavlinkVersion, m: &MavMessage| {
        out.extend_from_slice(&t.to_be_bytes());
        let h = MavHeader {
            system_id: sys,
            component_id: 1,
            sequence: 0,
        };
        mavlink::write_versioned_msg(&mut out, v, h, m).unwrap();
    };
    for k in 0..12u64 {
        let t = 1_700_000_000_000_000 + 20_000 * k;
        let v = if k % 2 == 0 {
            MavlinkVersion::V1
        } else {
            MavlinkVersion::V2
        };
        let att = ATTITUDE_DATA {
            roll: 0.01 * k as f32,
            yaw: 3.1,
            ..Default::default()
        };
        push(t, 1, v, &MavMessage::ATTITUDE(att));
        let imu = SCALED_IMU_DATA {
            zacc: -1000,
            ..Default::default()
        };
        push(t, 1, v, &MavMessage::SCALED_IMU(imu));
        let servo = SERVO_OUTPUT_RAW_DATA {
            servo2_raw: 1490,
            servo3_raw: 1600,
            ..Default::default()
        };
        push(t, 1, v, &MavMessage::SERVO_OUTPUT_RAW(servo));
        let hud = VFR_HUD_DATA {
            airspeed: 50.0,
            alt: 1200.0,
            ..Default::default()
        };
        push(t, 1, MavlinkVersion::V2, &MavMessage::VFR_HUD(hud));
        let aoa = AOA_SSA_DATA {
            AOA: 3.0,
            SSA: 0.5,
            ..Default::default()
        };
        push(t, 1, MavlinkVersion::V2, &MavMessage::AOA_SSA(aoa));
        if k % 4 == 0 {
            push(
                t,
                2,
                MavlinkVersion::V2,
                &MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()),
            );
            push(
                t,
                2,
                MavlinkVersion::V1,
                &MavMessage::ATTITUDE(ATTITUDE_DATA::default()),
            );
        }
    }
    out
}

fn servo_map() -> flightid::data::ServoMap {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("aircraft/servo_maps/c172x.toml");
    flightid::data::ServoMap::load(&p).unwrap()
}

fn check_tlog(bytes: &[u8], servo_map: &flightid::data::ServoMap, sysid: Option<u8>) {
    let opts = TlogOptions {
        sysid,
        rate_hz: None,
        ..Default::default()
    };
    match parse_tlog_bytes(bytes, "fuzz.tlog", Some(servo_map), &opts) {
        Ok(rep) => {
            rep.record
                .validate()
                .expect("accepted tlog must give a valid record");
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

#[test]
fn csv_reader_survives_80k_mutated_inputs() {
    let seeds = csv_seeds();
    let mut rng = StdRng::seed_from_u64(0x_c5f);
    let mut accepted = 0;
    for case in 0..80_000 {
        let seed = &seeds[case % seeds.len()];
        let input = mutate(&mut rng, seed, CSV_ALPHABET);
        let r = catch_unwind(AssertUnwindSafe(|| check_csv(&input)));
        assert!(
            r.is_ok(),
            "case {case} panicked on {:?}",
            String::from_utf8_lossy(&input)
        );
        accepted += usize::from(parse_csv_bytes(&input, "x").is_ok());
    }
    // Mutations must leave a fair share readable, or the test only exercises the first error.
    assert!(
        accepted > 5_000,
        "only {accepted} mutated inputs were accepted"
    );
}

#[test]
fn tlog_reader_survives_50k_mutated_inputs() {
    let seed = tlog_seed();
    let af = servo_map();
    let mut rng = StdRng::seed_from_u64(0x71);
    let all_bytes: Vec<u8> = (0..=255).collect();
    let mut accepted = 0;
    for case in 0..50_000 {
        let input = mutate(&mut rng, &seed, &all_bytes);
        let sysid = if case % 5 == 0 {
            Some(rng.gen_range(0..4))
        } else {
            None
        };
        let r = catch_unwind(AssertUnwindSafe(|| check_tlog(&input, &af, sysid)));
        assert!(r.is_ok(), "case {case} panicked on {}", hex(&input));
        accepted +=
            usize::from(parse_tlog_bytes(&input, "x", Some(&af), &TlogOptions::default()).is_ok());
    }
    assert!(
        accepted > 20_000,
        "only {accepted} mutated logs were accepted"
    );
}

/// Bytes a mutation of a TOML or JSON file inserts: structure, numbers and a little noise.
const FILE_ALPHABET: &[u8] = b"[]{}=\",:\n#.-+eE0123456789 naninf_\xff\x00\x1b";

/// Mutated aircraft, campaign and model files, each read through its real reader from a real file: no panic,
/// and an accepted file holds only finite numbers within their ranges (the readers validate them).
#[test]
fn toml_and_model_file_readers_survive_6k_mutated_files() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let aircraft = std::fs::read(root.join("aircraft/c172x.toml")).unwrap();
    let campaign = std::fs::read(root.join("campaigns/c172x_737.toml")).unwrap();
    let model =
        br#"{"aircraft": "c172x", "effects": [], "model_effects": [], "notes": {"data": "x.csv"}}"#
            .to_vec();
    let tmp = tempfile::tempdir().unwrap();
    let mut rng = StdRng::seed_from_u64(0x70_41);
    let mut accepted = [0usize; 3];
    for case in 0..6_000 {
        let kind = case % 3;
        let seed = [&aircraft, &campaign, &model][kind];
        let input = mutate(&mut rng, seed, FILE_ALPHABET);
        let r = catch_unwind(AssertUnwindSafe(|| match kind {
            0 => {
                let path = tmp.path().join("fuzz.toml");
                std::fs::write(&path, &input).unwrap();
                flightid::aircraft::load(path.to_str().unwrap())
                    .map(|cfg| {
                        for s in cfg.surfaces.values() {
                            assert!(
                                s.min_rad < 0.0 && s.max_rad > 0.0 && s.rad_per_norm.is_finite()
                            );
                        }
                        assert!(cfg.trim.speed_kts.is_finite() && cfg.trim.altitude_ft.is_finite());
                    })
                    .is_ok()
            }
            1 => {
                let path = tmp.path().join("campaign.toml");
                std::fs::write(&path, &input).unwrap();
                flightid::campaign::CampaignSpec::load(&path)
                    .map(|spec| {
                        assert!(
                            spec.duration_s.is_finite() && spec.duration_s * spec.rate_hz <= 1e6
                        );
                    })
                    .is_ok()
            }
            _ => {
                let path = tmp.path().join("extension.json");
                std::fs::write(&path, &input).unwrap();
                flightid::diagnose::extension::ExtensionFile::read(&path).is_ok()
            }
        }));
        match r {
            Ok(ok) => accepted[kind] += usize::from(ok),
            Err(_) => panic!(
                "case {case} panicked on {:?}",
                String::from_utf8_lossy(&input)
            ),
        }
    }
    // a fair share of each kind must stay readable, or only the first error is exercised
    for (kind, n) in accepted.iter().enumerate() {
        assert!(
            *n > 100,
            "kind {kind}: only {n} of 2000 mutated files were accepted"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic_either_reader(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        check_csv(&bytes);
        check_tlog(&bytes, &servo_map(), None);
    }

    #[test]
    fn written_records_read_back_bit_identical(
        rows in proptest::collection::vec(proptest::collection::vec(-1e12f64..1e12, 3), 1..40),
        dt in 1e-4f64..10.0,
    ) {
        let n = rows.len();
        let mut rec = FlightRecord::new((0..n).map(|i| i as f64 * dt).collect());
        for k in 0..3 {
            rec.push_column(format!("c{k}"), rows.iter().map(|r| r[k]).collect());
        }
        let mut buf = Vec::new();
        write_csv_to(&mut buf, &rec).unwrap();
        let back = parse_csv_bytes(&buf, "rt.csv").unwrap();
        prop_assert_eq!(back, rec);
    }
}
