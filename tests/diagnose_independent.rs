//! `diagnose` on records from the independent generator (`scripts/gen_diagnose_records.py`: JSBSim's c172x
//! through JSBSim's own Python API, its own actuator and sample timing, a random trim point and heading, the
//! maneuvers in sequence, sensor noise). A representative subset of the acceptance evaluation
//! (`cargo bench --bench diagnose_eval`): a clean record, a signal-path effect, a sensor effect, a derivative,
//! a pair, a derivative in light turbulence, an effect the filter error refit must name in place of one it
//! drops, a yaw-rate gyro bias that only the heading tells from a roll-angle bias, and an attitude scale that
//! only the flight-path reconstruction sees in the gusts (a scale, and a bias read as an a_y bias), and a record
//! whose integration step the replay must match (a rudder lag at 20 Hz in gusts), and the same lag named in place
//! of the delay output error named, an elevator effectiveness named in place of `Cm_de` on the innovations, and
//! the same generator's 737. The named set must be exactly the hidden one, each value within 15 % of the effect's
//! size.

use std::path::Path;
use std::process::Command;

use flightid::data::{read_csv, Channel, FlightRecord};
use flightid::diagnose::replay::ReplayCase;
use flightid::diagnose::search::Worker;
use flightid::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use flightid::sim::JsbsimSim;

/// Generates one case (training and validation record, 30 s, still air) with the given hidden effects,
/// diagnoses it and checks the named set and values.
fn check(seed: u64, effects: &str) -> Diagnosis {
    check_flown(seed, effects, 30.0, false)
}

/// [`check`] for a record of `duration_s`, flown in light turbulence when `turbulence`.
fn check_flown(seed: u64, effects: &str, duration_s: f64, turbulence: bool) -> Diagnosis {
    let duration = duration_s.to_string();
    let seed = seed.to_string();
    let mut args = vec![
        "--cases",
        "1",
        "--effects",
        effects,
        "--duration",
        &duration,
        "--seed",
        &seed,
    ];
    args.extend(turbulence.then_some("--turbulence"));
    check_generated(&args, 0)
}

/// Runs the generator with `args`, diagnoses its case number `case` and checks the named set and values
/// against the case's truth file.
fn check_generated(args: &[&str], case: usize) -> Diagnosis {
    check_generated_with(args, case, |r| r)
}

/// [`check_generated`] with the training and validation records passed through `log` first (what a data system
/// did to them).
fn check_generated_with(
    args: &[&str],
    case: usize,
    log: impl Fn(FlightRecord) -> FlightRecord,
) -> Diagnosis {
    check_generated_opts(
        args,
        case,
        log,
        DiagnoseOptions::default(),
        Values::ShareOfEffect(0.15),
    )
}

/// Case `case` of `cargo bench --bench diagnose_eval -- --seed <seed> --turbulence`, diagnosed with `opts` and
/// checked as [`check_generated`] does.
fn turbulent_bench_case(seed: u64, case: usize, opts: DiagnoseOptions) -> Diagnosis {
    turbulent_bench_case_within(seed, case, opts, Values::ShareOfEffect(0.15))
}

/// How close a named value must come to the hidden one.
#[derive(Clone, Copy)]
enum Values {
    /// Within this share of the effect's size, |value − truth| ≤ share |truth − null| (the acceptance's rule).
    ShareOfEffect(f64),
    /// Within this many of the value's own standard errors.
    Sigmas(f64),
}

/// [`turbulent_bench_case`] with the values checked by `values`.
fn turbulent_bench_case_within(
    seed: u64,
    case: usize,
    opts: DiagnoseOptions,
    values: Values,
) -> Diagnosis {
    let (seed, first) = (seed.to_string(), case.to_string());
    let args = [
        "--cases",
        "1",
        "--first",
        &first,
        "--seed",
        &seed,
        "--turbulence",
        "--stratified",
    ];
    check_generated_opts(&args, case, |r| r, opts, values)
}

