//! A transport's flight-test records in the layout of Jategaonkar's book, read with the map and airframe that
//! flightid ships for the book's ATTAS records (`models/attas.columns.toml`, `models/attas.airframe.toml`).
//!
//! The records come from `scripts/gen_attas_records.py`, an independent generator (numpy/scipy, not flightid):
//! a six-degree-of-freedom rigid body with the ATTAS mass, inertia, geometry, engine and sensor positions of
//! the book, linear aerodynamics (the book's lateral estimates as the lateral truth) and a parabolic drag polar,
//! flown through light Dryden turbulence, logged at 25 Hz as the book's files hold them: no header, 38 columns,
//! degrees and feet, two ailerons and two engines, α, β and airspeed at a nose boom 13 m ahead of the CG,
//! accelerations at an IMU off the CG, the book's accelerometer and gyro biases, the logged air density. What
//! they test that the other generators do not: derived columns (½(left − right) aileron, the engines' sum),
//! a logged density, large vane and IMU offsets, and a 3-2-1-1 logged slowly enough that its steps dominate the
//! elevator's sample-to-sample differences.

mod common;

use std::path::Path;
use std::process::Command;

/// The generator's records of seed 1 (and `extra` arguments) in a fresh temporary directory of the test `tag`
/// (removed when the returned handle drops).
fn generated(tag: &str, extra: &[&str]) -> tempfile::TempDir {
    let tmp = tempfile::Builder::new()
        .prefix(&format!("flightid-attas-{tag}-"))
        .tempdir()
        .unwrap();
    let python = flightid::sim::env::python().expect("the project's Python environment");
    common::run_ok(
        Command::new(python)
            .arg(root().join("scripts/gen_attas_records.py"))
            .args(["--seed", "1"])
            .args(extra)
            .arg("--out")
            .arg(tmp.path()),
    );
    tmp
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `derivatives --method METHOD --json` on both records of `dir` as `.EXT` files, through the shipped map and
/// airframe: the JSON document.
fn derivatives(dir: &Path, ext: &str, method: &str) -> serde_json::Value {
    let out = dir.join(format!("{method}-{ext}.json"));
    common::run_ok(
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("derivatives")
            .arg("--data")
            .arg(dir.join(format!("attas_elv.{ext}")))
            .arg("--data")
            .arg(dir.join(format!("attas_ailrud.{ext}")))
            .arg("--columns")
            .arg(root().join("models/attas.columns.toml"))
            .arg("--airframe")
            .arg(root().join("models/attas.airframe.toml"))
            .args(["--method", method, "--json"])
            .arg(&out),
    );
    common::read_json(&out)
}

/// The derivatives judged: every target of a measured-data estimate, and the side force's β derivative.
const JUDGED: [&str; 11] = [
    "Cm_alpha", "Cm_q", "Cm_de", "CL_alpha", "Cl_p", "Cl_da", "Cl_beta", "Cn_beta", "Cn_r",
    "Cn_dr", "CY_beta",
];

/// Both records of seed 1 through the shipped map and airframe, by equation error and by filter error:
/// equation error within 10 % (measured: within 5.5 %, C_mq the largest), filter error within 5 % (measured:
/// within 2.0 %; the lateral ones within 0.6 %). Each of these was measured to fail them: the vane offset left
/// out (13 m: 0.1 rad of α per rad/s of q at 129 m/s; filter error C_Lα +10.9 %, C_nr −52 %), the IMU offset
/// left out (C_Yβ −16 %), the ISA density at the logged altitude in place of the logged density on this warm
/// day (5.5 % too dense: every derivative 5–7 % small by filter error), and the elevator record taken for a
/// still one (the longitudinal derivatives missing).
#[test]
fn the_shipped_attas_map_and_airframe_give_the_derivatives_of_records_in_the_books_layout() {
    let tmp = generated("derivatives", &[]);
    let dir = tmp.path();
    let truth = &common::read_json(&dir.join("attas.truth.json"))["flightid_equivalent"];
    for (method, tolerance) in [("ee", 0.10), ("fem", 0.05)] {
        let fit = derivatives(dir, "asc", method);
        assert_eq!(
            fit["axis"], "both",
            "{method}: both records excite their axis"
        );
        for name in JUDGED {
            let t = truth[name].as_f64().unwrap();
            let v = fit["derivatives"][name]["value"].as_f64().unwrap();
            let e = (v - t) / t.abs();
            eprintln!(
                "{method} {name:<9} truth {t:>9.4}  estimate {v:>9.4}  ({:+.1} %)",
                100.0 * e
            );
            assert!(e.abs() < tolerance, "{method} {name}: {:+.1} %", 100.0 * e);
        }
        let air = fit["air_data"].to_string();
        assert!(air.contains("density_kg_m3"), "{method}: {air}");
    }
}

/// `check --airframe`: the nose boom 13 m ahead of the CG makes the β vane read β + r x/V, which the
/// reconstruction's CG kinematics take for a lag of about x/V (measured without the airframe: skew_beta_s
/// 106 ± 10 ms, significant); with the airframe's sensor positions the record is moved to the CG first and the
/// skew is gone (measured 4 ± 10 ms, not significant), while the gyro biases (the book's) are found either way
/// (q: 0.003403 rad/s against 0.003409).
///
/// A dropout (1.6 s of the record cut out): the piece after it starts from its own initial state. Measured: gyro
/// biases within 5.0 % of the truth (p the largest; 3.4 % on the whole record), where integrating across the
/// missing samples, as `check` did before, put p 14.8 % off; tolerance 6 %.
#[test]
fn check_moves_the_nose_boom_vanes_to_the_cg_and_starts_a_piece_after_a_dropout_afresh() {
    let tmp = generated("check", &[]);
    let dir = tmp.path();
    let check = |file: &str, airframe: bool| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_flightid"));
        cmd.arg("check")
            .arg(dir.join(file))
            .arg("--columns")
            .arg(root().join("models/attas.columns.toml"))
            .arg("--json");
        if airframe {
            cmd.arg("--airframe")
                .arg(root().join("models/attas.airframe.toml"));
        }
        let out = common::run_ok(&mut cmd);
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()
    };
    let find = |report: &serde_json::Value, name: &str| {
        report["instrument"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["name"] == name)
            .cloned()
            .unwrap_or_else(|| panic!("{name} not in {report}"))
    };
    let report = check("attas_ailrud.asc", false);
    let skew = find(&report, "skew_beta_s");
    eprintln!("without the airframe: skew_beta_s {skew}");
    assert_eq!(skew["significant"], true);
    assert!(skew["value"].as_f64().unwrap() > 0.07);
    let report = check("attas_ailrud.asc", true);
    let skew = find(&report, "skew_beta_s");
    eprintln!("with the airframe: skew_beta_s {skew}");
    assert_eq!(skew["significant"], false);
    assert!(skew["value"].as_f64().unwrap().abs() < 0.03);
    assert_eq!(report["pieces"], 1);

    let text = std::fs::read_to_string(dir.join("attas_ailrud.asc")).unwrap();
    let gap: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(300..340).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(dir.join("gap.asc"), gap.join("\n") + "\n").unwrap();
    let report = check("gap.asc", true);
    assert_eq!(report["pieces"], 2);
    assert!(report["initial_state"]
        .to_string()
        .contains("initial_phi_rad_piece2"));
    for (name, truth_deg_s) in [("p", 0.0588f64), ("q", 0.1953), ("r", 0.0571)] {
        let bias = find(&report, &format!("bias_{name}_rad_s"))["value"]
            .as_f64()
            .unwrap();
        let truth = truth_deg_s.to_radians();
        eprintln!("dropout: bias_{name} {bias:.6} rad/s, truth {truth:.6}");
        assert!((bias - truth).abs() < 0.06 * truth, "bias_{name}");
    }
}

