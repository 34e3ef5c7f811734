//! The one nonlinear least-squares optimiser: bounded Levenberg–Marquardt (Gauss–Newton with
//! Marquardt's damping) over a problem that supplies residuals and output sensitivities.
//!
//! Every estimator that minimises a (weighted) sum of squared residuals calls
//! [`levenberg_marquardt`]: the maximum-likelihood output-error and filter-error fits, the
//! transfer-function output error, the data compatibility check, the derivatives-from-transfer-
//! functions fit and the diagnose extension fits.
//!
//! Each iteration linearises the problem at `x` into weighted sensitivities `S = W^{1/2} ∂ŷ/∂x`
//! and weighted residuals `e = W^{1/2} (z − ŷ)`, forms the Gauss–Newton normal equations
//! `M = SᵀS`, `g = Sᵀe` and solves the damped system
//!
//! `(M + μ diag M) δ = g`
//!
//! (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., eq. 4.29–4.33 and §4.6;
//! Morelli & Klein, *Aircraft System Identification*, 2nd ed., eq. 6.56 and §6.3; Marquardt 1963).
//! With [`StepSolver::TruncatedSvd`] the step is instead `δ = Σ_i s_i/(s_i² + λ) v_i u_iᵀ e` over
//! the singular values of `S` above a fraction of the largest, `λ = μ s_max²` (Levenberg's
//! damping in the problem's own scaling, Nocedal & Wright §10.3): directions the data do not
//! determine are left out of the step instead of damped.
//!
//! A trial point that the problem cannot evaluate, or whose cost is not finite or not lower,
//! rejects the step and the damping grows; an accepted step lowers it. Bounds are kept by
//! projection, and parameters at a bound whose gradient points out of the box are left out of the
//! step (an active set). After every accepted step the problem may re-estimate its weights (the
//! relaxation algorithm of Jategaonkar §4.9, where the noise covariance R is re-estimated) and
//! say whether they have settled.

use faer::prelude::*;
use faer::Mat;

/// A least-squares problem for [`levenberg_marquardt`].
pub trait Problem {
    /// What an evaluation keeps (residuals, predictions …).
    type Point;
    /// An error that ends the minimisation.
    type Error;

    /// Evaluates the problem at `x`; `Ok(None)` when it cannot be evaluated there (a simulation
    /// diverged), which rejects the step.
    fn evaluate(&mut self, x: &[f64]) -> Result<Option<Self::Point>, Self::Error>;

    /// The cost a step must lower, `eᵀe` at the current weights.
    fn cost(&self, point: &Self::Point) -> f64;

    /// Weighted sensitivities and residuals at `x` (evaluated as `point`); `Ok(None)` ends the
    /// iterations without descent.
    fn linearise(
        &mut self,
        x: &[f64],
        point: &Self::Point,
    ) -> Result<Option<Linearised>, Self::Error>;

    /// Lower and upper bounds of `x` (empty slices: unbounded).
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&[], &[])
    }

    /// Makes the projected trial point admissible beyond the bounds (it may move it towards
    /// `x`); false rejects the step.
    fn admit(&mut self, _x: &[f64], _trial: &mut [f64]) -> bool {
        true
    }

    /// Called after an accepted step: the problem may re-estimate its weights (and adjust `x` and
    /// `point` to them).
    fn relax(
        &mut self,
        _x: &mut Vec<f64>,
        _point: &mut Self::Point,
    ) -> Result<Relaxation, Self::Error> {
        Ok(Relaxation::Steady)
    }
}

/// The problem linearised at a point.
#[derive(Clone, Debug)]
pub struct Linearised {
    /// Weighted output sensitivities `W^{1/2} ∂ŷ/∂x`, one row per residual.
    pub sensitivities: Mat<f64>,
    /// Weighted residuals `W^{1/2} (z − ŷ)`.
    pub residuals: Vec<f64>,
}

/// What [`Problem::relax`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Relaxation {
    /// The weights have settled: a small cost decrease ends the iterations.
    Steady,
    /// The weights still move: iterate on.
    Moving,
    /// The problem cannot go on from here.
    Stop,
}

