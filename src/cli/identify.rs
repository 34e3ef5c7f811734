//! `flightid identify`: identify a continuous transfer function from one input column to one output column of
//! a flight-data CSV.

use super::common::emit_json;
use super::paper::text_table;
use crate::cli::UsageError;
use crate::data::{self, FlightRecord};
use crate::ident::{self, IdentError, IdentOptions, Method};
use crate::report::Table;
use anyhow::Context;
use serde_json::json;
use std::path::PathBuf;

/// Identify B(s)/A(s)·e^(-τs) from an input column to an output column of a flight-data CSV (from
/// `flightid fly`, or measured) with the paper's least squares (ls), instrumental variables (iv), SRIVC or
/// output error (oe). Trim values (the means before the input first moves) are removed first.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid identify --data doublet.csv --input elevator --output theta_rad --method srivc\n  flightid identify --data roll.csv --input aileron_rad --output phi_rad --method oe --json out.json"
)]
pub struct IdentifyCmd {
    /// Flight-data CSV (DESIGN.md §4 schema; any columns).
    #[arg(long, value_name = "FLIGHT.csv")]
    pub data: PathBuf,
    /// Input: a surface (elevator, aileron, rudder → <surface>_rad) or any column name.
    #[arg(long)]
    pub input: String,
    /// Output column, e.g. theta_rad, phi_rad, q_rad_s.
    #[arg(long)]
    pub output: String,
    /// Estimator: ls (the paper's ARX least squares), iv, srivc or oe.
    #[arg(long, default_value = "srivc")]
    pub method: String,
    /// Number of poles.
    #[arg(long, default_value_t = 4)]
    pub poles: usize,
    /// Number of zeros (fewer than poles).
    #[arg(long, default_value_t = 2)]
    pub zeros: usize,
    /// Also estimate a pure input delay.
    #[arg(long)]
    pub delay: bool,
    /// Write the result as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
}

/// The column an `--input` names: `elevator` → `elevator_rad` when that column exists, else the name itself.
fn input_column(rec: &FlightRecord, name: &str) -> String {
    let with_unit = format!("{name}_rad");
    if rec.column(name).is_none() && rec.column(&with_unit).is_some() {
        with_unit
    } else {
        name.to_string()
    }
}

fn fmt_c(z: &num_complex::Complex64) -> String {
    if z.im.abs() < 1e-12 {
        format!("{:.6}", z.re)
    } else {
        format!("{:.6}{:+.6}i", z.re, z.im)
    }
}

/// Runs `flightid identify`.
pub fn run(args: &IdentifyCmd) -> anyhow::Result<()> {
    let method: Method = args
        .method
        .parse()
        .map_err(|e: IdentError| UsageError(format!("--method: {e}")))?;
    let rec = data::read_csv(&args.data).map_err(|e| UsageError(e.to_string()))?;
    let in_col = input_column(&rec, &args.input);
    let u = rec
        .require(&in_col, "the identification input (--input)")
        .map_err(|e| UsageError(format!("{}: {e}", args.data.display())))?;
    let y = rec
        .require(&args.output, "the identification output (--output)")
        .map_err(|e| UsageError(format!("{}: {e}", args.data.display())))?;
    let dt_s = rec.dt_s().ok_or_else(|| {
        UsageError(format!(
            "{}: {} samples, too few to identify anything",
            args.data.display(),
            rec.len()
        ))
    })?;
    // uniform sampling is assumed by every estimator: resample jittery records onto the median step
    let worst_jitter = rec
        .time_s
        .windows(2)
        .map(|w| ((w[1] - w[0]) - dt_s).abs())
        .fold(0.0, f64::max);
    let (u, y): (Vec<f64>, Vec<f64>) = if worst_jitter > 0.01 * dt_s {
        let t0 = rec.time_s[0];
        let n = ((rec.time_s[rec.len() - 1] - t0) / dt_s).floor() as usize + 1;
        let grid: Vec<f64> = (0..n).map(|k| t0 + k as f64 * dt_s).collect();
        eprintln!(
            "note: {} is not uniformly sampled (step varies by up to {:.3} ms); resampled at {:.4} s",
            args.data.display(),
            1e3 * worst_jitter,
            dt_s
        );
        (
            crate::signal::resample_linear(&rec.time_s, u, &grid),
            crate::signal::resample_linear(&rec.time_s, y, &grid),
        )
    } else {
        (u.to_vec(), y.to_vec())
    };
    let opts = IdentOptions {
        method,
        poles: args.poles,
        zeros: args.zeros,
        estimate_delay: args.delay,
    };
    let bad_input = |e: &IdentError| {
        matches!(
            e,
            IdentError::LengthMismatch { .. }
                | IdentError::TooFewSamples { .. }
                | IdentError::ConstantInput { .. }
                | IdentError::NonFinite { .. }
                | IdentError::InvalidOptions(_)
        )
    };
    let r = match ident::identify(&u, &y, dt_s, &opts) {
        Ok(r) => r,
        Err(e) if bad_input(&e) => {
            return Err(UsageError(format!(
                "{} ({} -> {}): {e}",
                args.data.display(),
                in_col,
                args.output
            ))
            .into())
        }
        Err(e) => {
            return Err(anyhow::Error::new(e)).with_context(|| {
                format!(
                    "identifying {} -> {} in {}",
                    in_col,
                    args.output,
                    args.data.display()
                )
            })
        }
    };
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    if args.json.as_deref() != Some("-") {
        print_result(args, &in_col, &r);
    }
    if let Some(target) = &args.json {
        emit_json(
            target,
            &json!({
                "data": args.data.display().to_string(),
                "input": in_col,
                "output": args.output,
                "result": r,
            }),
        )?;
    }
    Ok(())
}

