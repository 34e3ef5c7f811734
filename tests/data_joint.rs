//! `identify` on several segments or files at once, fitted jointly
//! (`flightid::ident::identify_joint`), and `--segment` on the command line.
//!
//! Recipe (as tests/ident_jsbsim.rs): JSBSim c172x trimmed at 4000 ft / 100 KTAS, 120 Hz, elevator
//! deflection overridden (no actuator dynamics), θ/δe with 4 poles / 2 zeros. 120 Hz, not 50 Hz:
//! at 50 Hz JSBSim's own integration adds a systematic ~12 % error to the short-period ζ of the
//! recorded response, which no estimator can remove. Two maneuvers are flown in one 60 s log: a
//! 1° doublet of 1 s pulses at 3 s and a 1° 3-2-1-1 of 0.5 s pulses at 30 s, from the same trim.
//!
//! Tolerances against JSBSim's linearization (decoupled 4-state submodel): ωn 5 %, ζ 10 %. Single-
//! record fits of this aircraft differ from that reference *systematically* by ωn +0.7…+5 % and
//! ζ −6…−8 % over pulse widths 0.2–1 s (tests/ident_jsbsim.rs: the reference submodel drops
//! couplings, and the 4/2 structure; not noise) — here the 0.5 s 3-2-1-1 alone gives ωn +4.6 %,
//! ζ −12 %, the doublet alone +2.0 %, −7.5 %. So the joint fit is held to that band and, the
//! point of fitting jointly, to "no worse than the worse single-record fit" (measured: srivc
//! ωn +3.6 %, ζ −6.7 %).

use std::path::{Path, PathBuf};
use std::process::Command;

use flightid::aircraft;
use flightid::data::{find_segments, write_csv_atomic, FlightRecord, SegmentOptions};
use flightid::ident::{self, IdentOptions, JointRecord, Method};
use flightid::lti::{self, Mode};
use flightid::signal::{self, Maneuver};
use flightid::sim::linear::paper_transfer_functions;
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};

const RATE_HZ: f64 = 120.0;

fn short_period(poles: &[num_complex::Complex64]) -> Mode {
    lti::modes(poles)
        .into_iter()
        .filter(|m| m.oscillatory)
        .max_by(|a, b| a.omega_n_rad_s.total_cmp(&b.omega_n_rad_s))
        .expect("an oscillatory mode")
}