/// How the damped step is solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepSolver {
    /// `(M + μ diag M) δ = g` by partial-pivoting LU.
    Marquardt,
    /// Levenberg's `(SᵀS + μ s_max² I) δ = Sᵀe` through the SVD of `S`, singular values below
    /// `null_tolerance · s_max` left out.
    TruncatedSvd {
        /// Relative singular-value threshold of a null direction.
        null_tolerance: f64,
    },
}

/// The damping schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Damping {
    /// Starting μ.
    pub initial: f64,
    /// Smallest μ.
    pub min: f64,
    /// Division of μ after an accepted step.
    pub decrease: f64,
    /// Multiplication of μ after a rejected step.
    pub increase: f64,
    /// Damped steps tried per iteration before giving up.
    pub tries: usize,
}

impl Default for Damping {
    fn default() -> Self {
        Damping {
            initial: 1e-3,
            min: 1e-9,
            decrease: 10.0,
            increase: 10.0,
            tries: 16,
        }
    }
}

/// Options of [`levenberg_marquardt`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Iteration limit.
    pub max_iterations: usize,
    /// Converged when an accepted step lowers the cost by less than this fraction (and the
    /// weights are steady).
    pub tolerance: f64,
    /// Converged, without evaluating it, when the first step of an iteration predicts a cost decrease
    /// `δ·g` (the Gauss–Newton decrease, `gᵀM⁻¹g` undamped) of at most this, in cost units; 0: every step is
    /// evaluated. For a problem whose evaluation is a simulation, a fraction of the residual variance s²
    /// ends where the next step would move the parameters by a small fraction of their Cramér–Rao bounds
    /// (`Δ cost / s² = δᵀMδ / s²`).
    pub min_decrease: f64,
    /// Damping schedule.
    pub damping: Damping,
    /// Step solver.
    pub solver: StepSolver,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 50,
            tolerance: 1e-7,
            min_decrease: 0.0,
            damping: Damping::default(),
            solver: StepSolver::Marquardt,
        }
    }
}

/// Why the iterations ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The cost stopped falling (and the weights stopped moving).
    Converged,
    /// The iteration limit came first.
    MaxIterations,
    /// No damped step lowered the cost while the predicted decrease was still significant, or the
    /// problem could not be linearised or relaxed.
    NoDescent,
}

/// Where [`levenberg_marquardt`] ended.
#[derive(Clone, Debug)]
pub struct Minimum<P> {
    /// The parameters.
    pub x: Vec<f64>,
    /// The problem evaluated there.
    pub point: P,
    /// Iterations taken.
    pub iterations: usize,
    /// Why they ended.
    pub stop: Stop,
}

/// Minimises the problem's cost from `x` (already evaluated as `start`); see the module doc.
pub fn levenberg_marquardt<P: Problem>(
    problem: &mut P,
    x: Vec<f64>,
    start: P::Point,
    options: &Options,
) -> Result<Minimum<P::Point>, P::Error> {
    let mut x = x;
    let mut point = start;
    let damping = options.damping;
    let mut mu = damping.initial;
    let mut stop = Stop::MaxIterations;
    let mut iterations = 0;
    while iterations < options.max_iterations {
        iterations += 1;
        let Some(lin) = problem.linearise(&x, &point)? else {
            stop = Stop::NoDescent;
            break;
        };
        let (s, e) = (&lin.sensitivities, &lin.residuals);
        let g: Vec<f64> = (0..s.ncols())
            .map(|j| (0..e.len()).map(|i| s[(i, j)] * e[i]).sum())
            .collect();
        let active = active_set(problem.bounds(), &x, &g);
        let Some(system) = System::new(options.solver, s, &lin.residuals, &g, &active) else {
            stop = Stop::Converged;
            break;
        };
        let q = problem.cost(&point);
        let mut accepted = None;
        let mut first_decrement = None;
        for _ in 0..damping.tries {
            let Some(step) = system.step(mu) else {
                mu *= damping.increase;
                continue;
            };
            let decrement: f64 = step.iter().zip(&g).map(|(a, b)| a * b).sum();
            if first_decrement.is_none()
                && options.min_decrease > 0.0
                && decrement <= options.min_decrease
            {
                break;
            }
            first_decrement.get_or_insert(decrement);
            let mut trial: Vec<f64> = x.iter().zip(&step).map(|(a, b)| a + b).collect();
            clamp(problem.bounds(), &mut trial);
            if !problem.admit(&x, &mut trial) {
                mu *= damping.increase;
                continue;
            }
            if let Some(tp) = problem.evaluate(&trial)? {
                let tq = problem.cost(&tp);
                if tq.is_finite() && tq < q {
                    accepted = Some((trial, tp, tq));
                    break;
                }
            }
            mu *= damping.increase;
        }
        let Some((trial, tp, tq)) = accepted else {
            // the quadratic model predicted (almost) no decrease: at the minimum
            let small = first_decrement
                .is_none_or(|d| d <= 10.0 * options.tolerance * q || d <= options.min_decrease);
            stop = if small {
                Stop::Converged
            } else {
                Stop::NoDescent
            };
            break;
        };
        mu = (mu / damping.decrease).max(damping.min);
        let gain = (q - tq) / q;
        x = trial;
        point = tp;
        match problem.relax(&mut x, &mut point)? {
            Relaxation::Stop => {
                stop = Stop::NoDescent;
                break;
            }
            Relaxation::Steady if gain < options.tolerance => {
                stop = Stop::Converged;
                break;
            }
            _ => {}
        }
    }
    Ok(Minimum {
        x,
        point,
        iterations,
        stop,
    })
}

