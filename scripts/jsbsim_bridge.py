#!/usr/bin/env python3
"""flightid's bridge to the official JSBSim (PyPI `jsbsim`): a long-lived batch server.

Protocol (one request = one whole job, arrays come back whole):
  request  : one JSON line on stdin; if it has "payload_f64": N, N little-endian float64 follow as raw bytes.
  response : one JSON line on the protocol stream; if it has "payload_f64": N, N float64 follow as raw bytes.
             {"ok": false, "kind": "...", "error": "..."} on failure; the process stays usable unless
             "fatal" is true.
  commands : `COMMANDS` below names each command's handler and the keys it takes; a missing or unknown key, or an
             unknown command, is a "protocol" error. flightid's side of the messages: src/sim/protocol.rs.

The protocol stream is a duplicate of the original stdout; file descriptor 1 itself is pointed at stderr so that
JSBSim's C++ console output (trim reports, warnings) cannot corrupt the protocol.

Well-behaved simulation (docs/jsbsim.md):
  * every process works in a scratch directory flightid makes and removes (`scratch_dir` of `load`; the bridge
    never makes or removes it, so nothing is left when the bridge is killed); each `load` gets its own root
    inside it: a private copy of the aircraft directory with the aircraft
    XML rewritten, `engine/` and `systems/` linked to the package's, and a private output path;
  * root-level <input> and <output> elements are removed from the private copy: no network listeners, no logs;
  * declared knob properties are added inside <aerodynamics>:
      flightid/override/<surface>      0/1  (1: the aero model reads the bridge's value, bypassing actuators)
      flightid/override/<surface>-rad  the surface deflection the aero model reads when overridden
      flightid/lin/<surface>           0/1  (1: add (command - reference) * 1 rad, for per-radian linearization)
      flightid/lin/<surface>-ref       the command reference for the above
      flightid/knob/<coefficient>      factor on aero/coefficient/<coefficient> (default 1)
    and every property the aero model reads for a surface is replaced by flightid/aero/<surface>-rad.
"""

import array
import json
import math
import os
import shutil
import signal
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

PROTO = os.fdopen(os.dup(1), "wb", buffering=0)
os.dup2(2, 1)  # C++ std::cout now goes to stderr

import numpy  # noqa: E402  (jsbsim imports it anyway)
import jsbsim  # noqa: E402  (after the fd swap so import-time prints cannot reach the protocol)


class BridgeError(Exception):
    def __init__(self, kind, message):
        super().__init__(message)
        self.kind = kind


def send(header, payload=None):
    if payload is not None:
        header["payload_f64"] = len(payload)
    PROTO.write((json.dumps(header) + "\n").encode())
    if payload is not None:
        PROTO.write(payload.tobytes())


def read_exact(n):
    buf = bytearray()
    while len(buf) < n:
        chunk = sys.stdin.buffer.read(n - len(buf))
        if not chunk:
            raise EOFError("stdin closed in the middle of a payload")
        buf.extend(chunk)
    return bytes(buf)


# ----------------------------------------------------------------------------------------------------------
# Private aircraft copy
# ----------------------------------------------------------------------------------------------------------

def knob_function(surface, reads):
    """The aero-side value of a surface: the aircraft's own position, or the bridge's override."""
    p = reads[0]
    xml = f"""
    <function name="flightid/aero/{surface}-rad">
      <sum>
        <product>
          <property>{p}</property>
          <difference><value>1</value><property>flightid/override/{surface}</property></difference>
        </product>
        <product>
          <property>flightid/override/{surface}</property>
          <sum>
            <property>flightid/override/{surface}-rad</property>
            <product>
              <property>flightid/lin/{surface}</property>
              <difference>
                <property>{CMD_PROPERTY[surface]}</property>
                <property>flightid/lin/{surface}-ref</property>
              </difference>
            </product>
          </sum>
        </product>
      </sum>
    </function>"""
    return ET.fromstring(xml)


CMD_PROPERTY = {}

# Aero-model inputs that can be perturbed for derivative evaluation: property -> (variable, factor per unit).
DEG = 57.29577951308232
PROBED = {
    "aero/alpha-rad": ("alpha", 1.0), "aero/alpha-deg": ("alpha", DEG),
    "aero/beta-rad": ("beta", 1.0), "aero/beta-deg": ("beta", DEG),
    "aero/mag-beta-rad": ("beta-mag", 1.0), "aero/mag-beta-deg": ("beta-mag", DEG),
    "velocities/p-aero-rad_sec": ("p", 1.0), "velocities/p-rad_sec": ("p", 1.0),
    "velocities/q-aero-rad_sec": ("q", 1.0), "velocities/q-rad_sec": ("q", 1.0),
    "velocities/r-aero-rad_sec": ("r", 1.0), "velocities/r-rad_sec": ("r", 1.0),
    "aero/alphadot-rad_sec": ("alphadot", 1.0), "aero/alphadot-deg_sec": ("alphadot", DEG),
    "aero/betadot-rad_sec": ("betadot", 1.0), "aero/betadot-deg_sec": ("betadot", DEG),
}
# Probe points of the private copy: original property -> (probe property, variable, factor).
PROBES = {}
# Coefficient function name -> the <axis> it belongs to (LIFT, DRAG, SIDE, ROLL, PITCH, YAW, ...).
AXIS_OF = {}


