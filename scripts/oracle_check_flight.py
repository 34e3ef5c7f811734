#!/usr/bin/env python3
"""Fly a JSBSim c172x maneuver and write it as a flightid flight CSV (docs/data.md).

Oracle data for the data-compatibility check (`flightid check`): a trimmed c172x
at 4000 ft / 100 KTAS gets an elevator doublet, an aileron doublet and a rudder doublet; the
measured channels come straight from JSBSim's state, so the record is kinematically consistent
(up to JSBSim's round-earth terms, below 1e-4 rad/s here).

Specific force (ax, ay, az) is the total non-gravitational body force over mass:
forces/fb{x,y,z}-total-lbs / inertia/weight-lbs * g  (level flight: az = -9.81 m/s^2).

Usage: oracle_check_flight.py OUT.csv [--seconds 30] [--rate-hz 50]
"""

import argparse
import math
import tempfile

import jsbsim

FT = 0.3048
G0 = 9.80665


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--rate-hz", type=float, default=50.0)
    args = ap.parse_args()

    sim_hz = 200.0
    private = tempfile.mkdtemp(prefix="flightid-oracle-")
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_dt(1.0 / sim_hz)
    fdm.set_output_path(private)
    fdm.load_model("c172x")
    fdm.disable_output()
    fdm["ic/lat-geod-deg"] = 47.0
    fdm["ic/long-gc-deg"] = 8.0
    fdm["ic/h-sl-ft"] = 4000.0
    fdm["ic/vt-kts"] = 100.0
    fdm["ic/psi-true-deg"] = 60.0
    fdm["ic/gamma-deg"] = 0.0
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    fdm["simulation/do_simple_trim"] = 1

    trim_elev = fdm["fcs/elevator-cmd-norm"]
    trim_ail = fdm["fcs/aileron-cmd-norm"]
    trim_rud = fdm["fcs/rudder-cmd-norm"]

    def doublet(t, t0, width, amp):
        if t0 <= t < t0 + width:
            return amp
        if t0 + width <= t < t0 + 2 * width:
            return -amp
        return 0.0

    cols = ["time_s", "elevator_rad", "aileron_rad", "rudder_rad", "throttle", "phi_rad", "theta_rad",
            "psi_rad", "p_rad_s", "q_rad_s", "r_rad_s", "alpha_rad", "beta_rad", "airspeed_m_s",
            "altitude_m", "ax_m_s2", "ay_m_s2", "az_m_s2"]
    rows = []
    every = int(round(sim_hz / args.rate_hz))
    steps = int(round(args.seconds * sim_hz))
    for k in range(steps + 1):
        t = k / sim_hz
        fdm["fcs/elevator-cmd-norm"] = trim_elev + doublet(t, 3.0, 0.6, 0.15)
        fdm["fcs/aileron-cmd-norm"] = trim_ail + doublet(t, 10.0, 0.8, 0.2)
        fdm["fcs/rudder-cmd-norm"] = trim_rud + doublet(t, 18.0, 1.0, 0.2)
        if k % every == 0:
            w = fdm["inertia/weight-lbs"]
            rows.append([
                t,
                fdm["fcs/elevator-pos-rad"],
                fdm["fcs/effective-aileron-pos"],
                fdm["fcs/rudder-pos-rad"],
                fdm["fcs/throttle-pos-norm"],
                fdm["attitude/phi-rad"],
                fdm["attitude/theta-rad"],
                fdm["attitude/psi-rad"],
                fdm["velocities/p-rad_sec"],
                fdm["velocities/q-rad_sec"],
                fdm["velocities/r-rad_sec"],
                fdm["aero/alpha-rad"],
                fdm["aero/beta-rad"],
                fdm["velocities/vt-fps"] * FT,
                fdm["position/h-sl-ft"] * FT,
                fdm["forces/fbx-total-lbs"] / w * G0,
                fdm["forces/fby-total-lbs"] / w * G0,
                fdm["forces/fbz-total-lbs"] / w * G0,
            ])
        fdm.run()

    with open(args.out, "w") as f:
        f.write("# JSBSim c172x, 4000 ft, 100 KTAS; elevator/aileron/rudder doublets (scripts/oracle_check_flight.py)\n")
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(repr(float(v)) for v in r) + "\n")


if __name__ == "__main__":
    main()
