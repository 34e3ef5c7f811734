//! `flightid campaign run|submit|worker|status|report`: scripted maneuver campaigns, on this machine or as a
//! Slurm job array.

use super::common::emit_json;
use crate::campaign::slurm::{self, SubmitOptions};
use crate::campaign::store::{self, StoreStatus};
use crate::campaign::{self, CampaignSpec, RunOptions, RunSummary, StorePolicy};
use crate::cli::UsageError;
use std::path::{Path, PathBuf};

/// Maneuver campaigns.
#[derive(clap::Args, Debug)]
pub struct CampaignCmd {
    #[command(subcommand)]
    pub action: CampaignAction,
}

/// What to do with results the campaign file does not explain.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PolicyArgs {
    /// Rerun cases whose definition changed since their result was made (rate, duration, maneuver, methods...)
    /// and delete results of cases no longer in the campaign; without it such a directory is refused (exit 2).
    #[arg(long)]
    rerun_changed: bool,
    /// Run the cases whose result is `failed` again.
    #[arg(long)]
    retry_failed: bool,
}

impl PolicyArgs {
    fn policy(self) -> StorePolicy {
        StorePolicy {
            rerun_changed: self.rerun_changed,
            retry_failed: self.retry_failed,
        }
    }
}

/// Campaign actions.
#[derive(clap::Subcommand, Debug)]
pub enum CampaignAction {
    /// Run every case of a campaign file that has no result in DIR/cases yet (so a re-run resumes). Exits 1 when
    /// any case failed.
    #[command(
        after_help = "Example:\n  flightid campaign run campaigns/c172x_737.toml --out out/campaign --jobs 2\n  \
                      flightid campaign run campaigns/c172x_737.toml --out out/campaign --retry-failed"
    )]
    Run {
        /// Campaign file (TOML).
        file: PathBuf,
        /// Output directory (results in DIR/cases/<case-id>.json).
        #[arg(long)]
        out: PathBuf,
        /// Worker threads, one JSBSim process each [default: number of CPUs].
        #[arg(long)]
        jobs: Option<usize>,
        #[command(flatten)]
        policy: PolicyArgs,
        /// Print the run summary as JSON (to stdout, or to the file given).
        #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
        json: Option<String>,
    },
    /// Submit the pending cases as a Slurm job array into DIR on a shared file system; prints the job id.
    #[command(after_help = "Example:\n  \
        flightid campaign submit campaigns/c172x_737.toml --out /shared/c172x_737 --slurm --tasks 8 --time 30\n  \
        flightid campaign status /shared/c172x_737\n\n\
        The tasks run this flightid binary by its absolute path: it must be reachable at that path on every node.")]
    Submit {
        /// Campaign file (TOML).
        file: PathBuf,
        /// Output directory, on a file system every node shares.
        #[arg(long)]
        out: PathBuf,
        /// Submit to Slurm (sbatch); the only scheduler supported.
        #[arg(long, required = true)]
        slurm: bool,
        /// Slurm partition [default: the cluster's default].
        #[arg(long)]
        partition: Option<String>,
        /// Array tasks, each running one contiguous shard of the pending cases [default: one per 50 cases].
        #[arg(long)]
        tasks: Option<usize>,
        /// Time limit per task, in Slurm's format (minutes, HH:MM:SS, D-HH...).
        #[arg(long)]
        time: Option<String>,
        /// Worker threads (CPUs) per task.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Follow the job to its end; exit 1 if any case failed or was left pending.
        #[arg(long)]
        wait: bool,
        #[command(flatten)]
        policy: PolicyArgs,
        /// Print the submission (and, with --wait, the final status) as JSON.
        #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
        json: Option<String>,
    },
    /// One array task of a submitted job: run shard K of N of a queue file into the store DIR.
    #[command(hide = true)]
    Worker {
        /// The store (holds campaign.toml).
        dir: PathBuf,
        /// Queue file: pending case ids, one a line.
        #[arg(long)]
        queue: PathBuf,
        /// K/N: this task's block of the queue.
        #[arg(long)]
        shard: String,
        /// Worker threads.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
    },
    /// Done / failed / pending cases in a campaign directory, and the state of its Slurm jobs.
    #[command(after_help = "Example:\n  flightid campaign status out/campaign --json")]
    Status {
        /// Campaign output directory.
        dir: PathBuf,
        /// Print the status as JSON (to stdout, or to the file given).
        #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
        json: Option<String>,
    },
    /// Summarise a campaign directory: modal parameters vs airspeed/altitude, failures per method.
    #[command(
        after_help = "Examples:\n  flightid campaign report out/campaign\n  flightid campaign report out/campaign --report out/campaign-report --json out/campaign.json\n  flightid campaign report out/campaign --json    # the summary as JSON on stdout"
    )]
    Report {
        /// Campaign output directory.
        dir: PathBuf,
        /// Report directory [default: DIR/report].
        #[arg(long)]
        report: Option<PathBuf>,
        /// Also write the summary as JSON (to stdout, or to the file given).
        #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
        json: Option<String>,
    },
}

