//! `flightid derivatives`: aerodynamic derivatives backed out of identified transfer functions (the paper's
//! Section 5) and by equation error, scored against the JSBSim model's own values (Tables 1 and 3).

use super::common::{emit_json, write_report_and_json, ColumnsArg, TrimArgs};
use super::paper::text_table;
use crate::cli::UsageError;
use crate::ident::Method;
use crate::report::text::{wrap, TERMINAL_WIDTH};
use crate::study::spec::{parse_derivatives, Structure};
use crate::study::trials::{SensorNoise, TrialOptions};
use crate::study::{self, Source, StudyOptions};
use std::path::PathBuf;

/// Which axis `--data … --airframe …` estimates.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisArg {
    /// C_L, C_D, C_m (states V, α, θ, q).
    Longitudinal,
    /// C_Y, C_l, C_n (states β, p, r, φ).
    Lateral,
    /// Both.
    Both,
}

/// Model structure for the transfer-function route.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum StructureArg {
    /// The paper's simplifying assumptions.
    Paper,
    /// Every term the model knows, JSBSim's wind-axis side force.
    Full,
}

/// Estimate aerodynamic derivatives and score them against the aircraft's own (JSBSim) values.
///
/// With --data and --airframe: measured records of any aircraft (equation error, output error or filter
/// error on built-in nondimensional models; see docs/derivatives-measured.md).
///
/// Without --from/--data it flies elevator, aileron and rudder doublets on JSBSim, identifies θ/δe, φ/δa, φ/δr,
/// backs the derivatives out of them through the paper's parametric model, estimates them also by equation
/// error on the full state, and prints the paper's Table 1 (truth vs estimate, 3σ interval, identifiability)
/// and Table 3 (errors, 3σ coverage, targets, the structure term behind a miss).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  flightid derivatives --aircraft c172x\n  flightid derivatives --aircraft c172x --noise --report deriv-report\n  flightid identify --data el.csv --input elevator --output theta_rad --json th.json && flightid derivatives --from th.json\n  flightid derivatives --aircraft c172x --data lateral.csv --json out.json\n  flightid derivatives --data lon1.csv --data lon2.csv --airframe my.toml --columns map.toml --method oe"
)]
pub struct DerivativesCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Identified transfer functions (`flightid identify --json` output, or an array of them); repeatable.
    /// May carry `mass` / `geometry` objects replacing the JSBSim model's.
    #[arg(long, value_name = "IDENTIFIED.json", conflicts_with = "data")]
    pub from: Vec<PathBuf>,
    /// A flight-data CSV (docs/data.md); repeatable (records fitted jointly). With --airframe: measured data
    /// of that aircraft. Without: a JSBSim record of --aircraft (`flightid fly`), scored against the model's
    /// own derivatives (its differentiated rates lag the moments by half a sample, which is modelled).
    #[arg(long, value_name = "FLIGHT.csv")]
    pub data: Vec<PathBuf>,
    #[command(flatten)]
    pub columns: ColumnsArg,
    /// With --data: the aircraft that flew, as an airframe description (FILE.toml: mass, inertia, geometry,
    /// thrust line, sensor positions; docs/airframe.md) or the name of any model JSBSim ships (p51d, c310,
    /// T37, …: mass, inertia, wing and thrust line read from the model, sensors taken at the CG). Nothing
    /// falls back to another aircraft: a missing key is named (exit 2).
    #[arg(long, value_name = "FILE.toml|NAME", requires = "data")]
    pub airframe: Option<String>,
    /// With --airframe: the axis to estimate [default: what the records excite].
    #[arg(long, value_enum, requires = "airframe")]
    pub axis: Option<AxisArg>,
    /// With --airframe: estimate C_mα̇ (and C_Lα̇ for output error) too.
    #[arg(long, requires = "airframe")]
    pub alphadot: bool,
    /// With --data without --airframe: the CSV is measured sensor data, sampled together, with no
    /// integrator lag to model.
    #[arg(long, requires = "data")]
    pub sensor_data: bool,
    /// Model structure of the transfer-function route.
    #[arg(long = "model", value_enum, default_value = "paper")]
    pub structure: StructureArg,
    /// Free derivatives of the TF route, comma separated (default: Cm_alpha,Cm_q,Cm_alphadot,Cm_de,
    /// Cl_beta,Cl_p,Cl_da,Cn_beta,Cn_r). With --airframe --method oe|fem: parameters or groups (speed,
    /// curvature, alphadot, zero, skew, all) to free, `-NAME` to hold, applied in order to the default set
    /// (docs/derivatives-measured.md).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub free: Option<Vec<String>>,
    /// Estimator: with --airframe ee (equation error), oe (output error) or fem (filter error)
    /// [default ee]; when flying, of the transfer functions: srivc or oe [default srivc].
    #[arg(long)]
    pub method: Option<String>,
    /// Add realistic sensor noise to the flown records (vanes 0.1°, AHRS 0.05°, gyros 0.1°/s, …).
    #[arg(long)]
    pub noise: bool,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
    /// Write index.html, report.md and report.json into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
}

