//! Tests of `regression.rs`.

#[test]
fn a_response_lagging_half_a_sample_is_fitted_exactly_once_the_regressors_lag_too() {
    // z_k = ½ (x_{k−1} + x_k)·θ, θ = (−1.2, 0.4): what a central difference of Euler-integrated rates sees
    // (the moment of the step before and of this one). Without the lag the slope is biased by the
    // signal's own change per half sample; with it, LS returns θ to round-off.
    let n = 400;
    let x1: Vec<f64> = (0..n).map(|k| (0.07 * k as f64).sin()).collect();
    let x2: Vec<f64> = (0..n).map(|k| (0.031 * k as f64).cos() * 0.5).collect();
    let z: Vec<f64> = (0..n)
        .map(|k: usize| {
            let j = k.saturating_sub(1);
            -1.2 * 0.5 * (x1[j] + x1[k]) + 0.4 * 0.5 * (x2[j] + x2[k])
        })
        .collect();
    let names = vec!["Cm_alpha".to_string(), "Cm_de".to_string()];
    let cols = vec![x1, x2];
    let fit = |lag: bool| {
        let opts = EquationErrorOptions {
            smooth_regressors: false,
            response_lags_half_sample: lag,
            ..EquationErrorOptions::default()
        };
        let r = lesq_smoothed("Cm", &names, &cols, &z, &opts).unwrap();
        (r.terms[0].value, r.terms[1].value)
    };
    let (a, b) = fit(true);
    assert!(
        (a + 1.2).abs() < 1e-12 && (b - 0.4).abs() < 1e-12,
        "{a} {b}"
    );
    let (a, _) = fit(false);
    assert!(
        (a + 1.2).abs() > 1e-4,
        "without the lag the fit is biased: {a}"
    );
    // force equations never lag (their response comes from differentiated velocities)
    let opts = EquationErrorOptions {
        response_lags_half_sample: true,
        ..EquationErrorOptions::default()
    };
    assert!(
        opts.lags_half_sample("Cl") && !opts.lags_half_sample("CL") && !opts.lags_half_sample("CY")
    );
}

use super::*;
use crate::aero::model::tests::{c172x_model, CL_TRIM, RHO_KG_M3, V_M_S};
use crate::aero::model::{AeroModel, LinearModel};
use crate::aero::params::{Assumptions, Derivative as D};

