//! `flightid identify`: identify a continuous transfer function from one input column to one output column of
//! a flight-data CSV.

use super::common::{emit_json, resample, ColumnsArg};
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
    /// Flight-data CSV (docs/data.md; any columns). Repeat to fit several files jointly.
    #[arg(long, value_name = "FLIGHT.csv", required = true)]
    pub data: Vec<PathBuf>,
    /// Input: a surface (elevator, aileron, rudder → <surface>_rad) or any column name.
    #[arg(long)]
    pub input: String,
    /// Output column, e.g. theta_rad, phi_rad, q_rad_s.
    #[arg(long)]
    pub output: String,
    /// Estimator: ls (the paper's ARX least squares), iv, srivc or oe.
    #[arg(long, default_value = "srivc")]
    pub method: String,
    /// Number of poles. Without --poles and --zeros the order is chosen from the data: every
    /// order up to 4 poles is fitted and the simplest whose simulation fit is within 1 point of the
    /// best is kept, setting aside unstable poles, pole-zero cancellations and insignificant poles
    /// (the table lists each). With several records or segments the default is 4.
    #[arg(long)]
    pub poles: Option<usize>,
    /// Number of zeros (fewer than poles; default with --poles: 2, or poles − 1 if fewer).
    #[arg(long)]
    pub zeros: Option<usize>,
    /// Also estimate a pure input delay.
    #[arg(long)]
    pub delay: bool,
    /// Identify on maneuver N as listed by `flightid segments` (K:N = segment N of the K-th
    /// --data file). Repeat to fit several segments jointly.
    #[arg(long, value_name = "N|K:N")]
    pub segment: Vec<String>,
    /// With --segment: seconds of record used, from 1 s before the maneuver starts (default: up
    /// to 5 s after it ends).
    #[arg(long, value_name = "SECONDS")]
    pub window_s: Option<f64>,
    /// Resample every record onto a uniform grid at this rate first (linear interpolation).
    #[arg(long = "resample-hz", value_name = "HZ", value_parser = crate::limits::RESAMPLE_HZ.parser())]
    pub resample_hz: Option<f64>,
    /// Write the result as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    #[command(flatten)]
    pub columns: ColumnsArg,
}

/// The input and output columns `--input` and `--output` name in `rec`: exact names, or names
/// without their unit suffix (`elevator` → `elevator_rad`, `theta` → `theta_rad`); `label` names
/// the record in errors.
fn io_columns(
    rec: &FlightRecord,
    args: &IdentifyCmd,
    label: &str,
) -> anyhow::Result<(String, String)> {
    let present = rec.column_names();
    let resolve = |name: &str, why: &str| {
        data::resolve_column(&present, name, why).map_err(|e| UsageError(format!("{label}: {e}")))
    };
    Ok((
        resolve(&args.input, "as the identification input (--input)")?,
        resolve(&args.output, "as the identification output (--output)")?,
    ))
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
    super::common::check_outputs(&[super::common::json_path(&args.json)], &[])?;
    let method: Method = args
        .method
        .parse()
        .map_err(|e: IdentError| UsageError(format!("--method: {e}")))?;
    if args.data.len() > 1 || !args.segment.is_empty() || args.window_s.is_some() {
        return run_joint(args, method);
    }
    let data_path = &args.data[0];
    let rec = read_record(data_path, args, true)?;
    let (in_col, out_col) = io_columns(&rec, args, &data_path.display().to_string())?;
    let u = rec.column(&in_col).unwrap_or_default();
    let y = rec.column(&out_col).unwrap_or_default();
    let dt_s = rec.dt_s().ok_or_else(|| {
        UsageError(format!(
            "{}: {} samples, too few to identify anything",
            data_path.display(),
            rec.len()
        ))
    })?;
    // uniform sampling is assumed by every estimator: resample jittery records onto the median step
    let (uy, jitter_s) = crate::signal::on_uniform_step(&rec.time_s, &[u, y], dt_s);
    if let Some(worst) = jitter_s {
        eprintln!(
            "note: {} is not uniformly sampled (step varies by up to {:.3} ms); resampled at {:.4} s",
            data_path.display(),
            1e3 * worst,
            dt_s
        );
    }
    let mut uy = uy.into_iter();
    let (u, y) = (uy.next().unwrap_or_default(), uy.next().unwrap_or_default());
    let opts = given_options(args, method);
    let (poles, zeros) = (opts.poles, opts.zeros);
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
    let selected = if args.poles.is_none() && args.zeros.is_none() {
        ident::select_order(&u, &y, dt_s, method, args.delay, 4).map(Some)
    } else {
        Ok(None)
    };
    let fitted = match selected {
        Ok(Some(sel)) => Ok((sel.result, sel.poles, sel.zeros, Some(sel.candidates))),
        Ok(None) => ident::identify(&u, &y, dt_s, &opts).map(|r| (r, poles, zeros, None)),
        Err(e) => Err(e),
    };
    let (r, poles, zeros, candidates) = match fitted {
        Ok(r) => r,
        Err(e) if bad_input(&e) => {
            return Err(UsageError(format!(
                "{} ({} -> {}): {e}",
                data_path.display(),
                in_col,
                out_col
            ))
            .into())
        }
        Err(e) => {
            return Err(anyhow::Error::new(e)).with_context(|| {
                format!(
                    "identifying {} -> {} in {}",
                    in_col,
                    out_col,
                    data_path.display()
                )
            })
        }
    };
    for w in &r.warnings {
        super::warn(w);
    }
    if args.json.as_deref() != Some("-") {
        if let Some(c) = &candidates {
            print_order_selection(c, poles, zeros);
        }
        print_result(
            (poles, zeros),
            &data_path.display().to_string(),
            &in_col,
            &out_col,
            &r,
        );
    }
    if let Some(target) = &args.json {
        emit_json(
            target,
            &json!({
                "data": data_path.display().to_string(),
                "input": in_col,
                "output": out_col,
                "result": r,
                "order_selection": candidates,
            }),
        )?;
    }
    Ok(())
}