/// [`check_generated_with`] with the search settings `opts` (progress off).
fn check_generated_opts(
    args: &[&str],
    case: usize,
    log: impl Fn(FlightRecord) -> FlightRecord,
    opts: DiagnoseOptions,
    values: Values,
) -> Diagnosis {
    let dir = generated(args);
    let file = |what: &str| dir.path().join(format!("case_{case:03}_{what}"));
    let train = log(read_csv(&file("train.csv")).unwrap());
    let valid = log(read_csv(&file("valid.csv")).unwrap());
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file("truth.json")).unwrap()).unwrap();
    let hidden = truth["effects"].as_array().unwrap().clone();
    let cfg =
        flightid::sim::derived::aircraft_config(truth["aircraft"].as_str().unwrap_or("c172x"))
            .unwrap();
    let rate = ReplayCase::new(&train).unwrap().sim_rate_hz();
    let mut workers: Vec<Worker> = (0..2)
        .map(|_| Worker::new(Box::new(JsbsimSim::start(&cfg, rate).unwrap())))
        .collect();
    let opts = DiagnoseOptions {
        progress: false,
        ..opts
    };
    let d = diagnose(&mut workers, &train, Some(&valid), &opts).unwrap();
    // Every simulation is counted in the stage that ran it, and the stages run in the diagnosis' order.
    let per_stage: usize = d.stages.iter().map(|s| s.simulations).sum();
    assert_eq!(per_stage, d.simulations, "stages: {:?}", d.stages);
    let names: Vec<&str> = d.stages.iter().map(|s| s.stage.as_str()).collect();
    assert_eq!(names.first(), Some(&"trim"), "stages: {names:?}");
    assert_eq!(names.last(), Some(&"validation"), "stages: {names:?}");
    assert!(d.stages.iter().all(|s| s.wall_s >= 0.0));
    let mut want: Vec<String> = hidden
        .iter()
        .map(|h| {
            format!(
                "{}/{}",
                h["effect"].as_str().unwrap(),
                h["target"].as_str().unwrap()
            )
        })
        .collect();
    let mut got: Vec<String> = d
        .named_cause
        .iter()
        .map(|c| format!("{}/{}", c.effect, c.target))
        .collect();
    want.sort();
    got.sort();
    let summary = || {
        d.candidates
            .iter()
            .filter(|c| c.full_fit)
            .map(|c| {
                format!(
                    "{}/{} = {:.4} ({:?})",
                    c.effect, c.target, c.value, c.rejected_because
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(got, want, "full fits:\n{}", summary());
    for h in &hidden {
        let (e, t) = (h["effect"].as_str().unwrap(), h["target"].as_str().unwrap());
        let truth = h["value"].as_f64().unwrap();
        let null = match e {
            "control_effectiveness" | "sensor_scale" | "aero_derivative" => 1.0,
            _ => 0.0,
        };
        let c = d
            .named_cause
            .iter()
            .find(|c| c.effect == e && c.target == t)
            .unwrap();
        let tolerance = match values {
            Values::ShareOfEffect(share) => share * (truth - null).abs(),
            Values::Sigmas(k) => k * c.std_error,
        };
        assert!(
            (c.value - truth).abs() <= tolerance,
            "{e}/{t}: {} ± {} vs hidden {truth}",
            c.value,
            c.std_error
        );
    }
    d
}

/// JSBSim's c182, which flightid has no configuration of: the configuration derived from the model
/// (`sim::derived`) replays its records, and a hidden yaw stiffness ×1.42 is named (case 5 of
/// `cargo bench --bench diagnose_eval -- --aircraft c182 --seed 1`: 66 s at 40 Hz, still air).
#[test]
fn a_c182_record_is_diagnosed_with_the_configuration_derived_from_its_model() {
    let args = [
        "--cases",
        "1",
        "--first",
        "5",
        "--seed",
        "1",
        "--stratified",
        "--aircraft",
        "c182",
    ];
    check_generated(&args, 5);
}

/// JSBSim's c310, a light twin with retractable gear that flightid has no configuration of either: its derived
/// configuration (both engines running, gear up, the left aileron's own travel) replays the records, and a hidden
/// aileron effectiveness ×1.36 is named (case 21 of `cargo bench --bench diagnose_eval -- --aircraft c310 --seed 1`:
/// 38 s at 50 Hz, still air).
#[test]
fn a_c310_record_is_diagnosed_with_the_configuration_derived_from_its_model() {
    let args = [
        "--cases",
        "1",
        "--first",
        "21",
        "--seed",
        "1",
        "--stratified",
        "--aircraft",
        "c310",
    ];
    check_generated(&args, 21);
}

#[test]
fn clean_record_names_nothing() {
    let d = check(101, "[]");
    // Every channel sits near its sensor noise: the search keeps the noise weights.
    assert!(d.relaxed_weights.is_empty(), "{:?}", d.relaxed_weights);
}

#[test]
fn elevator_delay_is_named() {
    check(
        102,
        r#"[{"effect": "input_delay", "target": "elevator", "value": 0.08}]"#,
    );
}

/// Training and validation logs with a 1.5 s dropout 20 s in (after the elevator 3-2-1-1 and the aileron
/// doublet): each replay runs on its longest uninterrupted piece, the first 20 s, the warnings say so for both
/// records, and the delay is named from them. Before
/// the dropout handling the record was put on one uniform grid across the gap, its step stretched by the missing
/// samples' share (5 %), and the missing 1.5 s interpolated.
#[test]
fn a_dropout_in_the_log_leaves_the_replay_its_longest_piece() {
    let args = [
        "--cases",
        "1",
        "--effects",
        r#"[{"effect": "input_delay", "target": "elevator", "value": 0.08}]"#,
        "--duration",
        "30",
        "--seed",
        "102",
    ];
    let d = check_generated_with(&args, 0, |rec| {
        let t0 = rec.time_s[0];
        let keep: Vec<bool> = rec
            .time_s
            .iter()
            .map(|t| !(20.0..21.5).contains(&(t - t0)))
            .collect();
        let pick = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(x, _)| *x)
                .collect()
        };
        let mut out = FlightRecord::new(pick(&rec.time_s));
        for (name, values) in &rec.columns {
            out.push_column(name, pick(values));
        }
        out
    });
    let warnings = d.warnings.join("\n");
    for record in ["training", "validation"] {
        for needle in [
            "a dropout of 1.5",
            "the replay uses the longest uninterrupted piece, t = 0",
        ] {
            assert!(
                warnings.contains(&format!("{record} record: {needle}")),
                "{record}: {needle}: {warnings}"
            );
        }
    }
}

/// A clean 55 s record in light turbulence whose only maneuver is an elevator 3-2-1-1 (case 10 of the
/// turbulent false-alarm run `diagnose_eval -- --false-alarm --turbulence --seed 23`): the lateral axis moves by
/// the gusts alone. Before the derivatives needed an input of their axis, `Cl_r` ×2.27 was named on it (and on
/// three more of that run's 24 clean records: 4/24, now 1/24). Nothing is named; the lateral derivatives are
/// listed as skipped, with the reason.
#[test]
fn a_clean_longitudinal_record_in_gusts_names_no_lateral_derivative() {
    let args = [
        "--cases",
        "1",
        "--first",
        "10",
        "--seed",
        "23",
        "--stratified",
        "--turbulence",
        "--effects",
        "[]",
        "--plan",
        "random",
        "--min-duration",
        "15",
        "--max-duration",
        "90",
        "--max-noise",
        "2",
    ];
    let d = check_generated(&args, 10);
    let skipped: Vec<String> = d
        .skipped
        .iter()
        .filter(|s| {
            s.reason
                .starts_with("no input of its axis (aileron, rudder) moves")
        })
        .map(|s| s.target.clone())
        .collect();
    for t in ["Cl_r", "Cl_p", "Cn_beta", "Cn_r"] {
        assert!(
            skipped.iter().any(|s| s == t),
            "{t} not skipped: {skipped:?}"
        );
    }
}

#[test]
fn pitch_rate_gyro_bias_is_named() {
    check(
        103,
        r#"[{"effect": "sensor_bias", "target": "q_rad_s", "value": 0.0105}]"#,
    );
}

#[test]
fn pitch_damping_is_named() {
    check(
        104,
        r#"[{"effect": "aero_derivative", "target": "Cm_q", "value": 2.0}]"#,
    );
}

/// A signal-path effect and a derivative together. This record once named an extra `CL_alpha2` ×−1.4 as well:
/// on its narrow α range that term acts like a CL_alpha change of about 1 %, far below what is worth naming.
#[test]
fn delay_and_roll_damping_pair_is_named() {
    check(
        105,
        r#"[{"effect": "input_delay", "target": "elevator", "value": 0.08},
            {"effect": "aero_derivative", "target": "Cl_p", "value": 0.6}]"#,
    );
}

