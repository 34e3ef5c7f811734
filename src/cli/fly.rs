//! `flightid fly`: fly a designed maneuver from trim and write the flight-data CSV.

use super::common::{emit_json, TrimArgs};
use crate::cli::UsageError;
use crate::data;
use crate::signal::{Maneuver, Sweep};
use crate::sim::{FlightPlan, Simulator};
use std::path::PathBuf;

/// Input shapes.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ManeuverKind {
    /// +A for one pulse, -A for one pulse.
    Doublet,
    /// 3-2-1-1: +A 3T, -A 2T, +A T, -A T.
    #[value(name = "3211")]
    ThreeTwoOneOne,
    /// Sum of harmonics with Schroeder phases (low peak factor), --f-min-hz..--f-max-hz.
    Multisine,
    /// Frequency sweep --f-min-hz..--f-max-hz over the record (--log-sweep for logarithmic).
    Chirp,
}

/// The maneuver design shared by `fly` and the commands that fly for themselves.
#[derive(clap::Args, Debug, Clone)]
pub struct ManeuverArgs {
    /// Surface to excite: elevator, aileron or rudder; repeat for simultaneous inputs.
    #[arg(long = "surface", default_value = "elevator")]
    pub surfaces: Vec<String>,
    /// Input shape.
    #[arg(long, value_enum, default_value = "doublet")]
    pub maneuver: ManeuverKind,
    /// Peak surface deflection relative to trim, deg.
    #[arg(long, default_value_t = 2.0, value_parser = crate::limits::AMPLITUDE_DEG.parser())]
    pub amplitude_deg: f64,
    /// Pulse width of doublet / 3-2-1-1 (the unit T), s.
    #[arg(long, default_value_t = 1.0, value_parser = crate::limits::PULSE_S.parser())]
    pub pulse_s: f64,
    /// Time the maneuver starts after the trim state, s.
    #[arg(long, default_value_t = 1.0, value_parser = crate::limits::START_S.parser())]
    pub start_s: f64,
    /// Record length, s.
    #[arg(long, default_value_t = 30.0, value_parser = crate::limits::DURATION_S.parser())]
    pub duration_s: f64,
    /// Lowest frequency of multisine and chirp, Hz.
    #[arg(long, default_value_t = 0.1, value_parser = crate::limits::FREQUENCY_HZ.parser())]
    pub f_min_hz: f64,
    /// Highest frequency of multisine and chirp, Hz.
    #[arg(long, default_value_t = 2.0, value_parser = crate::limits::FREQUENCY_HZ.parser())]
    pub f_max_hz: f64,
    /// Logarithmic chirp instead of linear.
    #[arg(long)]
    pub log_sweep: bool,
}

impl ManeuverArgs {
    /// The maneuver shape.
    pub fn maneuver(&self) -> anyhow::Result<Maneuver> {
        let active_s = self.duration_s - self.start_s;
        if !(self.duration_s > 0.0 && self.start_s >= 0.0 && active_s > 0.0) {
            return Err(UsageError(format!(
                "--duration-s ({}) must exceed --start-s ({}) and both be non-negative",
                self.duration_s, self.start_s
            ))
            .into());
        }
        if !(self.f_min_hz > 0.0 && self.f_max_hz > self.f_min_hz) {
            return Err(UsageError(format!(
                "need 0 < --f-min-hz < --f-max-hz, got {} and {}",
                self.f_min_hz, self.f_max_hz
            ))
            .into());
        }
        Ok(match self.maneuver {
            ManeuverKind::Doublet => Maneuver::Doublet {
                pulse_s: self.pulse_s,
            },
            ManeuverKind::ThreeTwoOneOne => Maneuver::ThreeTwoOneOne {
                pulse_s: self.pulse_s,
            },
            ManeuverKind::Multisine => {
                Maneuver::multisine_in_band(self.f_min_hz, self.f_max_hz, active_s)
            }
            ManeuverKind::Chirp => Maneuver::Chirp(Sweep {
                f0_hz: self.f_min_hz,
                f1_hz: self.f_max_hz,
                sweep_s: active_s,
                log: self.log_sweep,
            }),
        })
    }

