#!/usr/bin/env python3
"""Independent generator of diagnose test records: JSBSim's c172x (or 737) through JSBSim's own Python API.

It shares nothing with flightid's bridge or `fly`: its own private aircraft copy, its own actuator, its own
sample timing. Each case is a pair of records (training and validation) of the same aircraft with the same
hidden effects, flown at a random trim point and heading, with sensor noise and optionally light turbulence:

  * simulation at 100-200 Hz, logged at 20-50 Hz (the logged value is the instantaneous value at the log time);
  * 30-90 s per record, the maneuvers in sequence: elevator 3-2-1-1, aileron doublet, rudder doublet, elevator
    doublet, with quiet flight in between so that the slow modes (phugoid, spiral) drift;
  * the surface deflection moves through a first-order actuator with a rate limit (not a sample-and-hold);
  * 0-3 hidden effects drawn from the whole diagnose catalogue (the truth is written beside each CSV).

Hidden effects and how they are made:
  input_delay / actuator_lag / control_effectiveness: the aero model reads k * lag(delay(delta)) of the logged
      deflection delta (the private copy's aero functions read a declared property the script sets each step);
  sensor_bias / sensor_scale: the logged column is k * true + b;
  aero_derivative: the coefficient function is multiplied by a declared factor property;
  aero_nonlinearity: an added term (Cm_alpha2: dCm = k alpha^2, CL_alpha2: dCL = k alpha^2, alpha in rad).

--aircraft 737 flies JSBSim's stock Boeing 737 instead (AIRCRAFT holds one entry per aircraft): gear up, flaps 0,
both engines running, the tanks filled again before each trim, a trim point drawn in 15000-30000 ft and 280-450 kts
true airspeed and drawn again until the aircraft with its effects trims there at alpha <= 8 deg (its linear lift
range ends at 13 deg) and at most 340 kts calibrated; smaller maneuver amplitudes (elevator 1-2 deg, aileron about
3-5 deg, rudder 2-4 deg), longer elevator and aileron pulses for its slower short period and roll mode; Cm_alpha2
and CL_alpha2 in 1-2 and 5-10 (the same share of the local slope at the median trim alpha as 4-8 and 15-30 on the
c172x; 4-8 makes the 737 diverge). The aero reads the script's own deflection as on the c172x, so the 737's yaw
damper (in its FCS) does not act. The 737 has no Cm_0, Cn_p, Cn_da: they are never drawn for it.
--aircraft c182 flies JSBSim's c182 (its own aero tables and names), at 2000-7000 ft and 85-125 kts, with the c172x's
maneuvers; flightid has no configuration of it and derives one from the model.
--aircraft c310 flies JSBSim's c310, a light twin with retractable gear (gear up, both engines), at 3000-8000 ft and
115-145 kts with the c172x's maneuvers; JSBSim's trim of it fails at scattered points and depends on what the model
flew before, so every trim starts from a freshly loaded model and a point that fails is drawn again. flightid has no
configuration of it either.

Usage: gen_diagnose_records.py --out DIR --cases N --seed S [--aircraft c172x|c182|c310|737] [--turbulence]
       [--clean-share 0.25] [--stratified] [--first K] [--effects JSON]
       [--duration S | --min-duration S --max-duration S] [--plan NAME|random] [--max-noise L] [--without COLUMNS]
Writes DIR/case_NNN_train.csv, DIR/case_NNN_valid.csv and DIR/case_NNN_truth.json (flight-data CSV schema; the
truth's "aircraft" names the model).
"""

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

_STDOUT = os.dup(1)
os.dup2(2, 1)  # JSBSim's C++ console output goes to stderr
import jsbsim  # noqa: E402

FT = 0.3048
SLUG_FT3 = 515.378818  # kg/m^3 per slug/ft^3
KT = 0.514444

# The added terms, the same on every aircraft: the properties that make each coefficient a force or moment.
ADDED_TERMS = {
    "Cm_alpha2": ("PITCH", ["aero/qbar-psf", "metrics/Sw-sqft", "metrics/cbarw-ft"]),
    "CL_alpha2": ("LIFT", ["aero/qbar-psf", "metrics/Sw-sqft"]),
}
# The maneuvers' surface amplitude (rad) and pulse width (s) ranges of the light aircraft (c172x, c182).
LIGHT_AIRCRAFT_MANEUVERS = {
    "amplitude": {"e3211": (0.025, 0.045), "ad": (0.04, 0.08), "rd": (0.05, 0.09), "ed": (0.025, 0.045)},
    "pulse": {"e3211": (0.35, 0.6), "ad": (0.6, 1.2), "rd": (0.7, 1.3), "ed": (0.6, 1.0)},
}

# The surfaces of the models whose aerodynamics read the left aileron's deflection (c182, c310, 737).
LEFT_AILERON_SURFACES = {
    "elevator": ("fcs/elevator-pos-rad", "fcs/mag-elevator-pos-rad", "fcs/elevator-cmd-norm"),
    "aileron": ("fcs/left-aileron-pos-rad", None, "fcs/aileron-cmd-norm"),
    "rudder": ("fcs/rudder-pos-rad", None, "fcs/rudder-cmd-norm"),
}

