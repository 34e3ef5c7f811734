//! Specification of `flightid estimate`: a short-period model written in a TOML file, fitted to
//! two records that the test generates itself (a fine-step RK4 of the same equations with its own
//! noise, biases and initial states), and bad model files answered with exit 2 naming file, line
//! and name.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const TRUTH: [(&str, f64); 5] = [
    ("Z_alpha", -1.2),
    ("Z_de", -0.15),
    ("M_alpha", -8.0),
    ("M_q", -2.5),
    ("M_de", -12.0),
];

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flightid"))
}

fn model_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml")
}

/// 12 s at 25 Hz: a 3-2-1-1 elevator of 2°, RK4 at 1 ms with linear interpolation of the input,
/// noise σ = 0.002 rad on α and 0.005 rad/s on q, output biases, nonzero initial state.
fn write_record(path: &Path, x0: [f64; 2], bias: [f64; 2], seed: u64) {
    let [za, zde, ma, mq, mde] = TRUTH.map(|t| t.1);
    let de = |t: f64| {
        let a = 2f64.to_radians();
        let step = |t0: f64, t1: f64| if t >= t0 && t < t1 { 1.0 } else { 0.0 };
        a * (step(1.0, 1.9) - step(1.9, 2.5) + step(2.5, 2.8) - step(2.8, 3.1))
    };
    let dt = 0.04;
    let n = 300;
    // the sampled input, linearly interpolated as the fit assumes
    let samples: Vec<f64> = (0..n).map(|k| de(k as f64 * dt)).collect();
    let u = |t: f64| {
        let k = ((t / dt).floor() as usize).min(n - 2);
        let f = t / dt - k as f64;
        samples[k] + f * (samples[k + 1] - samples[k])
    };
    let f = |x: [f64; 2], t: f64| {
        [
            za * x[0] + x[1] + zde * u(t),
            ma * x[0] + mq * x[1] + mde * u(t),
        ]
    };
    let mut x = x0;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let (na, nq) = (
        Normal::new(0.0, 0.002).unwrap(),
        Normal::new(0.0, 0.005).unwrap(),
    );
    let mut csv = String::from("time_s,elevator_rad,alpha_rad,q_rad_s\n");
    let h = 0.001;
    for (k, &sample) in samples.iter().enumerate() {
        let t = k as f64 * dt;
        csv += &format!(
            "{t},{},{},{}\n",
            sample,
            x[0] + bias[0] + na.sample(&mut rng),
            x[1] + bias[1] + nq.sample(&mut rng)
        );
        for s in 0..40 {
            let tt = t + s as f64 * h;
            let k1 = f(x, tt);
            let k2 = f(
                [x[0] + 0.5 * h * k1[0], x[1] + 0.5 * h * k1[1]],
                tt + 0.5 * h,
            );
            let k3 = f(
                [x[0] + 0.5 * h * k2[0], x[1] + 0.5 * h * k2[1]],
                tt + 0.5 * h,
            );
            let k4 = f([x[0] + h * k3[0], x[1] + h * k3[1]], tt + h);
            for i in 0..2 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
            }
        }
    }
    std::fs::write(path, csv).unwrap();
}

#[test]
fn two_records_give_every_parameter_within_3_sigma_of_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, json) = (
        dir.path().join("a.csv"),
        dir.path().join("b.csv"),
        dir.path().join("est.json"),
    );
    write_record(&a, [0.02, -0.05], [0.01, -0.003], 1);
    write_record(&b, [-0.03, 0.04], [-0.02, 0.004], 2);
    let out = common::run_ok(
        bin()
            .arg("estimate")
            .arg("--model")
            .arg(model_file())
            .arg("--data")
            .arg(&a)
            .arg("--data")
            .arg(&b)
            .arg("--json")
            .arg(&json),
    );
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("M_alpha") && table.contains("converged"),
        "{table}"
    );
    let v = common::read_json(&json);
    assert_eq!(v["converged"], true, "{v}");
    for (name, truth) in TRUTH {
        let p = &v["parameters"][name];
        let (value, sigma) = (
            p["value"].as_f64().unwrap(),
            p["std_error"].as_f64().unwrap(),
        );
        // 3σ: a 0.3 % chance per parameter of a false failure for a correct estimator
        assert!(
            (value - truth).abs() < 3.0 * sigma,
            "{name}: {value} ± {sigma} vs {truth}"
        );
        assert!(
            sigma > 0.0 && sigma < 0.2 * truth.abs(),
            "{name}: σ {sigma}"
        );
    }
    // the q noise (σ 0.005 rad/s) is a sizeable share of the response: fit % is noise-limited
    assert!(v["fit_percent"]["q_rad_s"].as_f64().unwrap() > 50.0);
}