/// Entries of `x` free to move: not at a bound with the gradient pointing out of the box.
fn active_set((lower, upper): (&[f64], &[f64]), x: &[f64], g: &[f64]) -> Vec<usize> {
    (0..x.len())
        .filter(|&j| {
            let at_lo = lower.get(j).is_some_and(|&l| x[j] <= l) && g[j] < 0.0;
            let at_hi = upper.get(j).is_some_and(|&u| x[j] >= u) && g[j] > 0.0;
            !(at_lo || at_hi)
        })
        .collect()
}

/// Projects `x` onto the bounds.
fn clamp((lower, upper): (&[f64], &[f64]), x: &mut [f64]) {
    for (j, v) in x.iter_mut().enumerate() {
        if let Some(&l) = lower.get(j) {
            *v = v.max(l);
        }
        if let Some(&u) = upper.get(j) {
            *v = v.min(u);
        }
    }
}

/// The damped system of one iteration, factorised once for every μ tried.
enum System<'a> {
    Marquardt {
        m: Mat<f64>,
        g: Vec<f64>,
        active: &'a [usize],
        p: usize,
    },
    Svd {
        s: Vec<f64>,
        v: Mat<f64>,
        ute: Vec<f64>,
        active: &'a [usize],
        p: usize,
        cut: f64,
    },
}

impl<'a> System<'a> {
    /// `None` when no active parameter moves the outputs (nothing left to fit).
    fn new(
        solver: StepSolver,
        s: &Mat<f64>,
        e: &[f64],
        g: &[f64],
        active: &'a [usize],
    ) -> Option<Self> {
        let p = g.len();
        if active.is_empty() {
            return None;
        }
        match solver {
            StepSolver::Marquardt => {
                let full: Mat<f64> = s.transpose() * s;
                let m = Mat::from_fn(active.len(), active.len(), |i, k| {
                    full[(active[i], active[k])]
                });
                if !(0..active.len()).any(|k| m[(k, k)] > 0.0) {
                    return None;
                }
                Some(System::Marquardt {
                    m,
                    g: active.iter().map(|&j| g[j]).collect(),
                    active,
                    p,
                })
            }
            StepSolver::TruncatedSvd { null_tolerance } => {
                let sa = Mat::from_fn(s.nrows(), active.len(), |i, k| s[(i, active[k])]);
                let svd = sa.thin_svd().ok()?;
                let sv: Vec<f64> = svd.S().column_vector().iter().copied().collect();
                let s_max = sv.first().copied().unwrap_or(0.0);
                if s_max.is_nan() || s_max <= 0.0 {
                    return None;
                }
                let (u, v) = (svd.U(), svd.V().to_owned());
                let ute = (0..sv.len())
                    .map(|i| (0..e.len()).map(|k| u[(k, i)] * e[k]).sum())
                    .collect();
                Some(System::Svd {
                    cut: null_tolerance * s_max,
                    s: sv,
                    v,
                    ute,
                    active,
                    p,
                })
            }
        }
    }

