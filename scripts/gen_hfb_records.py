#!/usr/bin/env python3
"""Longitudinal flight-test records of an HFB-320-like business jet in turbulence, with known true parameters.

An independent test-data generator for `flightid derivatives --method oe|fem`: it does not import or call
flightid, only numpy and scipy. The aircraft, its aerodynamic model and the parameter values are those of the
DLR HFB-320 longitudinal test case in Jategaonkar, *Flight Vehicle System Identification* (2nd ed., test
case 4); the true values are the book's published filter-error estimates. The records are flown in Dryden
turbulence and written as a data system writes them (the book's column names, sensor noise, a logged thrust).

Files written to --out DIR:

  hfb_1.csv … hfb_N.csv   the records, header `T,DELV,PDYN,THRUST,TASCG,ALFCG,THE,Q,QDOT,AXCG,AZCG,AYCG,P,R,
                          PDOT,RDOT,BETCG,PHI,DAIL,DRUD`, all SI units and radians;
  hfb.columns.toml        the flightid column map of those columns (QDOT, PDOT, RDOT left unmapped);
  hfb_K.asc, hfb.asc.columns.toml   with --asc: the same records as the book's supplement writes them (no header,
                          spaces between the columns, exponent form) and the map naming their columns by position;
  hfb.airframe.toml       the flightid airframe description (mass, inertia, wing, thrust line, density);
  hfb.truth.json          the true coefficients, their equivalents in flightid's model convention, the trim,
                          the turbulence, the input timing and the seeds.

Model (SI units, radians; body axes x forward, z down; θ, α, q positive nose up)
-------------------------------------------------------------------------------

Constants: m = 7472 kg, S = 30.097 m², c̄ = 2.43 m, I_yy = 91389 kg m², ρ = 0.792 kg/m³, g = 9.80665 m/s²,
thrust line inclined σ_T = 0.0524 rad nose up against body x, pitching moment per newton of thrust
l_T = −0.6411 m (the thrust pitches the nose down), reference speed V₀ = 104.67 m/s.

States are inertial: the speed V over ground (still atmosphere at rest), the angle of attack α of that
velocity, the pitch attitude θ and the pitch rate q. The flight path angle is γ = θ − α, wings level.

The atmosphere moves with a gust velocity given by two components in the flight-path axes of the trim:
u_g along the flight path, positive forward (a tailwind gust), and w_g normal to it, positive upward (an
updraft). The air-relative speed and angle of attack are therefore

  V_air = √((V − u_g)² + w_g²) ≈ V − u_g,      α_air = α + atan2(w_g, V − u_g) ≈ α + w_g/V,

so a tailwind gust lowers the airspeed and an updraft raises the angle of attack. The aerodynamic
coefficients are those of the book, with the speed and pitch rate normalised by V₀:

  V̂ = V_air/V₀,   q̂ = q c̄/(2V₀),
  C_D = C_D0 + C_DV V̂ + C_Dα α_air,
  C_L = C_L0 + C_LV V̂ + C_Lα α_air,
  C_m = C_m0 + C_mV V̂ + C_mα α_air + C_mq q̂ + C_mδe δe,

with the dynamic pressure q̄ = ½ ρ V_air². Drag D = q̄ S C_D acts against the air-relative velocity and lift
L = q̄ S C_L normal to it, so in body axes, together with the thrust T,

  X = −D cos α_air + L sin α_air + T cos σ_T,      Z = −D sin α_air − L cos α_air − T sin σ_T.

The point-mass equations, with X and Z projected onto the inertial velocity (wind axes of α):

  V̇ = (X cos α + Z sin α)/m − g sin(θ − α)
  α̇ = (Z cos α − X sin α)/(m V) + q + g cos(θ − α)/V
  θ̇ = q
  q̇ = (q̄ S c̄ C_m + T l_T)/I_yy

In still air (α_air = α, V_air = V) the first two reduce to the book's wind-axis form
V̇ = −q̄S C_D/m + T cos(α + σ_T)/m − g sin(θ − α) and
α̇ = −q̄S C_L/(mV) − T sin(α + σ_T)/(mV) + q + g cos(θ − α)/V. The gust gradient's pitch rate is neglected.

Sensors see: the IMU, attitude and rate gyros the inertial θ, q, q̇ (q̇ from the model equation) and the
body-axis specific force at the CG, a_x = X/m, a_z = Z/m (level trim: a_z = −g cos θ ≈ −9.74 m/s²); the α vane
sees α_air (read --alpha-skew-s late, linearly interpolated, trim value before t = 0); the airspeed sensor
V_air; the dynamic pressure sensor ½ρV_air². Gaussian white sensor noise (1σ): V 0.1 m/s, α 0.002 rad,
θ 0.0005 rad, q 0.0005 rad/s, q̇ 0.005 rad/s², a_x, a_z 0.02 m/s², q̄ 5 Pa, thrust 20 N, elevator 0.0002 rad.
The lateral columns carry only noise about zero (AYCG 0.02 m/s², P and R 0.0005 rad/s, PDOT and RDOT
0.005 rad/s², BETCG 0.002 rad, PHI 0.0005 rad, DAIL and DRUD 0.0002 rad).

Turbulence (Dryden, MIL-F-8785C / Hoblit), frozen field flown through at the trim speed V_t = 106 m/s,
scale lengths L_u = L_w = 533 m (about 1750 ft), σ_u = σ_w = --turb-ms. Driven by unit-intensity white
noise η (E[η(t)η(t')] = δ(t − t')), the filters are

  u_g:  H_u(s) = σ_u √(2L_u/V_t) / (1 + (L_u/V_t) s)
  w_g:  H_w(s) = σ_w √(L_w/V_t) (1 + √3 (L_w/V_t) s) / (1 + (L_w/V_t) s)²

which have the Dryden spectra Φ_u(ω) = σ_u² (2L_u/(πV_t)) / (1 + (L_u ω/V_t)²) and
Φ_w(ω) = σ_w² (L_w/(πV_t)) (1 + 3(L_w ω/V_t)²) / (1 + (L_w ω/V_t)²)² (one-sided, ω ≥ 0) and the variances
σ_u², σ_w². Each filter is a linear state-space system integrated at the simulation rate by its exact
zero-order-hold discretisation (transition matrix and Van Loan's discrete noise covariance); its state
starts in the stationary distribution, so the record is stationary turbulence from t = 0.

Input and thrust: the aircraft starts in trim (level flight at V = 106 m/s, still air; α, δe, T solved with
scipy.optimize). The elevator flies a 3-2-1-1 (unit 1.5 s, amplitude 1.5°, positive first, i.e. trailing
edge down) from t = 2 s, then, 20 s after it ends, a single 2 s pulse of −1.5°, then holds trim to t = 60 s.
Each level change is a linear ramp of 0.1 s. Per record the pulse widths vary by ±5 % and the amplitudes by
±10 % (uniform, seeded), like a pilot's inputs. The engine thrust is the trim thrust times
(1 + a slow random walk, scaled so that its largest excursion is 2 % + 0.5 % white noise), defined at the log
times and linearly interpolated between them (as flightid interpolates its inputs); it starts at trim.

Integration: fixed-step RK4 at 200 Hz (elevator exact at every stage, gusts linearly interpolated between
their 200 Hz samples, thrust linearly between log samples); logged at --log-hz (default 10 Hz).

Randomness: record k of --seed S draws from numpy's SeedSequence([S, k]), split into independent streams
for the input jitter, the thrust, the turbulence and the sensor noise. So for one seed the records with
--turb-ms 0 and --turb-ms 1 differ only by the turbulence (same inputs, thrust history and sensor noise).

flightid's convention: its built-in longitudinal model uses V̂ = (V − V_ref)/V_ref with V_ref the mean
measured airspeed and q̂ = q c̄/(2V). The book's C_X0 + C_XV V/V₀ is C_X0 + C_XV (V_ref/V₀) + C_XV (V_ref/V₀) V̂,
so flightid's zero term is C_X0 + C_XV V_ref/V₀ and its speed derivative C_XV V_ref/V₀; its C_mq is
C_mq V/V₀ (≈ C_mq V_ref/V₀). hfb.truth.json gives the book values, "flightid_zero_terms" (V_ref = V₀:
C_X0 + C_XV) and "flightid_equivalent" at the mean logged airspeed of the records written.

Usage: gen_hfb_records.py --out DIR [--seed 1] [--records 2] [--turb-ms 1.0] [--alpha-skew-s 0] [--log-hz 10]
"""
import argparse
import json
import math
import os

