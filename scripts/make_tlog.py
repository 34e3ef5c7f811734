#!/usr/bin/env python3
"""Encode a flightid flight CSV (docs/data.md) into a MAVLink telemetry log (.tlog) with pymavlink.

Test fixture generator for flightid's .tlog reader. A .tlog is a sequence of
[8-byte big-endian microsecond Unix timestamp][MAVLink frame]; pymavlink's own log writer omits the
timestamps, so they are written here explicitly.

Per CSV row (system 1, component 1), all stamped with the row's time:
  ATTITUDE          phi/theta/psi, p/q/r                      (float32; v1 on odd rows, v2 on even)
  SCALED_IMU        ax/ay/az in milli-g                        (int16;   v1 every third row)
  VFR_HUD           equivalent airspeed (the standard atmosphere at the row's altitude), ground speed = the true
                    airspeed, altitude, throttle percent       (float32 / uint16)
  AOA_SSA           alpha, beta in degrees                     (float32; v2 only, id 11020 > 255)
  SERVO_OUTPUT_RAW  surfaces and throttle in PWM microseconds  (uint16; mapping from --servo-map)
Unrelated traffic: HEARTBEAT and SYS_STATUS from system 1 once per second, and a second system
(id 2) sending HEARTBEAT and a slower ATTITUDE stream (every 10th row) with different values.
Damage on request: --garbage N inserts N runs of random bytes between records, --flip N flips one
byte inside N HEARTBEAT/SYS_STATUS frames, --truncate cuts the last record short.

Prints a JSON summary (frame counts and the damage done) on stdout.

Usage: make_tlog.py IN.csv OUT.tlog --servo-map aircraft/servo_maps/c172x.toml
       [--epoch-us 1700000000000000] [--garbage 3] [--flip 2] [--truncate] [--seed 1]
"""

import argparse
import csv
import json
import math
import random
import struct
import sys
import tomllib

from pymavlink.dialects.v10 import ardupilotmega as mav1
from pymavlink.dialects.v20 import ardupilotmega as mav2

G0 = 9.80665  # standard gravity, m/s^2


def standard_density(altitude_m):
    """Air density of the standard atmosphere in the troposphere at geometric altitude (geopotential with
    JSBSim's Earth radius), kg/m^3."""
    radius, t0, lapse, r_air = 6_356_766.0, 288.15, 0.0065, 287.05287
    h = radius * altitude_m / (radius + altitude_m)
    t = t0 - lapse * h
    p = 101_325.0 * (t / t0) ** (G0 / (r_air * lapse))
    return p / (r_air * t)


def equivalent_per_true(altitude_m):
    """Equivalent over true airspeed at an altitude of the standard atmosphere, sqrt(rho / rho0)."""
    h = min(max(altitude_m, -500.0), 10_900.0)
    return math.sqrt(standard_density(h) / standard_density(0.0))


def read_flight_csv(path):
    """Returns (metadata lines, {column: [floats]}) from a flight CSV with '#' metadata lines."""
    with open(path, newline="") as f:
        lines = [ln for ln in f if not ln.startswith("#")]
    reader = csv.reader(lines)
    header = [h.strip() for h in next(reader)]
    cols = {h: [] for h in header}
    for row in reader:
        if not row:
            continue
        for h, cell in zip(header, row):
            cols[h].append(float(cell))
    return cols


def pwm_of(mapping, rad):
    """Surface deflection (rad) -> PWM microseconds, inverse of flightid's SurfaceMap::to_rad."""
    pwm = mapping["trim_pwm_us"] + mapping["sign"] * rad * mapping["pwm_per_rad"]
    return int(min(65535, max(0, round(pwm))))


