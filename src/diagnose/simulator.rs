//! The simulations diagnose replays on: the [`ReplaySim`] trait (a [`Simulator`] with coefficient knobs,
//! added terms and model export) and its JSBSim implementation.

use crate::data::FlightRecord;
use crate::sim::{FlightPlan, JsbsimSim, SimError, Simulator, StateReset};

/// A simulation that can be replayed: JSBSim or a linear model (no coefficient knobs).
pub trait ReplaySim: Simulator + Send {
    /// Names of the aerodynamic coefficient functions that can be scaled.
    fn coefficient_names(&self) -> Vec<String>;
    /// Sets the factor on a coefficient function from the next trim on.
    fn set_coefficient_scale(&mut self, name: &str, factor: f64) -> Result<(), SimError>;
    /// Names of the added aerodynamic terms the simulation offers (e.g. `Cm_alpha2`).
    fn added_term_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Sets the coefficient of an added term from the next trim on.
    fn set_added_term(&mut self, name: &str, _coefficient: f64) -> Result<(), SimError> {
        Err(SimError::Usage(format!(
            "this simulation has no added aerodynamic term '{name}'"
        )))
    }
    /// The rate the simulation integrates at, Hz (None: it runs at whatever rate the plan asks for).
    fn rate_hz(&self) -> Option<f64> {
        None
    }
    /// Makes the simulation integrate at `rate_hz` from the next trim on (None from [`ReplaySim::rate_hz`]: it
    /// has no rate of its own and the call does nothing).
    fn set_rate_hz(&mut self, rate_hz: f64) -> Result<(), SimError> {
        match self.rate_hz() {
            None => Ok(()),
            Some(r) if r == rate_hz => Ok(()),
            Some(r) => Err(SimError::Usage(format!(
                "this simulation integrates at {r} Hz only, not {rate_hz} Hz"
            ))),
        }
    }
    /// Whether the simulation can set its state mid-flight ([`ReplaySim::fly_recording_every`] with resets).
    fn supports_resets(&self) -> bool {
        false
    }
    /// Flies `plan`, setting the state at each reset (multiple shooting; without resets, [`Simulator::fly`]),
    /// and keeps only every `every`-th sample (the first included): a replay integrating at a multiple of its
    /// record's rate needs only the record's samples.
    fn fly_recording_every(
        &mut self,
        plan: &FlightPlan,
        resets: &[StateReset],
        every: usize,
    ) -> Result<FlightRecord, SimError> {
        if !resets.is_empty() {
            return Err(SimError::Usage(
                "this simulation cannot set its state mid-flight".into(),
            ));
        }
        let rec = self.fly(plan)?;
        Ok(if every > 1 { rec.every_nth(every) } else { rec })
    }
    /// Writes the model with the current coefficient factors and added terms in it to `dir`.
    fn export_model(&mut self, dir: &std::path::Path) -> Result<std::path::PathBuf, SimError> {
        Err(SimError::Usage(format!(
            "this simulation cannot be exported as a model ({})",
            dir.display()
        )))
    }
}

impl ReplaySim for JsbsimSim {
    fn rate_hz(&self) -> Option<f64> {
        Some(JsbsimSim::rate_hz(self))
    }
    fn set_rate_hz(&mut self, rate_hz: f64) -> Result<(), SimError> {
        JsbsimSim::set_rate_hz(self, rate_hz)
    }
    fn coefficient_names(&self) -> Vec<String> {
        self.coefficient_knobs.clone()
    }
    fn set_coefficient_scale(&mut self, name: &str, factor: f64) -> Result<(), SimError> {
        JsbsimSim::set_coefficient_scale(self, name, factor)
    }
    fn added_term_names(&self) -> Vec<String> {
        self.added_terms.clone()
    }
    fn set_added_term(&mut self, name: &str, coefficient: f64) -> Result<(), SimError> {
        JsbsimSim::set_added_term(self, name, coefficient)
    }
    fn export_model(&mut self, dir: &std::path::Path) -> Result<std::path::PathBuf, SimError> {
        self.export_aircraft(dir)
    }
    fn supports_resets(&self) -> bool {
        true
    }
    fn fly_recording_every(
        &mut self,
        plan: &FlightPlan,
        resets: &[StateReset],
        every: usize,
    ) -> Result<FlightRecord, SimError> {
        JsbsimSim::fly_recording_every(self, plan, resets, every)
    }
}
