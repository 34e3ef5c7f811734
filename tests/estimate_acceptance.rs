//! Acceptance of `flightid estimate` on records flightid did not write.
//!
//! Linear short period: `scripts/gen_short_period_records.py` (scipy's DOP853, its own noise,
//! biases and initial states, noise on the logged elevator too) writes two records per seed for
//! 20 seeds; each pair is fitted jointly with `models/short_period.toml` (initial states and output
//! biases estimated per record). Every parameter must lie within 3σ of the generator's truth in at
//! least 95 % of the seeds (19 of 20), and the σ must be honest: the RMS of the normalised errors
//! over all 100 estimates lies in [0.6, 1.6] (a σ inflated to pass would drive it towards 0).

use std::path::{Path, PathBuf};
use std::process::Command;

fn python() -> PathBuf {
    flightid::sim::env::python().expect("provisioned Python")
}

fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scripts")
        .join(name)
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn short_period_parameters_lie_within_3_sigma_of_an_independent_generators_truth() {
    let dir = tempfile::tempdir().unwrap();
    let seeds = 1..=20;
    let truth = generate("gen_short_period_records.py", dir.path(), 1, 20, &[]);
    let truth = truth.as_object().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml");
    let mut misses = std::collections::BTreeMap::<String, usize>::new();
    let mut z2 = Vec::new();
    for seed in seeds {
        let json = dir.path().join(format!("est{seed}.json"));
        let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
            .arg("estimate")
            .arg("--model")
            .arg(&model)
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_a.csv")))
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_b.csv")))
            .arg("--json")
            .arg(&json)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = read_json(&json);
        assert_eq!(v["converged"], true, "seed {seed}: {v}");
        for (name, t) in truth {
            let p = &v["parameters"][name];
            let (value, sigma) = (
                p["value"].as_f64().unwrap(),
                p["std_error"].as_f64().unwrap(),
            );
            let z = (value - t.as_f64().unwrap()) / sigma;
            z2.push(z * z);
            if z.abs() > 3.0 {
                *misses.entry(name.clone()).or_default() += 1;
            }
        }
    }
    for (name, m) in &misses {
        assert!(*m <= 1, "{name} outside 3σ in {m} of 20 seeds");
    }
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    assert!((0.6..=1.6).contains(&rms), "RMS normalised error {rms:.2}");
}

/// Runs `flightid estimate --method METHOD --model MODEL` on `csv`; the JSON estimate (written
/// as `<csv stem>-<tag>.json`).
fn estimate_with(
    dir: &Path,
    model: &Path,
    csv: &Path,
    method: &str,
    tag: &str,
) -> serde_json::Value {
    let json = dir.join(format!(
        "{}-{tag}.json",
        csv.file_stem().unwrap().to_string_lossy()
    ));
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .args(["estimate", "--method", method, "--model"])
        .arg(model)
        .arg("--data")
        .arg(csv)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_json(&json)
}

fn model_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models")
        .join(name)
}

fn value(v: &serde_json::Value, name: &str) -> (f64, f64) {
    let p = &v["parameters"][name];
    (
        p["value"].as_f64().unwrap(),
        p["std_error"].as_f64().unwrap(),
    )
}

