//! Simulation of a [`StateModel`]: classical fourth-order Runge–Kutta at the model's own step.
//!
//! The integrator stops at every output sample and at every breakpoint of the input
//! reconstruction (a sample time shifted by an input skew), so within one step the input is a
//! single affine piece: a zero-order hold's steps and the kinks of linear interpolation are never
//! smeared across a step, and the response is a smooth function of the skews (which their
//! finite-difference sensitivities need). Between stops, steps are equal and at most
//! `run.max_step_s` long.

use super::model::{SimError, StateModel};
use super::record::Run;

/// Implements [`Model`](crate::estimate::Model) for types that implement [`StateModel`]: the signature is the
/// state model's, `simulate` integrates `f` with the core's [`simulate_states`](crate::estimate::simulate_states),
/// and `state_model` hands the state-space form to the filter error method.
#[macro_export]
macro_rules! model_from_state_model {
    ($($t:ty),+ $(,)?) => {$(
        impl $crate::estimate::Model for $t {
            fn signature(&self) -> &$crate::estimate::Signature {
                $crate::estimate::StateModel::signature(self)
            }
            fn simulate(
                &self,
                theta: &[f64],
                x0: &[f64],
                run: &$crate::estimate::Run<'_>,
            ) -> Result<Vec<Vec<f64>>, $crate::estimate::SimError> {
                $crate::estimate::simulate_states(self, theta, x0, run)
            }
            fn state_model(&self) -> Option<&dyn $crate::estimate::StateModel> {
                Some(self)
            }
        }
    )+};
}

/// Largest magnitude a state or output may reach before the simulation counts as diverged.
pub(crate) const DIVERGED: f64 = 1e12;

/// [`SimError::Diverged`] naming the first state of `x` that is not finite or beyond [`DIVERGED`], `time_s` into
/// the run (`states` names them).
pub(crate) fn check_states(x: &[f64], states: &[String], time_s: f64) -> Result<(), SimError> {
    match x.iter().position(|v| !v.is_finite() || v.abs() > DIVERGED) {
        Some(i) => Err(SimError::Diverged {
            time_s,
            what: format!("state {}", states[i]),
        }),
        None => Ok(()),
    }
}

/// [`SimError::Diverged`] when output `name`'s value `y` is not finite or beyond [`DIVERGED`], `time_s` into the
/// run.
pub(crate) fn check_output(y: f64, name: &str, time_s: f64) -> Result<(), SimError> {
    if !y.is_finite() || y.abs() > DIVERGED {
        return Err(SimError::Diverged {
            time_s,
            what: format!("output {name}"),
        });
    }
    Ok(())
}

/// Outputs `[output][k]` of `model` at the run's sample times, starting from `x0` at the first.
pub fn simulate_states(
    model: &dyn StateModel,
    theta: &[f64],
    x0: &[f64],
    run: &Run<'_>,
) -> Result<Vec<Vec<f64>>, SimError> {
    let sig = model.signature();
    let time = run.time_s;
    let mut p = Propagation::new(model, theta, x0, run);
    let mut y_out = vec![vec![0.0; time.len()]; sig.outputs.len()];
    for k in 0..time.len() {
        if k > 0 {
            p.integrate_to(k);
            p.check_state(k)?;
        }
        p.outputs(k);
        for (o, v) in p.y.iter().enumerate() {
            check_output(*v, &sig.outputs[o], time[k] - time[0])?;
            y_out[o][k] = *v;
        }
    }
    Ok(y_out)
}

/// A state model stepped through a run's sample times: its state, its outputs at the current sample and the
/// integrator's work space. [`simulate_states`] and the filter error method's filter both step with it.
pub(crate) struct Propagation<'a, 'r> {
    model: &'a dyn StateModel,
    theta: &'a [f64],
    run: &'a Run<'r>,
    /// The state at the current sample.
    pub(crate) x: Vec<f64>,
    /// The outputs at the current sample (set by [`Propagation::outputs`]).
    pub(crate) y: Vec<f64>,
    u: Vec<f64>,
    stage: Stages,
}

impl<'a, 'r> Propagation<'a, 'r> {
    /// At the run's first sample, in state `x0`.
    pub(crate) fn new(
        model: &'a dyn StateModel,
        theta: &'a [f64],
        x0: &[f64],
        run: &'a Run<'r>,
    ) -> Self {
        let sig = model.signature();
        let (nx, nu, ny) = (sig.states.len(), sig.inputs.len(), sig.outputs.len());
        Propagation {
            model,
            theta,
            run,
            x: x0.to_vec(),
            y: vec![0.0; ny],
            u: vec![0.0; nu],
            stage: Stages::new(nx, nu),
        }
    }