import numpy as np
import scipy.optimize

from dryden import dryden_series

# ---------------------------------------------------------------- constants
MASS = 7472.0
S_REF = 30.097
CBAR = 2.43
SPAN = 14.49
IXX, IYY, IZZ, IXZ = 13336.0, 91389.0, 35959.0, 1144.2
SIGMA_T = 0.0524
L_T = -0.6411
RHO = 0.792
G = 9.80665
V0 = 104.67

V_TRIM = 106.0
SIM_HZ = 200.0
DURATION_S = 60.0
L_TURB = 533.0

TRUTH = {
    "CD_0": 0.122688,
    "CD_V": -0.0644969,
    "CD_alpha": 0.320055,
    "CL_0": -0.0929113,
    "CL_V": 0.148726,
    "CL_alpha": 4.32785,
    "Cm_0": 0.111905,
    "Cm_V": 0.00395154,
    "Cm_alpha": -0.967854,
    "Cm_q": -34.7098,
    "Cm_de": -1.52913,
}

# input
UNIT_S = 1.5
AMP_RAD = math.radians(1.5)
START_3211_S = 2.0
GAP_S = 20.0
PULSE_S = 2.0
RISE_S = 0.1

# sensor noise (1 sigma)
NOISE = {
    "DELV": 0.0002, "PDYN": 5.0, "THRUST": 20.0, "TASCG": 0.1, "ALFCG": 0.002, "THE": 0.0005,
    "Q": 0.0005, "QDOT": 0.005, "AXCG": 0.02, "AZCG": 0.02,
    "AYCG": 0.02, "P": 0.0005, "R": 0.0005, "PDOT": 0.005, "RDOT": 0.005,
    "BETCG": 0.002, "PHI": 0.0005, "DAIL": 0.0002, "DRUD": 0.0002,
}
COLUMNS = ["T", "DELV", "PDYN", "THRUST", "TASCG", "ALFCG", "THE", "Q", "QDOT", "AXCG", "AZCG", "AYCG",
           "P", "R", "PDOT", "RDOT", "BETCG", "PHI", "DAIL", "DRUD"]
