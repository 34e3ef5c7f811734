"""Independent generator of nonlinear longitudinal flight records for flightid's estimator acceptance.

A light aircraft's point-mass longitudinal motion in still air, flat earth, body-axis thrust through
the centre of gravity (states V, alpha, theta, q; inputs elevator and a measured thrust):

    qbar = 0.5 rho V^2
    CL = CL_0 + CL_alpha*alpha + CL_de*de
    CD = CD_0 + CD_alpha*alpha + CD_alpha2*alpha^2
    Cm = Cm_0 + Cm_alpha*alpha + Cm_q*q*c/(2V) + Cm_de*de
    V_dot     = (T cos(alpha) - qbar S CD)/m - g sin(theta - alpha)
    alpha_dot = (-T sin(alpha) - qbar S CL)/(m V) + q + g cos(theta - alpha)/V
    theta_dot = q
    q_dot     = qbar S c Cm / Iyy
    ax = (T - qbar S (CD cos(alpha) - CL sin(alpha)))/m      (body-axis specific force)
    az = -qbar S (CD sin(alpha) + CL cos(alpha))/m

Trimmed for level flight by scipy's fsolve, integrated with solve_ivp (DOP853, rtol 1e-10) sample to
sample with the sampled inputs linearly interpolated. Per record, 40 s at 25 Hz: an elevator 3-2-1-1
(record a) or doublets (record b) of 1.5-2.5 deg, and a thrust step pair of +-15 % to excite the
phugoid and the drag. Logged: white noise on every channel (V 0.15 m/s, angles 0.1 deg, q 0.15 deg/s,
accelerations 0.05 / 0.08 m/s^2, elevator 0.02 deg, thrust 10 N), an alpha-vane bias and an az bias.

With the optional fourth argument `exact-inputs` the logged elevator and thrust carry no noise: the
inputs are then known exactly, as output error assumes. With noisy inputs (the default, as on real
aircraft) the input noise drives the aircraft like process noise that output error does not model.

Usage: gen_longitudinal_records.py OUT_DIR FIRST_SEED N_SEEDS [exact-inputs]
Writes OUT_DIR/seed{S}_{a,b}.csv and OUT_DIR/truth.json (the aerodynamic coefficients).
"""
import json
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

MASS_KG, S_M2, C_M, IYY_KG_M2, RHO, G = 1043.0, 16.2, 1.49, 1825.0, 1.112, 9.80665
TRUTH = {
    "CL_0": 0.28, "CL_alpha": 4.9, "CL_de": 0.42,
    "CD_0": 0.032, "CD_alpha": 0.12, "CD_alpha2": 1.1,
    "Cm_0": 0.045, "Cm_alpha": -0.95, "Cm_q": -12.5, "Cm_de": -1.25,
}
RATE_HZ, DURATION_S, V_TRIM = 25.0, 40.0, 52.0


def forces(x, de, thrust, p=TRUTH):
    v, alpha, theta, q = x
    qbar = 0.5 * RHO * v * v
    cl = p["CL_0"] + p["CL_alpha"] * alpha + p["CL_de"] * de
    cd = p["CD_0"] + p["CD_alpha"] * alpha + p["CD_alpha2"] * alpha**2
    cm = p["Cm_0"] + p["Cm_alpha"] * alpha + p["Cm_q"] * q * C_M / (2 * v) + p["Cm_de"] * de
    return qbar, cl, cd, cm


def rhs(x, de, thrust):
    v, alpha, theta, q = x
    qbar, cl, cd, cm = forces(x, de, thrust)
    return np.array([
        (thrust * np.cos(alpha) - qbar * S_M2 * cd) / MASS_KG - G * np.sin(theta - alpha),
        (-thrust * np.sin(alpha) - qbar * S_M2 * cl) / (MASS_KG * v) + q + G * np.cos(theta - alpha) / v,
        q,
        qbar * S_M2 * C_M * cm / IYY_KG_M2,
    ])