/// Two flights in one log, with a 1 s dropout between them (a data system that stopped and started again):
/// `estimate` splits the log at the dropout, says so, and fits the two pieces as the records they are, each
/// with its own initial state and biases: the same estimates as from the two files, to 1e-6. Fitted across
/// the gap as one record, the second flight's initial state would have to follow from the first's.
#[test]
fn a_log_with_a_dropout_is_fitted_as_its_pieces() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str| dir.path().join(name);
    write_record(&file("a.csv"), [0.02, -0.05], [0.01, -0.003], 1);
    write_record(&file("b.csv"), [-0.03, 0.04], [-0.02, 0.004], 2);
    let mut log = std::fs::read_to_string(file("a.csv")).unwrap();
    for row in std::fs::read_to_string(file("b.csv"))
        .unwrap()
        .lines()
        .skip(1)
    {
        let (t, rest) = row.split_once(',').unwrap();
        log += &format!("{},{rest}\n", t.parse::<f64>().unwrap() + 13.0);
    }
    std::fs::write(file("log.csv"), log).unwrap();
    let run = |data: &[&str], json: &str| {
        let mut cmd = bin();
        cmd.arg("estimate").arg("--model").arg(model_file());
        for d in data {
            cmd.arg("--data").arg(file(d));
        }
        let out = common::run_ok(cmd.arg("--json").arg(file(json)));
        (
            common::read_json(&file(json)),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let (two, _) = run(&["a.csv", "b.csv"], "two.json");
    let (one, stderr) = run(&["log.csv"], "one.json");
    assert!(
        stderr.contains("a dropout of 1.04") && stderr.contains("after t = 11.96 s"),
        "{stderr}"
    );
    for (name, _) in TRUTH {
        let (a, b) = (
            two["parameters"][name]["value"].as_f64().unwrap(),
            one["parameters"][name]["value"].as_f64().unwrap(),
        );
        assert!((a - b).abs() <= 1e-6 * a.abs(), "{name}: {b} against {a}");
    }
}

/// Runs `estimate` on a model text and returns (exit code, stderr).
fn bad_model(text: &str, csv: &Path) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("bad.toml");
    std::fs::write(&model, text).unwrap();
    let out = bin()
        .arg("estimate")
        .arg("--model")
        .arg(&model)
        .arg("--data")
        .arg(csv)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_model_files_exit_2_with_file_line_and_name() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("a.csv");
    write_record(&csv, [0.0, 0.0], [0.0, 0.0], 3);
    let good = std::fs::read_to_string(model_file()).unwrap();
    let cases = [
        // an unknown name in an equation (line 16 of the file holds q_rad_s's equation)
        (
            good.replace("M_q*q_rad_s", "M_qq*q_rad_s"),
            "bad.toml:16",
            "M_qq",
        ),
        // wrong arity
        (
            good.replace("Z_de*elevator_rad\"", "Z_de*sin(elevator_rad, q_rad_s)\""),
            "bad.toml:15",
            "sin",
        ),
        // a column the record does not have
        (
            good.replace(
                "inputs  = [\"elevator_rad\"]",
                "inputs  = [\"elevator_rad\", \"thrust_n\"]",
            ),
            "bad.toml:4",
            "thrust_n",
        ),
        // process noise on a name that is not a state (line 21)
        (
            good.replace(
                "output_bias   = [\"alpha_rad\", \"q_rad_s\"]",
                "output_bias   = [\"alpha_rad\", \"q_rad_s\"]\nprocess_noise = [\"gust\"]",
            ),
            "bad.toml:21",
            "gust",
        ),
    ];
    for (text, at, name) in cases {
        let (code, err) = bad_model(&text, &csv);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(at) && err.contains(name),
            "expected {at} and {name} in: {err}"
        );
    }
}

