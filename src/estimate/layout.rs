//! The estimated vector φ: free model parameters first, then the nuisance terms.
//!
//! `φ = [θ_free, (x0_est, b_y, b_u) of record 1, …, of record R, τ_u]`: initial states and biases
//! belong to one record each, an input skew to all records (it is a property of the data system,
//! not of a manoeuvre).

use super::model::{Parameter, Signature};
use super::record::Record;
use super::EstimateError;
use crate::signal::std_dev;

/// Which nuisance terms are estimated besides the model parameters (indices into the signature's
/// states, outputs and inputs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Nuisance {
    /// States whose initial value is estimated, per record (the others start at the record's).
    pub initial_state: Vec<usize>,
    /// Outputs with an additive bias per record (`z = y + b_y`).
    pub output_bias: Vec<usize>,
    /// Inputs with an additive bias per record (the model sees `u_meas − b_u`).
    pub input_bias: Vec<usize>,
    /// Inputs with a time skew shared by all records (the model sees `u_meas(t − τ)`).
    pub input_skew: Vec<usize>,
    /// States driven by process noise in the filter error method (`None`: every state). A gust
    /// or drift state written into the model carries the noise alone when it is named here.
    pub process_noise: Option<Vec<usize>>,
}

/// Kind of a nuisance term.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NuisanceKind {
    /// Initial value of a state, per record.
    InitialState,
    /// Additive output bias, per record.
    OutputBias,
    /// Additive input bias, per record.
    InputBias,
    /// Input time skew, s, shared by all records.
    InputSkew,
    /// Process-noise variance `q_i = F_ii²` of a state, shared by all records (filter error
    /// method only).
    ProcessNoise,
}

/// One entry of φ after the model parameters.
#[derive(Clone, Debug)]
pub(crate) struct Slot {
    pub kind: NuisanceKind,
    /// Record it belongs to (None for a skew).
    pub record: Option<usize>,
    /// State, output or input index.
    pub index: usize,
    /// Name of that state, output or input.
    pub target: String,
}

/// Nuisance values of one record, unpacked from φ.
#[derive(Clone, Debug)]
pub(crate) struct RecordTerms {
    pub x0: Vec<f64>,
    pub output_bias: Vec<f64>,
    pub input_bias: Vec<f64>,
    pub input_skew_s: Vec<f64>,
}

/// The map between φ and (θ, nuisance terms).
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    /// Full θ at the start (fixed parameters keep these values).
    pub theta_start: Vec<f64>,
    /// Indices into θ of the free parameters: φ[0..free.len()].
    pub free: Vec<usize>,
    pub slots: Vec<Slot>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    pub start: Vec<f64>,
    /// Typical magnitude of each entry (finite-difference steps, convergence).
    pub scale: Vec<f64>,
    /// Held parameters with an uncertainty the covariance carries: (index into θ, σ).
    pub consider: Vec<(usize, f64)>,
    n_inputs: usize,
    n_outputs: usize,
    /// Initial states of each record as given.
    x0_given: Vec<Vec<f64>>,
}

