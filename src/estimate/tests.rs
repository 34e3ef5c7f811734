//! Scenarios for the estimation core on models whose truth is known.

use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::StandardNormal;

use super::*;

/// Short-period model: states α, q; input δe; outputs α, q.
/// `α̇ = Z_α α + q + Z_δe δe`, `q̇ = M_α α + M_q q + M_δe δe`.
fn short_period() -> LinearModel {
    let sig = Signature {
        parameters: ["Z_alpha", "Z_de", "M_alpha", "M_q", "M_de"]
            .map(String::from)
            .to_vec(),
        states: vec!["alpha_rad".into(), "q_rad_s".into()],
        inputs: vec!["elevator_rad".into()],
        outputs: vec!["alpha_rad".into(), "q_rad_s".into()],
    };
    let p = Entry::param;
    let k = Entry::constant;
    LinearModel::new(
        sig,
        vec![vec![p(0), k(1.0)], vec![p(2), p(3)]],
        vec![vec![p(1)], vec![p(4)]],
        vec![vec![k(1.0), k(0.0)], vec![k(0.0), k(1.0)]],
        vec![vec![k(0.0)], vec![k(0.0)]],
    )
    .unwrap()
}

const TRUTH: [f64; 5] = [-1.2, -0.15, -8.0, -2.5, -12.0];

/// A 3-2-1-1 elevator input of 2° at `dt_s`, then 8 s of free response.
fn record(
    name: &str,
    dt_s: f64,
    x0: [f64; 2],
    noise: [f64; 2],
    bias: [f64; 2],
    seed: u64,
) -> Record {
    let n = (12.0 / dt_s) as usize;
    let time_s: Vec<f64> = (0..n).map(|k| k as f64 * dt_s).collect();
    let amp = 2f64.to_radians();
    let de: Vec<f64> = time_s
        .iter()
        .map(|&t| match t {
            t if (1.0..1.9).contains(&t) => amp,
            t if (1.9..2.5).contains(&t) => -amp,
            t if (2.5..2.8).contains(&t) => amp,
            t if (2.8..3.1).contains(&t) => -amp,
            _ => 0.0,
        })
        .collect();
    let model = short_period();
    let inputs = vec![de];
    let run = Run {
        record: 0,
        time_s: &time_s,
        input: InputSignal::measured(&time_s, &inputs, InputHold::Linear),
        max_step_s: dt_s / 4.0,
    };
    let y = simulate_states(&model, &TRUTH, &x0, &run).unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let outputs = y
        .iter()
        .enumerate()
        .map(|(o, col)| {
            col.iter()
                .map(|v| v + bias[o] + noise[o] * rng.sample::<f64, _>(StandardNormal))
                .collect()
        })
        .collect();
    Record {
        name: name.into(),
        time_s,
        inputs,
        outputs,
        initial_state: vec![0.0, 0.0],
    }
}

fn start() -> Vec<Parameter> {
    let names = ["Z_alpha", "Z_de", "M_alpha", "M_q", "M_de"];
    let start = [-0.8, -0.05, -5.0, -1.5, -8.0];
    names
        .iter()
        .zip(start)
        .map(|(n, v)| Parameter::free(*n, v))
        .collect()
}

/// `p` lies within `k` of its standard errors of `truth`.
fn within_sigmas(p: &ParameterEstimate, truth: f64, k: f64) -> bool {
    (p.value - truth).abs() < k * p.std_error
}

#[test]
fn noise_free_short_period_is_recovered_to_round_off() {
    // exact data (linear interpolation both in the generator's RK4 and the fit's exact
    // discretisation): the estimate is the truth up to the generator's RK4 error at dt/4
    let rec = record("a", 0.02, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], 1);
    let est = fit(
        &short_period(),
        &start(),
        &[rec],
        &Nuisance::default(),
        &Options::default(),
    )
    .unwrap();
    assert!(est.converged, "{:?} after {}", est.stop, est.iterations);
    for (p, truth) in est.parameters.iter().zip(TRUTH) {
        assert!(
            (p.value - truth).abs() < 1e-5 * truth.abs(),
            "{}: {} vs {truth}",
            p.name,
            p.value
        );
    }
}

