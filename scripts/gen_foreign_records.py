#!/usr/bin/env python3
"""Flight-test records of JSBSim aircraft, written as a real data logger would write them.

An independent generator: it drives JSBSim through its own Python API (not flightid's bridge), flies elevator
3-2-1-1s and doublets and aileron/rudder doublets, and writes for each aircraft:

  NAME_lon1.csv, NAME_lon2.csv, NAME_lat1.csv, NAME_lat2.csv   the records (foreign column names and units:
        deg, deg/s, ft, kts, g, psf, lbf), logged at --log-hz from a --sim-hz simulation, with sensor noise,
        biases, an IMU and an α/β vane away from the CG, a time skew on the vanes, and light Dryden turbulence
        (its own realisation per --seed);
  NAME.airframe.toml     mass, inertia, geometry, thrust line and sensor positions (the airframe description);
  NAME.columns.toml      the column map onto the flight-data schema;
  NAME.truth.json        JSBSim's own derivatives about the CG at the trim the records start from
        (`derivatives`), and the α and β derivatives over the range the records fly (`derivatives_over_records`).

Truth: each aero input (α, β, p, q, r and the three surfaces) is perturbed by ±h about the trimmed state through
run_ic (integration suspended, engines keep their state), and the aero coefficients are differenced: forces in
wind axes (C_L, C_D), the side force in body axes (C_Y, as flightid's a_y = q̄S C_Y/m reads it: the wind-axis
C_Yβ differs from it by the drag, 3 % on the 737), moments in body axes about the CG (JSBSim's moments/*-aero-lbsft). run_ic leaves the
α̇ that the unbalanced state implies; the α̇ coefficient functions (names containing `adot`) are subtracted, their
lift moved from the aero reference point to the CG (as scripts/oracle_aero.py does for the c172x). The α̇
derivatives themselves are those functions' values divided by α̇ c̄/(2V).

A local derivative is the slope of a table at the trim, and a piecewise-linear table (the p51d's C_L(α): 6.67
per rad between 1.5° and 2°, 6.1 between 1° and 1.5°) changes slope within the few degrees a maneuver flies.
A linear model fitted to the records can only find the slope over the range flown, so the truth also holds
the α and β derivatives as the least-squares slope of the coefficient over quantiles of the α (β) the
longitudinal (lateral) records flew, every other state at the trim (`derivatives_over_records`).

Private copy: the aircraft directory is copied to a temporary root (engine/ and systems/ linked); top-level
<input> and <output> elements are removed (no listeners, no files), and the aero model reads each surface as
the FCS output plus a declared offset property (`gen/elevator-offset-rad`, …) that the generator drives through
its own first-order actuator. JSBSim's simple trim cannot trim constant-speed propellers (it finds udot not
trimmable), so the trim is flown: airspeed, altitude, wings-level and yaw-damping loops settle the aircraft for
--settle-s seconds, then hold their commands constant. Where that leaves no trim (over the settle's last 5 s a
body acceleration above 0.3 m/s² or a flight path off level by 0.5°: the 737, whose phugoid the loops excite),
JSBSim's own full trim is taken instead.

Integration (`--integrator`): JSBSim's default integrates the body rates and attitude by rectangular Euler,
whose lag of about one step acts like a delay on every moment: the aircraft flown at 200 Hz has the damping
C_nr + C_nβ·h·2V/b, not C_nr (737: −0.336 for −0.350; C_lr 8 % low, C_mq shifted by C_mα·h·2V/c̄). `ab2` takes
Adams–Bashforth 2 there instead (the translational states already use AB2/AB3), and noise-free 737 records
at 200 Hz then carry C_nr and C_lr within 0.5 % (as Euler at 1000 Hz nearly does). The default stays JSBSim's,
since that is what other JSBSim scripts fly.

Usage: gen_foreign_records.py --aircraft p51d --out DIR [--seed 1] [--sim-hz 200] [--log-hz 50]
                              [--altitude-ft 6000] [--speed-kts 200] [--turbulence light|none]
                              [--integrator euler|ab2] [--sensors logger|ideal]
"""
import argparse
import contextlib
import json
import math
import os
import re
import shutil
import sys
import tempfile

import numpy as np
import jsbsim

FT = 0.3048
LBF = 4.4482216152605
SLUG = 14.593902937
KT = 1852.0 / 3600.0
G0 = 9.80665
PSF = LBF / FT**2

SURFACES = ("elevator", "aileron", "rudder")
# Each surface and the suffix of its derivatives (Cm_de, Cl_da, Cn_dr, …).
SURFACE_KEYS = (("elevator", "de"), ("aileron", "da"), ("rudder", "dr"))
# What each surface's aero functions read, in order of preference.
SURFACE_READS = {
    "elevator": ["fcs/elevator-pos-rad"],
    "aileron": ["fcs/effective-aileron-pos", "fcs/left-aileron-pos-rad", "fcs/aileron-pos-rad"],
    "rudder": ["fcs/rudder-pos-rad"],
}
# Trim altitude (ft) and true airspeed (kts) per aircraft; others fly at 6000 ft and the speed of a cruise
# lift coefficient (Aircraft.cruise_speed_kts) unless told.
DEFAULTS = {"p51d": (6000.0, 200.0), "c310": (5000.0, 150.0), "pa28": (4000.0, 110.0), "737": (15000.0, 280.0),
            "pc7": (6000.0, 180.0)}