COLUMN_MAP = {
    "T": ("time_s", "s"), "DELV": ("elevator_rad", "rad"), "PDYN": ("qbar_pa", "Pa"),
    "THRUST": ("thrust_n", "N"), "TASCG": ("airspeed_m_s", "m/s"), "ALFCG": ("alpha_rad", "rad"),
    "THE": ("theta_rad", "rad"), "Q": ("q_rad_s", "rad/s"), "AXCG": ("ax_m_s2", "m/s2"),
    "AZCG": ("az_m_s2", "m/s2"), "AYCG": ("ay_m_s2", "m/s2"), "P": ("p_rad_s", "rad/s"),
    "R": ("r_rad_s", "rad/s"), "BETCG": ("beta_rad", "rad"), "PHI": ("phi_rad", "rad"),
    "DAIL": ("aileron_rad", "rad"), "DRUD": ("rudder_rad", "rad"),
}

P = TRUTH  # shorthand
COS_ST, SIN_ST = math.cos(SIGMA_T), math.sin(SIGMA_T)


# ---------------------------------------------------------------- model
def forces(V, alpha, q, de, T, ug, wg):
    """Body-axis force (X, Z), pitching moment M, dynamic pressure, V_air, α_air. Scalars or arrays."""
    vx = V - ug
    v_air = np.hypot(vx, wg)
    a_air = alpha + np.arctan2(wg, vx)
    qbar = 0.5 * RHO * v_air * v_air
    vhat = v_air / V0
    qhat = q * CBAR / (2.0 * V0)
    cd = P["CD_0"] + P["CD_V"] * vhat + P["CD_alpha"] * a_air
    cl = P["CL_0"] + P["CL_V"] * vhat + P["CL_alpha"] * a_air
    cm = P["Cm_0"] + P["Cm_V"] * vhat + P["Cm_alpha"] * a_air + P["Cm_q"] * qhat + P["Cm_de"] * de
    drag = qbar * S_REF * cd
    lift = qbar * S_REF * cl
    ca, sa = np.cos(a_air), np.sin(a_air)
    X = -drag * ca + lift * sa + T * math.cos(SIGMA_T)
    Z = -drag * sa - lift * ca - T * math.sin(SIGMA_T)
    M = qbar * S_REF * CBAR * cm + T * L_T
    return X, Z, M, qbar, v_air, a_air


