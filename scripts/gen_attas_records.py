#!/usr/bin/env python3
"""Flight-test records of an ATTAS-like transport in the text layout of Jategaonkar's book, with known truth.

An independent test-data generator for `flightid derivatives` on the book's ATTAS records: it does not import
or call flightid, only numpy and scipy. It flies a six-degree-of-freedom rigid body with the mass, inertia,
geometry, engine position and sensor positions of DLR's ATTAS (VFW-614) as the book's preprocessing script
for its ATTAS records gives them, through light Dryden turbulence, and writes what the aircraft's data system
would log, in the layout of the book's supplement (fAttasElv1.asc, fAttasAilRud1.asc, ...): no header row,
38 columns of numbers separated by spaces, degrees, deg/s, feet, two ailerons, two engines, the flow angles
and airspeed at a nose boom 13 m ahead of the CG, accelerations at an IMU 1 m behind and 0.9 m to the right
of it, sensor noise and biases. The aerodynamic coefficients are the truth; the lateral ones are the book's
output-error estimates for the ATTAS records converted to span-based coefficients, the longitudinal ones
typical of a transport of this size (the book's ATTAS longitudinal estimates are dimensional).

Files written to --out DIR:

  attas_elv.asc       elevator 3-2-1-1 (jittered timing, unequal pulses), then free response;
  attas_ailrud.asc    an aileron doublet, then a rudder doublet (the book's fAttasAilRud1 plan);
  attas.truth.json    the coefficients (flightid's names), the trim, the constants, the seeds;
  attas_elv.mat, attas_ailrud.mat   with --mat: the same numbers as MATLAB MAT-files (a matrix named as the file).

Column layout (1-based, as the book's test cases read its records): 1 time s; 2-4 a_x a_y a_z m/s2 at the
IMU; 7-9 p q r deg/s; 10-12 phi theta psi deg; 13-14 alpha beta deg at the nose boom; 15 true airspeed m/s at
the nose boom; 16 altitude ft; 17-19 pdot qdot rdot deg/s2; 22 elevator deg; 28-29 left and right aileron
deg; 30 rudder deg; 31 Mach; 34 air density kg/m3; 37-38 left and right engine thrust N. The other columns
are written as zeros.

Model (SI units, radians; body axes x forward, y right, z down; flat Earth, gravity g along the local
vertical). States: body velocity u, v, w over ground, body rates p, q, r, Euler angles phi, theta, psi,
altitude h (a pressure altitude; the day is 15 K warmer than the standard atmosphere, so the air is 5.5 %
thinner than the ISA density at h). The air moves with a gust (u_g, v_g, w_g) given in body axes (Dryden, MIL-F-8785C forms, frozen
along the trim speed; the gusts' rotary part is neglected), so the air-relative velocity is
(u - u_g, v - v_g, w - w_g) with V = its norm, alpha = atan2(w_a, u_a), beta = asin(v_a / V).

  C_L = C_L0 + C_Lalpha alpha + C_Lde de            C_D = C_D0 + k C_L^2 (a parabolic polar)
  C_Y = C_Ybeta beta + C_Ydr dr
  C_l = C_lbeta beta + C_lp p b/2V + C_lr r b/2V + C_lda da + C_ldr dr
  C_m = C_m0 + C_malpha alpha + C_mq q c/2V + C_mde de
  C_n = C_nbeta beta + C_np p b/2V + C_nr r b/2V + C_nda da + C_ndr dr

Body forces X = qS(-C_D cos alpha + C_L sin alpha) + T, Y = qS C_Y, Z = qS(-C_D sin alpha - C_L cos alpha);
moments qSb C_l, qSc C_m + T z_E, qSb C_n about the CG (T is the sum of both engines along body x, z_E the
engines' height below the CG). Rigid-body equations (Stevens & Lewis eq. 1.7-18, with I_xz):

  u' = X/m - g sin theta + r v - q w,   v' = Y/m + g cos theta sin phi + p w - r u,
  w' = Z/m + g cos theta cos phi + q u - p v,
  I_x p' - I_xz r' = L + (I_y - I_z) q r + I_xz p q,   I_y q' = M + (I_z - I_x) p r + I_xz (r^2 - p^2),
  I_z r' - I_xz p' = N + (I_x - I_y) p q - I_xz q r,
  Euler-angle kinematics, h' = u sin theta - v sin phi cos theta - w cos phi cos theta.

Sensors: the IMU reads the specific force at its position, a_CG + w' x r + w x (w x r); the nose boom reads
the air velocity at its position, V_a + w x r_nb, as alpha, beta and airspeed. Integrated by RK4 at 200 Hz,
logged at 25 Hz (every 8th step), the surfaces held over each step.
"""