@contextlib.contextmanager
def quiet():
    """JSBSim prints to the C stdout; keep it off ours."""
    fd = sys.stdout.fileno()
    saved = os.dup(fd)
    with open(os.devnull, "w") as dn:
        os.dup2(dn.fileno(), fd)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, fd)
            os.close(saved)


def strip_io(text):
    """Remove top-level <input ...> and <output ...> elements (they carry attributes; FCS ones do not)."""
    for tag in ("input", "output"):
        text = re.sub(rf"<{tag}\s[^>]*/>", "", text)
        text = re.sub(rf"<{tag}\s[^>]*>.*?</{tag}>", "", text, flags=re.S)
    return text


def private_copy(name, workdir):
    pkg = os.path.dirname(jsbsim.__file__)
    root = os.path.join(workdir, "root")
    os.makedirs(os.path.join(root, "aircraft"))
    for sub in ("engine", "systems"):
        os.symlink(os.path.join(pkg, sub), os.path.join(root, sub))
    dst = os.path.join(root, "aircraft", name)
    shutil.copytree(os.path.join(pkg, "aircraft", name), dst)
    # The p51d's manifold-pressure autothrottle reads FlightGear's /engines/engine/mp-inhg, which nothing
    # feeds outside FlightGear (it stays 0 and the throttle opens fully): read JSBSim's own instead.
    fix = os.path.join(dst, "Systems", "autothrottle.xml")
    if os.path.isfile(fix):
        t = open(fix).read().replace("/engines/engine/mp-inhg", "propulsion/engine/map-inhg")
        open(fix, "w").write(t)
    path = os.path.join(dst, f"{name}.xml")
    text = strip_io(open(path).read())
    a0, a1 = text.index("<aerodynamics>"), text.index("</aerodynamics>")
    aero = text[a0:a1]
    declared = []
    reads = {}
    totals = []
    for surface in SURFACES:
        offset = f"gen/{surface}-offset-rad"
        for prop in SURFACE_READS[surface]:
            pat = re.compile(rf"<(property|p)>\s*{re.escape(prop)}\s*</\1>")
            # A table lookup names its variable in <independentVar>, which takes a property and not a
            # function: such reads go through a pre-function of the aerodynamics (evaluated before the
            # coefficients) that sums the deflection and the offset.
            lookup = re.compile(rf"(<independentVar[^>]*>)\s*{re.escape(prop)}\s*(</independentVar>)")
            if not pat.search(aero) and not lookup.search(aero):
                continue
            summed = f"<sum><property>{prop}</property><property>{offset}</property></sum>"
            aero = pat.sub(summed, aero)
            total = f"gen/{surface}-total-rad"
            aero = lookup.sub(rf"\g<1>{total}\g<2>", aero)
            totals.append(f'<function name="{total}">{summed}</function>')
            mag = prop.replace("fcs/", "fcs/mag-")
            aero = re.sub(rf"<(property|p)>\s*{re.escape(mag)}\s*</\1>", f"<abs>{summed}</abs>", aero)
            mag_lookup = re.compile(rf"(<independentVar[^>]*>)\s*{re.escape(mag)}\s*(</independentVar>)")
            if mag_lookup.search(aero):
                aero = mag_lookup.sub(rf"\g<1>gen/mag-{surface}-total-rad\g<2>", aero)
                totals.append(f'<function name="gen/mag-{surface}-total-rad"><abs>{summed}</abs></function>')
            reads[surface] = prop
            declared.append(f'<property value="0">{offset}</property>')
            break
        if surface not in reads:
            sys.exit(f"{name}: the aero model reads none of {SURFACE_READS[surface]}")
    aero = aero.replace("<aerodynamics>", "<aerodynamics>\n" + "\n".join(declared + totals), 1)
    open(path, "w").write(text[:a0] + aero + text[a1:])
    adot = re.findall(r'<axis name="(\w+)">(.*?)</axis>', aero, flags=re.S)
    adot_functions = [(axis, f) for axis, body in adot
                      for f in re.findall(r'<function name="([^"]*adot[^"]*)"', body, flags=re.I)]
    return root, reads, adot_functions


