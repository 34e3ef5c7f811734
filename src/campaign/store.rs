//! The campaign store: one directory that any number of processes, on one machine or on the nodes of a cluster
//! sharing a file system, fill with results at the same time.
//!
//! ```text
//! DIR/campaign.toml        the campaign as last run or submitted (the reference for `status` and the workers)
//! DIR/cases/<id>.json      one result per case, written to a temporary file and renamed into place (atomic)
//! DIR/claims/<id>.lock     the claim of a case: an exclusive flock(2) held while the case runs
//! DIR/slurm/               sbatch scripts, queues and task logs of `campaign submit --slurm`
//! ```
//!
//! **Claims.** A process runs a case only while it holds an exclusive, non-blocking `flock` on the case's lock
//! file, and looks again for the case's result after taking it: of any number of processes offered the same case,
//! exactly one runs it, and none runs a case another already finished. The kernel (or the NFS lock manager) drops
//! the lock when its holder dies, `kill -9` and `scancel` included, so a claim never outlives its process and a
//! killed run leaves nothing to clean up: its finished cases are complete files, its unfinished ones have no file.
//! The file system must honour flock across its clients (local file systems; NFSv3/v4, where Linux maps flock to
//! byte-range locks; Lustre mounted with `-o flock`; GPFS; BeeGFS).
//!
//! **Definition hashes.** Every result carries the SHA-256 of its case's definition: the case (configuration,
//! aircraft, coefficient factors, pre-trim properties, flight condition, surface, maneuver, amplitude) and the
//! campaign settings that shape its record and identifications (rate, duration, maneuver start, methods, the
//! noise level and seed of every identification), as compact JSON. A campaign file changed under an existing
//! store is refused, naming the cases whose results would no longer match it, unless they are to be rerun.
//! (The aircraft files and the flightid version are not part of the hash.)

use super::result::CaseResult;
use super::spec::{CampaignSpec, CaseSpec};
use super::CampaignError;
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

/// `DIR/cases/<id>.json`.
pub fn case_path(out: &Path, id: &str) -> PathBuf {
    out.join("cases").join(format!("{id}.json"))
}

/// `DIR/claims/<id>.lock`.
pub fn claim_path(out: &Path, id: &str) -> PathBuf {
    out.join("claims").join(format!("{id}.lock"))
}

/// `DIR/campaign.toml`.
pub fn spec_path(out: &Path) -> PathBuf {
    out.join("campaign.toml")
}

/// What the definition hash covers (serialised as compact JSON, then hashed).
#[derive(Serialize)]
struct Definition<'a> {
    case: &'a CaseSpec,
    rate_hz: f64,
    duration_s: f64,
    start_s: f64,
    methods: &'a [String],
    /// (output noise deg, seed) of each identification, in the order run_case applies them.
    noise_seeds: Vec<(f64, u64)>,
}

/// The (noise level, seed) pairs a case's record is identified at: every seed for a noisy level, seed 0 for a
/// noise-free one.
pub fn noise_seeds(spec: &CampaignSpec) -> Vec<(f64, u64)> {
    let mut out = Vec::new();
    for &noise in &spec.noise_std_deg {
        if noise > 0.0 {
            out.extend(spec.seeds.iter().map(|&s| (noise, s)));
        } else {
            out.push((noise, 0));
        }
    }
    out
}