/// Runs `flightid derivatives`.
pub fn run(args: &DerivativesCmd) -> anyhow::Result<()> {
    super::common::check_outputs(
        &[super::common::json_path(&args.json)],
        &[args.report.as_deref()],
    )?;
    if let Some(airframe) = &args.airframe {
        return run_measured(args, airframe);
    }
    // Measured data scored against a JSBSim model only when the user named that model: never the default
    // c172x by accident.
    let named_aircraft =
        std::env::args().any(|a| a == "--aircraft" || a.starts_with("--aircraft="));
    if args.sensor_data && !named_aircraft {
        return Err(UsageError(
            "--sensor-data: measured data need the aircraft that flew them: give --airframe FILE.toml \
             (mass, inertia, geometry) or --airframe NAME for a JSBSim model (or --aircraft NAME to score \
             them against that model's own derivatives)"
                .into(),
        )
        .into());
    }
    if args.data.len() > 1 {
        return Err(UsageError("several --data records need --airframe".into()).into());
    }
    let free = match &args.free {
        Some(names) => Some(parse_derivatives(names)?),
        None => None,
    };
    let method: Method = args
        .method
        .as_deref()
        .unwrap_or("srivc")
        .parse()
        .map_err(|e| UsageError(format!("--method: {e}")))?;
    let source = if let Some(path) = args.data.first() {
        let record = args.columns.read(path)?;
        Source::Data {
            record,
            simulated: !args.sensor_data,
        }
    } else if !args.from.is_empty() {
        let mut docs = Vec::new();
        for p in &args.from {
            let text = std::fs::read_to_string(p)
                .map_err(|e| UsageError(format!("{}: {e}", p.display())))?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| UsageError(format!("{}: not JSON: {e}", p.display())))?;
            docs.push((p.display().to_string(), v));
        }
        Source::Identified(docs)
    } else {
        Source::Fly(TrialOptions {
            rate_hz: args.trim.rate_hz,
            noise: args.noise.then(SensorNoise::realistic),
            seed: args.seed,
            method,
            ..TrialOptions::default()
        })
    };
    let opts = StudyOptions {
        source,
        structure: match args.structure {
            StructureArg::Paper => Structure::Paper,
            StructureArg::Full => Structure::Full,
        },
        free,
        start_factor: 1.2,
    };
    let cfg = args.trim.config()?;
    let point = args.trim.point(&cfg)?;
    let progress = super::common::spinner("derivatives: trim, model check, flights, estimates");
    let mut sim = crate::sim::JsbsimSim::start(&cfg, args.trim.rate_hz)?;
    let result = study::run(&mut sim, &point, &opts);
    progress.finish_and_clear();
    let result = result?;
    let quiet = args.json.as_deref() == Some("-");
    if !quiet {
        println!(
            "{} at {} ft, {} kts: derivatives vs the JSBSim model's own values\n",
            cfg.name, point.altitude_ft, point.speed_kts
        );
        for t in result.tables() {
            println!("{}", text_table(&t));
        }
        if !result.identifiability.is_empty() {
            println!("Identifiability (TF route):");
            for line in result.identifiability.lines() {
                let indent = &line[..line.len() - line.trim_start().len()];
                let rest = format!("{indent}    ");
                for l in wrap(line.trim_start(), TERMINAL_WIDTH, indent, &rest) {
                    println!("{l}");
                }
            }
        }
        for n in &result.notes {
            for l in wrap(n, TERMINAL_WIDTH, "- ", "  ") {
                println!("{l}");
            }
        }
    }
    write_report_and_json(
        args.report.as_deref(),
        || result.report(),
        &result.to_json(),
        args.json.as_deref(),
    )
}