import argparse
import json
import math
import os

import numpy as np
import scipy.io

from dryden import dryden_series

G = 9.80665
MASS = 17631.0
IX, IY, IZ, IXZ = 133367.0, 252687.0, 359593.0, 11442.0
S_REF, SPAN, CBAR = 64.0, 21.5, 3.159
Z_ENGINE = -0.652          # engines above the CG: the thrust pitches the nose down
R_IMU = np.array([-1.010, 0.886, 0.103])
R_BOOM = np.array([13.080, -0.010, -0.027])
ALT_M = 4877.0
V_TRIM = 129.0
SIM_HZ, LOG_EVERY = 200.0, 8
L_TURB = 533.0             # Dryden scale length above 2000 ft, m
DELTA_T = 15.0             # a warm day: the air 15 K above the standard atmosphere's temperature

TRUTH = {
    "CL_0": 0.20, "CL_alpha": 5.20, "CL_de": 0.35,
    "CD_0": 0.025, "CD_k": 1.0 / (math.pi * 7.22 * 0.8),
    "Cm_0": 0.06, "Cm_alpha": -1.05, "Cm_q": -22.0, "Cm_de": -1.60,
    "CY_beta": -0.85, "CY_dr": 0.22,
    "Cl_beta": -0.063, "Cl_p": -0.385, "Cl_r": 0.10, "Cl_da": -0.096, "Cl_dr": 0.010,
    "Cn_beta": 0.131, "Cn_p": -0.030, "Cn_r": -0.26, "Cn_da": -0.005, "Cn_dr": -0.074,
}

# 1-sigma noise and biases of the logged signals (the biases of a_x, a_y, a_z, p, q, r are the book's for its
# ATTAS records).
NOISE = {"acc_m_s2": 0.02, "rate_deg_s": 0.05, "att_deg": 0.02, "flow_deg": 0.03, "airspeed_m_s": 0.08,
         "alt_ft": 2.0, "accel_deg_s2": 0.3, "surface_deg": 0.01, "thrust_n": 150.0}
BIAS = {"ax": 6.76e-3, "ay": -1.51e-3, "az": 8.40e-2, "p_deg_s": 0.0588, "q_deg_s": 0.1953, "r_deg_s": 0.0571}


def isa_density(h):
    """The density of a day DELTA_T warmer than the standard atmosphere at the same pressure altitude h: the
    ISA pressure over R (T_ISA + DELTA_T). What the data system logs; the ISA density at the logged altitude
    is DELTA_T / T higher."""
    t = 288.15 - 0.0065 * h
    p = 101325.0 * (t / 288.15) ** (G / (287.05287 * 0.0065))
    return p / (287.05287 * (t + DELTA_T))


def speed_of_sound(h):
    return math.sqrt(1.4 * 287.05287 * (288.15 - 0.0065 * h + DELTA_T))