/// The book's supplement ships most of its ATTAS records as MATLAB MAT-files. The same records written as
/// MAT-files (`--mat`: the text files' numbers, one compressed as MATLAB's `-v7` saves, one not, each beside a
/// scalar and a character array) read through the same positional map give the same equation-error estimates
/// to the last digit; the matrix stored transposed (channels × samples) gives the same maneuvers, and so do the
/// same signals saved one vector per variable or as the fields of a structure. A file that is not a MAT-file,
/// one without a matrix of samples × channels, vectors of one length or a structure of them, and one whose
/// matrix is complex are refused with exit 2, saying which and what the file holds.
#[test]
fn mat_files_are_read_as_the_books_text_files_are() {
    let tmp = generated("mat", &["--mat"]);
    let dir = tmp.path();
    let python = flightid::sim::env::python().expect("the project's Python environment");
    let estimates = |ext: &str| derivatives(dir, ext, "ee")["derivatives"].clone();
    let text = estimates("asc");
    assert!(text["Cm_alpha"]["value"].is_f64() && text["Cl_p"]["value"].is_f64());
    assert_eq!(estimates("mat"), text);

    let script = "import numpy as np, scipy.io, sys\n\
                  d = sys.argv[1]\n\
                  scipy.io.savemat(d + '/scalars.mat', {'dt': 0.04, 'gain': np.array([1.0, 2.0])})\n\
                  scipy.io.savemat(d + '/complex.mat', {'data': np.ones((5, 3)) + 1j})\n\
                  m = scipy.io.loadmat(d + '/attas_ailrud.mat')['attas_ailrud']\n\
                  scipy.io.savemat(d + '/rows.mat', {'rows': m.T})\n\
                  r = np.deg2rad\n\
                  v = {'time_s': m[:, 0], 'p_rad_s': r(m[:, 6]), 'q_rad_s': r(m[:, 7]), 'r_rad_s': r(m[:, 8]),\n\
                       'elevator_rad': r(m[:, 21]), 'aileron_rad': r(0.5 * (m[:, 27] - m[:, 28])),\n\
                       'rudder_rad': r(m[:, 29]), 'dt': 0.04, 'gains': np.ones(3), 'pilot': 'test'}\n\
                  scipy.io.savemat(d + '/vectors.mat', v)\n\
                  rates = ('p_rad_s', 'q_rad_s', 'r_rad_s')\n\
                  flight = {k: x for k, x in v.items() if k not in rates}\n\
                  flight['imu'] = {k: v[k] for k in rates}\n\
                  scipy.io.savemat(d + '/struct.mat', {'flight': flight})\n\
                  scipy.io.savemat(d + '/notes.mat', {'notes': {'pilot': 'test', 'dt': 0.04}})\n\
                  open(d + '/garbage.mat', 'w').write('time,elevator\\n0,1\\n')\n";
    common::run_ok(Command::new(&python).args(["-c", script]).arg(dir));
    // The same matrix stored as channels × samples is read transposed: the same maneuvers are found.
    let segments = |file: &str| {
        let out = common::run_ok(
            Command::new(env!("CARGO_BIN_EXE_flightid"))
                .arg("segments")
                .arg(dir.join(file))
                .arg("--columns")
                .arg(root().join("models/attas.columns.toml")),
        );
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let found = segments("attas_ailrud.mat");
    assert!(
        found.contains("aileron_rad") && found.contains("rudder_rad"),
        "{found}"
    );
    assert_eq!(segments("rows.mat"), found);
    // One vector per signal, named as the schema's columns (a logger's export, or `save -struct`): read as
    // columns by name, without a map; the same maneuvers.
    let out = common::run_ok(
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("segments")
            .arg(dir.join("vectors.mat")),
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout), found);
    // The same signals in a structure (a nested one for the rates), read through scipy: the same maneuvers.
    let out = common::run_ok(
        Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("segments")
            .arg(dir.join("struct.mat")),
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout), found);
    for (file, needles) in [
        (
            "garbage.mat",
            vec!["garbage.mat", "not a readable MATLAB level-5 MAT-file"],
        ),
        (
            "scalars.mat",
            vec![
                "scalars.mat",
                "no numeric matrix of samples × channels",
                "`dt`",
            ],
        ),
        ("complex.mat", vec!["complex.mat", "`data` is complex"]),
        (
            "notes.mat",
            vec!["notes.mat", "no structure of signals", "'-struct'"],
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("segments")
            .arg(dir.join(file))
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{file}: {e}");
        for n in needles {
            assert!(e.contains(n), "{file}: '{n}' not in {e}");
        }
    }
}

