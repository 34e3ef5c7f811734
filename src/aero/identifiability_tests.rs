//! Tests of `identifiability`.

use super::*;
use crate::aero::model::tests::c172x_model;
use crate::aero::params::{Assumptions, Derivative as D};

fn lon_paper() -> Vec<D> {
    D::PAPER
        .iter()
        .copied()
        .filter(|d| d.is_longitudinal())
        .collect()
}

fn lat_paper() -> Vec<D> {
    D::PAPER
        .iter()
        .copied()
        .filter(|d| !d.is_longitudinal())
        .collect()
}

fn lift_known() -> Vec<D> {
    vec![D::CD0, D::CDCL2, D::Cmalpha, D::Cmalphadot, D::Cmq, D::Cmde]
}

#[test]
fn theta_elevator_alone_leaves_one_null_direction_and_determines_only_cm_alpha() {
    // θ/δe has 7 coefficients (4 denominator, 3 numerator) for the paper's 8 longitudinal derivatives,
    // so at least one direction is invisible; the analysis must find exactly one and keep Cm_alpha.
    let m = c172x_model(Assumptions::paper());
    let r = analyse_identifiability(&m, &lon_paper(), &[TfOutput::THETA_ELEVATOR]).unwrap();
    assert_eq!(r.null_space.len(), 1, "{}", r.to_text());
    let s = &r.singular_values;
    assert!(s[7] < 1e-12 * s[0] && s[6] > 1e-2 * s[0], "{s:?}");
    assert!(matches!(
        r.verdict(D::Cmalpha).unwrap().verdict,
        Verdict::Determined { .. }
    ));
    for d in [D::Cmq, D::Cmalphadot, D::CLalpha, D::CLde] {
        let v = r.verdict(d).unwrap();
        assert!(
            matches!(v.verdict, Verdict::Combination { .. }),
            "{d}: {}",
            v.explanation
        );
        // An angle-of-attack measurement separates them (the paper's missing C_Mq explained).
        assert!(
            v.separated_by
                .iter()
                .any(|w| w.contains("alpha_rad/elevator_rad")),
            "{d}: {v:?}"
        );
        assert!(
            !v.separated_by.iter().any(|w| w.starts_with("pitch rate")),
            "q = sθ adds nothing: {v:?}"
        );
    }
    // The flagged direction really is invisible: moving 1e-4 along it changes the coefficients
    // at second order only (< 1e-6 of the change along the weakest determined direction).
    let n = &r.null_space[0];
    let free = lon_paper();
    let c0 = crate::aero::coefficients::model_coefficients(&m, &[TfOutput::THETA_ELEVATOR], &[3])
        .unwrap();
    let moved = |dir: &[f64]| {
        let vals: Vec<f64> = free
            .iter()
            .zip(dir)
            .map(|(&d, x)| m.derivatives.get(d) + 1e-4 * x)
            .collect();
        let mm = with_values(&m, &free, &vals);
        let c =
            crate::aero::coefficients::model_coefficients(&mm, &[TfOutput::THETA_ELEVATOR], &[3])
                .unwrap();
        c.iter()
            .zip(&c0)
            .map(|(a, b)| ((a - b) / b.abs().max(1e-12)).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let along_null = moved(n);
    let along_cm_alpha = moved(
        &free
            .iter()
            .map(|&d| if d == D::Cmalpha { 1.0 } else { 0.0 })
            .collect::<Vec<_>>(),
    );
    assert!(
        along_null < 1e-6 * along_cm_alpha.max(1e-3),
        "{along_null} vs {along_cm_alpha}"
    );
}

#[test]
fn with_lift_known_theta_elevator_determines_pitch_derivatives_and_cd_cl2_cm_alphadot_weakly() {
    // C_Lα, C_Lδe from elsewhere (e.g. a lift-curve fit): the remaining 6 are all determined, but a 1 %
    // coefficient error moves C_D_CL2 by ~8 % and C_mα̇ by ~11 %, the latter correlated with C_mq.
    let m = c172x_model(Assumptions::paper());
    let r = analyse_identifiability(&m, &lift_known(), &[TfOutput::THETA_ELEVATOR]).unwrap();
    assert!(r.null_space.is_empty(), "{}", r.to_text());
    for d in [D::Cmalpha, D::Cmde, D::CD0, D::Cmq] {
        assert!(
            matches!(r.verdict(d).unwrap().verdict, Verdict::Determined { .. }),
            "{}",
            r.to_text()
        );
    }
    match &r.verdict(D::CDCL2).unwrap().verdict {
        Verdict::Weak { relative_std, .. } => assert!((5.0..20.0).contains(relative_std)),
        v => panic!("CD_CL2 should be weak: {v:?}"),
    }
    match &r.verdict(D::Cmalphadot).unwrap().verdict {
        Verdict::Weak {
            correlated_with: Some((other, rho)),
            ..
        } => {
            assert_eq!(*other, D::Cmq);
            assert!(rho.abs() > 0.8, "{rho}");
        }
        v => panic!(
            "Cm_alphadot should be weak and correlated with Cm_q: {v:?} {}",
            r.to_text()
        ),
    }
}

#[test]
fn roll_attitude_transfer_functions_leave_two_null_directions_that_sideslip_resolves() {
    // φ/δa and φ/δr: 4 + 3 + 3 = 10 coefficients (the shared denominator counted twice adds no
    // information) for 12 lateral derivatives: two invisible directions; only Cl_da stands alone.
    let m = c172x_model(Assumptions::paper());
    let r = analyse_identifiability(
        &m,
        &lat_paper(),
        &[TfOutput::PHI_AILERON, TfOutput::PHI_RUDDER],
    )
    .unwrap();
    assert_eq!(r.null_space.len(), 2, "{}", r.to_text());
    assert!(matches!(
        r.verdict(D::Clda).unwrap().verdict,
        Verdict::Determined { .. }
    ));
    let cn_beta = r.verdict(D::Cnbeta).unwrap();
    assert!(
        cn_beta.separated_by.iter().any(|w| w.contains("sideslip")),
        "{cn_beta:?}"
    );
    // Adding β and r responses to both inputs determines all twelve.
    let mut outs = vec![TfOutput::PHI_AILERON, TfOutput::PHI_RUDDER];
    for state in [0, 2] {
        for input in [0, 1] {
            outs.push(TfOutput {
                axis: Axis::Lateral,
                state,
                input,
            });
        }
    }
    let r = analyse_identifiability(&m, &lat_paper(), &outs).unwrap();
    assert!(
        r.verdicts
            .iter()
            .all(|v| matches!(v.verdict, Verdict::Determined { .. })),
        "{}",
        r.to_text()
    );
}

#[test]
fn data_verdict_reports_a_highly_correlated_poorly_determined_pair_only_as_its_combination() {
    // Two estimates p = (−16, 1.4), σ = (0.6, 5), ρ = −0.95, in z units with scale 1: the second is 360 %
    // uncertain, the pair only as p₁ + c p₂ with c = −Cov₁₂/Var₂ = 0.95·0.6/5 = 0.114, whose σ is
    // σ₁ √(1 − ρ²) = 0.187; a third, uncorrelated, 2 % estimate stays determined.
    let ders = [D::Cmq, D::Cmalphadot, D::Cmde];
    let values = [-16.0, 1.4, -1.25];
    let scale = [1.0; 3];
    let (s1, s2, s3, rho) = (0.6, 5.0, 0.025, -0.95);
    let cov = Mat::from_fn(3, 3, |a, b| match (a, b) {
        (0, 0) => s1 * s1,
        (1, 1) => s2 * s2,
        (2, 2) => s3 * s3,
        (0, 1) | (1, 0) => rho * s1 * s2,
        _ => 0.0,
    });
    match data_verdict(&cov, 0, &ders, &values, &scale) {
        Verdict::Correlated {
            partner,
            rho: r,
            value,
            std_error,
            ..
        } => {
            assert_eq!(partner, D::Cmalphadot);
            assert!((r - rho).abs() < 1e-12);
            let c = -rho * s1 * s2 / (s2 * s2);
            assert!((value - (values[0] + c * values[1])).abs() < 1e-12);
            assert!((std_error - s1 * (1.0 - rho * rho).sqrt()).abs() < 1e-12);
        }
        v => panic!("{v:?}"),
    }
    assert!(matches!(
        data_verdict(&cov, 1, &ders, &values, &scale),
        Verdict::Correlated { .. }
    ));
    match data_verdict(&cov, 2, &ders, &values, &scale) {
        Verdict::Determined { relative_std } => assert!((relative_std - 0.02).abs() < 1e-12),
        v => panic!("{v:?}"),
    }
}

#[test]
fn lateral_derivative_is_absent_from_the_pitch_transfer_function() {
    let m = c172x_model(Assumptions::paper());
    let r =
        analyse_identifiability(&m, &[D::Cmalpha, D::Clp], &[TfOutput::THETA_ELEVATOR]).unwrap();
    assert_eq!(r.verdict(D::Clp).unwrap().verdict, Verdict::Absent);
    assert!(r.to_text().contains("Cl_p"));
}

#[test]
fn unknown_derivative_name_is_a_clear_error() {
    let err = "Cm_beta_dot".parse::<D>().unwrap_err().to_string();
    assert!(err.contains("Cm_beta_dot") && err.contains("Cm_q"), "{err}");
    assert_eq!("Cn_dr".parse::<D>().unwrap(), D::Cndr);
}
