//! Starting the simulation workers diagnose and replay fly on: JSBSim's stock aircraft, an exported extended
//! model, or a linear model.

use std::path::Path;

use super::model::ExtendedModel;
use super::replay::LinearReplay;
use super::search::Worker;
use super::DiagnoseError;
use crate::sim::JsbsimSim;

/// Where the simulation comes from: the aircraft's JSBSim model, an exported extended model, or a linear model.
pub enum SimSource<'a> {
    /// JSBSim's stock aircraft of the configuration, with `--property` settings of its loading.
    Aircraft(&'a str, &'a [String]),
    /// An exported model directory (aircraft configuration and loading in its extension.json), with `--property`
    /// settings that add to or replace that loading.
    Model(&'a ExtendedModel, &'a [String]),
    /// `flightid linearize --json` output.
    Linear(&'a Path),
}

/// Starts `n` simulation workers at `rate_hz`, in parallel (each is its own process: the Python start,
/// `import jsbsim` and the aircraft load take a few tenths of a second).
pub fn start_workers(
    source: &SimSource,
    rate_hz: f64,
    n: usize,
) -> Result<Vec<Worker>, DiagnoseError> {
    std::thread::scope(|s| {
        let started: Vec<_> = (0..n.max(1))
            .map(|_| s.spawn(|| start_worker(source, rate_hz)))
            .collect();
        started
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    })
}

/// Starts one simulation worker at `rate_hz`.
fn start_worker(source: &SimSource, rate_hz: f64) -> Result<Worker, DiagnoseError> {
    let starting = |what: String| {
        move |source| DiagnoseError::Sim {
            during: what,
            source,
        }
    };
    Ok(match source {
        SimSource::Aircraft(name, loading) => {
            let cfg = crate::sim::derived::aircraft_config(name)?.with_properties(loading)?;
            let sim = JsbsimSim::start(&cfg, rate_hz)
                .map_err(starting(format!("starting JSBSim for {}", cfg.name)))?;
            Worker::new(Box::new(sim))
        }
        SimSource::Model(m, loading) => {
            let cfg = m.config(loading)?;
            let sim = m.start(&cfg, rate_hz).map_err(starting(format!(
                "starting JSBSim on the model in {}",
                m.dir.display()
            )))?;
            Worker::new(Box::new(sim))
        }
        SimSource::Linear(p) => Worker::new(Box::new(LinearReplay::from_json(p)?)),
    })
}
