"""Independent generator of surface-deflection logs for flightid's maneuver detection (`segments`).

Written the way a pilot flies and a data system logs, not the way flightid's `fly` commands inputs:
- pulses with finite rise times (0.08-0.2 s), amplitudes that differ from pulse to pulse (+-25 %) and
  timing that is off by up to +-25 % per pulse;
- trim offsets on every surface, white sensor noise (0.02-0.06 deg), a slow autopilot-like wander
  (0.05-0.1 deg);
- a sample rate drawn from 20-50 Hz.

Record `maneuvers.csv` (about 330 s) holds, in order: an elevator 3-2-1-1, an unequal elevator doublet,
an aileron doublet, a rudder doublet, an aileron bank-to-bank (three rolls with holds at wings level),
an elevator 2-1-1, an elevator frequency sweep, a rudder 3-2-1-1 with loose timing, an aileron doublet
followed half a second later by a recovery held for 12 s; between them things that are not maneuvers: a
turn (roll in, hold 1 deg of aileron for 20 s, roll out), the recovery hold and an elevator trim change
(1 deg, held). Record `level.csv` (120 s) is level flight: noise and wander only.

Usage: gen_maneuver_records.py OUT_DIR SEED
Writes OUT_DIR/maneuvers.csv, OUT_DIR/level.csv and OUT_DIR/truth.json: per maneuver the surface,
start and end time and the kinds a detector may call it.
"""
import json
import os
import sys

import numpy as np


def smooth_step(t, t0, rise):
    """0 before t0, 1 after t0 + rise, a cosine ramp between."""
    x = np.clip((t - t0) / rise, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * x)


class Surface:
    def __init__(self, t, rng):
        self.t, self.rng = t, rng
        self.u = np.zeros_like(t)

    def pulses(self, start, widths_s, amp_rad, signs):
        """A train of pulses back to back with jittered widths, amplitudes and finite rise times."""
        t0 = start
        for w, s in zip(widths_s, signs):
            w = w * self.rng.uniform(0.75, 1.25)
            a = s * amp_rad * self.rng.uniform(0.75, 1.25)
            rise = self.rng.uniform(0.08, 0.2)
            self.u += a * (smooth_step(self.t, t0, rise) - smooth_step(self.t, t0 + w, rise))
            t0 += w
        return t0 + 0.2

    def hold(self, start, duration_s, amp_rad):
        rise = 0.5
        self.u += amp_rad * (smooth_step(self.t, start, rise) - smooth_step(self.t, start + duration_s, rise))


def logged(rng, t, u, trim_rad):
    noise = np.deg2rad(rng.uniform(0.02, 0.06))
    wander = np.deg2rad(rng.uniform(0.05, 0.1))
    phase = rng.uniform(0, 2 * np.pi)
    return trim_rad + u + wander * np.sin(2 * np.pi * t / rng.uniform(15, 30) + phase) + rng.normal(0, noise, len(t))


def write(path, t, cols):
    with open(path, "w") as fh:
        fh.write("time_s," + ",".join(cols) + "\n")
        for k in range(len(t)):
            fh.write(f"{t[k]:.4f}," + ",".join(f"{cols[c][k]:.8f}" for c in cols) + "\n")


def main():
    out, seed = sys.argv[1], int(sys.argv[2])
    rng = np.random.default_rng(seed)
    os.makedirs(out, exist_ok=True)
    rate = rng.uniform(20.0, 50.0)
    t = np.arange(0.0, 330.0, 1.0 / rate)
    el, ai, ru = Surface(t, rng), Surface(t, rng), Surface(t, rng)
    d = np.deg2rad
    truth = []

    def add(surface, name, start, end, kinds):
        truth.append({"surface": name, "start_s": start, "end_s": end, "kinds": kinds})

    s = 10.0
    e = el.pulses(s, [1.2, 0.8, 0.4, 0.4], d(2.5), [1, -1, 1, -1])
    add(el, "elevator_rad", s, e, ["3-2-1-1", "multistep"])
    s = 35.0
    e = el.pulses(s, [1.0, 0.6], d(3.0), [1, -1])
    add(el, "elevator_rad", s, e, ["doublet", "multistep"])
    s = 60.0
    e = ai.pulses(s, [1.0, 1.0], d(5.0), [1, -1])
    add(ai, "aileron_rad", s, e, ["doublet"])
    s = 85.0
    e = ru.pulses(s, [1.5, 1.5], d(4.0), [1, -1])
    add(ru, "rudder_rad", s, e, ["doublet"])
    # bank to bank: roll right, hold level stick, roll left through to the other bank, hold, roll back
    s = 110.0
    t1 = ai.pulses(s, [1.2], d(6.0), [1])
    t2 = ai.pulses(t1 + 3.0, [2.0], d(6.0), [-1])
    e = ai.pulses(t2 + 3.0, [1.2], d(6.0), [1])
    add(ai, "aileron_rad", s, e, ["bank-to-bank"])
    # a turn: roll in, hold, roll out (not a maneuver)
    ai.pulses(140.0, [1.0], d(6.0), [1])
    ai.hold(141.0, 20.0, d(1.0))
    ai.pulses(161.5, [1.0], d(6.0), [-1])
    s = 180.0
    e = el.pulses(s, [1.0, 0.5, 0.5], d(2.0), [1, -1, 1])
    add(el, "elevator_rad", s, e, ["multistep"])
    s = 200.0
    sweep_t = np.clip(t - s, 0.0, 20.0)
    inside = (t >= s) & (t <= s + 20.0)
    el.u += np.where(inside, d(2.0) * np.sin(2 * np.pi * (0.1 * sweep_t + 0.5 * (1.4 / 20.0) * sweep_t**2)), 0.0)
    add(el, "elevator_rad", s, s + 20.0, ["sweep"])
    s = 240.0
    e = ru.pulses(s, [1.5, 1.0, 0.5, 0.5], d(3.0), [1, -1, 1, -1])
    add(ru, "rudder_rad", s, e, ["3-2-1-1", "multistep"])
    # an aileron doublet and, half a second after it, the pilot's recovery: 2 deg held for 12 s (the doublet
    # is a maneuver, the hold is not). Its jitter comes from a generator of its own, so that everything else
    # in the record is as before this case was added.
    extra = Surface(t, np.random.default_rng(seed + 1000))
    s = 255.0
    e = extra.pulses(s, [1.0, 1.0], d(5.0), [1, -1])
    extra.hold(e + 0.5, 12.0, d(-2.0))
    ai.u += extra.u
    add(ai, "aileron_rad", s, e, ["doublet"])
    # an elevator trim change (not a maneuver): 1 deg, held to the end
    el.u += d(1.0) * smooth_step(t, 280.0, 1.0)

    trims = {"elevator_rad": d(rng.uniform(-3, 1)), "aileron_rad": d(rng.uniform(-0.5, 0.5)),
             "rudder_rad": d(rng.uniform(-1, 1))}
    cols = {name: logged(rng, t, surf.u, trims[name])
            for name, surf in (("elevator_rad", el), ("aileron_rad", ai), ("rudder_rad", ru))}
    write(os.path.join(out, "maneuvers.csv"), t, cols)
    tl = np.arange(0.0, 120.0, 1.0 / rate)
    level = {name: logged(rng, tl, np.zeros_like(tl), trims[name]) for name in trims}
    write(os.path.join(out, "level.csv"), tl, level)
    with open(os.path.join(out, "truth.json"), "w") as fh:
        json.dump({"rate_hz": rate, "maneuvers": truth}, fh, indent=1)


if __name__ == "__main__":
    main()