AIRCRAFT = {
    # One entry per aircraft:
    #   model: the JSBSim model (aircraft/<model>/<model>.xml of the jsbsim package);
    #   surfaces: surface -> (position property the aero model reads, its magnitude property or None, command);
    #   derivatives: vocabulary name -> coefficient function (a name the model lacks is left out, never drawn);
    #   added: added term -> (axis, the properties that make its coefficient a force or moment);
    #   pre_ic: properties set before each trim's initial conditions are run;
    #   pre_trim: properties set after the engines are started, before the trim;
    #   envelope: the random trim point's altitude (ft) and true airspeed (kts) ranges; limits, if given: upper
    #       bounds on properties at the trim (a point where the trim fails or exceeds one is drawn again);
    #   amplitude, pulse: the maneuvers' surface amplitude (rad) and pulse width (s) ranges;
    #   ranges: the catalogue's magnitude ranges that differ from its default for this aircraft.
    "c172x": {
        "model": "c172x",
        "surfaces": {
            "elevator": ("fcs/elevator-pos-rad", "fcs/mag-elevator-pos-rad", "fcs/elevator-cmd-norm"),
            "aileron": ("fcs/effective-aileron-pos", None, "fcs/aileron-cmd-norm"),
            "rudder": ("fcs/rudder-pos-rad", None, "fcs/rudder-cmd-norm"),
        },
        "derivatives": {
            "CL_alpha": "CLwbh", "CD_0": "CDo", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq", "Cm_de": "Cmde",
            "CY_beta": "CYb", "Cl_beta": "Clb", "Cl_p": "Clp", "Cl_r": "Clr", "Cl_da": "Clda", "Cn_beta": "Cnb",
            "Cn_r": "Cnr", "Cn_dr": "Cndr", "Cm_alphadot": "Cmadot", "Cn_p": "Cnp", "Cl_dr": "Cldr",
            "Cn_da": "Cnda", "Cm_0": "Cmo",
        },
        "added": ADDED_TERMS,
        "pre_ic": {},
        "pre_trim": {"fcs/mixture-cmd-norm": 1.0},
        "envelope": {"altitude_ft": (2000, 8000), "speed_kts": (85, 115)},
        **LIGHT_AIRCRAFT_MANEUVERS,
        "ranges": {},
    },
    # JSBSim's c182 (another author's model than the c172x: its own tables, CLalpha/CmDe/ClDa/CnDr names, the
    # left aileron read). flightid has no configuration for it and derives one from the model.
    "c182": {
        "model": "c182",
        "surfaces": LEFT_AILERON_SURFACES,
        "derivatives": {
            "CL_alpha": "CLalpha", "CD_0": "CDo", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq", "Cm_de": "CmDe",
            "CY_beta": "CYb", "Cl_beta": "Clb", "Cl_p": "Clp", "Cl_r": "Clr", "Cl_da": "ClDa", "Cn_beta": "Cnb",
            "Cn_r": "Cnr", "Cn_dr": "CnDr", "Cm_alphadot": "Cmadot", "Cn_p": "Cnp", "Cl_dr": "ClDr",
            "Cn_da": "CnDa", "Cm_0": "Cmo",
        },
        "added": ADDED_TERMS,
        # The tanks filled as in c182.xml before every trim (as for the 737): a record flown after the earlier ones
        # burned fuel would be lighter, with its CG elsewhere, than the model flightid replays.
        "pre_ic": {"propulsion/tank[0]/contents-lbs": 200.0, "propulsion/tank[1]/contents-lbs": 200.0},
        "pre_trim": {"fcs/mixture-cmd-norm": 1.0},
        "envelope": {"altitude_ft": (2000, 7000), "speed_kts": (85, 125)},
        **LIGHT_AIRCRAFT_MANEUVERS,
        # Its static stability is a third of the c172x's (Cmalpha -0.61 to -0.65 against -1.8): the c172x's
        # Cm_alpha2 of 4-8 left it statically unstable and a turbulent record tumbled (phi 177 deg); scaled by a third.
        "ranges": {("aero_nonlinearity", "Cm_alpha2"): (1.5, 3.0)},
    },
    # JSBSim's c310, a light twin (two engines whose propellers turn the same way, retractable gear, a fourth of
    # the c172x's elevator travel trailing edge down). flightid has no configuration for it and derives one.
    "c310": {
        "model": "c310",
        "surfaces": LEFT_AILERON_SURFACES,
        "derivatives": {
            "CL_alpha": "CLalpha", "CD_0": "CDo", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq", "Cm_de": "CmDe",
            "CY_beta": "CYbeta", "Cl_beta": "Clbeta", "Cl_p": "Clp", "Cl_r": "Clr", "Cl_da": "ClDa",
            "Cn_beta": "Cnbeta", "Cn_r": "Cnr", "Cn_dr": "CnDr", "Cm_alphadot": "Cmadot", "Cn_p": "Cnp",
            "Cl_dr": "Cldr", "Cn_da": "CnDa", "Cm_0": "Cmo",
        },
        "added": ADDED_TERMS,
        # The four tanks filled as in c310.xml before every trim (as for the c182 and the 737).
        "pre_ic": {"propulsion/tank[0]/contents-lbs": 225.0, "propulsion/tank[1]/contents-lbs": 225.0,
                   "propulsion/tank[2]/contents-lbs": 95.0, "propulsion/tank[3]/contents-lbs": 95.0},
        "pre_trim": {"fcs/mixture-cmd-norm[0]": 1.0, "fcs/mixture-cmd-norm[1]": 1.0,
                     "gear/gear-cmd-norm": 0.0, "gear/gear-pos-norm": 0.0},
        # JSBSim's full trim of the c310 fails at scattered points of this envelope (4000 ft 120 kts fails, 5000 ft 120
        # kts trims): a point where it fails is drawn again (the limit on alpha is only there to ask for that).
        "envelope": {"altitude_ft": (3000, 8000), "speed_kts": (115, 145), "limits": {"aero/alpha-deg": 10.0}},
        # Whether it trims depends on what the FGFDMExec flew before (a point found trimmable failed when the record
        # was flown from it): every trim starts from a freshly loaded model.
        "fresh_trim": True,
        **LIGHT_AIRCRAFT_MANEUVERS,
        # Cm_alpha -1.0 (c172x -1.8) and a median trim alpha of about 0.045 rad (c172x 0.021): the added terms scaled to
        # change the local slope by the same share as the c172x's.
        "ranges": {("aero_nonlinearity", "Cm_alpha2"): (1.0, 2.0), ("aero_nonlinearity", "CL_alpha2"): (7.0, 14.0)},
    },
    "737": {
        "model": "737",
        "surfaces": LEFT_AILERON_SURFACES,
        "derivatives": {
            "CL_alpha": "CLalpha", "CD_0": "CD0", "Cm_alpha": "Cmalpha", "Cm_q": "Cmq", "Cm_de": "Cmde",
            "CY_beta": "CYb", "Cl_beta": "Clb", "Cl_p": "Clp", "Cl_r": "Clr", "Cl_da": "Clda", "Cn_beta": "Cnb",
            "Cn_r": "Cnr", "Cn_dr": "Cndr", "Cm_alphadot": "Cmadot", "Cl_dr": "Cldr",
        },
        "added": ADDED_TERMS,
        # The tanks filled as in 737.xml before every trim: the fuel an earlier flight burned would otherwise change
        # the weight and balance, and a trim point found trimmable before a record might not trim for the next.
        "pre_ic": {"propulsion/tank[0]/contents-lbs": 10000.0, "propulsion/tank[1]/contents-lbs": 10000.0,
                   "propulsion/tank[2]/contents-lbs": 4000.0},
        "pre_trim": {"gear/gear-cmd-norm": 0.0, "gear/gear-pos-norm": 0.0, "fcs/flap-cmd-norm": 0.0},
        "envelope": {"altitude_ft": (15000, 30000), "speed_kts": (280, 450),
                     "limits": {"aero/alpha-deg": 8.0, "velocities/vc-kts": 340.0}},
        "amplitude": {"e3211": (0.0175, 0.035), "ad": (0.05, 0.09), "rd": (0.035, 0.07), "ed": (0.0175, 0.035)},
        # Elevator and aileron pulses longer than the c172x's: short period 1.6 rad/s (c172x 6.3), roll mode time
        # constant 0.6 s (0.2); the Dutch roll is about 2 rad/s on both (flown at 22500 ft 365 kts, 5000 ft 100 kts).
        "pulse": {"e3211": (0.6, 1.0), "ad": (1.0, 1.6), "rd": (0.7, 1.3), "ed": (1.0, 1.6)},
        # The added terms change the local slope at the median trim alpha (0.054 rad, c172x 0.021) by the same share.
        "ranges": {("aero_nonlinearity", "Cm_alpha2"): (1.0, 2.0), ("aero_nonlinearity", "CL_alpha2"): (5.0, 10.0)},
    },
}
LOGGED = [
    # column, property, factor
    ("phi_rad", "attitude/phi-rad", 1.0), ("theta_rad", "attitude/theta-rad", 1.0),
    ("psi_rad", "attitude/psi-rad", 1.0),
    ("p_rad_s", "velocities/p-rad_sec", 1.0), ("q_rad_s", "velocities/q-rad_sec", 1.0),
    ("r_rad_s", "velocities/r-rad_sec", 1.0),
    ("alpha_rad", "aero/alpha-rad", 1.0), ("beta_rad", "aero/beta-rad", 1.0),
    ("airspeed_m_s", "velocities/vt-fps", FT), ("altitude_m", "position/h-sl-meters", 1.0),
    ("ax_m_s2", "accelerations/a-pilot-x-ft_sec2", FT), ("ay_m_s2", "accelerations/a-pilot-y-ft_sec2", FT),
    ("az_m_s2", "accelerations/a-pilot-z-ft_sec2", FT),
    ("latitude_rad", "position/lat-geod-rad", 1.0),  # GPS
]
# Noise standard deviations at "level 1" (scaled by a random level per case): 0.05 deg attitude, 0.1 deg/s rates
NOISE = {
    "phi_rad": 0.0009, "theta_rad": 0.0009, "psi_rad": 0.0017, "p_rad_s": 0.0017, "q_rad_s": 0.0017,
    "r_rad_s": 0.0017, "alpha_rad": 0.0012, "beta_rad": 0.0012, "airspeed_m_s": 0.1, "altitude_m": 0.3,
    "ax_m_s2": 0.03, "ay_m_s2": 0.03, "az_m_s2": 0.03,
}


