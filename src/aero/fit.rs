//! Derivatives from identified transfer functions: nonlinear least squares on the coefficient mismatch.
//!
//! The paper (Şahin & Kalyon 2021, Section 5) solves its coefficient equations for the derivatives. Here the
//! same idea is a weighted nonlinear least-squares problem (Levenberg–Marquardt, Nocedal & Wright §10.3):
//!
//! min_p ‖W^{1/2} (c_model(p) − c_identified)‖²,
//!
//! with c the concatenated [den₁…den₄, num…] of every supplied transfer function, W the inverse of the
//! supplied coefficient covariance (else relative weights 1/c²), and the covariance of the estimate
//! Cov(p) = (Jᵀ W J)⁻¹ (Gauss–Newton approximation, Seber & Wild §5.1). Directions of parameter space that
//! the coefficients do not see (singular values of the scaled Jacobian below `null_tolerance`) are held at
//! the prior and reported by the identifiability analysis instead of receiving a meaningless value.

use faer::{Mat, Side};

use super::coefficients::{model_coefficients, relative_whitening, scales, with_values};
use super::identifiability::{
    analyse_with_weights, assess_estimate, numerical_rank, IdentifiabilityReport,
};
use super::model::{AeroModel, Axis, TfOutput};
use super::params::Derivative;
use super::AeroError;
use crate::optimise;
use crate::signal::sum_sq;

/// One identified continuous-time transfer function, descending powers of s.
#[derive(Debug, Clone)]
pub struct IdentifiedTf {
    /// Numerator coefficients (degree ≤ 3 for the 4-state models).
    pub num: Vec<f64>,
    /// Denominator coefficients, degree 4; normalised to monic if `den[0] ≠ 1` and no covariance is given.
    pub den: Vec<f64>,
    /// Optional covariance of `[den[1], …, den[4], num[0], …]` (denominator first, as an ARX θ vector);
    /// requires a monic denominator.
    pub covariance: Option<Mat<f64>>,
}

/// The identified transfer functions to fit, each tagged with which model output/input it is.
#[derive(Debug, Clone, Default)]
pub struct IdentifiedTfs {
    /// (which transfer function, its identified coefficients).
    pub tfs: Vec<(TfOutput, IdentifiedTf)>,
}

impl IdentifiedTfs {
    /// The paper's set: θ/δe, φ/δa, φ/δr (any may be absent).
    pub fn paper(
        theta_elevator: Option<IdentifiedTf>,
        phi_aileron: Option<IdentifiedTf>,
        phi_rudder: Option<IdentifiedTf>,
    ) -> Self {
        let mut tfs = Vec::new();
        for (o, tf) in [
            (TfOutput::THETA_ELEVATOR, theta_elevator),
            (TfOutput::PHI_AILERON, phi_aileron),
            (TfOutput::PHI_RUDDER, phi_rudder),
        ] {
            if let Some(tf) = tf {
                tfs.push((o, tf));
            }
        }
        Self { tfs }
    }
}

/// Tuning of the Levenberg–Marquardt fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Maximum number of iterations.
    pub max_iterations: usize,
    /// Singular values of the scaled Jacobian below this fraction of the largest are a null direction.
    pub null_tolerance: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            null_tolerance: 1e-7,
        }
    }
}

/// The result of [`estimate_derivatives`].
#[derive(Debug, Clone)]
pub struct DerivativeEstimate {
    /// The model at the estimate (free derivatives updated, the rest as in the prior).
    pub model: AeroModel,
    /// The free derivatives, in the order of `values`, `std_error` and `covariance`.
    pub free: Vec<Derivative>,
    /// Estimated values.
    pub values: Vec<f64>,
    /// Standard errors: ∞ for a derivative the transfer functions cannot determine on its own; NaN when no
    /// coefficient covariance was given and there are no more coefficients than determined directions
    /// (nothing to estimate the coefficient noise from).
    pub std_error: Vec<f64>,
    /// Covariance of the free derivatives, (JᵀWJ)⁺ on the determined subspace.
    pub covariance: Mat<f64>,
    /// Final weighted cost ‖W^{1/2} r‖².
    pub cost: f64,
    /// Per free derivative, the scale applied to its axis' block of (JᵀWJ)⁻¹: that axis' reduced χ²
    /// cost/(N − rank) (≥ 1 with a coefficient covariance).
    pub covariance_scale: Vec<f64>,
    /// Iterations used.
    pub iterations: usize,
    /// Identifiability of each free derivative at the estimate.
    pub identifiability: IdentifiabilityReport,
}