def accelerations(x, de, thrust):
    alpha = x[1]
    qbar, cl, cd, _ = forces(x, de, thrust)
    ax = (thrust - qbar * S_M2 * (cd * np.cos(alpha) - cl * np.sin(alpha))) / MASS_KG
    az = -qbar * S_M2 * (cd * np.sin(alpha) + cl * np.cos(alpha)) / MASS_KG
    return ax, az


def trim():
    def eq(z):
        alpha, de, thrust = z
        return rhs([V_TRIM, alpha, alpha, 0.0], de, thrust)[[0, 1, 3]]
    alpha, de, thrust = fsolve(eq, [0.03, -0.02, 1500.0], xtol=1e-13)
    return alpha, de, thrust


def schedule(t, edges, amp):
    u = np.zeros_like(t)
    for t0, t1, s in edges:
        u[(t >= t0 - 1e-9) & (t < t1 - 1e-9)] = s * amp
    return u


def record(rng, kind, input_noise):
    t = np.arange(0.0, DURATION_S + 1e-9, 1.0 / RATE_HZ)
    alpha0, de0, thrust0 = trim()
    amp = np.deg2rad(rng.uniform(1.5, 2.5))
    if kind == "3211":
        edges = [(2.0, 3.2, 1), (3.2, 4.0, -1), (4.0, 4.4, 1), (4.4, 4.8, -1)]
    else:
        edges = [(2.0, 2.8, 1), (2.8, 3.6, -1), (20.0, 20.8, -1), (20.8, 21.6, 1)]
    de = de0 + schedule(t, edges, amp)
    thrust = thrust0 * (1.0 + schedule(t, [(8.0, 14.0, 1), (26.0, 32.0, -1)], 0.15))

    def f(tt, x):
        return rhs(x, np.interp(tt, t, de), np.interp(tt, t, thrust))

    x = np.array([V_TRIM + rng.normal(0, 0.5), alpha0 + rng.normal(0, 0.005),
                  alpha0 + rng.normal(0, 0.005), rng.normal(0, 0.005)])
    xs = [x]
    for k in range(len(t) - 1):
        sol = solve_ivp(f, (t[k], t[k + 1]), x, method="DOP853", rtol=1e-10, atol=1e-12)
        x = sol.y[:, -1]
        xs.append(x)
    xs = np.array(xs)
    acc = np.array([accelerations(xs[k], de[k], thrust[k]) for k in range(len(t))])
    n = len(t)
    noise = lambda sd: rng.normal(0.0, sd, n)
    alpha_bias, az_bias = rng.normal(0.0, np.deg2rad(0.5)), rng.normal(0.0, 0.1)
    return {
        "time_s": t,
        "elevator_rad": de + input_noise * noise(np.deg2rad(0.02)),
        "thrust_n": thrust + input_noise * noise(10.0),
        "airspeed_m_s": xs[:, 0] + noise(0.15),
        "alpha_rad": xs[:, 1] + alpha_bias + noise(np.deg2rad(0.1)),
        "theta_rad": xs[:, 2] + noise(np.deg2rad(0.1)),
        "q_rad_s": xs[:, 3] + noise(np.deg2rad(0.15)),
        "ax_m_s2": acc[:, 0] + noise(0.05),
        "az_m_s2": acc[:, 1] + az_bias + noise(0.08),
    }


def main():
    out, first, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    input_noise = 0.0 if sys.argv[4:5] == ["exact-inputs"] else 1.0
    os.makedirs(out, exist_ok=True)
    for seed in range(first, first + n):
        rng = np.random.default_rng(1000 + seed)
        for name, kind in (("a", "3211"), ("b", "doublets")):
            cols = record(rng, kind, input_noise)
            with open(os.path.join(out, f"seed{seed}_{name}.csv"), "w") as fh:
                fh.write(",".join(cols) + "\n")
                for row in zip(*cols.values()):
                    fh.write(",".join(f"{v:.10g}" for v in row) + "\n")
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump(TRUTH, fh)


if __name__ == "__main__":
    main()