def make_private_aircraft(root_dir, aircraft, surfaces, aircraft_dir=None):
    """Writes root_dir/aircraft/<aircraft>/ with the rewritten XML; returns the list of coefficient knobs.

    aircraft_dir: a directory holding <aircraft>.xml to use instead of the package's (an exported model)."""
    # a process may load several aircraft one after the other (campaign workers switching aircraft)
    CMD_PROPERTY.clear()
    PROBES.clear()
    AXIS_OF.clear()
    pkg = jsbsim.get_default_root_dir()
    src_dir = aircraft_dir or os.path.join(pkg, "aircraft", aircraft)
    src_xml = os.path.join(src_dir, aircraft + ".xml")
    if aircraft_dir and not os.path.isfile(src_xml):
        raise BridgeError("unknown_aircraft", f"model directory {aircraft_dir} has no {aircraft}.xml")
    if not os.path.isfile(src_xml):
        known = sorted(d for d in os.listdir(os.path.join(pkg, "aircraft"))
                       if os.path.isfile(os.path.join(pkg, "aircraft", d, d + ".xml")))
        raise BridgeError("unknown_aircraft",
                          f"JSBSim has no aircraft model '{aircraft}' (known: {', '.join(known)})")
    for sub in ("engine", "systems"):
        os.symlink(os.path.join(pkg, sub), os.path.join(root_dir, sub))
    dst_dir = os.path.join(root_dir, "aircraft", aircraft)
    os.makedirs(dst_dir)
    for entry in os.listdir(src_dir):
        if entry != aircraft + ".xml":
            os.symlink(os.path.join(src_dir, entry), os.path.join(dst_dir, entry))

    tree = ET.parse(src_xml)
    root = tree.getroot()
    for tag in ("input", "output"):
        for el in root.findall(tag):
            root.remove(el)
    aero = root.find("aerodynamics")
    if aero is None:
        raise BridgeError("bad_aircraft", f"{src_xml} has no <aerodynamics> section")

    # Replace every property the aero model reads for a surface by flightid/aero/<surface>-rad.
    replace = {}
    for surface, spec in surfaces.items():
        CMD_PROPERTY[surface] = spec["command"]
        for p in spec["aero_reads"]:
            replace[p] = f"flightid/aero/{surface}-rad"
        for p in spec.get("aero_reads_abs", []):
            replace[p] = f"flightid/aero/{surface}-mag-rad"
    for el in aero.iter():
        if el.tag in ("property", "independentVar") and el.text and el.text.strip() in replace:
            el.text = replace[el.text.strip()]

    # Probe points: every state variable the aero model reads goes through flightid/probe/<name> = value +
    # perturbation, so stability derivatives can be evaluated from the model's own functions (tables included).
    probes = {}
    for el in aero.iter():
        if el.tag in ("property", "independentVar") and el.text and el.text.strip() in PROBED:
            orig = el.text.strip()
            var, factor = PROBED[orig]
            name = "flightid/probe/" + orig.replace("/", "_")
            probes[orig] = (name, var, factor)
            el.text = name

    knobs = []
    for axis in aero.iter("axis"):
        for fn in axis.iter("function"):
            name = fn.get("name", "")
            if name.startswith("aero/coefficient/"):
                AXIS_OF[name[len("aero/coefficient/"):]] = axis.get("name", "?").upper()
    for fn in aero.iter("function"):
        name = fn.get("name", "")
        if not name.startswith("aero/coefficient/"):
            continue
        coef = name[len("aero/coefficient/"):]
        body = [c for c in list(fn) if c.tag != "description"]
        if len(body) != 1:
            continue
        fn.remove(body[0])
        prod = ET.SubElement(fn, "product")
        knob = ET.SubElement(prod, "property")
        knob.text = f"flightid/knob/{coef}"
        prod.append(body[0])
        knobs.append(coef)

    # Declarations and the surface functions go first in <aerodynamics> (pre-functions run before the axes).
    head = []
    for surface in surfaces:
        for prop, value in ((f"flightid/override/{surface}", 0.0), (f"flightid/override/{surface}-rad", 0.0),
                            (f"flightid/lin/{surface}", 0.0), (f"flightid/lin/{surface}-ref", 0.0)):
            d = ET.Element("property", {"value": repr(value)})
            d.text = prop
            head.append(d)
    for coef in knobs:
        d = ET.Element("property", {"value": "1.0"})
        d.text = f"flightid/knob/{coef}"
        head.append(d)
    for surface, spec in surfaces.items():
        head.append(knob_function(surface, spec["aero_reads"]))
        if spec.get("aero_reads_abs"):
            head.append(ET.fromstring(
                f'<function name="flightid/aero/{surface}-mag-rad"><abs>'
                f'<property>flightid/aero/{surface}-rad</property></abs></function>'))
    for var in sorted({v for v, _ in PROBED.values()}):
        d = ET.Element("property", {"value": "0.0"})
        d.text = f"flightid/probe/d-{var}"
        head.append(d)
    d = ET.Element("property", {"value": "0.0"})
    d.text = "flightid/probe/freeze"
    head.append(d)
    for orig, (name, var, factor) in probes.items():
        d = ET.Element("property", {"value": "0.0"})
        d.text = f"{name}-frozen"
        head.append(d)
        # value = (1 - freeze) * live + freeze * frozen + factor * perturbation
        head.append(ET.fromstring(
            f'<function name="{name}"><sum>'
            f'<product><property>{orig}</property><difference><value>1</value>'
            f'<property>flightid/probe/freeze</property></difference></product>'
            f'<product><property>flightid/probe/freeze</property><property>{name}-frozen</property></product>'
            f'<product><value>{factor!r}</value><property>flightid/probe/d-{var}</property></product>'
            f'</sum></function>'))
    PROBES.update(probes)
    for i, el in enumerate(head):
        aero.insert(i, el)
    add_term_knobs(aero)
    tree.write(os.path.join(dst_dir, aircraft + ".xml"), encoding="utf-8", xml_declaration=True)
    return knobs


# ----------------------------------------------------------------------------------------------------------
# The simulation
# ----------------------------------------------------------------------------------------------------------

# State read from a trimmed aircraft to restore it (Sim.restore).
SNAPSHOT_STATE = [
    "position/ecef-x-ft", "position/ecef-y-ft", "position/ecef-z-ft",
    "attitude/phi-rad", "attitude/theta-rad", "attitude/psi-rad",
    "velocities/u-fps", "velocities/v-fps", "velocities/w-fps",
    "velocities/p-rad_sec", "velocities/q-rad_sec", "velocities/r-rad_sec",
]


def ic_xml(state):
    """A version-2 JSBSim initialization file holding a SNAPSHOT_STATE exactly (repr round-trips float64)."""
    s, r = state, repr
    return (
        '<?xml version="1.0"?>\n<initialize name="flightid" version="2.0">\n'
        f'<position frame="ECEF"><x unit="FT">{r(s["position/ecef-x-ft"])}</x>'
        f'<y unit="FT">{r(s["position/ecef-y-ft"])}</y><z unit="FT">{r(s["position/ecef-z-ft"])}</z></position>\n'
        f'<orientation unit="RAD" frame="LOCAL"><roll>{r(s["attitude/phi-rad"])}</roll>'
        f'<pitch>{r(s["attitude/theta-rad"])}</pitch><yaw>{r(s["attitude/psi-rad"])}</yaw></orientation>\n'
        f'<velocity unit="FT/SEC" frame="BODY"><x>{r(s["velocities/u-fps"])}</x>'
        f'<y>{r(s["velocities/v-fps"])}</y><z>{r(s["velocities/w-fps"])}</z></velocity>\n'
        f'<attitude_rate unit="RAD/SEC" frame="BODY"><roll>{r(s["velocities/p-rad_sec"])}</roll>'
        f'<pitch>{r(s["velocities/q-rad_sec"])}</pitch><yaw>{r(s["velocities/r-rad_sec"])}</yaw></attitude_rate>\n'
        '</initialize>\n')


# The body accelerations a trim makes zero, and how close to zero is trimmed (JSBSim's FGTrim defaults: 1e-3 on
# the translational, 1e-4 on the rotational).
TRIM_ACCELERATIONS = ("accelerations/udot-ft_sec2", "accelerations/vdot-ft_sec2", "accelerations/wdot-ft_sec2",
                      "accelerations/pdot-rad_sec2", "accelerations/qdot-rad_sec2", "accelerations/rdot-rad_sec2")
TRIM_TOLERANCES = (1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4)
# What flightid's own trim accepts when no start reaches TRIM_TOLERANCES: 0.03 ft/s² (a milli-g) on u̇, v̇, ẇ.
# The throttle is not a smooth input on every model (the c310's thrust jumps by 20 lbf within 0.006 of
# throttle), and a milli-g is a tenth of an accelerometer's noise; over a 60 s record it changes the airspeed by
# half a metre per second, which the replay's segment initial states absorb.
TRIM_ACCEPTED = (0.03, 0.03, 0.03, 1e-4, 1e-4, 1e-4)
# The reply key that says which trim found the state: 0 JSBSim's full trim, 1 flightid's own (Sim.newton_trim).
TRIM_METHOD = "flightid/trim-method"
# The keys of a trim request that name the point (not the model changes, knobs, the flight asks for).
TRIM_POINT_KEYS = ("altitude_ft", "speed_kts", "heading_deg", "gamma_deg", "latitude_deg", "longitude_deg", "ic")
# The value of a coefficient knob (flightid/knob/…: a factor) and of an added term (flightid/added/…) that leaves
# the aircraft as configured.
NEUTRAL_KNOB = {"knob": 1.0, "added": 0.0}
# Newton iterations of flightid's own trim, and the forward-difference step of each unknown (rad, or command).
NEWTON_TRIM_ITERATIONS = 20
# A step is halved until the residual falls, down to this share of the Newton step; below it the start has stalled.
NEWTON_TRIM_SMALLEST_STEP = 1.0 / 16.0
# The throttles Newton starts from, in turn, until one ends trimmed.
NEWTON_TRIM_THROTTLES = (0.6, 0.3, 0.9, 0.45, 0.75)
NEWTON_TRIM_STEP = {"alpha": 1e-4, "throttle": 1e-3, "elevator": 1e-3, "aileron": 1e-3, "rudder": 1e-3,
                    "phi": 1e-4}