def aero(x, ctl, gust):
    """Body forces (without gravity) and moments about the CG, and the air data, at state x."""
    u, v, w, p, q, r = x[:6]
    h = x[9]
    de, da, dr, thrust = ctl
    ua, va, wa = u - gust[0], v - gust[1], w - gust[2]
    V = math.sqrt(ua * ua + va * va + wa * wa)
    alpha = math.atan2(wa, ua)
    beta = math.asin(va / V)
    rho = isa_density(h)
    qs = 0.5 * rho * V * V * S_REF
    ph, qh, rh = p * SPAN / (2 * V), q * CBAR / (2 * V), r * SPAN / (2 * V)
    t = TRUTH
    cl = t["CL_0"] + t["CL_alpha"] * alpha + t["CL_de"] * de
    cd = t["CD_0"] + t["CD_k"] * cl * cl
    cy = t["CY_beta"] * beta + t["CY_dr"] * dr
    cll = t["Cl_beta"] * beta + t["Cl_p"] * ph + t["Cl_r"] * rh + t["Cl_da"] * da + t["Cl_dr"] * dr
    cm = t["Cm_0"] + t["Cm_alpha"] * alpha + t["Cm_q"] * qh + t["Cm_de"] * de
    cn = t["Cn_beta"] * beta + t["Cn_p"] * ph + t["Cn_r"] * rh + t["Cn_da"] * da + t["Cn_dr"] * dr
    ca, sa = math.cos(alpha), math.sin(alpha)
    force = np.array([qs * (-cd * ca + cl * sa) + thrust, qs * cy, qs * (-cd * sa - cl * ca)])
    moment = np.array([qs * SPAN * cll, qs * CBAR * cm + thrust * Z_ENGINE, qs * SPAN * cn])
    return force, moment, (V, alpha, beta, rho)


def derivs(x, ctl, gust):
    u, v, w, p, q, r, phi, theta, psi, h = x
    force, moment, _ = aero(x, ctl, gust)
    sphi, cphi, sth, cth = math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta)
    du = force[0] / MASS - G * sth + r * v - q * w
    dv = force[1] / MASS + G * cth * sphi + p * w - r * u
    dw = force[2] / MASS + G * cth * cphi + q * u - p * v
    # [I_x, -I_xz; -I_xz, I_z] [p'; r'] = [L + ...; N + ...]
    ll = moment[0] + (IY - IZ) * q * r + IXZ * p * q
    nn = moment[2] + (IX - IY) * p * q - IXZ * q * r
    det = IX * IZ - IXZ * IXZ
    dp = (IZ * ll + IXZ * nn) / det
    dr_ = (IXZ * ll + IX * nn) / det
    dq = (moment[1] + (IZ - IX) * p * r + IXZ * (r * r - p * p)) / IY
    dphi = p + (q * sphi + r * cphi) * math.tan(theta)
    dth = q * cphi - r * sphi
    dpsi = (q * sphi + r * cphi) / cth
    dh = u * sth - v * sphi * cth - w * cphi * cth
    return np.array([du, dv, dw, dp, dq, dr_, dphi, dth, dpsi, dh])


def trim(psi0):
    """Wings-level straight flight at V_TRIM and ALT_M: alpha, elevator and thrust from the three symmetric
    equations (Newton on u' = w' = q' = 0 with theta = alpha)."""
    z = np.array([0.04, -0.02, 20000.0])

    def state(z):
        a = z[0]
        return np.array([V_TRIM * math.cos(a), 0.0, V_TRIM * math.sin(a), 0, 0, 0, 0, a, psi0, ALT_M])

    def res(z):
        d = derivs(state(z), (z[1], 0.0, 0.0, z[2]), (0.0, 0.0, 0.0))
        return np.array([d[0], d[2], d[4]])

    for _ in range(50):
        f = res(z)
        jac = np.empty((3, 3))
        for j, step in enumerate((1e-6, 1e-6, 1.0)):
            dz = np.zeros(3)
            dz[j] = step
            jac[:, j] = (res(z + dz) - f) / step
        z = z - np.linalg.solve(jac, f)
        if np.max(np.abs(res(z) / [1.0, 1.0, 0.01])) < 1e-10:
            break
    return state(z), {"alpha_rad": z[0], "theta_rad": z[0], "elevator_rad": z[1], "thrust_n": z[2],
                      "airspeed_m_s": V_TRIM, "altitude_m": ALT_M, "density_kg_m3": isa_density(ALT_M)}


def dryden(sigma, n, dt, rng):
    """u_g, v_g, w_g (m/s) on n samples dt apart, one row per sample (scripts/dryden.py: the MIL-F-8785C
    forms, T = L/V, exact discretisation from the stationary distribution); zeros when sigma == 0."""
    return np.array(dryden_series(("u", "w", "w"), sigma, L_TURB / V_TRIM, n, dt, rng)).T