    /// The step for damping `mu` (full length, 0 outside the active set); `None` when singular.
    fn step(&self, mu: f64) -> Option<Vec<f64>> {
        let (x, active, p): (Vec<f64>, &[usize], usize) = match self {
            System::Marquardt { m, g, active, p } => (marquardt_step(m, g, mu)?, active, *p),
            System::Svd {
                s,
                v,
                ute,
                active,
                p,
                cut,
            } => {
                let lambda = mu * s[0] * s[0];
                let mut x = vec![0.0; active.len()];
                for i in 0..s.len() {
                    if s[i] <= *cut {
                        continue;
                    }
                    let f = s[i] / (s[i] * s[i] + lambda) * ute[i];
                    for (k, xk) in x.iter_mut().enumerate() {
                        *xk += f * v[(k, i)];
                    }
                }
                (x, active, *p)
            }
        };
        let mut step = vec![0.0; p];
        for (i, &j) in active.iter().enumerate() {
            step[j] = x[i];
        }
        step.iter().all(|v| v.is_finite()).then_some(step)
    }
}

/// Solves `(M + μ diag M) δ = g` by partial-pivoting LU, a vanishing diagonal floored at 1e-12
/// of the largest.
fn marquardt_step(m: &Mat<f64>, g: &[f64], mu: f64) -> Option<Vec<f64>> {
    let n = g.len();
    let dmax = (0..n).map(|k| m[(k, k)]).fold(0.0_f64, f64::max);
    let a = Mat::from_fn(n, n, |i, k| {
        let v = m[(i, k)];
        if i == k {
            v + mu * v.max(1e-12 * dmax).max(f64::MIN_POSITIVE)
        } else {
            v
        }
    });
    let b = Mat::from_fn(n, 1, |i, _| g[i]);
    let x = a.partial_piv_lu().solve(&b);
    let x: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y = a e^{b t}` sampled without noise; the residuals weighted by `1/σ`.
    struct Exponential {
        t: Vec<f64>,
        y: Vec<f64>,
        lower: Vec<f64>,
        upper: Vec<f64>,
    }

    impl Exponential {
        fn new(a: f64, b: f64) -> Self {
            let t: Vec<f64> = (0..40).map(|k| 0.1 * k as f64).collect();
            let y = t.iter().map(|t| a * (b * t).exp()).collect();
            Exponential {
                t,
                y,
                lower: vec![],
                upper: vec![],
            }
        }
        fn residuals(&self, x: &[f64]) -> Vec<f64> {
            self.t
                .iter()
                .zip(&self.y)
                .map(|(t, y)| y - x[0] * (x[1] * t).exp())
                .collect()
        }
    }

    impl Problem for Exponential {
        type Point = Vec<f64>;
        type Error = ();
        fn evaluate(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, ()> {
            let r = self.residuals(x);
            Ok(r.iter().all(|v| v.is_finite()).then_some(r))
        }
        fn cost(&self, r: &Vec<f64>) -> f64 {
            crate::signal::sum_sq(r)
        }
        fn linearise(&mut self, x: &[f64], r: &Vec<f64>) -> Result<Option<Linearised>, ()> {
            let s = Mat::from_fn(self.t.len(), 2, |k, j| {
                let e = (x[1] * self.t[k]).exp();
                if j == 0 {
                    e
                } else {
                    x[0] * self.t[k] * e
                }
            });
            Ok(Some(Linearised {
                sensitivities: s,
                residuals: r.clone(),
            }))
        }
        fn bounds(&self) -> (&[f64], &[f64]) {
            (&self.lower, &self.upper)
        }
    }

    fn solve(problem: &mut Exponential, x0: Vec<f64>, solver: StepSolver) -> Minimum<Vec<f64>> {
        let start = problem.evaluate(&x0).unwrap().unwrap();
        let options = Options {
            max_iterations: 100,
            tolerance: 1e-14,
            solver,
            ..Options::default()
        };
        levenberg_marquardt(problem, x0, start, &options).unwrap()
    }

    #[test]
    fn noise_free_exponential_is_recovered_from_a_poor_start() {
        // exact data: the minimum is the generating (a, b) to rounding; start 3× off in a and
        // with the wrong sign of b, which needs the damping to grow and shrink
        for solver in [
            StepSolver::Marquardt,
            StepSolver::TruncatedSvd {
                null_tolerance: 1e-10,
            },
        ] {
            let mut p = Exponential::new(2.0, -0.7);
            let m = solve(&mut p, vec![6.0, 0.3], solver);
            assert!((m.x[0] - 2.0).abs() < 1e-8, "{solver:?}: a = {}", m.x[0]);
            assert!((m.x[1] + 0.7).abs() < 1e-8, "{solver:?}: b = {}", m.x[1]);
            assert_eq!(m.stop, Stop::Converged);
        }
    }

    #[test]
    fn a_bound_holds_and_the_other_parameter_fits_given_it() {
        // a ≤ 1.5 while the data want a = 2: a ends on its bound, and b is the least-squares b
        // for a = 1.5 (found here by a fine scan of the one-dimensional cost)
        let mut p = Exponential::new(2.0, -0.7);
        p.lower = vec![f64::NEG_INFINITY, f64::NEG_INFINITY];
        p.upper = vec![1.5, f64::INFINITY];
        let m = solve(&mut p, vec![1.0, -0.5], StepSolver::Marquardt);
        assert_eq!(m.x[0], 1.5);
        let cost_at = |b: f64| p.cost(&p.residuals(&[1.5, b]));
        let best_b = (0..200_001)
            .map(|k| -1.2 + 1e-5 * k as f64)
            .min_by(|a, b| cost_at(*a).total_cmp(&cost_at(*b)))
            .unwrap();
        assert!(
            (m.x[1] - best_b).abs() < 2e-5,
            "b = {}, scan {best_b}",
            m.x[1]
        );
    }

    #[test]
    fn a_step_predicting_less_than_min_decrease_is_not_evaluated() {
        // The exact minimum costs 0 here, so every accepted step is a large relative gain and the
        // relative tolerance never ends the iterations before the limit; a minimum decrease of 1e-6 ends them
        // once the Gauss–Newton step predicts less than that (quadratic convergence: within an iteration or
        // two of the noise-free answer) without evaluating the step, and its value stays within √1e-6 in cost.
        struct Counted(Exponential, usize);
        impl Problem for Counted {
            type Point = Vec<f64>;
            type Error = ();
            fn evaluate(&mut self, x: &[f64]) -> Result<Option<Vec<f64>>, ()> {
                self.1 += 1;
                self.0.evaluate(x)
            }
            fn cost(&self, r: &Vec<f64>) -> f64 {
                self.0.cost(r)
            }
            fn linearise(&mut self, x: &[f64], r: &Vec<f64>) -> Result<Option<Linearised>, ()> {
                self.0.linearise(x, r)
            }
            fn bounds(&self) -> (&[f64], &[f64]) {
                self.0.bounds()
            }
        }
        let run = |min_decrease: f64| {
            let mut p = Counted(Exponential::new(2.0, -0.7), 0);
            let start = p.evaluate(&[2.5, -0.6]).unwrap().unwrap();
            let options = Options {
                max_iterations: 40,
                tolerance: 0.0,
                min_decrease,
                ..Options::default()
            };
            let m = levenberg_marquardt(&mut p, vec![2.5, -0.6], start, &options).unwrap();
            (p.1, m)
        };
        let (every, _) = run(0.0);
        let (fewer, m) = run(1e-6);
        assert_eq!(m.stop, Stop::Converged);
        assert!(
            fewer < every,
            "{fewer} evaluations with the minimum decrease, {every} without"
        );
        assert!(fewer <= 8, "{fewer} evaluations");
        let r = m.point;
        assert!(
            crate::signal::sum_sq(&r) < 1e-6,
            "cost {}",
            crate::signal::sum_sq(&r)
        );
    }

    #[test]
    fn a_start_that_cannot_move_the_outputs_stops_at_once() {
        // every sample at t = 0 and y = 0, started at a = 0: already at a minimum (b does not
        // move the outputs at all), the step is zero, nothing lowers the cost

        let mut p = Exponential::new(2.0, -0.7);
        p.t = vec![0.0; 5];
        p.y = vec![0.0; 5];
        let m = solve(&mut p, vec![0.0, 1.0], StepSolver::Marquardt);
        assert_eq!(m.iterations, 1);
        assert_eq!(m.stop, Stop::Converged);
    }
}
