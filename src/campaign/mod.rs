//! Campaigns: TOML files of aircraft configurations × conditions × maneuvers × methods × noise, parallel
//! execution over a pool of JSBSim processes with resumable per-case results, summary reports, and
//! regression baselines of identified modal parameters per aircraft configuration.

pub mod baseline;
pub mod result;
pub mod run;
pub mod slurm;
pub mod spec;
pub mod store;
pub mod summary;

pub use baseline::{compare_baseline, quantities, Baseline, BaselineEntry, Deviation};
pub use result::{CaseResult, Identification};
pub use run::{run_campaign, run_case, RunOptions, RunSummary};
pub use spec::{CampaignSpec, CaseSpec};
pub use store::{load_results, StorePolicy};
pub use summary::campaign_report;

use std::path::{Path, PathBuf};

/// Campaign failures, with the file they concern.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// File system.
    #[error("{path}: {source}")]
    Io {
        /// File or directory.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// Malformed TOML or JSON.
    #[error("{path}: malformed file: {message}")]
    Parse {
        /// File.
        path: PathBuf,
        /// Parser message (with line and column).
        message: String,
    },
    /// Well-formed but meaningless content (unknown aircraft, maneuver, method...).
    #[error("{path}: {message}")]
    Invalid {
        /// File.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The run itself failed (cannot write results...).
    #[error("campaign run: {0}")]
    Run(String),
}

impl CampaignError {
    /// For `map_err`: a file-system failure on `path`.
    fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CampaignError + '_ {
        move |source| CampaignError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Reads a campaign file (spec, baseline, queue, case result) as text.
fn read_text(path: &Path) -> Result<String, CampaignError> {
    std::fs::read_to_string(path).map_err(CampaignError::io(path))
}

/// Reads a TOML campaign file (spec, baseline) into `T`.
fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CampaignError> {
    toml::from_str(&read_text(path)?).map_err(|e| CampaignError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}
