//! What the first hour's commands print: no terminal line of `demo`, `derivatives`, `compare` or `diagnose` is
//! wider than 120 characters, and the demo explains its anomalous numbers beside them — on the terminal, in the
//! JSON and on the rendered report page (headless Chromium).

mod common;

use std::path::Path;
use std::process::Command;

const WIDTH: usize = 120;

fn flightid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
}

fn assert_narrow(what: &str, stdout: &[u8]) -> String {
    let text = String::from_utf8_lossy(stdout).to_string();
    let wide = common::lines_wider_than(&text, WIDTH);
    assert!(wide.is_empty(), "{what}: {}", wide.join("\n"));
    text
}

/// The notes every demo anomaly gets, as they read on the terminal, in the JSON and on the report page.
const DEMO_NOTES: &[&str] = &[
    // the methods named in full
    "the paper's equation-error ARX least squares",
    "Young's simplified refined instrumental variable",
    "output error: Levenberg-Marquardt",
    // the modes named
    "short period",
    "Dutch roll",
    // the paper's least squares drifting in simulation, and why
    "equation error fits one-step predictions",
    // oe repeating srivc, and why
    "same model as srivc",
    // an unstable identified pole, flagged
    "unstable pole",
];

#[test]
fn demo_explains_every_anomaly_beside_it_within_120_columns() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("demo");
    let json = tmp.path().join("demo.json");
    let out = common::run_ok(
        flightid()
            .arg("demo")
            .arg("--report")
            .arg(&dir)
            .arg("--json")
            .arg(&json),
    );
    let stdout = assert_narrow("demo", &out.stdout);
    for note in DEMO_NOTES {
        assert!(
            stdout.replace('\n', " ").contains(note),
            "terminal lacks {note:?}:\n{stdout}"
        );
    }
    // the record lengths that make demo and compare differ are stated
    assert!(stdout.contains("30 s"), "{stdout}");
    let v = common::read_json(&json);
    let notes_of = |tf: &str, model: &str| -> String {
        v["models"][tf]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["model"] == model)
            .unwrap()["notes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap().to_string())
            .collect::<Vec<_>>()
            .join("; ")
    };
    // ls on theta/elevator: equation error drifts, explained; an unstable pole flagged where the model has one
    assert!(notes_of("theta/elevator", "ls").contains("one-step predictions"));
    for tf in ["theta/elevator", "phi/aileron", "phi/rudder"] {
        let unstable = v["models"][tf]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| {
                m["tf"]["poles"]
                    .as_array()
                    .is_some_and(|p| p.iter().any(|p| p[0].as_f64().unwrap() > 0.0))
            })
            .map(|m| m["model"].as_str().unwrap().to_string())
            .collect::<Vec<_>>();
        for model in unstable {
            assert!(
                notes_of(tf, &model).contains("unstable pole"),
                "{tf} {model}: an unstable pole without its note"
            );
        }
    }
    common::browser_check(&dir, 12, DEMO_NOTES);
}

#[test]
fn compare_json_without_report_and_derivatives_stay_within_120_columns() {
    let tmp = tempfile::tempdir().unwrap();
    let json = tmp.path().join("compare.json");
    let out = common::run_ok(
        flightid()
            .args(["compare", "--aircraft", "c172x", "--duration-s", "12"])
            .args(["--method", "ls,srivc", "--sweep-deg", "1,6", "--json"])
            .arg(&json),
    );
    let stdout = assert_narrow("compare", &out.stdout);
    assert!(stdout.contains("note:"), "{stdout}");
    assert!(
        common::read_json(&json)["models"]["theta/elevator"].is_array(),
        "compare --json without --report writes the results"
    );
    let out = common::run_ok(flightid().args(["derivatives", "--aircraft", "c172x"]));
    assert_narrow("derivatives", &out.stdout);
}

#[test]
fn diagnose_stays_within_120_columns() {
    let tmp = tempfile::tempdir().unwrap();
    let lin = tmp.path().join("lin.json");
    let csv = tmp.path().join("flight.csv");
    common::run_ok(
        flightid()
            .args(["linearize", "--aircraft", "c172x", "--json"])
            .arg(&lin),
    );
    common::run_ok(
        flightid()
            .args([
                "fly",
                "--aircraft",
                "c172x",
                "--surface",
                "elevator",
                "--maneuver",
                "3211",
            ])
            .args(["--duration-s", "15", "--rate-hz", "50", "--out"])
            .arg(&csv),
    );
    let out = common::run_ok(
        flightid()
            .arg("diagnose")
            .arg("--linear")
            .arg(&lin)
            .arg("--data")
            .arg(Path::new(&csv)),
    );
    assert_narrow("diagnose", &out.stdout);
}