fn spread(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// The c172x's short-period derivatives at the generator's trim (4000 ft, 100 KTAS) from JSBSim's
/// own aerodynamics: `scripts/oracle_aero.py` differences JSBSim's forces and moments about the
/// CG; the two-state model's derivatives follow (Klein & Morelli §3.6, α̇ folded in as a two-state
/// fit sees it): `Z_α = −q̄S(C_Lα + C_D)/(mV)`, `M_α = q̄Sc̄/I_yy (C_mα + C_mα̇ c̄/(2V) Z_α)`,
/// `M_q = q̄Sc̄/I_yy c̄/(2V) (C_mq + C_mα̇)`, `M_δe = q̄Sc̄/I_yy (C_mδe + C_mα̇ c̄/(2V) Z_δe)` with
/// `Z_δe = −q̄S C_Lδe/(mV)`, and `M_α̇ = q̄Sc̄/I_yy c̄/(2V) C_mα̇` alone.
fn jsbsim_short_period_truth() -> std::collections::BTreeMap<&'static str, f64> {
    let out = Command::new(python())
        .arg(script("oracle_aero.py"))
        .output()
        .expect("run the aero oracle");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let get = |key: &str| -> f64 {
        text.lines()
            .find_map(|l| {
                let (k, v) = l.split_once(" = ")?;
                (k.trim() == key).then(|| v.split_whitespace().next()?.parse().ok())?
            })
            .unwrap_or_else(|| panic!("{key} missing from the oracle's output"))
    };
    let (qbar, s, c, v) = (get("qbar_pa"), get("S_m2"), get("cbar_m"), get("V_m_s"));
    let (m, iyy) = (get("mass_kg"), get("iyy_kg_m2"));
    let moment = qbar * s * c / iyy;
    let rate = c / (2.0 * v);
    let z_alpha = -qbar * s * (get("CL_alpha") + get("CD_trim")) / (m * v);
    let z_de = -qbar * s * get("CL_de") / (m * v);
    let m_adot = moment * rate * get("Cm_adot");
    std::collections::BTreeMap::from([
        ("Z_alpha", z_alpha),
        ("M_alpha", moment * get("Cm_alpha") + m_adot * z_alpha),
        ("M_q", moment * rate * get("Cm_q") + m_adot),
        ("M_de", moment * get("Cm_de") + m_adot * z_de),
        ("M_adot", m_adot),
    ])
}

