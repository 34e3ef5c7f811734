//! Campaign execution: a pool of JSBSim processes (one per worker thread), one atomic JSON result per case,
//! resume by skipping cases whose result file exists; each case runs under a claim in the store (see
//! [`super::store`]), so any number of runs, local or Slurm array tasks, can work on one directory at once.

use super::result::{CaseResult, Identification};
use super::spec::{CampaignSpec, CaseSpec};
use super::store::{self, case_path, StorePolicy};
use super::CampaignError;
use crate::compare::{modal_summary, paper_options, perturbations, single_surface_plan};
use crate::ident::{self, Method};
use crate::sim::{JsbsimSim, SimError, Simulator, TrimPoint};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Mutex;

/// Options of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Worker threads, each with its own JSBSim process.
    pub jobs: usize,
    /// Show a progress bar (only drawn on a terminal).
    pub progress: bool,
    /// Changed and failed results: refuse, rerun or retry (applied before any case runs).
    pub policy: StorePolicy,
    /// Only these case ids, in this order, in a store already prepared by someone else (a task of a submitted
    /// job: its shard of the queue). `None`: the whole campaign, preparing the store first.
    pub queue: Option<Vec<String>>,
}

/// What a run did.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Cases this run was given (the campaign, or the task's queue).
    pub total: usize,
    /// Cases already done before this run (resumed).
    pub skipped: usize,
    /// Cases run now.
    pub ran: usize,
    /// Cases left to another process that had claimed them (or finished them meanwhile).
    pub claimed_elsewhere: usize,
    /// Cases (of those given) whose result is `failed`.
    pub failed: usize,
    /// Their ids.
    pub failed_ids: Vec<String>,
    /// What was removed from the store before the run (changed, retried, orphaned results).
    pub prepared: store::Prepared,
    /// Wall-clock time of this run, s.
    pub elapsed_s: f64,
}

/// The configuration a process is set up for: coefficient scales and pre-trim properties (values as text).
type ConfigKey = Vec<(String, String)>;

struct Worker {
    /// The aircraft of the running process and the configuration applied to it.
    key: Option<(String, ConfigKey)>,
    sim: Option<JsbsimSim>,
}

impl Worker {
    /// The simulator for a case: the running process (another aircraft is loaded into it; switching
    /// configuration only changes the knobs applied at the next trim), else a new one.
    fn sim_for(&mut self, case: &CaseSpec, rate_hz: f64) -> Result<&mut JsbsimSim, String> {
        let config: ConfigKey = case
            .coefficient_scales
            .iter()
            .chain(&case.properties)
            .map(|(k, v)| (k.clone(), format!("{v:e}")))
            .collect();
        let same_aircraft =
            self.sim.is_some() && self.key.as_ref().is_some_and(|(a, _)| *a == case.aircraft);
        if !same_aircraft {
            self.key = None;
            let cfg =
                crate::sim::derived::aircraft_config(&case.aircraft).map_err(|e| e.to_string())?;
            // another aircraft in the running process saves a process start
            let mut sim = match self.sim.take() {
                Some(old) => old.reload(&cfg, rate_hz),
                None => JsbsimSim::start(&cfg, rate_hz),
            }
            .map_err(|e| e.to_string())?;
            // trim once per flight condition, every case flies from the restored snapshot
            sim.set_trim_reuse(true);
            self.sim = Some(sim);
        }
        let sim = self
            .sim
            .as_mut()
            .ok_or_else(|| "no simulator".to_string())?;
        if self.key.as_ref().map(|(_, c)| c) != Some(&config) {
            self.key = None;
            sim.clear_configuration();
            for (name, factor) in &case.coefficient_scales {
                sim.set_coefficient_scale(name, *factor)
                    .map_err(|e| e.to_string())?;
            }
            for (property, value) in &case.properties {
                sim.set_pre_trim_property(property, *value)
                    .map_err(|e| e.to_string())?;
            }
            self.key = Some((case.aircraft.clone(), config));
        }
        Ok(sim)
    }
}

/// Pending cases grouped by configuration, handed out so that a worker stays on one configuration while it has
/// cases and workers spread over configurations: a switch to another aircraft costs an aircraft load in the
/// worker's process (a process start, ~0.08 s CPU, for its first) and each process trims a flight condition once, so
/// two workers sharing every group would start and trim twice as often as one worker. When its group runs dry a
/// worker moves to a group of its own aircraft if one is as free as any other (same process, new knobs).
struct CaseQueue<'a> {
    /// (cases left, workers on the group) per configuration, in campaign order.
    groups: Vec<(std::collections::VecDeque<&'a CaseSpec>, usize)>,
    /// The aircraft of each group.
    aircraft: Vec<&'a str>,
}