/// RK4 of ẋ = A x + B u(t) with the input evaluated inside the step (a held input would put a half-sample
/// delay between sampled inputs and the central-difference derivative of the sampled states).
fn simulate(lin: &LinearModel, u: &dyn Fn(f64) -> Vec<f64>, t: &[f64]) -> Vec<[f64; 4]> {
    let f = |x: &[f64; 4], time: f64| -> [f64; 4] {
        let uv = u(time);
        std::array::from_fn(|i| {
            (0..4).map(|j| lin.a[(i, j)] * x[j]).sum::<f64>()
                + (0..uv.len()).map(|j| lin.b[(i, j)] * uv[j]).sum::<f64>()
        })
    };
    let add = |x: &[f64; 4], k: &[f64; 4], h: f64| -> [f64; 4] {
        std::array::from_fn(|i| x[i] + h * k[i])
    };
    let dt = t[1] - t[0];
    let mut x = [0.0; 4];
    let mut out = Vec::with_capacity(t.len());
    for &ti in t {
        out.push(x);
        let k1 = f(&x, ti);
        let k2 = f(&add(&x, &k1, dt / 2.0), ti + dt / 2.0);
        let k3 = f(&add(&x, &k2, dt / 2.0), ti + dt / 2.0);
        let k4 = f(&add(&x, &k3, dt), ti + dt);
        x = std::array::from_fn(|i| x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    }
    out
}

/// A smooth doublet: one sine period of amplitude `amp` starting at `t0`, lasting `2 half_s`
/// (continuous, like a surface behind an actuator).
fn doublet(t: f64, t0: f64, half_s: f64, amp: f64) -> f64 {
    if t >= t0 && t < t0 + 2.0 * half_s {
        amp * (std::f64::consts::PI * (t - t0) / half_s).sin()
    } else {
        0.0
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn savitzky_golay_is_exact_on_polynomials_of_its_order_including_the_ends() {
    // A cubic fit differentiates a cubic exactly (to round-off), edges included.
    let dt = 0.02;
    let y: Vec<f64> = (0..200)
        .map(|i| {
            let t = i as f64 * dt;
            0.3 - 1.2 * t + 0.5 * t * t - 0.07 * t * t * t
        })
        .collect();
    let d = savitzky_golay_derivative(&y, dt, 6, 3).unwrap();
    for (i, di) in d.iter().enumerate() {
        let t = i as f64 * dt;
        let exact = -1.2 + t - 0.21 * t * t;
        assert!((di - exact).abs() < 1e-9, "t = {t}: {di} vs {exact}");
    }
}

#[test]
fn savitzky_golay_differentiates_a_sine_with_the_predicted_smoothing_error() {
    let dt = 0.01;
    let w = 2.0 * std::f64::consts::PI;
    let y: Vec<f64> = (0..500).map(|i| (w * i as f64 * dt).sin()).collect();
    let d = savitzky_golay_derivative(&y, dt, 5, 2).unwrap();
    // Symmetric quadratic fit: relative error ≈ ω²Δt² Σj⁴ / (6 Σj²) = 1.17 % for ω = 2π, Δt = 0.01, h = 5.
    for (i, di) in d.iter().enumerate().skip(5).take(490) {
        assert!(
            (di - w * (w * i as f64 * dt).cos()).abs() < 1.3e-2 * w,
            "{i}"
        );
    }
    assert!(savitzky_golay_derivative(&y[..5], dt, 5, 2).is_err());
    assert!(savitzky_golay_derivative(&y, dt, 5, 11).is_err());
}

/// The c172x lateral model (stability axes, no wind-axis drag term so C_Y is the model's own).
fn lateral_model() -> AeroModel {
    c172x_model(Assumptions {
        side_force_rate_terms: true,
        ..Assumptions::paper()
    })
}

/// `model`'s lateral response to an aileron doublet at 1 s and a rudder doublet at 6 s (smooth, 0.05 rad),
/// 50 Hz for 14 s: time, states (β, p, r, φ), aileron and rudder.
fn lateral_record(model: &AeroModel) -> (Vec<f64>, Vec<[f64; 4]>, Vec<f64>, Vec<f64>) {
    let lin = model.lateral().unwrap();
    let dt = 0.02;
    let t: Vec<f64> = (0..700).map(|i| i as f64 * dt).collect();
    let input = |t: f64| vec![doublet(t, 1.0, 0.7, 0.05), doublet(t, 6.0, 1.0, 0.05)];
    let u: Vec<Vec<f64>> = t.iter().map(|&t| input(t)).collect();
    let x = simulate(&lin, &input, &t);
    let da: Vec<f64> = u.iter().map(|v| v[0]).collect();
    let dr: Vec<f64> = u.iter().map(|v| v[1]).collect();
    (t, x, da, dr)
}

/// The channels the lateral equations need, as a flight record: time, (β, p, r), airspeed and
/// (aileron, rudder); the rest absent.
fn lateral_flight<'a>(
    t: &'a [f64],
    [beta, p, r]: [&'a [f64]; 3],
    airspeed_m_s: &'a [f64],
    [da, dr]: [&'a [f64]; 2],
) -> FlightRecord<'a> {
    FlightRecord {
        time_s: t,
        beta_rad: Some(beta),
        p_rad_s: Some(p),
        r_rad_s: Some(r),
        airspeed_m_s: Some(airspeed_m_s),
        aileron_rad: Some(da),
        rudder_rad: Some(dr),
        ..Default::default()
    }
}

#[test]
fn equation_error_on_a_noise_free_lateral_flight_recovers_roll_and_yaw_derivatives() {
    // Noise-free simulated doublets: the regression must return the model's derivatives; the error budget
    // is the Savitzky–Golay derivative of ṗ, ṙ (≈ 1e-3) and small-angle differences (β ≈ 0.03 rad), so 2 %.
    let model = lateral_model();
    let (t, x, da, dr) = lateral_record(&model);
    let col = |k: usize| -> Vec<f64> { x.iter().map(|s| s[k]).collect() };
    let (beta, p, r, phi) = (col(0), col(1), col(2), col(3));
    let v = vec![V_M_S; t.len()];
    let zeros = vec![0.0; t.len()];
    let record = FlightRecord {
        alpha_rad: Some(&zeros),
        phi_rad: Some(&phi),
        theta_rad: Some(&zeros),
        ..lateral_flight(&t, [&beta, &p, &r], &v, [&da, &dr])
    };
    let opts = EquationErrorOptions {
        air_density_kg_m3: RHO_KG_M3,
        g_m_s2: model.flight.g_m_s2,
        max_lag: Some(200),
        ..Default::default()
    };
    let res = equation_error(&record, &model.mass, &model.geometry, &opts).unwrap();
    for d in [
        D::Clbeta,
        D::Clp,
        D::Clr,
        D::Clda,
        D::Cnbeta,
        D::Cnp,
        D::Cnr,
        D::Cnda,
        D::Cndr,
        D::CYbeta,
        D::CYdr,
    ] {
        let term = res.term(d).unwrap_or_else(|| panic!("{d} missing"));
        assert!(
            rel(term.value, model.derivatives.get(d)) < 0.02,
            "{d}: {} vs {}",
            term.value,
            model.derivatives.get(d)
        );
    }
    // Longitudinal equations are skipped with the missing channel named.
    assert!(
        res.skipped
            .iter()
            .any(|(c, why)| *c == "Cm" && why.contains("q_rad_s")),
        "{:?}",
        res.skipped
    );
}

#[test]
fn equation_error_with_sensor_noise_keeps_key_lateral_derivatives_within_15_percent() {
    // Specification on simulated data: Gaussian noise of 0.1° on β and 0.3 °/s on p, r (a
    // MEMS-grade IMU and vane). C_lp, C_lδa, C_nβ, C_nδr within 15 %, and the coloured-residual 3σ
    // interval covers the truth for those four.
    use rand::{rngs::StdRng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let model = lateral_model();
    let (t, x, da, dr) = lateral_record(&model);
    let mut rng = StdRng::seed_from_u64(42);
    let beta_noise = Normal::new(0.0, 0.1f64.to_radians()).unwrap();
    let rate_noise = Normal::new(0.0, 0.3f64.to_radians()).unwrap();
    let beta: Vec<f64> = x
        .iter()
        .map(|s| s[0] + beta_noise.sample(&mut rng))
        .collect();
    let p: Vec<f64> = x
        .iter()
        .map(|s| s[1] + rate_noise.sample(&mut rng))
        .collect();
    let r: Vec<f64> = x
        .iter()
        .map(|s| s[2] + rate_noise.sample(&mut rng))
        .collect();
    let v = vec![V_M_S; t.len()];
    let record = lateral_flight(&t, [&beta, &p, &r], &v, [&da, &dr]);
    let opts = EquationErrorOptions {
        air_density_kg_m3: RHO_KG_M3,
        half_window: 10,
        ..Default::default()
    };
    let res = equation_error(&record, &model.mass, &model.geometry, &opts).unwrap();
    for d in [D::Clp, D::Clda, D::Cnbeta, D::Cndr] {
        let term = res.term(d).unwrap();
        let truth = model.derivatives.get(d);
        assert!(
            rel(term.value, truth) < 0.15,
            "{d}: {} vs {truth}",
            term.value
        );
        assert!(
            (term.value - truth).abs() < 3.0 * term.std_error_colored,
            "{d}: {} ± {} (white {}) vs {truth}",
            term.value,
            term.std_error_colored,
            term.std_error
        );
    }
}

#[test]
fn equation_error_pitch_needs_alpha_dot_to_separate_cm_q_from_cm_alphadot() {
    // Longitudinal doublets on the paper-structure model. With α̇ as a regressor the pitch derivatives
    // come back (C_mα, C_mδe 2 %; see below for C_mq, C_mα̇). Without it, C_mq absorbs C_mα̇ (α̇ ≈ q + Z_α α): the estimate is C_mq + C_mα̇
    // within 3 %, and C_mα is biased by C_mα̇ (c̄/2V) V Z_α — the textbook equation-error trap.
    let model = c172x_model(Assumptions::paper());
    let lin = model.longitudinal().unwrap();
    let dt = 0.01;
    let t: Vec<f64> = (0..1000).map(|i| i as f64 * dt).collect();
    let input = |t: f64| vec![doublet(t, 0.5, 0.3, 0.02) + doublet(t, 4.0, 0.15, -0.01)];
    let de: Vec<f64> = t.iter().map(|&t| input(t)[0]).collect();
    let x = simulate(&lin, &input, &t);
    let alpha0 = 0.0194;
    let v: Vec<f64> = x.iter().map(|s| V_M_S + s[0]).collect();
    let alpha: Vec<f64> = x.iter().map(|s| alpha0 + s[1]).collect();
    let q: Vec<f64> = x.iter().map(|s| s[2]).collect();
    let theta: Vec<f64> = x.iter().map(|s| alpha0 + s[3]).collect();
    let record = FlightRecord {
        time_s: &t,
        alpha_rad: Some(&alpha),
        q_rad_s: Some(&q),
        theta_rad: Some(&theta),
        airspeed_m_s: Some(&v),
        elevator_rad: Some(&de),
        ..Default::default()
    };
    let base = EquationErrorOptions {
        air_density_kg_m3: RHO_KG_M3,
        max_lag: Some(100),
        ..Default::default()
    };
    let d = &model.derivatives;
    let with = equation_error(
        &record,
        &model.mass,
        &model.geometry,
        &EquationErrorOptions {
            include_alphadot: true,
            ..base
        },
    )
    .unwrap();
    for e in &with.equations {
        for t in &e.terms {
            eprintln!("{} {} {} {}", t.name, t.value, t.std_error, e.r_squared);
        }
    }
    let qd = savitzky_golay_derivative(&q, dt, 5, 2).unwrap();
    for i in [40, 60, 80, 100, 200, 400] {
        let exact: f64 =
            (0..4).map(|j| lin.a[(2, j)] * x[i][j]).sum::<f64>() + lin.b[(2, 0)] * de[i];
        eprintln!("qdot {i}: {} vs {}", qd[i], exact);
    }
    let est = |k: D| with.term(k).unwrap().value;
    // C_mα and C_mδe to 2 %; q and α̇ are nearly collinear regressors (α̇ ≈ q + Z_α α): each alone to 10 %,
    // the sum to 2 %.
    for (derivatives, tolerance) in [
        ([D::Cmalpha, D::Cmde], 0.02),
        ([D::Cmq, D::Cmalphadot], 0.10),
    ] {
        for k in derivatives {
            assert!(
                rel(est(k), d.get(k)) < tolerance,
                "{k}: {} vs {}",
                est(k),
                d.get(k)
            );
        }
    }
    let sum = est(D::Cmq) + est(D::Cmalphadot);
    assert!(
        rel(sum, d.get(D::Cmq) + d.get(D::Cmalphadot)) < 0.02,
        "{sum}"
    );
    let without = equation_error(&record, &model.mass, &model.geometry, &base).unwrap();
    let cmq = without.term(D::Cmq).unwrap().value;
    assert!(
        rel(cmq, d.get(D::Cmq) + d.get(D::Cmalphadot)) < 0.03,
        "{cmq}"
    );
    let z_alpha =
        -model.flight.dynamic_pressure_pa() * model.geometry.wing_area_m2 * d.get(D::CLalpha)
            / (model.mass.mass_kg * V_M_S);
    let biased =
        d.get(D::Cmalpha) + d.get(D::Cmalphadot) * model.geometry.chord_m / (2.0 * V_M_S) * z_alpha;
    let cma = without.term(D::Cmalpha).unwrap().value;
    assert!(rel(cma, biased) < 0.03, "{cma} vs {biased}");
    // The lift equation from the kinematics: C_Lα to 3 % (C_L = −Z/(q̄S cos α) neglects D tan α).
    let cla = with.term(D::CLalpha).unwrap().value;
    assert!(rel(cla, d.get(D::CLalpha)) < 0.03, "{cla}");
    let _ = CL_TRIM;
}

#[test]
fn coloured_residual_correction_inflates_errors_only_when_residuals_are_correlated() {
    // z = 2 + 3 x + e with smooth x. White e: both standard errors agree (within 30 %, estimator noise).
    // AR(1) e with pole 0.98: the white formula is optimistic; the corrected one is > 2× larger.
    use rand::{rngs::StdRng, Rng, SeedableRng};
    let n = 2000;
    let x: Vec<f64> = (0..n)
        .map(|i| (i as f64 * 0.01).sin() + 0.5 * (i as f64 * 0.037).cos())
        .collect();
    let mut rng = StdRng::seed_from_u64(7);
    let white: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0) * 0.1).collect();
    let mut ar = vec![0.0; n];
    for i in 1..n {
        ar[i] = 0.98 * ar[i - 1] + white[i];
    }
    let names = vec!["c_0".to_string(), "c_x".to_string()];
    for (e, coloured) in [(&white, false), (&ar, true)] {
        let z: Vec<f64> = (0..n).map(|i| 2.0 + 3.0 * x[i] + e[i]).collect();
        let res = lesq("C", &names, &[vec![1.0; n], x.clone()], &z, None).unwrap();
        let t = &res.terms[1];
        let ratio = t.std_error_colored / t.std_error;
        if coloured {
            assert!(ratio > 2.0, "coloured ratio {ratio}");
        } else {
            assert!((0.7..1.3).contains(&ratio), "white ratio {ratio}");
        }
    }
}

#[test]
fn missing_channels_and_bad_time_are_clear_errors() {
    let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
    let m = c172x_model(Assumptions::paper());
    let error_with_time = |time_s: &[f64]| {
        equation_error(
            &FlightRecord {
                time_s,
                ..Default::default()
            },
            &m.mass,
            &m.geometry,
            &EquationErrorOptions::default(),
        )
        .unwrap_err()
        .to_string()
    };
    let err = error_with_time(&t);
    assert!(err.contains("airspeed_m_s"), "{err}");
    let mut bad = t.clone();
    bad[50] = bad[49];
    let err = error_with_time(&bad);
    assert!(err.contains("uniformly sampled"), "{err}");
}