def derivs(x, de, T, ug, wg):
    """State derivative of x = [V, α, θ, q] (module doc)."""
    V, alpha, theta, q = x
    X, Z, M, _, _, _ = forces(V, alpha, q, de, T, ug, wg)
    ca, sa = np.cos(alpha), np.sin(alpha)
    gam = theta - alpha
    vdot = (X * ca + Z * sa) / MASS - G * np.sin(gam)
    adot = (Z * ca - X * sa) / (MASS * V) + q + G * np.cos(gam) / V
    return np.array([vdot, adot, q, M / IYY])


def derivs_scalar(V, alpha, theta, q, de, T, ug, wg):
    """Same as derivs, plain floats (the integration loop)."""
    vx = V - ug
    v_air = math.hypot(vx, wg)
    a_air = alpha + math.atan2(wg, vx)
    qs = 0.5 * RHO * v_air * v_air * S_REF
    vhat = v_air / V0
    cd = P["CD_0"] + P["CD_V"] * vhat + P["CD_alpha"] * a_air
    cl = P["CL_0"] + P["CL_V"] * vhat + P["CL_alpha"] * a_air
    cm = (P["Cm_0"] + P["Cm_V"] * vhat + P["Cm_alpha"] * a_air + P["Cm_q"] * q * CBAR / (2.0 * V0)
          + P["Cm_de"] * de)
    ca, sa = math.cos(a_air), math.sin(a_air)
    X = -qs * cd * ca + qs * cl * sa + T * COS_ST
    Z = -qs * cd * sa - qs * cl * ca - T * SIN_ST
    cb, sb = math.cos(alpha), math.sin(alpha)
    gam = theta - alpha
    return ((X * cb + Z * sb) / MASS - G * math.sin(gam),
            (Z * cb - X * sb) / (MASS * V) + q + G * math.cos(gam) / V,
            q,
            (qs * CBAR * cm + T * L_T) / IYY)


def trim():
    """Level flight at V_TRIM in still air: α, δe, T with V̇ = α̇ = q̇ = 0 (θ = α, q = 0)."""
    def res(z):
        a, de, T = z
        d = derivs(np.array([V_TRIM, a, a, 0.0]), de, T * 1e4, 0.0, 0.0)
        return [d[0], d[1] * V_TRIM, d[3]]
    sol = scipy.optimize.least_squares(res, [0.1, -0.02, 1.2], xtol=1e-15, ftol=1e-15, gtol=1e-15,
                                       x_scale=[0.1, 0.01, 1.0])
    a, de, t4 = sol.x
    T = t4 * 1e4
    d = derivs(np.array([V_TRIM, a, a, 0.0]), de, T, 0.0, 0.0)
    return {"airspeed_m_s": V_TRIM, "alpha_rad": a, "theta_rad": a, "elevator_rad": de, "thrust_n": T,
            "residual_vdot_m_s2": float(d[0]), "residual_alphadot_rad_s": float(d[1]),
            "residual_qdot_rad_s2": float(d[3])}