/// The book defines its aileron as half the difference right minus left, the other sign from flightid's (positive
/// rolling right). A map written the book's way passes every unit check; the reader's sign check flags the mapped
/// aileron by the roll it causes, and the shipped map draws no warning. Measured on seed 1: −5.86 ± 0.04 rad/s²
/// per rad.
#[test]
fn an_aileron_mapped_the_books_way_is_flagged_by_its_sign() {
    let tmp = generated("sign", &[]);
    let dir = tmp.path();
    let shipped = std::fs::read_to_string(root().join("models/attas.columns.toml")).unwrap();
    let books = shipped.replace(
        "aileron_rad = { from = { 28 = 0.5, 29 = -0.5 }",
        "aileron_rad = { from = { 28 = -0.5, 29 = 0.5 }",
    );
    assert_ne!(
        books, shipped,
        "the shipped map derives the aileron as expected"
    );
    std::fs::write(dir.join("books.toml"), books).unwrap();
    let stderr = |map: &Path| {
        let out = common::run_ok(
            Command::new(env!("CARGO_BIN_EXE_flightid"))
                .arg("segments")
                .arg(dir.join("attas_ailrud.asc"))
                .arg("--columns")
                .arg(map),
        );
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let own = stderr(&root().join("models/attas.columns.toml"));
    assert!(!own.contains("warning"), "{own}");
    let books = stderr(&dir.join("books.toml"));
    assert!(
        books.contains("column `aileron_rad`: the roll acceleration follows it at -")
            && books.contains("sign opposite to flightid's convention"),
        "{books}"
    );
    assert_eq!(books.matches("warning").count(), 1, "{books}");
}
