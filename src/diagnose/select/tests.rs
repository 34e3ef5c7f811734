//! Unit tests of the selection's rules.
use super::gates::{beyond_resolution, WITHIN_RESOLUTION};
use super::{beaten_within_resolution, drop_below_resolution, profiled_information, score_test};
use crate::diagnose::extension::make;
use crate::diagnose::search::Active;
use crate::diagnose::{Candidate, NamedCause};

/// The accepted candidate entry of a named effect.
fn accepted(effect: &str, target: &str, value: f64, resolution: f64) -> Candidate {
    Candidate {
        effect: effect.into(),
        target: target.into(),
        value,
        std_error: 0.01,
        cost_before: 100.0,
        cost_after: 50.0,
        criterion: "BIC".into(),
        criterion_delta: -100.0,
        z: 30.0,
        n_eff: 1000.0,
        resolution,
        validation_gain: None,
        rejected_because: None,
        round: 0,
        full_fit: true,
        held_out_share: None,
    }
}

#[test]
fn a_named_effect_a_later_joint_fit_moved_within_its_resolution_is_dropped() {
    let no_coefficients: Vec<String> = Vec::new();
    let gain = make("control_effectiveness", "elevator", &no_coefficients).unwrap();
    let delay = make("input_delay", "rudder", &no_coefficients).unwrap();
    // resolutions 0.1 and 0.02 (the accepted entries'): ×1.02 is within 0.1 of 1 (no effect); a 0.08 s delay is four resolutions from 0.
    let mut selected = vec![
        Active {
            ext: gain.as_ref(),
            params: vec![1.02],
            free: false,
        },
        Active {
            ext: delay.as_ref(),
            params: vec![0.08],
            free: false,
        },
    ];
    let named_as = |e: &str, t: &str, v: f64| NamedCause {
        effect: e.into(),
        target: t.into(),
        value: v,
        std_error: 0.01,
        ambiguous_with: Vec::new(),
    };
    let mut named = vec![
        named_as("control_effectiveness", "elevator", 1.02),
        named_as("input_delay", "rudder", 0.08),
    ];
    let mut candidates = vec![
        accepted("control_effectiveness", "elevator", 1.48, 0.1),
        accepted("input_delay", "rudder", 0.08, 0.02),
    ];
    let dropped = drop_below_resolution(&mut selected, &mut named, &mut candidates);
    assert!(dropped);
    assert_eq!(named.len(), 1);
    assert_eq!(named[0].target, "rudder");
    assert_eq!(selected.len(), 1);
    assert_eq!(selected[0].ext.target(), "rudder");
    let why = candidates[0].rejected_because.as_deref().unwrap_or("");
    assert!(
        why.contains("1.0200") && why.contains("resolution"),
        "{why}"
    );
    assert!(candidates[1].rejected_because.is_none());
    // Nothing left to drop: a second pass changes nothing.
    assert!(!drop_below_resolution(
        &mut selected,
        &mut named,
        &mut candidates
    ));
}

#[test]
fn a_change_must_stand_beyond_its_resolution_by_two_standard_errors() {
    // The turbulent record's a_x scale ×0.963 ± 0.007 against the resolution 0.03: past it, not beyond it.
    assert!(!beyond_resolution(0.963 - 1.0, 0.0066, 0.03));
    assert!(beyond_resolution(0.963 - 1.0, 0.002, 0.03));
    assert!(beyond_resolution(-0.1493, 0.0057, 0.03));
    // A held bias has no σ of its own: its value decides.
    assert!(beyond_resolution(0.3598, f64::NAN, 0.05));
    // A joint fit that leaves a named ×1.13 at σ 0.02 (resolution 0.1) drops it; at σ 0.01 it stays.
    let no_coefficients: Vec<String> = Vec::new();
    let gain = make("control_effectiveness", "rudder", &no_coefficients).unwrap();
    for (std_error, kept) in [(0.02, false), (0.01, true)] {
        let mut selected = vec![Active {
            ext: gain.as_ref(),
            params: vec![1.13],
            free: false,
        }];
        let mut named = vec![NamedCause {
            effect: "control_effectiveness".into(),
            target: "rudder".into(),
            value: 1.13,
            std_error,
            ambiguous_with: Vec::new(),
        }];
        let mut candidates = vec![accepted("control_effectiveness", "rudder", 1.2, 0.1)];
        let dropped = drop_below_resolution(&mut selected, &mut named, &mut candidates);
        assert_eq!(dropped, !kept, "σ {std_error}");
        assert_eq!(named.len(), usize::from(kept), "σ {std_error}");
    }
}