def modes_at_trim(tr):
    """Eigenvalues of the still-air model's Jacobian at the trim (central differences)."""
    x0 = np.array([tr["airspeed_m_s"], tr["alpha_rad"], tr["theta_rad"], 0.0])
    A = np.zeros((4, 4))
    for j, h in enumerate([1e-3, 1e-6, 1e-6, 1e-6]):
        dx = np.zeros(4)
        dx[j] = h
        A[:, j] = (derivs(x0 + dx, tr["elevator_rad"], tr["thrust_n"], 0, 0)
                   - derivs(x0 - dx, tr["elevator_rad"], tr["thrust_n"], 0, 0)) / (2 * h)
    ev = np.linalg.eigvals(A)
    out = {}
    for lam in ev[ev.imag > 0]:
        wn = abs(lam)
        key = "short_period" if wn > 1.0 else "phugoid"
        out[key] = {"omega_n_rad_s": float(wn), "zeta": float(-lam.real / wn)}
    if len(out) < 2:
        out["eigenvalues"] = [[float(l.real), float(l.imag)] for l in ev]
    return out


# ---------------------------------------------------------------- turbulence
def dryden(sigma, n, dt, rng):
    """u_g and w_g (m/s) on n samples dt apart (module doc); zeros when sigma == 0 (draws made anyway)."""
    u, w = dryden_series(("u", "w"), sigma, L_TURB / V_TRIM, n, dt, rng)
    return u, w


# ---------------------------------------------------------------- inputs
def elevator_schedule(rng):
    """(times, increments) of the level changes of the elevator deflection from trim."""
    widths = UNIT_S * np.array([3.0, 2.0, 1.0, 1.0]) * rng.uniform(0.95, 1.05, 4)
    amps = AMP_RAD * np.array([1.0, -1.0, 1.0, -1.0]) * rng.uniform(0.9, 1.1, 4)
    pulse_w = PULSE_S * rng.uniform(0.95, 1.05)
    pulse_a = -AMP_RAD * rng.uniform(0.9, 1.1)
    starts = START_3211_S + np.concatenate([[0.0], np.cumsum(widths)])   # four starts and the end
    t_end = starts[-1]
    times = list(starts) + [t_end + GAP_S, t_end + GAP_S + pulse_w]
    levels = list(amps) + [0.0, pulse_a, 0.0]
    incr = np.diff(np.concatenate([[0.0], levels]))
    info = {"3211_start_s": START_3211_S, "3211_widths_s": widths.tolist(), "3211_amplitudes_rad": amps.tolist(),
            "3211_end_s": t_end, "pulse_start_s": t_end + GAP_S, "pulse_width_s": pulse_w,
            "pulse_amplitude_rad": pulse_a, "rise_time_s": RISE_S}
    return np.array(times), incr, info


def elevator(t, sched, de_trim):
    times, incr = sched
    r = np.clip((np.asarray(t)[..., None] - times) / RISE_S, 0.0, 1.0)
    return de_trim + (r * incr).sum(axis=-1)


def thrust_history(t_log, t_trim, rng):
    n = len(t_log)
    walk = np.cumsum(rng.standard_normal(n))
    walk -= walk[0]
    peak = np.max(np.abs(walk))
    walk = 0.02 * walk / peak if peak > 0 else walk
    white = 0.005 * rng.standard_normal(n)
    white[0] = 0.0
    return t_trim * (1.0 + walk + white)


