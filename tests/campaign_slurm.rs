//! Campaigns as Slurm job arrays on a real cluster: `scripts/slurm-local.sh start` runs a single-node one here.
//!
//! The tests need `sbatch` on PATH and a reachable controller (`SLURM_CONF`, else the configuration the script
//! writes under `$TMPDIR/flightid-slurm`). Without one they say so loudly and pass, unless
//! `FLIGHTID_REQUIRE_SLURM` is set (`.ci/run` sets it once it has started the cluster): then they fail.
//! They run one at a time (one lock), so that one test's job does not wait behind another's on 2 CPUs.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;
use std::time::{Duration, Instant};

static CLUSTER: Mutex<()> = Mutex::new(());

/// The cluster's SLURM_CONF, or `None` (with a loud message) when there is no cluster and none is required.
fn cluster() -> Option<String> {
    let conf = std::env::var("SLURM_CONF").unwrap_or_else(|_| {
        let tmp = std::env::var("TMPDIR").unwrap_or_else(|_| "/tmp".into());
        format!("{tmp}/flightid-slurm/slurm.conf")
    });
    let up = Command::new("sinfo")
        .env("SLURM_CONF", &conf)
        .args(["-h", "-o", "%t"])
        .output()
        .is_ok_and(|o| o.status.success() && !o.stdout.is_empty());
    if up {
        return Some(conf);
    }
    if std::env::var_os("FLIGHTID_REQUIRE_SLURM").is_some() {
        panic!("FLIGHTID_REQUIRE_SLURM is set but no Slurm cluster answers (SLURM_CONF={conf})");
    }
    eprintln!(
        "\n!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n\
         !!! SKIPPED: no Slurm cluster (sinfo with SLURM_CONF={conf} failed).\n\
         !!! Start one with `scripts/slurm-local.sh start` (root, apt) to run the Slurm campaign tests.\n\
         !!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n"
    );
    None
}

fn flightid(conf: &str) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_flightid"));
    c.env("SLURM_CONF", conf);
    c
}

fn slurm(conf: &str, program: &str, args: &[&str]) -> Output {
    Command::new(program)
        .env("SLURM_CONF", conf)
        .args(args)
        .output()
        .unwrap()
}

fn case_files(dir: &Path) -> BTreeMap<String, String> {
    std::fs::read_dir(dir.join("cases"))
        .map(|entries| {
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
        })
        .unwrap_or_default()
}