/// Prepared measurement: coefficient vector, whitening matrix (W^{1/2}) and per-TF layout.
pub(crate) struct Target {
    pub(crate) outputs: Vec<TfOutput>,
    pub(crate) num_lengths: Vec<usize>,
    pub(crate) coefficients: Vec<f64>,
    pub(crate) whitening: Mat<f64>,
    pub(crate) from_covariance: bool,
}

fn prepare(tfs: &IdentifiedTfs) -> Result<Target, AeroError> {
    if tfs.tfs.is_empty() {
        return Err(AeroError::NothingToFit(
            "no identified transfer function given".into(),
        ));
    }
    let mut outputs = Vec::new();
    let mut num_lengths = Vec::new();
    let mut coefficients = Vec::new();
    let mut blocks: Vec<Option<Mat<f64>>> = Vec::new();
    for (o, tf) in &tfs.tfs {
        let label = o.label();
        if tf.den.len() != 5 {
            return Err(AeroError::WrongTfOrder {
                tf: label,
                problem: format!(
                    "denominator has degree {} but the 4-state {:?} model needs degree 4 (5 coefficients)",
                    tf.den.len().saturating_sub(1),
                    o.axis
                ),
            });
        }
        if tf.num.is_empty() || tf.num.len() > 4 {
            return Err(AeroError::WrongTfOrder {
                tf: label,
                problem: format!(
                    "numerator has {} coefficients; a proper 4th-order model has 1 to 4",
                    tf.num.len()
                ),
            });
        }
        if tf.den.iter().chain(&tf.num).any(|c| !c.is_finite()) || tf.den[0] == 0.0 {
            return Err(AeroError::WrongTfOrder {
                tf: label,
                problem:
                    "coefficients must be finite with a nonzero leading denominator coefficient"
                        .into(),
            });
        }
        let lead = tf.den[0];
        let n_coef = 4 + tf.num.len();
        if let Some(cov) = &tf.covariance {
            if (lead - 1.0).abs() > 1e-12 {
                return Err(AeroError::BadCovariance {
                    tf: label,
                    problem: "given with a non-monic denominator; normalise den[0] to 1 first"
                        .into(),
                });
            }
            if cov.nrows() != n_coef || cov.ncols() != n_coef {
                return Err(AeroError::BadCovariance {
                    tf: label,
                    problem: format!(
                        "is {}×{} but [den₁…den₄, num] has {n_coef} entries",
                        cov.nrows(),
                        cov.ncols()
                    ),
                });
            }
            let llt = cov.llt(Side::Lower).map_err(|_| AeroError::BadCovariance {
                tf: label.clone(),
                problem: "is not positive definite".into(),
            })?;
            // W^{1/2} = L⁻¹ with Σ = L Lᵀ.
            let l = llt.L().to_owned();
            let mut inv = Mat::<f64>::identity(n_coef, n_coef);
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                l.as_ref(),
                inv.as_mut(),
                faer::Par::Seq,
            );
            blocks.push(Some(inv));
        } else {
            blocks.push(None);
        }
        outputs.push(*o);
        num_lengths.push(tf.num.len());
        coefficients.extend(tf.den[1..].iter().map(|c| c / lead));
        coefficients.extend(tf.num.iter().map(|c| c / lead));
    }
    let from_covariance = blocks.iter().all(Option::is_some);
    let relative = relative_whitening(&coefficients, &num_lengths);
    let n = coefficients.len();
    let mut whitening = Mat::<f64>::zeros(n, n);
    let mut start = 0;
    for (block, &len) in blocks.iter().zip(&num_lengths) {
        let size = 4 + len;
        for i in 0..size {
            for j in 0..size {
                whitening[(start + i, start + j)] = match block {
                    Some(b) => b[(i, j)],
                    None => relative[(start + i, start + j)],
                };
            }
        }
        start += size;
    }
    Ok(Target {
        outputs,
        num_lengths,
        coefficients,
        whitening,
        from_covariance,
    })
}

