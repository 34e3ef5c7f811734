//! Tests of `attribution`.

use super::*;
use crate::aero::fit::IdentifiedTf;
use crate::aero::model::tests::c172x_model;
use crate::aero::model::TfOutput;
use crate::aero::regression::RegressionTerm;
use crate::study::spec::full_assumptions;

/// Normal-equation solve (a different path from the SVD in `ls_solve`), for checking.
fn normal_solve(cols: &[Vec<f64>], y: &[f64]) -> Vec<f64> {
    let p = cols.len();
    let a = Mat::from_fn(p, p, |i, j| {
        cols[i]
            .iter()
            .zip(&cols[j])
            .map(|(x, z)| x * z)
            .sum::<f64>()
    });
    let b = Mat::from_fn(p, 1, |i, _| {
        cols[i].iter().zip(y).map(|(x, z)| x * z).sum::<f64>()
    });
    let x = faer::prelude::Solve::solve(&a.partial_piv_lu(), &b);
    (0..p).map(|i| x[(i, 0)]).collect()
}

#[test]
fn synthetic_regression_bias_splits_exactly_into_the_nonlinear_terms() {
    // C_m = F1 + F2 with F1 = 2α + 0.5α² and F2 = −δe + 0.3 δe α (PITCH functions, q̄ = S = c̄ = 1), regressed
    // on [1, α, δe]. Truth: C_mα = 2, C_mδe = −1. The LS bias must be exactly the projection of 0.5α² (F1)
    // plus that of 0.3 δe α (F2) (Morelli & Klein eq. 5.8), and the parts must add up to θ̂ − θ.
    let n = 400;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.02).collect();
    let alpha: Vec<f64> = t
        .iter()
        .map(|t| 0.05 * (1.3 * t).sin() + 0.02 * (3.1 * t).cos())
        .collect();
    let de: Vec<f64> = t.iter().map(|t| 0.03 * (2.2 * t).sin().signum()).collect();
    let f1: Vec<f64> = alpha.iter().map(|a| 2.0 * a + 0.5 * a * a).collect();
    let f2: Vec<f64> = de
        .iter()
        .zip(&alpha)
        .map(|(d, a)| -d + 0.3 * d * a)
        .collect();
    let z: Vec<f64> = f1.iter().zip(&f2).map(|(a, b)| a + b).collect();
    let cols = vec![vec![1.0; n], alpha.clone(), de.clone()];
    let theta = normal_solve(&cols, &z);
    let names = ["Cm_0", "Cm_alpha", "Cm_de"];
    let result = RegressionResult {
        coefficient: "Cm",
        terms: names
            .iter()
            .zip(&theta)
            .map(|(nm, v)| RegressionTerm {
                name: nm.to_string(),
                derivative: nm.parse().ok(),
                value: *v,
                std_error: 0.0,
                std_error_colored: 0.0,
            })
            .collect(),
        r_squared: 1.0,
        fit_error_std: 0.0,
        regressors: cols.clone(),
        response: z.clone(),
        considered: Vec::new(),
    };
    let mut rec = data::FlightRecord::new(t.clone());
    rec.push_column("alpha_rad", alpha.clone());
    rec.push_column("beta_rad", vec![0.0; n]);
    rec.push_column("aero/qbar-psf", vec![1.0; n]);
    rec.push_column("aero/coefficient/F1", f1);
    rec.push_column("aero/coefficient/F2", f2);
    let map = |pairs: &[(&str, f64)]| -> BTreeMap<String, f64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    };
    let probe = CoefficientProbe {
        axes: [("F1", "PITCH"), ("F2", "PITCH")]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        base: map(&[("F1", 0.0), ("F2", 0.0)]),
        slopes: [
            ("alpha".to_string(), map(&[("F1", 2.0), ("F2", 0.0)])),
            (
                "surface:elevator".to_string(),
                map(&[("F1", 0.0), ("F2", -1.0)]),
            ),
        ]
        .into_iter()
        .collect(),
        arm_ft: [0.0; 3],
        wing_area_ft2: 1.0,
        span_ft: 1.0,
        chord_ft: 1.0,
        alpha_rad: 0.0,
        beta_rad: 0.0,
        airspeed_fps: 100.0,
        qbar_psf: 1.0,
    };
    let mut truth = Derivatives::default();
    truth.set(Derivative::Cmalpha, 2.0);
    truth.set(Derivative::Cmde, -1.0);
    let options = EquationErrorOptions {
        smooth_regressors: false,
        ..EquationErrorOptions::default()
    };
    let a = attribute_equation_error(&result, &result, &rec, &probe, &truth, &options).unwrap();
    let part = |name: &str| &a.parts.iter().find(|(n, _)| n.starts_with(name)).unwrap().1;
    let b1 = normal_solve(
        &cols,
        &alpha.iter().map(|a| 0.5 * a * a).collect::<Vec<_>>(),
    );
    let b2 = normal_solve(
        &cols,
        &de.iter()
            .zip(&alpha)
            .map(|(d, a)| 0.3 * d * a)
            .collect::<Vec<_>>(),
    );
    for j in 1..3 {
        assert!(
            (part("F1")[j] - b1[j]).abs() < 1e-10,
            "F1 {j}: {} vs {}",
            part("F1")[j],
            b1[j]
        );
        assert!(
            (part("F2")[j] - b2[j]).abs() < 1e-10,
            "F2 {j}: {} vs {}",
            part("F2")[j],
            b2[j]
        );
        // θ̂ − θ = bias(F1) + bias(F2); skew and reconstruction rest cancel (z is exactly Σ F).
        let truth_j = [f64::NAN, 2.0, -1.0][j];
        assert!((theta[j] - truth_j - b1[j] - b2[j]).abs() < 1e-10);
        assert!(
            a.closure()[j].abs() < 1e-12,
            "closure {j}: {}",
            a.closure()[j]
        );
        assert!((part(SKEW)[j] + part("other")[j]).abs() < 1e-12);
        assert!(part(PROBE_MISMATCH)[j].abs() < 1e-12);
    }
    // The rows name the term: C_mα's bias comes from F1's α², C_mδe's from F2's δe·α.
    let rows = equation_rows(std::slice::from_ref(&a));
    let row = |n: &str| rows.iter().find(|r| r.name == n).unwrap();
    assert!(row("Cm_alpha")
        .terms
        .iter()
        .any(|t| t.term.starts_with("F1") && (t.share - b1[1] / a.error[1]).abs() < 1e-9));
    assert!(row("Cm_de").terms.iter().any(|t| t.term.starts_with("F2")));
}