def schedule(kind, rng):
    """Pulse trains (start s, end s, deflection rad) for each surface; timing jittered, pulses unequal."""
    j = lambda: rng.uniform(-0.08, 0.08)
    amp = lambda base: math.radians(base) * rng.uniform(0.85, 1.15)
    if kind == "elv":
        unit = 0.75 + rng.uniform(-0.05, 0.05)
        t, a, pulses = 2.0 + rng.uniform(0, 1), amp(1.6), []
        for k, sign in ((3, 1), (2, -1), (1, 1), (1, -1)):
            d = k * unit + j()
            pulses.append((t, t + d, sign * a * rng.uniform(0.9, 1.1)))
            t += d
        return {"elevator": pulses, "aileron": [], "rudder": []}, 20.0
    t0 = 2.0 + rng.uniform(0, 1)
    ail = [(t0, t0 + 1.5 + j(), amp(4.0)), (t0 + 1.5, t0 + 3.0 + j(), -amp(4.0))]
    t1 = 17.0 + rng.uniform(0, 1)
    rud = [(t1, t1 + 1.8 + j(), amp(3.5)), (t1 + 1.8, t1 + 3.6 + j(), -amp(3.5))]
    return {"elevator": [], "aileron": ail, "rudder": rud}, 35.0


def surface(t, pulses, trim_value=0.0):
    return trim_value + sum(d for (a, b, d) in pulses if a <= t < b)


def simulate(kind, seed, turb, psi0):
    rng = np.random.default_rng([seed, 1 if kind == "elv" else 2])
    plan, duration = schedule(kind, rng)
    x, tr = trim(psi0)
    dt = 1.0 / SIM_HZ
    n = int(round(duration * SIM_HZ)) + 1
    gust = dryden(turb, n + 1, dt, rng)
    thrust_walk = np.cumsum(rng.standard_normal(n)) * 2.0
    rows = []
    for i in range(n):
        t = i * dt
        ctl = (surface(t, plan["elevator"], tr["elevator_rad"]), surface(t, plan["aileron"]),
               surface(t, plan["rudder"]), tr["thrust_n"] + thrust_walk[i])
        if i % LOG_EVERY == 0:
            rows.append(log_row(t, x, ctl, gust[i], rng))
        g_mid = 0.5 * (gust[i] + gust[i + 1])
        k1 = derivs(x, ctl, gust[i])
        k2 = derivs(x + 0.5 * dt * k1, ctl, g_mid)
        k3 = derivs(x + 0.5 * dt * k2, ctl, g_mid)
        k4 = derivs(x + dt * k3, ctl, gust[i + 1])
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.all(np.isfinite(x)):
            raise SystemExit(f"gen_attas_records: the {kind} flight diverged at t = {t:.2f} s")
    return np.array(rows), plan, tr


