//! Command-line interface: argument parsing only; every command is a thin call into the library.
//!
//! Each command lives in its own file with a `clap::Args` struct and a `run` function returning
//! `anyhow::Result<()>`. Exit codes: 0 ok, 1 failure, 2 bad usage or bad input (see [`crate::exit`]).

use clap::{Parser, Subcommand};

use crate::exit::{self, ExitCode};

pub mod campaign;
pub mod check;
pub mod common;
pub mod compare;
pub mod demo;
pub mod derivatives;
pub mod diagnose;
pub mod estimate;
pub mod fly;
pub mod identify;
pub mod ingest;
pub mod linearize;
pub mod paper;
pub mod regress;
pub mod replay;
pub mod segments;
pub mod trim;

/// flightid — aircraft system identification coupled to the JSBSim flight dynamics model.
#[derive(Parser, Debug)]
#[command(name = "flightid", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// The main job on the default aircraft: trim, linearize, three doublets, identification summary.
    Demo(demo::DemoCmd),
    /// Trim an aircraft at a steady level-flight point (JSBSim full trim; flightid's own Newton trim where it fails).
    Trim(trim::TrimCmd),
    /// JSBSim's linearization at a trim point: A, B, C, D, transfer functions, modes.
    Linearize(linearize::LinearizeCmd),
    /// Fly a maneuver (doublet, 3211, multisine, chirp) from trim and write the flight-data CSV.
    Fly(fly::FlyCmd),
    /// Convert a MAVLink telemetry log (.tlog) into the flight-data CSV.
    Ingest(ingest::IngestArgs),
    /// List the maneuvers (doublet, 3-2-1-1, sweep) found in a long flight-data file.
    Segments(segments::SegmentsArgs),
    /// Data compatibility check: sensor biases, scale factors and time skews by flight-path reconstruction.
    Check(check::CheckArgs),
    /// Identified linear models vs JSBSim's linearization and nonlinear flight, as a report.
    Compare(compare::CompareCmd),
    /// Maneuver campaigns: run (parallel, resumable) and report.
    Campaign(campaign::CampaignCmd),
    /// Compare a campaign's identified modal parameters with a stored baseline (exit 1 when any moved).
    Regress(regress::RegressCmd),
    /// Name what the simulation gets wrong on measured data and measure the gain on a validation record.
    Diagnose(diagnose::DiagnoseCmd),
    Estimate(estimate::EstimateCmd),
    /// Replay measured data on the simulation (optionally with fitted extensions) and compare the outputs.
    Replay(replay::ReplayCmd),
    /// Identify a transfer function from an input column to an output column of a flight-data CSV.
    Identify(identify::IdentifyCmd),
    /// Reproduce Section 4 of Sahin & Kalyon 2021 (coefficients, ISE table, response overlays).
    Paper(paper::PaperCmd),
    /// Aerodynamic derivatives from identified TFs and by equation error, scored against the model (Tables 1, 3).
    Derivatives(derivatives::DerivativesCmd),
}

/// An error caused by the user's input (bad file, unknown name): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// Runs the CLI and returns the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { 2 } else { 0 };
        }
    };
    let result = match &cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Trim(a) => trim::run(a),
        Command::Linearize(a) => linearize::run(a),
        Command::Fly(a) => fly::run(a),
        Command::Ingest(a) => ingest::run(a),
        Command::Segments(a) => segments::run(a),
        Command::Check(a) => check::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Campaign(a) => campaign::run(a),
        Command::Regress(a) => regress::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Estimate(a) => estimate::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Identify(a) => identify::run(a),
        Command::Paper(a) => paper::run(a),
        Command::Derivatives(a) => derivatives::run(a),
    };
    crate::sim::scratch::wait_if_terminating();
    match result {
        Ok(()) => 0,
        Err(e) => report_error(&e),
    }
}

/// Prints a warning on stderr, control characters escaped (warnings echo user data too).
pub fn warn(message: &dyn std::fmt::Display) {
    eprintln!(
        "warning: {}",
        crate::text::escape_control_in_message(&message.to_string())
    );
}

/// Prints an error chain (its causes joined by `: `) and returns its exit code ([`exit_code`]).
pub fn report_error(e: &anyhow::Error) -> i32 {
    let mut message = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if message.ends_with(&text) {
            continue; // the wrapper's own message already quotes its cause
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    // messages echo user data (column names, cells, paths): no control character but the message's own line
    // breaks reaches the terminal
    eprintln!(
        "error: {}",
        crate::text::escape_control_in_message(&message)
    );
    i32::from(exit_code(e))
}

impl ExitCode for UsageError {
    fn exit_code(&self) -> u8 {
        exit::BAD_INPUT
    }
}

/// The exit code of an error: that of the outermost error in its chain whose type says one ([`ExitCode`]);
/// [`exit::FAILURE`] when none does.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    e.chain().find_map(known_exit_code).unwrap_or(exit::FAILURE)
}

/// The exit code of one error in a chain, if its type is one of the library's error types.
fn known_exit_code(e: &(dyn std::error::Error + 'static)) -> Option<u8> {
    macro_rules! first_known {
        ($($t:ty),+ $(,)?) => {
            $(if let Some(e) = e.downcast_ref::<$t>() {
                return Some(e.exit_code());
            })+
        };
    }
    first_known!(
        UsageError,
        crate::data::DataError,
        crate::aircraft::AircraftError,
        crate::limits::LimitError,
        crate::aero::AirframeError,
        crate::paper::PaperError,
        crate::sim::SimError,
        crate::report::ReportError,
        crate::campaign::CampaignError,
        crate::compare::CompareError,
        crate::diagnose::DiagnoseError,
        crate::aero::AeroError,
        crate::estimate::EstimateError,
        crate::aero::measured::MeasuredError,
    );
    None
}