class Aircraft:
    def __init__(self, name, sim_hz, workdir, integrator="euler"):
        self.name = name
        self.root, self.reads, self.adot_functions = private_copy(name, workdir)
        with quiet():
            fdm = jsbsim.FGFDMExec(self.root)
            fdm.set_debug_level(0)
            fdm.set_output_path(os.path.join(workdir, "out"))
            fdm.set_dt(1.0 / sim_hz)
            fdm.load_model(name)
            if integrator == "ab2":  # body rates and attitude (see the module doc)
                fdm["simulation/integrator/rate/rotational"] = 3
                fdm["simulation/integrator/position/rotational"] = 3
            fdm.disable_output()
        self.fdm = fdm
        self.dt = 1.0 / sim_hz
        self.flown = {}

    def __getitem__(self, k):
        return self.fdm[k]

    def __setitem__(self, k, v):
        self.fdm[k] = v

    def start(self, altitude_ft, speed_kts):
        f = self.fdm
        f["ic/h-sl-ft"] = altitude_ft
        f["ic/vt-kts"] = speed_kts
        f["ic/psi-true-deg"] = 0.0
        f["ic/gamma-deg"] = 0.0
        for e in range(4):
            for prop, v in (("fcs/mixture-cmd-norm", 1.0), ("fcs/advance-cmd-norm", 1.0),
                            ("fcs/throttle-cmd-norm", 0.7)):
                with contextlib.suppress(Exception):
                    f[f"{prop}[{e}]"] = v
        # Models flown in FlightGear (the fokker50, the p51d's autothrottle) read the throttle levers from
        # FlightGear's /controls tree, which nothing creates outside it: create it before the FCS first runs.
        self.set_throttle(0.7)
        f["propulsion/magneto_cmd"] = 3
        f["propulsion/starter_cmd"] = 1
        with quiet():
            f.run_ic()
        f["propulsion/set-running"] = -1
        f["gear/gear-cmd-norm"] = 0.0
        f["gear/gear-pos-norm"] = 0.0
        self.h0_ft, self.v0_kts = altitude_ft, speed_kts

    def cruise_speed_kts(self, lift_coefficient=0.4):
        """The true airspeed at which the loaded aircraft (after start()) flies level at the lift coefficient
        given, at the initial altitude: V = sqrt(2 W / (ρ S C_L)). A speed for models without a default (a fixed
        180 kts would be past the never-exceed speed of a c182 or a J3 Cub)."""
        f = self.fdm
        v_fps = math.sqrt(2.0 * f["inertia/weight-lbs"]
                          / (f["atmosphere/rho-slugs_ft3"] * f["metrics/Sw-sqft"] * lift_coefficient))
        return v_fps * FT / KT

    def set_throttle(self, v):
        for e in range(4):
            with contextlib.suppress(Exception):
                self.fdm[f"fcs/throttle-cmd-norm[{e}]"] = v
            # FlightGear's throttle levers, which some models' FCS copy onto throttle-cmd-norm
            with contextlib.suppress(Exception):
                self.fdm[f"/controls/engines/engine[{e}]/throttle"] = v

    def settle(self, seconds):
        """Fly the trim: PI loops on airspeed (throttle), flight path (pitch trim) and bank (aileron trim),
        yaw damping on the rudder; afterwards the trims stay where the loops left them."""
        f = self.fdm
        ith, igam, iphi = 0.0, 0.0, 0.0
        worst = (0.0, 0.0)
        n = int(seconds / self.dt)
        for k in range(n):
            gain = min(1.0, k / (2.0 / self.dt))
            ev = (self.v0_kts - f["velocities/vt-fps"] * FT / KT) / self.v0_kts
            ith += ev * self.dt
            self.set_throttle(float(np.clip(0.6 + 3.0 * ev + 0.8 * ith, 0.02, 1.0)))
            gamma = f["flight-path/gamma-rad"]
            gcmd = float(np.clip(0.0004 * (self.h0_ft - f["position/h-sl-ft"]), -0.05, 0.05))
            eg = gcmd - gamma
            igam += eg * self.dt
            pitch = -gain * (1.5 * eg + 0.6 * igam) + 0.3 * f["velocities/q-rad_sec"]
            f["fcs/pitch-trim-cmd-norm"] = float(np.clip(pitch, -1, 1))
            phi = f["attitude/phi-rad"]
            iphi += phi * self.dt
            roll = -1.0 * phi - 0.3 * iphi - 0.3 * f["velocities/p-rad_sec"]
            f["fcs/roll-trim-cmd-norm"] = float(np.clip(roll, -1, 1))
            f["fcs/yaw-trim-cmd-norm"] = float(np.clip(0.5 * f["velocities/r-rad_sec"], -1, 1))
            f.run()
            if k >= n - int(5.0 / self.dt):
                acc = max(abs(f["accelerations/udot-ft_sec2"]), abs(f["accelerations/wdot-ft_sec2"])) * FT
                worst = (max(worst[0], acc), max(worst[1], abs(gamma)))
        self.settle_worst = worst

    def steady(self):
        """Whether the settle ended in a trim: over its last 5 s the body accelerations stayed below 0.3 m/s²
        and the flight path within 0.5° of level (read as flown: nothing here touches the simulation)."""
        acc, gamma = self.settle_worst
        return acc < 0.3 and gamma < math.radians(0.5)

    def trim_jsbsim(self):
        """JSBSim's own full trim at the start point, the settle's trims cleared (a jet's trim: a long-period
        aircraft such as the 737 is not settled by the flown loops within the settle time)."""
        f = self.fdm
        for k in ("fcs/pitch-trim-cmd-norm", "fcs/roll-trim-cmd-norm", "fcs/yaw-trim-cmd-norm",
                  "fcs/elevator-cmd-norm", "fcs/aileron-cmd-norm", "fcs/rudder-cmd-norm"):
            f[k] = 0.0
        f["ic/h-sl-ft"] = self.h0_ft
        f["ic/vt-kts"] = self.v0_kts
        for k in ("ic/gamma-deg", "ic/phi-deg", "ic/beta-deg", "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec"):
            f[k] = 0.0
        with quiet():
            f.run_ic()
            try:
                f["simulation/do_simple_trim"] = 1
            except Exception as e:  # JSBSim raises TrimFailureError
                sys.exit(f"{self.name}: neither the flown settle nor JSBSim's trim reached a trim at "
                         f"{self.h0_ft:g} ft, {self.v0_kts:g} kts ({e})")

    def pilot(self):
        """A light wings leveller (a pilot holding the wings level between inputs) on the aileron command."""
        f = self.fdm
        f["fcs/aileron-cmd-norm"] = float(np.clip(-0.4 * f["attitude/phi-rad"] - 0.1 * f["velocities/p-rad_sec"], -0.3, 0.3))

    def state(self):
        f = self.fdm
        return {"ic/h-sl-ft": f["position/h-sl-ft"], "ic/vt-fps": f["velocities/vt-fps"],
                "ic/alpha-rad": f["aero/alpha-rad"], "ic/beta-rad": f["aero/beta-rad"],
                "ic/theta-rad": f["attitude/theta-rad"], "ic/phi-rad": f["attitude/phi-rad"],
                "ic/psi-true-rad": f["attitude/psi-rad"],
                "ic/p-rad_sec": 0.0, "ic/q-rad_sec": 0.0, "ic/r-rad_sec": 0.0}

    def aero_at(self, base, over, offsets):
        f = self.fdm
        st = dict(base)
        st.update(over)
        for k in ("ic/h-sl-ft", "ic/vt-fps", "ic/alpha-rad", "ic/beta-rad", "ic/psi-true-rad", "ic/theta-rad",
                  "ic/phi-rad", "ic/p-rad_sec", "ic/q-rad_sec", "ic/r-rad_sec"):
            f[k] = st[k]
        for s in SURFACES:
            f[f"gen/{s}-offset-rad"] = offsets.get(s, 0.0)
        with quiet():
            f.run_ic()
        qs = f["aero/qbar-psf"] * f["metrics/Sw-sqft"]
        b, c = f["metrics/bw-ft"], f["metrics/cbarw-ft"]
        alpha = f["aero/alpha-rad"]
        # α̇ functions: lift (wind) and pitching moment about the CG
        rx = -(f["metrics/aero-rp-x-in"] - f["inertia/cg-x-in"]) / 12.0
        rz = -(f["metrics/aero-rp-z-in"] - f["inertia/cg-z-in"]) / 12.0
        lift_adot, m_adot = 0.0, 0.0
        for axis, fn in self.adot_functions:
            v = f[fn]
            if axis == "LIFT":
                lift_adot += v
                fx, fz = v * math.sin(alpha), -v * math.cos(alpha)
                m_adot += rz * fx - rx * fz
            elif axis == "PITCH":
                m_adot += v
        return dict(CL=(f["forces/fwz-aero-lbs"] - lift_adot) / qs, CD=f["forces/fwx-aero-lbs"] / qs,
                    CY=f["forces/fby-aero-lbs"] / qs, Cl=f["moments/l-aero-lbsft"] / (qs * b),
                    Cm=(f["moments/m-aero-lbsft"] - m_adot) / (qs * c), Cn=f["moments/n-aero-lbsft"] / (qs * b),
                    adot=f["aero/alphadot-rad_sec"], lift_adot=lift_adot / qs, m_adot=m_adot / (qs * c),
                    udot=f["accelerations/udot-ft_sec2"], wdot=f["accelerations/wdot-ft_sec2"],
                    qdot=f["accelerations/qdot-rad_sec2"], thrust=self.thrust_lbf(),
                    surfaces={s: f[self.reads[s]] for s in SURFACES})

    def thrust_lbf(self):
        if not hasattr(self, "thrust_props"):
            self.thrust_props = [p.split(" ")[0] for p in self.fdm.get_property_catalog()
                                 if re.match(r"propulsion/engine(\[\d+\])?/thrust-lbs", p)]
        return sum(self.fdm[p] for p in self.thrust_props)

    def truth(self):
        f = self.fdm
        base = self.state()
        offsets = {s: f[f"gen/{s}-offset-rad"] for s in SURFACES}
        V = f["velocities/vt-fps"]
        b, c = f["metrics/bw-ft"], f["metrics/cbarw-ft"]
        b0 = self.aero_at(base, {}, offsets)
        d = {}
        # A state derivative holds the surfaces: an aircraft whose FCS feeds back the state (the 737's yaw
        # damper moves the rudder with r) moves them within run_ic, and what the surfaces moved by is taken
        # off through the control derivatives. (The order of the run_ic calls is that of the records' first
        # generator version: the engines keep their state through them, so it shapes the records.)
        h = 1e-3
        raw, moved = {}, {}
        for var, key, scale in (("ic/alpha-rad", "alpha", 1.0), ("ic/beta-rad", "beta", 1.0),
                                ("ic/p-rad_sec", "p", b / (2 * V)), ("ic/q-rad_sec", "q", c / (2 * V)),
                                ("ic/r-rad_sec", "r", b / (2 * V))):
            up = self.aero_at(base, {var: base[var] + h}, offsets)
            dn = self.aero_at(base, {var: base[var] - h}, offsets)
            moved[key] = {s: (up["surfaces"][s] - dn["surfaces"][s]) / (2 * h) for s in SURFACES}
            for coef in ("CL", "CD", "CY", "Cl", "Cm", "Cn"):
                raw[(coef, key, scale)] = (up[coef] - dn[coef]) / (2 * h)
            if key == "alpha" and abs(up["adot"]) > 1e-6 and self.adot_functions:
                k = up["adot"] * c / (2 * V)
                d["CL_alphadot"] = up["lift_adot"] / k
                d["Cm_alphadot"] = up["m_adot"] / k
        hs = 0.01
        for s, key in SURFACE_KEYS:
            up = self.aero_at(base, {}, {**offsets, s: offsets[s] + hs})
            dn = self.aero_at(base, {}, {**offsets, s: offsets[s] - hs})
            for coef in ("CL", "CD", "CY", "Cl", "Cm", "Cn"):
                d[f"{coef}_{key}"] = (up[coef] - dn[coef]) / (2 * hs)
        for (coef, key, scale), slope in raw.items():
            by_fcs = sum(d[f"{coef}_{k}"] * moved[key][s] for s, k in SURFACE_KEYS)
            d[f"{coef}_{key}"] = (slope - by_fcs) / scale
        d.setdefault("CL_alphadot", 0.0)
        d.setdefault("Cm_alphadot", 0.0)
        # back to the trimmed state (rates zero)
        self.aero_at(base, {}, offsets)
        cond = dict(airspeed_m_s=V * FT, rho_kg_m3=f["atmosphere/rho-slugs_ft3"] * SLUG / FT**3,
                    qbar_pa=f["aero/qbar-psf"] * PSF, alpha_rad=f["aero/alpha-rad"],
                    theta_rad=f["attitude/theta-rad"], altitude_m=f["position/h-sl-ft"] * FT,
                    CL_trim=b0["CL"], CD_trim=b0["CD"], Cm_trim=b0["Cm"], thrust_n=b0["thrust"] * LBF,
                    trim_residual=dict(udot_m_s2=b0["udot"] * FT, wdot_m_s2=b0["wdot"] * FT,
                                       qdot_rad_s2=b0["qdot"]))
        return d, cond

    def truth_over_records(self, base, offsets, kinds, control, points=21):
        """The α and β derivatives the records determine where the aero tables are not linear over the range
        flown: the least-squares slope of each coefficient over `points` quantiles of the true α (longitudinal
        records) or β (lateral records), every other state at the trim (equal weights: each quantile stands for
        the same share of the samples). The surfaces are held as in `truth`: what an FCS moves them by is taken
        off through the control derivatives `control`."""
        out = {}
        trim = self.aero_at(base, {}, offsets)["surfaces"]
        for angle, var, kind, coefs in (("alpha", "ic/alpha-rad", "lon", ("CL", "CD", "Cm")),
                                        ("beta", "ic/beta-rad", "lat", ("CY", "Cl", "Cn"))):
            flown = [x for k, x in zip(kinds, self.flown.get(angle, [])) if k.startswith(kind)]
            if not flown:
                continue
            x = np.quantile(np.concatenate(flown), np.linspace(0.0, 1.0, points + 2)[1:-1])
            ys = [self.aero_at(base, {var: float(v)}, offsets) for v in x]
            for coef in coefs:
                held = [y[coef] - sum(control[f"{coef}_{k}"] * (y["surfaces"][s] - trim[s])
                                      for s, k in SURFACE_KEYS)
                        for y in ys]
                out[f"{coef}_{angle}"] = float(np.polyfit(x, held, 1)[0])
        self.aero_at(base, {}, offsets)
        return out

    def airframe(self, imu_m, vane_m):
        f = self.fdm
        thrust = self.thrust_lbf()
        fx, fz = f["forces/fbx-prop-lbs"], f["forces/fbz-prop-lbs"]
        m_prop = f["moments/m-prop-lbsft"]
        return {
            "name": self.name,
            "mass_kg": f["inertia/mass-slugs"] * SLUG,
            # ixz as the airframe description takes it, ∫xz dm in body axes (Ixx ṗ − Ixz ṙ = L): JSBSim's
            # inertia tensor holds its ixz where that tensor holds −Ixz, so the property has the other sign.
            "inertia_kg_m2": {k: (-1.0 if k == "ixz" else 1.0) * f[f"inertia/{k}-slugs_ft2"] * SLUG * FT**2
                              for k in ("ixx", "iyy", "izz", "ixz")},
            "wing": {"area_m2": f["metrics/Sw-sqft"] * FT**2, "span_m": f["metrics/bw-ft"] * FT,
                     "mac_m": f["metrics/cbarw-ft"] * FT},
            "thrust": {"inclination_rad": math.atan2(-fz, fx) if thrust > 0 else 0.0,
                       "moment_arm_m": (m_prop / thrust) * FT if abs(thrust) > 1 else 0.0},
            "sensors": {"imu_m": list(imu_m), "alpha_vane_m": list(vane_m), "beta_vane_m": list(vane_m)},
            "flight": {"density_kg_m3": f["atmosphere/rho-slugs_ft3"] * SLUG / FT**3},
        }


