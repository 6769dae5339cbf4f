#!/usr/bin/env python3
"""Writes a deterministic team-quad flight as an LCM event log.

Setpoints (throttle, yaw, armed) at 50 Hz on one channel, pid (roll, pitch)
at 400 Hz on another, with timing noise, through these phases: disarmed on
the ground, arming, take-off, hover, a roll sine sweep, pitch steps, yaw
left and right, an aggressive roll+pitch with a throttle punch, landing,
disarmed. Same seed, same bytes.

    tools/make_flight.py --seed 1 -o test/data/team_quad_flight.lcmlog
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

lcm_python.add_types_path()
import lcm  # noqa: E402
from motormix import pid_t, setpoint_t  # noqa: E402

SETPOINT_HZ = 50.0
PID_HZ = 400.0
JITTER_S = 0.0003  # publisher timing noise, standard deviation
START_UTIME = 1_764_000_000_000_000  # a fixed epoch, so logs are reproducible

# (start s, name) of each phase; the flight ends at END_S.
PHASES = [
    (0.0, "ground"),
    (1.0, "takeoff"),
    (2.5, "hover"),
    (4.0, "roll_sweep"),
    (6.0, "pitch_steps"),
    (8.0, "yaw"),
    (10.0, "aggressive"),
    (11.0, "landing"),
    (13.0, "ground_after"),
]
END_S = 14.0
HOVER = 0.55


def phase_at(t):
    name = PHASES[0][1]
    start = 0.0
    for s, n in PHASES:
        if t >= s:
            name, start = n, s
    return name, t - start


def setpoint_at(t):
    """(throttle, yaw, armed) commanded at time t."""
    name, dt = phase_at(t)
    if name == "ground":
        return 0.0, 0.0, False
    if name == "takeoff":
        return HOVER * min(1.0, dt / 1.5), 0.0, True
    if name == "yaw":
        return HOVER, 0.8 if dt < 1.0 else -0.8, True
    if name == "aggressive":
        return 1.0, 0.3, True
    if name == "landing":
        return HOVER * max(0.0, 1.0 - dt / 1.8), 0.0, True
    if name == "ground_after":
        return 0.0, 0.0, False
    return HOVER, 0.0, True


def pid_at(t, rng):
    """(roll, pitch) from the attitude controller at time t, with sensor noise."""
    name, dt = phase_at(t)
    if name in ("ground", "ground_after"):
        return 0.0, 0.0
    noise = rng.normal(0.0, 0.02, size=2)
    roll, pitch = 0.0, 0.0
    if name == "roll_sweep":
        roll = 0.6 * math.sin(2.0 * math.pi * (0.5 + 0.5 * dt) * dt)
    elif name == "pitch_steps":
        pitch = [0.5, -0.5, 0.3, -0.3][min(3, int(dt / 0.5))]
    elif name == "aggressive":
        roll, pitch = 0.9, -0.9 if dt < 0.5 else 0.9
    clip = lambda v: float(np.clip(v, -1.0, 1.0))  # noqa: E731
    return clip(roll + noise[0]), clip(pitch + noise[1])


def events(seed, setpoint_channel, pid_channel):
    rng = np.random.default_rng(seed)
    out = []
    for rate, kind in ((SETPOINT_HZ, "setpoint"), (PID_HZ, "pid")):
        n = int(END_S * rate)
        for k in range(n):
            t = k / rate + float(rng.normal(0.0, JITTER_S))
            t = min(max(t, 0.0), END_S)
            out.append((t, kind))
    out.sort()
    encoded = []
    last_utime = {"setpoint": 0, "pid": 0}
    for t, kind in out:
        utime = START_UTIME + int(round(t * 1e6))
        utime = max(utime, last_utime[kind] + 1)  # each publisher's clock moves forward
        last_utime[kind] = utime
        if kind == "setpoint":
            msg = setpoint_t()
            msg.utime = utime
            msg.throttle, msg.yaw, msg.armed = setpoint_at(t)
            encoded.append((utime, setpoint_channel, msg.encode()))
        else:
            msg = pid_t()
            msg.utime = utime
            msg.roll, msg.pitch = pid_at(t, rng)
            msg.yaw = 0.0
            encoded.append((utime, pid_channel, msg.encode()))
    encoded.sort(key=lambda e: e[0])
    return encoded


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--setpoint-channel", default="pos_deseada")
    ap.add_argument("--pid-channel", default="pid")
    args = ap.parse_args()
    log = lcm.EventLog(args.output, "w", overwrite=True)
    evs = events(args.seed, args.setpoint_channel, args.pid_channel)
    for utime, channel, data in evs:
        log.write_event(utime, channel, data)
    log.close()
    print(f"{args.output}: {len(evs)} events over {END_S:.1f} s (seed {args.seed})")


if __name__ == "__main__":
    main()