/// A record whose elevator and aileron columns have the other sign convention (a servo output, an aileron logged
/// as right minus left) drove the replay the wrong way round: on the clean seed-41 record an elevator
/// effectiveness of 0.10 was named, with the aileron reversed an aileron delay of 0.99 s. The control moment of
/// each surface (equation error on the rates' increments) on the record against the replay's now reverses such
/// a column and says so, and the pair of the test above is named as it is on the record as generated (measured:
/// `Cl_p` 0.5887, delay 0.0809 s; the elevator's moment +12.1 ± 0.6 rad/s² per rad on the record, −20.6 on the
/// replay, the aileron's −23.2 and +20.1).
#[test]
fn surfaces_logged_with_the_other_sign_are_reversed_not_causes() {
    let args = [
        "--cases",
        "1",
        "--effects",
        r#"[{"effect": "input_delay", "target": "elevator", "value": 0.08},
            {"effect": "aero_derivative", "target": "Cl_p", "value": 0.6}]"#,
        "--duration",
        "30",
        "--seed",
        "105",
    ];
    let d = check_generated_with(&args, 0, |mut rec| {
        for c in [Channel::Elevator, Channel::Aileron] {
            rec.column_mut(c).unwrap().iter_mut().for_each(|v| *v = -*v);
        }
        rec
    });
    let reversed: Vec<&str> = d
        .reversed_inputs
        .iter()
        .map(|r| r.column.as_str())
        .collect();
    assert_eq!(
        reversed,
        ["elevator_rad", "aileron_rad"],
        "{:?}",
        d.reversed_inputs
    );
    assert!(
        d.warnings
            .iter()
            .filter(|w| w.contains("the replay reverses it"))
            .count()
            == 2,
        "{:?}",
        d.warnings
    );
    // The report lists them among the record's conventions.
    let dir = tempfile::tempdir().unwrap();
    let train = &d.traces.train_before;
    flightid::diagnose::report::write_report(&d, "c172x", train, None, dir.path()).unwrap();
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    for column in ["elevator_rad", "aileron_rad"] {
        assert!(
            md.contains(&format!("| other sign convention | {column} | moment ")),
            "{md}"
        );
    }
}

/// Three effects, of which the first round cannot tell two apart: with the vane scales still unmodelled,
/// `Cm_alpha2` ×2.5 fits this record better than the hidden `CL_alpha2` 16. Sequential replacement fits the
/// runner-up again once both scales are named, and `CL_alpha2` takes its place.
#[test]
fn lift_curvature_beside_vane_scales_is_named() {
    check(
        106,
        r#"[{"effect": "sensor_scale", "target": "beta_rad", "value": 1.17},
            {"effect": "aero_nonlinearity", "target": "CL_alpha2", "value": 16},
            {"effect": "sensor_scale", "target": "alpha_rad", "value": 1.135}]"#,
    );
}

/// Pitch damping in light turbulence (40 s): `Cm_q` ×0.45 is named with its value within 15 % although the
/// gusts' response stays in every channel of the record.
#[test]
fn pitch_damping_in_turbulence_is_named() {
    check_flown(
        206,
        r#"[{"effect": "aero_derivative", "target": "Cm_q", "value": 0.45}]"#,
        40.0,
        true,
    );
}