def multistep(t, t0, unit_s, pattern, amp):
    """A pulse train: `pattern` gives each pulse's sign and length in units (3-2-1-1: [3, -2, 1, -1])."""
    edge = t0
    for p in pattern:
        length = abs(p) * unit_s
        if edge <= t < edge + length:
            return amp * math.copysign(1.0, p)
        edge += length
    return 0.0


def plans(rng, kind):
    """(duration s, command functions per surface) of one record, with jittered timing and amplitudes."""
    j = lambda x, r=0.1: x * (1.0 + r * rng.uniform(-1, 1))
    if kind == "lon1":
        u, a = j(0.35), math.radians(j(2.0))
        return 22.0, {"elevator": lambda t: multistep(t, 2.0, u, [3, -2, 1, -1], a)}
    if kind == "lon2":
        u, a = j(0.6), math.radians(j(2.5))
        u2 = j(0.3)
        return 22.0, {"elevator": lambda t: multistep(t, 1.5, u, [-1, 1], a) + multistep(t, 9.0, u2, [3, -2, 1, -1], 0.8 * a)}
    if kind == "lat1":
        ua, ur = j(0.8), j(1.2)
        aa, ar = math.radians(j(4.0)), math.radians(j(4.0))
        return 22.0, {"aileron": lambda t: multistep(t, 1.5, ua, [1, -1], aa),
                      "rudder": lambda t: multistep(t, 7.0, ur, [1, -1], ar)}
    if kind == "lat2":
        ua, ur = j(0.6), j(0.9)
        aa, ar = math.radians(j(3.0)), math.radians(j(5.0))
        return 22.0, {"rudder": lambda t: multistep(t, 1.5, ur, [1, -1], ar),
                      "aileron": lambda t: multistep(t, 8.0, ua, [2, -2, 1, -1], aa)}
    raise ValueError(kind)


