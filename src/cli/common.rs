//! Argument groups and output helpers shared by several commands.

use crate::aircraft::AircraftConfig;
use crate::cli::UsageError;
use crate::data::{self, ColumnMap, FlightRecord};
use crate::sim::{JsbsimSim, Simulator, TrimPoint, TrimState};
use anyhow::Context;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The loading an aircraft flies with, where it is not the model's own.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LoadingArg {
    /// JSBSim property set before every trim, NAME=VALUE (repeatable): the loading or configuration flown where
    /// it is not the model's own, e.g. `--property 'propulsion/tank[0]/contents-lbs=30'`, a point mass's weight
    /// (`inertia/pointmass-weight-lbs[N]`), a flap setting (`fcs/flap-cmd-norm`), the day's temperature offset
    /// (`atmosphere/delta-T`, °R). Another weight, CG or flap setting trims at another α and elevator, which a
    /// replay with the model's own takes for an aerodynamic error (docs/diagnose.md, "Loading").
    #[arg(long = "property", value_name = "NAME=VALUE")]
    pub properties: Vec<String>,
}

/// Which aircraft and where to trim it.
#[derive(clap::Args, Debug, Clone)]
pub struct TrimArgs {
    /// Aircraft configuration: a name from aircraft/ (c172x, 737, f16), a path to an aircraft .toml, or any
    /// JSBSim model (c172p, c310, B747, …: configured from the model, docs/airframe.md).
    #[arg(long, default_value = "c172x")]
    pub aircraft: String,
    #[command(flatten)]
    pub loading: LoadingArg,
    /// Trim altitude above sea level, ft [default: the aircraft's default trim point].
    #[arg(long, value_parser = crate::limits::ALTITUDE_FT.parser())]
    pub altitude_ft: Option<f64>,
    /// Trim true airspeed, kts [default: the aircraft's default trim point].
    #[arg(long, value_parser = crate::limits::SPEED_KTS.parser())]
    pub speed_kts: Option<f64>,
    /// Simulation rate, Hz (JSBSim integrates at this rate; records are sampled at it).
    #[arg(long, default_value_t = 120.0, value_parser = crate::limits::RATE_HZ.parser())]
    pub rate_hz: f64,
}

impl TrimArgs {
    /// Loads the aircraft configuration (unknown names are a usage error).
    pub fn config(&self) -> anyhow::Result<AircraftConfig> {
        crate::sim::derived::aircraft_config(&self.aircraft)
            .and_then(|c| c.with_properties(&self.loading.properties))
            .map_err(|e| UsageError(e.to_string()).into())
    }

    /// The trim point: given values or the aircraft's defaults.
    pub fn point(&self, cfg: &AircraftConfig) -> anyhow::Result<TrimPoint> {
        let p = TrimPoint::level(
            self.altitude_ft.unwrap_or(cfg.trim.altitude_ft),
            self.speed_kts.unwrap_or(cfg.trim.speed_kts),
        );
        if !(p.speed_kts.is_finite() && p.speed_kts > 0.0) {
            return Err(
                UsageError(format!("--speed-kts must be positive, got {}", p.speed_kts)).into(),
            );
        }
        if !(p.altitude_ft.is_finite() && p.altitude_ft >= 0.0) {
            return Err(
                UsageError(format!("--altitude-ft must be >= 0, got {}", p.altitude_ft)).into(),
            );
        }
        Ok(p)
    }

    /// Starts JSBSim and trims; errors carry the aircraft and the point.
    pub fn start_and_trim(&self) -> anyhow::Result<(JsbsimSim, TrimState)> {
        let cfg = self.config()?;
        let point = self.point(&cfg)?;
        if !(self.rate_hz.is_finite() && self.rate_hz >= 10.0 && self.rate_hz <= 2000.0) {
            return Err(UsageError(format!(
                "--rate-hz must be within 10..2000, got {}",
                self.rate_hz
            ))
            .into());
        }
        let mut sim = JsbsimSim::start(&cfg, self.rate_hz)
            .with_context(|| format!("starting JSBSim for {}", cfg.name))?;
        let trim = sim.trim(&point)?;
        Ok((sim, trim))
    }
}

/// Writes bytes to `path` atomically (temporary file in the same directory, then rename): never a partial file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    crate::report::write_atomic(path, bytes).map_err(Into::into)
}

/// Checks every output a command will write before any work starts (see [`crate::report::check_output_file`]
/// and [`crate::report::check_output_dir`]), so a bad path is refused at once and no other output is written
/// before it. `files` are single files (`-`, stdout, is skipped); `dirs` are output directories.
pub fn check_outputs(files: &[Option<&Path>], dirs: &[Option<&Path>]) -> anyhow::Result<()> {
    for file in files.iter().flatten() {
        if file.as_os_str() != "-" {
            crate::report::check_output_file(file)?;
        }
    }
    for dir in dirs.iter().flatten() {
        crate::report::check_output_dir(dir)?;
    }
    Ok(())
}

/// A `--json` target as a path for [`check_outputs`] (`-` is skipped there).
pub fn json_path(target: &Option<String>) -> Option<&Path> {
    target.as_deref().map(Path::new)
}

