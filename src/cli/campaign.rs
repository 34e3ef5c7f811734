//! `flightid campaign run|report`: scripted maneuver campaigns.

use super::common::emit_json;
use crate::campaign::{self, CampaignError, CampaignSpec, RunOptions};
use crate::cli::UsageError;
use std::path::{Path, PathBuf};

/// Maneuver campaigns.
#[derive(clap::Args, Debug)]
pub struct CampaignCmd {
    #[command(subcommand)]
    pub action: CampaignAction,
}

/// Campaign actions.
#[derive(clap::Subcommand, Debug)]
pub enum CampaignAction {
    /// Run every case of a campaign file that has no result in DIR/cases yet (so a re-run resumes).
    #[command(
        after_help = "Example:\n  flightid campaign run campaigns/c172x_737.toml --out out/campaign --jobs 2"
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
        /// Print the run summary as JSON (to stdout, or to the file given).
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

/// Campaign errors caused by the user's files are usage errors (exit 2).
pub fn classify(e: CampaignError) -> anyhow::Error {
    match e {
        CampaignError::Parse { .. } | CampaignError::Invalid { .. } => {
            anyhow::Error::new(UsageError(e.to_string()))
        }
        CampaignError::Io { ref path, .. } if !path.exists() => {
            anyhow::Error::new(UsageError(e.to_string()))
        }
        other => anyhow::Error::new(other),
    }
}

/// Loads a campaign file (errors are usage errors).
pub fn load_spec(file: &Path) -> anyhow::Result<CampaignSpec> {
    CampaignSpec::load(file).map_err(classify)
}

/// Runs `flightid campaign`.
pub fn run(args: &CampaignCmd) -> anyhow::Result<()> {
    match &args.action {
        CampaignAction::Run {
            file,
            out,
            jobs,
            json,
        } => {
            let spec = load_spec(file)?;
            let jobs = jobs.unwrap_or_else(|| {
                std::thread::available_parallelism()
                    .map(|n| n.get())
                    .unwrap_or(1)
            });
            if jobs == 0 {
                return Err(UsageError("--jobs must be at least 1".into()).into());
            }
            let summary = campaign::run_campaign(
                &spec,
                out,
                &RunOptions {
                    jobs,
                    progress: true,
                },
            )
            .map_err(classify)?;
            match json {
                Some(t) => emit_json(t, &summary)?,
                None => eprintln!(
                    "campaign '{}': {} cases, {} already done, {} run now in {:.1} s, {} failed; results in {}",
                    spec.name,
                    summary.total,
                    summary.skipped,
                    summary.ran,
                    summary.elapsed_s,
                    summary.failed,
                    out.join("cases").display()
                ),
            }
            Ok(())
        }
        CampaignAction::Report { dir, report, json } => {
            let (rep, value) = campaign::campaign_report(dir).map_err(classify)?;
            let target = report.clone().unwrap_or_else(|| dir.join("report"));
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