fn local_run(conf: &str, spec: &Path, out: &Path) -> BTreeMap<String, String> {
    let o = flightid(conf)
        .args(["campaign", "run"])
        .arg(spec)
        .arg("--out")
        .arg(out)
        .args(["--jobs", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    case_files(out)
}

fn submit(conf: &str, spec: &Path, out: &Path, extra: &[&str]) -> Output {
    flightid(conf)
        .args(["campaign", "submit"])
        .arg(spec)
        .arg("--out")
        .arg(out)
        .arg("--slurm")
        .args(extra)
        .output()
        .unwrap()
}

fn manifest(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

#[test]
fn the_example_campaign_through_slurm_gives_the_local_runs_case_files_byte_for_byte() {
    let Some(conf) = cluster() else { return };
    let _one = CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let spec = manifest("campaigns/c172x_737.toml");
    let reference = local_run(&conf, &spec, &tmp.path().join("local"));
    assert_eq!(reference.len(), 36);

    let out = tmp.path().join("slurm");
    let o = submit(&conf, &spec, &out, &["--tasks", "3", "--wait"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let job_id = String::from_utf8_lossy(&o.stdout)
        .lines()
        .next()
        .unwrap_or("")
        .to_string();
    assert!(
        job_id.parse::<u64>().is_ok(),
        "the job id is printed first: {job_id:?}"
    );
    assert!(stderr.contains("36 case(s) in 3 array task(s)"), "{stderr}");
    // three shards of 12 cases: one task per configuration pair, each its own process
    for k in 0..3 {
        let log =
            std::fs::read_to_string(out.join(format!("slurm/task-{job_id}_{k}.log"))).unwrap();
        assert!(
            log.contains(&format!(
                "shard {k}/3: 12 cases, 0 already done, 12 run now"
            )),
            "{log}"
        );
    }
    assert_eq!(case_files(&out), reference);

    // status: the store and the job
    let st = flightid(&conf)
        .args(["campaign", "status"])
        .arg(&out)
        .arg("--json")
        .output()
        .unwrap();
    assert!(st.status.success());
    let v: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!(v["store"]["counts"]["done"], 36);
    assert_eq!(v["store"]["counts"]["pending"], 0);
    assert_eq!(v["slurm_jobs"][0]["job_id"], job_id.as_str());
    assert_eq!(v["slurm_jobs"][0]["state"], "COMPLETED 3");
    // report works as on a local run
    let rep = flightid(&conf)
        .args(["campaign", "report"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(rep.status.success());
    assert!(out.join("report/index.html").exists());
}

/// 16 cases of 30 s, a fresh process per case (~0.4 s a case): a few seconds per shard, so a task can be
/// cancelled while it runs.
const LONG: &str = r#"
name = "long"
rate_hz = 60.0
duration_s = 30.0
methods = ["ls"]
fresh_process_per_case = true
[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 }, { altitude_ft = 8000.0, speed_kts = 110.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0, 2.0, 3.0, 4.0]
[[maneuvers]]
surface = "aileron"
shape = "doublet"
amplitudes_deg = [1.0, 2.0, 3.0, 4.0]
"#;

#[test]
fn a_cancelled_array_task_loses_nothing_and_a_resubmission_finishes_the_campaign() {
    let Some(conf) = cluster() else { return };
    let _one = CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("long.toml");
    std::fs::write(&spec, LONG).unwrap();
    let out = tmp.path().join("slurm");
    let o = submit(&conf, &spec, &out, &["--tasks", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let job_id = String::from_utf8_lossy(&o.stdout).trim().to_string();
    // task 1's shard: the second half of the queue
    let queue_file = std::fs::read_dir(out.join("slurm"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("queue-")
        })
        .unwrap();
    let queue: Vec<String> = std::fs::read_to_string(&queue_file)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    assert_eq!(queue.len(), 16);
    let shard1: Vec<&String> = queue[8..].iter().collect();
    let done_in_shard1 = || {
        let files = case_files(&out);
        shard1
            .iter()
            .filter(|id| files.contains_key(&format!("{id}.json")))
            .count()
    };
    // cancel task 1 once it has finished its first case
    let t0 = Instant::now();
    while done_in_shard1() < 1 && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(10));
    }
    let task1 = format!("{job_id}_1");
    let c = slurm(&conf, "scancel", &[&task1]);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    let at_cancel = done_in_shard1();
    assert!(
        (1..8).contains(&at_cancel),
        "the cancel must land mid-shard: {at_cancel} of 8 done"
    );
    // the job ends (task 0 finishes its shard)
    let t0 = Instant::now();
    loop {
        let q = slurm(&conf, "squeue", &["-h", "-j", &job_id]);
        if q.stdout.is_empty() || t0.elapsed() > Duration::from_secs(180) {
            break;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    // nothing half-written: every result parses, and the cancelled case left no claim behind
    let files = case_files(&out);
    for (name, text) in &files {
        let v: serde_json::Value =
            serde_json::from_str(text).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(v["status"], "ok", "{name}");
    }
    let left = 16 - files.len();
    assert!(left >= 1, "the cancelled task left cases undone");
    let st = flightid(&conf)
        .args(["campaign", "status"])
        .arg(&out)
        .arg("--json")
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    assert_eq!(v["store"]["counts"]["pending"], left as u64);
    assert_eq!(v["store"]["running"], 0, "a cancelled task holds no claim");
    assert!(
        v["slurm_jobs"][0]["state"]
            .as_str()
            .unwrap()
            .contains("CANCELLED"),
        "{}",
        v["slurm_jobs"][0]
    );
    // no bridge of the cancelled task survives it
    let ps = Command::new("pgrep")
        .args(["-f", &out.to_string_lossy()])
        .output()
        .unwrap();
    assert!(
        ps.stdout.is_empty(),
        "processes left: {}",
        String::from_utf8_lossy(&ps.stdout)
    );

    // resubmitting queues exactly the missing cases and finishes the campaign
    let o = submit(&conf, &spec, &out, &["--wait"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{left} case(s) in 1 array task(s)")),
        "{stderr}"
    );
    let reference = local_run(&conf, &spec, &tmp.path().join("local"));
    assert_eq!(
        case_files(&out),
        reference,
        "byte-identical to an uninterrupted local run"
    );
}

#[test]
fn wait_exits_1_on_failed_cases_retry_failed_reruns_them_and_a_changed_spec_is_refused() {
    let Some(conf) = cluster() else { return };
    let _one = CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("mixed.toml");
    std::fs::write(
        &spec,
        r#"
name = "mixed"
duration_s = 6.0
methods = ["ls"]
[[configurations]]
name = "c172x"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 }, { altitude_ft = 4000.0, speed_kts = 15.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [2.0]
"#,
    )
    .unwrap();
    let out = tmp.path().join("slurm");
    let o = submit(&conf, &spec, &out, &["--tasks", "2", "--wait"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(1),
        "a failed case fails --wait: {stderr}"
    );
    assert!(
        stderr.contains("1 of 2 cases failed: c172x_4000ft_15kts_elevator_doublet_2deg"),
        "{stderr}"
    );
    let log = std::fs::read_dir(out.join("slurm"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with("_1.log"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .next()
        .unwrap();
    assert!(
        log.contains("1 of 1 cases failed"),
        "the task says so in its log: {log}"
    );

    // without --retry-failed nothing is left to run: the verdict stays 1
    let o = submit(&conf, &spec, &out, &["--wait"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nothing submitted"));
    // with it, the failed case runs again (and fails again: 15 kts is below the stall speed)
    let o = submit(&conf, &spec, &out, &["--wait", "--retry-failed"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("1 case(s) in 1 array task(s)"), "{stderr}");

    // a changed campaign into the same directory is refused before anything is submitted
    std::fs::write(
        &spec,
        std::fs::read_to_string(&spec)
            .unwrap()
            .replace("duration_s = 6.0", "duration_s = 8.0"),
    )
    .unwrap();
    let jobs_before = std::fs::read_to_string(out.join("slurm/jobs.txt")).unwrap();
    let o = submit(&conf, &spec, &out, &["--wait"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("c172x_4000ft_100kts_elevator_doublet_2deg")
            && stderr.contains("--rerun-changed"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("slurm/jobs.txt")).unwrap(),
        jobs_before
    );
    // fixed by going without the stall-speed condition and rerunning the changed case
    std::fs::write(
        &spec,
        std::fs::read_to_string(&spec)
            .unwrap()
            .replace(", { altitude_ft = 4000.0, speed_kts = 15.0 }", ""),
    )
    .unwrap();
    let o = submit(&conf, &spec, &out, &["--wait", "--rerun-changed"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(case_files(&out).len(), 1);
    let reference = local_run(&conf, &spec, &tmp.path().join("local"));
    assert_eq!(case_files(&out), reference);
}