/// Loads a campaign file (errors are usage errors).
pub fn load_spec(file: &Path) -> anyhow::Result<CampaignSpec> {
    Ok(CampaignSpec::load(file)?)
}

/// Exit 1 naming the failed cases, when there are any.
fn fail_on_failed(failed_ids: &[String], total: usize) -> anyhow::Result<()> {
    if failed_ids.is_empty() {
        return Ok(());
    }
    let mut names = failed_ids
        .iter()
        .take(10)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    if failed_ids.len() > 10 {
        names += &format!(" and {} more", failed_ids.len() - 10);
    }
    Err(anyhow::anyhow!(
        "{} of {total} cases failed: {names} (their errors are in the case files and `campaign report`; \
         --retry-failed runs them again)",
        failed_ids.len()
    ))
}

/// `, N what` for a positive count `n`, else nothing: a count the summaries mention only when it is not zero.
fn count_note(n: usize, what: &str) -> String {
    if n > 0 {
        format!(", {n} {what}")
    } else {
        String::new()
    }
}

fn print_run_summary(what: &str, s: &RunSummary, out: &Path) {
    let p = &s.prepared;
    if !p.rerun_changed.is_empty() || !p.retried.is_empty() || !p.removed.is_empty() {
        eprintln!(
            "{what}: rerunning {} changed and {} failed case(s); removed {} result(s) of cases no longer in the campaign",
            p.rerun_changed.len(),
            p.retried.len(),
            p.removed.len()
        );
    }
    eprintln!(
        "{what}: {} cases, {} already done, {} run now in {:.1} s{}, {} failed; results in {}",
        s.total,
        s.skipped,
        s.ran,
        s.elapsed_s,
        count_note(s.claimed_elsewhere, "run by another process"),
        s.failed,
        out.join("cases").display()
    );
}