# ---------------------------------------------------------------- one record
def simulate(seed, record, tr, args):
    ss = np.random.SeedSequence([seed, record])
    r_input, r_thrust, r_turb, r_noise = (np.random.default_rng(s) for s in ss.spawn(4))
    dt = 1.0 / SIM_HZ
    n = int(round(DURATION_S * SIM_HZ)) + 1
    t_sim = np.arange(n) * dt
    n_log = int(round(DURATION_S * args.log_hz)) + 1
    t_log = np.arange(n_log) / args.log_hz

    times, incr, input_info = elevator_schedule(r_input)
    sched = (times, incr)
    thrust_log = thrust_history(t_log, tr["thrust_n"], r_thrust)
    ug, wg = dryden(args.turb_ms, n, dt, r_turb)

    de_sim = elevator(t_sim, sched, tr["elevator_rad"])
    de_mid = elevator(t_sim[:-1] + 0.5 * dt, sched, tr["elevator_rad"])
    T_sim = np.interp(t_sim, t_log, thrust_log)
    T_mid = np.interp(t_sim[:-1] + 0.5 * dt, t_log, thrust_log)
    ug_mid = 0.5 * (ug[:-1] + ug[1:])
    wg_mid = 0.5 * (wg[:-1] + wg[1:])

    X = np.empty((n, 4))
    x = [tr["airspeed_m_s"], tr["alpha_rad"], tr["theta_rad"], 0.0]
    X[0] = x
    for i in range(n - 1):
        V, a, th, q = x
        k1 = derivs_scalar(V, a, th, q, de_sim[i], T_sim[i], ug[i], wg[i])
        h = 0.5 * dt
        k2 = derivs_scalar(V + h * k1[0], a + h * k1[1], th + h * k1[2], q + h * k1[3],
                           de_mid[i], T_mid[i], ug_mid[i], wg_mid[i])
        k3 = derivs_scalar(V + h * k2[0], a + h * k2[1], th + h * k2[2], q + h * k2[3],
                           de_mid[i], T_mid[i], ug_mid[i], wg_mid[i])
        k4 = derivs_scalar(V + dt * k3[0], a + dt * k3[1], th + dt * k3[2], q + dt * k3[3],
                           de_sim[i + 1], T_sim[i + 1], ug[i + 1], wg[i + 1])
        x = [x[j] + dt / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]) for j in range(4)]
        X[i + 1] = x

    V, a, th, q = X.T
    Fx, Fz, M, qbar, v_air, a_air = forces(V, a, q, de_sim, T_sim, ug, wg)
    qdot = M / IYY

    def at_log(y):
        return np.interp(t_log, t_sim, y)

    alpha_vane = np.interp(t_log - args.alpha_skew_s, t_sim, a_air, left=a_air[0])
    true = {
        "DELV": elevator(t_log, sched, tr["elevator_rad"]), "PDYN": at_log(qbar), "THRUST": thrust_log,
        "TASCG": at_log(v_air), "ALFCG": alpha_vane, "THE": at_log(th), "Q": at_log(q), "QDOT": at_log(qdot),
        "AXCG": at_log(Fx / MASS), "AZCG": at_log(Fz / MASS),
    }
    cols = {"T": t_log}
    for c in COLUMNS[1:]:
        clean = true.get(c, np.zeros(n_log))
        cols[c] = clean + NOISE[c] * r_noise.standard_normal(n_log)
    diag = {
        "alpha_inertial_log": at_log(a), "alpha_air_log": at_log(a_air), "ug": ug, "wg": wg,
        "alpha_p2p_rad": float(np.ptp(a_air)), "alpha_inertial_p2p_rad": float(np.ptp(a)),
        "rms_alpha_air_minus_alpha_rad": float(np.sqrt(np.mean((a_air - a) ** 2))),
        "mean_airspeed_logged_m_s": float(np.mean(cols["TASCG"])),
        "az_first_s_mean": float(np.mean(true["AZCG"][t_log < START_3211_S])),
        "ax_first_s_mean": float(np.mean(true["AXCG"][t_log < START_3211_S])),
        "sigma_ug_m_s": float(np.std(ug)), "sigma_wg_m_s": float(np.std(wg)),
    }
    return cols, input_info, diag