/// An a_z bias of 0.35 m/s² in light turbulence (case 13 of `cargo bench --bench diagnose_eval -- --seed 4
/// --turbulence`, 45 s at 25 Hz). Output error names `Cm_alpha2` first, and the bias loses its round to a
/// candidate within its resolution; the filter error refit drops `Cm_alpha2`, and the bias, an alternative or a
/// near miss of output error's, must take its place on the filter's innovations.
#[test]
fn dropped_effect_gives_way_to_its_alternative_in_turbulence() {
    let d = turbulent_bench_case(4, 13, DiagnoseOptions::default());
    assert!(
        d.candidates.iter().any(|c| c
            .rejected_because
            .as_deref()
            .is_some_and(|r| r.starts_with("dropped by the filter error refit"))),
        "the filter error refit dropped nothing: the case no longer exercises the replacement"
    );
}

/// An r-gyro bias of −0.55°/s beside `Cn_r` ×0.51 and an elevator effectiveness ×1.37, in light turbulence
/// (case 7 of `cargo bench --bench diagnose_eval -- --seed 4 --turbulence`, 50 s at 40 Hz). Without heading a
/// replay banked by 0.039 rad turns at the rate the bias adds, and a φ bias took the r bias' place; the
/// heading the record carries tells the two apart.
#[test]
fn yaw_gyro_bias_is_told_from_a_roll_bias_by_heading() {
    let d = turbulent_bench_case(4, 7, DiagnoseOptions::default());
    assert!(
        d.noise_std.contains_key("psi_rad"),
        "heading is not compared: {:?}",
        d.noise_std
    );
}

/// A θ logged × 1.12 in light turbulence (45 s, seed 31). Output error weights θ by its misfit in the gusts and
/// does not name the scale. The filter error refit, on innovations weighted by their channels' variances, names
/// it as a near miss of output error's, 1.124; summed unweighted, the innovations did not, and the flight-path
/// reconstruction named it (+0.124 ± 0.001 against the integrated pitch rate; docs/diagnose.md, "Sensor errors
/// from the flight-path reconstruction"). Checked: the named set exactly and the value within 15 %, by either
/// route.
#[test]
fn an_attitude_scale_lost_in_the_gusts_is_named() {
    let d = check_flown(
        31,
        r#"[{"effect": "sensor_scale", "target": "theta_rad", "value": 1.12}]"#,
        45.0,
        true,
    );
    assert!(
        d.process_noise.as_ref().is_some_and(|p| p.used),
        "the refit ran on output error: the record no longer exercises the filter"
    );
}

/// A φ bias of 1.13° in light turbulence (case 2 of `cargo bench --bench diagnose_eval -- --seed 3
/// --turbulence`, 41 s at 40 Hz), which the selection does not name. The flight-path reconstruction reads it as an
/// a_y bias of 0.218 ± 0.006 m/s² (g cos θ times it), and the replay prefers the φ bias to an a_y bias
/// (docs/diagnose.md, "Sensor errors from the flight-path reconstruction"): 0.0222 rad named for 0.0197. Checked:
/// the named set exactly, the value within 15 %, and that the kinematic stage named it.
#[test]
fn a_roll_attitude_bias_lost_in_the_gusts_is_named_from_the_kinematics() {
    let d = turbulent_bench_case(3, 2, DiagnoseOptions::default());
    assert_named_from_kinematics(&d, "phi_rad");
}

/// A clean record (seed 31, 45 s, light turbulence) with θ logged × 1.12 over its first 74 % only: no constant
/// sensor error, but the reconstruction of the whole record reads a θ scale of +0.108 at z 12.5, beyond the
/// stage's 10. The second half's own reconstruction gives +0.070 at z 4.2, which does not confirm it, so the
/// kinematic stage names nothing (docs/diagnose.md, "Sensor errors from the flight-path reconstruction");
/// without that test it named a θ scale here. Checked: nothing named by the kinematic stage.
#[test]
fn an_attitude_error_over_part_of_the_record_is_not_named_from_the_kinematics() {
    let args = [
        "--cases",
        "1",
        "--effects",
        "[]",
        "--duration",
        "45",
        "--seed",
        "31",
        "--turbulence",
    ];
    let d = check_generated_with(&args, 0, |mut rec| {
        let cut = rec.len() * 74 / 100;
        for (name, values) in rec.columns.iter_mut() {
            if name == "theta_rad" {
                values[..cut].iter_mut().for_each(|v| *v *= 1.12);
            }
        }
        rec
    });
    assert!(
        d.candidates.iter().all(|c| c.criterion != "kinematics"),
        "named from the kinematics: {:?}",
        d.named_cause
    );
}

/// A clean record in light turbulence (case 8 of `cargo bench --bench diagnose_eval -- --seed 7 --turbulence`,
/// 35 s at 20 Hz). The filter error refit used to name a θ bias of −0.0109 rad from the innovations: a bias on θ
/// takes up the record's mean vertical gust (θ = γ + α), and the flight-path reconstruction dropped it (it reads a
/// θ bias as an a_x bias of −g cos θ₀ times it and finds none; docs/diagnose.md, "Sensor errors from the
/// flight-path reconstruction"). Since a change must stand two standard errors beyond its resolution, output
/// error's −0.0065 ± 0.0015 rad (resolution 0.005) is turned down first. Checked: nothing named, and the θ
/// bias's entries say which of the two turned it down.
#[test]
fn a_pitch_attitude_bias_in_gusts_is_not_named() {
    let d = turbulent_bench_case(7, 8, DiagnoseOptions::default());
    let theta: Vec<&str> = d
        .candidates
        .iter()
        .filter(|c| c.target == "theta_rad" && c.full_fit)
        .filter_map(|c| c.rejected_because.as_deref())
        .collect();
    assert!(
        theta.iter().any(
            |r| r.starts_with("dropped by the flight-path reconstruction")
                || r.starts_with("smaller than the resolution")
        ),
        "the θ bias's entries: {theta:?}"
    );
}

