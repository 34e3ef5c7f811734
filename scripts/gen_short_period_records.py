"""Independent generator of short-period flight records for flightid's estimator acceptance test.

Linear short-period model (states alpha_rad, q_rad_s; input elevator_rad):
    alpha_dot = Z_alpha*alpha + q + Z_de*de
    q_dot     = M_alpha*alpha + M_q*q + M_de*de
integrated with scipy's solve_ivp (DOP853, rtol 1e-10) with the sampled elevator linearly
interpolated between samples. Per record: a random initial state, a 3-2-1-1 (record 1) or a
doublet pair (record 2) of 2-3 deg, 25 Hz, 14 s; the logged elevator carries white noise
(0.02 deg), the logged alpha and q white noise (0.002 rad, 0.005 rad/s) and a constant bias each.

Usage: gen_short_period_records.py OUT_DIR FIRST_SEED N_SEEDS
Writes OUT_DIR/seed{S}_{a,b}.csv and OUT_DIR/truth.json.
"""
import json
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

TRUTH = {"Z_alpha": -1.05, "Z_de": -0.12, "M_alpha": -6.5, "M_q": -2.1, "M_de": -10.5}
RATE_HZ = 25.0
DURATION_S = 14.0


def elevator(t, kind, amp):
    """3-2-1-1 or doublet pair, seconds from 1 s, unit 0.4 s."""
    if kind == "3211":
        edges = [(1.0, 2.2, 1), (2.2, 3.0, -1), (3.0, 3.4, 1), (3.4, 3.8, -1)]
    else:
        edges = [(1.0, 1.6, 1), (1.6, 2.2, -1), (6.0, 6.5, -1), (6.5, 7.0, 1)]
    u = np.zeros_like(t)
    for t0, t1, s in edges:
        u[(t >= t0 - 1e-9) & (t < t1 - 1e-9)] = s * amp
    return u


def record(rng, kind):
    t = np.arange(0.0, DURATION_S + 1e-9, 1.0 / RATE_HZ)
    amp = np.deg2rad(rng.uniform(2.0, 3.0))
    de = elevator(t, kind, amp)
    p = TRUTH
    a = np.array([[p["Z_alpha"], 1.0], [p["M_alpha"], p["M_q"]]])
    b = np.array([p["Z_de"], p["M_de"]])

    def f(tt, x):
        return a @ x + b * np.interp(tt, t, de)

    x0 = np.array([rng.normal(0.0, 0.01), rng.normal(0.0, 0.02)])
    # integrate sample to sample so the kinks of the interpolated input are never stepped over
    xs = [x0]
    x = x0
    for k in range(len(t) - 1):
        sol = solve_ivp(f, (t[k], t[k + 1]), x, method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
        xs.append(x)
    xs = np.array(xs)
    bias = rng.normal(0.0, [0.01, 0.005])
    alpha = xs[:, 0] + bias[0] + rng.normal(0.0, 0.002, len(t))
    q = xs[:, 1] + bias[1] + rng.normal(0.0, 0.005, len(t))
    de_logged = de + rng.normal(0.0, np.deg2rad(0.02), len(t))
    return t, de_logged, alpha, q


def main():
    out, first, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    os.makedirs(out, exist_ok=True)
    for seed in range(first, first + n):
        rng = np.random.default_rng(seed)
        for name, kind in (("a", "3211"), ("b", "doublets")):
            t, de, alpha, q = record(rng, kind)
            with open(os.path.join(out, f"seed{seed}_{name}.csv"), "w") as fh:
                fh.write("time_s,elevator_rad,alpha_rad,q_rad_s\n")
                for row in zip(t, de, alpha, q):
                    fh.write(",".join(f"{v:.10g}" for v in row) + "\n")
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump(TRUTH, fh)


if __name__ == "__main__":
    main()