/// JSBSim's c172x flown by `scripts/fly_turbulent_short_period.py` through JSBSim's own Python API:
/// an elevator 3-2-1-1 pair around trim, once in still air and in four MIL-F-8785C turbulence seeds
/// (`atmosphere/turb-type` 3, severity 3: moderate), 11 s at 50 Hz. The truth is JSBSim's own
/// aerodynamics about the CG ([`jsbsim_short_period_truth`]). Three fits per seed:
///
/// - output error with the plain short period (`models/short_period.toml`): its estimates scatter
///   far from the truth (its σ, corrected for coloured residuals, are wide);
/// - the filter error method with that model (white process noise on α̇ and q̇): it detects the
///   turbulence and is precise, but biased — JSBSim's gusts reach the pitching moment through the
///   aerodynamic pitch rate `q − q_g`, a filtered copy of the gust's α̇, which a diagonal white `F`
///   cannot describe (M_q near −2.6 against −4.3, beyond 3σ on every seed);
/// - the filter error method with the Dryden gust written into the model
///   (`models/short_period_gust.toml`, process noise on the gust state alone), started from the
///   still-air output-error estimate as a flight-test engineer starts from a calm-air flight.
///
/// Asserted: the gust model's Z_α, M_α, M_q and M_δe lie within 3σ of JSBSim's truth in at least 14
/// of the 16 estimates (measured: 15; the miss is M_δe on seed 1 at 4.9σ, 10 % off); the white
/// filter's M_q is beyond 3σ on at least 3 of 4 seeds (measured: all 4, 9–14σ); output error's RMS
/// relative error on M_α, M_q, M_δe is more than three times the gust model's. Z_α comes out
/// 8–44 % steep (within 3σ), and M_α̇ alone, which only the gust separates, is printed, not
/// asserted (measured −1.6 … −2.3 against −1.27): the model leaves out the speed changes
/// (±7 % in V) and the rotation of the gust into body axes at up to 12° pitch and 20° bank.
#[test]
fn jsbsim_turbulence_filter_error_with_a_gust_state_finds_jsbsims_derivatives() {
    let dir = tempfile::tempdir().unwrap();
    let fly = |name: &str, args: &[&str]| {
        let csv = dir.path().join(format!("{name}.csv"));
        let out = Command::new(python())
            .arg(script("fly_turbulent_short_period.py"))
            .arg(&csv)
            .args(args)
            .output()
            .expect("run JSBSim");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        csv
    };
    let truth = jsbsim_short_period_truth();
    let plain = model_file("short_period.toml");
    let clean = fly("still", &[]);
    let still = estimate_with(dir.path(), &plain, &clean, "oe", "oe");
    let still_fem = estimate_with(dir.path(), &plain, &clean, "fem", "fem");
    let q_still = still_fem["nuisance"]["process_noise:alpha_rad"]["value"]
        .as_f64()
        .unwrap();
    // the gust model, started from the still-air estimate
    let mut gust_text = std::fs::read_to_string(model_file("short_period_gust.toml")).unwrap();
    for name in ["Z_alpha", "Z_de", "M_alpha", "M_q", "M_de"] {
        let (v, _) = value(&still, name);
        let line = gust_text
            .lines()
            .find(|l| l.split('=').next().map(str::trim) == Some(name))
            .unwrap()
            .to_string();
        gust_text = gust_text.replace(&line, &format!("{name} = {v}"));
    }
    let gust = dir.path().join("short_period_gust.toml");
    std::fs::write(&gust, gust_text).unwrap();

    let names = ["Z_alpha", "M_alpha", "M_q", "M_de"];
    println!("JSBSim truth: {truth:.3?}");
    let mut within = 0;
    let mut white_mq_misses = 0;
    let (mut rel_oe, mut rel_gust) = (Vec::new(), Vec::new());
    let mut by_method: std::collections::BTreeMap<(&str, &str), Vec<f64>> = Default::default();
    for seed in 1..=4 {
        let csv = fly(
            &format!("turbulence{seed}"),
            &["--turbulence", "milspec", "--seed", &seed.to_string()],
        );
        for (tag, model, method) in [
            ("oe", &plain, "oe"),
            ("fem", &plain, "fem"),
            ("fem+gust", &gust, "fem"),
        ] {
            let est = estimate_with(dir.path(), model, &csv, method, &tag.replace('+', "_"));
            assert_eq!(est["converged"], true, "seed {seed} {tag}: {est}");
            if tag == "fem+gust" {
                let noise: Vec<&String> = est["nuisance"]
                    .as_object()
                    .unwrap()
                    .keys()
                    .filter(|k| k.starts_with("process_noise"))
                    .collect();
                assert_eq!(
                    noise,
                    ["process_noise:wg"],
                    "process noise only where declared"
                );
            }
            let mut row = Vec::new();
            for n in names.iter().chain(if tag == "fem+gust" {
                &["M_adot"][..]
            } else {
                &[][..]
            }) {
                let (v, s) = value(&est, n);
                let t = truth[n];
                let z = (v - t) / s;
                row.push(format!("{n} {v:.2}±{s:.2} ({z:+.1}σ)"));
                by_method.entry((tag, n)).or_default().push(v);
                if *n == "M_adot" {
                    continue;
                }
                let moment = n.starts_with("M_");
                match tag {
                    "oe" if moment => rel_oe.push(((v - t) / t).powi(2)),
                    "oe" => {}
                    "fem+gust" => {
                        if moment {
                            rel_gust.push(((v - t) / t).powi(2));
                        }
                        within += usize::from(z.abs() <= 3.0);
                    }
                    _ => {
                        if *n == "M_q" && z.abs() > 3.0 {
                            white_mq_misses += 1;
                        }
                    }
                }
            }
            println!("seed {seed} {tag:8}: {}", row.join("  "));
            if tag == "fem" {
                let q = &est["nuisance"]["process_noise:alpha_rad"];
                let (qv, qt) = (q["value"].as_f64().unwrap(), q["t"].as_f64().unwrap());
                assert!(
                    qv > 10.0 * q_still && qt > 5.0,
                    "turbulence not detected: {q} (still air {q_still:.3e})"
                );
            }
        }
    }
    let rms = |x: &[f64]| (x.iter().sum::<f64>() / x.len() as f64).sqrt();
    let (oe, gust_rms) = (rms(&rel_oe), rms(&rel_gust));
    println!(
        "within 3σ of JSBSim's truth (gust model): {within}/16; white-noise M_q beyond 3σ on \
         {white_mq_misses}/4 seeds; RMS relative error of M_α, M_q, M_δe: oe {:.0} %, fem+gust {:.0} %",
        100.0 * oe,
        100.0 * gust_rms
    );
    for n in ["M_alpha", "M_de"] {
        println!(
            "{n}: seed-to-seed spread oe {:.2}, fem {:.2}, fem+gust {:.2}",
            spread(&by_method[&("oe", n)]),
            spread(&by_method[&("fem", n)]),
            spread(&by_method[&("fem+gust", n)])
        );
    }
    assert!(
        within >= 14,
        "gust model: only {within}/16 within 3σ of JSBSim's truth"
    );
    assert!(
        white_mq_misses >= 3,
        "the white-noise filter was expected to miss M_q (the gust's pitch rate is not white): \
         {white_mq_misses}/4"
    );
    assert!(
        oe > 3.0 * gust_rms,
        "output error ({:.0} %) should miss the moment derivatives by more than three times the \
         gust model ({:.0} %)",
        100.0 * oe,
        100.0 * gust_rms
    );
}

