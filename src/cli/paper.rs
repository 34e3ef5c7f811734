//! `flightid paper`: reproduce Section 4 of Şahin & Kalyon 2021 (coefficients, ISE table, response overlays).

use super::common::write_report_and_json;
use crate::cli::UsageError;
use crate::ident::Method;
use crate::paper::{self, PaperInput, PaperOptions};
use crate::report::Table;
use std::path::PathBuf;

/// Input shapes for the reproduction.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum PaperInputArg {
    /// Unit doublet, 1 s pulses from t = 1 s (the paper's excitation).
    Doublet,
    /// Unit 3-2-1-1, T = 1 s, from t = 1 s.
    #[value(name = "3211")]
    ThreeTwoOneOne,
    /// Unit-peak Schroeder multisine, 0.05-2 Hz.
    Multisine,
}

/// Simulate the paper's three original transfer functions (eq. 65, 67, 69) under a doublet, identify them
/// with the paper's ARX least squares, and compare with the original and the paper's own estimates
/// (eq. 66, 68, 70); `--noise` adds white output noise and runs srivc and oe beside ls.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid paper\n  flightid paper --noise 0.01 --report paper-report\n  flightid paper --noise 0.01 --duration-s 300 --input 3211 --json out.json"
)]
pub struct PaperCmd {
    /// White output noise, std relative to the std of the noise-free output (0.01 = 1 %).
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Seed of the noise generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Record length, s.
    #[arg(long, default_value_t = 60.0, value_parser = crate::limits::DURATION_S.parser())]
    pub duration_s: f64,
    /// Input shape.
    #[arg(long, value_enum, default_value = "doublet")]
    pub input: PaperInputArg,
    /// Estimators, comma separated [default: ls without noise; ls,srivc,oe with noise].
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    /// Write an HTML/Markdown report with SVG overlays (the paper's Figs. 5, 7, 9) into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Formats a table as aligned plain text (first column left, others right).
pub(crate) fn text_table(t: &Table) -> String {
    crate::report::text::text_table(t, crate::report::text::TERMINAL_WIDTH)
}

/// Runs `flightid paper`.
pub fn run(args: &PaperCmd) -> anyhow::Result<()> {
    super::common::check_outputs(
        &[super::common::json_path(&args.json)],
        &[args.report.as_deref()],
    )?;
    let mut opts = PaperOptions::new(args.noise);
    opts.seed = args.seed;
    opts.duration_s = args.duration_s;
    opts.input = match args.input {
        PaperInputArg::Doublet => PaperInput::Doublet,
        PaperInputArg::ThreeTwoOneOne => PaperInput::ThreeTwoOneOne,
        PaperInputArg::Multisine => PaperInput::Multisine,
    };
    if let Some(names) = &args.methods {
        opts.methods = names
            .iter()
            .map(|n| n.trim().parse::<Method>())
            .collect::<Result<_, _>>()
            .map_err(|e| UsageError(format!("--methods: {e}")))?;
        if opts.methods.is_empty() {
            return Err(UsageError("--methods: name at least one estimator".into()).into());
        }
    }
    let run = paper::run(&opts).map_err(|e| UsageError(e.to_string()))?;
    let quiet = args.json.as_deref() == Some("-");
    if !quiet {
        println!("{}\n{}\n", run.settings_text(), run.paper_lsm_text());
        for t in &run.tfs {
            println!("{}", text_table(&run.coefficient_table(t)));
            if opts.noise_rel > 0.0 {
                println!("{}", text_table(&run.pole_table(t)));
            }
        }
        println!("{}", text_table(&run.ise_table()));
        println!(
            "{}",
            text_table(&paper::derivatives::derivative_table(&run))
        );
        println!("{}\n", paper::derivatives::PAPER_OMITS);
        println!("{}", text_table(&run.fit_table()));
        for v in run.verdicts() {
            println!("{v}");
        }
    }
    write_report_and_json(
        args.report.as_deref(),
        || run.report(),
        &run.to_json(),
        args.json.as_deref(),
    )
}