#[test]
fn two_noisy_records_with_biases_and_unknown_initial_states() {
    // one parameter set, per-record initial states and output biases
    let a = record("a", 0.02, [0.02, -0.05], [0.002, 0.005], [0.01, -0.003], 11);
    let b = record("b", 0.02, [-0.03, 0.04], [0.002, 0.005], [-0.02, 0.004], 12);
    let nuisance = Nuisance {
        initial_state: vec![0, 1],
        output_bias: vec![0, 1],
        ..Nuisance::default()
    };
    let est = fit(
        &short_period(),
        &start(),
        &[a, b],
        &nuisance,
        &Options::default(),
    )
    .unwrap();
    assert!(est.converged, "{:?}", est.stop);
    for (p, truth) in est.parameters.iter().zip(TRUTH) {
        assert!(
            within_sigmas(p, truth, 4.0),
            "{}: {} ± {} vs {truth}",
            p.name,
            p.value,
            p.std_error
        );
        assert!(
            p.std_error > 0.0 && p.std_error < 0.2 * truth.abs(),
            "{p:?}"
        );
    }
    let bias = |rec: &str, target: &str| {
        est.nuisance
            .iter()
            .find(|n| {
                n.kind == Some(NuisanceKind::OutputBias)
                    && n.record.as_deref() == Some(rec)
                    && n.name == target
            })
            .unwrap()
            .value
    };
    assert!((bias("a", "alpha_rad") - 0.01).abs() < 0.002);
    assert!((bias("b", "alpha_rad") + 0.02).abs() < 0.002);
    // R estimates the noise variance: 0.002², 0.005² within 10 %
    assert!((est.residual_covariance[0][0].sqrt() / 0.002 - 1.0).abs() < 0.1);
    assert!((est.residual_covariance[1][1].sqrt() / 0.005 - 1.0).abs() < 0.1);
}

#[test]
fn a_skewed_input_is_found() {
    // the record's elevator is logged 0.03 s late relative to the response: u_meas(t) = u(t − 0.03)
    // → the model must see u_meas(t + 0.03), a skew of −0.03 s
    let mut rec = record("a", 0.02, [0.0, 0.0], [0.001, 0.002], [0.0, 0.0], 5);
    let t = rec.time_s.clone();
    let orig = rec.inputs.clone();
    let shifted = InputSignal::new(&t, &orig, vec![0.0], vec![0.03], InputHold::Linear);
    let mut u = [0.0];
    rec.inputs[0] = t
        .iter()
        .map(|&tk| {
            shifted.at(tk, &mut u);
            u[0]
        })
        .collect();
    let nuisance = Nuisance {
        input_skew: vec![0],
        ..Nuisance::default()
    };
    let est = fit(
        &short_period(),
        &start(),
        &[rec],
        &nuisance,
        &Options::default(),
    )
    .unwrap();
    let skew = &est.nuisance[0];
    assert!(
        (skew.value + 0.03).abs() < 3.0 * skew.std_error.max(1e-3),
        "{skew:?}"
    );
}

#[test]
fn a_diverging_start_is_a_clear_error() {
    let rec = record("a", 0.02, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], 1);
    let mut p = start();
    p[2].value = 400.0; // M_alpha: violently unstable, e^(20 t) over 12 s
    let err = fit(
        &short_period(),
        &p,
        &[rec],
        &Nuisance::default(),
        &Options::default(),
    )
    .unwrap_err();
    assert!(matches!(err, EstimateError::StartDiverges { .. }), "{err}");
}