def log_row(t, x, ctl, gust, rng):
    """One logged sample: the 38 columns of the book's layout."""
    de, da, dr, thrust = ctl
    force, _, (_, _, _, rho) = aero(x, ctl, gust)
    d = derivs(x, ctl, gust)
    w = x[3:6]
    wdot = d[3:6]
    a_cg = force / MASS
    a_imu = a_cg + np.cross(wdot, R_IMU) + np.cross(w, np.cross(w, R_IMU))
    air = x[:3] - gust + np.cross(w, R_BOOM)
    v_nb = float(np.linalg.norm(air))
    alpha_nb, beta_nb = math.atan2(air[2], air[0]), math.asin(air[1] / v_nb)
    nz = NOISE
    e = lambda s: rng.normal(0.0, s)
    deg = math.degrees
    row = np.zeros(38)
    row[0] = t
    row[1:4] = a_imu + [BIAS["ax"], BIAS["ay"], BIAS["az"]] + rng.normal(0, nz["acc_m_s2"], 3)
    rates = [deg(w[0]) + BIAS["p_deg_s"], deg(w[1]) + BIAS["q_deg_s"], deg(w[2]) + BIAS["r_deg_s"]]
    row[6:9] = np.array(rates) + rng.normal(0, nz["rate_deg_s"], 3)
    row[9:12] = np.degrees(x[6:9]) + rng.normal(0, nz["att_deg"], 3)
    row[12] = deg(alpha_nb) + e(nz["flow_deg"])
    row[13] = deg(beta_nb) + e(nz["flow_deg"])
    row[14] = v_nb + e(nz["airspeed_m_s"])
    row[15] = x[9] / 0.3048 + e(nz["alt_ft"])
    row[16:19] = np.degrees(wdot) + rng.normal(0, nz["accel_deg_s2"], 3)
    row[21] = deg(de) + e(nz["surface_deg"])
    # The book's aileron is half of right minus left: the right surface at +da, the left at -da.
    row[27] = -deg(da) + e(nz["surface_deg"])
    row[28] = deg(da) + e(nz["surface_deg"])
    row[29] = deg(dr) + e(nz["surface_deg"])
    row[30] = v_nb / speed_of_sound(x[9])
    row[33] = rho
    row[36] = 0.5 * thrust + e(nz["thrust_n"])
    row[37] = 0.5 * thrust + e(nz["thrust_n"])
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--turb-ms", type=float, default=0.5, help="sigma of each Dryden gust component, m/s")
    ap.add_argument("--mat", action="store_true",
                    help="also write each record as a MATLAB MAT-file (attas_elv.mat compressed, attas_ailrud.mat not)")
    args = ap.parse_args()
    if args.turb_ms < 0:
        ap.error("--turb-ms must be >= 0")
    os.makedirs(args.out, exist_ok=True)
    psi0 = 0.226
    records = []
    for kind in ("elv", "ailrud"):
        rows, plan, tr = simulate(kind, args.seed, args.turb_ms, psi0)
        name = f"attas_{kind}.asc"
        tmp = os.path.join(args.out, name + ".part")
        np.savetxt(tmp, rows, delimiter="", fmt="%16.7e")
        os.replace(tmp, os.path.join(args.out, name))
        if args.mat:
            # The same numbers as the text file (read back from it), as the book's supplement also ships its
            # ATTAS records: a MATLAB matrix named as the file, here beside a scalar and a character array.
            # The elevator record compressed (MATLAB's -v7 default), the other not (-v6).
            stem = f"attas_{kind}"
            scipy.io.savemat(os.path.join(args.out, stem + ".mat"),
                             {stem: np.loadtxt(os.path.join(args.out, name)), "dt": 1.0 / (SIM_HZ / LOG_EVERY),
                              "source": "gen_attas_records.py"},
                             do_compression=(kind == "elv"))
        records.append({"file": name, "samples": len(rows), "pulses_rad": plan})
    truth = {
        "source": "scripts/gen_attas_records.py: ATTAS mass, inertia, geometry, engine and sensor positions of "
                  "Jategaonkar's book; lateral coefficients the book's output-error estimates (span-based)",
        "coefficients": TRUTH,
        "flightid_equivalent": {**TRUTH, "Cl_da": -TRUTH["Cl_da"], "Cn_da": -TRUTH["Cn_da"],
                                "note": "the coefficients against flightid's aileron_rad, which the shipped map "
                                        "forms as half of left minus right (positive rolls right, the schema's "
                                        "sign): the book's aileron derivatives with the other sign"},
        "note": "C_D = C_D0 + k C_L^2; flightid's linear C_D is an approximation of it. Rates normalised by the "
                "air-relative speed at the CG. Moments about the CG.",
        "trim": tr,
        "constants": {"mass_kg": MASS, "inertia_kg_m2": [IX, IY, IZ, IXZ], "area_m2": S_REF, "span_m": SPAN,
                      "mac_m": CBAR, "engine_z_m": Z_ENGINE, "imu_m": R_IMU.tolist(), "boom_m": R_BOOM.tolist()},
        "atmosphere": {"isa_temperature_offset_k": DELTA_T},
        "turbulence": {"model": "Dryden u, v, w in body axes", "sigma_m_s": args.turb_ms, "scale_m": L_TURB},
        "noise_1sigma": NOISE, "biases": BIAS,
        "sim_hz": SIM_HZ, "log_hz": SIM_HZ / LOG_EVERY, "seed": args.seed, "records": records,
    }
    with open(os.path.join(args.out, "attas.truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")


if __name__ == "__main__":
    main()
