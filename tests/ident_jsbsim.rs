//! Identification on JSBSim data: c172x at 4000 ft, 100 KTAS, doublets flown through the bridge; srivc and oe
//! against JSBSim's own linearization (decoupled 4-state submodels). Target: short-period ωn and ζ from θ/δe and
//! Dutch-roll ωn from φ/δa within 3 %.
//!
//! Recipe, and why:
//! - **2000 Hz simulation rate.** At JSBSim's usual 120 Hz the flown response differs from the continuous
//!   linearization in two ways that shrink with the step: (a) the free short-period response itself is less damped
//!   (`scripts/oracle_jsbsim_step.py`, free response after a pulse vs FGLinearization: ζ −2.0 % at 120 Hz, −0.5 % at
//!   2400 Hz, the same for 0.25° and 1° pulses — JSBSim's rectangular-Euler rotational integration); (b) the
//!   response lags the zero-order-hold surface input by an effective 1.5 steps (delay estimated by srivc/oe on
//!   correctly aligned data: 12.9 ms at 120 Hz, 1.0 ms at 2000 Hz). A 4-pole/2-zero model without delay absorbs
//!   (b) as lost damping: on ZOH-aligned 120 Hz data SP ζ comes out −12.6 %, with the delay estimated −2.7 %.
//!   At 2000 Hz both effects are below 2 % and no delay needs estimating.
//! - **Mode-matched doublets, 1° surface deflection** (override, no actuator dynamics): 0.4 s pulses on the
//!   elevator (≈ 0.4 of a short-period cycle, 2π/6.1 ≈ 1 s), 1.1 s pulses on the aileron (≈ 0.4 of a Dutch-roll
//!   cycle, 2π/2.13 ≈ 3 s) — the mode under test dominates the response.
//! - **10 s records.** Over 30 s the slow lateral–longitudinal coupling that the decoupled 4-state reference
//!   drops enters φ: the φ/δa fit falls from 98 % to 92 % and the Dutch-roll ωn error grows to 3.0 % (ζ −5.5 %).
//! - 4 poles, 2 zeros, all 20,000 samples (decimating by 10 without an anti-alias filter moved ζ by 4 points).
//!
//! Measured (srivc and oe agree to 4 digits): SP ωn +1.44 %, ζ −1.68 %; DR ωn +2.07 % (ζ +0.7 %); runtime ≈ 4 s.
//! The 3 % tolerance is the issue's; the remaining +1.5…2 % ωn bias is what is left of (a) and (b) plus the
//! 4-state reference's dropped couplings.
//!
//! Quirk of the recorded data: the surface columns of a `fly` record are one sample late for a ZOH model (row k
//! holds the deflection applied during step k−1 → k, whose effect row k already shows). Used as recorded, that
//! one-sample lead partly cancels JSBSim's 1.5-step lag (b) — at 120 Hz ζ is then −6.4 % instead of −12.6 %; at
//! 2000 Hz the difference is 0.4 points of ζ. Left as is (src/sim is not ident's); noted in the report.

use flightid::aircraft;
use flightid::ident::{self, IdentOptions, Method};
use flightid::lti::{self, Mode};
use flightid::signal::{self, Maneuver};
use flightid::sim::linear::paper_transfer_functions;
use flightid::sim::{FlightPlan, JsbsimSim, Simulator, SurfaceInput, TrimPoint};

fn dominant(poles: &[num_complex::Complex64]) -> Mode {
    lti::modes(poles)
        .into_iter()
        .filter(|m| m.oscillatory)
        .max_by(|a, b| a.omega_n_rad_s.total_cmp(&b.omega_n_rad_s))
        .expect("an oscillatory mode")
}

#[test]
fn srivc_and_oe_match_the_c172x_linearization_short_period_and_dutch_roll_within_3_percent() {
    let rate_hz = 2000.0;
    let duration_s = 10.0;
    let dt_s = 1.0 / rate_hz;
    let mut sim = JsbsimSim::start(&aircraft::load("c172x").unwrap(), rate_hz).unwrap();
    let point = TrimPoint::level(4000.0, 100.0);
    sim.trim(&point).unwrap();
    let truth = paper_transfer_functions(&sim.linearize().unwrap()).unwrap();
    for (key, surface, output, pulse_s) in [
        ("theta/elevator", "elevator", "theta_rad", 0.4),
        ("phi/aileron", "aileron", "phi_rad", 1.1),
    ] {
        sim.trim(&point).unwrap();
        let n_steps = (duration_s * rate_hz) as usize;
        let mut shape = signal::generate(&Maneuver::Doublet { pulse_s }, dt_s, duration_s, 1.0);
        shape.resize(n_steps, 0.0);
        let rec = sim
            .fly(&FlightPlan {
                rate_hz,
                n_steps,
                inputs: vec![SurfaceInput {
                    surface: surface.into(),
                    deflection_rad: shape.iter().map(|x| x * 1f64.to_radians()).collect(),
                }],
            })
            .unwrap();
        let u = rec.require(format!("{surface}_rad"), "input").unwrap();
        let y = rec.require(output, "output").unwrap();
        let lin = dominant(&truth[key].poles());
        for method in [Method::Srivc, Method::Oe] {
            let opts = IdentOptions {
                method,
                poles: 4,
                zeros: 2,
                estimate_delay: false,
            };
            let r = ident::identify(u, y, dt_s, &opts).unwrap();
            let m = dominant(&r.poles);
            let wn_err = (m.omega_n_rad_s - lin.omega_n_rad_s) / lin.omega_n_rad_s;
            let zeta_err = (m.zeta - lin.zeta) / lin.zeta;
            eprintln!(
                "{key} {method}: wn {:.4} vs {:.4} ({:+.2} %), zeta {:.4} vs {:.4} ({:+.2} %), fit {:.2} %",
                m.omega_n_rad_s,
                lin.omega_n_rad_s,
                100.0 * wn_err,
                m.zeta,
                lin.zeta,
                100.0 * zeta_err,
                r.fit_sim_percent
            );
            assert!(wn_err.abs() < 0.03, "{key} {method}: ωn error {wn_err}");
            if key == "theta/elevator" {
                assert!(zeta_err.abs() < 0.03, "{key} {method}: ζ error {zeta_err}");
            }
        }
    }
}
