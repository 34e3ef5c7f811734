//! Campaigns run for real on JSBSim: resumption after kill -9, failed trims, bad campaign files, and the store's
//! rules: concurrent runs share the cases, a changed campaign file is refused, failed cases are retried on request.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

fn flightid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
}

/// 6 cases: c172x at one condition × 3 surfaces × 2 amplitudes, 8 s records.
const SMALL: &str = r#"
name = "small"
rate_hz = 60.0
duration_s = 8.0
methods = ["srivc"]

[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]

[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0, 3.0]

[[maneuvers]]
surface = "aileron"
shape = "doublet"
amplitudes_deg = [1.0, 3.0]

[[maneuvers]]
surface = "rudder"
shape = "3211"
pulse_s = 0.5
amplitudes_deg = [1.0, 3.0]
"#;

fn case_files(dir: &Path) -> BTreeMap<String, String> {
    let Ok(entries) = std::fs::read_dir(dir.join("cases")) else {
        return BTreeMap::new();
    };
    entries
        .flatten()
        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
        .map(|e| {
            (
                e.file_name().to_string_lossy().to_string(),
                std::fs::read_to_string(e.path()).unwrap(),
            )
        })
        .collect()
}

#[test]
fn killed_campaign_resumes_to_the_same_results_as_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("small.toml");
    std::fs::write(&spec, SMALL).unwrap();
    let full = tmp.path().join("full");
    let st = flightid()
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(&full)
        .args(["--jobs", "2"])
        .status()
        .unwrap();
    assert!(st.success());
    let reference = case_files(&full);
    assert_eq!(reference.len(), 6, "6 cases: {:?}", reference.keys());

    // Interrupted run: kill -9 as soon as two results exist, then resume with a different job count.
    let part = tmp.path().join("part");
    let mut child = flightid()
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(&part)
        .args(["--jobs", "1"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while case_files(&part).len() < 2 && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let done = case_files(&part).len();
    assert!(
        (2..6).contains(&done),
        "the kill must land mid-campaign, {done} of 6 done"
    );
    let out = flightid()
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(&part)
        .args(["--jobs", "2", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        summary["skipped"], done as u64,
        "finished cases are not redone"
    );
    assert_eq!(summary["ran"], (6 - done) as u64);
    // Byte-identical: the bridge resets every model before each trim, so neither scheduling nor process reuse
    // can leak into results.
    assert_eq!(case_files(&part), reference);
}

/// Two aircraft, a mass variant of one of them, two conditions: with one job a worker switches configuration
/// (same process, other pre-trim properties) and aircraft (same process, new JSBSim instance) and restores trims
/// it made for earlier cases; with two jobs the histories differ again.
const MIXED: &str = r#"
name = "mixed"
rate_hz = 60.0
duration_s = 6.0
methods = ["ls"]

[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 }, { altitude_ft = 8000.0, speed_kts = 110.0 } ]

[[configurations]]
name = "c172x_aft_cg"
aircraft = "c172x"
properties = { "inertia/pointmass-weight-lbs[4]" = 200.0, "inertia/pointmass-location-X-inches[4]" = 140.0 }
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]

[[configurations]]
name = "737"
aircraft = "737"
conditions = [ { altitude_ft = 30000.0, speed_kts = 450.0 } ]

[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0]

[[maneuvers]]
surface = "aileron"
shape = "doublet"
amplitudes_deg = [2.0]
"#;

#[test]
fn results_do_not_depend_on_how_cases_share_processes() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("mixed.toml");
    std::fs::write(&spec, MIXED).unwrap();
    let mut runs = Vec::new();
    for (dir, jobs, fresh) in [
        ("one", "1", false),
        ("two", "2", false),
        ("fresh", "2", true),
    ] {
        let out = tmp.path().join(dir);
        let spec_path = if fresh {
            let p = tmp.path().join("mixed_fresh.toml");
            std::fs::write(
                &p,
                MIXED.replace(
                    "methods = [\"ls\"]",
                    "methods = [\"ls\"]\nfresh_process_per_case = true",
                ),
            )
            .unwrap();
            p
        } else {
            spec.clone()
        };
        let st = flightid()
            .args(["campaign", "run"])
            .arg(&spec_path)
            .arg("--out")
            .arg(&out)
            .args(["--jobs", jobs])
            .stderr(std::process::Stdio::null())
            .status()
            .unwrap();
        assert!(st.success());
        runs.push(case_files(&out));
    }
    assert_eq!(runs[0].len(), 8, "8 cases: {:?}", runs[0].keys());
    // byte-identical: one process per worker switching configuration and aircraft, two workers, and a fresh
    // process per case all give the same result files
    assert_eq!(runs[0], runs[1]);
    assert_eq!(runs[0], runs[2]);
}

