//! Bad input and faults through the real binary: each class exits 2 (bad input) or 1 (failure) with a message
//! that says what and what is allowed, no user file is ever lost, and no JSBSim scratch directory is left after
//! SIGINT, SIGTERM or a killed bridge. Every child runs with its own TMPDIR, so leftovers are counted exactly.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn flightid(tmp: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flightid"));
    c.env("TMPDIR", tmp).current_dir(tmp);
    c
}

fn run(tmp: &Path, args: &[&str]) -> Output {
    flightid(tmp).args(args).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Asserts exit 2 and that stderr holds every `needle`, once for the first.
fn assert_bad_input(o: &Output, needles: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    for n in needles {
        assert!(e.contains(n), "'{n}' not in: {e}");
    }
    assert_eq!(e.matches(needles[0]).count(), 1, "reason printed once: {e}");
}

fn scratch_dirs(tmp: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(tmp)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("flightid-jsbsim-"))
        })
        .collect()
}

#[test]
fn a_report_never_replaces_a_directory_flightid_did_not_make() {
    let tmp = tempfile::tempdir().unwrap();
    let victim = tmp.path().join("victim");
    std::fs::create_dir_all(victim.join("sub")).unwrap();
    std::fs::write(victim.join("important.txt"), "keep").unwrap();
    std::fs::write(victim.join("report.json"), "{}").unwrap(); // looks like a report, is not flightid's
    let t0 = Instant::now();
    for args in [
        vec!["demo", "--report", "victim"],
        vec!["compare", "--report", "victim"],
        vec!["paper", "--report", "victim"],
        vec!["derivatives", "--report", "victim"],
        vec!["campaign", "report", "nowhere", "--report", "victim"],
    ] {
        let o = run(tmp.path(), &args);
        assert_bad_input(&o, &["refusing to write victim", "not made by flightid"]);
    }
    // refused before any work: five commands, no JSBSim started
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    assert!(victim.join("important.txt").exists() && victim.join("sub").is_dir());
    // `.` is refused up front, once
    let o = run(tmp.path(), &["demo", "--report", "."]);
    assert_bad_input(&o, &["refusing to write .", "no directory of its own"]);
    assert!(victim.join("important.txt").exists());
}

#[test]
fn an_output_path_that_cannot_be_written_is_refused_before_any_work_and_no_other_output_is_left() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("afile"), "x").unwrap(); // a regular file used as if it were a directory
    let tlog = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/flight.tlog");
    let t0 = Instant::now();
    for args in [
        vec![
            "diagnose",
            "--data",
            "train.csv",
            "--json",
            "d.json",
            "--report",
            "drep",
            "--extension-out",
            "afile/x.json",
        ],
        vec!["diagnose", "--data", "train.csv", "--json", "afile/x.json"],
        vec![
            "compare",
            "--sweep-deg",
            "1",
            "--method",
            "ls",
            "--json",
            "afile/x.json",
            "--report",
            "crep",
        ],
        vec!["fly", "--duration-s", "2", "--out", "afile/x.csv"],
        vec![
            "ingest",
            "--tlog",
            tlog.to_str().unwrap(),
            "--out",
            "afile/x.csv",
        ],
    ] {
        let o = run(tmp.path(), &args);
        assert_bad_input(
            &o,
            &[
                "afile, which is not a directory",
                "refusing to write afile/x.",
            ],
        );
    }
    // refused before any data is read or JSBSim started, and nothing else written
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    for left in ["d.json", "drep", "crep"] {
        assert!(!tmp.path().join(left).exists(), "{left} left behind");
    }
}

