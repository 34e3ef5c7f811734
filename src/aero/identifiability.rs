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

use super::fit::{model_coefficients, relative_whitening, scales, with_values};
use super::model::{AeroModel, Axis, TfOutput};
use super::params::Derivative;
use super::AeroError;

/// Singular values below this fraction of the largest span the null space.
const NULL_TOLERANCE: f64 = 1e-7;
/// A derivative whose share of the null space exceeds this is not determined on its own.
const NULL_SHARE: f64 = 1e-4;
/// Relative standard deviation per unit relative coefficient error above which a derivative is "weak":
/// a 1 % coefficient error would move it by more than 20 %.
const WEAK_RELATIVE_STD: f64 = 20.0;

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
    },
    /// Only a combination with other derivatives is determined.
    Combination {
        /// The derivatives sharing its null direction(s).
        partners: Vec<Derivative>,
        /// The determined combination in words, e.g. `Cm_q + 1.0000·Cm_alphadot`.
        combination: String,
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
}

impl IdentifiabilityReport {
    /// True if the derivative is determined (strongly or weakly) on its own.
    pub fn is_determined(&self, d: Derivative) -> bool {
        self.verdicts.iter().any(|v| {
            v.derivative == d
                && matches!(v.verdict, Verdict::Determined { .. } | Verdict::Weak { .. })
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
    let s_max = s.first().copied().unwrap_or(0.0);
    let rank = s
        .iter()
        .filter(|&&x| x > NULL_TOLERANCE * s_max && s_max > 0.0)
        .count();
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
        let partners: Vec<Derivative> = (0..p)
            .filter(|&j| j != k)
            .filter(|&j| {
                (core.rank..p)
                    .any(|i| core.v[(j, i)].abs() > NULL_SHARE && core.v[(k, i)].abs() > NULL_SHARE)
            })
            .map(|j| derivatives[j])
            .collect();
        let combination = if p - core.rank == 1 && partners.len() == 1 {
            // One null direction n (physical δp = s ⊙ v): p_k − (n_k/n_j) p_j is invariant.
            let j = derivatives
                .iter()
                .position(|&d| d == partners[0])
                .unwrap_or(k);
            let nk = core.v[(k, core.rank)] * scale[k];
            let nj = core.v[(j, core.rank)] * scale[j];
            let c = -nk / nj;
            format!(
                "{} {} {:.4}·{}",
                derivatives[k].name(),
                if c >= 0.0 { "+" } else { "−" },
                c.abs(),
                partners[0].name()
            )
        } else {
            format!(
                "a combination of {} and {}",
                derivatives[k].name(),
                partners
                    .iter()
                    .map(|d| d.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        return Verdict::Combination {
            partners,
            combination,
        };
    }
    let relative_std = (0..core.rank)
        .map(|i| (core.v[(k, i)] / core.singular_values[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    if relative_std > WEAK_RELATIVE_STD {
        Verdict::Weak { relative_std }
    } else {
        Verdict::Determined { relative_std }
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

    // Candidate extra measurements: every output/input pair of the axes in play that is not used yet.
    let axes: Vec<Axis> = {
        let mut a: Vec<Axis> = outputs.iter().map(|o| o.axis).collect();
        a.dedup();
        a
    };
    let candidates: Vec<TfOutput> = axes
        .iter()
        .flat_map(|&axis| {
            (0..4).flat_map(move |state| {
                (0..axis.input_names().len()).map(move |input| TfOutput { axis, state, input })
            })
        })
        .filter(|o| !outputs.contains(o))
        .collect();

    let mut verdicts = Vec::with_capacity(p);
    for k in 0..p {
        let verdict = verdict_of(&c, k, derivatives, &scale);
        let name = derivatives[k].name();
        let explanation = match &verdict {
            Verdict::Determined { relative_std } => format!(
                "determined (a 1 % coefficient error moves it by about {:.2} %).",
                relative_std
            ),
            Verdict::Weak { relative_std } => format!(
                "weakly determined: a 1 % coefficient error moves it by about {:.0} %.",
                relative_std
            ),
            Verdict::Combination { combination, .. } => {
                format!("not determined alone; only {combination} is determined.")
            }
            Verdict::Absent => format!("{name} does not enter these transfer functions."),
        };
        let mut separated_by = Vec::new();
        if !matches!(verdict, Verdict::Determined { .. }) {
            for &extra in &candidates {
                let mut outs = outputs.to_vec();
                outs.push(extra);
                let mut lens = num_lengths.to_vec();
                lens.push(natural_num_length(extra));
                let ce = core(model, derivatives, &outs, &lens, None)?;
                if matches!(
                    verdict_of(&ce, k, derivatives, &scale),
                    Verdict::Determined { .. }
                ) {
                    separated_by.push(measurement_words(extra));
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
    })
}