impl Layout {
    pub fn new(
        sig: &Signature,
        parameters: &[Parameter],
        records: &[Record],
        nuisance: &Nuisance,
    ) -> Result<Layout, EstimateError> {
        let invalid = |m: String| Err(EstimateError::Invalid(m));
        if parameters.len() != sig.parameters.len() {
            return invalid(format!(
                "{} parameters given for a model with {}",
                parameters.len(),
                sig.parameters.len()
            ));
        }
        for (p, name) in parameters.iter().zip(&sig.parameters) {
            if &p.name != name {
                return invalid(format!(
                    "parameter '{}' given where the model has '{name}'",
                    p.name
                ));
            }
            if !p.value.is_finite() || p.lower.is_nan() || p.upper.is_nan() || p.lower > p.upper {
                return invalid(format!(
                    "parameter '{}': start {} with bounds [{}, {}]",
                    p.name, p.value, p.lower, p.upper
                ));
            }
        }
        let (nx, nu, ny) = (sig.states.len(), sig.inputs.len(), sig.outputs.len());
        for (what, list, n) in [
            ("initial_state", &nuisance.initial_state, nx),
            ("output_bias", &nuisance.output_bias, ny),
            ("input_bias", &nuisance.input_bias, nu),
            ("input_skew", &nuisance.input_skew, nu),
        ] {
            if let Some(i) = list.iter().find(|&&i| i >= n) {
                return invalid(format!("nuisance {what} names index {i} of {n}"));
            }
        }
        if records.is_empty() {
            return invalid("no records".into());
        }
        for r in records {
            let bad = |reason: String| {
                Err(EstimateError::Record {
                    record: r.name.clone(),
                    reason,
                })
            };
            if r.len() < 3 {
                return bad(format!("{} samples (at least 3 needed)", r.len()));
            }
            if r.inputs.len() != nu || r.outputs.len() != ny || r.initial_state.len() != nx {
                return bad(format!(
                    "{} inputs, {} outputs, {} initial states for a model with {nu}, {ny}, {nx}",
                    r.inputs.len(),
                    r.outputs.len(),
                    r.initial_state.len()
                ));
            }
            if r.inputs
                .iter()
                .chain(&r.outputs)
                .any(|c| c.len() != r.len())
            {
                return bad("a column's length differs from the time column's".into());
            }
            if r.time_s
                .windows(2)
                .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
            {
                return bad("time_s is not strictly increasing".into());
            }
            for (names, cols) in [(&sig.inputs, &r.inputs), (&sig.outputs, &r.outputs)] {
                for (name, col) in names.iter().zip(cols) {
                    if let Some(k) = col.iter().position(|v| !v.is_finite()) {
                        return bad(format!("{name} is not finite at sample {k}"));
                    }
                }
            }
            if r.initial_state.iter().any(|v| !v.is_finite()) {
                return bad("an initial state is not finite".into());
            }
        }
        let free: Vec<usize> = (0..parameters.len())
            .filter(|&i| !parameters[i].fixed)
            .collect();
        let mut lower: Vec<f64> = free.iter().map(|&i| parameters[i].lower).collect();
        let mut upper: Vec<f64> = free.iter().map(|&i| parameters[i].upper).collect();
        let mut start: Vec<f64> = free
            .iter()
            .map(|&i| {
                parameters[i]
                    .value
                    .clamp(parameters[i].lower, parameters[i].upper)
            })
            .collect();
        let mut scale: Vec<f64> = free
            .iter()
            .map(|&i| parameters[i].value.abs().max(1e-3))
            .collect();
        let mut slots = Vec::new();
        let mut push = |slot: Slot, s: f64, lo: f64, hi: f64, sc: f64| {
            slots.push(slot);
            start.push(s);
            lower.push(lo);
            upper.push(hi);
            scale.push(sc);
        };
        for (r, rec) in records.iter().enumerate() {
            for &i in &nuisance.initial_state {
                let x = rec.initial_state[i];
                let slot = Slot {
                    kind: NuisanceKind::InitialState,
                    record: Some(r),
                    index: i,
                    target: sig.states[i].clone(),
                };
                push(slot, x, f64::NEG_INFINITY, f64::INFINITY, x.abs().max(1e-2));
            }
            // output biases, then input biases: each scaled by the spread of its signal
            for (kind, indices, names, signals) in [
                (
                    NuisanceKind::OutputBias,
                    &nuisance.output_bias,
                    &sig.outputs,
                    &rec.outputs,
                ),
                (
                    NuisanceKind::InputBias,
                    &nuisance.input_bias,
                    &sig.inputs,
                    &rec.inputs,
                ),
            ] {
                for &i in indices {
                    let slot = Slot {
                        kind,
                        record: Some(r),
                        index: i,
                        target: names[i].clone(),
                    };
                    let sc = std_dev(&signals[i]).max(1e-6);
                    push(slot, 0.0, f64::NEG_INFINITY, f64::INFINITY, sc);
                }
            }
        }
        // a skew is bounded to a quarter of the shortest record and 0.5 s
        let max_skew_s = records
            .iter()
            .map(|r| r.duration_s() / 4.0)
            .fold(0.5_f64, f64::min);
        let dt_s = records
            .iter()
            .map(Record::median_dt_s)
            .fold(f64::INFINITY, f64::min);
        for &i in &nuisance.input_skew {
            let slot = Slot {
                kind: NuisanceKind::InputSkew,
                record: None,
                index: i,
                target: sig.inputs[i].clone(),
            };
            push(slot, 0.0, -max_skew_s, max_skew_s, dt_s);
        }
        Ok(Layout {
            theta_start: parameters.iter().map(|p| p.value).collect(),
            consider: parameters
                .iter()
                .enumerate()
                .filter(|(_, p)| p.fixed)
                .filter_map(|(i, p)| p.consider_std.filter(|s| *s > 0.0).map(|s| (i, s)))
                .collect(),
            free,
            slots,
            lower,
            upper,
            start,
            scale,
            n_inputs: nu,
            n_outputs: ny,
            x0_given: records.iter().map(|r| r.initial_state.clone()).collect(),
        })
    }