/// Asserts that the sensor error on `target` was named by the kinematic stage, not by the replay's selection.
fn assert_named_from_kinematics(d: &Diagnosis, target: &str) {
    assert!(
        d.candidates
            .iter()
            .any(|c| c.criterion == "kinematics" && c.target == target),
        "named by the replay, not the kinematics: {:?}",
        d.named_cause
    );
}

/// A rudder lag of 0.123 s on a 32 s record in light turbulence, flown at 100 Hz and logged at 20 Hz
/// (`diagnose_eval -- --seed 3 --turbulence`, case 10). Replayed at 200 Hz, JSBSim's other integration step left
/// a residual that a rudder *delay* of 0.122 s fitted better than the lag. Asked to, the replay integrates at
/// the step that fits the record best (`diagnose::rate`, `--estimate-rate`), the record's own 100 Hz, and the
/// lag is named.
#[test]
fn the_replay_integrates_at_the_step_the_record_was_flown_at() {
    let opts = DiagnoseOptions {
        choose_rate: true,
        ..Default::default()
    };
    let d = turbulent_bench_case(3, 10, opts);
    let rate = d.replay_rate.expect("the integration rate is chosen");
    assert_eq!(rate.rate_hz, 100.0, "rates tried: {:?}", rate.tried);
}

/// A rudder effectiveness ×1.33 beside an aileron lag of 0.12 s and a `Cm_alpha2` of 6.9, in light turbulence
/// (case 7 of `cargo bench --bench diagnose_eval -- --seed 3 --turbulence`, 78 s at 40 Hz). The filter error
/// refit sizes the named effects on innovations divided by their channels' innovation standard deviations;
/// summed as they were, the channels the filter follows closely (β, p, r) counted for little and the
/// effectiveness came out ×1.45, a third too far from 1.
#[test]
fn the_filter_error_refit_weighs_each_channel_by_its_innovation_variance() {
    let d = turbulent_bench_case(3, 7, DiagnoseOptions::default());
    assert!(
        d.process_noise.as_ref().is_some_and(|p| p.used),
        "the refit ran on output error: the case no longer exercises the filter"
    );
}

/// A β vane logged × 1.142 in light turbulence (case 10 of `cargo bench --bench diagnose_eval -- --seed 4
/// --turbulence`, 65 s at 20 Hz). Output error weighs β by its misfit in the gusts, and the identifiability gate
/// sets the scale aside before any fit (Cramér–Rao σ 0.0145 against a gate of 0.010). The filter error refit puts
/// it to the same gate on the innovations, where it passes, and names it: 1.172 ± 0.021. Checked: the named set
/// exactly, the value within 3σ of the truth (it is 21 % of the effect off, outside the acceptance's 15 %), that
/// the identifiability gate did set it aside and that `skipped` no longer lists it.
#[test]
fn a_vane_scale_output_error_cannot_identify_in_gusts_is_named_on_the_innovations() {
    let d = turbulent_bench_case_within(4, 10, DiagnoseOptions::default(), Values::Sigmas(3.0));
    let beta_scale = |effect: &str, target: &str| effect == "sensor_scale" && target == "beta_rad";
    assert!(
        d.candidates
            .iter()
            .filter(|c| beta_scale(&c.effect, &c.target))
            .all(|c| c.round > 0 && c.full_fit),
        "output error fitted the β scale: the case no longer exercises the second look"
    );
    assert!(
        !d.skipped.iter().any(|s| beta_scale(&s.effect, &s.target)),
        "the named β scale is still listed as skipped"
    );
}

/// The same rudder lag of 0.123 s in light turbulence (`diagnose_eval -- --seed 3 --turbulence`, case 10), replayed
/// at the default rate. Output error named an input delay of 0.122 s with the lag in its ambiguity group: while the
/// gusts colour the residual, the two nearly parallel sensitivities differ in cost by less than the gusts' share.
/// The filter error refit runs the sequential replacement again on the innovations, where the lag fits better
/// and is named (0.120 s).
#[test]
fn a_lag_output_error_named_as_a_delay_in_gusts_is_named_on_the_innovations() {
    let d = turbulent_bench_case(3, 10, DiagnoseOptions::default());
    assert!(
        d.candidates.iter().any(|c| c.effect == "actuator_lag"
            && c.target == "rudder"
            && c.rejected_because
                .as_deref()
                .is_some_and(|r| r.starts_with("in place of"))),
        "no replacement of the lag was tried: the case no longer exercises it"
    );
}

/// An elevator effectiveness ×0.637 beside an α-vane bias of −1.9° in light turbulence (`diagnose_eval -- --seed 3
/// --turbulence`, case 15, 61 s at 50 Hz). Output error named `Cm_de` ×0.69 beside the bias (ΔBIC −236 against
/// the effectiveness's −224). On the innovations the sequential replacement judges the effectiveness with the
/// bias free, as the bias was sized beside `Cm_de` (held at that value, the effectiveness cost 8 % more, most of
/// it on α), and names it, 0.641; the bias keeps its output-error value.
#[test]
fn an_elevator_effectiveness_output_error_named_as_cm_de_in_gusts_is_named_on_the_innovations() {
    let d = turbulent_bench_case(3, 15, DiagnoseOptions::default());
    assert!(
        d.candidates.iter().any(|c| c.effect == "aero_derivative"
            && c.target == "Cm_de"
            && c.full_fit
            && c.rejected_because.is_none()),
        "output error never passed Cm_de: the case no longer exercises the replacement"
    );
}