/// The options as given: the order with its defaults (4 poles; 2 zeros, fewer than the poles).
fn given_options(args: &IdentifyCmd, method: Method) -> IdentOptions {
    let poles = args.poles.unwrap_or(4);
    IdentOptions {
        method,
        poles,
        zeros: args.zeros.unwrap_or(2.min(poles.saturating_sub(1))),
        estimate_delay: args.delay,
    }
}

/// The orders tried and the one chosen.
fn print_order_selection(candidates: &[ident::OrderCandidate], poles: usize, zeros: usize) {
    let rows = candidates
        .iter()
        .map(|c| {
            let chosen = c.poles == poles && c.zeros == zeros;
            vec![
                format!("{}/{}", c.poles, c.zeros),
                match c.fit_sim_percent {
                    Some(f) if f < -999.0 => "< -999".into(),
                    Some(f) => format!("{f:.2}"),
                    None => "-".into(),
                },
                match (&c.set_aside, chosen) {
                    (_, true) => "chosen".into(),
                    (Some(why), _) => format!("set aside: {why}"),
                    (None, _) => "eligible".into(),
                },
            ]
        })
        .collect();
    let caption = format!(
        "order chosen from the data: the simplest within {} point of the best simulation fit",
        ident::FIT_MARGIN_PERCENT
    );
    let table = Table::new(caption, &["poles/zeros", "fit %", "verdict"], rows);
    println!("{}", text_table(&table));
}