    /// Length of φ.
    pub fn len(&self) -> usize {
        self.free.len() + self.slots.len()
    }

    /// Full θ for φ.
    pub fn theta(&self, phi: &[f64]) -> Vec<f64> {
        let mut theta = self.theta_start.clone();
        for (k, &i) in self.free.iter().enumerate() {
            theta[i] = phi[k];
        }
        theta
    }

    /// The nuisance terms of record `r` for φ.
    pub fn record_terms(&self, phi: &[f64], r: usize) -> RecordTerms {
        let mut t = RecordTerms {
            x0: self.x0_given[r].clone(),
            output_bias: vec![0.0; self.n_outputs],
            input_bias: vec![0.0; self.n_inputs],
            input_skew_s: vec![0.0; self.n_inputs],
        };
        for (k, slot) in self.slots.iter().enumerate() {
            let v = phi[self.free.len() + k];
            match (slot.kind, slot.record) {
                (NuisanceKind::InputSkew, _) => t.input_skew_s[slot.index] = v,
                (NuisanceKind::ProcessNoise, _) => {}
                (_, Some(rec)) if rec != r => {}
                (NuisanceKind::InitialState, _) => t.x0[slot.index] = v,
                (NuisanceKind::OutputBias, _) => t.output_bias[slot.index] = v,
                (NuisanceKind::InputBias, _) => t.input_bias[slot.index] = v,
            }
        }
        t
    }

    /// The nuisance slot of φ entry `j`, if it is one.
    pub fn slot(&self, j: usize) -> Option<&Slot> {
        j.checked_sub(self.free.len()).map(|k| &self.slots[k])
    }

    /// The record that φ entry `j` alone affects (None: all records).
    pub fn only_record(&self, j: usize) -> Option<usize> {
        self.slot(j).and_then(|s| s.record)
    }

    /// Appends a process-noise variance (start 0, bounded below by 0) for each state in `which`
    /// (`None`: every state) with the given typical magnitudes (per state).
    pub fn add_process_noise(&mut self, states: &[String], which: Option<&[usize]>, scale: &[f64]) {
        for (i, (name, sc)) in states.iter().zip(scale).enumerate() {
            if which.is_some_and(|w| !w.contains(&i)) {
                continue;
            }
            self.slots.push(Slot {
                kind: NuisanceKind::ProcessNoise,
                record: None,
                index: i,
                target: name.clone(),
            });
            self.start.push(0.0);
            self.lower.push(0.0);
            self.upper.push(f64::INFINITY);
            self.scale.push(*sc);
        }
    }

    /// The process-noise variances per state for φ (zeros when none are estimated).
    pub fn process_noise(&self, phi: &[f64], n_states: usize) -> Vec<f64> {
        let mut q = vec![0.0; n_states];
        for (k, slot) in self.slots.iter().enumerate() {
            if slot.kind == NuisanceKind::ProcessNoise {
                q[slot.index] = phi[self.free.len() + k];
            }
        }
        q
    }

    /// Indices into φ of the process-noise variances, in state order.
    pub fn process_noise_entries(&self) -> Vec<usize> {
        self.slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.kind == NuisanceKind::ProcessNoise)
            .map(|(k, _)| self.free.len() + k)
            .collect()
    }

    /// Clamps φ into its bounds.
    pub fn clamp(&self, phi: &mut [f64]) {
        for (j, v) in phi.iter_mut().enumerate() {
            *v = v.clamp(self.lower[j], self.upper[j]);
        }
    }
}