#[test]
fn a_candidate_beaten_by_a_change_within_resolution_is_not_named() {
    // The seed-12 false alarm: Cn_p ×1.058 (within its resolution 0.15) fits better than Cn_da ×0.69.
    let mut within = accepted("aero_derivative", "Cn_p", 1.058, 0.15);
    within.criterion_delta = -325.3;
    within.rejected_because = Some(format!(
        "{WITHIN_RESOLUTION} 0.150 of the effect on this record"
    ));
    let mut cn_da = accepted("aero_derivative", "Cn_da", 0.691, 0.15);
    cn_da.criterion_delta = -268.4;
    let round = vec![within.clone(), cn_da.clone()];
    let why = beaten_within_resolution(&round, &cn_da).unwrap_or_default();
    assert!(why.contains("Cn_p") && why.contains("-325.3"), "{why}");
    // A cause that explains more than every change within resolution is named.
    cn_da.criterion_delta = -400.0;
    assert!(beaten_within_resolution(&round, &cn_da).is_none());
    // Only full fits within resolution count; one rejected for another reason does not.
    let mut other = within;
    other.rejected_because = Some("|z| 3.0 ≤ 5".into());
    cn_da.criterion_delta = -268.4;
    assert!(beaten_within_resolution(&[other, cn_da.clone()], &cn_da).is_none());
}

/// Two channels of four samples each.
const MASK_BOTH: [bool; 2] = [true, true];

#[test]
fn an_offset_carries_no_information_once_offsets_are_nuisance_terms() {
    // A constant on each channel is exactly what the two offsets explain: nothing is left.
    let s = [1.0, 1.0, 1.0, 1.0, -2.0, -2.0, -2.0, -2.0];
    assert!(profiled_information(&s, &[], &MASK_BOTH) < 1e-24);
    // Without the offsets, the whole ‖s‖² = 4 + 16 is information.
    assert!((profiled_information(&s, &[], &[false, false]) - 20.0).abs() < 1e-12);
}

#[test]
fn information_is_the_schur_complement_of_the_information_matrix() {
    // Schur complement I_ss − I_sn² / I_nn for one nuisance column, no offsets:
    // s·s = 1 + 4 + 9 + 16 = 30, s·n = 1 + 2 = 3, n·n = 2 → 30 − 9/2 = 25.5.
    let s = [1.0, 2.0, 3.0, 4.0];
    let n = vec![1.0, 1.0, 0.0, 0.0];
    let i = profiled_information(&s, &[n], &[false]);
    assert!((i - 25.5).abs() < 1e-12, "{i}");
}

#[test]
fn a_parallel_nuisance_column_removes_all_information() {
    let s = [0.5, -1.0, 2.0, 0.0, 1.0, 3.0, -1.0, 0.5];
    let n = s.iter().map(|v| -3.0 * v).collect::<Vec<f64>>();
    assert!(profiled_information(&s, &[n], &[false, false]) < 1e-20);
}

#[test]
fn a_score_test_step_beyond_the_range_is_held_at_the_bound() {
    // An elevator effectiveness (null 1, range 0.1 … 3) whose residual wants a step of +10 (×11):
    // sᵀs = 4, sᵀr = −40. Unbounded the reduction would be (sᵀr)²/sᵀs = 400, the whole cost; held at the bound
    // (step +2) it is sᵀs (2·2·10 − 2²) = 144, and the estimate is the bound.
    let no_coefficients: Vec<String> = Vec::new();
    let gain = make("control_effectiveness", "elevator", &no_coefficients).unwrap();
    let s = [1.0, 1.0, 1.0, 1.0];
    let r = [-10.0, -10.0, -10.0, -10.0];
    let o = score_test(gain.as_ref(), &s, &r, 400.0, 4.0);
    assert!((o.values[0] - 3.0).abs() < 1e-12, "{}", o.values[0]);
    assert!(
        (o.cost_after - (400.0 - 144.0)).abs() < 1e-9,
        "{}",
        o.cost_after
    );
    // A step inside the range is the Gauss–Newton one: −0.5, reduction (−2)²/4 = 1.
    let r = [0.5, 0.5, 0.5, 0.5];
    let o = score_test(gain.as_ref(), &s, &r, 1.0, 4.0);
    assert!((o.values[0] - 0.5).abs() < 1e-12, "{}", o.values[0]);
    assert!(o.cost_after.abs() < 1e-12, "{}", o.cost_after);
}