def private_aircraft(root, spec):
    """root/aircraft/<model> with declared effect properties; engine/ and systems/ linked to the package's."""
    model = spec["model"]
    pkg = jsbsim.get_default_root_dir()
    for sub in ("engine", "systems"):
        os.symlink(os.path.join(pkg, sub), os.path.join(root, sub))
    src = os.path.join(pkg, "aircraft", model)
    dst = os.path.join(root, "aircraft", model)
    os.makedirs(dst)
    for f in os.listdir(src):
        if f != f"{model}.xml":
            s = os.path.join(src, f)
            (shutil.copytree if os.path.isdir(s) else shutil.copy)(s, os.path.join(dst, f))
    tree = ET.parse(os.path.join(src, f"{model}.xml"))
    top = tree.getroot()
    for tag in ("output", "input"):
        for e in top.findall(tag):
            top.remove(e)
    aero = top.find("aerodynamics")
    head = []

    def declare(name, value):
        p = ET.Element("property", {"value": repr(float(value))})
        p.text = name
        head.append(p)

    for s, (pos, mag, _cmd) in spec["surfaces"].items():
        declare(f"gen/eff/{s}", 1.0)
        declare(f"gen/override/{s}", 0.0)
        declare(f"gen/drive/{s}-rad", 0.0)
        head.append(ET.fromstring(
            f'<function name="gen/aero/{s}-rad"><product><property>gen/eff/{s}</property><sum>'
            f'<product><property>{pos}</property><difference><value>1</value>'
            f'<property>gen/override/{s}</property></difference></product>'
            f'<product><property>gen/override/{s}</property><property>gen/drive/{s}-rad</property></product>'
            f'</sum></product></function>'))
        if mag:
            head.append(ET.fromstring(
                f'<function name="gen/aero/{s}-mag"><abs><property>gen/aero/{s}-rad</property></abs></function>'))
    for name in spec["derivatives"].values():
        declare(f"gen/factor/{name}", 1.0)
    for name in spec["added"]:
        declare(f"gen/added/{name}", 0.0)
    for i, e in enumerate(head):
        aero.insert(i, e)
    replace = {}
    for s, (pos, mag, _cmd) in spec["surfaces"].items():
        replace[pos] = f"gen/aero/{s}-rad"
        if mag:
            replace[mag] = f"gen/aero/{s}-mag"
    for axis in aero.iter("axis"):
        for el in axis.iter():
            if el.tag in ("property", "independentVar") and el.text and el.text.strip() in replace:
                el.text = replace[el.text.strip()]
        for fn in axis.findall("function"):
            coef = fn.get("name", "").split("/")[-1]
            if coef in spec["derivatives"].values():
                body = [c for c in fn if c.tag != "description"]
                for c in body:
                    fn.remove(c)
                prod = ET.SubElement(fn, "product")
                prod.extend(body)
                ET.SubElement(prod, "property").text = f"gen/factor/{coef}"
    axes = {a.get("name"): a for a in aero.iter("axis")}
    for name, (axis, factors) in spec["added"].items():
        props = "".join(f"<property>{p}</property>" for p in factors)
        axes[axis].append(ET.fromstring(
            f'<function name="gen/term/{name}"><product>{props}<property>aero/alpha-rad</property>'
            f'<property>aero/alpha-rad</property><property>gen/added/{name}</property></product></function>'))
    tree.write(os.path.join(dst, f"{model}.xml"))


