//! Specification of the data compatibility check: flight-path reconstruction
//! recovers an injected pitch-rate bias and an angle-of-attack time skew, and finds nothing on
//! clean data.

mod common;

use flightid::data::{check_compatibility, CheckOptions, CheckReport, FlightRecord};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const G: f64 = 9.80665;

/// Smooth pulse: one period of a raised sine of width `w` starting at `t0`, signed.
fn bump(t: f64, t0: f64, w: f64) -> f64 {
    if t < t0 || t > t0 + w {
        0.0
    } else {
        (std::f64::consts::PI * (t - t0) / w).sin().powi(2)
    }
}

/// Kinematically consistent 40 s flight at 52 m/s, sampled at 50 Hz from a 400 Hz RK4 truth:
/// pitch doublet-like q pulses with α following, roll pulses in p, a little yaw rate. Specific
/// forces are what the rigid-body equations need for that motion (Klein & Morelli eq. 10.1).
/// Returns the truth at 400 Hz (time, states) for injecting skews, and the sampled record.
fn consistent_flight(q_bias_rad_s: f64, alpha_skew_s: f64, noise: bool) -> FlightRecord {
    let h = 1.0 / 400.0;
    let n_fine = 16_000;
    let rates = |t: f64| {
        let p = 0.25 * (bump(t, 5.0, 1.5) - bump(t, 6.5, 1.5))
            + 0.15 * (bump(t, 25.0, 2.0) - bump(t, 27.0, 2.0));
        let q = 0.08 * (bump(t, 12.0, 1.2) - bump(t, 13.2, 1.2))
            + 0.05 * (bump(t, 31.0, 1.0) - bump(t, 32.0, 1.0));
        let r = 0.03 * (bump(t, 18.0, 3.0) - bump(t, 21.0, 3.0));
        [p, q, r]
    };
    // Specific force: hold u, make v follow a sideslip pulse and w follow q (α responds to pitch
    // rate like a short period).
    let force = |x: &[f64; 6], w: [f64; 3], t: f64| {
        let [u, v, wv, phi, theta, _] = *x;
        let [p, q, r] = w;
        let fx = -(r * v - q * wv - G * theta.sin());
        let v_ref = 1.5 * (bump(t, 18.0, 3.0) - bump(t, 21.0, 3.0));
        let fy = -2.0 * (v - v_ref) - (p * wv - r * u + G * theta.cos() * phi.sin());
        let w_ref = 2.5 + 8.0 * q;
        let fz = -2.0 * (wv - w_ref) - (q * u - p * v + G * theta.cos() * phi.cos());
        [fx, fy, fz]
    };
    let deriv = |x: &[f64; 6], t: f64| {
        let w = rates(t);
        let f = force(x, w, t);
        let [u, v, wv, phi, theta, _] = *x;
        let [p, q, r] = w;
        [
            r * v - q * wv - G * theta.sin() + f[0],
            p * wv - r * u + G * theta.cos() * phi.sin() + f[1],
            q * u - p * v + G * theta.cos() * phi.cos() + f[2],
            p + theta.tan() * (q * phi.sin() + r * phi.cos()),
            q * phi.cos() - r * phi.sin(),
            (q * phi.sin() + r * phi.cos()) / theta.cos(),
        ]
    };
    let mut x = [51.94, 0.0, 2.5, 0.0, 0.048, 1.0];
    // (time, state u v w φ θ ψ, rates p q r, specific force)
    type Sample = (f64, [f64; 6], [f64; 3], [f64; 3]);
    let mut fine: Vec<Sample> = Vec::with_capacity(n_fine + 1);
    for k in 0..=n_fine {
        let t = k as f64 * h;
        let w = rates(t);
        fine.push((t, x, w, force(&x, w, t)));
        let a = |x: &[f64; 6], d: &[f64; 6], s: f64| [0, 1, 2, 3, 4, 5].map(|i| x[i] + s * d[i]);
        let k1 = deriv(&x, t);
        let k2 = deriv(&a(&x, &k1, h / 2.0), t + h / 2.0);
        let k3 = deriv(&a(&x, &k2, h / 2.0), t + h / 2.0);
        let k4 = deriv(&a(&x, &k3, h), t + h);
        x = [0, 1, 2, 3, 4, 5]
            .map(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    let alpha_of = |s: &[f64; 6]| s[2].atan2(s[0]);
    let alpha_at = |t: f64| {
        let k = ((t / h).floor() as usize).min(n_fine - 1);
        let w = t / h - k as f64;
        (1.0 - w) * alpha_of(&fine[k].1) + w * alpha_of(&fine[k + 1].1)
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let mut gauss = |sd: f64| {
        if noise {
            Normal::new(0.0, sd).unwrap().sample(&mut rng)
        } else {
            0.0
        }
    };
    let mut cols: Vec<(&str, Vec<f64>)> = [
        "p_rad_s",
        "q_rad_s",
        "r_rad_s",
        "ax_m_s2",
        "ay_m_s2",
        "az_m_s2",
        "airspeed_m_s",
        "alpha_rad",
        "beta_rad",
        "phi_rad",
        "theta_rad",
        "psi_rad",
    ]
    .into_iter()
    .map(|n| (n, Vec::new()))
    .collect();
    let mut time_s = Vec::new();
    for k in (0..=n_fine).step_by(8).skip(40) {
        let (t, s, w, f) = fine[k];
        time_s.push(t);
        let vt = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
        let values = [
            w[0] + gauss(1e-3),
            w[1] + q_bias_rad_s + gauss(1e-3),
            w[2] + gauss(1e-3),
            f[0] + gauss(0.02),
            f[1] + gauss(0.02),
            f[2] + gauss(0.02),
            vt + gauss(0.05),
            alpha_at(t - alpha_skew_s) + gauss(1e-3),
            (s[1] / vt).asin() + gauss(1e-3),
            s[3] + gauss(1e-3),
            s[4] + gauss(1e-3),
            s[5] + gauss(1e-3),
        ];
        for (c, v) in cols.iter_mut().zip(values) {
            c.1.push(v);
        }
    }
    let mut rec = FlightRecord::new(time_s);
    for (n, v) in cols {
        rec.push_column(n, v);
    }
    rec
}

fn get<'a>(rep: &'a CheckReport, name: &str) -> &'a flightid::data::Estimate {
    rep.instrument
        .iter()
        .find(|e| e.name == name)
        .unwrap_or_else(|| panic!("{name} not estimated: {:#?}", rep.instrument))
}

#[test]
fn injected_pitch_rate_bias_and_alpha_skew_are_recovered_within_20_percent() {
    let q_bias = 0.5_f64.to_radians();
    let rec = consistent_flight(q_bias, 0.060, true);
    let rep = check_compatibility(&rec, &CheckOptions::default()).unwrap();
    assert!(rep.translational && rep.converged, "{rep:#?}");
    let bq = get(&rep, "bias_q_rad_s");
    assert!(
        (bq.value - q_bias).abs() < 0.2 * q_bias,
        "q bias {} vs {q_bias}",
        bq.value
    );
    assert!(bq.significant);
    let skew = get(&rep, "skew_alpha_s");
    assert!(
        (skew.value - 0.060).abs() < 0.2 * 0.060,
        "alpha skew {} s",
        skew.value
    );
    assert!(skew.significant && skew.std_error < 0.01, "{skew:?}");
    // Nothing else was injected.
    for e in &rep.instrument {
        if e.name != "bias_q_rad_s" && e.name != "skew_alpha_s" {
            assert!(!e.significant, "spurious {e:?}");
        }
    }
}

#[test]
fn clean_data_shows_no_significant_instrument_error() {
    let rec = consistent_flight(0.0, 0.0, true);
    let rep = check_compatibility(&rec, &CheckOptions::default()).unwrap();
    for e in &rep.instrument {
        assert!(!e.significant, "spurious {e:?}");
    }
    let bq = get(&rep, "bias_q_rad_s");
    assert!(bq.value.abs() < 0.05_f64.to_radians(), "{bq:?}");
}

#[test]
fn attitude_only_data_still_checks_the_gyros() {
    let full = consistent_flight(0.5_f64.to_radians(), 0.0, false);
    let mut rec = FlightRecord::new(full.time_s.clone());
    for n in [
        "p_rad_s",
        "q_rad_s",
        "r_rad_s",
        "phi_rad",
        "theta_rad",
        "psi_rad",
    ] {
        rec.push_column(n, full.column(n).unwrap().to_vec());
    }
    let rep = check_compatibility(&rec, &CheckOptions::default()).unwrap();
    assert!(!rep.translational);
    let bq = get(&rep, "bias_q_rad_s");
    assert!(
        (bq.value - 0.5_f64.to_radians()).abs() < 0.02 * 0.5_f64.to_radians(),
        "{bq:?}"
    );
}

/// The project's provisioned Python with jsbsim for the oracle flight.
fn python() -> std::path::PathBuf {
    flightid::sim::env::python().expect("provisioned Python")
}

/// A 30 s JSBSim c172x flight with elevator, aileron and rudder doublets, 50 Hz
/// (scripts/oracle_check_flight.py). The first sample (before the first `run()`) has zero rates and
/// is dropped.
fn jsbsim_flight() -> FlightRecord {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("jsbsim.csv");
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/oracle_check_flight.py");
    let out = std::process::Command::new(python())
        .arg(script)
        .arg(&csv)
        .output()
        .expect("run oracle script");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rec = flightid::data::read_csv(&csv).unwrap();
    rec.slice(1, rec.len())
}

/// Delays a column by `skew_s` (linear interpolation, held at the start).
fn delay(rec: &mut FlightRecord, column: &str, skew_s: f64) {
    let t = rec.time_s.clone();
    let x = rec.column(column).unwrap().to_vec();
    let delayed = t
        .iter()
        .map(|&ti| {
            let tt = (ti - skew_s).max(t[0]);
            let k = t
                .partition_point(|&s| s <= tt)
                .saturating_sub(1)
                .min(t.len() - 2);
            let w = (tt - t[k]) / (t[k + 1] - t[k]);
            x[k] + w * (x[k + 1] - x[k])
        })
        .collect();
    rec.push_column(column, delayed);
}

#[test]
fn jsbsim_flight_with_q_bias_and_alpha_skew_is_diagnosed_and_clean_flight_is_not() {
    let clean = jsbsim_flight();
    let rep = check_compatibility(&clean, &CheckOptions::default()).unwrap();
    assert!(rep.translational && rep.converged);
    for e in &rep.instrument {
        assert!(!e.significant, "clean JSBSim flight: spurious {e:?}");
    }

    // Specification: +0.5 °/s on q and α delayed by 60 ms, both recovered within 20 %.
    let q_bias = 0.5_f64.to_radians();
    let mut bad = clean.clone();
    let q: Vec<f64> = bad
        .column("q_rad_s")
        .unwrap()
        .iter()
        .map(|q| q + q_bias)
        .collect();
    bad.push_column("q_rad_s", q);
    delay(&mut bad, "alpha_rad", 0.060);
    let rep = check_compatibility(&bad, &CheckOptions::default()).unwrap();
    let bq = get(&rep, "bias_q_rad_s");
    assert!(
        bq.significant && (bq.value - q_bias).abs() < 0.2 * q_bias,
        "{bq:?}"
    );
    let skew = get(&rep, "skew_alpha_s");
    assert!(
        skew.significant && (skew.value - 0.060).abs() < 0.2 * 0.060,
        "{skew:?}"
    );
    for e in &rep.instrument {
        if e.name != "bias_q_rad_s" && e.name != "skew_alpha_s" {
            assert!(!e.significant, "spurious {e:?}");
        }
    }
}

/// Specification: a longitudinal-only record (the JSBSim flight up to its aileron doublet: an
/// elevator doublet, β never moves) gets no β scale factor or skew at all, and says why; nothing
/// on it is flagged significant.
#[test]
fn a_longitudinal_only_record_gets_no_beta_scale_factor_and_says_why() {
    let flight = jsbsim_flight();
    let end = flight.time_s.partition_point(|&t| t < 9.5);
    let mut longitudinal = flight.slice(0, end);
    // A vane on a wings-level flight: β is its trim value plus sensor noise of 0.1° (JSBSim's noise-free β
    // still swings 0.55° here, which is excitation).
    let beta = longitudinal.column("beta_rad").unwrap().to_vec();
    let mean = beta.iter().sum::<f64>() / beta.len() as f64;
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let vane = Normal::new(0.0, 0.1_f64.to_radians()).unwrap();
    let noisy: Vec<f64> = beta.iter().map(|_| mean + vane.sample(&mut rng)).collect();
    longitudinal.push_column("beta_rad", noisy);
    let rep = check_compatibility(&longitudinal, &CheckOptions::default()).unwrap();
    assert!(rep.converged);
    for name in ["scale_beta", "skew_beta_s"] {
        assert!(
            rep.instrument.iter().all(|e| e.name != name),
            "{name} estimated: {rep:?}"
        );
        assert!(
            rep.not_excited.iter().any(|w| w.starts_with(name)
                && w.contains("beta_rad moves")
                && w.contains("not clearly beyond")),
            "{name}: {:?}",
            rep.not_excited
        );
    }
    // α is excited by the doublet: its scale factor and skew are estimated.
    assert!(
        rep.instrument.iter().any(|e| e.name == "scale_alpha"),
        "{rep:?}"
    );
    for e in &rep.instrument {
        assert!(!e.significant, "longitudinal JSBSim flight: spurious {e:?}");
    }
}

/// Specification: a reconstruction stopped before it converges is an error (exit 1) with no table.
#[test]
fn an_unconverged_check_exits_1_without_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("f.csv");
    flightid::data::write_csv_atomic(&csv, &consistent_flight(0.5_f64.to_radians(), 0.0, true))
        .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(["check", csv.to_str().unwrap(), "--max-iterations", "1"])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("did not converge in 1 iterations"),
        "{stderr}"
    );
    assert!(
        !stdout.contains("instrument error"),
        "a table was printed: {stdout}"
    );
}

