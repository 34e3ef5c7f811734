#!/usr/bin/env python3
"""Oracle: how JSBSim's integration step moves the c172x short-period damping away from its linearization.

For each simulation rate, through flightid's own bridge (scripts/jsbsim_bridge.py, imported, same private aircraft
copy and surface override as `flightid fly`): trim c172x at 4000 ft, 100 KTAS; take the short-period eigenvalue
of JSBSim's FGLinearization (4-state longitudinal submodel Vt, alpha, theta, q); then fly a short elevator pulse
(override, no actuator) and fit the free pitch-rate response that follows,
    q(t) = e^{sigma t} (c1 cos wd t + c2 sin wd t) + d0 + d1 t + d2 t^2   (polynomial = phugoid over 3 s),
by variable projection (scipy least_squares on sigma, wd). Prints omega_n and zeta of the flown short period
against the linearization's, for two pulse sizes (the gap is an integration effect if it does not depend on size).

Measured (JSBSim 1.3.3, this script):
   rate_Hz  zeta error (0.25 deg / 1 deg pulse)   omega_n error
       120     -2.06 % / -1.94 %                     +0.95 % / +0.87 %
       480     -0.88 % / -0.78 %                     -0.14 % / -0.19 %
      2400     -0.57 % / -0.47 %                     -0.40 % / -0.46 %
independent of the pulse size: an integration effect (JSBSim integrates the rotational rates with rectangular
Euler), not a nonlinearity. The identified gap at 120 Hz is larger (zeta -12.6 % on ZOH-aligned doublet data)
because the response also lags the surface input by about 1.5 steps (see tests/ident_jsbsim.rs); both shrink with
the step, hence tests/ident_jsbsim.rs flies at 2000 Hz.

Usage: python scripts/oracle_jsbsim_step.py    (the provisioned venv: ~/.cache/flightid/venv-*/bin/python)
"""
import os
import shutil
import sys
import tempfile
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.fdopen(os.dup(1), "w", buffering=1)  # the bridge points fd 1 at stderr on import
sys.path.insert(0, HERE)
import jsbsim_bridge as bridge  # noqa: E402

import numpy as np  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

RATES_HZ = [120, 240, 480, 1200, 2400]
PULSES_DEG = [0.25, 1.0]
PULSE_S = 0.1
FIT_S = 3.0
LON = ["Vt", "Alpha", "Theta", "Q"]


def surfaces_spec():
    with open(os.path.join(HERE, "..", "aircraft", "c172x.toml"), "rb") as f:
        cfg = tomllib.load(f)
    return {name: {"command": s["command"], "aero_reads": s["aero_reads"],
                   "aero_reads_abs": s.get("aero_reads_abs", [])} for name, s in cfg["surfaces"].items()}


def short_period(lin):
    a = np.array(lin["A"])
    idx = [lin["states"].index(s) for s in LON]
    ev = np.linalg.eigvals(a[np.ix_(idx, idx)])
    p = max(ev, key=abs)
    wn = abs(p)
    return wn, -p.real / wn


def fit_free_response(t, q, wn0, zeta0):
    def basis(sigma, wd):
        e = np.exp(sigma * t)
        return np.column_stack([e * np.cos(wd * t), e * np.sin(wd * t), np.ones_like(t), t, t * t])

    def resid(x):
        b = basis(*x)
        c, *_ = np.linalg.lstsq(b, q, rcond=None)
        return b @ c - q

    x0 = [-zeta0 * wn0, wn0 * np.sqrt(1 - zeta0 ** 2)]
    sigma, wd = least_squares(resid, x0, x_scale="jac").x
    wn = np.hypot(sigma, wd)
    return wn, -sigma / wn


def main():
    surfaces = surfaces_spec()
    OUT.write(f"{'rate_Hz':>8} {'pulse_deg':>9} {'wn_lin':>8} {'wn_sim':>8} {'wn_err%':>8} "
              f"{'zeta_lin':>8} {'zeta_sim':>8} {'zeta_err%':>9}\n")
    for rate in RATES_HZ:
        dt = 1.0 / rate
        scratch = tempfile.mkdtemp(prefix="flightid-oracle-")
        sim = bridge.Sim({"aircraft": "c172x", "dt_s": dt, "surfaces": surfaces, "scratch_dir": scratch})
        try:
            point = {"altitude_ft": 4000.0, "speed_kts": 100.0}
            sim.trim(point)
            wn_lin, zeta_lin = short_period(sim.linearize({"per_radian_surfaces": list(surfaces)}))
            for pulse_deg in PULSES_DEG:
                sim.trim(point)
                base = sim.trim_surface["elevator"]
                n_pulse = round(PULSE_S * rate)
                n = n_pulse + round(FIT_S * rate)
                u = [base + np.radians(pulse_deg)] * n_pulse + [base] * (n - n_pulse)
                _, out = sim.fly({
                    "n_steps": n,
                    "drives": [{"property": "flightid/override/elevator-rad", "offset": 0}],
                    "record": ["velocities/q-rad_sec"],
                    "set_before": {"flightid/override/elevator": 1.0, "flightid/override/elevator-rad": base},
                }, u)
                q = np.array(out)[n_pulse + 1:]  # row k+1 is the state after step k: free from here on
                t = np.arange(len(q)) * dt
                wn, zeta = fit_free_response(t, q, wn_lin, zeta_lin)
                OUT.write(f"{rate:>8} {pulse_deg:>9.2f} {wn_lin:>8.4f} {wn:>8.4f} {100 * (wn / wn_lin - 1):>+8.2f} "
                          f"{zeta_lin:>8.4f} {zeta:>8.4f} {100 * (zeta / zeta_lin - 1):>+9.2f}\n")
        finally:
            sim.close()
            shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