class Aircraft:
    def __init__(self, root, sim_hz, spec):
        self.root = root
        self.sim_hz = sim_hz
        self.spec = spec
        self.surfaces = spec["surfaces"]
        self.load()

    def load(self):
        self.fdm = jsbsim.FGFDMExec(self.root)
        self.fdm.set_dt(1.0 / self.sim_hz)
        self.fdm.set_output_path(self.root)
        self.fdm.load_model(self.spec["model"])
        self.fdm.disable_output()

    def trim(self, cond, effects):
        if self.spec.get("fresh_trim"):
            self.load()
        fdm = self.fdm
        fdm["ic/lat-geod-deg"] = cond["latitude_deg"]
        fdm["ic/long-gc-deg"] = cond["longitude_deg"]
        fdm["ic/h-sl-ft"] = cond["altitude_ft"]
        fdm["ic/vt-kts"] = cond["speed_kts"]
        fdm["ic/psi-true-deg"] = cond["heading_deg"]
        fdm["ic/gamma-deg"] = 0.0
        for s in self.surfaces:
            fdm[f"gen/override/{s}"] = 0.0
            fdm[f"gen/eff/{s}"] = 1.0
        for name in self.spec["derivatives"].values():
            fdm[f"gen/factor/{name}"] = 1.0
        for name in self.spec["added"]:
            fdm[f"gen/added/{name}"] = 0.0
        for e in effects:
            if e["effect"] == "control_effectiveness":
                fdm[f"gen/eff/{e['target']}"] = e["value"]
            elif e["effect"] == "aero_derivative":
                fdm[f"gen/factor/{self.spec['derivatives'][e['target']]}"] = e["value"]
            elif e["effect"] == "aero_nonlinearity":
                fdm[f"gen/added/{e['target']}"] = e["value"]
        fdm["atmosphere/turb-type"] = 0
        for prop, value in self.spec["pre_ic"].items():
            fdm[prop] = value
        fdm.run_ic()
        fdm["propulsion/set-running"] = -1
        for prop, value in self.spec["pre_trim"].items():
            fdm[prop] = value
        fdm["simulation/do_simple_trim"] = 1
        return {s: fdm[self.surfaces[s][0]] for s in self.surfaces}

    def trimmable(self, cond, effects):
        """Whether the aircraft with its effects trims at cond, within the envelope's limits (upper bounds)."""
        try:
            self.trim(cond, effects)
        except jsbsim.TrimFailureError:
            return False
        return all(self.fdm[prop] <= limit for prop, limit in self.spec["envelope"]["limits"].items())