#[test]
fn out_of_range_numbers_exit_2_naming_the_allowed_range() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("x.csv");
    std::fs::write(&csv, "time_s,q_rad_s\n0,0\n0.01,0\n0.02,0\n").unwrap();
    for (args, needles) in [
        (
            vec!["fly", "--duration-s", "1e9", "--out", "o.csv"],
            vec!["--duration-s", "[0.01, 36000] s"],
        ),
        (
            vec![
                "fly",
                "--start-s",
                "1e308",
                "--duration-s",
                "inf",
                "--out",
                "o.csv",
            ],
            vec!["--start-s", "[0, 36000] s"],
        ),
        (
            vec!["fly", "--pulse-s", "0", "--out", "o.csv"],
            vec!["--pulse-s", "[0.005, 600] s"],
        ),
        (
            vec![
                "fly",
                "--pulse-s",
                "0.01",
                "--rate-hz",
                "60",
                "--out",
                "o.csv",
            ],
            vec!["shorter than two samples"],
        ),
        (
            vec![
                "fly",
                "--duration-s",
                "30000",
                "--rate-hz",
                "2000",
                "--out",
                "o.csv",
            ],
            vec!["exceed the limit of 1000000"],
        ),
        (
            vec!["segments", "x.csv", "--resample-hz", "1e9"],
            vec!["--resample-hz", "[0.1, 2000] Hz"],
        ),
        (
            vec![
                "identify",
                "--data",
                "x.csv",
                "--input",
                "elevator",
                "--output",
                "q_rad_s",
                "--resample-hz",
                "1e9",
            ],
            vec!["--resample-hz"],
        ),
        (
            vec!["check", "x.csv", "--from-s", "30", "--to-s", "10"],
            vec!["--from-s (30) must be below --to-s (10)"],
        ),
        (vec!["trim", "--speed-kts", "nan"], vec!["--speed-kts"]),
    ] {
        let o = run(tmp.path(), &args);
        assert_bad_input(&o, &needles);
    }
    assert!(!tmp.path().join("o.csv").exists());
}

/// A record longer than the flight-path reconstruction's memory budget (250 000 samples, ~2 kB each) is refused
/// by `check` before the reconstruction starts, with the way out; a window of it within the budget is accepted
/// (it gets past the limit to the reconstruction, which then reports what the record lacks).
#[test]
fn check_refuses_a_record_beyond_the_reconstruction_budget_and_names_the_way_out() {
    use std::io::Write;
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("long.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&csv).unwrap());
    writeln!(f, "time_s,p_rad_s,q_rad_s,r_rad_s").unwrap();
    for k in 0..260_000 {
        writeln!(f, "{:.2},0,0,0", k as f64 * 0.01).unwrap();
    }
    f.flush().unwrap();
    drop(f);
    let o = run(tmp.path(), &["check", "long.csv"]);
    assert_bad_input(
        &o,
        &[
            "260000 samples exceed the limit of 250000 per flight-path reconstruction",
            "--from-s/--to-s",
            "--resample-hz",
        ],
    );
    let o = run(
        tmp.path(),
        &["check", "long.csv", "--from-s", "0", "--to-s", "60"],
    );
    assert!(
        !stderr(&o).contains("exceed the limit"),
        "a 60 s window is within the budget: {}",
        stderr(&o)
    );
}

#[test]
fn out_of_range_numbers_in_files_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let c172x =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("aircraft/c172x.toml"))
            .unwrap();
    // the elevator's limits swapped
    let swapped = c172x.replacen("min_rad = -", "min_rad = 9", 1);
    assert_ne!(swapped, c172x);
    std::fs::write(tmp.path().join("swapped.toml"), swapped).unwrap();
    let o = run(tmp.path(), &["trim", "--aircraft", "swapped.toml"]);
    assert_bad_input(&o, &["swapped.toml", "min_rad"]);
    let campaign = r#"
name = "huge"
rate_hz = 60.0
duration_s = 1e9
methods = ["ls"]
[[configurations]]
name = "c"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0]
"#;
    std::fs::write(tmp.path().join("huge.toml"), campaign).unwrap();
    let o = run(
        tmp.path(),
        &["campaign", "run", "huge.toml", "--out", "camp"],
    );
    assert_bad_input(&o, &["duration_s", "36000"]);
}

