//! `flightid regress`: identified modal parameters of a campaign vs a stored baseline.

use super::campaign::load_spec;
use crate::campaign::{self, Baseline, RunOptions};
use crate::cli::UsageError;
use std::path::PathBuf;

/// Re-runs a campaign (or reads its results with --results) and compares the identified modal parameters
/// and control-derivative proxies per aircraft configuration with a baseline. Prints what moved; exits 1 when
/// any quantity is out of tolerance. --update writes the baseline instead.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid regress --campaign campaigns/c172x_737.toml --baseline aircraft/baselines/c172x.toml\n  flightid regress --campaign campaigns/c172x_737.toml --baseline aircraft/baselines/737.toml --configuration 737 --update"
)]
pub struct RegressCmd {
    /// Campaign file (TOML).
    #[arg(long)]
    pub campaign: PathBuf,
    /// Baseline file (TOML).
    #[arg(long)]
    pub baseline: PathBuf,
    /// Read results from this campaign directory instead of re-running (missing cases are run into it).
    #[arg(long)]
    pub results: Option<PathBuf>,
    /// Write the baseline from the current results instead of checking.
    #[arg(long)]
    pub update: bool,
    /// With --update: configurations to store [default: those in the existing baseline, else all].
    #[arg(long)]
    pub configuration: Vec<String>,
    /// Worker threads.
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Print every compared quantity, not only those that moved.
    #[arg(long)]
    pub verbose: bool,
}

/// Runs `flightid regress`.
pub fn run(args: &RegressCmd) -> anyhow::Result<()> {
    let spec = load_spec(&args.campaign)?;
    let tmp;
    let dir = match &args.results {
        Some(d) => d.clone(),
        None => {
            tmp = tempdir()?;
            tmp.clone()
        }
    };
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let summary = campaign::run_campaign(
        &spec,
        &dir,
        &RunOptions {
            jobs: jobs.max(1),
            progress: true,
            ..Default::default()
        },
    );
    let results = summary.and_then(|_| campaign::load_results(&dir));
    if args.results.is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let results = results?;
    let known: Vec<String> = spec.configurations.iter().map(|c| c.name.clone()).collect();
    if args.update {
        let configs = if !args.configuration.is_empty() {
            args.configuration.clone()
        } else if args.baseline.exists() {
            Baseline::load(&args.baseline)?.configurations
        } else {
            known.clone()
        };
        if let Some(c) = configs.iter().find(|c| !known.contains(c)) {
            return Err(UsageError(format!(
                "configuration '{c}' is not in {} (it has: {})",
                args.campaign.display(),
                known.join(", ")
            ))
            .into());
        }
        let b = Baseline::from_results(&spec.name, &configs, &results);
        b.save(&args.baseline)?;
        println!(
            "wrote {} ({} quantities for {})",
            args.baseline.display(),
            b.quantities.len(),
            configs.join(", ")
        );
        return Ok(());
    }
    let baseline = Baseline::load(&args.baseline)?;
    if let Some(c) = baseline.configurations.iter().find(|c| !known.contains(c)) {
        return Err(UsageError(format!(
            "baseline {} covers configuration '{c}', which {} does not have",
            args.baseline.display(),
            args.campaign.display()
        ))
        .into());
    }
    let deviations = campaign::compare_baseline(&baseline, &results);
    let moved: Vec<_> = deviations.iter().filter(|d| !d.ok).collect();
    println!(
        "{:<10} {:<70} {:>13} {:>13} {:>11} {:>9}",
        "config", "quantity", "baseline", "current", "allowed ±", "status"
    );
    for d in &deviations {
        if d.ok && !args.verbose {
            continue;
        }
        println!(
            "{:<10} {:<70} {:>13.6} {:>13} {:>11.3e} {:>9}",
            d.configuration,
            d.key,
            d.baseline,
            d.current
                .map(|v| format!("{v:.6}"))
                .unwrap_or_else(|| "missing".into()),
            d.allowed,
            if d.ok { "ok" } else { "MOVED" }
        );
    }
    println!(
        "{} of {} quantities within tolerance ({})",
        deviations.len() - moved.len(),
        deviations.len(),
        baseline.configurations.join(", ")
    );
    if moved.is_empty() {
        Ok(())
    } else {
        anyhow::bail!(
            "{} quantities out of tolerance, first: {} {}",
            moved.len(),
            moved[0].configuration,
            moved[0].key
        )
    }
}

fn tempdir() -> anyhow::Result<PathBuf> {
    let d = std::env::temp_dir().join(format!("flightid-regress-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d); // a leftover of an earlier process with the same id
    std::fs::create_dir_all(&d)?;
    Ok(d)
}