#[test]
fn a_case_whose_trim_fails_is_recorded_and_the_campaign_carries_on() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("slow.toml");
    std::fs::write(
        &spec,
        r#"
name = "slow"
duration_s = 6.0
methods = ["ls"]
[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 }, { altitude_ft = 4000.0, speed_kts = 15.0 } ]
[[configurations]]
name = "c172x_typo"
aircraft = "c172x"
properties = { "inertia/no-such-mass-lbs" = 10.0 }
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [2.0]
"#,
    )
    .unwrap();
    let out_dir = tmp.path().join("out");
    let out = flightid()
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(&out_dir)
        .args(["--jobs", "2", "--json"])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "a campaign with failed cases exits 1: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("2 of 3 cases failed")
            && stderr.contains("c172x_4000ft_15kts_elevator_doublet_2deg"),
        "the failed cases are named: {stderr}"
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["total"], 3);
    assert_eq!(
        summary["failed"], 2,
        "15 kts is below the c172x stall speed; the typo configuration names no JSBSim property"
    );
    let typo: serde_json::Value =
        case_json(&out_dir, "c172x_typo_4000ft_100kts_elevator_doublet_2deg");
    assert_eq!(typo["status"], "failed");
    assert!(
        typo["error"]
            .as_str()
            .unwrap()
            .contains("inertia/no-such-mass-lbs"),
        "the error names the property: {typo}"
    );
    let failed: serde_json::Value = case_json(&out_dir, "c172x_4000ft_15kts_elevator_doublet_2deg");
    assert_eq!(failed["status"], "failed");
    assert!(failed["error"].as_str().unwrap().contains("trim"));
    let ok: serde_json::Value = case_json(&out_dir, "c172x_4000ft_100kts_elevator_doublet_2deg");
    assert_eq!(ok["status"], "ok");
    // The summary report lists the failure.
    let st = flightid()
        .args(["campaign", "report"])
        .arg(&out_dir)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(st.success());
    let html = std::fs::read_to_string(out_dir.join("report/index.html")).unwrap();
    assert!(html.contains("Cases that failed") && html.contains("c172x_4000ft_15kts_elevator"));
    assert!(html.contains("c172x_typo_4000ft_100kts_elevator"));
    assert!(
        html.matches("<svg").count() >= 4,
        "modal plots vs speed and altitude"
    );
}