#[test]
fn a_message_of_several_lines_prints_real_line_breaks_not_backslash_n() {
    let tmp = tempfile::tempdir().unwrap();
    let tlog =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/flight.tlog"))
            .unwrap();
    std::fs::write(tmp.path().join("twice.tlog"), [tlog.clone(), tlog].concat()).unwrap();
    let o = run(
        tmp.path(),
        &[
            "ingest",
            "--tlog",
            "twice.tlog",
            "--servo-map",
            "c172x",
            "--out",
            "x.csv",
        ],
    );
    assert_bad_input(&o, &["2 stretches", "\n  1: 0.00 to 30.00 s"]);
    assert!(!stderr(&o).contains("\\n"), "{}", stderr(&o));
    std::fs::write(tmp.path().join("map.toml"), "[columns\nq_rad_s = ").unwrap();
    std::fs::write(tmp.path().join("x.csv"), "time_s,q_rad_s\n0,0\n").unwrap();
    let o = run(tmp.path(), &["segments", "--columns", "map.toml", "x.csv"]);
    assert_bad_input(&o, &["column map map.toml", "invalid table header\n"]);
    assert!(!stderr(&o).contains("\\n"), "{}", stderr(&o));
}

#[test]
fn option_and_extension_values_outside_their_range_are_refused_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(tmp.path().join(name), text).unwrap();
    write(
        "flat.csv",
        &level_record(
            "elevator_rad,q_rad_s,theta_rad,beta_rad,airspeed_m_s,altitude_m",
            "0,0,0,0,50,1200",
        ),
    );
    write(
        "ext_huge.json",
        r#"{"aircraft":"c172x","effects":[{"effect":"sensor_scale","target":"beta_rad","value":1e308,"std_error":0.1}],
            "model_effects":[],"notes":{}}"#,
    );
    for value in ["nan", "-1"] {
        let flag = format!("--min-amplitude-deg={value}");
        let o = run(tmp.path(), &["segments", "flat.csv", &flag]);
        assert_bad_input(&o, &["--min-amplitude-deg", "[0, 30] deg"]);
    }
    let t0 = Instant::now();
    let o = run(
        tmp.path(),
        &[
            "replay",
            "--data",
            "flat.csv",
            "--extension",
            "ext_huge.json",
            "--json",
            "r.json",
        ],
    );
    assert_bad_input(
        &o,
        &[
            "ext_huge.json",
            "sensor_scale on beta_rad: value 1e308",
            "outside the effect's range [",
        ],
    );
    assert!(
        t0.elapsed() < Duration::from_secs(5),
        "refused before JSBSim starts: {:?}",
        t0.elapsed()
    );
    assert!(!tmp.path().join("r.json").exists());
}

/// A 3 s, 50 Hz level record: enough to replay, nothing moving.
fn level_record(columns: &str, row: &str) -> String {
    let mut text = format!("time_s,{columns}\n");
    for k in 0..150 {
        text.push_str(&format!("{},{row}\n", k as f64 * 0.02));
    }
    text
}

#[test]
fn a_bad_record_or_file_is_named_with_its_role_and_the_reason_in_words() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(tmp.path().join(name), text).unwrap();
    let full = "elevator_rad,q_rad_s,theta_rad,airspeed_m_s,altitude_m";
    write("flat.csv", &level_record(full, "0,0,0,50,1200"));
    write(
        "tworow.csv",
        &format!("time_s,{full}\n0,0,0,0,50,1200\n0.02,0,0,0,50,1200\n"),
    );
    write("onerow.csv", &format!("time_s,{full}\n0,0,0,0,50,1200\n"));
    write(
        "noairspeed.csv",
        &level_record("elevator_rad,q_rad_s,altitude_m", "0,0,1200"),
    );
    write("semicolon.csv", "time_s;elevator_rad\n0;0\n0.02;0\n");
    write("lin_bad.json", r#"{"A": [[1,2],[3]]}"#);
    for (args, needles) in [
        (
            vec!["diagnose", "--data", "tworow.csv"],
            vec!["tworow.csv (the training record)", "2 samples"],
        ),
        (
            vec!["diagnose", "--data", "flat.csv", "--validate", "tworow.csv"],
            vec!["tworow.csv (the validation record)", "2 samples"],
        ),
        (
            vec!["derivatives", "--data", "tworow.csv", "--airframe", "c172x"],
            vec!["tworow.csv: the record is 2 samples, 0.02 s long; at least 2 s is needed"],
        ),
        (
            vec!["derivatives", "--data", "onerow.csv", "--airframe", "c172x"],
            vec!["onerow.csv: the record is 1 sample, 0 s long; at least 2 s is needed"],
        ),
        (
            vec!["diagnose", "--linear", "lin_bad.json", "--data", "flat.csv"],
            vec!["linear-model file lin_bad.json"],
        ),
        (
            vec!["diagnose", "--data", "noairspeed.csv"],
            vec![
                "noairspeed.csv (the training record)",
                "is required because replay trims",
            ],
        ),
        (
            vec!["segments", "semicolon.csv"],
            vec![
                "separate its columns with `;`",
                "flightid reads comma-separated files",
            ],
        ),
    ] {
        let o = run(tmp.path(), &args);
        assert_bad_input(&o, &needles);
        assert!(!stderr(&o).contains("dropout"), "{}", stderr(&o));
    }
}

