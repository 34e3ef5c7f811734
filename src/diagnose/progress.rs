//! Progress of the search on the terminal (candidate round, fits and simulations done); quiet when stderr is
//! not a terminal. It also counts the simulations and times the stages for the diagnosis.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Wall time and simulations of one stage of the diagnosis.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StageTime {
    /// The stage, as the progress line names it.
    pub stage: String,
    /// Wall time, s.
    pub wall_s: f64,
    /// Simulations counted in it.
    pub simulations: usize,
}

/// Simulation counter, stage clock and (on a terminal) a progress line.
pub struct Progress {
    bar: indicatif::ProgressBar,
    /// The workers' count of the simulations they ran (`search::Worker::shared_simulations`).
    simulations: Arc<AtomicUsize>,
    round: AtomicUsize,
    /// The stages ended so far, and the current one.
    stages: Mutex<(Vec<StageTime>, Option<Current>)>,
}

/// The current stage: its name, start and the simulation count then.
type Current = (String, Instant, usize);

impl Progress {
    /// A progress line on stderr when `show` and stderr is a terminal; otherwise only the stage clock.
    /// `simulations` is the workers' shared count of the simulations they run.
    pub fn new(show: bool, simulations: Arc<AtomicUsize>) -> Self {
        let bar = if show && std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            let b = indicatif::ProgressBar::new(0);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "diagnose: {prefix:24} {bar:30} {pos}/{len} fits  {msg}  {elapsed}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            b.enable_steady_tick(std::time::Duration::from_millis(250));
            b
        } else {
            indicatif::ProgressBar::hidden()
        };
        Progress {
            bar,
            simulations,
            round: AtomicUsize::new(0),
            stages: Mutex::new((Vec::new(), None)),
        }
    }

    /// A new stage (trim and baseline, identifiability screening, validation) with `fits` steps planned; the
    /// current one ends.
    pub fn stage(&self, label: &str, fits: usize) {
        let sims = self.simulations();
        if let Ok(mut st) = self.stages.lock() {
            let (done, current) = &mut *st;
            if let Some((name, t0, s0)) = current.replace((label.to_string(), Instant::now(), sims))
            {
                done.push(StageTime {
                    stage: name,
                    wall_s: t0.elapsed().as_secs_f64(),
                    simulations: sims - s0,
                });
            }
        }
        self.bar.set_position(0);
        self.bar.set_length(fits as u64);
        self.bar.set_prefix(label.to_string());
    }

    /// A new selection round with `fits` candidate fits planned.
    pub fn round(&self, round: usize, fits: usize) {
        self.round.store(round, Ordering::Relaxed);
        self.stage(&format!("candidate round {}", round + 1), fits);
    }

    /// One fit (or sensitivity) done.
    pub fn fitted(&self) {
        self.bar.inc(1);
        self.bar
            .set_message(format!("{} simulations", self.simulations()));
    }

    /// Simulations run so far.
    pub fn simulations(&self) -> usize {
        self.simulations.load(Ordering::Relaxed)
    }

    /// The stages so far, the current one up to now.
    pub fn stage_times(&self) -> Vec<StageTime> {
        let sims = self.simulations();
        let Ok(st) = self.stages.lock() else {
            return Vec::new();
        };
        let (done, current) = &*st;
        let mut out = done.clone();
        if let Some((name, t0, s0)) = current {
            out.push(StageTime {
                stage: name.clone(),
                wall_s: t0.elapsed().as_secs_f64(),
                simulations: sims - s0,
            });
        }
        out
    }

    /// Removes the progress line.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