/// Whitened residual W^{1/2} (c_model − c_target).
pub(crate) fn residual(
    model: &AeroModel,
    target: &Target,
    free: &[Derivative],
    values: &[f64],
) -> Result<Vec<f64>, AeroError> {
    let m = with_values(model, free, values);
    let c = model_coefficients(&m, &target.outputs, &target.num_lengths)?;
    let diff: Vec<f64> = c
        .iter()
        .zip(&target.coefficients)
        .map(|(a, b)| a - b)
        .collect();
    let w = &target.whitening;
    Ok((0..diff.len())
        .map(|i| (0..diff.len()).map(|j| w[(i, j)] * diff[j]).sum())
        .collect())
}

/// Jacobian of the whitened residual w.r.t. the scaled parameters z (p = p0 + s ⊙ z), central differences.
pub(crate) fn scaled_jacobian(
    model: &AeroModel,
    target: &Target,
    free: &[Derivative],
    values: &[f64],
    scale: &[f64],
) -> Result<Mat<f64>, AeroError> {
    let n_res = target.coefficients.len();
    let mut jac = Mat::<f64>::zeros(n_res, free.len());
    let h = 1e-6;
    for k in 0..free.len() {
        let mut up = values.to_vec();
        let mut dn = values.to_vec();
        up[k] += h * scale[k];
        dn[k] -= h * scale[k];
        let ru = residual(model, target, free, &up)?;
        let rd = residual(model, target, free, &dn)?;
        for i in 0..n_res {
            jac[(i, k)] = (ru[i] - rd[i]) / (2.0 * h);
        }
    }
    Ok(jac)
}

/// The whitened coefficient residual in the scaled parameters `z` (values = start + scale ⊙ z)
/// for [`optimise::levenberg_marquardt`].
struct Coefficients<'a> {
    prior: &'a AeroModel,
    target: &'a Target,
    free: &'a [Derivative],
    start: &'a [f64],
    scale: &'a [f64],
}

impl Coefficients<'_> {
    fn values(&self, z: &[f64]) -> Vec<f64> {
        self.start
            .iter()
            .zip(z)
            .zip(self.scale)
            .map(|((p, z), s)| p + z * s)
            .collect()
    }
}

impl optimise::Problem for Coefficients<'_> {
    type Point = Vec<f64>;
    type Error = AeroError;

    fn evaluate(&mut self, z: &[f64]) -> Result<Option<Vec<f64>>, AeroError> {
        residual(self.prior, self.target, self.free, &self.values(z)).map(Some)
    }

    fn cost(&self, r: &Vec<f64>) -> f64 {
        sum_sq(r)
    }

    /// The residual's own Jacobian as the sensitivities, the negated residual as `e`.
    fn linearise(
        &mut self,
        z: &[f64],
        r: &Vec<f64>,
    ) -> Result<Option<optimise::Linearised>, AeroError> {
        let jac = scaled_jacobian(
            self.prior,
            self.target,
            self.free,
            &self.values(z),
            self.scale,
        )?;
        Ok(Some(optimise::Linearised {
            sensitivities: jac,
            residuals: r.iter().map(|v| -v).collect(),
        }))
    }
}