class Sensors:
    """Noise (σ), biases and the vane time skew of the logger, in the logged units. `ideal`: no bias, no skew,
    and a thousandth of the noise (a channel without any would have no variance to be weighted by)."""

    def __init__(self, rng, ideal=False):
        self.rng = rng
        self.sigma = dict(AOA_DEG=0.08, AOS_DEG=0.08, PHI_DEG=0.05, THETA_DEG=0.05, PSI_DEG=0.1,
                          P_DPS=0.08, Q_DPS=0.08, R_DPS=0.08, AX_G=0.004, AY_G=0.004, AZ_G=0.006,
                          KTAS=0.3, ALT_FT=2.0, QBAR_PSF=0.15, DE_DEG=0.04, DA_DEG=0.04, DR_DEG=0.04,
                          THRUST_LBF=5.0)
        b = lambda s: s * rng.uniform(-1, 1)
        self.bias = dict(AOA_DEG=b(0.4), AOS_DEG=b(0.3), PHI_DEG=b(0.3), THETA_DEG=b(0.3), P_DPS=b(0.15),
                         Q_DPS=b(0.15), R_DPS=b(0.15), AX_G=b(0.01), AY_G=b(0.01), AZ_G=b(0.01))
        self.vane_skew_s = 0.03
        if ideal:
            self.sigma = {k: v * 1e-3 for k, v in self.sigma.items()}
            self.bias = {k: 0.0 for k in self.bias}
            self.vane_skew_s = 0.0

    def measure(self, col, values):
        v = np.asarray(values) + self.bias.get(col, 0.0)
        return v + self.rng.normal(0.0, self.sigma.get(col, 0.0), size=v.shape)