#[test]
fn a_change_the_held_out_segments_do_not_confirm_is_not_named() {
    use super::gates::{rejection, NOT_HELD_OUT};
    use crate::diagnose::search::FitOutcome;
    use crate::diagnose::DiagnoseOptions;
    let no_coefficients: Vec<String> = Vec::new();
    let gain = make("control_effectiveness", "elevator", &no_coefficients).unwrap();
    // a well-determined, significant fit: one parameter, a sensitivity of 10 on 400 samples
    let o = FitOutcome {
        cost_before: 1000.0,
        cost_after: 500.0,
        values: vec![1.4],
        std_errors: vec![0.01],
        crb_std_errors: vec![0.01],
        n_eff: 400.0,
        sensitivities: vec![vec![10.0; 400]],
        evaluations: 5,
        residual: Vec::new(),
    };
    let mut c = accepted("control_effectiveness", "elevator", 1.4, 0.1);
    c.cost_before = 1000.0;
    c.cost_after = 500.0;
    let opts = DiagnoseOptions::default();
    let mask = vec![false; 1];
    for (share, named) in [
        (None, true),
        (Some(0.9), true),
        (Some(0.0), false),
        (Some(-0.8), false),
    ] {
        c.held_out_share = share;
        let why = rejection(&c, gain.as_ref(), &o, 1000.0, &opts, &mask);
        assert_eq!(why.is_none(), named, "{share:?}: {why:?}");
        if let Some(why) = why {
            assert!(why.starts_with(NOT_HELD_OUT), "{why}");
        }
    }
}

#[test]
fn a_change_the_refit_adds_must_hold_on_the_other_half_of_every_segment() {
    use super::gates::{unconfirmed_in_time, HELD_OUT_CHI2, NOT_HELD_OUT_IN_TIME};
    // one channel of 400 samples, segments starting at 0 and 200; halves [0, 100) ∪ [200, 300) and the rest
    let (len, segments) = (400, [0usize, 200]);
    let wiggle = |k: usize| ((k as f64) * 0.37).sin();
    let first_half = |k: usize| k % 200 < 100;
    // the model misses the same signature everywhere, and the fit removes it: both halves agree
    let everywhere: Vec<f64> = (0..len).map(|k| 2.0 * wiggle(k)).collect();
    let removed = vec![0.0; len];
    // only the first halves depart; the fit moves every sample by the compromise −0.7 w
    let departing: Vec<f64> = (0..len)
        .map(|k| if first_half(k) { 2.0 * wiggle(k) } else { 0.0 })
        .collect();
    let compromise: Vec<f64> = (0..len).map(|k| departing[k] - 0.7 * wiggle(k)).collect();
    for (base, fit, z, named) in [
        (&everywhere, &removed, 6.0, true),
        (&departing, &compromise, 6.0, false),
        // agreed, but the held-out half alone is no evidence: χ² = 1.0 · 2.5² < 6.63
        (&everywhere, &removed, 2.5, false),
    ] {
        let mut c = accepted("sensor_scale", "ax_m_s2", 0.94, 0.02);
        c.z = z;
        let why = unconfirmed_in_time(&mut c, base, fit, &segments, len);
        assert_eq!(why.is_none(), named, "z {z}: {why:?}");
        let share = c.held_out_share.expect("both halves can be held out");
        assert_eq!(share * z * z > HELD_OUT_CHI2, named, "share {share}");
        if let Some(why) = why {
            assert!(why.starts_with(NOT_HELD_OUT_IN_TIME), "{why}");
        }
    }
}

#[test]
fn a_change_one_half_of_the_segments_carries_alone_passes_untested() {
    use super::gates::unconfirmed_in_time;
    // the change lives in the first half of each segment only (an input effect): nothing to size it on elsewhere
    let len = 400;
    let base: Vec<f64> = (0..len)
        .map(|k| {
            if k % 200 < 100 {
                ((k as f64) * 0.37).sin()
            } else {
                0.0
            }
        })
        .collect();
    let mut c = accepted("input_delay", "elevator", 0.08, 0.02);
    assert_eq!(
        unconfirmed_in_time(&mut c, &base, &[0.0; 400], &[0, 200], len),
        None
    );
    assert_eq!(c.held_out_share, None);
}