/// The result file of one case.
fn case_json(out_dir: &Path, id: &str) -> serde_json::Value {
    let path = out_dir.join(format!("cases/{id}.json"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn run_bad(text: &str) -> (i32, String) {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("bad.toml");
    std::fs::write(&spec, text).unwrap();
    let out = flightid()
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(tmp.path().join("out"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

#[test]
fn malformed_or_meaningless_campaign_files_are_usage_errors_that_say_what_is_wrong() {
    let (code, err) = run_bad("name = \"x\"\nmethods = [\"ls\"\n");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("malformed") && err.contains("line"), "{err}");

    let good = SMALL;
    let (code, err) = run_bad(&good.replacen("aircraft = \"c172x\"", "aircraft = \"a380\"", 1));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown aircraft 'a380'"), "{err}");

    let (code, err) = run_bad(&good.replace("\"3211\"", "\"sawtooth\""));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown maneuver shape 'sawtooth'"), "{err}");

    let (code, err) = run_bad(&good.replacen("surface = \"elevator\"", "surface = \"flaps\"", 1));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("'flaps'"), "{err}");

    let (code, err) = run_bad(&good.replace("[\"srivc\"]", "[\"magic\"]"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown method 'magic'"), "{err}");

    let (code, err) = run_bad(&good.replace("rate_hz = 60.0", "rate_hz = 60.0\ncolour = 1"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("colour"), "unknown keys are named: {err}");
}

fn run_into(spec: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    flightid()
        .args(["campaign", "run"])
        .arg(spec)
        .arg("--out")
        .arg(out)
        .args(["--jobs", "2"])
        .args(extra)
        .output()
        .unwrap()
}

/// 2 cases of 6 s: enough to see what the store does with them.
const TWO: &str = r#"
name = "two"
rate_hz = 60.0
duration_s = 6.0
methods = ["ls"]
[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0, 2.0]
"#;

#[test]
fn a_changed_campaign_file_is_refused_naming_the_changed_cases_unless_they_are_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let (spec, out) = (tmp.path().join("two.toml"), tmp.path().join("out"));
    std::fs::write(&spec, TWO).unwrap();
    let first = run_into(&spec, &out, &[]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = case_files(&out);
    let one = case_json(&out, "c172x_4000ft_100kts_elevator_doublet_1deg");
    assert_eq!(
        (one["rate_hz"].as_f64(), one["duration_s"].as_f64()),
        (Some(60.0), Some(6.0))
    );
    assert_eq!(one["definition_sha256"].as_str().map(str::len), Some(64));

    // a longer record: both results no longer describe their case
    std::fs::write(&spec, TWO.replace("duration_s = 6.0", "duration_s = 7.0")).unwrap();
    let refused = run_into(&spec, &out, &[]);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{err}");
    assert!(
        err.contains("2 case(s) changed definition")
            && err.contains("c172x_4000ft_100kts_elevator_doublet_1deg")
            && err.contains("c172x_4000ft_100kts_elevator_doublet_2deg")
            && err.contains("--rerun-changed"),
        "{err}"
    );
    assert_eq!(case_files(&out), before, "a refused run touches no result");

    // one amplitude dropped, one changed: the dropped case's result is named too
    std::fs::write(
        &spec,
        TWO.replace("duration_s = 6.0", "duration_s = 7.0")
            .replace("[1.0, 2.0]", "[2.0]"),
    )
    .unwrap();
    let refused = run_into(&spec, &out, &[]);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{err}");
    assert!(
        err.contains("1 case(s) changed definition")
            && err.contains("1 result(s) belong to no case of the campaign: c172x_4000ft_100kts_elevator_doublet_1deg"),
        "{err}"
    );

    let rerun = run_into(&spec, &out, &["--rerun-changed", "--json"]);
    assert!(
        rerun.status.success(),
        "{}",
        String::from_utf8_lossy(&rerun.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&rerun.stdout).unwrap();
    assert_eq!(summary["ran"], 1);
    assert_eq!(
        summary["prepared"]["rerun_changed"]
            .as_array()
            .map(Vec::len),
        Some(1)
    );
    assert_eq!(
        summary["prepared"]["removed"].as_array().map(Vec::len),
        Some(1)
    );
    let after = case_files(&out);
    assert_eq!(after.len(), 1, "{:?}", after.keys());
    let two = case_json(&out, "c172x_4000ft_100kts_elevator_doublet_2deg");
    assert_eq!(two["duration_s"].as_f64(), Some(7.0));
    assert_ne!(two["definition_sha256"], one["definition_sha256"]);
    // and now the store matches the file: a plain run has nothing to do
    let again = run_into(&spec, &out, &["--json"]);
    assert!(again.status.success());
    let summary: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(
        (summary["skipped"].as_u64(), summary["ran"].as_u64()),
        (Some(1), Some(0))
    );
}

#[test]
fn failed_cases_fail_the_run_until_retried_with_retry_failed() {
    let tmp = tempfile::tempdir().unwrap();
    let (spec, out) = (tmp.path().join("two.toml"), tmp.path().join("out"));
    std::fs::write(&spec, TWO).unwrap();
    // a simulator that cannot start: every case fails
    let broken = flightid()
        .env("FLIGHTID_PYTHON", "/bin/false")
        .args(["campaign", "run"])
        .arg(&spec)
        .arg("--out")
        .arg(&out)
        .args(["--jobs", "2", "--json"])
        .output()
        .unwrap();
    assert_eq!(
        broken.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&broken.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&broken.stdout).unwrap();
    assert_eq!(summary["failed"], 2);
    assert_eq!(case_files(&out).len(), 2, "failures are results too");

    // resuming does not rerun failures, and still exits 1
    let resumed = run_into(&spec, &out, &["--json"]);
    assert_eq!(resumed.status.code(), Some(1));
    let summary: serde_json::Value = serde_json::from_slice(&resumed.stdout).unwrap();
    assert_eq!(
        (summary["ran"].as_u64(), summary["failed"].as_u64()),
        (Some(0), Some(2))
    );

    let retried = run_into(&spec, &out, &["--retry-failed", "--json"]);
    assert!(
        retried.status.success(),
        "{}",
        String::from_utf8_lossy(&retried.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&retried.stdout).unwrap();
    assert_eq!(
        (summary["ran"].as_u64(), summary["failed"].as_u64()),
        (Some(2), Some(0))
    );
    let clean = tmp.path().join("clean");
    assert!(run_into(&spec, &clean, &[]).status.success());
    assert_eq!(
        case_files(&out),
        case_files(&clean),
        "retried = never failed, byte for byte"
    );
}

#[test]
fn two_runs_on_one_directory_at_once_run_each_case_exactly_once() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("small.toml");
    std::fs::write(&spec, SMALL).unwrap();
    let out = tmp.path().join("shared");
    let start = || {
        flightid()
            .args(["campaign", "run"])
            .arg(&spec)
            .arg("--out")
            .arg(&out)
            .args(["--jobs", "1", "--json"])
            .stderr(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (start(), start());
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success() && b.status.success());
    let sa: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    let sb: serde_json::Value = serde_json::from_slice(&b.stdout).unwrap();
    let ran = |s: &serde_json::Value| s["ran"].as_u64().unwrap();
    // each case ran in exactly one of the two processes; the other skipped it, found it claimed, or found it done
    assert_eq!(ran(&sa) + ran(&sb), 6, "{sa}\n{sb}");
    for s in [&sa, &sb] {
        assert_eq!(
            s["ran"].as_u64().unwrap()
                + s["skipped"].as_u64().unwrap()
                + s["claimed_elsewhere"].as_u64().unwrap(),
            6,
            "{s}"
        );
    }
    let full = tmp.path().join("alone");
    assert!(run_into(&spec, &full, &[]).status.success());
    assert_eq!(case_files(&out), case_files(&full));
}