/// SHA-256 (hex) of a case's definition within its campaign (see the module doc).
pub fn definition_sha256(spec: &CampaignSpec, case: &CaseSpec) -> String {
    let def = Definition {
        case,
        rate_hz: spec.rate_hz,
        duration_s: spec.duration_s,
        start_s: spec.start_s,
        methods: &spec.methods,
        noise_seeds: noise_seeds(spec),
    };
    // serialising plain data cannot fail; an empty string would only ever mismatch
    let json = serde_json::to_string(&def).unwrap_or_default();
    Sha256::digest(json.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Where a case of the campaign stands in the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CaseState {
    /// A result with status `ok` for this very definition.
    Done,
    /// A result with status `failed` for this very definition.
    Failed,
    /// A result for another definition of the same case id (the campaign file changed since).
    Changed,
    /// No result yet.
    Pending,
}

/// A case's state, read from its result file.
pub fn case_state(spec: &CampaignSpec, out: &Path, case: &CaseSpec) -> CaseState {
    let Ok(text) = std::fs::read_to_string(case_path(out, &case.id)) else {
        return CaseState::Pending;
    };
    match serde_json::from_str::<CaseResult>(&text) {
        Ok(r) if r.definition_sha256 == definition_sha256(spec, case) => {
            if r.status == "ok" {
                CaseState::Done
            } else {
                CaseState::Failed
            }
        }
        // an unreadable result or one of another definition is not this case's result
        _ => CaseState::Changed,
    }
}

/// The state of every case of `spec`, in campaign order, and the ids of results that belong to no case of it.
pub fn scan(spec: &CampaignSpec, out: &Path) -> (Vec<(CaseSpec, CaseState)>, Vec<String>) {
    let cases = spec.cases();
    let states: Vec<(CaseSpec, CaseState)> = cases
        .into_iter()
        .map(|c| {
            let s = case_state(spec, out, &c);
            (c, s)
        })
        .collect();
    let known: std::collections::BTreeSet<&str> =
        states.iter().map(|(c, _)| c.id.as_str()).collect();
    let mut orphans: Vec<String> = result_ids(out)
        .into_iter()
        .filter(|id| !known.contains(id.as_str()))
        .collect();
    orphans.sort();
    (states, orphans)
}

/// Ids of the result files in `DIR/cases` (temporary files excluded).
fn result_ids(out: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(out.join("cases")) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            (!name.starts_with('.'))
                .then(|| name.strip_suffix(".json").map(str::to_string))
                .flatten()
        })
        .collect()
}

/// Counts of case states.
#[derive(Debug, Clone, Default, Serialize, PartialEq, Eq)]
pub struct StateCounts {
    /// Cases with an `ok` result.
    pub done: usize,
    /// Cases with a `failed` result.
    pub failed: usize,
    /// Cases whose result is of another definition.
    pub changed: usize,
    /// Cases without a result.
    pub pending: usize,
}

impl StateCounts {
    /// Tallies states.
    pub fn of<'a>(states: impl IntoIterator<Item = &'a CaseState>) -> StateCounts {
        let mut n = StateCounts::default();
        for s in states {
            match s {
                CaseState::Done => n.done += 1,
                CaseState::Failed => n.failed += 1,
                CaseState::Changed => n.changed += 1,
                CaseState::Pending => n.pending += 1,
            }
        }
        n
    }
}

/// What to do with results that the campaign file does not explain.
#[derive(Debug, Clone, Copy, Default)]
pub struct StorePolicy {
    /// Rerun cases whose definition changed, and delete results of cases no longer in the campaign.
    pub rerun_changed: bool,
    /// Rerun cases whose result is `failed`.
    pub retry_failed: bool,
}

/// What [`prepare`] did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Prepared {
    /// Changed cases whose old results were removed to be rerun.
    pub rerun_changed: Vec<String>,
    /// Results of cases no longer in the campaign, removed.
    pub removed: Vec<String>,
    /// Failed cases whose results were removed to be retried.
    pub retried: Vec<String>,
}

/// Makes `out` the store of `spec`: refuses (an `Invalid` error naming the cases) when results there were made
/// for another definition of a case or belong to no case of the campaign, unless `policy.rerun_changed`; removes
/// the results to be rerun or retried, so that every process working on the store afterwards simply runs the cases
/// without a result; records the campaign as `DIR/campaign.toml`.
pub fn prepare(
    spec: &CampaignSpec,
    out: &Path,
    policy: StorePolicy,
) -> Result<Prepared, CampaignError> {
    for sub in ["cases", "claims"] {
        let d = out.join(sub);
        std::fs::create_dir_all(&d).map_err(CampaignError::io(&d))?;
    }
    let (states, orphans) = scan(spec, out);
    let changed: Vec<&str> = states
        .iter()
        .filter(|(_, s)| *s == CaseState::Changed)
        .map(|(c, _)| c.id.as_str())
        .collect();
    if !policy.rerun_changed && (!changed.is_empty() || !orphans.is_empty()) {
        let mut message = format!(
            "{} holds results of another version of this campaign",
            out.display()
        );
        if !changed.is_empty() {
            message += &format!(
                "; {} case(s) changed definition (rate, duration, maneuver, condition, methods, noise...): {}",
                changed.len(),
                list(&changed)
            );
        }
        if !orphans.is_empty() {
            let o: Vec<&str> = orphans.iter().map(String::as_str).collect();
            message += &format!(
                "; {} result(s) belong to no case of the campaign: {}",
                o.len(),
                list(&o)
            );
        }
        message += ". Use another --out, or --rerun-changed to rerun them (and delete the others)";
        return Err(CampaignError::Invalid {
            path: out.to_path_buf(),
            message,
        });
    }
    let mut done = Prepared::default();
    let remove = |id: &str| -> Result<(), CampaignError> {
        let p = case_path(out, id);
        match std::fs::remove_file(&p) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                Err(CampaignError::Io { path: p, source: e })
            }
            _ => Ok(()),
        }
    };
    for (c, s) in &states {
        match s {
            CaseState::Changed => {
                remove(&c.id)?;
                done.rerun_changed.push(c.id.clone());
            }
            CaseState::Failed if policy.retry_failed => {
                remove(&c.id)?;
                done.retried.push(c.id.clone());
            }
            _ => {}
        }
    }
    for id in orphans {
        remove(&id)?;
        done.removed.push(id);
    }
    record_spec(spec, out)?;
    Ok(done)
}

