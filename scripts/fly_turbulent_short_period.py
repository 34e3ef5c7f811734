#!/usr/bin/env python3
"""Fly JSBSim's c172x through an elevator 3-2-1-1 in JSBSim's own turbulence (or none) and log the
short-period channels as a flightid flight CSV, driving JSBSim's Python API directly.

Trim at 4000 ft, 100 KTAS, wings level; then an elevator 3-2-1-1 (unit 0.4 s, 0.15 of the
normalised command, beyond the c172x actuator's 0.05 rad hysteresis) at 1 s and a reversed one at 6 s around the trim command. Turbulence: JSBSim's
MIL-F-8785C (Dryden) model, `atmosphere/turb-type` 3 (ttMilspec) with
`atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps` and `.../severity`, seeded by
`simulation/randomseed`. Logged at 50 Hz as deviations from trim (elevator_rad, alpha_rad; q_rad_s
as is), with white sensor noise (alpha 0.0005 rad, q 0.001 rad/s, numpy seed).

Usage: fly_turbulent_short_period.py OUT.csv [--turbulence none|milspec] [--wind-20ft-fps 25]
       [--severity 3] [--seed 1] [--seconds 11]
"""

import argparse
import math
import tempfile

import jsbsim
import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--turbulence", choices=["none", "milspec"], default="none")
    ap.add_argument("--wind-20ft-fps", type=float, default=25.0)
    ap.add_argument("--severity", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--seconds", type=float, default=11.0)
    ap.add_argument("--rate-hz", type=float, default=50.0)
    args = ap.parse_args()

    sim_hz = 200.0
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_dt(1.0 / sim_hz)
    fdm.set_output_path(tempfile.mkdtemp(prefix="flightid-turb-"))
    fdm.load_model("c172x")
    fdm.disable_output()
    fdm["simulation/randomseed"] = args.seed
    fdm["ic/lat-geod-deg"] = 47.0
    fdm["ic/long-gc-deg"] = 8.0
    fdm["ic/h-sl-ft"] = 4000.0
    fdm["ic/vt-kts"] = 100.0
    fdm["ic/psi-true-deg"] = 0.0
    fdm["ic/gamma-deg"] = 0.0
    fdm["atmosphere/turb-type"] = 0
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    fdm["simulation/do_simple_trim"] = 1
    trim_cmd = fdm["fcs/elevator-cmd-norm"]
    trim_de = fdm["fcs/elevator-pos-rad"]
    trim_alpha = fdm["aero/alpha-rad"]
    if args.turbulence == "milspec":
        fdm["atmosphere/turb-type"] = 3
        fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = args.wind_20ft_fps
        fdm["atmosphere/turbulence/milspec/severity"] = args.severity

    def elevator(t):
        u = 0.0
        for start, sign in ((1.0, 1.0), (6.0, -1.0)):
            s = start
            for width, pulse in ((1.2, 1), (0.8, -1), (0.4, 1), (0.4, -1)):
                if s <= t < s + width:
                    u = sign * pulse * 0.15
                s += width
        return u

    rng = np.random.default_rng(args.seed + 1000)
    every = int(round(sim_hz / args.rate_hz))
    rows = []
    for k in range(int(round(args.seconds * sim_hz)) + 1):
        t = k / sim_hz
        fdm["fcs/elevator-cmd-norm"] = trim_cmd + elevator(t)
        if k % every == 0:
            rows.append((
                t,
                fdm["fcs/elevator-pos-rad"] - trim_de,
                fdm["aero/alpha-rad"] - trim_alpha + rng.normal(0.0, 0.0005),
                fdm["velocities/q-rad_sec"] + rng.normal(0.0, 0.001),
            ))
        fdm.run()
    with open(args.out, "w") as f:
        f.write(f"# JSBSim c172x 4000 ft 100 KTAS, elevator 3-2-1-1 x2, turbulence {args.turbulence} "
                f"(scripts/fly_turbulent_short_period.py)\n")
        f.write("time_s,elevator_rad,alpha_rad,q_rad_s\n")
        for r in rows:
            f.write(",".join(repr(float(v)) for v in r) + "\n")


if __name__ == "__main__":
    main()