class Sim:
    def __init__(self, req):
        self.aircraft = req["aircraft"]
        self.dt_s = float(req["dt_s"])
        self.surfaces = req["surfaces"]
        self.engine_running = req.get("engine_running", True)
        self.gear_up = req.get("gear_up", False)
        self.engines = int(req.get("engines", 1))
        scratch = req.get("scratch_dir")
        if not scratch or not os.path.isdir(scratch):
            raise BridgeError("protocol", f"'load' needs an existing scratch_dir, got {scratch!r}")
        self.root = tempfile.mkdtemp(prefix="load-", dir=scratch)
        os.makedirs(os.path.join(self.root, "output"))
        self.aircraft_dir = req.get("aircraft_dir")
        self.knobs = make_private_aircraft(self.root, self.aircraft, self.surfaces, self.aircraft_dir)
        fdm = jsbsim.FGFDMExec(self.root)
        fdm.set_debug_level(0)
        fdm.set_dt(self.dt_s)
        fdm.set_output_path(os.path.join(self.root, "output"))
        if not fdm.load_model(self.aircraft):
            raise BridgeError("load_failed", f"JSBSim could not load aircraft '{self.aircraft}'")
        fdm.disable_output()
        self.fdm = fdm
        self.pm = fdm.get_property_manager()
        self.trimmed = False
        self.trim_method = 0.0
        # Points where JSBSim's trim failed (TRIM_POINT_KEYS of the request) -> flightid's last trim solution there.
        self.newton_starts = {}
        # Trimmed states by trim request (see restore_trim): key -> snapshot, or the trim's BridgeError.
        self.snapshots = {}
        self.ic_path = os.path.join(self.root, "flightid-ic.xml")
        # A fixed initial condition loaded before every trim: it overwrites JSBSim's whole IC object, so the ic/
        # properties a trim sets do not carry round-off of the previous IC (see restore()).
        self.blank_ic_path = os.path.join(self.root, "flightid-blank-ic.xml")
        with open(self.blank_ic_path, "w") as f:
            f.write(ic_xml({k: 0.0 for k in SNAPSHOT_STATE} | {"position/ecef-x-ft": 20925646.32546}))
        # Values, after a model reset, of every property a trim request has set (pre-trim properties, knobs):
        # a trim without that property puts it back, so one process serves several configurations of an aircraft.
        self.pristine = {}

    def close(self):
        shutil.rmtree(self.root, ignore_errors=True)

    def set_rate(self, dt_s):
        """Integrates at another step from the next trim on (a trim is needed before the next flight; trimmed
        snapshots of the former step are dropped)."""
        if not (dt_s > 0.0 and math.isfinite(dt_s)):
            raise BridgeError("protocol", f"'rate' needs a positive dt_s, got {dt_s!r}")
        self.dt_s = dt_s
        self.fdm.set_dt(dt_s)
        self.snapshots.clear()
        self.trimmed = False

    def node(self, name):
        n = self.pm.get_node(name)
        if n is None:
            raise BridgeError("unknown_property", f"aircraft '{self.aircraft}' has no property '{name}'")
        return n

    def set_many(self, props):
        for k, v in props.items():
            self.node(k).set_double_value(float(v))

    def trim(self, req):
        """JSBSim's full trim at the request's point; where it fails, flightid's own (`newton_trim`)."""
        # Which trim a request gets depends on its point and on the aircraft as configured, never on what the
        # process trimmed before, and a search that trims one point with many model changes gets one trim for all
        # of them: a point where JSBSim's trim fails for the aircraft as configured (every coefficient factor 1,
        # every added term 0) is a Newton point, trimmed by flightid's own for every model. Elsewhere a model
        # change that JSBSim cannot trim is a failed trim, as it always was (a fit takes it for a trial that
        # explains nothing). A Newton point is remembered, with the solution found there last: a failed JSBSim
        # trim takes seconds.
        point = json.dumps({k: v for k, v in req.items() if k in TRIM_POINT_KEYS}, sort_keys=True)
        self.start_trim(req)
        if point not in self.newton_starts:
            try:
                self.fdm["simulation/do_simple_trim"] = 1
                self.trim_method = 0.0
            except Exception as e:  # jsbsim.TrimFailureError; the state is garbage afterwards
                if not self.is_newton_point(req):
                    raise BridgeError("trim_failed", f"{self.aircraft} cannot trim at {req['altitude_ft']} ft, "
                                                     f"{req['speed_kts']} kts: {e}")
                self.newton_starts[point] = None
                self.start_trim(req)
                self.newton_starts[point] = self.newton_trim(req, e)
                self.trim_method = 1.0
        else:
            self.newton_starts[point] = self.newton_trim(req, "it fails here", self.newton_starts[point])
            self.trim_method = 1.0
        self.trimmed = True
        self.trim_surface = {s: self.fdm[f"flightid/aero/{s}-rad"] for s in self.surfaces}
        return self.report(req)

    def is_newton_point(self, req):
        """Whether JSBSim's trim fails at the point of `req`, where it has just failed, for the aircraft as
        configured (see `trim`): the request itself when it changes no coefficient, else one more JSBSim trim."""
        knobs = req.get("knobs", {})
        neutral = {k: NEUTRAL_KNOB.get(k.split("/")[1], v) if k.startswith(("flightid/knob/", "flightid/added/"))
                   else v for k, v in knobs.items()}
        if neutral == knobs:
            return True
        self.start_trim(req | {"knobs": neutral})
        try:
            self.fdm["simulation/do_simple_trim"] = 1
            return False
        except Exception:
            return True

    def report(self, req):
        """A trim's reply: the request's `report` properties, and which trim found it (TRIM_METHOD)."""
        return {k: self.fdm[k] for k in req.get("report", [])} | {TRIM_METHOD: self.trim_method}

    def start_trim(self, req):
        """The request's initial condition, run: the state a trim starts from."""
        fdm = self.fdm
        self.trimmed = False
        # Every trim starts from the same state whatever ran before: reset all models (engines, actuators, FCS
        # commands) without running the ICs yet (mode bit 2), so results do not depend on the previous case.
        fdm.reset_to_initial_conditions(2)
        for i in range(self.engines):
            fdm[f"fcs/throttle-cmd-norm[{i}]"] = 0.0
        for p in ("fcs/pitch-trim-cmd-norm", "fcs/roll-trim-cmd-norm", "fcs/yaw-trim-cmd-norm"):
            if self.pm.hasNode(p):
                fdm[p] = 0.0
        for s in self.surfaces:
            fdm[f"flightid/override/{s}"] = 0.0
            fdm[f"flightid/lin/{s}"] = 0.0
        for s, spec in self.surfaces.items():
            fdm[spec["command"]] = 0.0
        # Initial-condition order matters (docs/jsbsim.md): position, altitude, speed, heading, gamma.
        fdm.load_ic(self.blank_ic_path, False)
        fdm["ic/lat-geod-deg"] = float(req.get("latitude_deg", 0.0))
        fdm["ic/long-gc-deg"] = float(req.get("longitude_deg", 0.0))
        fdm["ic/h-sl-ft"] = float(req["altitude_ft"])
        fdm["ic/vt-kts"] = float(req["speed_kts"])
        fdm["ic/psi-true-deg"] = float(req.get("heading_deg", 0.0))
        fdm["ic/gamma-deg"] = float(req.get("gamma_deg", 0.0))
        for k, v in req.get("ic", {}).items():
            fdm[k] = float(v)
        self.set_knobs(req.get("knobs", {}))
        fdm.set_dt(self.dt_s)
        if not fdm.run_ic():
            raise BridgeError("trim_failed", "JSBSim rejected the initial conditions (run_ic failed)")
        if self.engine_running:
            fdm["propulsion/set-running"] = -1
        if self.gear_up:
            fdm["gear/gear-cmd-norm"] = 0.0
            fdm["gear/gear-pos-norm"] = 0.0

    def newton_trim(self, req, jsbsim_error, start=None):
        """Straight flight at the request's point by Newton's method on all trim unknowns at once, from the state
        `start_trim` left; raises `trim_failed` naming JSBSim's error and where this one ended.

        JSBSim's trim adjusts one control per acceleration in turn (FGTrim: α for ẇ, throttle for u̇, the pitch
        trim for q̇, φ for v̇, aileron for ṗ, rudder for ṙ), and on some models it fails at points between points
        it trims (JSBSim 1.3.3's c310 at 4 000 ft: 116 and 128 kts trim, 120 and 124 kts do not). Here the unknowns
        x = (α, throttle, elevator, aileron and rudder commands, φ), with β = 0 and the request's flight path
        angle, are solved together for zero body accelerations f(x) = (u̇, v̇, ẇ, ṗ, q̇, ṙ): the Jacobian by
        forward differences, a damped step x ← x − λ J⁻¹ f halved until the scaled residual falls, every unknown
        kept within its range. Each f(x) restores the state and commands exactly as a trimmed snapshot is
        restored (`restore`): actuators at their commands, engines at their steady state. Newton starts from
        `start` (an earlier solution at this point) when given, else from NEWTON_TRIM_THROTTLES in turn; returns
        the solution."""
        fdm = self.fdm
        knobs = req.get("knobs", {})
        position = {k: fdm[k] for k in SNAPSHOT_STATE[:3]}
        psi = fdm["attitude/psi-rad"]
        speed = fdm["velocities/vt-fps"]
        gamma = math.radians(float(req.get("gamma_deg", 0.0)))
        held = {k: fdm[k] for k in self.trim_commands()}
        unknowns = [("alpha", -0.10, 0.30), ("throttle", 0.0, 1.0)]
        unknowns += [(s, -1.0, 1.0) for s in ("elevator", "aileron", "rudder") if s in self.surfaces]
        unknowns += [("phi", -0.5, 0.5)]
        names = [u[0] for u in unknowns]
        if len(names) != len(TRIM_ACCELERATIONS):
            raise BridgeError("trim_failed", f"{self.aircraft} cannot trim at {req['altitude_ft']} ft, "
                                             f"{req['speed_kts']} kts: {jsbsim_error} (and without an elevator, "
                                             "aileron and rudder flightid's own trim cannot run)")

        def accelerations(x):
            v = dict(zip(names, x))
            alpha, phi = v["alpha"], v["phi"]
            # climb rate u sinθ − w cosφ cosθ = V sinγ with β = 0
            a, b = math.cos(alpha), math.sin(alpha) * math.cos(phi)
            theta = math.atan2(b, a) + math.asin(max(-1.0, min(1.0, math.sin(gamma) / math.hypot(a, b))))
            state = position | {
                "attitude/phi-rad": phi, "attitude/theta-rad": theta, "attitude/psi-rad": psi,
                "velocities/u-fps": speed * math.cos(alpha), "velocities/v-fps": 0.0,
                "velocities/w-fps": speed * math.sin(alpha),
                "velocities/p-rad_sec": 0.0, "velocities/q-rad_sec": 0.0, "velocities/r-rad_sec": 0.0}
            commands = dict(held)
            for i in range(self.engines):
                if f"fcs/throttle-cmd-norm[{i}]" in held:
                    commands[f"fcs/throttle-cmd-norm[{i}]"] = v["throttle"]
            for s in ("elevator", "aileron", "rudder"):
                if s in v:
                    commands[self.surfaces[s]["command"]] = v[s]
            self.restore({"state": state, "commands": commands}, knobs)
            return [fdm[k] for k in TRIM_ACCELERATIONS]

        lo = [u[1] for u in unknowns]
        hi = [u[2] for u in unknowns]
        every = range(len(names))

        def merit(f, rows=every):
            return sum((f[i] / TRIM_TOLERANCES[i]) ** 2 for i in rows)

        def trimmed(f, rows=every):
            return all(abs(f[i]) < TRIM_TOLERANCES[i] for i in rows)

        def newton(x, free=every, rows=every):
            """Newton on the unknowns `free` for the accelerations `rows` (as many), the other unknowns held."""
            f = accelerations(x)
            for _ in range(NEWTON_TRIM_ITERATIONS):
                if trimmed(f, rows):
                    break
                jac = []
                for j in free:
                    h = NEWTON_TRIM_STEP[names[j]]
                    xj = list(x)
                    xj[j] += h if xj[j] + h <= hi[j] else -h
                    fj = accelerations(xj)
                    jac.append([(fj[i] - f[i]) / (xj[j] - x[j]) for i in rows])
                try:  # jac holds the Jacobian's columns
                    step = numpy.linalg.solve(numpy.array(jac).T, [-f[i] for i in rows]).tolist()
                except numpy.linalg.LinAlgError:  # an unknown that moves no acceleration
                    break
                lam, m0 = 1.0, merit(f, rows)
                while lam >= NEWTON_TRIM_SMALLEST_STEP:
                    xn = list(x)
                    for j, d in zip(free, step):
                        xn[j] = min(hi[j], max(lo[j], x[j] + lam * d))
                    fn = accelerations(xn)
                    if merit(fn, rows) < m0:
                        x, f = xn, fn
                        break
                    lam *= 0.5
                else:
                    break
            return x, f

        # Thrust need not rise with the throttle, nor continuously: the c310's propeller governor makes it dip (at
        # 4 000 ft, 120 kts: 227.6 lbf at throttle 0.720, 224.3 at 0.727) and jump (205.9 lbf at 0.702, 225.7 at
        # 0.708), and a Newton step stalls there. So it starts again from other throttles, the best ending kept;
        # where none trims, the throttle is held where the best ended and the other five unknowns are solved for
        # v̇, ẇ, ṗ, q̇, ṙ, which leaves u̇ to the acceptance (TRIM_ACCEPTED).
        best = None
        starts = [[0.05, throttle] + [0.0] * (len(names) - 2) for throttle in NEWTON_TRIM_THROTTLES]
        for x0 in ([start] if start else []) + starts:
            x, f = newton(x0)
            if best is None or merit(f) < merit(best[1]):
                best = (x, f)
            if trimmed(f):
                break
        if not trimmed(best[1]):
            best = newton(best[0], [i for i in every if names[i] != "throttle"], every[1:])
        x, f = best
        f = accelerations(x)
        if not all(abs(fi) < tol for fi, tol in zip(f, TRIM_ACCEPTED)):
            ended = ", ".join(f"{n} {xi:.4g}" for n, xi in zip(names, x))
            worst = max(range(len(f)), key=lambda i: abs(f[i]) / TRIM_ACCEPTED[i])
            raise BridgeError(
                "trim_failed",
                f"{self.aircraft} cannot trim at {req['altitude_ft']} ft, {req['speed_kts']} kts: JSBSim's trim "
                f"failed ({jsbsim_error}), and flightid's own ended at {ended} with "
                f"{TRIM_ACCELERATIONS[worst]} = {f[worst]:.3g}")
        return x

    def set_knobs(self, knobs):
        """Sets a trim request's knobs and pre-trim properties (right after a model reset); every property an
        earlier request set and this one does not goes back to its value after a reset in a fresh process."""
        for k in knobs:
            if k not in self.pristine:
                self.pristine[k] = self.node(k).get_double_value()
        self.set_many({k: v for k, v in self.pristine.items() if k not in knobs})
        self.set_many(knobs)

    def trim_commands(self):
        """Properties that hold the trim: throttles, mixtures, trim tabs, surface commands."""
        names = [f"fcs/{c}-cmd-norm[{i}]" for c in ("throttle", "mixture") for i in range(self.engines)]
        names += ["fcs/pitch-trim-cmd-norm", "fcs/roll-trim-cmd-norm", "fcs/yaw-trim-cmd-norm"]
        # a glider has no mixture, a model may lack a trim tab
        names = [p for p in names if self.pm.hasNode(p)]
        names += [spec["command"] for spec in self.surfaces.values()]
        return names

    def snapshot(self):
        """The trimmed state: ECEF position, Euler angles, body velocities and rates, and the trim commands."""
        fdm = self.fdm
        return {
            "state": {k: fdm[k] for k in SNAPSHOT_STATE},
            "commands": {k: fdm[k] for k in self.trim_commands()},
            "method": self.trim_method,
        }

    def restore(self, snap, knobs):
        """Puts the aircraft back into a snapshot's trimmed state (JSBSim 1.3.3 has no state save/restore).

        The result is a function of the snapshot alone, whatever ran before (checked bit for bit):
          * all models are reset (mode 2: without running the ICs);
          * the initial condition is loaded from a version-2 IC file (ECEF position, local Euler angles, body
            velocity and rates), which overwrites every part of JSBSim's IC object; setting ic/ properties one by
            one would keep round-off of the previous IC (a 1e-13 fps "wind");
          * run_ic() twice: the first run lets the mass balance see the reset tanks (otherwise its CG-shift
            "nudge" moves the aircraft by the fuel the previous flight burned), the second starts clean;
          * engines set running, the trim commands set again (set-running puts throttles and mixtures to 1),
            one model pass in trim mode (actuators snap to their commands) and the engines' steady state;
          * a last run_ic, so forces and the integrators' derivative history come from the trimmed thrust.
        Against a live trim: max |dtheta| over a 20 s elevator doublet 8e-9 rad on c172x (engine temperatures,
        which JSBSim does not let us set, differ), 1e-15 rad on the 737.
        """
        fdm = self.fdm
        with open(self.ic_path, "w") as f:
            f.write(ic_xml(snap["state"]))
        self.trimmed = False
        fdm.reset_to_initial_conditions(2)
        for surface in self.surfaces:
            fdm[f"flightid/override/{surface}"] = 0.0
            fdm[f"flightid/lin/{surface}"] = 0.0
        self.set_knobs(knobs)
        commands = snap["commands"]
        self.set_many(commands)
        fdm.set_dt(self.dt_s)
        for _ in range(2):
            fdm.load_ic(self.ic_path, False)
            if not fdm.run_ic():
                raise BridgeError("trim_failed", "JSBSim rejected the restored trim state (run_ic failed)")
        if self.engine_running:
            fdm["propulsion/set-running"] = -1
        if self.gear_up:
            fdm["gear/gear-cmd-norm"] = 0.0
            fdm["gear/gear-pos-norm"] = 0.0
        self.set_many(commands)
        fdm.set_trim_status(True)
        fdm.suspend_integration()
        try:
            fdm.run()
            if self.engine_running:
                fdm.get_propulsion().get_steady_state()
        finally:
            fdm.set_trim_status(False)
            fdm.resume_integration()
            fdm.set_dt(self.dt_s)
        # Once more with the engines at their steady state: forces, moments and the integrators' derivative
        # history are computed from the trimmed thrust, not from the full-throttle state set-running left.
        fdm.load_ic(self.ic_path, False)
        if not fdm.run_ic():
            raise BridgeError("trim_failed", "JSBSim rejected the restored trim state (run_ic failed)")
        self.trimmed = True
        self.trim_surface = {sf: fdm[f"flightid/aero/{sf}-rad"] for sf in self.surfaces}

    def restore_trim(self, req):
        """Trim once per trim request and process, then fly every case from the restored snapshot.

        The first request for a point runs the full trim and snapshots it; that and every later request restore
        the snapshot (~0.5 ms instead of a 3-9 ms trim), so no case ever flies from the live post-trim state
        and a case's result does not depend on what the process ran before."""
        key = json.dumps({k: v for k, v in req.items() if k not in ("cmd", "report", "reuse")}, sort_keys=True)
        snap = self.snapshots.get(key)
        if snap is None:
            try:
                self.trim(req)
                snap = self.snapshot()
            except BridgeError as e:
                snap = e
            self.snapshots[key] = snap
        if isinstance(snap, BridgeError):
            self.trimmed = False
            raise snap
        self.restore(snap, req.get("knobs", {}))
        self.trim_method = snap["method"]
        return self.report(req)

    def linearize(self, req):
        """JSBSim's FGLinearization at the current trim; per-radian inputs when the surfaces are overridden."""
        if not self.trimmed:
            raise BridgeError("not_trimmed", "linearize needs a successful trim first")
        fdm = self.fdm
        per_radian = req.get("per_radian_surfaces", [])
        for s in per_radian:
            cmd = self.surfaces[s]["command"]
            fdm[f"flightid/override/{s}-rad"] = fdm[f"flightid/aero/{s}-rad"]
            fdm[f"flightid/lin/{s}-ref"] = fdm[cmd]
            fdm[f"flightid/lin/{s}"] = 1.0
            fdm[f"flightid/override/{s}"] = 1.0
        try:
            lin = jsbsim.FGLinearization(fdm)
            a, b, c, d = lin.state_space
        finally:
            for s in per_radian:
                fdm[f"flightid/lin/{s}"] = 0.0
                fdm[f"flightid/override/{s}"] = 0.0
            # FGLinearization leaves integration suspended (dt = 0): restore it, or later runs stand still.
            if fdm.integration_suspended():
                fdm.resume_integration()
            fdm.set_dt(self.dt_s)
        return {
            "states": list(lin.x_names), "state_units": list(lin.x_units),
            "inputs": list(lin.u_names), "input_units": list(lin.u_units),
            "outputs": list(lin.y_names), "output_units": list(lin.y_units),
            "A": a.tolist(), "B": b.tolist(), "C": c.tolist(), "D": d.tolist(),
        }

    def probe(self, req):
        """Aerodynamic forces and moments at the trim, with one aero input perturbed at a time (central differences).

        Integration is suspended while probing (dt = 0), so fdm.run() re-evaluates the model without moving the
        state. Returns, per perturbation name, the axis totals at +h and -h, plus the unperturbed values and the
        flight condition, mass, inertia and geometry.
        """
        if not self.trimmed:
            raise BridgeError("not_trimmed", "probe needs a successful trim first")
        fdm = self.fdm
        # Axis totals are sums of the aircraft's own coefficient functions (about the aero reference point, in the
        # axes the model declares), so the derivatives are the model's, not the CG-transferred body forces.
        axes = {}
        for coef, axis in AXIS_OF.items():
            axes.setdefault(axis, []).append(self.node("aero/coefficient/" + coef).get_double_value)
        extra = {p: self.node(p).get_double_value for p in req.get("extra", [])}

        def read():
            vals = {axis: sum(g() for g in getters) for axis, getters in axes.items()}
            vals.update({k: g() for k, g in extra.items()})
            return vals

        fdm.suspend_integration()
        try:
            fdm.run()
            # Freeze every aero input at its trim value: otherwise a perturbed force changes the state derivatives,
            # and the next evaluation sees a different alphadot (JSBSim computes it from the previous step).
            for orig, (name, _var, _factor) in PROBES.items():
                fdm[f"{name}-frozen"] = fdm[orig]
            fdm["flightid/probe/freeze"] = 1.0
            fdm.run()
            base = read()
            out = {}
            for var, h in req["perturb"].items():
                vals = []
                for sign in (1.0, -1.0):
                    if var.startswith("surface:"):
                        s = var.split(":", 1)[1]
                        ref = self.trim_surface[s]
                        fdm[f"flightid/override/{s}-rad"] = ref + sign * h
                        fdm[f"flightid/override/{s}"] = 1.0
                    else:
                        fdm[f"flightid/probe/d-{var}"] = sign * h
                        if var == "beta":
                            # terms in |beta| see the same perturbation through |beta0 + dbeta| - |beta0|, so a
                            # kink at beta = 0 (c172x CDbeta) shows in the one-sided differences
                            beta0 = fdm["aero/beta-rad"]
                            fdm["flightid/probe/d-beta-mag"] = abs(beta0 + sign * h) - abs(beta0)
                    fdm.run()
                    vals.append(read())
                    if var.startswith("surface:"):
                        s = var.split(":", 1)[1]
                        fdm[f"flightid/override/{s}"] = 0.0
                    else:
                        fdm[f"flightid/probe/d-{var}"] = 0.0
                        fdm["flightid/probe/d-beta-mag"] = 0.0
                out[var] = {"plus": vals[0], "minus": vals[1], "h": h}
            fdm["flightid/probe/freeze"] = 0.0
            fdm.run()
        finally:
            fdm["flightid/probe/freeze"] = 0.0
            fdm.resume_integration()
            fdm.set_dt(self.dt_s)
        cond = {k: fdm[k] for k in req.get("condition", [])}
        return {"base": base, "perturbed": out, "condition": cond}

    def reset_state(self, state):
        """Sets the aircraft's state mid-flight (the start of a multiple-shooting segment): Euler angles phi and
        theta (rad), body velocities u, v, w (ft/s), body rates p, q, r (rad/s) and altitude h (ft, a shift along
        the local vertical); with "relative" set, the values are added to the current ones. Every key left out,
        the heading and the horizontal position keep their current values. Loaded as a version-2 IC file (see restore()), then run_ic(); the engines, actuators and surface
        drives keep their state."""
        fdm = self.fdm
        cur = {k: fdm[k] for k in SNAPSHOT_STATE}
        keys = {"phi": "attitude/phi-rad", "theta": "attitude/theta-rad", "u": "velocities/u-fps",
                "v": "velocities/v-fps", "w": "velocities/w-fps", "p": "velocities/p-rad_sec",
                "q": "velocities/q-rad_sec", "r": "velocities/r-rad_sec"}
        relative = bool(state.get("relative", False))
        for k, prop in keys.items():
            if k in state:
                cur[prop] = float(state[k]) + (cur[prop] if relative else 0.0)
        if "h" in state:
            dh = float(state["h"]) - (0.0 if relative else fdm["position/h-sl-ft"])
            lat, lon = fdm["position/lat-geod-rad"], fdm["position/long-gc-rad"]
            up = (math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat))
            for axis, c in zip("xyz", up):
                cur[f"position/ecef-{axis}-ft"] += dh * c
        with open(self.ic_path, "w") as f:
            f.write(ic_xml(cur))
        fdm.load_ic(self.ic_path, False)
        if not fdm.run_ic():
            raise BridgeError("sim_stopped", "JSBSim rejected a segment's initial state (run_ic failed)")

    def fly(self, req, payload):
        """Runs n_steps from the current (trimmed) state; returns the recorded properties, step-major."""
        if not self.trimmed:
            raise BridgeError("not_trimmed", "fly needs a successful trim first")
        if self.fdm["simulation/dt"] <= 0.0:
            raise BridgeError("sim_held", "JSBSim integration is suspended (dt = 0); refusing to fly a frozen state")
        n_steps = int(req["n_steps"])
        record_every = int(req.get("record_every", 1))
        drives = req["drives"]  # [{"property": name, "offset": k}] k = start of its n_steps values in payload
        rec_nodes = [self.node(p) for p in req["record"]]
        drive_nodes = [self.node(d["property"]) for d in drives]
        for k, v in req.get("set_before", {}).items():
            self.node(k).set_double_value(float(v))
        u = payload
        offsets = [d["offset"] for d in drives]
        pairs = list(zip(drive_nodes, offsets))
        out = array.array("d")
        get = [n.get_double_value for n in rec_nodes]
        run = self.fdm.run
        # State resets: after step j (j = 0: before the first) the state is set to the given one, before recording.
        resets = {int(r["step"]): r["state"] for r in req.get("resets", [])}
        t0 = time.perf_counter()
        if 0 in resets:
            self.reset_state(resets[0])
        for g in get:
            out.append(g())
        for k in range(n_steps):
            for node, off in pairs:
                node.set_double_value(u[off + k])
            if not run():
                raise BridgeError("sim_stopped", f"JSBSim stopped at step {k}")
            if k + 1 in resets:
                self.reset_state(resets[k + 1])
            if (k + 1) % record_every == 0:
                for g in get:
                    out.append(g())
        elapsed = time.perf_counter() - t0
        self.trimmed = False
        return {"n_records": len(out) // max(1, len(get)), "loop_s": elapsed}, out


# ----------------------------------------------------------------------------------------------------------
# Added aerodynamic terms and model export (flightid diagnose)
# ----------------------------------------------------------------------------------------------------------

# Added nonlinear terms: name -> (axis, factors of the force/moment); the coefficient is the declared property
# flightid/added/<name> (default 0), e.g. Cm_alpha2: dM = qbar S cbar k alpha^2.
ADDED_TERMS = {
    "Cm_alpha2": ("PITCH", ["aero/qbar-psf", "metrics/Sw-sqft", "metrics/cbarw-ft", "aero/alpha-rad",
                            "aero/alpha-rad"]),
    "CL_alpha2": ("LIFT", ["aero/qbar-psf", "metrics/Sw-sqft", "aero/alpha-rad", "aero/alpha-rad"]),
}


# Added terms the loaded aircraft offers (its model has the axis the term belongs to).
ADDED = []


def added_term_function(name, coefficient):
    """<function> of an added term; coefficient: a property name (knob) or a number (baked value)."""
    _axis, factors = ADDED_TERMS[name]
    last = (f"<property>{coefficient}</property>" if isinstance(coefficient, str)
            else f"<value>{coefficient!r}</value>")
    props = "".join(f"<property>{p}</property>" for p in factors)
    fname = f"flightid/added/{name}-term" if isinstance(coefficient, str) else f"flightid/fitted/{name}-term"
    return ET.fromstring(f'<function name="{fname}"><product>{props}{last}</product></function>')


def add_term_knobs(aero):
    """Declares flightid/added/<name> = 0 and adds each term to its axis (nothing changes until a knob is set)."""
    ADDED.clear()
    axes = {a.get("name", "").upper(): a for a in aero.iter("axis")}
    for i, name in enumerate(sorted(ADDED_TERMS)):
        d = ET.Element("property", {"value": "0.0"})
        d.text = f"flightid/added/{name}"
        aero.insert(i, d)
        axis = axes.get(ADDED_TERMS[name][0])
        if axis is not None:
            axis.append(added_term_function(name, f"flightid/added/{name}"))
            ADDED.append(name)


def export_aircraft(sim, req):
    """Writes req["dir"]/<aircraft>.xml: the source aircraft with the coefficient factors req["knobs"]
    ({coefficient: factor}) and added terms req["added"] ({name: coefficient}) written into its functions, no
    <input>/<output>; the other files of the aircraft directory are copied. Returns the XML path."""
    pkg = jsbsim.get_default_root_dir()
    src_dir = sim.aircraft_dir or os.path.join(pkg, "aircraft", sim.aircraft)
    dst_dir = req["dir"]
    os.makedirs(dst_dir, exist_ok=True)
    for entry in os.listdir(src_dir):
        src = os.path.join(src_dir, entry)
        if entry != sim.aircraft + ".xml" and os.path.isfile(src) and not entry.endswith(".json"):
            shutil.copy(src, os.path.join(dst_dir, entry))
    tree = ET.parse(os.path.join(src_dir, sim.aircraft + ".xml"))
    root = tree.getroot()
    for tag in ("input", "output"):
        for el in root.findall(tag):
            root.remove(el)
    aero = root.find("aerodynamics")
    knobs = {k: float(v) for k, v in req.get("knobs", {}).items()}
    for fn in aero.iter("function"):
        coef = fn.get("name", "")[len("aero/coefficient/"):]
        if not fn.get("name", "").startswith("aero/coefficient/") or knobs.get(coef, 1.0) == 1.0:
            continue
        body = [c for c in list(fn) if c.tag != "description"]
        if len(body) != 1:
            raise BridgeError("export", f"coefficient {coef} has no single body to scale")
        fn.remove(body[0])
        prod = ET.SubElement(fn, "product")
        ET.SubElement(prod, "value").text = repr(knobs[coef])
        prod.append(body[0])
        desc = fn.find("description")
        note = f" [flightid diagnose: x {knobs[coef]:.6g}]"
        if desc is not None:
            desc.text = (desc.text or "") + note
    axes = {a.get("name", "").upper(): a for a in aero.iter("axis")}
    for name, k in req.get("added", {}).items():
        if name not in ADDED_TERMS:
            raise BridgeError("export", f"unknown added term '{name}' (known: {', '.join(sorted(ADDED_TERMS))})")
        axis = axes.get(ADDED_TERMS[name][0])
        if axis is None:
            raise BridgeError("export", f"aircraft has no {ADDED_TERMS[name][0]} axis for {name}")
        if float(k) != 0.0:
            axis.append(added_term_function(name, float(k)))
    path = os.path.join(dst_dir, sim.aircraft + ".xml")
    tree.write(path, encoding="utf-8", xml_declaration=True)
    return path


# ----------------------------------------------------------------------------------------------------------
# Commands: one handler each, with the keys it takes (the Rust side's types: src/sim/protocol.rs)
# ----------------------------------------------------------------------------------------------------------

class Server:
    """What lives between requests: the loaded aircraft (None before the first 'load')."""

    def __init__(self):
        self.sim = None

    def close(self):
        if self.sim is not None:
            self.sim.close()
            self.sim = None


# Each handler takes (server, request, payload) and returns (reply fields, reply payload or None).

def do_load(server, req, _payload):
    server.close()
    server.sim = Sim(req)
    return {"knobs": server.sim.knobs, "axes": AXIS_OF, "added_terms": sorted(set(ADDED)),
            "jsbsim_version": jsbsim.__version__}, None


# What an airframe description needs from a JSBSim model (`airframe`).
MASS_AND_WING = ("inertia/mass-slugs", "inertia/ixx-slugs_ft2", "inertia/iyy-slugs_ft2", "inertia/izz-slugs_ft2",
                 "inertia/ixz-slugs_ft2", "metrics/Sw-sqft", "metrics/bw-ft", "metrics/cbarw-ft")


def do_airframe(server, req, _payload):
    """Mass, inertia and wing of a JSBSim model at its initial condition, without a trim: what an airframe
    description needs from an aircraft name. The model is loaded from a private copy (no listeners, no logs) in a
    root of its own under `scratch_dir`, run to its initial condition (JSBSim sums the empty weight, point masses
    and tank contents then) and dropped with the root; an aircraft loaded before is dropped too."""
    server.close()
    scratch = req["scratch_dir"]
    if not os.path.isdir(scratch):
        raise BridgeError("protocol", f"'airframe' needs an existing scratch_dir, got {scratch!r}")
    root = tempfile.mkdtemp(prefix="airframe-", dir=scratch)
    try:
        os.makedirs(os.path.join(root, "output"))
        make_private_aircraft(root, req["aircraft"], {}, req.get("aircraft_dir"))
        fdm = jsbsim.FGFDMExec(root)
        fdm.set_debug_level(0)
        fdm.set_output_path(os.path.join(root, "output"))
        if not fdm.load_model(req["aircraft"]):
            raise BridgeError("load_failed", f"JSBSim could not load aircraft '{req['aircraft']}'")
        fdm.disable_output()
        fdm.run_ic()
        xml = os.path.join(root, "aircraft", req["aircraft"], req["aircraft"] + ".xml")
        cg_in = [fdm[f"inertia/cg-{a}-in"] for a in "xyz"]
        values = {p: fdm[p] for p in MASS_AND_WING}
        facts = model_facts(xml)
        facts["responses"] = command_responses(fdm, facts["aero_reads"])
        return {"values": values, "thrust": thrust_line(xml, cg_in), "model": facts}, None
    finally:
        shutil.rmtree(root, ignore_errors=True)


# The pilot commands whose response `command_responses` measures, and the values it sets them to.
PILOT_COMMANDS = {"elevator": "fcs/elevator-cmd-norm", "aileron": "fcs/aileron-cmd-norm",
                  "rudder": "fcs/rudder-cmd-norm"}
COMMAND_LEVELS = (-1.0, -0.25, 0.0, 0.25, 1.0)
# Simulated time the FCS is given to follow each command level (actuator lags and rate limits), s.
COMMAND_SETTLE_S = 1.5


def model_facts(xml_path):
    """What a configuration of the model needs from its XML: its name, the FCS properties its aerodynamics
    read, the number of engines and whether its gear retracts."""
    root = ET.parse(xml_path).getroot()
    aero = root.find("aerodynamics")
    reads = sorted({el.text.strip() for el in (aero.iter() if aero is not None else [])
                    if el.tag in ("property", "independentVar") and el.text and el.text.strip().startswith("fcs/")})
    contacts = list(root.iter("contact"))
    retractable = any((c.findtext("retractable") or "0").strip() == "1" for c in contacts)
    propulsion = root.find("propulsion")
    engines = len(propulsion.findall("engine")) if propulsion is not None else 0
    return {"name": root.get("name", ""), "aero_reads": reads, "engines": engines,
            "retractable_gear": retractable, "levels": list(COMMAND_LEVELS)}


def command_responses(fdm, reads):
    """For each pilot command of PILOT_COMMANDS, the value of every property in `reads` once the FCS has
    followed the command held at each of COMMAND_LEVELS (the others at 0) for COMMAND_SETTLE_S: which surface
    each aero read belongs to, and its deflection per unit command, measured rather than read from the XML."""
    steps = max(1, int(round(COMMAND_SETTLE_S / fdm.get_delta_t())))
    out = {}
    for surface, cmd in PILOT_COMMANDS.items():
        levels = []
        for level in COMMAND_LEVELS:
            for other in PILOT_COMMANDS.values():
                fdm[other] = level if other == cmd else 0.0
            for _ in range(steps):
                fdm.run()
            # (a property JSBSim leaves at NaN is left out: it moves with no command)
            values = {p: fdm[p] for p in reads}
            levels.append({p: v for p, v in values.items() if math.isfinite(v)})
        out[surface] = levels
    for other in PILOT_COMMANDS.values():
        fdm[other] = 0.0
    return out


LENGTH_TO_M = {"IN": 0.0254, "FT": 0.3048, "M": 1.0}
ANGLE_TO_RAD = {"DEG": math.pi / 180.0, "RAD": 1.0}


def thrust_line(xml_path, cg_in):
    """The engines' mean thrust line about the CG from their thrusters' <location> and <orient> (JSBSim's
    structural frame: x aft, y right, z up): {"moment_arm_m": pitching moment per unit thrust (body axes, positive
    nose up: a thrust line below the CG), "inclination_rad": the line's angle above body x, "engines": count}, or
    None for a model without a located thruster."""
    arms, inclinations = [], []
    for engine in ET.parse(xml_path).getroot().iter("engine"):
        thruster = engine.find("thruster")
        loc = thruster.find("location") if thruster is not None else None
        if loc is None:
            continue
        to_m = LENGTH_TO_M.get(loc.get("unit", "IN").upper(), 0.0254)
        pos_m = [float(loc.findtext(a, "0")) * to_m for a in "xyz"]
        cg_m = [c * 0.0254 for c in cg_in]
        # from the CG to the thruster in body axes (x forward, z down)
        r_x, r_z = -(pos_m[0] - cg_m[0]), -(pos_m[2] - cg_m[2])
        orient = thruster.find("orient")
        to_rad = ANGLE_TO_RAD.get(orient.get("unit", "DEG").upper(), 1.0) if orient is not None else 0.0
        pitch = float(orient.findtext("pitch", "0")) * to_rad if orient is not None else 0.0
        yaw = float(orient.findtext("yaw", "0")) * to_rad if orient is not None else 0.0
        # thrust direction (cos θ cos ψ, cos θ sin ψ, −sin θ); M_y = r_z F_x − r_x F_z per unit thrust
        arms.append(r_z * math.cos(pitch) * math.cos(yaw) + r_x * math.sin(pitch))
        inclinations.append(math.atan2(math.sin(pitch), math.cos(pitch) * math.cos(yaw)))
    if not arms:
        return None
    return {"moment_arm_m": sum(arms) / len(arms), "inclination_rad": sum(inclinations) / len(inclinations),
            "engines": len(arms)}


def do_quit(_server, _req, _payload):
    return {}, None


def do_trim(server, req, _payload):
    values = server.sim.restore_trim(req) if req.get("reuse") else server.sim.trim(req)
    return {"values": values}, None


def do_rate(server, req, _payload):
    server.sim.set_rate(float(req["dt_s"]))
    return {}, None


def do_get(server, req, _payload):
    return {"values": {k: server.sim.node(k).get_double_value() for k in req["properties"]}}, None


def do_set(server, req, _payload):
    server.sim.set_many(req["values"])
    return {}, None


def do_probe(server, req, _payload):
    return server.sim.probe(req), None


def do_linearize(server, req, _payload):
    return server.sim.linearize(req), None


def do_export(server, req, _payload):
    return {"path": export_aircraft(server.sim, req)}, None


def do_fly(server, req, payload):
    return server.sim.fly(req, payload)


class Command:
    """A command's handler and keys; `needs_load`: refused with `not_loaded` before the first 'load'."""

    def __init__(self, handler, required=(), optional=(), needs_load=True):
        self.handler = handler
        self.required = required
        self.optional = optional
        self.needs_load = needs_load


COMMANDS = {
    "load": Command(do_load, ("aircraft", "dt_s", "surfaces", "scratch_dir"),
                    ("engine_running", "gear_up", "engines", "aircraft_dir"), needs_load=False),
    "quit": Command(do_quit, needs_load=False),
    "airframe": Command(do_airframe, ("aircraft", "scratch_dir"), ("aircraft_dir",), needs_load=False),
    "trim": Command(do_trim, ("altitude_ft", "speed_kts"),
                    ("heading_deg", "gamma_deg", "latitude_deg", "longitude_deg", "ic", "knobs", "report",
                     "reuse")),
    "rate": Command(do_rate, ("dt_s",)),
    "get": Command(do_get, ("properties",)),
    "set": Command(do_set, ("values",)),
    "probe": Command(do_probe, ("perturb",), ("condition", "extra")),
    "linearize": Command(do_linearize, (), ("per_radian_surfaces",)),
    "export": Command(do_export, ("dir",), ("knobs", "added")),
    "fly": Command(do_fly, ("n_steps", "drives", "record"), ("set_before", "resets", "record_every")),
}

# Keys of the framing, allowed in every request.
FRAMING_KEYS = ("cmd", "payload_f64")


def command_of(req, server):
    """The request's Command once its name and keys are checked (a `protocol` error naming what is wrong), and
    the aircraft is loaded if it needs one (`not_loaded`)."""
    name = req.get("cmd")
    command = COMMANDS.get(name)
    if command is None:
        raise BridgeError("protocol", f"unknown command '{name}'")
    missing = [k for k in command.required if k not in req]
    if missing:
        raise BridgeError("protocol", f"'{name}' needs the key(s) {', '.join(missing)}")
    allowed = set(command.required) | set(command.optional) | set(FRAMING_KEYS)
    unknown = sorted(k for k in req if k not in allowed)
    if unknown:
        raise BridgeError("protocol", f"'{name}' has no key(s) {', '.join(unknown)} "
                                      f"(it takes: {', '.join(command.required + command.optional) or 'none'})")
    if command.needs_load and server.sim is None:
        raise BridgeError("not_loaded", f"'{name}' before 'load'")
    return command


def main():
    # A Ctrl-C reaches the whole process group: flightid handles it (kills this process, removes the scratch
    # directory), so the bridge must not die first and be reported as a crash.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    server = Server()
    stdin = sys.stdin.buffer
    while True:
        line = stdin.readline()
        if not line:
            break
        try:
            req = json.loads(line)
        except json.JSONDecodeError as e:
            send({"ok": False, "kind": "protocol", "error": f"bad request line: {e}", "fatal": True})
            break
        payload = None
        if req.get("payload_f64"):
            payload = array.array("d")
            payload.frombytes(read_exact(8 * int(req["payload_f64"])))
        try:
            command = command_of(req, server)
            fields, out = command.handler(server, req, payload)
            send(dict(ok=True, **fields), out)
        except BridgeError as e:
            send({"ok": False, "kind": e.kind, "error": str(e)})
        except Exception as e:  # a JSBSim exception: report it, keep serving
            send({"ok": False, "kind": "jsbsim", "error": f"{type(e).__name__}: {e}"})
        else:
            if command.handler is do_quit:
                break
    server.close()


if __name__ == "__main__":
    main()