#[test]
fn control_characters_in_user_data_are_escaped_in_messages() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("esc.csv"),
        "time_s,\u{1b}[31mred\u{1b}[0m,\u{1b}[31mred\u{1b}[0m\n0,1,2\n",
    )
    .unwrap();
    let o = run(tmp.path(), &["check", "esc.csv"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        !e.contains('\u{1b}'),
        "raw escape reached the terminal: {e:?}"
    );
    assert!(e.contains("\\u{1b}[31mred"), "{e}");
}

/// Starts a long `fly` (about a minute of JSBSim work) and waits until its bridge works in its scratch directory.
fn long_fly(tmp: &Path) -> Child {
    let child = flightid(tmp)
        .args([
            "fly",
            "--duration-s",
            "20000",
            "--rate-hz",
            "40",
            "--sim-rate-hz",
            "40",
            "--out",
            "long.csv",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while scratch_dirs(tmp).is_empty() || bridge_of(child.id()).is_none() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the bridge never started"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(1500)); // into `load`/`trim`/`fly`
    child
}

/// The pid of a child process of `pid` (the bridge), from /proc.
fn bridge_of(pid: u32) -> Option<u32> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).ok()?;
    text.split_whitespace().next()?.parse().ok()
}

fn signal(pid: u32, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

#[test]
fn no_scratch_directory_is_left_after_sigint_sigterm_or_a_killed_bridge() {
    for (sig, code) in [("-INT", 130), ("-TERM", 143)] {
        let tmp = tempfile::tempdir().unwrap();
        let mut child = long_fly(tmp.path());
        let bridge = bridge_of(child.id()).unwrap();
        signal(child.id(), sig);
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{sig}");
        assert!(
            scratch_dirs(tmp.path()).is_empty(),
            "{sig}: {:?}",
            scratch_dirs(tmp.path())
        );
        assert!(
            !Path::new(&format!("/proc/{bridge}/cmdline")).exists() || {
                std::thread::sleep(Duration::from_millis(200));
                !Path::new(&format!("/proc/{bridge}/cmdline")).exists()
            },
            "{sig}: the bridge outlived flightid"
        );
        assert!(!tmp.path().join("long.csv").exists());
    }
    // the bridge killed under flightid: a crash (exit 1) named as such, and the directory removed
    let tmp = tempfile::tempdir().unwrap();
    let child = long_fly(tmp.path());
    signal(bridge_of(child.id()).unwrap(), "-KILL");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("bridge process died"),
        "{}",
        stderr(&out)
    );
    assert!(scratch_dirs(tmp.path()).is_empty());
    // flightid itself killed: its directory stays, and the next start removes it (its pid is gone)
    let mut child = long_fly(tmp.path());
    signal(child.id(), "-KILL");
    child.wait().unwrap();
    assert_eq!(scratch_dirs(tmp.path()).len(), 1);
    let o = run(
        tmp.path(),
        &["fly", "--duration-s", "2", "--out", "short.csv"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        scratch_dirs(tmp.path()).is_empty(),
        "{:?}",
        scratch_dirs(tmp.path())
    );
}

/// A stuck or unplugged gyro is named by every command that reads the record, through the one warning path
/// (`FlightRecord::warnings`): case 1 of the independent generator `scripts/gen_diagnose_records.py` (seed 4,
/// JSBSim's c172x, 75 s of elevator, aileron and rudder maneuvers) with `q_rad_s` written as 0.0 on every row.
/// The record as generated draws no warning at all.
#[test]
fn a_stuck_gyro_is_named_by_every_command_and_a_working_one_is_not() {
    let tmp = tempfile::tempdir().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_diagnose_records.py");
    let out = Command::new(flightid::sim::env::python().expect("provisioned Python"))
        .arg(script)
        .args([
            "--cases",
            "1",
            "--first",
            "1",
            "--seed",
            "4",
            "--stratified",
            "--out",
        ])
        .arg(tmp.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let good = tmp.path().join("case_001_train.csv");
    let mut rec = flightid::data::read_csv(&good).unwrap();
    let n = rec.len();
    rec.push_column("q_rad_s", vec![0.0; n]);
    flightid::data::write_csv_atomic(&tmp.path().join("stuck.csv"), &rec).unwrap();
    for file in ["case_001_train.csv", "stuck.csv"] {
        for args in [
            vec!["segments", file],
            vec!["check", file],
            vec![
                "identify",
                "--data",
                file,
                "--input",
                "elevator",
                "--output",
                "theta_rad",
            ],
            vec![
                "estimate",
                "--data",
                file,
                "--method",
                "n4sid",
                "--inputs",
                "elevator_rad",
                "--outputs",
                "alpha_rad,theta_rad",
                "--order",
                "2",
            ],
        ] {
            let o = run(tmp.path(), &args);
            let e = stderr(&o);
            assert!(o.status.success(), "{args:?}: {e}");
            let warnings: Vec<&str> = e.lines().filter(|l| l.starts_with("warning:")).collect();
            if file == "stuck.csv" {
                let want = format!(
                    "warning: stuck.csv: column `q_rad_s`: 0 on every one of its {n} rows (74.975 s): a stuck or \
                     unplugged sensor"
                );
                assert_eq!(warnings.len(), 1, "{args:?}: {e}");
                assert!(warnings[0].starts_with(&want), "{args:?}: {e}");
            } else {
                assert!(warnings.is_empty(), "{args:?}: {e}");
            }
        }
    }
}

/// A loading the model cannot take, a `--property` without a value or naming a property the aircraft does not
/// have, exits 2 naming the setting, leaves no output and no scratch directory.
#[test]
fn a_loading_the_model_cannot_take_is_refused_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let columns = "elevator_rad,q_rad_s,theta_rad,beta_rad,airspeed_m_s,altitude_m";
    let record = level_record(columns, "0,0,0,0,50,1200");
    std::fs::write(tmp.path().join("flat.csv"), record).unwrap();
    let diagnose = |setting: &str| {
        let args = [
            "diagnose",
            "--data",
            "flat.csv",
            "--json",
            "d.json",
            "--property",
            setting,
        ];
        run(tmp.path(), &args)
    };
    let o = diagnose("propulsion/tank[0]/contents-lbs");
    assert_bad_input(
        &o,
        &["expected NAME=VALUE", "propulsion/tank[0]/contents-lbs"],
    );
    let o = diagnose("propulsion/tank[9]/contents-lbs=30");
    assert_bad_input(&o, &["has no property", "propulsion/tank[9]/contents-lbs"]);
    assert!(!tmp.path().join("d.json").exists());
    assert!(scratch_dirs(tmp.path()).is_empty());
    let o = run(
        tmp.path(),
        &["trim", "--property", "inertia/pointmass-weight-lbs[0]=nan"],
    );
    assert_bad_input(
        &o,
        &["not a finite number", "inertia/pointmass-weight-lbs[0]"],
    );
}