/// `--report DIR`: overlays and residuals per record and output, the parameter and correlation
/// tables; a directory flightid did not write is refused before any work (exit 2), an earlier
/// report is replaced.
#[test]
fn report_holds_overlays_residuals_and_the_correlation_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.csv");
    write_record(&a, [0.02, -0.05], [0.01, -0.003], 3);
    let report = dir.path().join("report");
    let run = |method: &str| {
        bin()
            .arg("estimate")
            .arg("--model")
            .arg(model_file())
            .arg("--data")
            .arg(&a)
            .arg("--method")
            .arg(method)
            .arg("--report")
            .arg(&report)
            .output()
            .unwrap()
    };
    let out = run("oe");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["alpha_rad", "q_rad_s"] {
        for suffix in ["", "_residual"] {
            let svg = report.join(format!("record0_{name}{suffix}.svg"));
            assert!(svg.is_file(), "{} missing", svg.display());
        }
    }
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(
        html.contains("Correlation matrix") && html.contains("x0:alpha_rad@"),
        "{html}"
    );
    assert!(html.contains("measured") && html.contains("model (oe)"));
    // an earlier report is replaced (here by the filter error method's)
    let out = run("fem");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(html.contains("model (fem)") && html.contains("process_noise:q_rad_s"));
    // a directory of the user's is not
    let mine = dir.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let out = bin()
        .arg("estimate")
        .arg("--model")
        .arg(model_file())
        .arg("--data")
        .arg(&a)
        .arg("--report")
        .arg(&mine)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(mine.join("notes.txt").is_file());
}

/// Start values "auto" and `--method n4sid` refuse what they cannot do, exit 2, saying why: a
/// parameter that enters an equation nonlinearly, a state the record does not measure, n4sid
/// without channels, and a report n4sid does not write.
#[test]
fn auto_start_values_and_n4sid_refuse_bad_requests_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("a.csv");
    write_record(&csv, [0.0, 0.0], [0.0, 0.0], 5);
    let good = std::fs::read_to_string(model_file()).unwrap();
    let auto = good.replace("M_q     = -1.5", "M_q     = \"auto\"");
    let cases = [
        (
            auto.replace("M_q*q_rad_s", "M_q*M_q*q_rad_s"),
            "nonlinearly",
        ),
        (
            auto.replace(
                "states  = [\"alpha_rad\", \"q_rad_s\"]",
                "states  = [\"alpha_rad\", \"q_rad_s\", \"theta_rad\"]",
            )
            .replace("[equations]", "[equations]\ntheta_rad = \"q_rad_s\""),
            "theta_rad",
        ),
        (
            good.replace("M_q     = -1.5", "M_q     = \"guess\""),
            "or \"auto\"",
        ),
    ];
    for (text, why) in cases {
        let (code, err) = bad_model(&text, &csv);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(why), "expected '{why}' in: {err}");
    }
    let (code, err) = bad_model(&auto, &csv);
    assert_eq!(
        code, 0,
        "a model that is affine in its auto parameter fits: {err}"
    );
    assert!(err.contains("start values from the records"), "{err}");

    let run = |args: &[&str]| {
        let out = bin()
            .arg("estimate")
            .args(args)
            .arg("--data")
            .arg(&csv)
            .output()
            .unwrap();
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, err) = run(&["--method", "n4sid"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--inputs and --outputs"), "{err}");
    let report = dir.path().join("rep");
    let (code, err) = run(&[
        "--method",
        "n4sid",
        "--inputs",
        "elevator_rad",
        "--outputs",
        "alpha_rad,q_rad_s",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(!report.exists());
    let (code, err) = run(&[
        "--method",
        "n4sid",
        "--inputs",
        "elevator_rad",
        "--outputs",
        "nope",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("'nope'"), "{err}");
    let (code, err) = run(&["--method", "oe"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("needs --model"), "{err}");
    let (code, err) = run(&[
        "--method",
        "n4sid",
        "--inputs",
        "elevator_rad",
        "--outputs",
        "alpha_rad,q_rad_s",
    ]);
    assert_eq!(code, 0, "{err}");
}