/// Emits a JSON value: to stdout for `-`, else atomically to the file.
pub fn emit_json<T: serde::Serialize>(target: &str, value: &T) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    if target == "-" {
        std::io::stdout().write_all(text.as_bytes())?;
        Ok(())
    } else {
        write_atomic(Path::new(target), text.as_bytes())
    }
}

/// The outputs a command writes after its terminal summary: the HTML report in `report_dir` when given (its
/// index named on stdout unless the JSON goes there), then `json` to `json_target` when given (see
/// [`emit_json`]).
pub fn write_report_and_json(
    report_dir: Option<&Path>,
    report: impl FnOnce() -> crate::report::Report,
    json: &serde_json::Value,
    json_target: Option<&str>,
) -> anyhow::Result<()> {
    if let Some(dir) = report_dir {
        let index = crate::report::write_report_dir(dir, &report(), json)?;
        if json_target != Some("-") {
            println!("\nreport: {}", index.display());
        }
    }
    if let Some(target) = json_target {
        emit_json(target, json)?;
    }
    Ok(())
}

/// [`crate::compare::compare_and_explain`] behind a spinner (the `compare` and `demo` commands).
pub fn compare_with_spinner(
    sim: &mut JsbsimSim,
    opts: &crate::compare::CompareOptions,
    user_scales: &[(String, f64)],
) -> Result<crate::compare::ExplainedComparison, crate::compare::CompareError> {
    let progress = spinner("trim, linearize, fly doublets, identify, amplitude sweep");
    let result = crate::compare::compare_and_explain(sim, opts, user_scales);
    progress.finish_and_clear();
    result
}

/// A spinner with elapsed time on stderr for work that takes more than a couple of seconds; indicatif draws
/// nothing when stderr is not a terminal, so piped output stays clean. Finish it with `finish_and_clear`.
pub fn spinner(message: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new_spinner();
    pb.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    pb.set_message(message.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}

/// How a command reads flight-data CSVs: optionally through a column map.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ColumnsArg {
    /// Column map (TOML) renaming a foreign CSV's columns onto the schema and converting their
    /// units (`[columns] DELV = { to = "elevator_rad", unit = "deg" }`). A text file without a
    /// header row (columns separated by commas, spaces or tabs) is mapped by column position:
    /// `1 = { to = "time_s" }`. See docs/data.md.
    #[arg(long, value_name = "MAP.toml")]
    pub columns: Option<PathBuf>,
}

impl ColumnsArg {
    /// Reads a flight-data CSV through the map, printing the record's unit-sanity and sampling
    /// warnings on stderr. A bad map or file is a usage error (exit 2).
    pub fn read(&self, path: &Path) -> anyhow::Result<FlightRecord> {
        let rec = self.read_quietly(path)?;
        for w in rec.warnings() {
            eprintln!("warning: {}: {w}", path.display());
        }
        Ok(rec)
    }

    /// Reads a measured flight log through the map as the estimators take it: in uniformly sampled pieces
    /// (`data::uniform_pieces`: split at dropouts, jittered timestamps resampled), each named after the file
    /// and, when there are several, its time span. Prints the unit-sanity warnings and what was done to the
    /// sampling on stderr.
    pub fn read_pieces(&self, path: &Path) -> anyhow::Result<Vec<(String, FlightRecord)>> {
        let rec = self.read_quietly(path)?;
        for w in rec.warnings() {
            if w.kind != data::WarningKind::IrregularSampling {
                eprintln!("warning: {}: {w}", path.display());
            }
        }
        let split = data::uniform_pieces(&rec)
            .map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
        for note in &split.notes {
            eprintln!("warning: {}: {note}", path.display());
        }
        if split.pieces.len() > 1 {
            eprintln!(
                "warning: {}: its {} pieces are fitted as separate records, each with its own initial state",
                path.display(),
                split.pieces.len()
            );
        }
        let name = path.display().to_string();
        let several = split.pieces.len() > 1;
        Ok(split
            .pieces
            .into_iter()
            .map(|p| {
                let label = if several {
                    format!("{name} [{} s–{} s]", p.time_s[0], p.time_s[p.len() - 1])
                } else {
                    name.clone()
                };
                (label, p)
            })
            .collect())
    }

    /// Reads a flight-data CSV through the map, printing nothing.
    fn read_quietly(&self, path: &Path) -> anyhow::Result<FlightRecord> {
        let map = self.columns.as_deref().map(ColumnMap::load).transpose()?;
        Ok(data::read_csv_mapped(path, map.as_ref())?)
    }
}

/// `rec` from `path` resampled onto a uniform grid at `resample_hz` when given; a rate the record cannot take
/// is a usage error (exit 2).
pub fn resample(
    rec: FlightRecord,
    resample_hz: Option<f64>,
    path: &Path,
) -> anyhow::Result<FlightRecord> {
    match resample_hz {
        Some(hz) => Ok(data::resample_uniform(&rec, hz)
            .map_err(|e| UsageError(format!("{}: {e}", path.display())))?),
        None => Ok(rec),
    }
}

/// How `check` and `segments` read their record: through the column map, optionally resampled.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct RecordArgs {
    /// Resample onto a uniform grid at this rate first (linear interpolation, no filtering).
    #[arg(long = "resample-hz", value_name = "HZ", value_parser = crate::limits::RESAMPLE_HZ.parser())]
    pub resample_hz: Option<f64>,
    #[command(flatten)]
    pub columns: ColumnsArg,
}