    /// The flight plan at a rate: every listed surface gets the same shape, amplitude in radians.
    pub fn plan(&self, rate_hz: f64) -> anyhow::Result<FlightPlan> {
        if !(self.amplitude_deg.is_finite() && self.amplitude_deg.abs() <= 30.0) {
            return Err(UsageError(format!(
                "--amplitude-deg must be within ±30, got {}",
                self.amplitude_deg
            ))
            .into());
        }
        let m = self.maneuver()?;
        crate::limits::check_samples(
            "the simulation (--duration-s × the simulation rate, --sim-rate-hz or --rate-hz)",
            self.duration_s,
            rate_hz,
        )?;
        if matches!(
            self.maneuver,
            ManeuverKind::Doublet | ManeuverKind::ThreeTwoOneOne
        ) && self.pulse_s * rate_hz < 2.0
        {
            return Err(UsageError(format!(
                "--pulse-s {} is shorter than two samples at {rate_hz} Hz: the record would carry no excitation",
                self.pulse_s
            ))
            .into());
        }
        if matches!(self.maneuver, ManeuverKind::Multisine | ManeuverKind::Chirp)
            && self.f_max_hz > rate_hz / 2.0
        {
            return Err(UsageError(format!(
                "--f-max-hz {} is above the Nyquist frequency {} Hz of --rate-hz {rate_hz}",
                self.f_max_hz,
                rate_hz / 2.0
            ))
            .into());
        }
        let mut surfaces: Vec<&str> = Vec::new();
        for s in &self.surfaces {
            if !["elevator", "aileron", "rudder"].contains(&s.as_str()) {
                return Err(UsageError(format!(
                    "unknown surface '{s}' (use elevator, aileron or rudder)"
                ))
                .into());
            }
            if surfaces.contains(&s.as_str()) {
                return Err(UsageError(format!("surface '{s}' given twice")).into());
            }
            surfaces.push(s);
        }
        Ok(FlightPlan::maneuver(
            &surfaces,
            &m,
            self.amplitude_deg.to_radians(),
            self.start_s,
            self.duration_s,
            rate_hz,
        ))
    }
}

/// Fly a maneuver from trim and write the flight-data CSV (docs/data.md: all columns, SI units). JSBSim
/// integrates at --sim-rate-hz (default: 120 Hz, or the smallest multiple of --rate-hz at or above it) and the
/// record keeps every sample at --rate-hz: a log that is not a subsample of the simulation would need
/// interpolation, so the simulation rate must be a whole multiple of the logging rate. The first sample is the trim state.
/// Nothing is written if anything fails.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid fly --aircraft c172x --surface elevator --maneuver doublet --amplitude-deg 2 --pulse-s 1 --duration-s 30 --out flight.csv\n  flightid fly --aircraft 737 --surface aileron --surface rudder --maneuver 3211 --amplitude-deg 1 --out lat.csv"
)]
pub struct FlyCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    #[command(flatten)]
    pub maneuver: ManeuverArgs,
    /// Output CSV file.
    #[arg(long)]
    pub out: PathBuf,
    /// JSBSim integration rate, Hz: a whole multiple of --rate-hz (the logging rate). Default: --rate-hz if it is
    /// at least 120 Hz, else its smallest multiple at or above 120 Hz (a record flown at 50 Hz carries the
    /// integrator's error: the short-period damping identified from it comes out 9 % low).
    #[arg(long, value_name = "HZ")]
    pub sim_rate_hz: Option<f64>,
    /// Also print a JSON summary (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    /// Fly an extended model written by `flightid diagnose --model-out DIR` (its aircraft XML and the signal-path
    /// and sensor effects of its extension.json) instead of the stock aircraft.
    #[arg(long, value_name = "DIR")]
    pub model: Option<PathBuf>,
}