#[test]
fn tf_attribution_adds_up_and_names_the_released_structure() {
    // θ/δe and φ/δa from the full-structure model, fitted with the paper's structure: the parts (each
    // released assumption, the remainder) add up to estimate − truth, and a released assumption carries
    // the error of every derivative it moves by more than 1 %.
    // The truth has every released term (constant-power thrust included), so releasing them all leaves
    // nothing: the remainder is round-off.
    let truth = c172x_model(Assumptions {
        thrust: ThrustModel::ConstantPower,
        ..full_assumptions()
    });
    let tf = |o: TfOutput| {
        let t = truth.transfer_function(o).unwrap();
        IdentifiedTf {
            num: t.num[t.num.len() - 3..].to_vec(),
            den: t.den,
            covariance: None,
        }
    };
    let tfs = IdentifiedTfs::paper(
        Some(tf(TfOutput::THETA_ELEVATOR)),
        Some(tf(TfOutput::PHI_AILERON)),
        None,
    );
    let free = [
        Derivative::Cmalpha,
        Derivative::Cmq,
        Derivative::Cmde,
        Derivative::Clp,
        Derivative::Clda,
        Derivative::Cnbeta,
    ];
    let mut prior = truth.clone();
    prior.assumptions = Assumptions::paper();
    let rows = attribute_tf_fit(&prior, &tfs, None, &free, &truth.derivatives).unwrap();
    for r in &rows {
        let sum: f64 = r.terms.iter().map(|t| t.contribution).sum();
        assert!(
            (sum - r.error).abs() < 1e-9 * r.error.abs().max(1e-6),
            "{}: {sum} vs {}",
            r.name,
            r.error
        );
        let rel = r.error / truth.derivatives.get(r.name.parse().unwrap()).abs();
        if rel.abs() > 0.01 {
            let main = r.main_term().unwrap();
            assert!(main.term.starts_with("structure:"), "{}: {main:?}", r.name);
        }
        let left = r
            .terms
            .iter()
            .find(|t| t.term.starts_with("left after"))
            .unwrap();
        assert!(
            left.contribution.abs() < 1e-5 * truth.derivatives.get(r.name.parse().unwrap()).abs(),
            "{}: {left:?}",
            r.name
        );
    }
}