/// The short-period record of [`record`] with process noise: white `F w` on α̇ and q̇ (spectral
/// densities `q_alpha`, `q_q`), integrated by Euler–Maruyama at 1 ms; measured outputs with
/// white noise.
fn turbulent_record(dt_s: f64, q_psd: [f64; 2], noise: [f64; 2], seed: u64) -> Record {
    let clean = record("t", dt_s, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], seed);
    let [za, zde, ma, mq, mde] = TRUTH;
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed);
    let h = 1e-3;
    let sub = (dt_s / h).round() as usize;
    let de = &clean.inputs[0];
    let n = clean.len();
    let mut x = [0.0f64; 2];
    let mut outputs = vec![vec![0.0; n]; 2];
    for k in 0..n {
        for o in 0..2 {
            outputs[o][k] = x[o] + noise[o] * rng.sample::<f64, _>(StandardNormal);
        }
        if k + 1 == n {
            break;
        }
        for s in 0..sub {
            let f = s as f64 / sub as f64;
            let u = de[k] + f * (de[k + 1] - de[k]);
            let w: [f64; 2] = [
                (q_psd[0] / h).sqrt() * rng.sample::<f64, _>(StandardNormal),
                (q_psd[1] / h).sqrt() * rng.sample::<f64, _>(StandardNormal),
            ];
            let dx = [
                za * x[0] + x[1] + zde * u + w[0],
                ma * x[0] + mq * x[1] + mde * u + w[1],
            ];
            x = [x[0] + h * dx[0], x[1] + h * dx[1]];
        }
    }
    Record { outputs, ..clean }
}

/// Two records (seeds 31, 32) of the short period in turbulence of spectral densities 2e-4 and 4e-3, sampled at
/// 50 Hz with measurement noise of standard deviation `noise` on α and q.
fn two_turbulent_records(noise: [f64; 2]) -> Vec<Record> {
    (0..2)
        .map(|s| turbulent_record(0.02, [2e-4, 4e-3], noise, 31 + s))
        .collect()
}

/// The short-period model fitted to `recs` by output error and by filter error, both estimating the initial
/// state of each record.
fn output_error_and_filter_error(recs: &[Record]) -> (Estimate, Estimate) {
    let nuisance = Nuisance {
        initial_state: vec![0, 1],
        ..Nuisance::default()
    };
    let fit_by = |method: Method| {
        fit(
            &short_period(),
            &start(),
            recs,
            &nuisance,
            &Options {
                method,
                ..Options::default()
            },
        )
        .unwrap()
    };
    (fit_by(Method::Oe), fit_by(Method::Fem))
}

#[test]
fn without_process_noise_the_filter_error_method_gives_the_output_error_answer() {
    let rec = record("a", 0.02, [0.01, -0.02], [0.002, 0.005], [0.0, 0.0], 21);
    let (oe, fem) = output_error_and_filter_error(&[rec]);
    assert!(fem.converged, "{:?}", fem.stop);
    // the process noise stays on its bound 0: the gain is 0 and the filter is the simulation
    for n in fem
        .nuisance
        .iter()
        .filter(|n| n.kind == Some(NuisanceKind::ProcessNoise))
    {
        assert_eq!(n.value, 0.0, "{n:?}");
    }
    for (a, b) in oe.parameters.iter().zip(&fem.parameters) {
        assert!(
            (a.value - b.value).abs() < 0.05 * a.std_error,
            "{}: oe {} fem {}",
            a.name,
            a.value,
            b.value
        );
    }
}

#[test]
fn with_process_noise_the_filter_error_method_finds_the_truth() {
    let (oe, fem) = output_error_and_filter_error(&two_turbulent_records([0.001, 0.002]));
    for ((a, b), t) in oe.parameters.iter().zip(&fem.parameters).zip(TRUTH) {
        eprintln!(
            "{}: truth {t} oe {:.3} ± {:.3} ({:.1}σ)  fem {:.3} ± {:.3} ({:.1}σ)",
            a.name,
            a.value,
            a.std_error,
            (a.value - t) / a.std_error,
            b.value,
            b.std_error,
            (b.value - t) / b.std_error
        );
    }
    assert!(fem.converged, "{:?}", fem.stop);
    // within 3σ of the truth (the generator's noise is what the model assumes)
    for (b, t) in fem.parameters.iter().zip(TRUTH) {
        assert!(within_sigmas(b, t, 3.0), "{}", b.name);
    }
    // the process-noise spectral densities too (2e-4 and 4e-3 in the generator)
    let q: Vec<&ParameterEstimate> = fem
        .nuisance
        .iter()
        .filter(|n| n.kind == Some(NuisanceKind::ProcessNoise))
        .collect();
    for (n, truth) in q.iter().zip([2e-4, 4e-3]) {
        assert!(within_sigmas(n, truth, 3.0), "{n:?}");
    }
    // output error, blind to the turbulence, misses M_δe by more than 3σ here
    let m_de = oe.parameter("M_de").unwrap();
    assert!(
        (m_de.value - TRUTH[4]).abs() > 3.0 * m_de.std_error,
        "{m_de:?}"
    );
    // the gain stays inside its bound: the records carry measurement noise
    assert!(
        !fem.warnings
            .iter()
            .any(|w| w.contains("gain is on its bound")),
        "{:?}",
        fem.warnings
    );
}

