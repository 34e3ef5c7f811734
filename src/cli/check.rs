//! `flightid check`: data compatibility by flight-path reconstruction (sensor biases, scale
//! factors, time skews with uncertainties).

use std::path::PathBuf;

use super::common::{resample, RecordArgs};
use super::UsageError;
use crate::data::{self, CheckOptions};

/// Check the kinematic consistency of a flight-data CSV.
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Examples:\n  flightid check flight.csv\n  flightid check flight.csv --from-s 10 --to-s 40 --no-scale-factors --json\n  flightid check fAttasAilRud1.asc --columns models/attas.columns.toml --airframe models/attas.airframe.toml"
)]
pub struct CheckArgs {
    /// Flight-data CSV (docs/data.md); best a maneuver segment of some tens of seconds.
    pub file: PathBuf,
    /// Only use samples from this time on, s.
    #[arg(long, value_parser = crate::limits::TIME_S.parser())]
    pub from_s: Option<f64>,
    /// Only use samples up to this time, s.
    #[arg(long, value_parser = crate::limits::TIME_S.parser())]
    pub to_s: Option<f64>,
    /// Do not estimate scale factors on V, α, β, φ, θ.
    #[arg(long)]
    pub no_scale_factors: bool,
    /// Do not estimate time skews on α, β.
    #[arg(long)]
    pub no_time_skews: bool,
    /// Iteration limit of the reconstruction (an unconverged fit is an error, exit 1).
    #[arg(long, default_value_t = 50)]
    pub max_iterations: usize,
    /// The aircraft's airframe description (FILE.toml, docs/airframe.md): its `[sensors]` positions move the
    /// accelerations and the α and β vanes to the CG before the reconstruction, whose kinematics are the CG's.
    /// Without it the sensors are taken at the CG: a vane on a nose boom x metres ahead reads β + r x/V and
    /// α − q x/V, which the reconstruction takes for a skew of about x/V (0.1 s at 13 m and 130 m/s).
    #[arg(long, value_name = "FILE.toml")]
    pub airframe: Option<PathBuf>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Runs `flightid check`.
pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    if let (Some(from_s), Some(to_s)) = (args.from_s, args.to_s) {
        crate::limits::check_order("--from-s", from_s, "--to-s", to_s)?;
    }
    let mut rec = args.record.columns.read(&args.file)?;
    let from = args.from_s.unwrap_or(f64::NEG_INFINITY);
    let to = args.to_s.unwrap_or(f64::INFINITY);
    if args.from_s.is_some() || args.to_s.is_some() {
        let window = rec.between(from, to);
        if window.is_empty() {
            return Err(UsageError(format!(
                "{}: no sample lies within --from-s {} .. --to-s {} (the record spans {} .. {} s)",
                args.file.display(),
                from,
                to,
                rec.time_s.first().copied().unwrap_or(f64::NAN),
                rec.time_s.last().copied().unwrap_or(f64::NAN)
            ))
            .into());
        }
        rec = window;
    }
    let mut rec = resample(rec, args.record.resample_hz, &args.file)?;
    if let Some(path) = &args.airframe {
        let airframe = crate::aero::Airframe::load(path).map_err(|e| UsageError(e.to_string()))?;
        rec = crate::aero::measured::moved_to_cg(&rec, &airframe.sensors)
            .map_err(|e| UsageError(format!("{}: {e}", args.file.display())))?;
    }
    let what = args.file.display().to_string();
    crate::limits::RECONSTRUCTION.check(&what, rec.len() as f64)?;
    let opts = CheckOptions {
        scale_factors: !args.no_scale_factors,
        time_skews: !args.no_time_skews,
        max_iterations: args.max_iterations,
    };
    let progress = super::common::spinner(&format!(
        "check: reconstructing the flight path over {} samples",
        rec.len()
    ));
    let report = data::check_compatibility(&rec, &opts);
    progress.finish_and_clear();
    let report = report.map_err(|e| UsageError(format!("{}: {e}", args.file.display())))?;
    let not_converged = || {
        anyhow::anyhow!(
            "the flight-path reconstruction of {} did not converge in {} iterations: its biases, \
             scale factors and skews are not estimates. Try a shorter maneuver segment \
             (--from-s/--to-s), or --no-scale-factors/--no-time-skews",
            args.file.display(),
            report.iterations
        )
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return if report.converged {
            Ok(())
        } else {
            Err(not_converged())
        };
    }
    if !report.converged {
        return Err(not_converged());
    }
    println!(
        "flight-path reconstruction of {} ({} samples, {}{}): {} iterations",
        args.file.display(),
        rec.len(),
        if report.translational {
            "attitude + translational"
        } else {
            "attitude only"
        },
        if args.airframe.is_some() {
            ", sensors moved to the CG"
        } else {
            ""
        },
        report.iterations,
    );
    if report.pieces > 1 {
        println!(
            "{} pieces between dropouts, each reconstructed from its own initial state; the instrument errors \
             are common to all",
            report.pieces
        );
    }
    println!(
        "significant = |value| > 3 standard errors (Cramér–Rao, corrected for coloured residuals) and \
         above the practical floor\n(gyro bias 0.05 °/s, accelerometer bias 0.02 m/s², airspeed bias 0.1 m/s, \
         angle bias 0.1°, scale factor 1 %, skew 0.01 s);\nscale factors and skews only on signals the \
         maneuver moves clearly beyond their noise"
    );
    println!(
        "{:<22} {:>14} {:>14}  significant",
        "instrument error", "value", "std error"
    );
    for e in &report.instrument {
        println!(
            "{:<22} {:>14.6} {:>14.6}  {}",
            e.name,
            e.value,
            e.std_error,
            if e.significant { "YES" } else { "no" }
        );
    }
    let bound_s = data::skew_bound_s(&rec);
    for e in report.implausible_skews(&rec) {
        println!(
            "note: {} = {:.0} ms is longer than a data system's skew can be (one sample interval, {:.0} ms): \
             the vane reads motion the kinematics do not see (gusts), sits behind a filter, or sits away from \
             the CG (--airframe with its [sensors] position); `derivatives` does not shift it out",
            e.name,
            1000.0 * e.value,
            1000.0 * bound_s
        );
    }
    for why in &report.not_excited {
        println!("not estimated, not excited: {why}");
    }
    for name in &report.not_identifiable {
        println!("{name:<22} not identifiable from this data (fixed at 0)");
    }
    for (col, rms) in &report.residual_rms {
        println!("residual rms {col:<16} {rms:.6}");
    }
    Ok(())
}