/// A clean 40 s c172x record of seed 41 (still air), which the probes of a record's conventions start from.
const CLEAN_SEED_41: [&str; 8] = [
    "--cases",
    "1",
    "--seed",
    "41",
    "--effects",
    "[]",
    "--duration",
    "40",
];

/// JSBSim's 737 in cruise (the generator's `--aircraft 737`: 27 300 ft, 416 kts, 40 s at 20 Hz) with its lift curve
/// ×0.7 and its roll damping ×1.5. The 737 calls its lift `CLalpha` (the c172x `CLwbh`), which `diagnose` finds
/// among each derivative's JSBSim names; before, `CL_alpha` was skipped as "no coefficient knob 'CLwbh'" and the
/// hidden set could not be named.
#[test]
fn the_737_s_lift_and_roll_damping_are_named_under_its_own_coefficient_names() {
    let effects = r#"[{"effect": "aero_derivative", "target": "CL_alpha", "value": 0.7},
        {"effect": "aero_derivative", "target": "Cl_p", "value": 1.5}]"#;
    let args = [
        "--aircraft",
        "737",
        "--cases",
        "1",
        "--effects",
        effects,
        "--duration",
        "40",
        "--seed",
        "7",
    ];
    check_generated(&args, 0);
}

/// Runs the generator with `args` into a fresh directory.
fn generated(args: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/gen_diagnose_records.py");
    let st = Command::new(flightid::sim::env::python().expect("the provisioned Python"))
        .arg(script)
        .arg("--out")
        .arg(dir.path())
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .expect("running the generator");
    assert!(st.success(), "the generator failed");
    dir
}

/// `flightid diagnose` on case `case` of `dir` (training and validation record) with `extra` arguments; its
/// JSON.
fn diagnose_cli(dir: &Path, case: usize, extra: &[&str], tag: &str) -> serde_json::Value {
    let json = dir.join(format!("{tag}.json"));
    let file = |what: &str| dir.join(format!("case_{case:03}_{what}.csv"));
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .arg("diagnose")
        .arg("--data")
        .arg(file("train"))
        .arg("--validate")
        .arg(file("valid"))
        .arg("--json")
        .arg(&json)
        .args(extra)
        .output()
        .expect("running flightid diagnose");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
}