def trim_point(ac, cond, effects, rng, attempts=200):
    """cond, or the first of up to `attempts` trim points drawn after it, where the aircraft trims within its
    envelope's limits; None if none does."""
    for _ in range(attempts):
        if ac.trimmable(cond, effects):
            return cond
        cond = draw_condition(rng, ac.spec)
    return None


def draw_condition(rng, spec):
    env = spec["envelope"]
    return {
        "altitude_ft": float(rng.uniform(*env["altitude_ft"])), "speed_kts": float(rng.uniform(*env["speed_kts"])),
        "heading_deg": float(rng.uniform(0, 360)), "latitude_deg": float(rng.uniform(-60, 60)),
        "longitude_deg": float(rng.uniform(-180, 180)),
    }


# Maneuver plans of the false-alarm Monte Carlo (--plan random): which of the four maneuvers are flown, in order.
PLANS = {
    "full": ["e3211", "ad", "rd", "ed"],
    "longitudinal": ["e3211", "ed"],
    "lateral": ["ad", "rd"],
    "e3211": ["e3211"],
    "reversed": ["rd", "ad", "ed", "e3211"],
}


def maneuvers(rng, duration_s, validation, spec, plan=None):
    """Command deviations (rad of surface) as functions of time: the four maneuvers in sequence, or the plan's
    maneuvers spread evenly over the record (a maneuver not in the plan is not flown)."""
    order = ["e3211", "ad", "rd", "ed"]
    if plan is None:
        slots = [0.06, 0.30, 0.50, 0.72] if not validation else [0.05, 0.27, 0.52, 0.75]
    else:
        first = 0.06 if not validation else 0.05
        at = {m: first + (1.0 - first) * j / len(plan) for j, m in enumerate(plan)}
        slots = [at.get(m, 2.0) for m in order]  # 2.0: after the end of the record
    t0 = [max(1.0, f * duration_s + rng.uniform(-1.0, 1.0)) for f in slots]
    amp, pulse = spec["amplitude"], spec["pulse"]
    a = {m: rng.uniform(*amp[m]) * rng.choice([-1, 1]) for m in order}
    pulse_e = rng.uniform(*pulse["e3211"])
    pulse_a = rng.uniform(*pulse["ad"])
    pulse_r = rng.uniform(*pulse["rd"])
    pulse_ed = rng.uniform(*pulse["ed"])

    def sequence(t, start, pulses, amp):
        u, s = 0.0, start
        for width, sign in pulses:
            if s <= t < s + width:
                u = sign * amp
            s += width
        return u

    def cmd(t):
        return {
            "elevator": sequence(t, t0[0], [(3 * pulse_e, 1), (2 * pulse_e, -1), (pulse_e, 1), (pulse_e, -1)],
                                 a["e3211"])
            + sequence(t, t0[3], [(pulse_ed, 1), (pulse_ed, -1)], a["ed"]),
            "aileron": sequence(t, t0[1], [(pulse_a, 1), (pulse_a, -1)], a["ad"]),
            "rudder": sequence(t, t0[2], [(pulse_r, 1), (pulse_r, -1)], a["rd"]),
        }
    return cmd


