//! Campaigns on a Slurm cluster: one job array per submission, each array task running its shard of the queue of
//! pending cases into the same store on a shared file system (see [`super::store`] for the claim protocol).
//!
//! `submit` prepares the store (refusing changed results unless they are to be rerun; removing failed results to
//! be retried), lists the pending cases in campaign order in `DIR/slurm/queue-<stamp>.txt`, writes
//! `DIR/slurm/job-<stamp>.sbatch` and submits it with `sbatch --parsable`. Array task k of N runs
//! `flightid campaign worker DIR --queue FILE --shard k/N`: the k-th of N contiguous blocks of the queue (cases of
//! one configuration stay together, so a task starts its JSBSim process once per aircraft and trims each condition
//! once). Slurm's scheduling of the array is the load balance: with more tasks than CPUs, a CPU that finishes a
//! short shard takes the next task. The job ids go to `DIR/slurm/jobs.txt`, where `campaign status` finds them.

use super::spec::CampaignSpec;
use super::store::{self, StorePolicy};
use super::CampaignError;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Pending cases per array task when `--tasks` is not given.
pub const DEFAULT_CASES_PER_TASK: usize = 50;

/// How to submit.
#[derive(Debug, Clone, Default)]
pub struct SubmitOptions {
    /// Slurm partition (`--partition`); the cluster's default when `None`.
    pub partition: Option<String>,
    /// Array tasks; `None`: one per [`DEFAULT_CASES_PER_TASK`] pending cases.
    pub tasks: Option<usize>,
    /// Time limit per task (`--time`, Slurm's formats: `MM`, `HH:MM:SS`, `D-HH`...).
    pub time: Option<String>,
    /// Worker threads (and CPUs) per task.
    pub jobs_per_task: usize,
    /// The flightid binary the tasks run (must be reachable at this path on every node).
    pub binary: PathBuf,
    /// Changed and failed results: refuse, rerun or retry.
    pub policy: StorePolicy,
}

/// A submission.
#[derive(Debug, Clone, Serialize)]
pub struct Submitted {
    /// Slurm job id of the array; `None` when every case already had a result (nothing submitted).
    pub job_id: Option<String>,
    /// Array tasks.
    pub tasks: usize,
    /// Cases queued.
    pub queued: usize,
    /// The sbatch script.
    pub script: Option<PathBuf>,
    /// What was removed from the store first.
    pub prepared: store::Prepared,
}

/// `DIR/slurm`.
pub fn slurm_dir(out: &Path) -> PathBuf {
    out.join("slurm")
}

/// The k-th of n contiguous blocks of `ids` (sizes differ by at most one).
pub fn shard(ids: &[String], k: usize, n: usize) -> &[String] {
    let n = n.max(1);
    let k = k.min(n - 1);
    &ids[k * ids.len() / n..(k + 1) * ids.len() / n]
}

/// Parses `K/N` (0 <= K < N).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("shard '{s}' is not K/N"))?;
    let k: usize = k
        .trim()
        .parse()
        .map_err(|_| format!("shard '{s}': K is not a number"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("shard '{s}': N is not a number"))?;
    if n == 0 || k >= n {
        return Err(format!("shard '{s}': need 0 <= K < N"));
    }
    Ok((k, n))
}

/// Reads a queue file: one case id a line.
pub fn read_queue(path: &Path) -> Result<Vec<String>, CampaignError> {
    Ok(super::read_text(path)?
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect())
}

/// A shell word in single quotes.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The sbatch script of a job array of `tasks` tasks over `queue`.
pub fn sbatch_script(
    spec: &CampaignSpec,
    out: &Path,
    queue: &Path,
    tasks: usize,
    opts: &SubmitOptions,
) -> String {
    let jobs = opts.jobs_per_task.max(1);
    let name: String = spec
        .name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut s = String::from("#!/bin/bash\n");
    s += &format!("#SBATCH --job-name=flightid-{name}\n");
    s += &format!("#SBATCH --array=0-{}\n", tasks - 1);
    s += "#SBATCH --ntasks=1\n";
    s += &format!("#SBATCH --cpus-per-task={jobs}\n");
    s += &format!(
        "#SBATCH --output={}\n",
        slurm_dir(out).join("task-%A_%a.log").display()
    );
    if let Some(p) = &opts.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &opts.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s += "# Written by `flightid campaign submit`: array task K runs the K-th shard of the queue into the store.\n";
    s += &format!(
        "exec {} campaign worker {} --queue {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{tasks}\" --jobs {jobs}\n",
        quote(&opts.binary.to_string_lossy()),
        quote(&out.to_string_lossy()),
        quote(&queue.to_string_lossy()),
    );
    s
}