# ---------------------------------------------------------------- writers
def write_csv(path, cols):
    data = np.column_stack([cols[c] for c in COLUMNS])
    fmt = ["%.4f"] + ["%.9g"] * (len(COLUMNS) - 1)
    np.savetxt(path, data, delimiter=",", header=",".join(COLUMNS), comments="", fmt=fmt)


def write_asc(path, cols):
    """The record as the book's supplement writes its flight data: no header, the same columns in the same
    order, numbers in exponent form separated by runs of spaces."""
    data = np.column_stack([cols[c] for c in COLUMNS])
    np.savetxt(path, data, delimiter="", fmt="%16.7e")


def write_columns(path, by_position=False):
    lines = ["# Column map of the HFB-320-like records (scripts/gen_hfb_records.py) onto the flight-data schema.",
             "# QDOT, PDOT, RDOT have no schema column and are left unmapped (kept as they are).", "[columns]"]
    if by_position:
        lines.insert(1, "# The .asc files have no header row: their columns are named by position (1 = T, 2 = DELV, …).")
    for col, (to, unit) in COLUMN_MAP.items():
        key = COLUMNS.index(col) + 1 if by_position else col
        lines.append(f'{key} = {{ to = "{to}", unit = "{unit}" }}')
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def write_airframe(path):
    text = f"""# Airframe description of the DLR HFB-320 (Jategaonkar, test case 4); scripts/gen_hfb_records.py
name = "hfb320"
mass_kg = {MASS}
inertia_kg_m2 = {{ ixx = {IXX}, iyy = {IYY}, izz = {IZZ}, ixz = {IXZ} }}
wing = {{ area_m2 = {S_REF}, span_m = {SPAN}, mac_m = {CBAR} }}

[thrust]
inclination_rad = {SIGMA_T}
moment_arm_m = {L_T}

[flight]
density_kg_m3 = {RHO}
"""
    with open(path, "w") as fh:
        fh.write(text)