def fly(ac, cond, effects, duration_s, log_hz, rng, turbulence, validation, plan=None):
    fdm = ac.fdm
    trim = ac.trim(cond, effects)
    fdm["gen/override/elevator"] = 0.0
    dt = 1.0 / ac.sim_hz
    per_log = int(round(ac.sim_hz / log_hz))
    n_steps = int(round(duration_s * ac.sim_hz))
    delay = {e["target"]: e["value"] for e in effects if e["effect"] == "input_delay"}
    lag = {e["target"]: e["value"] for e in effects if e["effect"] == "actuator_lag"}
    surfaces = ac.surfaces
    hist = {s: [trim[s]] for s in surfaces}  # true deflection at every sim step
    lagged = dict(trim)
    pos = dict(trim)
    for s in surfaces:
        fdm[f"gen/drive/{s}-rad"] = trim[s]
        fdm[f"gen/override/{s}"] = 1.0
    if turbulence:
        fdm["atmosphere/turb-type"] = 3
        # The case's own gust realisation: FGWinds keeps one random sequence per FGFDMExec, which every case of a
        # run would otherwise continue (case K alone would then meet other gusts than case K of a longer run).
        fdm["atmosphere/randomseed"] = int(rng.integers(1, 2**31 - 1))
        fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = rng.uniform(10.0, 20.0)
        fdm["atmosphere/turbulence/milspec/severity"] = 1
    cmd = maneuvers(rng, duration_s, validation, ac.spec, plan)
    tau_act, rate_max = 0.04, 1.2  # the aircraft's own actuator: first order with a rate limit
    rows = []

    def log(t):
        row = {"time_s": t}
        for s in surfaces:
            row[f"{s}_rad"] = pos[s]
        row["throttle"] = fdm["fcs/throttle-cmd-norm[0]"]
        for col, prop, f in LOGGED:
            row[col] = fdm[prop] * f
        imu = ac.spec.get("imu_offset_m")
        if imu:  # accelerometers away from the point JSBSim reads them at: w_dot x r + w x (w x r), JSBSim's own w_dot
            w = [fdm[f"velocities/{a}-rad_sec"] for a in "pqr"]
            w_dot = [fdm[f"accelerations/{a}dot-rad_sec2"] for a in "pqr"]
            extra = np.cross(w_dot, imu) + np.cross(w, np.cross(w, imu))
            for col, a in zip(("ax_m_s2", "ay_m_s2", "az_m_s2"), extra):
                row[col] += float(a)
        if ac.spec.get("air_data"):  # a data system's density from static pressure and outside air temperature
            row["density_kg_m3"] = fdm["atmosphere/rho-slugs_ft3"] * SLUG_FT3
        rows.append(row)

    log(0.0)
    for k in range(1, n_steps + 1):
        t = k * dt
        c = cmd(t)
        for s in surfaces:
            target = trim[s] + c[s]
            step = (target - pos[s]) * (1.0 - math.exp(-dt / tau_act))
            pos[s] += max(-rate_max * dt, min(rate_max * dt, step))
            hist[s].append(pos[s])
            d = pos[s]
            if s in delay:  # continuous-time delay at the sim rate, linear interpolation
                back = delay[s] / dt
                i = len(hist[s]) - 1 - back
                i0 = max(0, int(math.floor(i)))
                fr = i - math.floor(i) if i >= 0 else 0.0
                d = hist[s][i0] if i0 + 1 >= len(hist[s]) else (1 - fr) * hist[s][i0] + fr * hist[s][i0 + 1]
            if s in lag:
                lagged[s] += (d - lagged[s]) * (1.0 - math.exp(-dt / lag[s]))
                d = lagged[s]
            fdm[f"gen/drive/{s}-rad"] = d
        fdm.run()
        if k % per_log == 0:
            log(t)
    return rows


def sensors(rows, effects, noise_level, rng):
    cols = list(rows[0].keys())
    data = {c: np.array([r[c] for r in rows]) for c in cols}
    for e in effects:
        if e["effect"] == "sensor_scale":
            data[e["target"]] = data[e["target"]] * e["value"]
        elif e["effect"] == "sensor_bias":
            data[e["target"]] = data[e["target"]] + e["value"]
    for c, sd in NOISE.items():
        data[c] = data[c] + rng.normal(0.0, sd * noise_level, len(rows))
    data["psi_rad"] = np.mod(data["psi_rad"] + math.pi, 2 * math.pi) - math.pi
    return cols, data


def write_csv(path, cols, data, meta):
    with open(path, "w") as f:
        for k, v in meta.items():
            f.write(f"# {k}: {v}\n")
        f.write(",".join(cols) + "\n")
        for i in range(len(data["time_s"])):
            f.write(",".join(f"{data[c][i]:.9g}" for c in cols) + "\n")


# The catalogue the effects are drawn from: (effect, target, magnitude range, both signs, null)
DEG = math.pi / 180
SURFACE_NAMES = ["elevator", "aileron", "rudder"]
CATALOGUE = (
    [("input_delay", s, (0.05, 0.15), False, 0.0) for s in SURFACE_NAMES]
    + [("actuator_lag", s, (0.08, 0.25), False, 0.0) for s in SURFACE_NAMES]
    + [("control_effectiveness", s, (0.25, 0.5), True, 1.0) for s in SURFACE_NAMES]
    + [("sensor_bias", c, r, True, 0.0) for c, r in [
        ("phi_rad", (1.0 * DEG, 2.0 * DEG)), ("theta_rad", (1.0 * DEG, 2.0 * DEG)),
        ("p_rad_s", (0.5 * DEG, 1.0 * DEG)), ("q_rad_s", (0.5 * DEG, 1.0 * DEG)), ("r_rad_s", (0.5 * DEG, 1.0 * DEG)),
        ("alpha_rad", (1.0 * DEG, 2.0 * DEG)), ("beta_rad", (1.0 * DEG, 2.0 * DEG)),
        ("ax_m_s2", (0.2, 0.4)), ("ay_m_s2", (0.2, 0.4)), ("az_m_s2", (0.2, 0.4))]]
    + [("sensor_scale", c, (0.1, 0.2), True, 1.0) for c in
       ["p_rad_s", "q_rad_s", "r_rad_s", "alpha_rad", "beta_rad", "phi_rad", "theta_rad"]]
    + [("aero_derivative", d, (0.3, 0.6), True, 1.0) for d in
       ["CL_alpha", "Cm_alpha", "Cm_q", "Cm_de", "Cl_beta", "Cl_p", "Cl_da", "Cn_beta", "Cn_r", "Cn_dr", "CY_beta"]]
    + [("aero_nonlinearity", "Cm_alpha2", (4.0, 8.0), True, 0.0),
       ("aero_nonlinearity", "CL_alpha2", (15.0, 30.0), True, 0.0)]
)


