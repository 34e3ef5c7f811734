//! Identifiability: which derivatives a set of transfer functions can determine, and what would help.
//!
//! The sensitivity of the transfer-function coefficients to the derivatives is the Jacobian J = ∂c/∂p at the
//! trim point, with rows weighted (relative coefficient error, or the identified coefficient covariance) and
//! columns scaled by each derivative's magnitude, so that J maps relative derivative changes to relative
//! coefficient changes. Its singular value decomposition J = U Σ Vᵀ (Golub & Van Loan §2.4; the classic
//! parameter-identifiability test, e.g. Jategaonkar, *Flight Vehicle System Identification*, §4.18) gives:
//!
//! - null directions: right singular vectors with σ ≈ 0 — derivative combinations the data cannot see;
//! - for each derivative outside the null space, its relative standard deviation per unit relative
//!   coefficient error, √(Σ_i v_ki²/σ_i²) — large means weakly determined.
//!
//! Each derivative gets a plain-words [`Verdict`]; for the undetermined ones the analysis repeats with each
//! extra measurable output (α, u, q, β, p, r, or the other input) to say which measurement would separate them.

use std::fmt::Write as _;

use faer::Mat;

use super::coefficients::{model_coefficients, relative_whitening, scales, with_values};
use super::model::{AeroModel, Axis, TfOutput};
use super::params::Derivative;
use super::AeroError;

/// Singular values below this fraction of the largest span the null space.
const NULL_TOLERANCE: f64 = 1e-7;
/// A derivative whose share of the null space exceeds this is not determined on its own.
const NULL_SHARE: f64 = 1e-4;
/// Relative standard deviation per unit relative coefficient error above which a derivative is "weak":
/// a 1 % coefficient error (a good ARX fit on clean data) would move it by more than 5 %.
const WEAK_RELATIVE_STD: f64 = 5.0;
/// Estimate correlation above which the explanation names the partner (Morelli & Klein §5.4 call
/// |ρ| > 0.9 high; 0.8 already doubles the variance through collinearity).
const HIGH_CORRELATION: f64 = 0.8;

/// What the transfer functions say about one derivative.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Determined on its own.
    Determined {
        /// Relative standard deviation per unit relative coefficient error.
        relative_std: f64,
    },
    /// Determined only poorly.
    Weak {
        /// Relative standard deviation per unit relative coefficient error.
        relative_std: f64,
        /// The most correlated other derivative and the correlation, when |ρ| > 0.8.
        correlated_with: Option<(Derivative, f64)>,
    },
    /// Only a combination with other derivatives is determined.
    Combination {
        /// The derivatives sharing its null direction(s).
        partners: Vec<Derivative>,
        /// The determined combination in words, e.g. `Cm_q + 1.0000·Cm_alphadot`.
        combination: String,
    },
    /// Determined by the structure, but at the identified transfer functions' actual uncertainty the estimate
    /// is so strongly correlated with a partner that only their combination is reliable.
    Correlated {
        /// The most correlated other derivative.
        partner: Derivative,
        /// Correlation coefficient of the two estimates.
        rho: f64,
        /// Relative standard error of this estimate, σ/|estimate|.
        relative_std: f64,
        /// The best-determined combination, e.g. `Cm_q + 0.9312·Cm_alphadot`.
        combination: String,
        /// The combination's estimate.
        value: f64,
        /// Its standard error.
        std_error: f64,
    },
    /// It does not enter these transfer functions at all.
    Absent,
}

/// The verdict for one derivative, with an explanation and the measurements that would determine it.
#[derive(Debug, Clone, PartialEq)]
pub struct DerivativeVerdict {
    /// The derivative.
    pub derivative: Derivative,
    /// The verdict.
    pub verdict: Verdict,
    /// One sentence a flight-test engineer can read.
    pub explanation: String,
    /// Extra measurements (output/input pairs) that would make it determined, in words.
    pub separated_by: Vec<String>,
}