/// Specification: a reconstruction whose residuals overflow (one pitch-rate sample of 1e300, as a corrupt
/// logger writes; the CSV reader refuses it, a record built in memory does not) is an error, not a converged fit
/// with infinite residuals.
#[test]
fn a_reconstruction_with_a_non_finite_cost_is_an_error() {
    let mut rec = consistent_flight(0.0, 0.0, true);
    let q = rec
        .columns
        .iter_mut()
        .find(|(n, _)| n == "q_rad_s")
        .unwrap();
    q.1[600] = 1e300;
    let err = check_compatibility(&rec, &CheckOptions::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with("the flight-path reconstruction diverged") && text.contains("not finite"),
        "{text}"
    );
}

/// Records of `aircraft` (seed 1, `records` e.g. "lon1,lon2") from the independent generator
/// `scripts/gen_foreign_records.py`, in a temporary directory.
fn foreign_records(aircraft: &str, records: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_foreign_records.py");
    common::run_ok(
        std::process::Command::new(python())
            .arg(script)
            .args([
                "--aircraft",
                aircraft,
                "--seed",
                "1",
                "--records",
                records,
                "--out",
            ])
            .arg(dir.path()),
    );
    dir
}

/// The reconstruction holds the altitude (ḣ = u sin θ − v sin φ cos θ − w cos φ cos θ, Klein & Morelli eq.
/// 10.1), which pins the flight-path angle. Without it, on pa28 records in light turbulence written by the
/// independent generator `scripts/gen_foreign_records.py`, the fit rotated the velocity vector by 34° and
/// named an α bias of 0.60 ± 0.09 rad significant (the generator's bias: 0.01°). Checked: the α bias stays
/// within 1° and the altitude is reconstructed to its noise.
#[test]
fn in_light_turbulence_the_alpha_bias_stays_a_sensor_bias_not_a_rotated_flight_path() {
    let dir = foreign_records("pa28", "lon1,lon2");
    for rec in ["pa28_lon1.csv", "pa28_lon2.csv"] {
        let out = common::run_ok(
            std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
                .arg("check")
                .arg(dir.path().join(rec))
                .arg("--columns")
                .arg(dir.path().join("pa28.columns.toml"))
                .arg("--json"),
        );
        let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let alpha_bias = report["instrument"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["name"] == "bias_alpha_rad")
            .unwrap_or_else(|| panic!("{rec}: no α bias in {report}"));
        let value = alpha_bias["value"].as_f64().unwrap();
        assert!(value.abs() < 1f64.to_radians(), "{rec}: {alpha_bias}");
        let h_rms = report["residual_rms"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r[0] == "altitude_m")
            .and_then(|r| r[1].as_f64())
            .unwrap_or_else(|| panic!("{rec}: altitude not reconstructed: {report}"));
        assert!(h_rms < 1.5, "{rec}: altitude residual {h_rms} m");
    }
}