/// Runs the generator `name` (in `scripts/`) into `dir` for seeds `first..first+n` (extra
/// arguments appended); the truth it writes.
fn generate(name: &str, dir: &Path, first: u32, n: u32, extra: &[&str]) -> serde_json::Value {
    let out = Command::new(python())
        .arg(script(name))
        .arg(dir)
        .arg(first.to_string())
        .arg(n.to_string())
        .args(extra)
        .output()
        .expect("run the generator");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_json(&dir.join("truth.json"))
}

/// Fits `models/longitudinal_nonlinear.toml` (every parameter "auto") to seed `seed`'s two records.
fn fit_longitudinal(dir: &Path, seed: u32) -> serde_json::Value {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/longitudinal_nonlinear.toml");
    let json = dir.join(format!("est{seed}.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
        .arg("estimate")
        .arg("--model")
        .arg(&model)
        .arg("--data")
        .arg(dir.join(format!("seed{seed}_a.csv")))
        .arg("--data")
        .arg(dir.join(format!("seed{seed}_b.csv")))
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "seed {seed}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("start values from the records"),
        "the auto start values are reported: {stderr}"
    );
    let v = read_json(&json);
    assert_eq!(v["converged"], true, "seed {seed}: {v}");
    v
}

/// A nonlinear longitudinal model written as a TOML file (states V, α, θ, q; elevator and a
/// measured thrust as inputs; V, α, θ, q, ax, az measured, with an α-vane and an az bias), fitted
/// with no start value given: scipy's DOP853 flies the same equations with its own trim, noise and
/// biases (`scripts/gen_longitudinal_records.py`), 40 s at 25 Hz, two records per seed.
///
/// - Inputs logged exactly (6 seeds, 60 estimates): at least 57 within 3σ of the truth, and the
///   RMS of the normalised errors in [0.5, 1.6] (measured: 0 of 60 beyond 3σ, RMS ≈ 0.9).
/// - Inputs logged with noise, as on a real aircraft (0.02° on the elevator, 10 N on the thrust;
///   3 seeds): the well-determined derivatives stay within a few percent (measured worst: CL_α
///   0.3 %, Cm_α 0.4 %, Cm_q 1.7 %, Cm_δe 1.0 %). Their σ are then optimistic (the input noise acts
///   as process noise that output error does not model: 13 of 60 estimates beyond 3σ over 6
///   seeds), which this test does not hide: it asserts only the relative errors there.
#[test]
fn nonlinear_longitudinal_toml_model_from_auto_start_values_recovers_the_truth() {
    let exact = tempfile::tempdir().unwrap();
    let truth = generate(
        "gen_longitudinal_records.py",
        exact.path(),
        1,
        6,
        &["exact-inputs"],
    );
    let truth = truth.as_object().unwrap();
    let (mut beyond, mut z2) = (Vec::new(), Vec::new());
    for seed in 1..=6 {
        let v = fit_longitudinal(exact.path(), seed);
        for (name, t) in truth {
            let (value, sigma) = value(&v, name);
            let z = (value - t.as_f64().unwrap()) / sigma;
            z2.push(z * z);
            if z.abs() > 3.0 {
                beyond.push(format!("seed {seed} {name} z = {z:.1}"));
            }
        }
    }
    assert!(beyond.len() <= 3, "beyond 3σ: {beyond:?}");
    let rms = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    assert!((0.5..=1.6).contains(&rms), "RMS normalised error {rms:.2}");

    let noisy = tempfile::tempdir().unwrap();
    let truth = generate("gen_longitudinal_records.py", noisy.path(), 1, 3, &[]);
    for seed in 1..=3 {
        let v = fit_longitudinal(noisy.path(), seed);
        for (name, tolerance) in [
            ("CL_alpha", 0.02),
            ("Cm_alpha", 0.02),
            ("Cm_q", 0.05),
            ("Cm_de", 0.03),
            ("CD_0", 0.06),
            ("CL_de", 0.15),
        ] {
            let t = truth[name].as_f64().unwrap();
            let (value, _) = value(&v, name);
            assert!(
                ((value - t) / t).abs() < tolerance,
                "seed {seed} {name} {value} against {t}"
            );
        }
    }
}

/// `estimate --method n4sid` on the independent short-period generator's records (5 seeds, two
/// records each): the subspace model, written in the basis of the measured α and q, reads as the
/// short-period derivatives; they land within 8 % of the truth (measured: within 3 % on M_α, M_q,
/// M_δe, Z_α). Z_δe is small and poorly determined and is not asserted.
#[test]
fn n4sid_reads_the_short_period_derivatives_off_independent_records() {
    let dir = tempfile::tempdir().unwrap();
    let truth = generate("gen_short_period_records.py", dir.path(), 1, 5, &[]);
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/short_period.toml");
    for seed in 1..=5 {
        let out = Command::new(env!("CARGO_BIN_EXE_flightid"))
            .args(["estimate", "--method", "n4sid", "--model"])
            .arg(&model)
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_a.csv")))
            .arg("--data")
            .arg(dir.path().join(format!("seed{seed}_b.csv")))
            .args(["--json", "-"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        let v: serde_json::Value = serde_json::from_str(&text[text.find('{').unwrap()..]).unwrap();
        assert_eq!(v["order"], 2);
        assert_eq!(v["states"], serde_json::json!(["alpha_rad", "q_rad_s"]));
        let a = |i: usize, j: usize| v["a"][i][j].as_f64().unwrap();
        let b = |i: usize| v["b"][i][0].as_f64().unwrap();
        for (name, got) in [
            ("Z_alpha", a(0, 0)),
            ("M_alpha", a(1, 0)),
            ("M_q", a(1, 1)),
            ("M_de", b(1)),
        ] {
            let t = truth[name].as_f64().unwrap();
            assert!(
                ((got - t) / t).abs() < 0.08,
                "seed {seed} {name} {got} against {t}"
            );
        }
        assert!(
            (a(0, 1) - 1.0).abs() < 0.08,
            "seed {seed}: α̇ per q {}",
            a(0, 1)
        );
        let modes = v["modes"].as_array().unwrap();
        assert_eq!(modes.len(), 1, "one short-period pair: {modes:?}");
    }
}