/// The simulation rate for a logging rate and the number of simulation steps per logged sample
/// ([`crate::sim::simulation_rate`]), with the flags checked.
pub fn simulation_rate(log_rate_hz: f64, sim_rate_hz: Option<f64>) -> anyhow::Result<(f64, usize)> {
    let bad = |msg: String| anyhow::Error::from(UsageError(msg));
    if !(log_rate_hz.is_finite() && (10.0..=2000.0).contains(&log_rate_hz)) {
        return Err(bad(format!(
            "--rate-hz must be within 10..2000, got {log_rate_hz}"
        )));
    }
    crate::sim::simulation_rate(log_rate_hz, sim_rate_hz).ok_or_else(|| {
        let sim_hz = sim_rate_hz.map_or_else(|| "the default".into(), |h| h.to_string());
        bad(format!(
            "--sim-rate-hz ({sim_hz}) must be a whole multiple of --rate-hz ({log_rate_hz}) and at most 2000"
        ))
    })
}

/// Runs `flightid fly`.
pub fn run(args: &FlyCmd) -> anyhow::Result<()> {
    super::common::check_outputs(
        &[Some(&args.out), super::common::json_path(&args.json)],
        &[],
    )?;
    let log_rate_hz = args.trim.rate_hz;
    let (sim_rate_hz, step) = simulation_rate(log_rate_hz, args.sim_rate_hz)?;
    let mut sim_args = args.trim.clone();
    sim_args.rate_hz = sim_rate_hz;
    let mut plan = args.maneuver.plan(sim_rate_hz)?;
    let (rec, trim) = match &args.model {
        None => {
            let (mut sim, trim) = sim_args.start_and_trim()?;
            (sim.fly(&plan)?, trim)
        }
        Some(dir) => fly_model(&sim_args, dir, &mut plan)?,
    };
    let mut rec = if step > 1 { rec.every_nth(step) } else { rec };
    if step > 1 {
        rec.metadata.push(format!(
            "logged at {log_rate_hz} Hz: one sample in {step} of a {sim_rate_hz} Hz simulation"
        ));
    }
    rec.metadata.push(format!(
        "maneuver: {:?} on {} amplitude {} deg, start {} s",
        args.maneuver.maneuver,
        args.maneuver.surfaces.join("+"),
        args.maneuver.amplitude_deg,
        args.maneuver.start_s
    ));
    data::write_csv_atomic(&args.out, &rec)?;
    let summary = serde_json::json!({
        "out": args.out.display().to_string(), "samples": rec.len(), "rate_hz": log_rate_hz,
        "sim_rate_hz": sim_rate_hz,
        "aircraft": trim.aircraft, "trim": trim,
    });
    match &args.json {
        Some(target) => emit_json(target, &summary)?,
        None => eprintln!(
            "wrote {} ({} samples at {} Hz, simulated at {} Hz, {} from trim at {} ft, {} kts)",
            args.out.display(),
            rec.len(),
            log_rate_hz,
            sim_rate_hz,
            args.maneuver.surfaces.join("+"),
            trim.point.altitude_ft,
            trim.point.speed_kts
        ),
    }
    Ok(())
}

/// Flies the extended model in `dir`: its exported aircraft, with its signal-path effects on the plan and its
/// sensor effects on the record.
fn fly_model(
    sim_args: &super::common::TrimArgs,
    dir: &std::path::Path,
    plan: &mut crate::sim::FlightPlan,
) -> anyhow::Result<(data::FlightRecord, crate::sim::TrimState)> {
    use crate::diagnose::model::{apply_to_plan, apply_to_record, ExtendedModel};
    use anyhow::Context as _;
    let model = ExtendedModel::read(dir).map_err(|e| UsageError(e.to_string()))?;
    let cfg = model
        .config(&sim_args.loading.properties)
        .map_err(|e| UsageError(e.to_string()))?;
    let point = sim_args.point(&cfg)?;
    let mut sim = model
        .start(&cfg, sim_args.rate_hz)
        .with_context(|| format!("starting JSBSim on the model in {}", dir.display()))?;
    let effects = model
        .effects(&sim.coefficient_knobs)
        .map_err(|e| UsageError(e.to_string()))?;
    apply_to_plan(&effects, plan);
    let trim = sim.trim(&point)?;
    let mut rec = sim.fly(plan)?;
    apply_to_record(&effects, &mut rec);
    rec.metadata
        .push(format!("extended model: {}", dir.display()));
    Ok((rec, trim))
}
