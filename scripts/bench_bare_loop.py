#!/usr/bin/env python3
"""Baseline for the bridge benchmark: the same JSBSim steps in a bare Python loop over fdm.run().

Stock aircraft (no flightid private copy), trimmed like flightid trims, then `n_steps` calls of fdm.run() reading
the same 17 properties flightid records each step (fastest access: property nodes, appended to an array).
Usage: bench_bare_loop.py AIRCRAFT ALT_FT SPEED_KTS N_STEPS REPEATS  -> prints {"loop_s": [...]} as JSON.
"""
import array
import json
import os
import sys
import tempfile
import time

PROTO = os.fdopen(os.dup(1), "w")
os.dup2(2, 1)
import jsbsim  # noqa: E402

RECORD = ["fcs/elevator-pos-rad", "fcs/effective-aileron-pos", "fcs/rudder-pos-rad", "fcs/throttle-pos-norm",
          "attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad", "velocities/p-rad_sec",
          "velocities/q-rad_sec", "velocities/r-rad_sec", "aero/alpha-rad", "aero/beta-rad", "velocities/vt-fps",
          "position/h-sl-ft", "accelerations/a-pilot-x-ft_sec2", "accelerations/a-pilot-y-ft_sec2",
          "accelerations/a-pilot-z-ft_sec2"]

aircraft, alt, speed, n_steps, repeats = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
out_dir = tempfile.mkdtemp()
times = []
for _ in range(repeats):
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    fdm.set_dt(1 / 120)
    fdm.set_output_path(out_dir)
    fdm.load_model(aircraft)
    fdm.disable_output()
    fdm["ic/lat-geod-deg"] = 0
    fdm["ic/long-gc-deg"] = 0
    fdm["ic/h-sl-ft"] = alt
    fdm["ic/vt-kts"] = speed
    fdm["ic/psi-true-deg"] = 0
    fdm["ic/gamma-deg"] = 0
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    fdm["simulation/do_simple_trim"] = 1
    pm = fdm.get_property_manager()
    get = [pm.get_node(p).get_double_value for p in RECORD]
    out = array.array("d")
    run = fdm.run
    t0 = time.perf_counter()
    for g in get:
        out.append(g())
    for _k in range(n_steps):
        run()
        for g in get:
            out.append(g())
    times.append(time.perf_counter() - t0)
PROTO.write(json.dumps({"loop_s": times}) + "\n")