def fly(ac, kind, rng, sensors, sim_hz, log_hz, imu_m, vane_m, tau_s=0.05, rate_lim=math.radians(60)):
    f = ac.fdm
    duration, cmds = plans(rng, kind)
    n = int(round(duration * sim_hz))
    pos = {s: f[f"gen/{s}-offset-rad"] for s in SURFACES}
    rows = {k: [] for k in ("t", "u", "v", "w", "p", "q", "r", "pd", "qd", "rd", "fx", "fy", "fz", "phi", "theta",
                             "psi", "vt", "h", "qbar", "de", "da", "dr", "thrust")}
    t0 = f["simulation/sim-time-sec"]
    mass = f["inertia/mass-slugs"]
    for k in range(n):
        t = k / sim_hz
        for s in SURFACES:
            cmd = cmds.get(s, lambda _t: 0.0)(t)
            rate = float(np.clip((cmd - pos[s]) / tau_s, -rate_lim, rate_lim))
            pos[s] += rate / sim_hz
            f[f"gen/{s}-offset-rad"] = pos[s]
        if kind.startswith("lat"):
            ac.pilot()
        f.run()
        rows["t"].append(f["simulation/sim-time-sec"] - t0)
        for key, prop in (("u", "velocities/u-aero-fps"), ("v", "velocities/v-aero-fps"),
                          ("w", "velocities/w-aero-fps"), ("p", "velocities/p-rad_sec"),
                          ("q", "velocities/q-rad_sec"), ("r", "velocities/r-rad_sec"),
                          ("pd", "accelerations/pdot-rad_sec2"), ("qd", "accelerations/qdot-rad_sec2"),
                          ("rd", "accelerations/rdot-rad_sec2"), ("phi", "attitude/phi-rad"),
                          ("theta", "attitude/theta-rad"), ("psi", "attitude/psi-rad"),
                          ("vt", "velocities/vt-fps"), ("h", "position/h-sl-ft"), ("qbar", "aero/qbar-psf")):
            rows[key].append(f[prop])
        for key, prop in (("fx", "forces/fbx-total-lbs"), ("fy", "forces/fby-total-lbs"),
                          ("fz", "forces/fbz-total-lbs")):
            rows[key].append(f[prop] / mass)  # specific force at the CG, ft/s²
        rows["de"].append(f[ac.reads["elevator"]] + pos["elevator"])
        rows["da"].append(f[ac.reads["aileron"]] + pos["aileron"])
        rows["dr"].append(f[ac.reads["rudder"]] + pos["rudder"])
        rows["thrust"].append(ac.thrust_lbf())
    a = {k: np.array(v) for k, v in rows.items()}
    # the aerodynamic angles flown (true, at the CG), for the truth over the records' range
    ac.flown.setdefault("alpha", []).append(np.arctan2(a["w"], a["u"]))
    ac.flown.setdefault("beta", []).append(np.arcsin(a["v"] / np.sqrt(a["u"] ** 2 + a["v"] ** 2 + a["w"] ** 2)))
    # sensors away from the CG (body axes, x fwd, y right, z down; ft)
    ri = np.array(imu_m) / FT
    rv = np.array(vane_m) / FT
    w = np.stack([a["p"], a["q"], a["r"]], axis=1)
    wd = np.stack([a["pd"], a["qd"], a["rd"]], axis=1)
    acc = np.stack([a["fx"], a["fy"], a["fz"]], axis=1) + np.cross(wd, ri) + np.cross(w, np.cross(w, ri))
    vel = np.stack([a["u"], a["v"], a["w"]], axis=1) + np.cross(w, rv)
    vane_alpha = np.degrees(np.arctan2(vel[:, 2], vel[:, 0]))
    vane_beta = np.degrees(np.arcsin(vel[:, 1] / np.linalg.norm(vel, axis=1)))
    # log samples: every sim_hz/log_hz-th step; the vanes are read `vane_skew_s` late
    step = int(round(sim_hz / log_hz))
    idx = np.arange(0, n, step)
    tl = a["t"][idx]
    late = lambda x: np.interp(tl - sensors.vane_skew_s, a["t"], x)
    cols = {
        "TIME_S": tl,
        "KTAS": a["vt"][idx] * FT / KT, "ALT_FT": a["h"][idx], "QBAR_PSF": a["qbar"][idx],
        "AOA_DEG": late(vane_alpha), "AOS_DEG": late(vane_beta),
        "PHI_DEG": np.degrees(a["phi"][idx]), "THETA_DEG": np.degrees(a["theta"][idx]),
        "PSI_DEG": np.degrees(a["psi"][idx]),
        "P_DPS": np.degrees(a["p"][idx]), "Q_DPS": np.degrees(a["q"][idx]), "R_DPS": np.degrees(a["r"][idx]),
        "AX_G": acc[idx, 0] * FT / G0, "AY_G": acc[idx, 1] * FT / G0, "AZ_G": acc[idx, 2] * FT / G0,
        "DE_DEG": np.degrees(a["de"][idx]), "DA_DEG": np.degrees(a["da"][idx]), "DR_DEG": np.degrees(a["dr"][idx]),
        "THRUST_LBF": a["thrust"][idx],
    }
    for k in cols:
        if k != "TIME_S":
            cols[k] = sensors.measure(k, cols[k])
    return cols