/// Writes `DIR/campaign.toml` when it does not already hold this campaign (workers on many nodes then never
/// rewrite it).
fn record_spec(spec: &CampaignSpec, out: &Path) -> Result<(), CampaignError> {
    let text = toml::to_string(spec).map_err(|e| CampaignError::Run(e.to_string()))?;
    let path = spec_path(out);
    if std::fs::read_to_string(&path).ok().as_deref() == Some(text.as_str()) {
        return Ok(());
    }
    crate::report::write_atomic(&path, text.as_bytes())
        .map_err(|e| CampaignError::Run(e.to_string()))
}

/// At most 10 ids, then how many more.
fn list(ids: &[&str]) -> String {
    let mut s = ids.iter().take(10).copied().collect::<Vec<_>>().join(", ");
    if ids.len() > 10 {
        s += &format!(" and {} more", ids.len() - 10);
    }
    s
}

/// A case claimed by this process: the flock is held until the claim is dropped.
pub struct Claim {
    _lock: File,
}

/// Claims a case if no other process holds it and it has no result yet (looked up after the lock is taken, so a
/// case finished by another process between planning and claiming is not run twice). `Ok(None)`: not for us.
pub fn claim(out: &Path, id: &str) -> Result<Option<Claim>, CampaignError> {
    let path = claim_path(out, id);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(CampaignError::io(&path))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
        Err(std::fs::TryLockError::Error(source)) => {
            return Err(CampaignError::Io { path, source })
        }
    }
    if case_path(out, id).exists() {
        return Ok(None);
    }
    Ok(Some(Claim { _lock: file }))
}

/// Whether another process holds the claim of a case now (it is running it).
pub fn is_claimed(out: &Path, id: &str) -> bool {
    let Ok(file) = File::open(claim_path(out, id)) else {
        return false;
    };
    matches!(file.try_lock(), Err(std::fs::TryLockError::WouldBlock))
}

/// Writes a case's result atomically (temporary file, then rename).
pub fn write_result(out: &Path, result: &CaseResult) -> Result<(), CampaignError> {
    let mut text =
        serde_json::to_string_pretty(result).map_err(|e| CampaignError::Run(e.to_string()))?;
    text.push('\n');
    let path = case_path(out, &result.case.id);
    crate::report::write_atomic(&path, text.as_bytes())
        .map_err(|e| CampaignError::Run(e.to_string()))
}

/// Reads every `DIR/cases/*.json` (temporary files are ignored), sorted by case id.
pub fn load_results(out: &Path) -> Result<Vec<CaseResult>, CampaignError> {
    let dir = out.join("cases");
    let entries = std::fs::read_dir(&dir).map_err(CampaignError::io(&dir))?;
    let mut results = Vec::new();
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().to_string();
        if name.starts_with('.') || !name.ends_with(".json") {
            continue;
        }
        let text = super::read_text(&path)?;
        let r: CaseResult = serde_json::from_str(&text).map_err(|e| CampaignError::Parse {
            path: path.clone(),
            message: e.to_string(),
        })?;
        results.push(r);
    }
    results.sort_by(|a, b| a.case.id.cmp(&b.case.id));
    Ok(results)
}

/// The store's view of a campaign: per-state counts, the failed and pending ids, and the cases being run now.
#[derive(Debug, Clone, Serialize)]
pub struct StoreStatus {
    /// Campaign name.
    pub campaign: String,
    /// Cases in the campaign.
    pub total: usize,
    /// Counts by state.
    pub counts: StateCounts,
    /// Pending cases claimed by a running process now.
    pub running: usize,
    /// Ids of failed cases.
    pub failed_ids: Vec<String>,
    /// Ids of changed cases.
    pub changed_ids: Vec<String>,
    /// Result files that belong to no case of the campaign.
    pub orphans: Vec<String>,
    /// Failure message per failed case.
    pub errors: BTreeMap<String, String>,
}