/// Estimate the `free` derivatives of `prior` from identified transfer functions (see the module doc).
///
/// `prior` supplies the flight condition, mass, geometry, assumptions, the fixed derivatives and the
/// starting values of the free ones. Derivatives or combinations the transfer functions cannot determine
/// keep their prior values and get an infinite standard error; `identifiability` says which and why.
pub fn estimate_derivatives(
    prior: &AeroModel,
    tfs: &IdentifiedTfs,
    free: &[Derivative],
    options: FitOptions,
) -> Result<DerivativeEstimate, AeroError> {
    prior.validate()?;
    if free.is_empty() {
        return Err(AeroError::NothingToFit(
            "no free derivative selected".into(),
        ));
    }
    let target = prepare(tfs)?;
    let scale = scales(prior, free);
    let start: Vec<f64> = free.iter().map(|&d| prior.derivatives.get(d)).collect();
    let mut problem = Coefficients {
        prior,
        target: &target,
        free,
        start: &start,
        scale: &scale,
    };
    let r = residual(prior, &target, free, &start)?;
    let lm = optimise::Options {
        max_iterations: options.max_iterations,
        tolerance: 1e-14,
        min_decrease: 0.0,
        damping: optimise::Damping {
            initial: 1e-6,
            min: 1e-16,
            decrease: 10.0,
            increase: 10.0,
            tries: 30,
        },
        solver: optimise::StepSolver::TruncatedSvd {
            null_tolerance: options.null_tolerance,
        },
    };
    let min = optimise::levenberg_marquardt(&mut problem, vec![0.0; free.len()], r, &lm)?;
    let values = problem.values(&min.x);
    let (r, iterations) = (min.point, min.iterations);
    let cost = sum_sq(&r);

    let model = with_values(prior, free, &values);
    let identifiability = analyse_with_weights(
        &model,
        free,
        &target.outputs,
        &target.num_lengths,
        Some(&target.whitening),
    )?;
    // Covariance on the determined subspace: (JᵀWJ)⁺ = V Σ⁻² Vᵀ over the kept singular values, scaled
    // back to physical units; with relative weights, times the residual variance s² = cost/(N − rank).
    let jac = scaled_jacobian(prior, &target, free, &values, &scale)?;
    let svd = jac
        .svd()
        .map_err(|_| AeroError::Numerical("SVD of the Jacobian"))?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let rank = numerical_rank(&s, options.null_tolerance);
    // With a coefficient covariance the residual should be χ²(N − rank); when the cost is larger the model
    // cannot reproduce the identified coefficients within their stated uncertainty (model-structure error or
    // an identification bias the covariance does not hold), and the covariance is scaled by the reduced χ²
    // (fit-error scaling, Morelli & Klein §6.2.3; Seber & Wild §2.1.3), never below 1. The axes are
    // decoupled (the Jacobian is block-diagonal), so each axis gets its own scale from its own residuals.
    let row_axis: Vec<Axis> = target
        .outputs
        .iter()
        .zip(&target.num_lengths)
        .flat_map(|(o, &len)| std::iter::repeat_n(o.axis, 4 + len))
        .collect();
    let axis_of = |d: Derivative| {
        if d.is_longitudinal() {
            Axis::Longitudinal
        } else {
            Axis::Lateral
        }
    };
    let p = free.len();
    let mut axis_sigma2: Vec<(Axis, f64, f64)> = Vec::new(); // (axis, σ², typical relative coefficient σ)
    for axis in [Axis::Longitudinal, Axis::Lateral] {
        let rows: Vec<usize> = (0..row_axis.len())
            .filter(|&i| row_axis[i] == axis)
            .collect();
        let cols: Vec<usize> = (0..p).filter(|&k| axis_of(free[k]) == axis).collect();
        if rows.is_empty() {
            continue;
        }
        let sub = Mat::from_fn(rows.len(), cols.len(), |i, k| jac[(rows[i], cols[k])]);
        let rank_g = if cols.is_empty() {
            0
        } else {
            let sv: Vec<f64> = sub
                .singular_values()
                .map_err(|_| AeroError::Numerical("SVD of the Jacobian"))?;
            numerical_rank(&sv, options.null_tolerance)
        };
        let cost_g: f64 = rows.iter().map(|&i| r[i] * r[i]).sum();
        let dof = rows.len().saturating_sub(rank_g);
        let s2 = if target.from_covariance {
            if dof > 0 {
                (cost_g / dof as f64).max(1.0)
            } else {
                1.0
            }
        } else if dof > 0 {
            cost_g / dof as f64
        } else {
            f64::NAN
        };
        let mut rel: Vec<f64> = rows
            .iter()
            .map(|&i| s2.sqrt() / (target.whitening[(i, i)] * target.coefficients[i]).abs())
            .filter(|x| x.is_finite() && *x > 0.0)
            .collect();
        rel.sort_by(f64::total_cmp);
        let eps = rel.get(rel.len() / 2).copied().unwrap_or(f64::NAN);
        axis_sigma2.push((axis, s2, eps));
    }
    let sigma2_of = |d: Derivative| {
        axis_sigma2
            .iter()
            .find(|(a, _, _)| *a == axis_of(d))
            .map_or(f64::NAN, |x| x.1)
    };
    let covariance_scale: Vec<f64> = free.iter().map(|&d| sigma2_of(d)).collect();
    let v = svd.V();
    let covariance = Mat::from_fn(p, p, |a, b| {
        let z: f64 = (0..rank)
            .map(|i| v[(a, i)] * v[(b, i)] / (s[i] * s[i]))
            .sum();
        z * scale[a] * scale[b] * (covariance_scale[a] * covariance_scale[b]).sqrt()
    });
    let std_error = (0..p)
        .map(|k| {
            if identifiability.is_determined(free[k]) {
                covariance[(k, k)].sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    // Data-based verdicts: the same Jacobian at the coefficients' actual uncertainty (module doc of
    // `identifiability`, `assess_estimate`). Needs a finite σ².
    let mut identifiability = identifiability;
    if covariance_scale.iter().all(|x| x.is_finite() && *x > 0.0) {
        let information = Mat::from_fn(p, p, |a, b| {
            (0..jac.nrows())
                .map(|i| jac[(i, a)] * jac[(i, b)])
                .sum::<f64>()
                / (covariance_scale[a] * covariance_scale[b]).sqrt()
        });
        let eps: Vec<(Axis, f64)> = axis_sigma2.iter().map(|&(a, _, e)| (a, e)).collect();
        assess_estimate(
            &mut identifiability,
            &model,
            &values,
            &scale,
            &information,
            &eps,
        )?;
    }
    Ok(DerivativeEstimate {
        model,
        free: free.to_vec(),
        values,
        std_error,
        covariance,
        cost,
        covariance_scale,
        iterations,
        identifiability,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::model::tests::c172x_model;
    use crate::aero::model::Axis;
    use crate::aero::params::{Assumptions, Derivative as D};
    use crate::aero::Verdict;

    fn exact_tf(model: &AeroModel, o: TfOutput, len: usize) -> IdentifiedTf {
        let tf = model.transfer_function(o).unwrap();
        IdentifiedTf {
            num: tf.num[4 - len..].to_vec(),
            den: tf.den,
            covariance: None,
        }
    }

    /// The truth with each free derivative moved by +8 %, −6 %, +8 %, … as the starting guess.
    fn perturbed(truth: &AeroModel, free: &[D]) -> AeroModel {
        let mut prior = truth.clone();
        for (i, &d) in free.iter().enumerate() {
            let f = if i % 2 == 0 { 1.08 } else { 0.94 };
            prior.derivatives.set(d, truth.derivatives.get(d) * f);
        }
        prior
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// The paper's derivatives of one axis.
    fn paper_set(longitudinal: bool) -> Vec<D> {
        D::PAPER
            .iter()
            .copied()
            .filter(|d| d.is_longitudinal() == longitudinal)
            .collect()
    }

    /// The paper's θ/δe alone, exact.
    fn theta_elevator_only(truth: &AeroModel) -> IdentifiedTfs {
        IdentifiedTfs::paper(
            Some(exact_tf(truth, TfOutput::THETA_ELEVATOR, 3)),
            None,
            None,
        )
    }

    /// The fit of `free` to `tfs` started from [`perturbed`].
    fn fit_from_perturbed(
        truth: &AeroModel,
        tfs: &IdentifiedTfs,
        free: &[D],
    ) -> DerivativeEstimate {
        estimate_derivatives(&perturbed(truth, free), tfs, free, FitOptions::default()).unwrap()
    }

    /// Every free derivative back to 1e-6 relative.
    fn assert_all_recovered(est: &DerivativeEstimate, truth: &AeroModel, free: &[D]) {
        for (k, &d) in free.iter().enumerate() {
            assert!(
                rel(est.values[k], truth.derivatives.get(d)) < 1e-6,
                "{d}: {} vs {}",
                est.values[k],
                truth.derivatives.get(d)
            );
        }
    }

    /// The message of a fit of `free` to `tfs` that must fail.
    fn fit_error(truth: &AeroModel, tfs: &IdentifiedTfs, free: &[D]) -> String {
        estimate_derivatives(truth, tfs, free, FitOptions::default())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn round_trip_with_lift_known_returns_all_six_pitch_derivatives_to_1e_6() {
        // Specification: derivatives → θ/δe → derivatives, identifiable ones to 1e-6 relative.
        let truth = c172x_model(Assumptions::paper());
        let free = [D::CD0, D::CDCL2, D::Cmalpha, D::Cmalphadot, D::Cmq, D::Cmde];
        let tfs = theta_elevator_only(&truth);
        let est = fit_from_perturbed(&truth, &tfs, &free);
        assert_all_recovered(&est, &truth, &free);
        assert!(est.identifiability.null_space.is_empty());
    }

    #[test]
    fn round_trip_paper_set_recovers_cm_alpha_and_errs_only_along_the_flagged_null_direction() {
        // All 8 paper derivatives from θ/δe alone: Cm_alpha comes back to 1e-6; the others move only along
        // the one flagged direction. The direction is local (the solution set is curved), so from an 8 %
        // start the error's component off the flagged direction is second order: < 5 % of its length.
        let truth = c172x_model(Assumptions::paper());
        let free = paper_set(true);
        let tfs = theta_elevator_only(&truth);
        let est = fit_from_perturbed(&truth, &tfs, &free);
        let k_alpha = free.iter().position(|&d| d == D::Cmalpha).unwrap();
        assert!(rel(est.values[k_alpha], truth.derivatives.get(D::Cmalpha)) < 1e-6);
        assert!(
            est.cost < 1e-20,
            "the fit must reproduce the coefficients: cost {}",
            est.cost
        );
        assert_eq!(est.identifiability.null_space.len(), 1);
        assert!(
            est.identifiability.is_determined(D::Cmalpha),
            "{}",
            est.identifiability.to_text()
        );
        // 7 coefficients, rank 7: no redundancy to estimate the coefficient noise without a covariance.
        assert!(est.std_error[k_alpha].is_nan());
        let k_q = free.iter().position(|&d| d == D::Cmq).unwrap();
        assert!(
            est.std_error[k_q].is_infinite(),
            "Cm_q alone must be flagged"
        );
        // Error in relative units versus the flagged null direction (also in relative units).
        let scale: Vec<f64> = free
            .iter()
            .map(|&d| truth.derivatives.get(d).abs())
            .collect();
        let err: Vec<f64> = free
            .iter()
            .enumerate()
            .map(|(k, &d)| (est.values[k] - truth.derivatives.get(d)) / scale[k])
            .collect();
        let n: Vec<f64> = est.identifiability.null_space[0]
            .iter()
            .zip(&scale)
            .map(|(x, s)| x / s)
            .collect();
        let nn = sum_sq(&n).sqrt();
        let along: f64 = err.iter().zip(&n).map(|(e, x)| e * x).sum::<f64>() / nn;
        let off = (sum_sq(&err) - along * along).max(0.0).sqrt();
        let total = sum_sq(&err).sqrt();
        assert!(off < 0.05 * total, "off-direction error {off} of {total}");
    }

    #[test]
    fn round_trip_lateral_with_sideslip_and_yaw_rate_returns_all_twelve_to_1e_6() {
        let truth = c172x_model(Assumptions::paper());
        let free = paper_set(false);
        let mut tfs = IdentifiedTfs::paper(
            None,
            Some(exact_tf(&truth, TfOutput::PHI_AILERON, 3)),
            Some(exact_tf(&truth, TfOutput::PHI_RUDDER, 3)),
        );
        for state in [0, 2] {
            for input in [0, 1] {
                let o = TfOutput {
                    axis: Axis::Lateral,
                    state,
                    input,
                };
                tfs.tfs.push((o, exact_tf(&truth, o, 4)));
            }
        }
        let est = fit_from_perturbed(&truth, &tfs, &free);
        assert_all_recovered(&est, &truth, &free);
    }

    #[test]
    fn covariance_from_coefficient_covariance_matches_the_identifiability_sensitivity() {
        // Two code paths, one formula: with Σ = diag((1 % · c)²) the propagated standard error (JᵀWJ)⁻¹ must
        // equal 1 % × the identifiability report's relative std × |derivative|, to 1e-4.
        let truth = c172x_model(Assumptions::paper());
        let free = [D::CD0, D::CDCL2, D::Cmalpha, D::Cmalphadot, D::Cmq, D::Cmde];
        let mut tf = exact_tf(&truth, TfOutput::THETA_ELEVATOR, 3);
        let c: Vec<f64> = tf.den[1..].iter().chain(&tf.num).copied().collect();
        tf.covariance = Some(Mat::from_fn(7, 7, |i, j| {
            if i == j {
                (0.01 * c[i]).powi(2)
            } else {
                0.0
            }
        }));
        let tfs = IdentifiedTfs::paper(Some(tf), None, None);
        let est = estimate_derivatives(&truth, &tfs, &free, FitOptions::default()).unwrap();
        let report =
            crate::aero::analyse_identifiability(&truth, &free, &[TfOutput::THETA_ELEVATOR])
                .unwrap();
        for (k, &d) in free.iter().enumerate() {
            let rs = match report.verdict(d).unwrap().verdict {
                Verdict::Determined { relative_std } | Verdict::Weak { relative_std, .. } => {
                    relative_std
                }
                ref v => panic!("{d}: {v:?}"),
            };
            let expected = 0.01 * rs * truth.derivatives.get(d).abs();
            assert!(
                rel(est.std_error[k], expected) < 1e-4,
                "{d}: {} vs {expected}",
                est.std_error[k]
            );
        }
    }

    #[test]
    fn wrong_order_and_bad_covariance_are_clear_errors() {
        let truth = c172x_model(Assumptions::paper());
        let free = [D::Cmalpha];
        let third_order = IdentifiedTf {
            num: vec![1.0, 2.0],
            den: vec![1.0, 2.0, 3.0, 4.0],
            covariance: None,
        };
        let err = fit_error(
            &truth,
            &IdentifiedTfs::paper(Some(third_order), None, None),
            &free,
        );
        assert!(
            err.contains("theta_rad/elevator_rad")
                && err.contains("degree 3")
                && err.contains("degree 4"),
            "{err}"
        );
        let mut tf = exact_tf(&truth, TfOutput::THETA_ELEVATOR, 3);
        tf.covariance = Some(Mat::identity(3, 3));
        let err = fit_error(&truth, &IdentifiedTfs::paper(Some(tf), None, None), &free);
        assert!(
            err.contains("covariance") && err.contains("7 entries"),
            "{err}"
        );
        let err = fit_error(&truth, &IdentifiedTfs::default(), &free);
        assert!(err.contains("no identified transfer function"));
    }
}