/// Whether a diagnosis warns that the record trims elsewhere than the model (a loading or an atmosphere).
fn warns_of_the_trim(d: &serde_json::Value) -> bool {
    d["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("--property"))
}

/// A clean record flown 200 lb lighter than JSBSim's c172x is loaded (the generator's `--property`: both tanks at
/// 30 lb of their 130). Replayed with the model's own loading it trims 0.2° off in elevator and 0.2° in α, and the
/// search names `Cm_0` ×2.4 for it; the warning says what a loading does to the trim. Given the record's loading
/// with `--property`, the same record names nothing and draws no such warning.
#[test]
fn a_record_flown_lighter_names_nothing_once_its_loading_is_given() {
    let loading = [
        "--property",
        "propulsion/tank[0]/contents-lbs=30",
        "--property",
        "propulsion/tank[1]/contents-lbs=30",
    ];
    let mut args = vec![
        "--cases",
        "1",
        "--seed",
        "31",
        "--effects",
        "[]",
        "--duration",
        "30",
    ];
    args.extend(loading);
    let dir = generated(&args);
    let unloaded = diagnose_cli(dir.path(), 0, &[], "model_loading");
    assert!(warns_of_the_trim(&unloaded), "{}", unloaded["warnings"]);
    let loaded = diagnose_cli(dir.path(), 0, &loading, "record_loading");
    assert_eq!(
        loaded["named_cause"],
        serde_json::json!([]),
        "{}",
        loaded["named_cause"]
    );
    assert!(!warns_of_the_trim(&loaded), "{}", loaded["warnings"]);
}

/// A clean record flown on a day 15 K warmer than the standard atmosphere, with the data system's air density
/// logged (the generator's `--air-data`): the replay flies in the atmosphere that density gives and names nothing.
/// Without the density column the replay flies the standard day, trims 0.13° off in elevator, and the search
/// named `Cm_0` ×0.34 for the thinner air.
#[test]
fn a_record_flown_on_a_warm_day_is_replayed_in_its_own_air() {
    let args = [
        "--first",
        "1",
        "--cases",
        "1",
        "--seed",
        "33",
        "--effects",
        "[]",
        "--duration",
        "40",
        "--property",
        "atmosphere/delta-T=27",
        "--air-data",
    ];
    let dir = generated(&args);
    let d = diagnose_cli(dir.path(), 1, &[], "own_air");
    assert_eq!(
        d["named_cause"],
        serde_json::json!([]),
        "{}",
        d["named_cause"]
    );
    assert!(!warns_of_the_trim(&d), "{}", d["warnings"]);
    let note = d["warnings"].as_array().unwrap().iter().find_map(|w| {
        let w = w.as_str().unwrap();
        w.contains("air density makes the day")
            .then(|| w.to_string())
    });
    assert!(
        note.as_deref().is_some_and(|w| w.contains("+15.0 K")),
        "{}",
        d["warnings"]
    );
    // The same records without their density column: the standard day, and the trim warning.
    for part in ["train", "valid"] {
        let path = dir.path().join(format!("case_001_{part}.csv"));
        let mut rec = read_csv(&path).unwrap();
        rec.columns.retain(|(name, _)| name != "density_kg_m3");
        flightid::data::write_csv_atomic(&path, &rec).unwrap();
    }
    let standard = diagnose_cli(dir.path(), 1, &[], "standard_day");
    assert!(warns_of_the_trim(&standard), "{}", standard["warnings"]);
}

/// A record flown from a trimmed 3° descent (the generator's `--property ic/gamma-deg=-3`) with `Cm_q` ×1.6
/// hidden: the replay trims at the flight path of the record's still start (its climb rate, with θ − α agreeing),
/// and names `Cm_q` alone. Trimmed level, as before, it named an a_x bias of −0.51 m/s² beside it.
#[test]
fn a_record_starting_in_a_descent_is_trimmed_in_it() {
    let effects = r#"[{"effect": "aero_derivative", "target": "Cm_q", "value": 1.6}]"#;
    let args = [
        "--cases",
        "1",
        "--seed",
        "37",
        "--effects",
        effects,
        "--duration",
        "30",
        "--property",
        "ic/gamma-deg=-3",
    ];
    check_generated(&args, 0);
}

/// Whether a diagnosis warns that the record does not start in steady flight, at an equilibrium within 0.3 kts
/// of `kts`.
fn settles_at(d: &serde_json::Value, kts: f64) -> bool {
    d["warnings"].as_array().unwrap().iter().any(|w| {
        let w = w.as_str().unwrap();
        w.strip_prefix("the record does not start in steady flight: its inputs hold the model at ")
            .and_then(|rest| rest.split(' ').next()?.parse::<f64>().ok())
            .is_some_and(|v| (v - kts).abs() <= 0.3)
    })
}

/// Logs cut from a longer flight (the generator's `--log-from`), as a data system that starts recording mid-flight
/// writes them; the generator trims its flight at 109.8 kts. Logged from 14 s on, the record begins in the phugoid
/// the elevator 3-2-1-1 left, 2 kts fast and climbing at 2°: replayed from a trim at its start, it named an a_x and
/// a θ bias. Logged from 2.5 s on, it begins inside the 3-2-1-1's step, 1.8° of elevator off its usual value: the
/// replay flew the rest with that offset and named an a_x and an α bias. Now the replay starts after the
/// maneuver, trims at the equilibrium its inputs hold, and names nothing; a hidden pitch-rate gyro bias on the
/// record logged from 14 s is named alone.
#[test]
fn a_log_cut_from_a_longer_flight_is_replayed_from_the_equilibrium_of_its_inputs() {
    for (log_from, effects, named) in [
        ("14", "[]", serde_json::json!([])),
        ("2.5", "[]", serde_json::json!([])),
        (
            "14",
            r#"[{"effect": "sensor_bias", "target": "q_rad_s", "value": 0.0105}]"#,
            serde_json::json!(["sensor_bias/q_rad_s"]),
        ),
    ] {
        let args = [
            "--cases",
            "1",
            "--seed",
            "41",
            "--effects",
            effects,
            "--duration",
            "40",
            "--log-from",
            log_from,
        ];
        let dir = generated(&args);
        let d = diagnose_cli(dir.path(), 0, &[], "cut");
        let got: Vec<String> = d["named_cause"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| {
                format!(
                    "{}/{}",
                    n["effect"].as_str().unwrap(),
                    n["target"].as_str().unwrap()
                )
            })
            .collect();
        assert_eq!(
            serde_json::json!(got),
            named,
            "logged from {log_from} s: {}",
            d["named_cause"]
        );
        assert!(
            settles_at(&d, 109.8),
            "logged from {log_from} s: {}",
            d["warnings"]
        );
        if let Some(bias) = d["named_cause"].as_array().unwrap().first() {
            let v = bias["value"].as_f64().unwrap();
            assert!((v - 0.0105).abs() <= 0.15 * 0.0105, "q bias {v}");
        }
    }
}

/// A clean record whose sensor channels the data system logged two samples (40 ms) later than its surface
/// channels. The search names an input delay of 40 ms on each of the three surfaces; they are one finding about the
/// record's timing, reported in `record_timing` and a warning, and no cause is named. The other way round, the
/// surfaces logged two samples late (a data system that stamps them later, or holds them), the response leads
/// them: nothing was named and the validation ISE stayed 15 times the record's as generated (7164 against 476),
/// for `time_skew` could not be negative; now one skew of −40 ms.
#[test]
fn a_time_skew_common_to_every_surface_is_the_records_timing_not_a_cause() {
    let args = CLEAN_SEED_41;
    let inputs = ["elevator_rad", "aileron_rad", "rudder_rad", "throttle"];
    for (surfaces_late, range, verb) in [
        (false, 0.037..0.043, "follows"),
        (true, -0.043..-0.037, "leads"),
    ] {
        let late = |mut rec: FlightRecord| {
            for (name, col) in rec.columns.iter_mut() {
                if inputs.contains(&name.as_str()) == surfaces_late {
                    let first = col[0];
                    col.rotate_right(2);
                    col[..2].fill(first);
                }
            }
            rec
        };
        let d = check_generated_with(&args, 0, late);
        assert_one_skew(&d, range);
        let said = format!("{verb} every surface that moves by the same 40 ms");
        assert!(
            d.warnings.iter().any(|w| w.contains(&said)),
            "{:?}",
            d.warnings
        );
    }
}

/// The record's timing is one `time_skew` on every surface, within `range` seconds.
fn assert_one_skew(d: &Diagnosis, range: std::ops::Range<f64>) {
    let timing: Vec<(String, String, f64)> = d
        .record_timing
        .iter()
        .map(|n| (n.effect.clone(), n.target.clone(), n.value))
        .collect();
    assert_eq!(timing.len(), 1, "{timing:?}");
    let (effect, target, v) = &timing[0];
    assert_eq!(
        (effect.as_str(), target.as_str()),
        ("time_skew", "surfaces")
    );
    assert!(range.contains(v), "{v} s outside {range:?}");
}

/// Every sensor channel through a first-order filter of 5 Hz (τ = 32 ms), as an attitude and rate system that
/// smooths its outputs logs them: the lag is common to every channel, so it is the record's timing. Before the
/// catalogue had `time_skew`, the same flight named an elevator delay of 22 ms alone.
#[test]
fn a_sensor_filter_on_every_channel_is_the_records_timing_not_an_elevator_delay() {
    let args = CLEAN_SEED_41;
    let inputs = [
        "time_s",
        "elevator_rad",
        "aileron_rad",
        "rudder_rad",
        "throttle",
    ];
    let filtered = |mut rec: FlightRecord| {
        let dt = rec.column("time_s").map_or(0.02, |t| t[1] - t[0]);
        let a = (-dt * 2.0 * std::f64::consts::PI * 5.0).exp();
        for (name, col) in rec.columns.iter_mut() {
            if !inputs.contains(&name.as_str()) {
                for k in 1..col.len() {
                    col[k] = a * col[k - 1] + (1.0 - a) * col[k];
                }
            }
        }
        rec
    };
    let d = check_generated_with(&args, 0, filtered);
    // A first-order lag τ acts as a delay of about τ at low frequency and less above 1/τ: 23 ms measured.
    assert_one_skew(&d, 0.018..0.032);
}

/// Accelerometers away from where the model reads its accelerations (the generator's `--imu-offset`: 0.8 m ahead
/// and 0.2 m below the eyepoint, with JSBSim's own angular accelerations; up to 1.1 m/s² on a_z): the lever arm is
/// the catalogue's `accelerometer_position` (`diagnose::lever_arm`), reported as the record's installation. Before
/// it, the clean record had an a_y scale ×0.45 named; now nothing, and the position 0.80 m forward, 0.20 m down.
/// Effects on the accelerometers' own channels are still found: an a_z bias and a `CY_beta` change (which moves
/// a_y).
#[test]
fn accelerometers_away_from_where_the_model_reads_them_are_no_cause() {
    let common = [
        "--cases",
        "1",
        "--seed",
        "41",
        "--duration",
        "40",
        "--imu-offset",
        "0.8,0,0.2",
        "--effects",
    ];
    let hidden = r#"[{"effect":"sensor_bias","target":"az_m_s2","value":0.3},
        {"effect":"aero_derivative","target":"CY_beta","value":0.6}]"#;
    for effects in ["[]", hidden] {
        let args: Vec<&str> = common.iter().copied().chain([effects]).collect();
        let d = check_generated_with(&args, 0, |rec| rec);
        let x = d
            .sensor_position
            .iter()
            .find(|n| n.target == "x")
            .map(|n| n.value);
        assert!(
            x.is_some_and(|x| (x - 0.8).abs() < 0.1),
            "{:?}",
            d.sensor_position
        );
    }
}

