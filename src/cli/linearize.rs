//! `flightid linearize`: JSBSim's own linearization at a trim point.

use super::common::{emit_json, TrimArgs};
use crate::sim::linear::{mode_names, paper_transfer_functions, submodel_modes, tf_json};
use crate::sim::Simulator;

/// Trim, then linearize with JSBSim's FGLinearization: A, B, C, D with state/input names and units, the
/// transfer functions theta/elevator, phi/aileron, phi/rudder per radian of surface deflection (decoupled 4-state
/// submodels: Vt, alpha, theta, q and beta, phi, p, r), poles, zeros and modal parameters.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid linearize --aircraft c172x --altitude-ft 4000 --speed-kts 100 --json lin.json"
)]
pub struct LinearizeCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Write the full result as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
}

/// Runs `flightid linearize`.
pub fn run(args: &LinearizeCmd) -> anyhow::Result<()> {
    super::common::check_outputs(&[super::common::json_path(&args.json)], &[])?;
    let (mut sim, trim) = args.trim.start_and_trim()?;
    let lin = sim.linearize()?;
    let tfs = paper_transfer_functions(&lin)?;
    let modes = submodel_modes(&lin)?;
    if let Some(target) = &args.json {
        let tf: serde_json::Map<String, serde_json::Value> = tfs
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    serde_json::to_value(tf_json(v)).expect("serialisable"),
                )
            })
            .collect();
        let mut value = serde_json::to_value(&lin)?;
        let obj = value.as_object_mut().expect("object");
        obj.insert("tf".into(), serde_json::Value::Object(tf));
        obj.insert("tf_model".into(), "decoupled 4-state submodels: longitudinal Vt, Alpha, Theta, Q; lateral Beta, Phi, P, R; inputs per radian of surface deflection".into());
        obj.insert("modes".into(), serde_json::to_value(&modes)?);
        let names: serde_json::Map<String, serde_json::Value> = modes
            .iter()
            .map(|(k, ms)| (k.clone(), serde_json::json!(mode_names(k, ms))))
            .collect();
        obj.insert("mode_names".into(), serde_json::Value::Object(names));
        obj.insert("trim".into(), serde_json::to_value(&trim)?);
        emit_json(target, &value)?;
        if target == "-" {
            return Ok(());
        }
    }
    println!(
        "{} linearized at {} ft, {} kts ({} states, inputs per radian)",
        trim.aircraft,
        trim.point.altitude_ft,
        trim.point.speed_kts,
        lin.states.len()
    );
    for (k, tf) in &tfs {
        println!(
            "  {k:<15} num {:?}",
            tf.num.iter().map(|x| format!("{x:.5}")).collect::<Vec<_>>()
        );
        println!(
            "  {:<15} den {:?}",
            "",
            tf.den.iter().map(|x| format!("{x:.5}")).collect::<Vec<_>>()
        );
    }
    for (name, ms) in &modes {
        for (m, mode) in ms.iter().zip(mode_names(name, ms)) {
            if m.oscillatory {
                println!(
                    "  {name:<13} {mode:<24} wn {:8.4} rad/s  zeta {:7.4}",
                    m.omega_n_rad_s, m.zeta
                );
            } else {
                println!("  {name:<13} {mode:<24} real pole {:9.5} rad/s", m.pole.re);
            }
        }
    }
    Ok(())
}
