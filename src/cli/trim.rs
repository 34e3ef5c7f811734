//! `flightid trim`: trim an aircraft (JSBSim full trim) and print the trim state.

use super::common::{emit_json, TrimArgs};

/// Trim the aircraft at a steady, wings-level point (JSBSim "full" trim) and print alpha, theta, surface and
/// throttle trims. A failed trim is an error (exit 1), never a garbage state.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Example:\n  flightid trim --aircraft c172x --altitude-ft 4000 --speed-kts 100 --json"
)]
pub struct TrimCmd {
    #[command(flatten)]
    pub trim: TrimArgs,
    /// Print the trim state as JSON (to stdout, or to the file given).
    #[arg(long, num_args = 0..=1, default_missing_value = "-", value_name = "FILE")]
    pub json: Option<String>,
}

/// Runs `flightid trim`.
pub fn run(args: &TrimCmd) -> anyhow::Result<()> {
    super::common::check_outputs(&[super::common::json_path(&args.json)], &[])?;
    let (_sim, t) = args.trim.start_and_trim()?;
    if let Some(target) = &args.json {
        return emit_json(target, &t);
    }
    println!(
        "{} trimmed at {} ft, {} kts ({})",
        t.aircraft,
        t.point.altitude_ft,
        t.point.speed_kts,
        t.method.describe()
    );
    println!("  alpha     {:9.4} deg", t.alpha_rad.to_degrees());
    println!("  theta     {:9.4} deg", t.theta_rad.to_degrees());
    println!("  phi       {:9.4} deg", t.phi_rad.to_degrees());
    println!("  airspeed  {:9.3} m/s", t.airspeed_m_s);
    println!("  throttle  {:9.4}", t.throttle);
    for (s, v) in &t.surfaces_rad {
        println!(
            "  {:<9} {:9.4} deg  (command {:+.4})",
            s,
            v.to_degrees(),
            t.commands_norm.get(s).copied().unwrap_or(f64::NAN)
        );
    }
    println!(
        "  pitch trim command {:+.4}",
        t.commands_norm
            .get("pitch-trim")
            .copied()
            .unwrap_or(f64::NAN)
    );
    Ok(())
}