/// JSBSim's 737 with its accelerations logged at the CG, as a data system that reads them there (or computes
/// them from the load factors) writes them: 14.2 m behind, 0.76 m right of and 2.79 m below the eyepoint where the
/// replay reads them (the generator's `--imu-offset -14.2,0.76,2.79`). Before `accelerometer_position`, an a_x
/// scale ×0.37 and an a_x bias were named, and the validation ISE fell by 1 %; now nothing, and the position
/// within 0.3 m on each axis.
#[test]
fn the_737_s_accelerations_logged_at_its_cg_are_its_installation_not_a_cause() {
    let args = [
        "--aircraft",
        "737",
        "--cases",
        "1",
        "--seed",
        "44",
        "--effects",
        "[]",
        "--duration",
        "40",
        "--imu-offset=-14.2,0.76,2.79",
    ];
    let d = check_generated_with(&args, 0, |rec| rec);
    for (axis, truth) in [("x", -14.2), ("y", 0.76), ("z", 2.79)] {
        let v = d
            .sensor_position
            .iter()
            .find(|n| n.target == axis)
            .map(|n| n.value);
        assert!(
            v.is_some_and(|v| (v - truth).abs() < 0.3),
            "{axis}: {:?}",
            d.sensor_position
        );
    }
}

/// `Cm_de` ×1.54 and `CY_beta` ×1.47 in light turbulence (case 15 of `cargo bench --bench diagnose_eval --
/// --seed 5 --turbulence`, 35 s at 20 Hz). A `Cl_r` ×2.30 ± 0.13 named in the fourth round let the sequential
/// replacement put an accelerometer position (x −0.70 m) in `CY_beta`'s place, and the diagnosis reported the
/// position instead of the cause. A change must now stand two standard errors beyond its resolution, so a
/// `Cn_dr` ×1.26 ± 0.08 counts as within it and `Cl_r` loses its round to it. Checked: both hidden effects
/// named with values within 15 % of the effect (the common check), and no accelerometer position reported.
#[test]
fn a_cause_is_not_swapped_for_an_accelerometer_position_in_gusts() {
    let d = turbulent_bench_case(5, 15, DiagnoseOptions::default());
    assert!(
        d.sensor_position.is_empty(),
        "a position in place of the cause: {:?}",
        d.sensor_position
    );
}