/// The identifiability analysis of a set of derivatives from a set of transfer functions.
#[derive(Debug, Clone)]
pub struct IdentifiabilityReport {
    /// The analysed derivatives (columns of the Jacobian).
    pub derivatives: Vec<Derivative>,
    /// The transfer functions used (rows).
    pub outputs: Vec<TfOutput>,
    /// Singular values of the scaled Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// Null directions in physical units (δ of each derivative, largest entry ±1).
    pub null_space: Vec<Vec<f64>>,
    /// One verdict per derivative, in `derivatives` order.
    pub verdicts: Vec<DerivativeVerdict>,
    /// Correlation matrix of the estimates at the identified transfer functions' uncertainty (`derivatives`
    /// order), when the verdicts come from an estimate ([`assess_estimate`]); empty otherwise.
    pub correlation: Vec<Vec<f64>>,
}

impl IdentifiabilityReport {
    /// True if the derivative is determined (strongly or weakly) on its own.
    pub fn is_determined(&self, d: Derivative) -> bool {
        self.verdicts.iter().any(|v| {
            v.derivative == d
                && matches!(
                    v.verdict,
                    Verdict::Determined { .. } | Verdict::Weak { .. } | Verdict::Correlated { .. }
                )
        })
    }

    /// The verdict of one derivative.
    pub fn verdict(&self, d: Derivative) -> Option<&DerivativeVerdict> {
        self.verdicts.iter().find(|v| v.derivative == d)
    }

