//! The dimensional control derivatives that the paper's transfer functions determine on their own
//! truth from the original TF, estimate from the paper's LSM TF and from ours.
//!
//! Şahin & Kalyon 2021 print only TF coefficients, no flight condition, mass, inertia or geometry, so
//! only what one TF fixes exactly can be backed out. With the paper's model (`crate::aero::model`,
//! Z_δe = 0, γ0 = 0) the numerator of an angle over a surface starts at s^(n−2) with
//! C A B (n = 4, C picks θ or φ, B the surface column of the explicit model, CB = 0):
//!
//! - θ/δe: θ̇ = q, so b2 = the q row of B = M_δe + M_α̇ Z_δe/(1 − Z_α̇), which is M_δe when Z_δe = 0
//!   (the paper's Z_δe-free pitch equation; on the c172x the α̇ coupling is tested below to be small), 1/s²;
//! - φ/δa: φ̇ = p (γ0 = 0) and the p row of B = C⁻¹ B_desc is L'_δa = (L_δa + (I_xz/I_xx) N_δa)/(1 − I_xz²/(I_xx I_zz)),
//!   so b2 = L'_δa, 1/s²;
//! - φ/δr: likewise b2 = L'_δr.
//!
//! The lower coefficients and the denominators mix several derivatives each (e.g. a3 of θ/δe is
//! −trace A), so none of them gives a single derivative.

use super::{PaperRun, TfOutcome};
use crate::lti::TransferFunction;
use crate::report::Table;
use serde_json::{json, Value};

/// What the paper leaves out, and so what cannot be formed from its TFs.
pub const PAPER_OMITS: &str = "The paper gives no flight condition (airspeed, dynamic pressure, altitude), \
     mass, inertias (I_xx, I_yy, I_zz, I_xz) or geometry (S, c̄, b), so no nondimensional derivative \
     (C_mδe, C_lδa, C_lδr, C_mα, C_lp, ...) can be formed and the primed L' cannot be split into L and N; \
     only the three dimensional control derivatives M_δe, L'_δa, L'_δr follow exactly from single TFs.";

/// One recoverable derivative: its name, unit and the TF it comes from.
#[derive(Debug, Clone, Copy)]
pub struct DerivativeSpec {
    /// Symbol, e.g. `M_de`.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Key of the paper TF.
    pub tf_key: &'static str,
}

/// The derivatives recoverable from the paper's three TFs, in the paper's order.
pub const DERIVATIVES: [DerivativeSpec; 3] = [
    DerivativeSpec {
        name: "M_de",
        unit: "1/s^2",
        tf_key: "theta/elevator",
    },
    DerivativeSpec {
        name: "L'_da",
        unit: "1/s^2",
        tf_key: "phi/aileron",
    },
    DerivativeSpec {
        name: "L'_dr",
        unit: "1/s^2",
        tf_key: "phi/rudder",
    },
];

/// Coefficient of s^(n−2) of the numerator of a monic n-th order TF (the C A B Markov parameter),
/// 0 when the numerator has lower degree.
pub fn control_derivative(tf: &TransferFunction) -> f64 {
    let n = tf.den.len() - 1;
    let k = n - 2; // power of s
    let m = tf.num.len();
    if m > k {
        tf.num[m - 1 - k] / tf.den[0]
    } else {
        0.0
    }
}

/// Standard error of the s^(n−2) numerator coefficient, when the estimator gave one.
fn control_derivative_std(tf: &TransferFunction, num_std: &[f64]) -> Option<f64> {
    let k = tf.den.len() - 3;
    (num_std.len() == tf.num.len() && num_std.len() > k).then(|| num_std[num_std.len() - 1 - k])
}

/// One estimate of a derivative.
#[derive(Debug, Clone)]
pub struct DerivativeEstimate {
    /// `paper_lsm` or the estimator name.
    pub source: String,
    /// The estimate, or NaN when the estimator failed.
    pub value: f64,
    /// Its standard error, if known.
    pub std: Option<f64>,
    /// |estimate − truth| / |truth|.
    pub rel_error: f64,
}

/// One row of the derivative table.
#[derive(Debug, Clone)]
pub struct DerivativeRow {
    /// Which derivative.
    pub spec: DerivativeSpec,
    /// Value from the original TF.
    pub truth: f64,
    /// Paper LSM first, then each of our estimators.
    pub estimates: Vec<DerivativeEstimate>,
}

fn row_for(spec: DerivativeSpec, t: &TfOutcome) -> DerivativeRow {
    let truth = control_derivative(&t.tf.original);
    let rel = |v: f64| (v - truth).abs() / truth.abs();
    let paper = control_derivative(&t.tf.paper_lsm);
    let mut estimates = vec![DerivativeEstimate {
        source: "paper_lsm".into(),
        value: paper,
        std: None,
        rel_error: rel(paper),
    }];
    for m in &t.methods {
        let (value, std) = match &m.result {
            Ok(r) => (
                control_derivative(&r.tf),
                control_derivative_std(&r.tf, &r.num_std),
            ),
            Err(_) => (f64::NAN, None),
        };
        estimates.push(DerivativeEstimate {
            source: m.method.name().into(),
            value,
            std,
            rel_error: rel(value),
        });
    }
    DerivativeRow {
        spec,
        truth,
        estimates,
    }
}