def equivalent(v_ref):
    """The true model in flightid's convention (module doc) at reference speed v_ref."""
    k = v_ref / V0
    out = {"reference_airspeed_m_s": v_ref}
    for c in ("CD", "CL", "Cm"):
        out[f"{c}_0"] = P[f"{c}_0"] + P[f"{c}_V"] * k
        out[f"{c}_V"] = P[f"{c}_V"] * k
    out.update({"CD_alpha": P["CD_alpha"], "CL_alpha": P["CL_alpha"], "Cm_alpha": P["Cm_alpha"],
                "Cm_de": P["Cm_de"], "Cm_q": P["Cm_q"] * k, "CL_q": 0.0, "CL_de": 0.0, "CD_de": 0.0,
                "CL_alphadot": 0.0, "Cm_alphadot": 0.0})
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--records", type=int, default=2)
    ap.add_argument("--turb-ms", type=float, default=1.0, help="σ_u = σ_w of the Dryden gusts, m/s (0: still air)")
    ap.add_argument("--alpha-skew-s", type=float, default=0.0, help="the α vane reads this many seconds late")
    ap.add_argument("--log-hz", type=float, default=10.0)
    ap.add_argument("--verbose", action="store_true", help="print per-record diagnostics")
    ap.add_argument("--asc", action="store_true",
                    help="also write each record as the book's text file (hfb_K.asc: no header, spaces between the "
                         "columns, exponent form) with its map by column position (hfb.asc.columns.toml)")
    args = ap.parse_args()
    if args.records < 1 or args.log_hz <= 0 or args.log_hz > SIM_HZ or args.turb_ms < 0:
        ap.error("need --records >= 1, 0 < --log-hz <= 200, --turb-ms >= 0")
    os.makedirs(args.out, exist_ok=True)

    tr = trim()
    records, mean_v = [], []
    for k in range(1, args.records + 1):
        cols, info, diag = simulate(args.seed, k, tr, args)
        name = f"hfb_{k}.csv"
        write_csv(os.path.join(args.out, name), cols)
        if args.asc:
            write_asc(os.path.join(args.out, f"hfb_{k}.asc"), cols)
        mean_v.append(diag["mean_airspeed_logged_m_s"])
        records.append({"file": name, "seed_sequence": [args.seed, k], "input": info,
                        "mean_airspeed_logged_m_s": diag["mean_airspeed_logged_m_s"],
                        "alpha_air_peak_to_peak_rad": diag["alpha_p2p_rad"],
                        "rms_alpha_air_minus_alpha_rad": diag["rms_alpha_air_minus_alpha_rad"],
                        "sigma_ug_m_s": diag["sigma_ug_m_s"], "sigma_wg_m_s": diag["sigma_wg_m_s"]})
        if args.verbose:
            print(f"{name}: alpha_air p2p {math.degrees(diag['alpha_p2p_rad']):.3f} deg "
                  f"(inertial {math.degrees(diag['alpha_inertial_p2p_rad']):.3f}), "
                  f"rms(alpha_air-alpha) {diag['rms_alpha_air_minus_alpha_rad']:.5f} rad, "
                  f"sigma ug {diag['sigma_ug_m_s']:.3f} wg {diag['sigma_wg_m_s']:.3f} m/s, "
                  f"az(t<2s) {diag['az_first_s_mean']:.4f} ax(t<2s) {diag['ax_first_s_mean']:.4f} m/s2, "
                  f"mean V {diag['mean_airspeed_logged_m_s']:.3f}")

    write_columns(os.path.join(args.out, "hfb.columns.toml"))
    if args.asc:
        write_columns(os.path.join(args.out, "hfb.asc.columns.toml"), by_position=True)
    write_airframe(os.path.join(args.out, "hfb.airframe.toml"))
    truth = {
        "source": "Jategaonkar, Flight Vehicle System Identification, 2nd ed., test case 4 (HFB-320 longitudinal), "
                  "published filter-error estimates; generated by scripts/gen_hfb_records.py",
        "convention": "book: Vhat = V_air/V0, qhat = q cbar/(2 V0), V0 = 104.67 m/s; alpha = alpha_air",
        **dict(TRUTH),
        "flightid_zero_terms": {"note": "flightid's Vhat = (V - V_ref)/V_ref: zero terms for V_ref = V0",
                                "CD_0": P["CD_0"] + P["CD_V"], "CL_0": P["CL_0"] + P["CL_V"],
                                "Cm_0": P["Cm_0"] + P["Cm_V"]},
        "flightid_equivalent": {**equivalent(float(np.mean(mean_v))),
                                "note": "the true model in flightid's convention at V_ref = mean logged airspeed "
                                        "of these records (flightid's reference); Cm_q scaled by V_ref/V0 "
                                        "(flightid's qhat uses V)"},
        "constants": {"mass_kg": MASS, "area_m2": S_REF, "mac_m": CBAR, "span_m": SPAN, "iyy_kg_m2": IYY,
                      "thrust_inclination_rad": SIGMA_T, "thrust_moment_arm_m": L_T, "density_kg_m3": RHO,
                      "g_m_s2": G, "v0_m_s": V0},
        "trim": tr,
        "modes_at_trim": modes_at_trim(tr),
        "turbulence": {"model": "Dryden (MIL-F-8785C), u_g and w_g", "sigma_u_m_s": args.turb_ms,
                       "sigma_w_m_s": args.turb_ms, "scale_length_m": L_TURB, "frozen_at_m_s": V_TRIM},
        "alpha_skew_s": args.alpha_skew_s,
        "sim_hz": SIM_HZ, "log_hz": args.log_hz, "duration_s": DURATION_S,
        "sensor_noise_1sigma": NOISE,
        "seed": args.seed,
        "records": records,
    }
    with open(os.path.join(args.out, "hfb.truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")


if __name__ == "__main__":
    main()