def wrap_pi(a):
    return math.atan2(math.sin(a), math.cos(a))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("tlog")
    ap.add_argument("--servo-map", required=True, help="servo mapping TOML")
    ap.add_argument("--epoch-us", type=int, default=1_700_000_000_000_000)
    ap.add_argument("--garbage", type=int, default=0, help="runs of random bytes to insert")
    ap.add_argument("--flip", type=int, default=0, help="HEARTBEAT/SYS_STATUS frames to damage")
    ap.add_argument("--truncate", action="store_true", help="cut the final record short")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()

    rng = random.Random(args.seed)
    with open(args.servo_map, "rb") as f:
        airframe = tomllib.load(f)
    cols = read_flight_csv(args.csv)
    t = cols["time_s"]
    n = len(t)

    def col(name, i, default=0.0):
        c = cols.get(name)
        return c[i] if c is not None else default

    v1 = mav1.MAVLink(None, srcSystem=1, srcComponent=1)
    v2 = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
    other = mav2.MAVLink(None, srcSystem=2, srcComponent=1)
    records = []  # (timestamp_us, frame bytes, kind)
    counts = {"v1": 0, "v2": 0}

    def emit(stamp, link, msg, kind):
        frame = msg.pack(link)
        records.append((stamp, frame, kind))
        counts["v1" if link is v1 else "v2"] += 1

    servo_channels = {}
    for surface, column in (("elevator", "elevator_rad"), ("aileron", "aileron_rad"), ("rudder", "rudder_rad")):
        if surface in airframe and column in cols:
            servo_channels[airframe[surface]["channel"]] = (surface, column)

    for i in range(n):
        stamp = args.epoch_us + round(t[i] * 1e6)
        boot_ms = int(round(t[i] * 1000)) & 0xFFFFFFFF
        link = v1 if i % 2 == 1 else v2
        if all(c in cols for c in ("phi_rad", "theta_rad", "psi_rad")):
            emit(stamp, link, link.attitude_encode(
                boot_ms, col("phi_rad", i), col("theta_rad", i), wrap_pi(col("psi_rad", i)),
                col("p_rad_s", i), col("q_rad_s", i), col("r_rad_s", i)), "ATTITUDE")
        if "az_m_s2" in cols:
            imu_link = v1 if i % 3 == 0 else v2
            mg = [int(round(col(c, i) / G0 * 1000.0)) for c in ("ax_m_s2", "ay_m_s2", "az_m_s2")]
            emit(stamp, imu_link, imu_link.scaled_imu_encode(boot_ms, *mg, 0, 0, 0, 0, 0, 0), "SCALED_IMU")
        if "airspeed_m_s" in cols:
            thr = int(round(100.0 * col("throttle", i)))
            heading = int(math.degrees(col("psi_rad", i))) % 360
            # an autopilot's VFR_HUD carries equivalent airspeed (ArduPilot, PX4) and ground speed
            eas = col("airspeed_m_s", i) * equivalent_per_true(col("altitude_m", i))
            emit(stamp, v2, v2.vfr_hud_encode(eas, col("airspeed_m_s", i),
                                             heading, thr, col("altitude_m", i), 0.0), "VFR_HUD")
        if "alpha_rad" in cols:
            emit(stamp, v2, v2.aoa_ssa_encode(stamp, math.degrees(col("alpha_rad", i)),
                                             math.degrees(col("beta_rad", i))), "AOA_SSA")
        if servo_channels or "throttle" in airframe:
            pwm = [0] * 8
            for ch, (surface, column) in servo_channels.items():
                pwm[ch - 1] = pwm_of(airframe[surface], col(column, i))
            if "throttle" in airframe and "throttle" in cols:
                tm = airframe["throttle"]
                pwm[tm["channel"] - 1] = int(round(tm["min_pwm_us"] + col("throttle", i) * (tm["max_pwm_us"] - tm["min_pwm_us"])))
            emit(stamp, link, link.servo_output_raw_encode(stamp & 0xFFFFFFFF, 0, *pwm), "SERVO_OUTPUT_RAW")
        if i % 100 == 0:
            emit(stamp, v2, v2.heartbeat_encode(1, 3, 0, 0, 4), "HEARTBEAT")
            emit(stamp, v1, v1.sys_status_encode(0, 0, 0, 500, 12000, 100, 80, 0, 0, 0, 0, 0, 0), "SYS_STATUS")
            emit(stamp, other, other.heartbeat_encode(6, 8, 0, 0, 4), "HEARTBEAT")
        if i % 10 == 5:
            emit(stamp, other, other.attitude_encode(boot_ms, 0.5, -0.5, 1.0, 0.0, 0.0, 0.0), "ATTITUDE")

    # Damage: flip one payload byte inside some HEARTBEAT/SYS_STATUS frames (their CRC then fails).
    candidates = [k for k, r in enumerate(records) if r[2] in ("HEARTBEAT", "SYS_STATUS")]
    flipped = rng.sample(candidates, min(args.flip, len(candidates)))
    damaged_bytes = 0
    for k in flipped:
        stamp, frame, kind = records[k]
        b = bytearray(frame)
        j = len(b) - 3  # last payload byte
        b[j] ^= 0x5A
        records[k] = (stamp, bytes(b), kind)
        damaged_bytes += 8 + len(b)

    out = bytearray()
    garbage_at = set(rng.sample(range(1, len(records)), min(args.garbage, len(records) - 1)))
    garbage_bytes = 0
    for k, (stamp, frame, _) in enumerate(records):
        if k in garbage_at:
            run = bytes(rng.randrange(256) for _ in range(rng.randrange(3, 12)))
            out += run
            garbage_bytes += len(run)
        out += struct.pack(">Q", stamp) + frame

    truncated_bytes = 0
    if args.truncate:
        stamp = args.epoch_us + round((t[-1] + 0.01) * 1e6)
        frame = v2.attitude_encode(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0).pack(v2)
        partial = struct.pack(">Q", stamp) + frame[:12]
        out += partial
        truncated_bytes = len(partial)

    with open(args.tlog, "wb") as f:
        f.write(out)
    json.dump({
        "frames_written": len(records),
        "frames_v1": counts["v1"],
        "frames_v2": counts["v2"],
        "flipped_frames": len(flipped),
        "garbage_bytes": garbage_bytes,
        "skipped_bytes_expected": garbage_bytes + damaged_bytes,
        "truncated_bytes": truncated_bytes,
        "rows": n,
    }, sys.stdout)
    print()


if __name__ == "__main__":
    main()