/// Reads the store of the campaign recorded in `DIR/campaign.toml`.
pub fn status(out: &Path) -> Result<StoreStatus, CampaignError> {
    let spec = CampaignSpec::load(&spec_path(out))?;
    let (states, orphans) = scan(&spec, out);
    let counts = StateCounts::of(states.iter().map(|(_, s)| s));
    let running = states
        .iter()
        .filter(|(c, s)| *s == CaseState::Pending && is_claimed(out, &c.id))
        .count();
    let ids = |want: CaseState| -> Vec<String> {
        states
            .iter()
            .filter(|(_, s)| *s == want)
            .map(|(c, _)| c.id.clone())
            .collect()
    };
    let failed_ids = ids(CaseState::Failed);
    let errors = failed_ids
        .iter()
        .filter_map(|id| {
            let text = std::fs::read_to_string(case_path(out, id)).ok()?;
            let r: CaseResult = serde_json::from_str(&text).ok()?;
            Some((id.clone(), r.error.unwrap_or_else(|| "failed".into())))
        })
        .collect();
    Ok(StoreStatus {
        campaign: spec.name.clone(),
        total: states.len(),
        counts,
        running,
        failed_ids,
        changed_ids: ids(CaseState::Changed),
        orphans,
        errors,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    fn spec(text: &str) -> CampaignSpec {
        toml::from_str(text).unwrap()
    }

    /// A small campaign for the campaign tests: one aircraft, one flight condition, elevator doublets of 1° and
    /// 2°, the LS estimator.
    pub(in crate::campaign) const BASE: &str = r#"
name = "t"
rate_hz = 60.0
duration_s = 8.0
methods = ["ls"]
[[configurations]]
name = "c"
aircraft = "c172x"
conditions = [ { altitude_ft = 4000.0, speed_kts = 100.0 } ]
[[maneuvers]]
surface = "elevator"
shape = "doublet"
amplitudes_deg = [1.0, 2.0]
"#;

    #[test]
    fn the_definition_hash_moves_with_rate_duration_and_methods_but_not_with_process_reuse() {
        let a = spec(BASE);
        let case = &a.cases()[0];
        let h = definition_sha256(&a, case);
        assert_eq!(h.len(), 64);
        assert_eq!(h, definition_sha256(&spec(BASE), case), "deterministic");
        for changed in [
            BASE.replace("rate_hz = 60.0", "rate_hz = 120.0"),
            BASE.replace("duration_s = 8.0", "duration_s = 9.0"),
            BASE.replace("[\"ls\"]", "[\"ls\", \"srivc\"]"),
            BASE.replace("name = \"t\"", "name = \"t\"\nstart_s = 2.0"),
        ] {
            assert_ne!(h, definition_sha256(&spec(&changed), case), "{changed}");
        }
        let fresh = spec(&BASE.replace(
            "name = \"t\"",
            "name = \"t\"\nfresh_process_per_case = true",
        ));
        assert_eq!(h, definition_sha256(&fresh, case));
        // seeds only matter where noise is added
        let seeds = spec(&BASE.replace("name = \"t\"", "name = \"t\"\nseeds = [7]"));
        assert_eq!(h, definition_sha256(&seeds, case));
        let noisy = spec(&BASE.replace("name = \"t\"", "name = \"t\"\nnoise_std_deg = [0.1]"));
        let noisy7 = spec(&BASE.replace(
            "name = \"t\"",
            "name = \"t\"\nnoise_std_deg = [0.1]\nseeds = [7]",
        ));
        assert_ne!(
            definition_sha256(&noisy, case),
            definition_sha256(&noisy7, case)
        );
    }

    #[test]
    fn a_claim_is_exclusive_released_on_drop_and_refused_once_the_result_exists() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path();
        let s = spec(BASE);
        prepare(&s, out, StorePolicy::default()).unwrap();
        let id = &s.cases()[0].id;
        let first = claim(out, id).unwrap();
        assert!(first.is_some());
        assert!(
            claim(out, id).unwrap().is_none(),
            "held: a second claim fails"
        );
        assert!(is_claimed(out, id));
        drop(first);
        assert!(!is_claimed(out, id));
        std::fs::write(case_path(out, id), "{}").unwrap();
        assert!(
            claim(out, id).unwrap().is_none(),
            "finished by someone else"
        );
    }
}