/// The recoverable derivatives of a run: truth (original TF), the paper's LSM and each estimator.
pub fn derivative_rows(run: &PaperRun) -> Vec<DerivativeRow> {
    DERIVATIVES
        .iter()
        .filter_map(|spec| {
            run.tfs
                .iter()
                .find(|t| t.tf.key == spec.tf_key)
                .map(|t| row_for(*spec, t))
        })
        .collect()
}

/// Table 1 + Table 3 in one: truth vs estimate per derivative, with relative error (and 3σ check when a
/// standard error exists).
pub fn derivative_table(run: &PaperRun) -> Table {
    let rows = derivative_rows(run);
    let mut header = vec![
        "derivative".to_string(),
        "unit".into(),
        "from".into(),
        "original".into(),
    ];
    if let Some(r) = rows.first() {
        for e in &r.estimates {
            let name = if e.source == "paper_lsm" {
                "paper LSM".to_string()
            } else {
                e.source.clone()
            };
            header.push(name);
            header.push("err %".into());
            if e.source != "paper_lsm" {
                header.push("in 3σ".into());
            }
        }
    }
    let body = rows
        .iter()
        .map(|r| {
            let mut row = vec![
                r.spec.name.to_string(),
                r.spec.unit.into(),
                format!("{} b2", r.spec.tf_key),
                format!("{:.4}", r.truth),
            ];
            for e in &r.estimates {
                if e.value.is_finite() {
                    row.push(format!("{:.6}", e.value));
                    row.push(format!("{:.5}", 100.0 * e.rel_error));
                } else {
                    row.push("failed".into());
                    row.push("-".into());
                }
                if e.source != "paper_lsm" {
                    row.push(match e.std {
                        Some(s) if e.value.is_finite() => {
                            if (e.value - r.truth).abs() <= 3.0 * s {
                                "yes".into()
                            } else {
                                "NO".into()
                            }
                        }
                        _ => "-".into(),
                    });
                }
            }
            row
        })
        .collect();
    Table {
        caption:
            "Dimensional control derivatives recoverable from the paper's TFs — Table 1 (truth vs \
                  estimate) and Table 3 (error %); truth = the original TF's numerator b2"
                .into(),
        header,
        rows: body,
    }
}

/// JSON for the `derivatives` key: the rows and the sentence on what the paper leaves out.
pub fn derivatives_json(run: &PaperRun) -> Value {
    let rows: Vec<Value> = derivative_rows(run)
        .iter()
        .map(|r| {
            let mut est = serde_json::Map::new();
            for e in &r.estimates {
                est.insert(
                    e.source.clone(),
                    json!({
                        "value": if e.value.is_finite() { json!(e.value) } else { Value::Null },
                        "std": e.std,
                        "rel_error": if e.rel_error.is_finite() { json!(e.rel_error) } else { Value::Null },
                    }),
                );
            }
            json!({
                "name": r.spec.name,
                "unit": r.spec.unit,
                "tf": r.spec.tf_key,
                "coefficient": "b2",
                "truth": r.truth,
                "estimates": est,
            })
        })
        .collect();
    json!({"rows": rows, "paper_omits": PAPER_OMITS})
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aero::model;

    #[test]
    fn control_derivative_is_the_s_pow_n_minus_2_numerator_coefficient() {
        // θ/δe of eq. 65: b2 = −24.7885 → M_δe = −24.7885 1/s².
        let tf = TransferFunction::new(
            vec![-24.7885, -18.2186, -0.4659],
            vec![1.0, 2.0072, 32.5269, 0.8638, 0.0179],
        );
        assert_eq!(control_derivative(&tf), -24.7885);
        // a numerator of lower degree has no s² term
        let tf = TransferFunction::new(vec![2.0, 1.0], vec![1.0, 1.0, 1.0, 1.0, 1.0]);
        assert_eq!(control_derivative(&tf), 0.0);
    }

    #[test]
    fn b2_of_the_paper_structure_tfs_is_the_explicit_control_column() {
        // The claim of the module doc, checked on the library's paper-structure c172x model: the s² numerator
        // coefficient equals the q (θ/δe) or p (φ/δa, φ/δr) row of B = C⁻¹ B_desc, to rounding (1e-9 relative).
        let m = model::tests::c172x_model(crate::aero::Assumptions::paper());
        let lon = m.longitudinal().unwrap();
        let lat = m.lateral().unwrap();
        let [(_, th), (_, pa), (_, pr)] = m.paper_transfer_functions().unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        assert!(
            close(th.num[1], lon.b[(2, 0)]),
            "{} vs {}",
            th.num[1],
            lon.b[(2, 0)]
        );
        assert!(
            close(pa.num[1], lat.b[(1, 0)]),
            "{} vs {}",
            pa.num[1],
            lat.b[(1, 0)]
        );
        assert!(
            close(pr.num[1], lat.b[(1, 1)]),
            "{} vs {}",
            pr.num[1],
            lat.b[(1, 1)]
        );
        // and that row is M_δe itself up to the α̇ coupling M_α̇ Z_δe/(1 − Z_α̇): under 2 % on the c172x
        let m_de = lon.b_desc[(2, 0)];
        let rel = (lon.b[(2, 0)] - m_de).abs() / m_de.abs();
        eprintln!(
            "c172x: q row of B {} vs M_de {m_de} ({:.3} %)",
            lon.b[(2, 0)],
            100.0 * rel
        );
        assert!(rel < 0.02, "{rel}");
    }
}
