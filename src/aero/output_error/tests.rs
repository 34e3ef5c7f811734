//! Tests of `output_error.rs`.

use super::*;
use crate::aero::airframe::SensorPositions;
use crate::aero::params::{Geometry, MassProperties};
use crate::estimate::{simulate_states, InputHold, InputSignal, Run};

/// The parameters of a model started at `starts`, no equation-error fallback, no still surface.
fn started_parameters(
    names: &[&'static str],
    held: &[&str],
    starts: &BTreeMap<String, f64>,
    options: &OutputErrorOptions,
    notes: &mut Vec<String>,
) -> Vec<crate::estimate::Parameter> {
    parameters(
        names,
        held,
        starts,
        &BTreeMap::new(),
        &BTreeSet::new(),
        options,
        notes,
    )
}

fn constants() -> Constants {
    Constants {
        mass: MassProperties {
            mass_kg: 1200.0,
            ixx_kg_m2: 1800.0,
            iyy_kg_m2: 2200.0,
            izz_kg_m2: 3500.0,
            ixz_kg_m2: 60.0,
        },
        geometry: Geometry {
            wing_area_m2: 16.0,
            span_m: 11.0,
            chord_m: 1.5,
        },
        thrust_inclination_rad: 0.0,
        thrust_moment_arm_m: 0.0,
        sensors: SensorPositions {
            imu_m: [0.5, 0.0, 0.2],
            alpha_vane_m: [2.5, 0.0, 0.0],
            beta_vane_m: [2.5, 0.0, 0.0],
        },
        v_ref_m_s: 55.0,
        alpha_ref_rad: 0.0,
        g_m_s2: G0_M_S2,
    }
}

/// Deterministic zero-mean noise of standard deviation `sigma` (sum of 12 uniforms, an LCG).
fn noise(seed: u64, n: usize, sigma: f64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            let mut acc = 0.0;
            for _ in 0..12 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                acc += (s >> 11) as f64 / (1u64 << 53) as f64;
            }
            sigma * (acc - 6.0)
        })
        .collect()
}

/// An elevator 3-2-1-1 of `amp` rad on the trim elevator, unit 0.4 s from 1 s, 50 Hz for 12 s.
fn multistep(n: usize, amp: f64, trim: f64) -> Vec<f64> {
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.02;
            let u = 0.4;
            let s = if (1.0..1.0 + 3.0 * u).contains(&t) {
                1.0
            } else if (1.0 + 3.0 * u..1.0 + 5.0 * u).contains(&t) {
                -1.0
            } else if (1.0 + 5.0 * u..1.0 + 6.0 * u).contains(&t) {
                1.0
            } else if (1.0 + 6.0 * u..1.0 + 7.0 * u).contains(&t) {
                -1.0
            } else {
                0.0
            };
            trim + amp * s
        })
        .collect()
}

