//! `flightid diagnose` / `replay` / `fly --model` from the command line, and bad input: a record missing
//! the channels an extension needs (the extension is skipped and the output says so), a record too short to
//! identify anything (exit 2), a trim that fails at the measured condition (exit 1, the reason named), a linear
//! model used far from its trim point (exit 1, the reason named).

use std::path::Path;
use std::process::{Command, Output};

fn flightid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(args)
        .output()
        .expect("flightid runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// An 8 s, 50 Hz record of simultaneous doublets on elevator and aileron from c172x trim (4000 ft, 100 kts).
fn fly(out: &Path) {
    let o = flightid(&[
        "fly",
        "--surface",
        "elevator",
        "--surface",
        "aileron",
        "--maneuver",
        "doublet",
        "--amplitude-deg",
        "2",
        "--duration-s",
        "8",
        "--rate-hz",
        "50",
        "--sim-rate-hz",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "fly failed: {}", text(&o));
}

/// A column and the change applied to each of its values.
type Edit<'a> = Option<(&'a str, fn(f64) -> f64)>;

/// Rewrites a CSV: keeps the first `rows` data rows, drops `drop` columns, applies `edit` to one column.
fn rewrite(src: &Path, dst: &Path, rows: usize, drop: &[&str], edit: Edit) {
    let s = std::fs::read_to_string(src).unwrap();
    let mut lines = s.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !drop.contains(&header[i]))
        .collect();
    let mut out = keep
        .iter()
        .map(|&i| header[i])
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    for line in lines.take(rows) {
        let cells: Vec<&str> = line.split(',').collect();
        let row: Vec<String> = keep
            .iter()
            .map(|&i| match edit {
                Some((c, f)) if header[i] == c => format!("{}", f(cells[i].parse().unwrap())),
                _ => cells[i].to_string(),
            })
            .collect();
        out.push_str(&row.join(","));
        out.push('\n');
    }
    std::fs::write(dst, out).unwrap();
}

#[test]
fn record_too_short_is_refused_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.csv");
    let short = dir.path().join("short.csv");
    fly(&full);
    rewrite(&full, &short, 20, &[], None);
    let o = flightid(&["diagnose", "--data", short.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("too short"), "{}", text(&o));
}

#[test]
fn trim_failure_at_the_measured_condition_is_named() {
    // 12 m/s (23 kts) is far below the c172x stall speed: the model cannot trim there.
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.csv");
    let slow = dir.path().join("slow.csv");
    fly(&full);
    rewrite(&full, &slow, 400, &[], Some(("airspeed_m_s", |v| v - 39.4)));
    let o = flightid(&["replay", "--data", slow.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("cannot trim at the record's measured initial condition"),
        "{}",
        text(&o)
    );
}

#[test]
fn linear_model_replays_near_its_trim_and_refuses_far_from_it() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.csv");
    let fast = dir.path().join("fast.csv");
    let lin = dir.path().join("lin.json");
    fly(&full);
    let o = flightid(&["linearize", "--json", lin.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    // Near trim: the linear model reproduces pitch rate well under 2° doublets (fit > 80 %).
    let o = flightid(&[
        "replay",
        "--linear",
        lin.to_str().unwrap(),
        "--data",
        full.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let fit = v["residuals"]["q_rad_s"]["fit_percent"].as_f64().unwrap();
    assert!(fit > 80.0, "linear replay q fit {fit} %");
    // diagnose runs on the linear model too; the accelerations it does not produce are left out, and said so.
    // With `--json -` stdout is the JSON document alone (the summary and the progress go to stderr).
    let o = flightid(&[
        "diagnose",
        "--linear",
        lin.to_str().unwrap(),
        "--data",
        full.to_str().unwrap(),
        "--json",
        "-",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let d: serde_json::Value =
        serde_json::from_slice(&o.stdout).expect("stdout is one JSON document");
    assert!(d["named_cause"].is_array(), "{d}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("simulations in"),
        "the summary goes to stderr: {}",
        text(&o)
    );
    assert!(
        text(&o).contains("does not produce ax_m_s2, ay_m_s2, az_m_s2"),
        "{}",
        text(&o)
    );
    // 30 % faster than the linear model's trim: refused, with the reason.
    rewrite(&full, &fast, 400, &[], Some(("airspeed_m_s", |v| v * 1.3)));
    let o = flightid(&[
        "replay",
        "--linear",
        lin.to_str().unwrap(),
        "--data",
        fast.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("linear model holds only near"),
        "{}",
        text(&o)
    );
}

#[test]
fn missing_channel_skips_its_extensions_and_the_model_and_report_are_written() {
    // No rudder_rad and no beta_rad column (the rudder did not move): the rudder's signal-path effects and the β
    // sensor effects are skipped and listed, the missing surface column is warned about; on clean data nothing is
    // named; the model directory loads in replay and fly; the report holds the overlays.
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.csv");
    let cut = dir.path().join("cut.csv");
    fly(&full);
    rewrite(&full, &cut, 401, &["rudder_rad", "beta_rad"], None);
    // The last row logged twice, as a logger relaying a sample twice does: the reader drops it and says so, on the
    // terminal and in the diagnosis.
    let csv = std::fs::read_to_string(&cut).unwrap();
    let last = csv.lines().last().unwrap().to_string();
    std::fs::write(&cut, format!("{csv}{last}\n")).unwrap();
    let (json, model, report) = (
        dir.path().join("d.json"),
        dir.path().join("model"),
        dir.path().join("report"),
    );
    // Noise-free data simulated and logged by `fly` at 50 Hz: its input convention (each sample held over the
    // step that ends at it) is declared by replaying at the record's own rate.
    let o = flightid(&[
        "diagnose",
        "--replay-rate-hz",
        "50",
        "--data",
        cut.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--model-out",
        model.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("skipped input_delay on rudder: the data have no column rudder_rad"),
        "{}",
        text(&o)
    );
    assert!(
        text(&o).contains("warning: no rudder_rad column"),
        "{}",
        text(&o)
    );
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(d["named_cause"].as_array().unwrap().len(), 0, "{d}");
    let from_reader = d["record_warnings"].as_array().unwrap();
    assert!(
        from_reader.iter().any(|w| w.as_str().is_some_and(
            |w| w.starts_with("training record: ") && w.contains("1 repeated row(s) dropped")
        )),
        "{from_reader:?}"
    );
    let skipped = d["skipped"].as_array().unwrap();
    for (effect, target) in [
        ("actuator_lag", "rudder"),
        ("control_effectiveness", "rudder"),
        ("sensor_bias", "beta_rad"),
    ] {
        assert!(
            skipped
                .iter()
                .any(|s| s["effect"] == effect && s["target"] == target),
            "{effect}/{target} not listed as skipped"
        );
    }
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(html.contains("<svg") && html.contains("Catalogue entries skipped"));
    assert!(model.join("c172x.xml").is_file() && model.join("extension.json").is_file());

    let o = flightid(&[
        "replay",
        "--model",
        model.to_str().unwrap(),
        "--data",
        cut.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let flown = dir.path().join("flown.csv");
    let o = flightid(&[
        "fly",
        "--model",
        model.to_str().unwrap(),
        "--duration-s",
        "2",
        "--out",
        flown.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
}