    /// Integrates the state from sample `k − 1` to sample `k` (module doc).
    pub(crate) fn integrate_to(&mut self, k: usize) {
        let time = self.run.time_s;
        let (model, theta, run) = (self.model, self.theta, self.run);
        let (start, end) = (time[k - 1], time[k]);
        self.stage
            .advance(model, theta, &mut self.x, run, start, end, &mut self.u);
    }

    /// [`check_states`] on the state at sample `k`.
    pub(crate) fn check_state(&self, k: usize) -> Result<(), SimError> {
        let time = self.run.time_s;
        check_states(&self.x, &self.model.signature().states, time[k] - time[0])
    }

    /// Evaluates the outputs at sample `k` into `y`.
    pub(crate) fn outputs(&mut self, k: usize) {
        self.run.input.at(self.run.time_s[k], &mut self.u);
        self.model
            .outputs(self.theta, &self.x, &self.u, &mut self.y);
    }
}

/// Work space of the integrator.
pub(crate) struct Stages {
    k1: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl Stages {
    pub(crate) fn new(nx: usize, nu: usize) -> Stages {
        Stages {
            k1: vec![0.0; nx],
            k2: vec![0.0; nx],
            k3: vec![0.0; nx],
            k4: vec![0.0; nx],
            tmp: vec![0.0; nx],
            a: vec![0.0; nu],
            b: vec![0.0; nu],
        }
    }

    /// Integrates `x` from `start` to `end` (module doc: RK4 at most `run.max_step_s` long,
    /// split at the input's breakpoints). `u` is scratch of the input's length.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn advance(
        &mut self,
        model: &dyn StateModel,
        theta: &[f64],
        x: &mut [f64],
        run: &Run<'_>,
        start: f64,
        end: f64,
        u: &mut [f64],
    ) {
        let tiny = 1e-9 * (end - start);
        let mut t0 = start;
        while t0 < end - tiny {
            let t1 = match run.input.next_breakpoint(t0 + tiny) {
                Some(bp) if bp < end - tiny => bp,
                _ => end,
            };
            let mid = 0.5 * (t0 + t1);
            let (mut a, mut b) = (std::mem::take(&mut self.a), std::mem::take(&mut self.b));
            run.input.piece(mid, &mut a, &mut b);
            let steps = ((t1 - t0) / run.max_step_s).ceil().max(1.0) as usize;
            let h = (t1 - t0) / steps as f64;
            for s in 0..steps {
                let t = t0 + s as f64 * h - mid;
                self.rk4(model, theta, x, t, h, &a, &b, u);
            }
            (self.a, self.b) = (a, b);
            t0 = t1;
        }
    }

    /// One classical RK4 step of length `h` from `t` with the input `u(τ) = a + b τ` (times
    /// relative to the piece's reference).
    #[allow(clippy::too_many_arguments)]
    fn rk4(
        &mut self,
        model: &dyn StateModel,
        theta: &[f64],
        x: &mut [f64],
        t: f64,
        h: f64,
        a: &[f64],
        b: &[f64],
        u: &mut [f64],
    ) {
        let input = |u: &mut [f64], tau: f64| {
            for i in 0..u.len() {
                u[i] = a[i] + b[i] * tau;
            }
        };
        input(u, t);
        model.derivatives(theta, x, u, &mut self.k1);
        input(u, t + 0.5 * h);
        axpy(&mut self.tmp, x, 0.5 * h, &self.k1);
        model.derivatives(theta, &self.tmp, u, &mut self.k2);
        axpy(&mut self.tmp, x, 0.5 * h, &self.k2);
        model.derivatives(theta, &self.tmp, u, &mut self.k3);
        input(u, t + h);
        axpy(&mut self.tmp, x, h, &self.k3);
        model.derivatives(theta, &self.tmp, u, &mut self.k4);
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += h / 6.0 * (self.k1[i] + 2.0 * (self.k2[i] + self.k3[i]) + self.k4[i]);
        }
    }
}

/// `out = x + a k`.
fn axpy(out: &mut [f64], x: &[f64], a: f64, k: &[f64]) {
    for ((o, xi), ki) in out.iter_mut().zip(x).zip(k) {
        *o = xi + a * ki;
    }
}