COLUMN_MAP = {
    "TIME_S": ("time_s", None), "KTAS": ("airspeed_m_s", "kts"), "ALT_FT": ("altitude_m", "ft"),
    "QBAR_PSF": ("qbar_pa", "psf"), "AOA_DEG": ("alpha_rad", "deg"), "AOS_DEG": ("beta_rad", "deg"),
    "PHI_DEG": ("phi_rad", "deg"), "THETA_DEG": ("theta_rad", "deg"), "PSI_DEG": ("psi_rad", "deg"),
    "P_DPS": ("p_rad_s", "deg/s"), "Q_DPS": ("q_rad_s", "deg/s"), "R_DPS": ("r_rad_s", "deg/s"),
    "AX_G": ("ax_m_s2", "g"), "AY_G": ("ay_m_s2", "g"), "AZ_G": ("az_m_s2", "g"),
    "DE_DEG": ("elevator_rad", "deg"), "DA_DEG": ("aileron_rad", "deg"), "DR_DEG": ("rudder_rad", "deg"),
    "THRUST_LBF": ("thrust_n", "lbf"),
}


def toml_value(v):
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v)
    return repr(float(v))


def write_airframe(path, af):
    lines = [f"# Airframe description of the JSBSim {af['name']} (written by scripts/gen_foreign_records.py)",
             f"name = {toml_value(af['name'])}", f"mass_kg = {toml_value(af['mass_kg'])}",
             f"inertia_kg_m2 = {toml_value(af['inertia_kg_m2'])}", f"wing = {toml_value(af['wing'])}"]
    for table in ("thrust", "sensors", "flight"):
        lines.append(f"\n[{table}]")
        lines += [f"{k} = {toml_value(v)}" for k, v in af[table].items()]
    open(path, "w").write("\n".join(lines) + "\n")