/// The same turbulence with no measurement noise at all: R = C P Cᵀ + G Gᵀ leaves G = 0, the gain ends on its
/// bound diag(K C) = 1, and the estimate says so (`Problem::gain_on_bound`).
#[test]
fn filter_error_on_noise_free_records_warns_that_its_gain_is_on_the_bound() {
    let (_, fem) = output_error_and_filter_error(&two_turbulent_records([0.0, 0.0]));
    assert!(
        fem.warnings
            .iter()
            .any(|w| w.contains("gain is on its bound")),
        "{:?}",
        fem.warnings
    );
}

#[test]
fn a_considered_held_parameter_widens_the_others_by_their_refit_shift() {
    // Consider covariance: holding M_α at a value in error by δ moves each free estimate by d δ, and the
    // variance added is σ_c² d². d is checked against two refits with M_α held at its truth and at truth + δ
    // (to 10 %: the refits also re-estimate the noise variances that weight them).
    let rec = record("a", 0.02, [0.0, 0.0], [0.002, 0.005], [0.0, 0.0], 21);
    let held = |value: f64, consider: Option<f64>| {
        let mut p = start();
        p[2] = Parameter::fixed("M_alpha", value);
        if let Some(sd) = consider {
            p[2] = p[2].clone().considered(sd);
        }
        fit(
            &short_period(),
            &p,
            std::slice::from_ref(&rec),
            &Nuisance::default(),
            &Options::default(),
        )
        .unwrap()
    };
    let (delta, sd) = (0.01, 0.4);
    let base = held(TRUTH[2], None);
    let moved = held(TRUTH[2] + delta, None);
    let considered = held(TRUTH[2], Some(sd));
    assert_eq!(considered.considered, vec![("M_alpha".to_string(), sd)]);
    for ((b, m), c) in base
        .parameters
        .iter()
        .zip(&moved.parameters)
        .zip(&considered.parameters)
    {
        assert_eq!(
            b.value, c.value,
            "{}: considering changes no estimate",
            b.name
        );
        if b.fixed {
            continue;
        }
        let d = (m.value - b.value) / delta;
        let added = c.std_error_white.powi(2) - b.std_error_white.powi(2);
        let expected = (sd * d).powi(2);
        assert!(
            (added - expected).abs() < 0.1 * expected + 1e-12,
            "{}: added variance {added:.3e}, refit shift gives {expected:.3e}",
            b.name
        );
        assert!(c.std_error > b.std_error, "{}", b.name);
    }
}

/// A fit stopped by the iteration limit, or one whose cost is not finite, is not an estimate: `outcome` says
/// so, and the binary ends with exit 1 (a failure of the work, as `check`'s unconverged reconstruction).
#[test]
fn an_unconverged_or_diverged_fit_is_an_error() {
    use crate::exit::ExitCode;
    let rec = record("a", 0.02, [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], 1);
    let fit_with = |max_iterations| {
        let options = Options {
            max_iterations,
            ..Options::default()
        };
        fit(
            &short_period(),
            &start(),
            std::slice::from_ref(&rec),
            &Nuisance::default(),
            &options,
        )
        .unwrap()
    };
    let mut est = fit_with(50);
    assert!(est.outcome().is_ok(), "{:?}", est.stop);
    let stopped = fit_with(1).outcome().unwrap_err();
    assert!(
        matches!(stopped, EstimateError::NotConverged { iterations: 1, .. }),
        "{stopped}"
    );
    assert_eq!(stopped.exit_code(), crate::exit::FAILURE);
    est.cost = f64::NAN;
    let diverged = est.outcome().unwrap_err();
    assert!(
        diverged
            .to_string()
            .starts_with("the fit diverged: its cost is NaN"),
        "{diverged}"
    );
    assert_eq!(diverged.exit_code(), crate::exit::FAILURE);
}