def catalogue(spec):
    """CATALOGUE for one aircraft: without the derivatives and added terms it lacks, with its own ranges."""
    out = []
    for eff, target, r, both, null in CATALOGUE:
        if (eff == "aero_derivative" and target not in spec["derivatives"]) or \
                (eff == "aero_nonlinearity" and target not in spec["added"]):
            continue
        out.append((eff, target, spec["ranges"].get((eff, target), r), both, null))
    return out


def draw_effects(rng, n, cat, unlogged=()):
    """n distinct effects from the catalogue cat; none on a sensor in `unlogged` (a column the records leave
    out)."""
    effects, used = [], set()
    while len(effects) < n:
        eff, target, (lo, hi), both, null = cat[rng.integers(len(cat))]
        key = (eff if eff not in ("input_delay", "actuator_lag", "control_effectiveness") else "signal", target)
        if key in used or (eff, target) in used or target in unlogged:
            continue
        used.add(key)
        used.add((eff, target))
        m = rng.uniform(lo, hi)
        sign = rng.choice([-1.0, 1.0]) if both else 1.0
        value = null + sign * m
        effects.append({"effect": eff, "target": target, "value": float(value)})
    return effects


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--aircraft", default="c172x", choices=sorted(AIRCRAFT), help="the JSBSim model flown")
    ap.add_argument("--cases", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--turbulence", action="store_true")
    ap.add_argument("--clean-share", type=float, default=0.25)
    ap.add_argument("--multi-share", type=float, default=0.25)
    ap.add_argument("--stratified", action="store_true",
                    help="the mix by case index instead of by chance: i mod 4 = 0 clean, 3 two or three effects, "
                         "else one (40 cases: 10 clean, 20 single, 10 with two or more)")
    ap.add_argument("--first", type=int, default=0, help="first case index (for splitting work)")
    ap.add_argument("--effects", default=None,
                    help="JSON list of effects for every case instead of random draws ('[]' = clean)")
    ap.add_argument("--duration", type=float, default=None, help="record length, s (default random in the range)")
    ap.add_argument("--min-duration", type=float, default=30.0, help="shortest random record length, s")
    ap.add_argument("--max-duration", type=float, default=90.0, help="longest random record length, s")
    ap.add_argument("--plan", default=None, choices=sorted(PLANS) + ["random"],
                    help="maneuver plan (default: the four maneuvers in sequence; random: one plan per case)")
    ap.add_argument("--max-noise", type=float, default=1.0,
                    help="highest noise level (multiple of the level-1 noise; the level is drawn from 0.5 up)")
    ap.add_argument("--without", default="",
                    help="comma-separated sensor columns the records leave out (a log without them, e.g. "
                         "alpha_rad,beta_rad,ax_m_s2,ay_m_s2,az_m_s2: no vanes, no accelerometers); no effect is "
                         "drawn on them")
    ap.add_argument("--property", action="append", default=[], metavar="NAME=VALUE",
                    help="a JSBSim property set before every trim, after the aircraft's own (repeatable): a loading "
                         "other than the model's, e.g. propulsion/tank[0]/contents-lbs=30 (written to the truth's "
                         "\"properties\")")
    ap.add_argument("--air-data", action="store_true",
                    help="also log density_kg_m3, the air density a data system computes from static pressure and "
                         "outside air temperature (with --property atmosphere/delta-T=R: a day R deg Rankine warmer "
                         "than the standard atmosphere)")
    ap.add_argument("--imu-offset", default=None, metavar="X,Y,Z",
                    help="the accelerometers sit X,Y,Z metres (body axes: forward, right, down) from the point JSBSim "
                         "reads its accelerations at (the aircraft's eyepoint), as a data system's IMU seldom sits "
                         "where the model reads them; the truth gets \"imu_offset_m\"")
    ap.add_argument("--reverse", default="", metavar="COLUMNS",
                    help="comma-separated surface columns logged with the other sign (a data system's convention: "
                         "a servo output, an aileron logged right minus left, an elevator positive trailing edge "
                         "up); the truth gets \"reversed_columns\"")
    ap.add_argument("--log-from", type=float, default=0.0, metavar="S",
                    help="the log begins S seconds into the flight, as a log cut from a longer flight does (inside "
                         "a maneuver or a transient), its clock starting at 0 there; the truth gets \"log_from_s\"")
    args = ap.parse_args()
    loading = {}
    for setting in args.property:
        name, eq, value = setting.partition("=")
        try:
            loading[name.strip()] = float(value)
        except ValueError:
            eq = ""
        if not eq or not name.strip():
            ap.error(f"--property {setting}: expected NAME=VALUE with a number")
    unlogged = {c for c in args.without.split(",") if c}
    unknown = unlogged - {c for c, _, _ in LOGGED}
    if unknown:
        ap.error(f"--without names columns the generator does not log: {', '.join(sorted(unknown))}")
    reversed_columns = [c for c in args.reverse.split(",") if c]
    surfaces = {"elevator_rad", "aileron_rad", "rudder_rad"}
    if set(reversed_columns) - surfaces:
        ap.error(f"--reverse takes surface columns ({', '.join(sorted(surfaces))}), got {args.reverse}")
    spec = dict(AIRCRAFT[args.aircraft])
    spec["pre_ic"] = {**spec["pre_ic"], **loading}
    spec["air_data"] = args.air_data
    if args.imu_offset:
        spec["imu_offset_m"] = [float(v) for v in args.imu_offset.split(",")]
        if len(spec["imu_offset_m"]) != 3:
            sys.exit(f"--imu-offset {args.imu_offset}: three numbers X,Y,Z (m)")
    cat = catalogue(spec)
    if args.effects is not None:
        lacks = [e["target"] for e in json.loads(args.effects)
                 if e["effect"] in ("aero_derivative", "aero_nonlinearity")
                 and e["target"] not in spec["derivatives"] and e["target"] not in spec["added"]]
        if lacks:
            ap.error(f"--effects: the {args.aircraft} model has no {', '.join(lacks)}")
    os.makedirs(args.out, exist_ok=True)
    root = tempfile.mkdtemp(prefix="gen-diag-")
    private_aircraft(root, spec)
    rates = [(100, 20), (100, 25), (100, 50), (120, 40), (200, 50), (200, 40), (120, 20)]
    try:
        aircraft = {}
        for i in range(args.first, args.first + args.cases):
            rng = np.random.default_rng([args.seed, i])
            sim_hz, log_hz = rates[rng.integers(len(rates))]
            # In turbulence every case gets a fresh FGFDMExec: the Dryden filters' states carry over from one
            # flight to the next, so a case would otherwise depend on the cases flown before it.
            if sim_hz not in aircraft or args.turbulence:
                aircraft[sim_hz] = Aircraft(root, sim_hz, spec)
            ac = aircraft[sim_hz]
            u = rng.uniform()
            if args.effects is not None:
                effects = json.loads(args.effects)
            else:
                n = 0 if u < args.clean_share else (1 if u < 1 - args.multi_share else int(rng.integers(2, 4)))
                if args.stratified:
                    n = {0: 0, 3: int(rng.integers(2, 4))}.get(i % 4, 1)
                effects = draw_effects(rng, n, cat, unlogged)
            cond = draw_condition(rng, spec)
            if "limits" in spec["envelope"]:  # a trim point the aircraft cannot hold is drawn again
                cond = trim_point(ac, cond, effects, rng)
                while cond is None:  # nowhere in the envelope (two effects that both cost lift, at their largest)
                    if args.effects is not None:
                        sys.exit(f"case {i}: the {args.aircraft} with {args.effects} trims nowhere in its envelope")
                    print(f"case {i}: {json.dumps(effects)} trims nowhere in the envelope, drawn again",
                          file=sys.stderr)
                    effects = draw_effects(rng, len(effects), cat, unlogged)
                    cond = trim_point(ac, draw_condition(rng, spec), effects, rng)
            duration = args.duration or float(rng.uniform(args.min_duration, args.max_duration))
            noise_level = float(rng.uniform(0.5, args.max_noise))
            plan = None
            if args.plan == "random":
                plan = sorted(PLANS)[int(rng.integers(len(PLANS)))]
            elif args.plan is not None:
                plan = args.plan
            truth = {"effects": effects, "condition": cond, "sim_rate_hz": sim_hz, "log_rate_hz": log_hz,
                     "duration_s": duration, "noise_level": noise_level, "turbulence": args.turbulence,
                     "seed": args.seed, "case": i, "plan": plan or "full", "aircraft": args.aircraft}
            if loading:
                truth["properties"] = loading
            if args.log_from > 0.0:
                truth["log_from_s"] = args.log_from
            if args.imu_offset:
                truth["imu_offset_m"] = spec["imu_offset_m"]
            if reversed_columns:
                truth["reversed_columns"] = reversed_columns
            for part, validation in (("train", False), ("valid", True)):
                rows = fly(ac, cond, effects, duration, log_hz, rng, args.turbulence, validation,
                           PLANS[plan] if plan else None)
                if args.log_from > 0.0:
                    rows = [r for r in rows if r["time_s"] >= args.log_from - 1e-9]
                    if len(rows) < 2:
                        sys.exit(f"case {i}: --log-from {args.log_from} s leaves nothing of its {duration:.1f} s record")
                    t0 = rows[0]["time_s"]
                    for r in rows:
                        r["time_s"] -= t0
                cols, data = sensors(rows, effects, noise_level, rng)
                cols = [c for c in cols if c not in unlogged]
                for c in reversed_columns:
                    data[c] = -data[c]
                write_csv(os.path.join(args.out, f"case_{i:03d}_{part}.csv"), cols, data,
                          {"generator": f"gen_diagnose_records.py (JSBSim {spec['model']}, own API)", "case": i})
            with open(os.path.join(args.out, f"case_{i:03d}_truth.json"), "w") as f:
                json.dump(truth, f, indent=1)
            os.write(_STDOUT, f"case {i}: {json.dumps(effects)}\n".encode())
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