/// The longitudinal model simulated with known derivatives, measured with noise at sensors away from the
/// CG, a vane skew and gyro/accelerometer biases, is fitted back: the core and the model agree, so the
/// estimates land within a few σ of the truth (σ of the noise: α 0.05°, q 0.05°/s, a 0.02 m/s²).
#[test]
fn longitudinal_output_error_recovers_the_derivatives_it_simulated() {
    // the vane skew is held by default (the skew check frees it on evidence): free it, as `--free skew`
    recovers(
        &[],
        &["skew"],
        &["CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "tau_alpha_s"],
    );
}

/// A C_m and C_L that curve in α (C_mα² 1.5, C_Lα² 6 about α₀ = 0.05 rad, the trim): with the curvature terms
/// free the fit recovers them and C_mq, and C_mα, C_Lα are the slopes at α₀.
#[test]
fn longitudinal_output_error_recovers_the_curvature_in_alpha() {
    recovers(
        &[("Cm_alpha2", 1.5), ("CL_alpha2", 6.0)],
        &["skew", "curvature"],
        &["CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "Cm_alpha2"],
    );
}

/// The longitudinal model simulated with the derivatives below (and `extra`), fitted back with `free` freed;
/// the `check`ed estimates must lie within 4σ and 3 % of the truth.
fn recovers(extra: &[(&str, f64)], free: &[&str], check: &[&str]) {
    let mut c = constants();
    c.alpha_ref_rad = 0.05;
    let truth: Vec<f64> = LONGITUDINAL_PARAMETERS
        .iter()
        .map(|n| match *n {
            n if extra.iter().any(|(e, _)| *e == n) => {
                extra.iter().find(|(e, _)| *e == n).unwrap().1
            }
            "CL_0" => 0.25,
            "CL_alpha" => 5.2,
            "CL_de" => 0.4,
            "CD_0" => 0.03,
            "CD_alpha" => 0.25,
            "Cm_0" => 0.02,
            "Cm_alpha" => -0.8,
            "Cm_q" => -14.0,
            "Cm_de" => -1.3,
            "tau_alpha_s" => 0.03,
            _ => 0.0,
        })
        .collect();
    let model = LongitudinalModel::new(c, LonOutput::ALL[..6].to_vec(), true, None);
    let n = 600;
    let time_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.02).collect();
    let mut records = Vec::new();
    for (r, amp) in [0.03, -0.025].into_iter().enumerate() {
        let inputs = vec![multistep(n, amp, -0.02), vec![1500.0; n], vec![1.1; n]];
        let run = Run {
            record: r,
            time_s: &time_s,
            input: InputSignal::measured(&time_s, &inputs, InputHold::Linear),
            max_step_s: 0.01,
        };
        let x0 = [55.0, 0.05, 0.05, 0.0];
        let clean = simulate_states(&model, &truth, &x0, &run).unwrap();
        let sigma = [0.1, 0.001, 0.001, 0.001, 0.02, 0.02];
        let bias = [0.0, 0.0, 0.0, 0.002, 0.05, -0.04];
        let outputs = clean
            .iter()
            .enumerate()
            .map(|(o, y)| {
                let e = noise(10 * r as u64 + o as u64, n, sigma[o]);
                y.iter().zip(e).map(|(v, e)| v + e + bias[o]).collect()
            })
            .collect();
        records.push(Record {
            name: format!("rec{r}"),
            time_s: time_s.clone(),
            inputs,
            outputs,
            initial_state: vec![54.0, 0.045, 0.052, 0.003],
        });
    }
    let mut notes = Vec::new();
    let starts: BTreeMap<String, f64> = LONGITUDINAL_PARAMETERS
        .iter()
        .zip(&truth)
        .map(|(n, v)| {
            (
                n.to_string(),
                if n.starts_with("tau") { 0.0 } else { 1.25 * v },
            )
        })
        .collect();
    let options = OutputErrorOptions {
        free: parse_free(&free.iter().map(|f| f.to_string()).collect::<Vec<_>>()).unwrap(),
        ..OutputErrorOptions::default()
    };
    let params = started_parameters(
        &LONGITUDINAL_PARAMETERS,
        &LON_HELD,
        &starts,
        &options,
        &mut notes,
    );
    let nuisance = Nuisance {
        initial_state: (0..4).collect(),
        output_bias: vec![3, 4, 5],
        ..Nuisance::default()
    };
    let fit = fit_model(
        &model,
        &params,
        &records,
        &nuisance,
        &OutputErrorOptions::default(),
        c,
    )
    .unwrap();
    assert!(fit.estimate.converged, "{:?}", fit.estimate.stop);
    for &name in check {
        let k = LONGITUDINAL_PARAMETERS
            .iter()
            .position(|n| *n == name)
            .unwrap();
        let p = fit.estimate.parameter(name).unwrap();
        let err = (p.value - truth[k]).abs();
        // 4σ: a test that fails one run in ~10⁴ when the fit is right, and at once when it is not.
        assert!(
            err < 4.0 * p.std_error && err < 0.03 * truth[k].abs(),
            "{name}: {} ± {} vs {}",
            p.value,
            p.std_error,
            truth[k]
        );
    }
}

#[test]
fn free_lists_name_groups_and_holds() {
    let c = parse_free(&["speed".into(), "-Cm_0".into(), "Cl_r".into()]).unwrap();
    assert_eq!(c[0].names, vec!["CL_V", "CD_V", "Cm_V"]);
    assert!(c[0].free && !c[1].free && c[2].free);
    let e = parse_free(&["Cm_bogus".into()]).unwrap_err();
    assert!(e.contains("Cm_bogus"), "{e}");
}

#[test]
fn the_vertical_gust_states_give_the_dryden_rotary_term_and_scale_length() {
    // q_g = k_q s/(1 + τ_q s) α_g (k_q = 1 here): after a step of α_g the lag ξ follows over τ_q = 4b/(πV) and q_g decays from
    // α_g/τ_q as e^(−t/τ_q); MIL-F-8785C's L_w: the altitude below 1000 ft, 1750 ft above 2000 ft.
    use crate::aero::flight_models::VerticalGust;
    let c = constants();
    let v = 60.0;
    let tau = 4.0 * c.geometry.span_m / (std::f64::consts::PI * v);
    let dt = tau / 2000.0;
    let mut x = [v, 0.05, 0.05, 0.0, 0.01, 0.0];
    let mut theta = vec![0.0; LONGITUDINAL_PARAMETERS.len()];
    theta[LONGITUDINAL_PARAMETERS.len() - 1] = 1.0;
    let q0 = VerticalGust::of(&c, &theta, &x).q_rad_s;
    assert!((q0 - 0.01 / tau).abs() < 1e-12 * q0.abs(), "{q0}");
    for _ in 0..2000 {
        let d = VerticalGust::derivatives(&c, 1e12, &x);
        x[4] += dt * d[0];
        x[5] += dt * d[1];
    }
    let q1 = VerticalGust::of(&c, &theta, &x).q_rad_s;
    assert!((q1 / q0 - (-1.0_f64).exp()).abs() < 1e-3, "{}", q1 / q0);
    assert_eq!(VerticalGust::of(&c, &theta, &x[..4]).q_rad_s, 0.0);
    theta[LONGITUDINAL_PARAMETERS.len() - 1] = 0.0;
    assert_eq!(VerticalGust::of(&c, &theta, &x).q_rad_s, 0.0);
    let ft = 0.3048;
    assert!((VerticalGust::scale_length_m(Some(500.0 * ft)) - 500.0 * ft).abs() < 1e-9);
    assert!((VerticalGust::scale_length_m(Some(6000.0 * ft)) - 1750.0 * ft).abs() < 1e-9);
    assert!((VerticalGust::scale_length_m(None) - 1750.0 * ft).abs() < 1e-9);
}

#[test]
fn in_a_gust_the_flight_path_equations_are_the_body_forces_projected_on_the_inertial_velocity() {
    // The aerodynamics act in the air's axes (α + α_g), the kinematics in the inertial velocity's: V̇ and α̇
    // must be the body specific forces (a_x, a_z at the CG, which the model also outputs) projected on the
    // inertial velocity and its normal, V̇ = a_x cos α + a_z sin α − g sin γ and
    // α̇ = (a_z cos α − a_x sin α)/V + q + g cos γ/V. Held by a 3° gust with thrust on an inclined line and
    // C_Lα̇ free. The wind-axis form with α + α_g throughout (before) missed the lift's push along the path,
    // L sin α_g (about 0.5 m/s² here), and failed it.
    use crate::aero::flight_models::{longitudinal, LonInputs};
    let mut c = constants();
    c.thrust_inclination_rad = 0.04;
    let names = LONGITUDINAL_PARAMETERS;
    let mut theta = vec![0.0; names.len()];
    for (n, v) in [
        ("CL_0", 0.3),
        ("CL_alpha", 5.0),
        ("CL_alphadot", 2.0),
        ("CD_0", 0.03),
        ("CD_alpha", 0.2),
        ("Cm_alpha", -1.0),
        ("Cm_q", -12.0),
    ] {
        theta[names.iter().position(|p| *p == n).unwrap()] = v;
    }
    let (v, alpha, pitch, q, alpha_g) = (55.0, 0.06, 0.08, 0.02, 3f64.to_radians());
    let x = [v, alpha, pitch, q, alpha_g, 0.0];
    let u = LonInputs {
        elevator_rad: -0.02,
        thrust_n: 1800.0,
        density_kg_m3: 1.1,
    };
    let e = longitudinal(&c, &theta, &x, &u);
    let [ax, az] = e.accel_cg;
    let (g, gamma) = (c.g_m_s2, pitch - alpha);
    let vdot = ax * alpha.cos() + az * alpha.sin() - g * gamma.sin();
    let alphadot = (az * alpha.cos() - ax * alpha.sin()) / v + q + g * gamma.cos() / v;
    assert!(
        (e.dx[0] - vdot).abs() < 1e-12,
        "V̇ {} against {vdot}",
        e.dx[0]
    );
    assert!(
        (e.dx[1] - alphadot).abs() < 1e-12,
        "α̇ {} against {alphadot}",
        e.dx[1]
    );
}

/// A lateral flight whose rolling moment carries a propeller's torque reaction, C_lT T with C_lT = −0.5 m
/// (`aero::regression::PROPELLER_TORQUE`), and a thrust that swings with the aileron 0.3 s late (a ±1250 N
/// swing, a quarter of the aileron's moment) plus two slow sines: the same records fitted by output error,
/// and the aileron record by equation error. Both recover C_lT, C_lp and C_lδa; equation error without the
/// term puts C_lp 11 % off (the thrust follows the roll rate the aileron built), so the term is what the fits
/// need.
#[test]
fn the_propeller_torque_term_takes_the_thrust_borne_rolling_moment_off_the_roll_derivatives() {
    use crate::aero::regression::{equation_error, EquationErrorOptions, FlightRecord};
    let c = constants();
    let truth: Vec<f64> = LATERAL_PARAMETERS
        .iter()
        .map(|n| match *n {
            "CY_beta" => -0.6,
            "CY_dr" => 0.15,
            "Cl_beta" => -0.09,
            "Cl_p" => -0.5,
            "Cl_r" => 0.1,
            "Cl_da" => 0.18,
            "Cl_dr" => 0.01,
            "Cn_beta" => 0.07,
            "Cn_p" => -0.03,
            "Cn_r" => -0.1,
            "Cn_da" => -0.01,
            "Cn_dr" => -0.07,
            PROPELLER_TORQUE => -0.5,
            _ => 0.0,
        })
        .collect();
    let outputs = LatOutput::ALL[..5].to_vec();
    let model = LateralModel::new(c, outputs.clone(), true);
    let n = 600;
    let time_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.02).collect();
    let mut records = Vec::new();
    for r in 0..2 {
        let step = multistep(n, 0.05, 0.0);
        let (da, dr) = if r == 0 {
            (step, vec![0.0; n])
        } else {
            (vec![0.0; n], step)
        };
        let thrust: Vec<f64> = (0..n)
            .map(|k| {
                let t = time_s[k];
                let lagged = da[k.saturating_sub(15)];
                2500.0
                    + 25000.0 * lagged
                    + 400.0 * (0.9 * t).sin()
                    + 300.0 * (2.3 * t + r as f64).sin()
            })
            .collect();
        let inputs = vec![
            da,
            dr,
            vec![55.0; n],
            vec![0.05; n],
            vec![0.05; n],
            vec![0.0; n],
            vec![1.1; n],
            thrust,
        ];
        let run = Run {
            record: r,
            time_s: &time_s,
            input: InputSignal::measured(&time_s, &inputs, InputHold::Linear),
            max_step_s: 0.01,
        };
        let clean = simulate_states(&model, &truth, &[0.0; 4], &run).unwrap();
        let sigma = [0.001, 0.001, 0.001, 0.001, 0.02];
        let measured = clean
            .iter()
            .enumerate()
            .map(|(o, y)| {
                let e = noise(100 + 10 * r as u64 + o as u64, n, sigma[o]);
                y.iter().zip(e).map(|(v, e)| v + e).collect()
            })
            .collect();
        records.push(Record {
            name: format!("rec{r}"),
            time_s: time_s.clone(),
            inputs,
            outputs: measured,
            initial_state: vec![0.001, 0.0, 0.0, 0.002],
        });
    }
    let check = |name: &str, value: f64, tolerance: f64| {
        let k = LATERAL_PARAMETERS.iter().position(|n| *n == name).unwrap();
        let err = (value - truth[k]).abs() / truth[k].abs();
        assert!(err < tolerance, "{name}: {value} vs {}", truth[k]);
    };

    // Output error, every parameter but the held ones started 25 % off.
    let starts: BTreeMap<String, f64> = LATERAL_PARAMETERS
        .iter()
        .zip(&truth)
        .map(|(n, v)| (n.to_string(), 1.25 * v))
        .collect();
    let mut notes = Vec::new();
    let options = OutputErrorOptions::default();
    let params = started_parameters(
        &LATERAL_PARAMETERS,
        &LAT_HELD,
        &starts,
        &options,
        &mut notes,
    );
    let nuisance = Nuisance {
        initial_state: (0..4).collect(),
        ..Nuisance::default()
    };
    let fit = fit_model(&model, &params, &records, &nuisance, &options, c).unwrap();
    assert!(fit.estimate.converged, "{:?}", fit.estimate.stop);
    for name in ["Cl_p", "Cl_da", PROPELLER_TORQUE] {
        check(name, fit.estimate.parameter(name).unwrap().value, 0.03);
    }

    // Equation error on the aileron record's states, with and without the term.
    let rec = &records[0];
    let state = |s: usize| -> Vec<f64> {
        let run = Run {
            record: 0,
            time_s: &time_s,
            input: InputSignal::measured(&time_s, &rec.inputs, InputHold::Linear),
            max_step_s: 0.01,
        };
        simulate_states(&model, &truth, &[0.0; 4], &run).unwrap()[s].clone()
    };
    let (beta, p, r) = (state(0), state(1), state(2));
    let flight = FlightRecord {
        time_s: &time_s,
        beta_rad: Some(&beta),
        p_rad_s: Some(&p),
        r_rad_s: Some(&r),
        airspeed_m_s: Some(&rec.inputs[2]),
        aileron_rad: Some(&rec.inputs[0]),
        rudder_rad: Some(&rec.inputs[1]),
        thrust_n: Some(&rec.inputs[7]),
        ..Default::default()
    };
    let roll = |propeller_torque: bool| {
        let opts = EquationErrorOptions {
            air_density_kg_m3: 1.1,
            g_m_s2: c.g_m_s2,
            propeller_torque,
            ..Default::default()
        };
        let res = equation_error(&flight, &c.mass, &c.geometry, &opts).unwrap();
        let cl = res
            .equations
            .iter()
            .find(|e| e.coefficient == "Cl")
            .unwrap();
        let value = |name: &str| cl.terms.iter().find(|t| t.name == name).map(|t| t.value);
        (value("Cl_p"), value("Cl_da"), value(PROPELLER_TORQUE))
    };
    let (clp, clda, clt) = roll(true);
    check("Cl_p", clp.unwrap(), 0.03);
    check("Cl_da", clda.unwrap(), 0.03);
    check(PROPELLER_TORQUE, clt.unwrap(), 0.05);
    let (clp, _, clt) = roll(false);
    assert!(clt.is_none());
    let k = LATERAL_PARAMETERS
        .iter()
        .position(|n| *n == "Cl_p")
        .unwrap();
    assert!(
        (clp.unwrap() - truth[k]).abs() > 0.08 * truth[k].abs(),
        "without the term C_lp {} vs {}",
        clp.unwrap(),
        truth[k]
    );
}