/// Runs a Slurm client command; its stdout, or an error with its stderr.
fn slurm_command(program: &str, args: &[&str]) -> Result<String, CampaignError> {
    let out = Command::new(program).args(args).output().map_err(|e| {
        CampaignError::Run(format!(
            "cannot run {program} ({e}): is Slurm installed and on PATH? \
             (scripts/slurm-local.sh start runs a single-node cluster)"
        ))
    })?;
    if !out.status.success() {
        return Err(CampaignError::Run(format!(
            "{program} {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).to_string())
}

/// Prepares the store, writes the queue and the sbatch script, and submits the job array.
pub fn submit(
    spec: &CampaignSpec,
    out: &Path,
    opts: &SubmitOptions,
) -> Result<Submitted, CampaignError> {
    std::fs::create_dir_all(out).map_err(CampaignError::io(out))?;
    // absolute paths: the tasks start in whatever directory Slurm gives them
    let out = &std::fs::canonicalize(out).map_err(CampaignError::io(out))?;
    let prepared = store::prepare(spec, out, opts.policy)?;
    let pending: Vec<String> = spec
        .cases()
        .into_iter()
        .filter(|c| !store::case_path(out, &c.id).exists())
        .map(|c| c.id)
        .collect();
    if pending.is_empty() {
        return Ok(Submitted {
            job_id: None,
            tasks: 0,
            queued: 0,
            script: None,
            prepared,
        });
    }
    let tasks = opts
        .tasks
        .unwrap_or_else(|| pending.len().div_ceil(DEFAULT_CASES_PER_TASK))
        .clamp(1, pending.len());
    let dir = slurm_dir(out);
    std::fs::create_dir_all(&dir).map_err(CampaignError::io(&dir))?;
    let stamp = format!(
        "{}-{}",
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_millis())
            .unwrap_or(0),
        std::process::id()
    );
    let queue = dir.join(format!("queue-{stamp}.txt"));
    crate::report::write_atomic(&queue, (pending.join("\n") + "\n").as_bytes())
        .map_err(|e| CampaignError::Run(e.to_string()))?;
    let script = dir.join(format!("job-{stamp}.sbatch"));
    crate::report::write_atomic(
        &script,
        sbatch_script(spec, out, &queue, tasks, opts).as_bytes(),
    )
    .map_err(|e| CampaignError::Run(e.to_string()))?;
    let reply = slurm_command("sbatch", &["--parsable", &script.to_string_lossy()])?;
    // `--parsable` prints `jobid` or `jobid;cluster`
    let job_id = reply.trim().split(';').next().unwrap_or("").to_string();
    if job_id.is_empty() {
        return Err(CampaignError::Run(format!(
            "sbatch printed no job id: '{}'",
            reply.trim()
        )));
    }
    let jobs_txt = dir.join("jobs.txt");
    let line = format!(
        "{job_id} tasks={tasks} cases={} queue={}\n",
        pending.len(),
        queue.display()
    );
    use std::io::Write;
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&jobs_txt)
        .and_then(|mut f| f.write_all(line.as_bytes()))
        .map_err(CampaignError::io(&jobs_txt))?;
    Ok(Submitted {
        job_id: Some(job_id),
        tasks,
        queued: pending.len(),
        script: Some(script),
        prepared,
    })
}

/// Job ids submitted into a store, oldest first.
pub fn submitted_jobs(out: &Path) -> Vec<String> {
    std::fs::read_to_string(slurm_dir(out).join("jobs.txt"))
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

/// The state of each array task of a job, as `(task id, state)`, from squeue while the job is known to the
/// controller, else `scontrol show job`, else sacct (when accounting is configured). `None`: Slurm knows nothing
/// of the job (any more).
pub fn job_tasks(job_id: &str) -> Option<Vec<(String, String)>> {
    if let Ok(text) = slurm_command("squeue", &["-h", "-r", "-j", job_id, "-o", "%i %T"]) {
        let tasks = pairs(&text);
        if !tasks.is_empty() {
            return Some(tasks);
        }
    }
    if let Ok(text) = slurm_command("scontrol", &["-o", "show", "job", job_id]) {
        let tasks: Vec<(String, String)> = text
            .lines()
            .filter_map(|l| {
                let field = |k: &str| {
                    l.split_whitespace()
                        .find_map(|w| w.strip_prefix(k).map(str::to_string))
                };
                let task = field("ArrayTaskId=").or_else(|| field("JobId="))?;
                Some((format!("{job_id}_{task}"), field("JobState=")?))
            })
            .collect();
        if !tasks.is_empty() {
            return Some(tasks);
        }
    }
    if let Ok(text) = slurm_command(
        "sacct",
        &["-n", "-X", "-P", "-j", job_id, "-o", "JobID,State"],
    ) {
        let tasks: Vec<(String, String)> = text
            .lines()
            .filter_map(|l| l.split_once('|'))
            .map(|(a, b)| {
                (
                    a.to_string(),
                    b.split_whitespace().next().unwrap_or("").to_string(),
                )
            })
            .collect();
        if !tasks.is_empty() {
            return Some(tasks);
        }
    }
    None
}

fn pairs(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter_map(|l| {
            let mut w = l.split_whitespace();
            Some((w.next()?.to_string(), w.next()?.to_string()))
        })
        .collect()
}

/// `RUNNING 2, PENDING 3` (states counted over tasks, in first-seen order).
pub fn summarize_states(tasks: &[(String, String)]) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for (_, s) in tasks {
        match counts.iter_mut().find(|(k, _)| k == s) {
            Some(e) => e.1 += 1,
            None => counts.push((s.clone(), 1)),
        }
    }
    counts
        .iter()
        .map(|(s, n)| format!("{s} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether a job still has tasks pending or running (squeue lists it).
pub fn job_active(job_id: &str) -> Result<bool, CampaignError> {
    let text = slurm_command("squeue", &["-h", "-r", "-j", job_id, "-o", "%i %T"])?;
    Ok(!pairs(&text).is_empty())
}

/// Follows a job until squeue no longer lists it, calling `tick` about once per `poll_s`.
pub fn wait(job_id: &str, poll_s: f64, mut tick: impl FnMut()) -> Result<(), CampaignError> {
    let mut failures = 0;
    loop {
        match job_active(job_id) {
            Ok(false) => return Ok(()),
            Ok(true) => failures = 0,
            // a controller busy for a moment is not the end of the job
            Err(e) => {
                failures += 1;
                if failures >= 10 {
                    return Err(e);
                }
            }
        }
        tick();
        std::thread::sleep(std::time::Duration::from_secs_f64(poll_s));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_the_queue_once_in_contiguous_blocks() {
        let ids: Vec<String> = (0..10).map(|i| i.to_string()).collect();
        for n in 1..=12 {
            let all: Vec<String> = (0..n).flat_map(|k| shard(&ids, k, n).to_vec()).collect();
            assert_eq!(all, ids, "n = {n}");
            let sizes: Vec<usize> = (0..n).map(|k| shard(&ids, k, n).len()).collect();
            let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            assert!(hi - lo <= 1, "{sizes:?}");
        }
        assert_eq!(parse_shard("2/5"), Ok((2, 5)));
        assert!(parse_shard("5/5").is_err());
        assert!(parse_shard("x").is_err());
    }

    #[test]
    fn the_sbatch_script_runs_one_shard_per_array_task_with_quoted_paths() {
        // the job name comes from the campaign's name, spaces and all
        let spec: CampaignSpec =
            toml::from_str(&store::tests::BASE.replace(r#"name = "t""#, r#"name = "demo run""#))
                .unwrap();
        let opts = SubmitOptions {
            partition: Some("short".into()),
            time: Some("00:10:00".into()),
            jobs_per_task: 1,
            binary: PathBuf::from("/opt/it's/flightid"),
            ..Default::default()
        };
        let s = sbatch_script(
            &spec,
            Path::new("/shared/out"),
            Path::new("/shared/out/slurm/q.txt"),
            4,
            &opts,
        );
        assert!(s.starts_with("#!/bin/bash\n"));
        for line in [
            "#SBATCH --job-name=flightid-demo_run",
            "#SBATCH --array=0-3",
            "#SBATCH --partition=short",
            "#SBATCH --time=00:10:00",
            "#SBATCH --output=/shared/out/slurm/task-%A_%a.log",
            "exec '/opt/it'\\''s/flightid' campaign worker '/shared/out' --queue '/shared/out/slurm/q.txt' \
             --shard \"${SLURM_ARRAY_TASK_ID}/4\" --jobs 1",
        ] {
            assert!(s.lines().any(|l| l == line), "missing {line}:\n{s}");
        }
    }
}
