//! `flightid demo`: the main job on the embedded default — c172x at its default trim, JSBSim's linearization,
//! three doublets, and the identified transfer functions beside the linearization.

use super::common::{emit_json, TrimArgs};
use crate::ident::{self, IdentOptions, Method};
use crate::lti::Mode;
use crate::signal::{self, Maneuver};
use crate::sim::linear::{paper_transfer_functions, PAPER_TFS};
use crate::sim::{FlightPlan, Simulator, SurfaceInput};
use serde_json::json;

/// Trim c172x (or --aircraft) at its default point, linearize it with JSBSim, fly an elevator, an aileron and a
/// rudder doublet, identify theta/elevator, phi/aileron and phi/rudder with the paper's least squares and with
/// SRIVC, and print them beside JSBSim's linearization.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid demo\n  flightid demo --aircraft 737 --json demo.json"
)]
pub struct DemoCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Doublet amplitude, deg of surface deflection.
    #[arg(long, default_value_t = 2.0)]
    pub amplitude_deg: f64,
    /// Record length per doublet, s.
    #[arg(long, default_value_t = 30.0)]
    pub duration_s: f64,
    /// Write the results as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
}

fn dominant(modes: &[Mode]) -> Option<&Mode> {
    modes
        .iter()
        .filter(|m| m.oscillatory)
        .max_by(|a, b| a.omega_n_rad_s.total_cmp(&b.omega_n_rad_s))
}

/// Runs `flightid demo`.
pub fn run(args: &DemoCmd) -> anyhow::Result<()> {
    let quiet = args.json.as_deref() == Some("-");
    let say = |s: String| {
        if !quiet {
            println!("{s}");
        }
    };
    let (mut sim, trim) = args.trim.start_and_trim()?;
    say(format!(
        "{} trimmed at {} ft, {} kts: alpha {:.3} deg, elevator {:.3} deg, throttle {:.3}",
        trim.aircraft,
        trim.point.altitude_ft,
        trim.point.speed_kts,
        trim.alpha_rad.to_degrees(),
        trim.surfaces_rad["elevator"].to_degrees(),
        trim.throttle
    ));
    let lin = sim.linearize()?;
    let truth = paper_transfer_functions(&lin)?;
    let rate_hz = args.trim.rate_hz;
    let dt_s = 1.0 / rate_hz;
    let n_steps = (args.duration_s * rate_hz).round() as usize;
    let mut unit = signal::generate(
        &Maneuver::Doublet { pulse_s: 1.0 },
        dt_s,
        args.duration_s,
        1.0,
    );
    unit.resize(n_steps, 0.0);
    let amp = args.amplitude_deg.to_radians();
    let mut results = serde_json::Map::new();
    say(format!(
        "\n{:<15} {:<11} {:>10} {:>8} {:>10}",
        "transfer fn", "model", "wn rad/s", "zeta", "fit %"
    ));
    for (key, _, surface, output_state) in PAPER_TFS {
        sim.trim(&trim.point)?;
        let plan = FlightPlan {
            rate_hz,
            n_steps,
            inputs: vec![SurfaceInput {
                surface: surface.into(),
                deflection_rad: unit.iter().map(|u| u * amp).collect(),
            }],
        };
        let rec = sim.fly(&plan)?;
        let out_col = if output_state == "Theta" {
            "theta_rad"
        } else {
            "phi_rad"
        };
        let u = rec.require(&format!("{surface}_rad"), "the identification input")?;
        let y = rec.require(out_col, "the identification output")?;
        let du: Vec<f64> = u.iter().map(|x| x - u[0]).collect();
        let dy: Vec<f64> = y.iter().map(|x| x - y[0]).collect();
        let lin_tf = &truth[key];
        let lin_modes = crate::lti::modes(&lin_tf.poles());
        let lin_fit = ident::nrmse_fit(&dy, &crate::lti::lsim(lin_tf, &du, dt_s));
        let mut row = serde_json::Map::new();
        row.insert(
            "jsbsim_linearization".into(),
            json!({"num": lin_tf.num, "den": lin_tf.den, "fit_sim_percent": lin_fit}),
        );
        let show = |model: &str, modes: &[Mode], fit: f64| match dominant(modes) {
            Some(m) => say(format!(
                "{key:<15} {model:<11} {:>10.4} {:>8.4} {:>10.2}",
                m.omega_n_rad_s, m.zeta, fit
            )),
            None => say(format!(
                "{key:<15} {model:<11} {:>10} {:>8} {:>10.2}",
                "-", "-", fit
            )),
        };
        show("linearized", &lin_modes, lin_fit);
        for method in [Method::Ls, Method::Srivc] {
            let opts = IdentOptions {
                method,
                poles: 4,
                zeros: 2,
                estimate_delay: false,
            };
            match ident::identify(&du, &dy, dt_s, &opts) {
                Ok(r) => {
                    show(
                        &format!("{method:?}").to_lowercase(),
                        &crate::lti::modes(&r.poles),
                        r.fit_sim_percent,
                    );
                    row.insert(
                        format!("{method:?}").to_lowercase(),
                        serde_json::to_value(&r)?,
                    );
                }
                Err(e) => {
                    say(format!(
                        "{key:<15} {:<11} failed: {e}",
                        format!("{method:?}").to_lowercase()
                    ));
                    row.insert(
                        format!("{method:?}").to_lowercase(),
                        json!({"error": e.to_string()}),
                    );
                }
            }
        }
        results.insert(key.to_string(), serde_json::Value::Object(row));
    }
    if let Some(target) = &args.json {
        emit_json(
            target,
            &json!({"aircraft": trim.aircraft, "trim": trim, "results": results}),
        )?;
    }
    Ok(())
}