    /// A plain-text table: one line per derivative.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "transfer functions: {}",
            self.outputs
                .iter()
                .map(|o| o.label())
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(
            s,
            "singular values (scaled): {}",
            self.singular_values
                .iter()
                .map(|x| format!("{x:.3e}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        for v in &self.verdicts {
            let _ = write!(s, "{:<12} {}", v.derivative.name(), v.explanation);
            if !v.separated_by.is_empty() {
                let _ = write!(
                    s,
                    " Would be determined with: {}.",
                    v.separated_by.join("; ")
                );
            }
            s.push('\n');
        }
        s
    }
}

/// Identifiability of `derivatives` from the model transfer functions `outputs` (full numerators), with
/// relative coefficient weighting, at the point `model`.
pub fn analyse_identifiability(
    model: &AeroModel,
    derivatives: &[Derivative],
    outputs: &[TfOutput],
) -> Result<IdentifiabilityReport, AeroError> {
    let lengths: Vec<usize> = outputs.iter().map(|&o| natural_num_length(o)).collect();
    analyse_with_weights(model, derivatives, outputs, &lengths, None)
}

struct Core {
    singular_values: Vec<f64>,
    v: Mat<f64>,
    rank: usize,
    column_norms: Vec<f64>,
}

fn core(
    model: &AeroModel,
    derivatives: &[Derivative],
    outputs: &[TfOutput],
    num_lengths: &[usize],
    whitening: Option<&Mat<f64>>,
) -> Result<Core, AeroError> {
    let values: Vec<f64> = derivatives
        .iter()
        .map(|&d| model.derivatives.get(d))
        .collect();
    let scale = scales(model, derivatives);
    let c0 = model_coefficients(model, outputs, num_lengths)?;
    let w = match whitening {
        Some(w) => w.clone(),
        None => relative_whitening(&c0, num_lengths),
    };
    let n_res = c0.len();
    let p = derivatives.len();
    let h = 1e-6;
    let mut jac = Mat::<f64>::zeros(n_res.max(p), p);
    for k in 0..p {
        let mut up = values.clone();
        let mut dn = values.clone();
        up[k] += h * scale[k];
        dn[k] -= h * scale[k];
        let cu = model_coefficients(&with_values(model, derivatives, &up), outputs, num_lengths)?;
        let cd = model_coefficients(&with_values(model, derivatives, &dn), outputs, num_lengths)?;
        let dc: Vec<f64> = cu
            .iter()
            .zip(&cd)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        for i in 0..n_res {
            jac[(i, k)] = (0..n_res).map(|j| w[(i, j)] * dc[j]).sum();
        }
    }
    // Rows beyond n_res stay zero so that the full V exists even with fewer coefficients than derivatives.
    let svd = jac
        .svd()
        .map_err(|_| AeroError::Numerical("SVD of the identifiability Jacobian"))?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let rank = numerical_rank(&s, NULL_TOLERANCE);
    let column_norms = (0..p)
        .map(|k| {
            (0..n_res)
                .map(|i| jac[(i, k)] * jac[(i, k)])
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    Ok(Core {
        singular_values: s[..p.min(s.len())].to_vec(),
        v: svd.V().to_owned(),
        rank,
        column_norms,
    })
}

fn verdict_of(core: &Core, k: usize, derivatives: &[Derivative], scale: &[f64]) -> Verdict {
    let p = derivatives.len();
    let s_max = core.singular_values.first().copied().unwrap_or(0.0);
    if core.column_norms[k] <= 1e-12 * s_max.max(1e-300) {
        return Verdict::Absent;
    }
    let null_share: f64 = (core.rank..p)
        .map(|i| core.v[(k, i)] * core.v[(k, i)])
        .sum::<f64>()
        .sqrt();
    if null_share > NULL_SHARE {
        // Partners: derivatives that move with this one along the null direction(s), largest first.
        // share_j = relative change of j that accompanies +1 % of k along k's null-space projection.
        let mut partners: Vec<(usize, f64)> = (0..p)
            .filter(|&j| j != k)
            .filter(|&j| (core.rank..p).any(|i| core.v[(j, i)].abs() > NULL_SHARE))
            .map(|j| {
                let dot: f64 = (core.rank..p)
                    .map(|i| core.v[(j, i)] * core.v[(k, i)])
                    .sum();
                (j, dot / (null_share * null_share))
            })
            .collect();
        partners.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let combination = if p - core.rank == 1 && partners.len() == 1 {
            // One null direction n (physical δp = s ⊙ v): p_k − (n_k/n_j) p_j is invariant.
            let j = partners[0].0;
            let nk = core.v[(k, core.rank)] * scale[k];
            let nj = core.v[(j, core.rank)] * scale[j];
            let c = -nk / nj;
            format!(
                "{} {} {:.4}·{}",
                derivatives[k].name(),
                if c >= 0.0 { "+" } else { "−" },
                c.abs(),
                derivatives[j].name()
            )
        } else {
            let shown: Vec<String> = partners
                .iter()
                .filter(|(_, share)| share.abs() >= 0.01)
                .take(5)
                .map(|&(j, share)| format!("{} {:+.2} %", derivatives[j].name(), share))
                .collect();
            format!(
                "a combination: +1 % on {} is invisible when accompanied by {}{}",
                derivatives[k].name(),
                if shown.is_empty() {
                    "small changes".to_string()
                } else {
                    shown.join(", ")
                },
                if partners.len() > shown.len() {
                    " and smaller changes of others"
                } else {
                    ""
                }
            )
        };
        let partners = partners.into_iter().map(|(j, _)| derivatives[j]).collect();
        return Verdict::Combination {
            partners,
            combination,
        };
    }
    let relative_std = (0..core.rank)
        .map(|i| (core.v[(k, i)] / core.singular_values[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    let weak = relative_std > WEAK_RELATIVE_STD;
    let partner = if weak {
        // Correlation of the estimates from (JᵀJ)⁺ = V Σ⁻² Vᵀ over the determined subspace.
        let cov = |a: usize, b: usize| -> f64 {
            (0..core.rank)
                .map(|i| core.v[(a, i)] * core.v[(b, i)] / core.singular_values[i].powi(2))
                .sum()
        };
        (0..p)
            .filter(|&j| j != k)
            .map(|j| (j, cov(k, j) / (cov(k, k) * cov(j, j)).sqrt()))
            .filter(|(_, rho)| rho.is_finite())
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
    } else {
        None
    };
    weak_or_determined(weak, relative_std, partner, derivatives)
}

/// [`Verdict::Weak`] (naming the most correlated estimate `partner` = (index, ρ) when |ρ| is above
/// [`HIGH_CORRELATION`]) or [`Verdict::Determined`].
fn weak_or_determined(
    weak: bool,
    relative_std: f64,
    partner: Option<(usize, f64)>,
    derivatives: &[Derivative],
) -> Verdict {
    if weak {
        let correlated_with = partner
            .filter(|(_, rho)| rho.abs() > HIGH_CORRELATION)
            .map(|(j, rho)| (derivatives[j], rho));
        Verdict::Weak {
            relative_std,
            correlated_with,
        }
    } else {
        Verdict::Determined { relative_std }
    }
}

/// Pairwise correlation above which two estimates, one of them with a relative standard error above
/// [`WEAK_RELATIVE_SE`], are reported only as a combination: at |ρ| = 0.8 the partner's uncertainty already
/// makes up 64 % of this estimate's variance (ρ² of it, Morelli & Klein §5.4), so a poorly determined partner
/// drags this estimate with it.
const COMBINATION_CORRELATION: f64 = HIGH_CORRELATION;
/// Relative standard error σ/|estimate| above which an estimate is weakly determined (20 %: its 3σ interval
/// spans more than ±60 % of the value).
const WEAK_RELATIVE_SE: f64 = 0.2;

/// Numerical rank from singular values `s` (largest first): how many exceed `tolerance` times the largest
/// (none when the largest is not positive).
pub(super) fn numerical_rank(s: &[f64], tolerance: f64) -> usize {
    let s_max = s.first().copied().unwrap_or(0.0);
    s.iter()
        .filter(|&&x| x > tolerance * s_max && s_max > 0.0)
        .count()
}

/// Pseudo-inverse of a symmetric positive semi-definite matrix (eigenvalues below 1e-12 of the largest dropped).
fn pinv_symmetric(m: &Mat<f64>) -> Result<Mat<f64>, AeroError> {
    let n = m.nrows();
    let svd = m
        .svd()
        .map_err(|_| AeroError::Numerical("SVD of the information matrix"))?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let s_max = s.first().copied().unwrap_or(0.0);
    let (u, v) = (svd.U(), svd.V());
    Ok(Mat::from_fn(n, n, |a, b| {
        (0..s.len())
            .filter(|&i| s[i] > 1e-12 * s_max)
            .map(|i| v[(a, i)] * u[(b, i)] / s[i])
            .sum()
    }))
}

/// Data-based verdict of estimate `k` from the covariance of the scaled parameters (see [`assess_estimate`]).
fn data_verdict(
    cov_z: &Mat<f64>,
    k: usize,
    derivatives: &[Derivative],
    values: &[f64],
    scale: &[f64],
) -> Verdict {
    let phys = |a: usize, b: usize| cov_z[(a, b)] * scale[a] * scale[b];
    let rse = |a: usize| {
        let mag = if values[a].abs() > 1e-12 {
            values[a].abs()
        } else {
            scale[a]
        };
        phys(a, a).max(0.0).sqrt() / mag
    };
    let relative_std = rse(k);
    let partner = (0..derivatives.len())
        .filter(|&j| j != k && phys(j, j) > 0.0 && phys(k, k) > 0.0)
        .map(|j| (j, phys(k, j) / (phys(k, k) * phys(j, j)).sqrt()))
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    if let Some((j, rho)) = partner {
        if rho.abs() >= COMBINATION_CORRELATION && relative_std.max(rse(j)) > WEAK_RELATIVE_SE {
            // The minimum-variance combination p_k + c p_j: c = −Cov(k, j)/Var(j).
            let c = -phys(k, j) / phys(j, j);
            let var = phys(k, k) + 2.0 * c * phys(k, j) + c * c * phys(j, j);
            return Verdict::Correlated {
                partner: derivatives[j],
                rho,
                relative_std,
                combination: format!(
                    "{} {} {:.4}·{}",
                    derivatives[k].name(),
                    if c >= 0.0 { "+" } else { "−" },
                    c.abs(),
                    derivatives[j].name()
                ),
                value: values[k] + c * values[j],
                std_error: var.max(0.0).sqrt(),
            };
        }
    }
    weak_or_determined(
        relative_std > WEAK_RELATIVE_SE,
        relative_std,
        partner,
        derivatives,
    )
}

/// Re-judges the verdicts of `report` at an estimate, from the estimate's own covariance: the honest
/// identifiability at the identified transfer functions' actual uncertainty, not only the noise-free Jacobian.
///
/// With J the whitened Jacobian of the coefficients with respect to the scaled parameters z (p = p₀ + s ⊙ z),
/// Cov(ẑ) = σ² (JᵀJ)⁺ (Gauss–Newton; Morelli & Klein eq. 6.20 for output error, the same form as the
/// least-squares eq. 5.12), and ρ_kj = Cov_kj/√(Cov_kk Cov_jj). A derivative structurally determined is then
/// - "only as a combination" when |ρ| ≥ 0.9 with a partner and either has σ/|p̂| > 20 %, with the
///   minimum-variance combination p_k − (Cov_kj/Cov_jj) p_j and its estimate;
/// - weak when σ/|p̂| > 20 %;
/// - determined otherwise.
///
/// For every verdict short of "determined", each unused output/input pair of the axis is added as a
/// hypothetical extra measurement of the same relative quality (`coefficient_rel_std` on each of its
/// coefficients), the information matrix is updated, I = JᵀJ/σ² + J_oᵀW_oJ_o, and the verdict re-judged: the
/// pairs that make the derivative determined are the measurements that would separate it (a numerical check,
/// not an assertion).
pub(crate) fn assess_estimate(
    report: &mut IdentifiabilityReport,
    model: &AeroModel,
    values: &[f64],
    scale: &[f64],
    information_z: &Mat<f64>,
    coefficient_rel_std: &[(Axis, f64)],
) -> Result<(), AeroError> {
    let derivatives = report.derivatives.clone();
    let p = derivatives.len();
    let cov_z = pinv_symmetric(information_z)?;
    report.correlation = (0..p)
        .map(|a| {
            (0..p)
                .map(|b| cov_z[(a, b)] / (cov_z[(a, a)] * cov_z[(b, b)]).sqrt())
                .collect()
        })
        .collect();
    let candidates = unused_outputs(&report.outputs);
    // Whitened Jacobian of each candidate's coefficients, z units, weights 1/(ε |c|).
    let h = 1e-6;
    let mut extra_info = Vec::with_capacity(candidates.len());
    for &o in &candidates {
        let len = natural_num_length(o);
        let eps = coefficient_rel_std
            .iter()
            .find(|(a, _)| *a == o.axis)
            .map_or(f64::NAN, |x| x.1);
        let c0 = model_coefficients(model, &[o], &[len])?;
        let w = relative_whitening(&c0, &[len]);
        let mut jac = Mat::<f64>::zeros(c0.len(), p);
        for k in 0..p {
            let mut up = values.to_vec();
            let mut dn = values.to_vec();
            up[k] += h * scale[k];
            dn[k] -= h * scale[k];
            let cu = model_coefficients(&with_values(model, &derivatives, &up), &[o], &[len])?;
            let cd = model_coefficients(&with_values(model, &derivatives, &dn), &[o], &[len])?;
            for i in 0..c0.len() {
                jac[(i, k)] = w[(i, i)] * (cu[i] - cd[i]) / (2.0 * h) / eps;
            }
        }
        extra_info.push(jac.transpose() * &jac);
    }
    for k in 0..p {
        let structural = &report.verdicts[k].verdict;
        if !matches!(
            structural,
            Verdict::Determined { .. } | Verdict::Weak { .. }
        ) {
            continue;
        }
        let verdict = data_verdict(&cov_z, k, &derivatives, values, scale);
        let name = derivatives[k].name();
        let explanation = match &verdict {
            Verdict::Determined { relative_std } => format!(
                "determined: relative standard error {:.1} % at the identified transfer functions' uncertainty.",
                100.0 * relative_std
            ),
            Verdict::Weak {
                relative_std,
                correlated_with,
            } => {
                let mut t = format!(
                    "weakly determined: relative standard error {:.0} % at the identified transfer functions' \
                     uncertainty.",
                    100.0 * relative_std
                );
                if let Some((other, rho)) = correlated_with {
                    let _ = write!(t, " Correlated with {other} (ρ = {rho:+.3}).");
                }
                t
            }
            Verdict::Correlated {
                partner,
                rho,
                relative_std,
                combination,
                value,
                std_error,
            } => format!(
                "only as a combination: its estimate is correlated with {partner} (ρ = {rho:+.3}; σ/|{name}| = \
                 {:.0} %), so the data fix only {combination} = {value:.4} ± {std_error:.4} (1σ).",
                100.0 * relative_std
            ),
            _ => unreachable!("data_verdict gives Determined, Weak or Correlated"),
        };
        let mut separated_by = Vec::new();
        if !matches!(verdict, Verdict::Determined { .. }) {
            let words = |info: &Mat<f64>, what: String| -> Result<Option<String>, AeroError> {
                let cz = pinv_symmetric(info)?;
                Ok(match data_verdict(&cz, k, &derivatives, values, scale) {
                    Verdict::Determined { relative_std } => Some(format!(
                        "{what} (σ/|{name}| {:.0} % → {:.1} %)",
                        100.0 * rse_of(&verdict),
                        100.0 * relative_std
                    )),
                    _ => None,
                })
            };
            let own: Vec<usize> = (0..candidates.len())
                .filter(|&c| {
                    (candidates[c].axis == Axis::Longitudinal) == derivatives[k].is_longitudinal()
                })
                .collect();
            for &c in &own {
                let total = information_z + &extra_info[c];
                if let Some(w) = words(&total, measurement_words(candidates[c]))? {
                    separated_by.push(w);
                }
            }
            if separated_by.is_empty() {
                // No single extra measurement suffices: pairs of them.
                for (x, &a) in own.iter().enumerate() {
                    for &b in &own[x + 1..] {
                        let total = &(information_z + &extra_info[a]) + &extra_info[b];
                        let what = format!(
                            "{} together with {}",
                            measurement_words(candidates[a]),
                            measurement_words(candidates[b])
                        );
                        if separated_by.len() < 3 {
                            if let Some(w) = words(&total, what)? {
                                separated_by.push(w);
                            }
                        }
                    }
                }
            }
            if separated_by.is_empty() && !own.is_empty() {
                let mut total = information_z.clone();
                for &c in &own {
                    total = &total + &extra_info[c];
                }
                let all = own
                    .iter()
                    .map(|&c| candidates[c].label())
                    .collect::<Vec<_>>()
                    .join(" + ");
                if let Some(w) = words(&total, format!("all of {all}"))? {
                    separated_by.push(w);
                }
            }
        }
        let mut explanation = explanation;
        if separated_by.is_empty() && !matches!(verdict, Verdict::Determined { .. }) {
            explanation.push_str(
                " No extra transfer function of the same quality separates it (checked: every unused \
                 output/input pair of its axis alone, in pairs and all together).",
            );
        }
        report.verdicts[k] = DerivativeVerdict {
            derivative: derivatives[k],
            verdict,
            explanation,
            separated_by,
        };
    }
    Ok(())
}

/// Candidate extra measurements: every output/input pair of the axes in `outputs` that is not used yet.
fn unused_outputs(outputs: &[TfOutput]) -> Vec<TfOutput> {
    let mut axes: Vec<Axis> = outputs.iter().map(|o| o.axis).collect();
    axes.dedup();
    axes.iter()
        .flat_map(|&axis| {
            (0..4).flat_map(move |state| {
                (0..axis.input_names().len()).map(move |input| TfOutput { axis, state, input })
            })
        })
        .filter(|o| !outputs.contains(o))
        .collect()
}

fn rse_of(v: &Verdict) -> f64 {
    match v {
        Verdict::Determined { relative_std }
        | Verdict::Weak { relative_std, .. }
        | Verdict::Correlated { relative_std, .. } => *relative_std,
        _ => f64::NAN,
    }
}

/// Numerator length that covers the model: attitude outputs (θ, φ) have relative degree 2 (3 coefficients),
/// every other state relative degree 1 (4 coefficients).
fn natural_num_length(o: TfOutput) -> usize {
    if o.state == 3 {
        3
    } else {
        4
    }
}

fn measurement_words(o: TfOutput) -> String {
    let what = match (o.axis, o.state) {
        (Axis::Longitudinal, 0) => "airspeed (u)",
        (Axis::Longitudinal, 1) => "angle of attack (α)",
        (Axis::Longitudinal, 2) => "pitch rate (q)",
        (Axis::Longitudinal, _) => "pitch attitude (θ)",
        (Axis::Lateral, 0) => "sideslip (β)",
        (Axis::Lateral, 1) => "roll rate (p)",
        (Axis::Lateral, 2) => "yaw rate (r)",
        (Axis::Lateral, _) => "bank angle (φ)",
    };
    format!(
        "{what} response to {} ({})",
        o.axis.input_names()[o.input],
        o.label()
    )
}

/// The analysis with an explicit whitening matrix (used by the fit, whose weights come from the data).
pub(crate) fn analyse_with_weights(
    model: &AeroModel,
    derivatives: &[Derivative],
    outputs: &[TfOutput],
    num_lengths: &[usize],
    whitening: Option<&Mat<f64>>,
) -> Result<IdentifiabilityReport, AeroError> {
    if derivatives.is_empty() || outputs.is_empty() {
        return Err(AeroError::NothingToFit(
            "identifiability needs derivatives and transfer functions".into(),
        ));
    }
    let scale = scales(model, derivatives);
    let c = core(model, derivatives, outputs, num_lengths, whitening)?;
    let p = derivatives.len();
    let null_space = (c.rank..p)
        .map(|i| {
            let dp: Vec<f64> = (0..p).map(|k| c.v[(k, i)] * scale[k]).collect();
            let m = dp
                .iter()
                .fold(0.0f64, |m, x| if x.abs() > m.abs() { *x } else { m });
            dp.iter().map(|x| x / m).collect()
        })
        .collect();

    let candidates = unused_outputs(outputs);
    // The core with further measured transfer functions (full numerators), unwhitened.
    let core_adding = |extra: &[TfOutput]| {
        let mut outs = outputs.to_vec();
        outs.extend(extra);
        let mut lens = num_lengths.to_vec();
        lens.extend(extra.iter().map(|&o| natural_num_length(o)));
        core(model, derivatives, &outs, &lens, None)
    };

    let mut verdicts = Vec::with_capacity(p);
    for k in 0..p {
        let verdict = verdict_of(&c, k, derivatives, &scale);
        let name = derivatives[k].name();
        let explanation = match &verdict {
            Verdict::Determined { relative_std } => format!(
                "determined (a 1 % coefficient error moves it by about {:.2} %).",
                relative_std
            ),
            Verdict::Weak {
                relative_std,
                correlated_with,
            } => {
                let mut text = format!(
                    "weakly determined: a 1 % coefficient error moves it by about {relative_std:.0} %."
                );
                if let Some((other, rho)) = correlated_with {
                    let _ = write!(
                        text,
                        " Its estimate is correlated with {other} (ρ = {rho:+.3}): in practice only \
                         their combination is reliable."
                    );
                }
                text
            }
            Verdict::Combination { combination, .. } => {
                if combination.starts_with("a combination") {
                    format!("not determined alone; {combination}.")
                } else {
                    format!("not determined alone; only {combination} is determined.")
                }
            }
            Verdict::Absent => format!("{name} does not enter these transfer functions."),
            Verdict::Correlated { .. } => {
                unreachable!("only assess_estimate judges by correlation")
            }
        };
        let mut separated_by = Vec::new();
        if !matches!(verdict, Verdict::Determined { .. }) {
            for &extra in &candidates {
                let ce = core_adding(&[extra])?;
                match verdict_of(&ce, k, derivatives, &scale) {
                    Verdict::Determined { .. } => separated_by.push(measurement_words(extra)),
                    Verdict::Weak { .. } => {
                        separated_by.push(format!("{} (weakly)", measurement_words(extra)))
                    }
                    _ => {}
                }
            }
            if separated_by.is_empty() && !candidates.is_empty() {
                // No single extra measurement suffices: try them all together.
                let ce = core_adding(&candidates)?;
                let all = candidates
                    .iter()
                    .map(|o| o.label())
                    .collect::<Vec<_>>()
                    .join(" + ");
                match verdict_of(&ce, k, derivatives, &scale) {
                    Verdict::Determined { .. } => separated_by.push(format!("all of {all}")),
                    Verdict::Weak { .. } => separated_by.push(format!("all of {all} (weakly)")),
                    _ => {}
                }
            }
        }
        verdicts.push(DerivativeVerdict {
            derivative: derivatives[k],
            verdict,
            explanation,
            separated_by,
        });
    }
    Ok(IdentifiabilityReport {
        derivatives: derivatives.to_vec(),
        outputs: outputs.to_vec(),
        singular_values: c.singular_values,
        null_space,
        verdicts,
        correlation: Vec::new(),
    })
}

#[cfg(test)]
#[path = "identifiability_tests.rs"]
mod tests;