fn default_jobs() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// Runs `flightid campaign`.
pub fn run(args: &CampaignCmd) -> anyhow::Result<()> {
    match &args.action {
        CampaignAction::Run {
            file,
            out,
            jobs,
            policy,
            json,
        } => {
            let spec = load_spec(file)?;
            let jobs = jobs.unwrap_or_else(default_jobs);
            if jobs == 0 {
                return Err(UsageError("--jobs must be at least 1".into()).into());
            }
            let summary = campaign::run_campaign(
                &spec,
                out,
                &RunOptions {
                    jobs,
                    progress: true,
                    policy: policy.policy(),
                    queue: None,
                },
            )?;
            match json {
                Some(t) => emit_json(t, &summary)?,
                None => print_run_summary(&format!("campaign '{}'", spec.name), &summary, out),
            }
            fail_on_failed(&summary.failed_ids, summary.total)
        }
        CampaignAction::Worker {
            dir,
            queue,
            shard,
            jobs,
        } => {
            let (k, n) = slurm::parse_shard(shard).map_err(UsageError)?;
            let spec = load_spec(&store::spec_path(dir))?;
            let ids = slurm::read_queue(queue)?;
            let mine = slurm::shard(&ids, k, n).to_vec();
            let summary = campaign::run_campaign(
                &spec,
                dir,
                &RunOptions {
                    jobs: (*jobs).max(1),
                    progress: false,
                    policy: StorePolicy::default(),
                    queue: Some(mine),
                },
            )?;
            print_run_summary(&format!("shard {k}/{n}"), &summary, dir);
            fail_on_failed(&summary.failed_ids, summary.total)
        }
        CampaignAction::Submit {
            file,
            out,
            slurm: _,
            partition,
            tasks,
            time,
            jobs,
            wait,
            policy,
            json,
        } => {
            let spec = load_spec(file)?;
            if *tasks == Some(0) || *jobs == 0 {
                return Err(UsageError("--tasks and --jobs must be at least 1".into()).into());
            }
            let opts = SubmitOptions {
                partition: partition.clone(),
                tasks: *tasks,
                time: time.clone(),
                jobs_per_task: *jobs,
                binary: std::env::current_exe()?,
                policy: policy.policy(),
            };
            let submitted = slurm::submit(&spec, out, &opts)?;
            let Some(job_id) = submitted.job_id.clone() else {
                eprintln!(
                    "campaign '{}': every case already has a result in {}; nothing submitted",
                    spec.name,
                    out.display()
                );
                if json.is_some() {
                    emit_json(json.as_deref().unwrap_or("-"), &submitted)?;
                }
                return finish_status(out, None);
            };
            if json.is_none() || *wait {
                println!("{job_id}");
            }
            eprintln!(
                "campaign '{}': {} case(s) in {} array task(s), job {job_id} (script {})",
                spec.name,
                submitted.queued,
                submitted.tasks,
                submitted
                    .script
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            );
            if !*wait {
                if let Some(t) = json {
                    emit_json(t, &submitted)?;
                }
                return Ok(());
            }
            let bar = progress_bar(out);
            slurm::wait(&job_id, 1.0, || {
                if let Ok(s) = store::status(out) {
                    bar.set_length(s.total as u64);
                    bar.set_position((s.counts.done + s.counts.failed) as u64);
                }
            })?;
            bar.finish_and_clear();
            if let Some(t) = json {
                emit_json(t, &store::status(out)?)?;
            }
            finish_status(out, Some(&job_id))
        }
        CampaignAction::Status { dir, json } => {
            let status = store::status(dir)?;
            let jobs: Vec<JobStatus> = slurm::submitted_jobs(dir)
                .into_iter()
                .map(|id| {
                    let tasks = slurm::job_tasks(&id);
                    JobStatus {
                        state: tasks
                            .as_deref()
                            .map(slurm::summarize_states)
                            .unwrap_or_else(|| "unknown to Slurm (now)".into()),
                        job_id: id,
                        tasks: tasks.unwrap_or_default(),
                    }
                })
                .collect();
            match json {
                Some(t) => emit_json(
                    t,
                    &serde_json::json!({ "store": status, "slurm_jobs": jobs }),
                )?,
                None => {
                    print_status(dir, &status);
                    for j in &jobs {
                        println!("slurm job {}: {}", j.job_id, j.state);
                    }
                }
            }
            Ok(())
        }
        CampaignAction::Report { dir, report, json } => {
            let target = report.clone().unwrap_or_else(|| dir.join("report"));
            super::common::check_outputs(&[super::common::json_path(json)], &[Some(&target)])?;
            let (rep, value) = campaign::campaign_report(dir)?;
            let index = crate::report::write_report_dir(&target, &rep, &value)?;
            if let Some(t) = json {
                emit_json(t, &value)?;
            }
            if json.as_deref() != Some("-") {
                println!("report: {}", index.display());
            }
            Ok(())
        }
    }
}

/// A Slurm job of a store, for `campaign status`.
#[derive(serde::Serialize)]
struct JobStatus {
    job_id: String,
    /// States counted over array tasks.
    state: String,
    /// (task, state) per array task.
    tasks: Vec<(String, String)>,
}

fn progress_bar(out: &Path) -> indicatif::ProgressBar {
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return indicatif::ProgressBar::hidden();
    }
    let total = store::status(out).map(|s| s.total).unwrap_or(0);
    let b = indicatif::ProgressBar::new(total as u64);
    b.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} cases  {elapsed} elapsed")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    b
}

fn print_status(dir: &Path, s: &StoreStatus) {
    let c = &s.counts;
    println!(
        "campaign '{}' in {}: {} cases: {} done, {} failed, {} pending ({} running now){}",
        s.campaign,
        dir.display(),
        s.total,
        c.done,
        c.failed,
        c.pending,
        s.running,
        count_note(c.changed, "changed (rerun with --rerun-changed)")
    );
    for (id, e) in &s.errors {
        println!("failed {id}: {e}");
    }
}

/// After a job (or when nothing was left to submit): the store's verdict; exit 1 when a case failed or is still
/// pending.
fn finish_status(out: &Path, job_id: Option<&str>) -> anyhow::Result<()> {
    let s = store::status(out)?;
    print_status(out, &s);
    if let Some(id) = job_id {
        if let Some(tasks) = slurm::job_tasks(id) {
            println!("slurm job {id}: {}", slurm::summarize_states(&tasks));
        }
    }
    fail_on_failed(&s.failed_ids, s.total)?;
    if s.counts.pending + s.counts.changed > 0 {
        return Err(anyhow::anyhow!(
            "{} of {} cases have no result (a task was cancelled, hit its time limit or died); submit again to \
             run them",
            s.counts.pending + s.counts.changed,
            s.total
        ));
    }
    Ok(())
}