/// What `flightid COMMAND DIR/REC --columns DIR/MAP` prints on stderr (its warnings), the command succeeding.
fn mapped_stderr(command: &str, dir: &std::path::Path, rec: &str, map: &str) -> String {
    let out = common::run_ok(
        std::process::Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg(command)
            .arg(dir.join(rec))
            .arg("--columns")
            .arg(dir.join(map)),
    );
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// Sign conventions are checked on real records, not guessed: on c310 records from the independent generator
/// (light turbulence) an α or β vane mapped with the other sign (`scale = -1.0` in the column map) is flagged,
/// with its column and the fix; with the logger's own map nothing is. Measured: α's windowed change against
/// its kinematic rate −0.86 (correlation −0.87, the gusts move α without the kinematics), β's −0.99 (−0.98).
#[test]
fn an_alpha_or_beta_vane_of_the_other_sign_is_flagged_and_the_right_one_is_not() {
    let dir = foreign_records("c310", "lon1,lat1");
    let map = std::fs::read_to_string(dir.path().join("c310.columns.toml")).unwrap();
    let flipped = map
        .replace(
            "{ to = \"alpha_rad\", unit = \"deg\" }",
            "{ to = \"alpha_rad\", unit = \"deg\", scale = -1.0 }",
        )
        .replace(
            "{ to = \"beta_rad\", unit = \"deg\" }",
            "{ to = \"beta_rad\", unit = \"deg\", scale = -1.0 }",
        );
    assert_ne!(flipped, map, "the map names the vanes as expected");
    std::fs::write(dir.path().join("flipped.toml"), flipped).unwrap();
    let warnings = |rec: &str, map: &str| mapped_stderr("check", dir.path(), rec, map);
    for (rec, column) in [
        ("c310_lon1.csv", "alpha_rad"),
        ("c310_lat1.csv", "beta_rad"),
    ] {
        let own = warnings(rec, "c310.columns.toml");
        assert!(!own.contains("warning"), "{rec}: {own}");
        let stderr = warnings(rec, "flipped.toml");
        assert!(
            stderr.contains(&format!("column `{column}`: its change is"))
                && stderr.contains("the other sign convention")
                && stderr.contains("scale = -1.0"),
            "{rec}: {stderr}"
        );
    }
}

/// The surfaces' sign conventions are checked on the motion they cause: on records of two aircraft from the
/// independent generator (`scripts/gen_foreign_records.py`, JSBSim's p51d and 737, light turbulence, 50 Hz), each
/// surface mapped with the other sign (`scale = -1.0`) is flagged with its column and the fix, and with the
/// logger's own map nothing is. Measured (the moment on its axis, rad/s² per rad, and its standard error): p51d
/// elevator +13.80 ± 0.22, aileron −11.54 ± 0.09, rudder +6.54 ± 0.14; 737 elevator +1.78 ± 0.14 (the weakest,
/// 12.7 standard errors against the 10 the check asks), aileron −2.63 ± 0.07, rudder +1.82 ± 0.11.
#[test]
fn a_surface_of_the_other_sign_is_flagged_and_the_right_one_is_not() {
    for aircraft in ["p51d", "737"] {
        let dir = foreign_records(aircraft, "lon1,lat1");
        let map =
            std::fs::read_to_string(dir.path().join(format!("{aircraft}.columns.toml"))).unwrap();
        let mut flipped = map.clone();
        for surface in ["elevator_rad", "aileron_rad", "rudder_rad"] {
            let own = format!("{{ to = \"{surface}\", unit = \"deg\" }}");
            assert!(
                flipped.contains(&own),
                "{aircraft}: the map names {surface} as expected"
            );
            flipped = flipped.replace(
                &own,
                &format!("{{ to = \"{surface}\", unit = \"deg\", scale = -1.0 }}"),
            );
        }
        std::fs::write(dir.path().join("flipped.toml"), flipped).unwrap();
        let warnings = |rec: &str, map: &str| mapped_stderr("segments", dir.path(), rec, map);
        for (rec, flagged) in [
            ("lon1", &[("elevator_rad", "pitch")][..]),
            (
                "lat1",
                &[("aileron_rad", "roll"), ("rudder_rad", "yaw")][..],
            ),
        ] {
            let rec = format!("{aircraft}_{rec}.csv");
            let own = warnings(&rec, &format!("{aircraft}.columns.toml"));
            assert!(!own.contains("warning"), "{rec}: {own}");
            let stderr = warnings(&rec, "flipped.toml");
            for (column, axis) in flagged {
                assert!(
                    stderr.contains(&format!(
                        "column `{column}`: the {axis} acceleration follows it"
                    )) && stderr.contains("sign opposite to flightid's convention"),
                    "{rec}: {stderr}"
                );
            }
            assert_eq!(
                stderr
                    .matches("sign opposite to flightid's convention")
                    .count(),
                flagged.len(),
                "{rec}: a surface that does not move is not judged: {stderr}"
            );
        }
    }
}

/// φ and θ carry a scale factor against the attitude the rates integrate to. Records from the independent
/// generator `scripts/gen_diagnose_records.py` (JSBSim's c172x, light turbulence, 45 s of the full maneuver
/// sequence, seed 31), each with one logged column scaled: φ × 0.85 gives scale_phi −0.1495 ± 0.0021, θ × 1.12
/// gives scale_theta +0.1243 ± 0.0012, and neither is named on the same flight without it (0.0004, 0.0037). A
/// roll gyro reading 0.9 × p reads as φ scaled by 1/0.9 (+0.1113): the kinematics alone cannot tell the two
/// apart, as the docs say. Checked: the scaled signal's factor (1 + s) within 1 % of the truth (seed 32: within
/// 0.4 % too), the other not significant, nothing named on the clean flight.
#[test]
fn an_attitude_scale_factor_is_recovered_and_a_clean_flight_gets_none() {
    let cases: [(&str, Option<(&str, f64)>); 4] = [
        (
            r#"[{"effect":"sensor_scale","target":"phi_rad","value":0.85}]"#,
            Some(("scale_phi", 0.85)),
        ),
        (
            r#"[{"effect":"sensor_scale","target":"theta_rad","value":1.12}]"#,
            Some(("scale_theta", 1.12)),
        ),
        ("[]", None),
        (
            r#"[{"effect":"sensor_scale","target":"p_rad_s","value":0.9}]"#,
            Some(("scale_phi", 1.0 / 0.9)),
        ),
    ];
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_diagnose_records.py");
    for (effects, want) in cases {
        let dir = tempfile::tempdir().unwrap();
        common::run_ok(
            std::process::Command::new(python())
                .arg(&script)
                .args([
                    "--cases",
                    "1",
                    "--seed",
                    "31",
                    "--turbulence",
                    "--duration",
                    "45",
                ])
                .args(["--plan", "full", "--effects", effects, "--out"])
                .arg(dir.path()),
        );
        let rec = flightid::data::read_csv(&dir.path().join("case_000_train.csv")).unwrap();
        let rep = check_compatibility(&rec, &CheckOptions::default()).unwrap();
        assert!(rep.converged, "{effects}: {rep:?}");
        for name in ["scale_phi", "scale_theta"] {
            let e = get(&rep, name);
            match want {
                Some((scaled, factor)) if scaled == name => {
                    assert!(e.significant, "{effects}: {e:?}");
                    let err = (1.0 + e.value) / factor - 1.0;
                    assert!(
                        err.abs() < 0.01,
                        "{effects}: {e:?}, factor off by {err:+.4}"
                    );
                }
                _ => assert!(!e.significant, "{effects}: {name} named: {e:?}"),
            }
        }
    }
}