fn print_result(
    (poles, zeros): (usize, usize),
    source: &str,
    in_col: &str,
    out_col: &str,
    r: &ident::IdentResult,
) {
    println!(
        "{} -> {} from {}: {} samples at {:.4} s, method {}, {} poles / {} zeros",
        in_col, out_col, source, r.n_samples, r.dt_s, r.method, poles, zeros
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
        text_table(&Table::new(
            "B(s)/A(s), A monic (± standard error)",
            &["coefficient", "value", "± std"],
            rows,
        ))
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
        text_table(&Table::new(
            "poles and modes",
            &[
                "pole",
                "std (re, im)",
                "wn rad/s",
                "zeta",
                "tau s",
                "period s",
            ],
            pole_rows,
        ))
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

/// Reads a flight-data CSV through the column map, resampled at `--resample-hz` when given. A record fitted
/// whole (`whole`: not cut to a `--segment`) with a dropout is refused: see [`refuse_dropouts`].
fn read_record(
    path: &std::path::Path,
    args: &IdentifyCmd,
    whole: bool,
) -> anyhow::Result<FlightRecord> {
    let rec = args.columns.read(path)?;
    if whole {
        refuse_dropouts(&rec, path)?;
    }
    resample(rec, args.resample_hz, path)
}

/// Bad input when the record has a dropout (a step over 2.5 median steps, `data::dropout_starts`, the rule
/// that splits records for `estimate`): identify fits one uniformly sampled record, and interpolating over the
/// missing samples, with `--resample-hz` or without, would invent the motion in them (docs/data.md).
fn refuse_dropouts(rec: &FlightRecord, path: &std::path::Path) -> anyhow::Result<()> {
    let starts = data::dropout_starts(&rec.time_s);
    let Some(&k) = starts.first() else {
        return Ok(());
    };
    let t = &rec.time_s;
    let more = match starts.len() {
        1 => String::new(),
        n => format!(" (and {} more)", n - 1),
    };
    Err(UsageError(format!(
        "{}: a dropout of {:.3} s after t = {} s{more}: identify fits one uniformly sampled record, and \
         interpolating over the missing samples (with --resample-hz or without) would invent the motion in \
         them; fit a maneuver on one side of it (`--segment N`, see `flightid segments`), or use `flightid \
         estimate`, which fits the pieces between dropouts",
        path.display(),
        t[k] - t[k - 1],
        t[k - 1]
    ))
    .into())
}

/// The records a joint identification runs on: every `--data` file whole, or the `--segment`s.
fn joint_records(args: &IdentifyCmd) -> anyhow::Result<Vec<(String, FlightRecord)>> {
    let recs: Vec<FlightRecord> = args
        .data
        .iter()
        .map(|p| read_record(p, args, args.segment.is_empty()))
        .collect::<anyhow::Result<_>>()?;
    if args.segment.is_empty() {
        if args.window_s.is_some() {
            return Err(UsageError("--window-s applies to --segment".into()).into());
        }
        return Ok(args
            .data
            .iter()
            .map(|p| p.display().to_string())
            .zip(recs)
            .collect());
    }
    let mut out = Vec::new();
    for text in &args.segment {
        let r: data::SegmentRef = text
            .parse()
            .map_err(|e: data::DataError| UsageError(format!("--segment: {e}")))?;
        let k = match (r.file, args.data.len()) {
            (Some(k), n) if k <= n => k,
            (Some(k), n) => {
                return Err(UsageError(format!(
                    "--segment {text}: there is no --data file {k} (given: {n})"
                ))
                .into())
            }
            (None, 1) => 1,
            (None, _) => {
                return Err(UsageError(format!(
                    "--segment {text}: with several --data files, say which: --segment K:{}",
                    r.segment
                ))
                .into())
            }
        };
        let file = args.data[k - 1].display().to_string();
        let (seg, part) = data::segment_window(
            &recs[k - 1],
            &file,
            r.segment,
            args.window_s,
            &data::SegmentOptions::default(),
        )
        .map_err(|e| UsageError(e.to_string()))?;
        let label = format!(
            "{file} segment {} ({} {} {:.2}-{:.2} s)",
            r.segment,
            seg.surface,
            seg.kind.name(),
            seg.start_s,
            seg.end_s
        );
        out.push((label, part));
    }
    Ok(out)
}

/// `identify` on several files or segments: one transfer function fitted jointly
/// ([`ident::identify_joint`]), each record with its own trim, offset and initial condition.
fn run_joint(args: &IdentifyCmd, method: Method) -> anyhow::Result<()> {
    let named = joint_records(args)?;
    let mut records = Vec::with_capacity(named.len());
    let (mut in_col, mut out_col) = (String::new(), String::new());
    for (label, rec) in &named {
        (in_col, out_col) = io_columns(rec, args, label)?;
        let column = |name: &str, why: &str| -> anyhow::Result<Vec<f64>> {
            Ok(rec
                .require(name, why)
                .map_err(|e| UsageError(format!("{label}: {e}")))?
                .to_vec())
        };
        let dt_s = rec.dt_s().ok_or_else(|| {
            UsageError(format!(
                "{label}: {} samples, too few to identify anything",
                rec.len()
            ))
        })?;
        records.push(ident::JointRecord {
            label: label.clone(),
            u: column(&in_col, "the identification input (--input)")?,
            y: column(&out_col, "the identification output (--output)")?,
            dt_s,
        });
    }
    let opts = given_options(args, method);
    let (poles, zeros) = (opts.poles, opts.zeros);
    let joint = match ident::identify_joint(&records, &opts) {
        Ok(j) => j,
        Err(e @ (IdentError::InvalidOptions(_) | IdentError::TooFewSamples { .. })) => {
            return Err(UsageError(e.to_string()).into())
        }
        Err(e) => {
            return Err(anyhow::Error::new(e)).with_context(|| {
                format!(
                    "jointly identifying {in_col} -> {out_col} from {} records",
                    records.len()
                )
            })
        }
    };
    if args.json.as_deref() != Some("-") {
        let source = format!("{} record(s) jointly", records.len());
        print_result((poles, zeros), &source, &in_col, &out_col, &joint.result);
        if opts.estimate_delay {
            println!("delay: whole samples only in a joint fit");
        }
        let rows = joint
            .records
            .iter()
            .map(|r| {
                vec![
                    r.label.clone(),
                    r.n_samples.to_string(),
                    format!("{:.6}", r.u_offset),
                    format!("{:.6}", r.y_offset),
                    format!("{:.2}", r.fit_sim_percent),
                ]
            })
            .collect();
        println!(
            "\n{}",
            text_table(&Table::new(
                "records (each with its own trim, output offset and initial condition)",
                &["record", "samples", "input trim", "output offset", "fit %"],
                rows,
            ))
        );
    }
    if let Some(target) = &args.json {
        emit_json(
            target,
            &json!({
                "data": args.data.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
                "segments": args.segment,
                "input": in_col,
                "output": out_col,
                "result": joint.result,
                "records": joint.records,
            }),
        )?;
    }
    Ok(())
}
