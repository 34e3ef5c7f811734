//! `derivatives --data … --airframe …` on measured records of aircraft other than the c172x.
//!
//! The records come from `scripts/gen_foreign_records.py`, an independent generator that drives JSBSim through
//! its own Python API (not flightid's bridge): p51d and c310 flights logged as a real data logger would (deg,
//! deg/s, ft, kts, g, psf, lbf; noise, biases, an IMU and vanes away from the CG, a vane time skew, light
//! turbulence). flightid sees only the records, the airframe description and the column map; the truth is
//! JSBSim's own derivatives about the CG, which the generator writes beside them.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn flightid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
}

fn scratch_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("flightid-measured-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn assert_bad_input(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

/// A small record in the schema with an elevator doublet (enough for the axis detection).
fn doublet_record(dir: &Path) -> PathBuf {
    let mut text =
        String::from("time_s,airspeed_m_s,alpha_rad,q_rad_s,theta_rad,elevator_rad,az_m_s2\n");
    for k in 0..500 {
        let t = k as f64 * 0.02;
        let de = if (1.0..1.5).contains(&t) {
            0.03
        } else if (1.5..2.0).contains(&t) {
            -0.03
        } else {
            0.0
        };
        text += &format!("{t},60,{},{},{},{de},-9.8\n", 0.05 + 0.1 * de, -de, 0.05);
    }
    let p = dir.join("doublet.csv");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn a_missing_airframe_key_is_bad_input_naming_the_key() {
    let dir = scratch_dir("missing-key");
    let data = doublet_record(&dir);
    let no_iyy = dir.join("no_iyy.toml");
    std::fs::write(
        &no_iyy,
        "name = \"x\"\nmass_kg = 1000.0\ninertia_kg_m2 = { ixx = 900.0 }\nwing = { area_m2 = 16.0, span_m = 11.0, mac_m = 1.5 }\n",
    )
    .unwrap();
    let out = flightid()
        .args(["derivatives", "--data"])
        .arg(&data)
        .arg("--airframe")
        .arg(&no_iyy)
        .output()
        .unwrap();
    assert_bad_input(&out, &["inertia_kg_m2.iyy", "no_iyy.toml"]);
    let no_wing = dir.join("no_wing.toml");
    std::fs::write(
        &no_wing,
        "name = \"x\"\nmass_kg = 1000.0\ninertia_kg_m2 = { iyy = 900.0 }\n",
    )
    .unwrap();
    let out = flightid()
        .args(["derivatives", "--data"])
        .arg(&data)
        .arg("--airframe")
        .arg(&no_wing)
        .output()
        .unwrap();
    assert_bad_input(&out, &["wing.area_m2"]);
    // Measured data without an airframe: refused, not read as the c172x.
    let out = flightid()
        .args(["derivatives", "--sensor-data", "--data"])
        .arg(&data)
        .output()
        .unwrap();
    assert_bad_input(&out, &["--airframe"]);
    std::fs::remove_dir_all(&dir).ok();
}