/// The measured-data route: `--data … --airframe …`.
fn run_measured(args: &DerivativesCmd, airframe_arg: &str) -> anyhow::Result<()> {
    use crate::aero::measured::{self, AxisChoice};
    use crate::aero::output_error;
    let airframe = load_airframe(args, airframe_arg)?;
    let mut records = Vec::new();
    for p in &args.data {
        records.extend(args.columns.read_pieces(p)?);
    }
    let axis = match args.axis {
        Some(AxisArg::Longitudinal) => AxisChoice::Longitudinal,
        Some(AxisArg::Lateral) => AxisChoice::Lateral,
        Some(AxisArg::Both) => AxisChoice::Both,
        None => {
            let mut lon = false;
            let mut lat = false;
            for (_, r) in &records {
                if let Some(a) = measured::excited_axis(r) {
                    lon |= a.longitudinal();
                    lat |= a.lateral();
                }
            }
            match (lon, lat) {
                (true, true) => AxisChoice::Both,
                (true, false) => AxisChoice::Longitudinal,
                (false, true) => AxisChoice::Lateral,
                (false, false) => return Err(UsageError(
                    "no record moves a control surface by more than 0.5° above its noise: nothing \
                         excites an axis (give --axis to estimate anyway)"
                        .into(),
                )
                .into()),
            }
        }
    };
    let report = match args.method.as_deref().unwrap_or("ee") {
        "ee" => {
            if args.free.is_some() {
                return Err(UsageError(
                    "--free: equation error estimates every term of its regressions; --free chooses the \
                     free parameters of --method oe|fem"
                        .into(),
                )
                .into());
            }
            measured::equation_error_report(&records, &airframe, axis, args.alphadot)?
        }
        "oe" | "fem" => {
            let method = if args.method.as_deref() == Some("fem") {
                crate::estimate::Method::Fem
            } else {
                crate::estimate::Method::Oe
            };
            let free = output_error::parse_free(args.free.as_deref().unwrap_or(&[]))
                .map_err(|e| UsageError(format!("--free: {e}")))?;
            let options = output_error::OutputErrorOptions {
                method,
                free,
                alphadot: args.alphadot,
            };
            output_error::output_error_report(&records, &airframe, axis, &options)?
        }
        other => {
            return Err(UsageError(format!(
                "--method {other}: with --airframe the methods are ee, oe and fem"
            ))
            .into())
        }
    };
    if report.converged == Some(false) {
        eprintln!(
            "warning: the {} fit did not converge; the estimates below are not a minimum of the cost",
            report.method.replace('_', " ")
        );
    }
    let quiet = args.json.as_deref() == Some("-");
    if !quiet {
        println!("{} ({}):", airframe.name, airframe.source);
        print!("{}", report.to_text());
    }
    if let Some(target) = &args.json {
        emit_json(target, &report.to_json())?;
    }
    Ok(())
}

/// `--airframe FILE.toml` or a JSBSim aircraft name (mass, inertia and geometry read from its model at its
/// default trim).
fn load_airframe(args: &DerivativesCmd, arg: &str) -> anyhow::Result<crate::aero::Airframe> {
    use crate::aero::Airframe;
    let path = std::path::Path::new(arg);
    if arg.ends_with(".toml") || path.is_file() {
        return Airframe::load(path).map_err(|e| UsageError(e.to_string()).into());
    }
    if let Err(crate::aircraft::AircraftError::Unknown { known, .. }) = crate::aircraft::load(arg) {
        // not a configured aircraft: any JSBSim model, its mass, inertia and wing at its initial condition
        let m = crate::sim::aero_truth::model_mass_and_wing(arg).map_err(|e| match e {
            crate::sim::SimError::UnknownModel(why) => UsageError(format!(
                "--airframe {arg}: not an airframe description (FILE.toml), not a configured aircraft ({known}), \
                 and not a JSBSim model: {why}"
            ))
            .into(),
            other => anyhow::Error::from(other),
        })?;
        return Ok(airframe_of_mass_and_wing(arg, &m, None));
    }
    let trim = TrimArgs {
        aircraft: arg.to_string(),
        ..args.trim.clone()
    };
    let (mut sim, _) = trim.start_and_trim()?;
    let truth = sim.aero_truth()?;
    Ok(airframe_of_mass_and_wing(
        arg,
        &truth.mass_and_wing(),
        Some(truth.rho_kg_m3),
    ))
}

/// The airframe of a JSBSim model from its mass, inertia, wing and thrust line (sensors at the CG; the trim's
/// density when it was trimmed, else none: the records' own air data are needed then).
fn airframe_of_mass_and_wing(
    name: &str,
    m: &crate::sim::aero_truth::ModelMassAndWing,
    density_kg_m3: Option<f64>,
) -> crate::aero::Airframe {
    use crate::aero::airframe::{
        Airframe, FlightDefaults, Inertia, SensorPositions, ThrustLine, Wing,
    };
    let [ixx, iyy, izz, ixz] = m.inertia_kg_m2;
    Airframe {
        name: name.to_string(),
        mass_kg: Some(m.mass_kg),
        inertia_kg_m2: Inertia { ixx, iyy, izz, ixz },
        wing: Wing {
            area_m2: Some(m.wing_area_m2),
            span_m: Some(m.span_m),
            mac_m: Some(m.chord_m),
        },
        thrust: m
            .thrust_line
            .map(|(moment_arm_m, inclination_rad)| ThrustLine {
                inclination_rad,
                moment_arm_m,
            }),
        sensors: SensorPositions::default(),
        flight: FlightDefaults { density_kg_m3 },
        source: format!("{}{name}", crate::aero::airframe::JSBSIM_SOURCE_PREFIX),
    }
}