/// A filter-error estimate holding `parameters` (name, fixed, at its bound); the rest is what a converged fit
/// leaves.
fn estimate_with(parameters: &[(&str, bool, bool)]) -> estimate::Estimate {
    estimate::Estimate {
        method: Method::Fem,
        outputs: Vec::new(),
        parameters: parameters
            .iter()
            .map(|&(name, fixed, at_bound)| estimate::ParameterEstimate {
                name: name.to_string(),
                kind: None,
                record: None,
                value: 1.0,
                std_error: if fixed { 0.0 } else { 0.1 },
                std_error_white: if fixed { 0.0 } else { 0.1 },
                t: if fixed { 0.0 } else { 10.0 },
                fixed,
                at_bound,
            })
            .collect(),
        nuisance: Vec::new(),
        free: Vec::new(),
        covariance: Vec::new(),
        correlation: Vec::new(),
        residual_covariance: Vec::new(),
        records: Vec::new(),
        iterations: 5,
        converged: true,
        stop: estimate::StopReason::Converged,
        cost: 0.0,
        cost_history: Vec::new(),
        wall_s: 0.0,
        covariance_method: "",
        warnings: Vec::new(),
        considered: Vec::new(),
    }
}

/// The structure checks' bound rule: a wider fit is not trusted when it ends with a parameter on its bound that
/// the held fit estimated off it (the global5000's k_q driven to 1.5 by a freed C_mα̇). A parameter already on
/// its bound in the held fit, one the held fit did not estimate, or one of the freed terms itself on a bound
/// (absent from the held estimate's free set) does not count against it.
#[test]
fn a_wider_fit_that_pushes_a_held_fits_interior_parameter_onto_its_bound_is_not_interior() {
    use checks::drove_onto_bound;
    let held = estimate_with(&[
        ("Cm_q", false, false),
        ("Cm_alphadot", true, false),
        ("gust_q_gain", false, false),
        ("tau_alpha_s", false, true),
        ("CL_V", true, false),
    ]);
    let wider =
        |k_q_at_bound: bool, tau_at_bound: bool, cm_ad_at_bound: bool, clv_at_bound: bool| {
            estimate_with(&[
                ("Cm_q", false, false),
                ("Cm_alphadot", false, cm_ad_at_bound),
                ("gust_q_gain", false, k_q_at_bound),
                ("tau_alpha_s", false, tau_at_bound),
                ("CL_V", true, clv_at_bound),
            ])
        };
    assert!(!drove_onto_bound(&held, &wider(false, false, false, false)));
    assert!(
        drove_onto_bound(&held, &wider(true, false, false, false)),
        "k_q pushed onto its bound"
    );
    assert!(
        !drove_onto_bound(&held, &wider(false, true, false, false)),
        "τ_α was on its bound already"
    );
    assert!(
        !drove_onto_bound(&held, &wider(false, false, true, false)),
        "C_mα̇ was held, not estimated"
    );
    assert!(
        !drove_onto_bound(&held, &wider(false, false, false, true)),
        "C_LV is held in both"
    );
    assert!(drove_onto_bound(&held, &wider(true, true, true, true)));
}