def write_columns(path):
    lines = ["# Column map of the generated records onto the flight-data schema", "[columns]"]
    for col, (to, unit) in COLUMN_MAP.items():
        lines.append(f"{col} = {{ to = \"{to}\"" + (f", unit = \"{unit}\"" if unit else "") + " }")
    open(path, "w").write("\n".join(lines) + "\n")


def write_csv(path, cols, meta):
    names = list(cols)
    with open(path, "w") as fh:
        for m in meta:
            fh.write(f"# {m}\n")
        fh.write(",".join(names) + "\n")
        for i in range(len(cols["TIME_S"])):
            fh.write(",".join(f"{cols[k][i]:.6f}" if k == "TIME_S" else f"{cols[k][i]:.6g}" for k in names) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--aircraft", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--sim-hz", type=float, default=200.0)
    ap.add_argument("--log-hz", type=float, default=50.0)
    ap.add_argument("--altitude-ft", type=float)
    ap.add_argument("--speed-kts", type=float)
    ap.add_argument("--settle-s", type=float, default=60.0)
    ap.add_argument("--turbulence", choices=("light", "none"), default="light")
    ap.add_argument("--sensors", choices=("logger", "ideal"), default="logger",
                    help="logger: noise, biases, an IMU and vanes away from the CG, a 30 ms vane skew; ideal: "
                         "at the CG, no bias or skew, a thousandth of the noise (to test model structure)")
    ap.add_argument("--integrator", choices=("euler", "ab2"), default="euler",
                    help="JSBSim's integrator of the body rates and attitude (module doc)")
    ap.add_argument("--records", default="lon1,lon2,lat1,lat2")
    args = ap.parse_args()
    alt, spd = DEFAULTS.get(args.aircraft, (6000.0, None))
    alt = args.altitude_ft or alt
    spd = args.speed_kts or spd
    rng = np.random.default_rng(args.seed)
    os.makedirs(args.out, exist_ok=True)
    ideal = args.sensors == "ideal"
    imu_m = (0.0, 0.0, 0.0) if ideal else (0.6, -0.15, 0.25)
    vane_m = (0.0, 0.0, 0.0) if ideal else (3.0, 0.0, 0.1)
    with tempfile.TemporaryDirectory() as work:
        ac = Aircraft(args.aircraft, args.sim_hz, work, args.integrator)
        if spd is None:
            ac.start(alt, 150.0)
            spd = round(ac.cruise_speed_kts())
        ac.start(alt, spd)
        ac.settle(args.settle_s)
        if not ac.steady():
            acc, gamma = ac.settle_worst
            print(f"{args.aircraft}: the flown settle left no trim (body acceleration up to {acc:.2f} m/s², flight "
                  f"path {math.degrees(gamma):.1f}° over its last 5 s): JSBSim's trim is taken", file=sys.stderr)
            ac.trim_jsbsim()
        truth, cond = ac.truth()
        af = ac.airframe(imu_m, vane_m)
        sensors = Sensors(rng, ideal)
        if args.turbulence == "light":
            ac["atmosphere/turb-type"] = 3
            ac["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = 15.0
            ac["atmosphere/turbulence/milspec/severity"] = 1
            # The seed's own gust realisation: FGWinds draws from one random sequence per FGFDMExec whose seed
            # is 0 unless set, so without this every seed would fly through the same gusts.
            ac["atmosphere/randomseed"] = int(np.random.default_rng((args.seed, 0x6757)).integers(1, 2**31 - 1))
        written = []
        base = ac.state()
        offsets = {s: ac[f"gen/{s}-offset-rad"] for s in SURFACES}
        for kind in args.records.split(","):
            ac.aero_at(base, {}, offsets)  # every record starts from the trim
            ac["fcs/aileron-cmd-norm"] = 0.0
            cols = fly(ac, kind, rng, sensors, args.sim_hz, args.log_hz, imu_m, vane_m)
            path = os.path.join(args.out, f"{args.aircraft}_{kind}.csv")
            write_csv(path, cols, [f"JSBSim {args.aircraft}, {kind}, {alt:g} ft, {spd:g} kts, seed {args.seed}",
                                   f"logged at {args.log_hz:g} Hz from a {args.sim_hz:g} Hz simulation"])
            written.append(path)
        over_records = ac.truth_over_records(base, offsets, args.records.split(","), truth)
    write_airframe(os.path.join(args.out, f"{args.aircraft}.airframe.toml"), af)
    write_columns(os.path.join(args.out, f"{args.aircraft}.columns.toml"))
    json.dump({"aircraft": args.aircraft, "flight_condition": cond, "derivatives": truth,
               "derivatives_over_records": over_records,
               "sensors": {"bias": sensors.bias, "sigma": sensors.sigma, "vane_skew_s": sensors.vane_skew_s,
                           "imu_m": imu_m, "vane_m": vane_m},
               "surface_reads": ac.reads, "records": written},
              open(os.path.join(args.out, f"{args.aircraft}.truth.json"), "w"), indent=1)
    print(json.dumps({"records": written, "trim_residual": cond["trim_residual"]}))


if __name__ == "__main__":
    main()
