#!/usr/bin/env python3
"""Why JSBSim's linearization fits phi/rudder at only ~26 % on c172x (the gap `flightid compare` shows).

Stock JSBSim (no flightid private copy, no surface override): trim c172x at 4000 ft, 100 KTAS, take
FGLinearization there, then fly rudder *command* doublets (1 s pulses) and a small rudder step in the nonlinear
model, and simulate the same command inputs through the full 13-state linearization (ZOH at the sim rate).

What it shows (measured with JSBSim 1.3.3):
  * the first ~4 s agree to a few percent: the Dutch roll and the roll/yaw coupling are right;
  * after the doublet the nonlinear aircraft keeps a bank angle (about 0.31 deg per 0.05 of rudder command) that
    the linearization returns to ~0; the held bank scales linearly with the amplitude (0.02 -> 0.13 deg,
    0.05 -> 0.31 deg, 0.1 -> 0.62 deg), so it does not fade at small amplitude as a smooth nonlinearity
    would (the fit % is flat), and with no input the trim
    drifts by only 0.009 deg in 20 s, so it is not a trim residual;
  * the held bank has the SAME sign for +A and -A doublets (per unit of command at 20 s: +6.1 deg and -5.7 deg,
    i.e. +0.30 and +0.28 deg of bank): an even, |A|-proportional effect, which no linear model can have.
Cause: the c172x's sideslip drag CDbeta = 0.17 |beta| (aero/mag-beta-rad). It has no derivative at beta = 0, so
JSBSim's central-difference linearization sees none of it, while every doublet's sideslip adds drag whatever its
sign; the speed lost couples into a held bank. With CDbeta scaled to 0 in a private copy of the model the
linearization fits phi/rudder at ~95 % instead of ~26 % (phi/aileron 84 -> 94.5 %):
`flightid compare --aircraft c172x --scale CDbeta=0` (asserted in tests/compare_report.rs).

Usage: oracle_rudder_spiral.py   (prints the table; uses the JSBSim Python package, e.g. flightid's own venv
under ~/.cache/flightid/venv-*/bin/python)
"""
import os
import tempfile

import jsbsim
import numpy as np
import scipy.signal as ss

RATE_HZ = 120.0
OUT_DIR = tempfile.mkdtemp(prefix="flightid-oracle-")


def trimmed():
    """c172x trimmed like flightid trims it (docs/jsbsim.md)."""
    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    fdm.set_dt(1.0 / RATE_HZ)
    fdm.set_output_path(OUT_DIR)
    fdm.load_model("c172x")
    fdm.disable_output()
    for k, v in (("ic/lat-geod-deg", 0), ("ic/long-gc-deg", 0), ("ic/h-sl-ft", 4000), ("ic/vt-kts", 100),
                 ("ic/psi-true-deg", 0), ("ic/gamma-deg", 0)):
        fdm[k] = v
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    fdm["simulation/do_simple_trim"] = 1
    return fdm


def fly(u_cmd):
    """Nonlinear flight with rudder command perturbations u_cmd (one per step); phi, beta, r perturbations."""
    fdm = trimmed()
    r0, phi0 = fdm["fcs/rudder-cmd-norm"], fdm["attitude/phi-rad"]
    out = []
    for u in u_cmd:
        fdm["fcs/rudder-cmd-norm"] = r0 + u
        fdm.run()
        out.append((fdm["attitude/phi-rad"] - phi0, fdm["aero/beta-rad"], fdm["velocities/r-rad_sec"]))
    return np.array(out)


def linear(u_cmd):
    """The same input through FGLinearization (full state, ZOH); row k is the state after step k."""
    fdm = trimmed()
    lin = jsbsim.FGLinearization(fdm)
    a, b, _, _ = [np.array(m) for m in lin.state_space]
    names = list(lin.x_names)
    rows = [names.index(s) for s in ("Phi", "Beta", "R")]
    col = list(lin.u_names).index("DrCmd")
    dt = 1.0 / RATE_HZ
    sysd = ss.cont2discrete((a, b[:, [col]], np.eye(a.shape[0])[rows], np.zeros((3, 1))), dt, method="zoh")
    _, y, _ = ss.dlsim(sysd[:4] + (dt,), np.r_[u_cmd, 0.0])
    return y[1:], np.linalg.eigvals(a)


def fit_percent(y, y_hat):
    return 100.0 * (1.0 - np.linalg.norm(y - y_hat) / np.linalg.norm(y - y.mean()))


def main():
    t = np.arange(int(20 * RATE_HZ)) / RATE_HZ
    print("rudder command doublet (1 s pulses from t = 1 s), 20 s at 120 Hz")
    print(f"{'amplitude':>9} {'fit %':>7} {'max |phi| deg':>13} {'phi(20 s) nonlinear':>20} {'linear':>8}")
    for amp in (0.0, 0.02, 0.05, 0.1):
        u = np.where((t >= 1) & (t < 2), amp, np.where((t >= 2) & (t < 3), -amp, 0.0))
        nl = fly(u)
        li, eig = linear(u)
        fit = fit_percent(nl[:, 0], li[:, 0]) if amp > 0 else float("nan")
        print(f"{amp:9.2f} {fit:7.1f} {np.degrees(np.abs(nl[:, 0]).max()):13.3f} "
              f"{np.degrees(nl[-1, 0]):20.3f} {np.degrees(li[-1, 0]):8.3f}")
    slow = sorted((e for e in eig if abs(e.imag) < 1e-9 and -0.1 < e.real < -1e-3), key=lambda e: e.real)
    print("linearization's slow real poles (spiral), 1/s:", [f"{e.real:.4f}" for e in slow])

    t = np.arange(int(120 * RATE_HZ)) / RATE_HZ
    u = np.where(t >= 1.0, 0.01, 0.0)
    nl = fly(u)
    li, _ = linear(u)
    print("rudder command step of 0.01 at t = 1 s: bank angle, deg")
    for ts in (2, 5, 10, 20, 40, 60, 90, 119):
        k = int(ts * RATE_HZ)
        print(f"  t = {ts:4} s  nonlinear {np.degrees(nl[k, 0]):8.3f}  linear {np.degrees(li[k, 0]):8.3f}")


if __name__ == "__main__":
    main()