impl<'a> CaseQueue<'a> {
    fn new(pending: &[&'a CaseSpec]) -> Self {
        let mut groups: Vec<(std::collections::VecDeque<&'a CaseSpec>, usize)> = Vec::new();
        let mut names: Vec<&str> = Vec::new();
        let mut aircraft: Vec<&'a str> = Vec::new();
        for c in pending {
            match names.iter().position(|n| *n == c.configuration) {
                Some(i) => groups[i].0.push_back(c),
                None => {
                    names.push(&c.configuration);
                    aircraft.push(&c.aircraft);
                    groups.push((std::iter::once(*c).collect(), 0));
                }
            }
        }
        CaseQueue { groups, aircraft }
    }

    /// The next case for a worker now on `group`: more of the same configuration, else the group with the
    /// fewest workers on it (then one of the same aircraft, then the most cases left). Updates `group`.
    fn next(&mut self, group: &mut Option<usize>) -> Option<&'a CaseSpec> {
        let mut aircraft = None;
        if let Some(g) = *group {
            if let Some(c) = self.groups[g].0.pop_front() {
                return Some(c);
            }
            self.groups[g].1 -= 1;
            aircraft = Some(self.aircraft[g]);
            *group = None;
        }
        let g = (0..self.groups.len())
            .filter(|&g| !self.groups[g].0.is_empty())
            .min_by_key(|&g| {
                (
                    self.groups[g].1,
                    aircraft != Some(self.aircraft[g]),
                    std::cmp::Reverse(self.groups[g].0.len()),
                )
            })?;
        self.groups[g].1 += 1;
        *group = Some(g);
        self.groups[g].0.pop_front()
    }
}

/// Runs one case on a simulator; a failure (trim, flight) becomes a `failed` result, never an `Err`.
pub fn run_case<S: Simulator>(
    sim: &mut S,
    spec: &CampaignSpec,
    methods: &[Method],
    case: &CaseSpec,
) -> CaseResult {
    attempt_case(sim, spec, methods, case).0
}

/// The result of `case` with nothing measured yet: status `failed`, with `error` when known. [`attempt_case`]
/// fills it in as the case gets further.
fn failed_result(spec: &CampaignSpec, case: &CaseSpec, error: Option<String>) -> CaseResult {
    CaseResult {
        case: case.clone(),
        rate_hz: spec.rate_hz,
        duration_s: spec.duration_s,
        start_s: spec.start_s,
        definition_sha256: store::definition_sha256(spec, case),
        status: "failed".into(),
        error,
        trim_alpha_rad: None,
        trim_airspeed_m_s: None,
        identifications: Vec::new(),
    }
}

/// [`run_case`], and whether the case failed because the simulator process died ([`SimError::Crashed`]): such
/// a case says nothing about the aircraft and is run again on a fresh process.
fn attempt_case<S: Simulator>(
    sim: &mut S,
    spec: &CampaignSpec,
    methods: &[Method],
    case: &CaseSpec,
) -> (CaseResult, bool) {
    let mut result = failed_result(spec, case, None);
    let trim = match sim.trim(&TrimPoint::level(case.altitude_ft, case.speed_kts)) {
        Ok(t) => t,
        Err(e) => {
            result.error = Some(format!("trim: {e}"));
            return (result, matches!(e, SimError::Crashed { .. }));
        }
    };
    result.trim_alpha_rad = Some(trim.alpha_rad);
    result.trim_airspeed_m_s = Some(trim.airspeed_m_s);
    let plan = single_surface_plan(
        &case.surface,
        &case.maneuver,
        case.amplitude_deg,
        spec.start_s,
        spec.duration_s,
        spec.rate_hz,
    );
    let rec = match sim.fly(&plan) {
        Ok(r) => r,
        Err(e) => {
            result.error = Some(format!("fly: {e}"));
            return (result, matches!(e, SimError::Crashed { .. }));
        }
    };
    let (du, dy) = match perturbations(&rec, &case.surface, &case.tf_key) {
        Ok(p) => p,
        Err(e) => {
            result.error = Some(e.to_string());
            return (result, false);
        }
    };
    let dt_s = 1.0 / spec.rate_hz;
    for (noise, seed) in store::noise_seeds(spec) {
        let y = crate::signal::add_white_noise(&dy, noise.to_radians(), seed);
        for &method in methods {
            result
                .identifications
                .push(identify_one(&du, &y, dt_s, method, noise, seed));
        }
    }
    result.status = "ok".into();
    (result, false)
}

fn identify_one(
    du: &[f64],
    y: &[f64],
    dt_s: f64,
    method: Method,
    noise_std_deg: f64,
    seed: u64,
) -> Identification {
    match ident::identify(du, y, dt_s, &paper_options(method)) {
        Ok(r) => Identification {
            method: method.name().into(),
            noise_std_deg,
            seed,
            modal: modal_summary(&r.modes),
            leading_num: r.tf.num.first().copied().filter(|v| v.is_finite()),
            num: r.tf.num,
            den: r.tf.den,
            fit_sim_percent: Some(r.fit_sim_percent).filter(|v| v.is_finite()),
            error: None,
        },
        Err(e) => Identification {
            method: method.name().into(),
            noise_std_deg,
            seed,
            modal: BTreeMap::new(),
            num: vec![],
            den: vec![],
            leading_num: None,
            fit_sim_percent: None,
            error: Some(e.to_string()),
        },
    }
}

/// Runs every case of `spec` (or of `opts.queue`) that has no result in `out/cases` yet, over `opts.jobs` JSBSim
/// processes, each case under its claim in the store.
pub fn run_campaign(
    spec: &CampaignSpec,
    out: &Path,
    opts: &RunOptions,
) -> Result<RunSummary, CampaignError> {
    let t0 = std::time::Instant::now();
    let methods = spec.parsed_methods().map_err(CampaignError::Run)?;
    let all = spec.cases();
    let (prepared, mine) = match &opts.queue {
        None => (
            store::prepare(spec, out, opts.policy)?,
            all.iter().collect::<Vec<_>>(),
        ),
        Some(ids) => (
            store::Prepared::default(),
            queued_cases(spec, out, &all, ids)?,
        ),
    };
    let pending: Vec<&CaseSpec> = mine
        .iter()
        .copied()
        .filter(|c| !case_path(out, &c.id).exists())
        .collect();
    let skipped = mine.len() - pending.len();
    let bar = if opts.progress && std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        let b = indicatif::ProgressBar::new(mine.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} cases  {elapsed} elapsed, ~{eta} left  {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_position(skipped as u64);
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let queue = Mutex::new(CaseQueue::new(&pending));
    let first_error: Mutex<Option<CampaignError>> = Mutex::new(None);
    let ran = std::sync::atomic::AtomicUsize::new(0);
    let elsewhere = std::sync::atomic::AtomicUsize::new(0);
    let jobs = opts.jobs.max(1).min(pending.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                let mut worker = Worker {
                    key: None,
                    sim: None,
                };
                let mut group: Option<usize> = None;
                loop {
                    // two statements, so the queue is unlocked while the case runs
                    let next = queue.lock().ok().and_then(|mut q| q.next(&mut group));
                    let Some(case) = next else { break };
                    let fail = |e: CampaignError| {
                        if let Ok(mut slot) = first_error.lock() {
                            slot.get_or_insert(e);
                        }
                    };
                    // held until the result is written
                    let _claim = match store::claim(out, &case.id) {
                        Ok(Some(c)) => c,
                        Ok(None) => {
                            elsewhere.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                            bar.inc(1);
                            continue;
                        }
                        Err(e) => {
                            fail(e);
                            break;
                        }
                    };
                    let result = match worker.sim_for(case, spec.rate_hz) {
                        Ok(sim) => {
                            let (mut r, mut died) = attempt_case(sim, spec, &methods, case);
                            if died {
                                // the process died, not the case: once more on a fresh process
                                worker.sim = None;
                                if let Ok(sim) = worker.sim_for(case, spec.rate_hz) {
                                    (r, died) = attempt_case(sim, spec, &methods, case);
                                }
                            }
                            if spec.fresh_process_per_case || died {
                                worker.sim = None; // a fresh (or, after a crash, working) bridge next
                            }
                            r
                        }
                        Err(e) => failed_result(spec, case, Some(format!("simulator: {e}"))),
                    };
                    if let Err(e) = store::write_result(out, &result) {
                        fail(e);
                        break;
                    }
                    ran.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    bar.set_message(case.id.clone());
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }
    let failed_ids: Vec<String> = mine
        .iter()
        .filter(|c| store::case_state(spec, out, c) == store::CaseState::Failed)
        .map(|c| c.id.clone())
        .collect();
    Ok(RunSummary {
        total: mine.len(),
        skipped,
        ran: ran.into_inner(),
        claimed_elsewhere: elsewhere.into_inner(),
        failed: failed_ids.len(),
        failed_ids,
        prepared,
        elapsed_s: t0.elapsed().as_secs_f64(),
    })
}

/// The cases of a task's queue, in queue order: every id must be a case of the campaign, and none may hold a
/// result of another definition (the store was prepared for this campaign when the job was submitted).
fn queued_cases<'a>(
    spec: &CampaignSpec,
    out: &Path,
    all: &'a [CaseSpec],
    ids: &[String],
) -> Result<Vec<&'a CaseSpec>, CampaignError> {
    let by_id: BTreeMap<&str, &CaseSpec> = all.iter().map(|c| (c.id.as_str(), c)).collect();
    let invalid = |message: String| CampaignError::Invalid {
        path: out.to_path_buf(),
        message,
    };
    let mut mine = Vec::with_capacity(ids.len());
    for id in ids {
        let case = by_id.get(id.as_str()).ok_or_else(|| {
            invalid(format!(
                "queued case '{id}' is not a case of campaign '{}'",
                spec.name
            ))
        })?;
        mine.push(*case);
    }
    let changed: Vec<&str> = mine
        .iter()
        .filter(|c| store::case_state(spec, out, c) == store::CaseState::Changed)
        .map(|c| c.id.as_str())
        .collect();
    if !changed.is_empty() {
        return Err(invalid(format!(
            "results of another definition for queued cases: {} (resubmit with --rerun-changed)",
            changed.join(", ")
        )));
    }
    Ok(mine)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(configuration: &str, k: usize) -> CaseSpec {
        case_of("c172x", configuration, k)
    }

    fn case_of(aircraft: &str, configuration: &str, k: usize) -> CaseSpec {
        CaseSpec {
            id: format!("{configuration}_{k}"),
            configuration: configuration.into(),
            aircraft: aircraft.into(),
            coefficient_scales: BTreeMap::new(),
            properties: BTreeMap::new(),
            altitude_ft: 4000.0,
            speed_kts: 100.0,
            surface: "elevator".into(),
            tf_key: "theta/elevator".into(),
            maneuver: crate::signal::Maneuver::Doublet { pulse_s: 1.0 },
            amplitude_deg: 1.0,
        }
    }

    #[test]
    fn two_workers_take_separate_configurations_and_switch_only_when_one_runs_dry() {
        // the example campaign's shape: groups of 12, 6, 12, 6 cases
        let cases: Vec<CaseSpec> = [("a", 12), ("b", 6), ("c", 12), ("d", 6)]
            .iter()
            .flat_map(|(c, n)| (0..*n).map(move |k| case(c, k)))
            .collect();
        let pending: Vec<&CaseSpec> = cases.iter().collect();
        let mut q = CaseQueue::new(&pending);
        let (mut ga, mut gb) = (None, None);
        let mut seen = Vec::new();
        let mut switches = [0usize; 2];
        let mut last = [String::new(), String::new()];
        // the workers alternate, as two equally fast workers would
        for turn in 0.. {
            let w = turn % 2;
            let g = if w == 0 { &mut ga } else { &mut gb };
            let Some(c) = q.next(g) else {
                if q.groups.iter().all(|g| g.0.is_empty()) {
                    break;
                }
                continue;
            };
            if last[w] != c.configuration {
                switches[w] += 1;
                last[w] = c.configuration.clone();
            }
            seen.push(c.id.clone());
        }
        assert_eq!(seen.len(), 36, "every case exactly once");
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), 36);
        // 4 configurations: at most 5 process starts in all (one group shared at the end), not 8
        assert!(switches[0] + switches[1] <= 5, "{switches:?}");
    }

    #[test]
    fn a_worker_whose_configuration_runs_dry_moves_to_a_variant_of_its_own_aircraft() {
        // the example campaign: c172x (12), c172x_aft_cg (6), 737 (12), 737_light (6); processes are per
        // aircraft, so two workers need one JSBSim process each when each stays on one aircraft
        let cases: Vec<CaseSpec> = [
            ("c172x", "c172x", 12),
            ("c172x", "c172x_aft_cg", 6),
            ("737", "737", 12),
            ("737", "737_light", 6),
        ]
        .iter()
        .flat_map(|(a, c, n)| (0..*n).map(move |k| case_of(a, c, k)))
        .collect();
        let pending: Vec<&CaseSpec> = cases.iter().collect();
        let mut q = CaseQueue::new(&pending);
        let mut groups = [None, None];
        let mut aircraft: [Vec<String>; 2] = [vec![], vec![]];
        let mut n = 0;
        for turn in 0.. {
            let w = turn % 2;
            let Some(c) = q.next(&mut groups[w]) else {
                if q.groups.iter().all(|g| g.0.is_empty()) {
                    break;
                }
                continue;
            };
            n += 1;
            if aircraft[w].last() != Some(&c.aircraft) {
                aircraft[w].push(c.aircraft.clone());
            }
        }
        assert_eq!(n, 36);
        assert_eq!(aircraft[0].len() + aircraft[1].len(), 2, "{aircraft:?}");
    }
}