fn print_result(args: &IdentifyCmd, in_col: &str, r: &ident::IdentResult) {
    println!(
        "{} -> {} from {}: {} samples at {:.4} s, method {}, {} poles / {} zeros",
        in_col,
        args.output,
        args.data.display(),
        r.n_samples,
        r.dt_s,
        r.method,
        args.poles,
        args.zeros
    );
    println!(
        "trim removed: input {:.6}, output {:.6}",
        r.u_offset, r.y_offset
    );
    let std_cell = |v: &[f64], i: usize| {
        v.get(i)
            .map(|s| format!("{s:.3e}"))
            .unwrap_or_else(|| "-".into())
    };
    let m = r.tf.num.len() - 1;
    let n = r.tf.den.len() - 1;
    let mut rows = Vec::new();
    for (i, c) in r.tf.num.iter().enumerate() {
        rows.push(vec![
            format!("b{} (s^{})", m - i, m - i),
            format!("{c:.6}"),
            std_cell(&r.num_std, i),
        ]);
    }
    for (i, c) in r.tf.den.iter().enumerate().skip(1) {
        rows.push(vec![
            format!("a{} (s^{})", n - i, n - i),
            format!("{c:.6}"),
            std_cell(&r.den_std, i),
        ]);
    }
    if let Some(d) = r.delay_s {
        rows.push(vec![
            "delay, s".into(),
            format!("{d:.4}"),
            r.delay_std_s
                .map(|s| format!("{s:.3e}"))
                .unwrap_or_else(|| "-".into()),
        ]);
    }
    println!(
        "\n{}",
        text_table(&Table {
            caption: "B(s)/A(s), A monic (± standard error)".into(),
            header: vec!["coefficient".into(), "value".into(), "± std".into()],
            rows,
        })
    );
    let pole_rows = r
        .poles
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mode = crate::lti::Mode::from_pole(*p);
            vec![
                fmt_c(p),
                r.pole_std
                    .get(k)
                    .map(|s| format!("({:.2e}, {:.2e})", s.re, s.im))
                    .unwrap_or_else(|| "-".into()),
                format!("{:.4}", mode.omega_n_rad_s),
                format!("{:.4}", mode.zeta),
                mode.time_constant_s
                    .map(|t| format!("{t:.3}"))
                    .unwrap_or_else(|| "-".into()),
                mode.period_s
                    .map(|t| format!("{t:.3}"))
                    .unwrap_or_else(|| "-".into()),
            ]
        })
        .collect();
    println!(
        "{}",
        text_table(&Table {
            caption: "poles and modes".into(),
            header: vec![
                "pole".into(),
                "std (re, im)".into(),
                "wn rad/s".into(),
                "zeta".into(),
                "tau s".into(),
                "period s".into(),
            ],
            rows: pole_rows,
        })
    );
    let zeros: Vec<String> = r.zeros.iter().map(fmt_c).collect();
    println!("zeros: {}", zeros.join(", "));
    println!(
        "fit: simulation {:.2} %, one-step-ahead {:.2} %",
        r.fit_sim_percent, r.fit_one_step_percent
    );
    let verdict = |t: &ident::CorrelationTest| {
        format!(
            "{} ({:.0} % of lags outside the 99 % bound ±{:.4})",
            if t.pass { "pass" } else { "FAIL" },
            100.0 * t.fraction_outside,
            t.bound_99
        )
    };
    println!("residual whiteness: {}", verdict(&r.residual_whiteness));
    println!(
        "input-residual independence: {}",
        verdict(&r.input_residual_independence)
    );
}