/// The 60 s two-maneuver log and the linearization's short period.
fn flight() -> (FlightRecord, Mode) {
    let dt_s = 1.0 / RATE_HZ;
    let duration_s = 60.0;
    let mut sim = JsbsimSim::start(&aircraft::load("c172x").unwrap(), RATE_HZ).unwrap();
    sim.trim(&TrimPoint::level(4000.0, 100.0)).unwrap();
    let truth = paper_transfer_functions(&sim.linearize().unwrap()).unwrap();
    let lin = short_period(&truth["theta/elevator"].poles());
    let doublet = signal::generate(&Maneuver::Doublet { pulse_s: 1.0 }, dt_s, duration_s, 3.0);
    let m3211 = signal::generate(
        &Maneuver::ThreeTwoOneOne { pulse_s: 0.5 },
        dt_s,
        duration_s,
        30.0,
    );
    let n_steps = (duration_s * RATE_HZ) as usize;
    let deflection_rad: Vec<f64> = (0..n_steps)
        .map(|k| (doublet[k] + m3211[k]) * 1f64.to_radians())
        .collect();
    let rec = sim
        .fly(&FlightPlan {
            rate_hz: RATE_HZ,
            n_steps,
            inputs: vec![SurfaceInput {
                surface: "elevator".into(),
                deflection_rad,
            }],
        })
        .unwrap();
    (rec, lin)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn flightid(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(args)
        .output()
        .expect("run flightid")
}

/// Runs flightid, which must succeed, and parses its JSON output.
fn flightid_json(args: &[&str]) -> serde_json::Value {
    let out = flightid(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn joint_fit_of_two_jsbsim_maneuvers_matches_the_linearization_and_the_cli_selects_segments() {
    let (rec, lin) = flight();
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("two_maneuvers.csv");
    write_csv_atomic(&log, &rec).unwrap();

    // The segment finder sees both maneuvers (what --segment 1 / 2 refer to).
    let segs = find_segments(&rec, &SegmentOptions::default()).unwrap();
    let elevator: Vec<_> = segs
        .iter()
        .filter(|s| s.surface == "elevator_rad")
        .collect();
    assert_eq!(elevator.len(), 2, "{segs:?}");
    assert_eq!(segs.len(), 2, "{segs:?}");

    // Library: the two segments (1 s before to 12 s after each start) jointly vs one by one.
    let window = |start_s: f64| {
        let a = ((start_s - 1.0) * RATE_HZ) as usize;
        rec.slice(a, a + (13.0 * RATE_HZ) as usize)
    };
    let records: Vec<JointRecord> = [3.0, 30.0]
        .iter()
        .map(|&t0| {
            let w = window(t0);
            JointRecord {
                label: format!("maneuver at {t0} s"),
                u: w.column("elevator_rad").unwrap().to_vec(),
                y: w.column("theta_rad").unwrap().to_vec(),
                dt_s: 1.0 / RATE_HZ,
            }
        })
        .collect();
    for method in [Method::Srivc, Method::Oe] {
        let opts = IdentOptions {
            method,
            poles: 4,
            zeros: 2,
            estimate_delay: false,
        };
        let joint = ident::identify_joint(&records, &opts).unwrap();
        let m = short_period(&joint.result.poles);
        let (wn_err, zeta_err) = (
            rel(m.omega_n_rad_s, lin.omega_n_rad_s),
            rel(m.zeta, lin.zeta),
        );
        let single: Vec<(f64, f64)> = records
            .iter()
            .map(|r| {
                let s = ident::identify(&r.u, &r.y, r.dt_s, &opts).unwrap();
                let sm = short_period(&s.poles);
                (
                    rel(sm.omega_n_rad_s, lin.omega_n_rad_s),
                    rel(sm.zeta, lin.zeta),
                )
            })
            .collect();
        eprintln!(
            "{method}: joint ωn err {:.2} %, ζ err {:.2} %, fit {:.2} %; single {:?}",
            100.0 * wn_err,
            100.0 * zeta_err,
            joint.result.fit_sim_percent,
            single
        );
        assert!(wn_err < 0.05, "{method}: joint ωn error {wn_err}");
        assert!(zeta_err < 0.10, "{method}: joint ζ error {zeta_err}");
        // No worse than the worse single fit (0.5 % of slack for round-off between fits).
        let worst_wn = single.iter().map(|s| s.0).fold(0.0, f64::max);
        let worst_zeta = single.iter().map(|s| s.1).fold(0.0, f64::max);
        assert!(
            wn_err <= worst_wn + 0.005,
            "{method}: {wn_err} vs {worst_wn}"
        );
        assert!(
            zeta_err <= worst_zeta + 0.005,
            "{method}: {zeta_err} vs {worst_zeta}"
        );
        assert!(joint.result.fit_sim_percent > 95.0);
        assert_eq!(joint.records.len(), 2);
    }

    // CLI: the same two segments of one file, by number.
    let v = flightid_json(&[
        "identify",
        "--data",
        path(&log),
        "--segment",
        "1",
        "--segment",
        "2",
        "--input",
        "elevator",
        "--output",
        "theta_rad",
        "--method",
        "srivc",
        "--json",
        "-",
    ]);
    assert_eq!(v["records"].as_array().unwrap().len(), 2, "{v}");
    let poles: Vec<num_complex::Complex64> = v["result"]["poles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| num_complex::Complex64::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
        .collect();
    let m = short_period(&poles);
    assert!(
        rel(m.omega_n_rad_s, lin.omega_n_rad_s) < 0.05,
        "{m:?} vs {lin:?}"
    );
    assert!(rel(m.zeta, lin.zeta) < 0.10, "{m:?} vs {lin:?}");

    // Two files, one segment each (K:N), with a window length.
    let second: PathBuf = dir.path().join("copy.csv");
    std::fs::copy(&log, &second).unwrap();
    let v = flightid_json(&[
        "identify",
        "--data",
        path(&log),
        "--data",
        path(&second),
        "--segment",
        "1:1",
        "--segment",
        "2:2",
        "--window-s",
        "12",
        "--input",
        "elevator",
        "--output",
        "theta_rad",
        "--json",
        "-",
    ]);
    let n: Vec<u64> = v["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["n_samples"].as_u64().unwrap())
        .collect();
    assert_eq!(
        n,
        vec![12 * 120 + 1, 12 * 120 + 1],
        "12 s windows at 120 Hz"
    );

    // Bad segment references: exit 2, naming what is wrong.
    let out = flightid(&[
        "identify",
        "--data",
        path(&log),
        "--segment",
        "3",
        "--input",
        "elevator",
        "--output",
        "theta_rad",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no segment 3") && err.contains("finds 2"),
        "{err}"
    );
    let out = flightid(&[
        "identify",
        "--data",
        path(&log),
        "--data",
        path(&second),
        "--segment",
        "1",
        "--input",
        "elevator",
        "--output",
        "theta_rad",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--segment K:1"), "{err}");
    let out = flightid(&[
        "identify",
        "--data",
        path(&log),
        "--segment",
        "3:1",
        "--input",
        "elevator",
        "--output",
        "theta_rad",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no --data file 3"));
}
