#!/usr/bin/env python3
"""Writes deterministic flights as LCM event logs (same seed, same bytes).

Setpoints (throttle, yaw, armed) at 50 Hz, pid (roll, pitch) at 400 Hz, with
timing noise. Scenarios:

- team_quad: disarmed on the ground, arming, take-off, hover, a roll sine
  sweep, pitch steps, yaw left and right, an aggressive roll+pitch with a
  throttle punch, landing, disarmed (channels pos_deseada / pid).
- dropout: hover, the publisher goes silent for 0.4 s, comes back still
  "armed", is disarmed and re-armed; NaN, infinite and out-of-range messages
  along the way (channels SETPOINT / PID).
- flips: punch-outs, full-yaw spins at low and high throttle, saturating
  flips (SETPOINT / PID).
- diff_drive: a wheeled robot: straight, spin in place, saturating turns as
  in the locomotion document, reverse (SETPOINT / PID; throttle -1..1).
- hexa_motor_out: a hexa hovers and manoeuvres; at 5.0 s its failure
  detector reports m1 dead on MOTOR_STATUS (10 Hz, healthy before), and the
  flight goes on with the same manoeuvres on five motors (SETPOINT / PID).
- battery_sag: hover and gentle manoeuvres while the pack sags from 16.8 V
  to 13.4 V on BATTERY (50 Hz), with a 0 V sensor glitch at 4.0 s and a
  0.8 s silence of the battery monitor at 6.0 s (SETPOINT / PID).

    tools/make_flight.py --scenario team_quad --seed 1 -o test/data/flights/team_quad.lcmlog
    tools/make_flight.py --all test/data/flights     # every scenario + MANIFEST.md
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
from motormix import battery_t, motor_status_t, pid_t, setpoint_t  # noqa: E402

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


# --- further scenarios: (setpoint_at, pid_at, end_s, silent windows, bad-value times) ---

def dropout_setpoint(t):
    if t < 1.0:
        return 0.0, 0.0, False
    if t < 2.0:
        return 0.05, 0.0, True  # armed at low throttle
    if t < 6.0:
        return 0.5, 0.1 * math.sin(t), True
    if t < 6.5:
        return 0.0, 0.0, False  # disarm after the dropout...
    if t < 8.5:
        return 0.05 if t < 7.0 else 0.5, 0.0, True  # ...and re-arm
    return 0.0, 0.0, False


def dropout_pid(t, rng):
    if t < 1.0 or t >= 8.5:
        return 0.0, 0.0
    n = rng.normal(0.0, 0.02, size=2)
    return float(np.clip(0.3 * math.sin(3 * t) + n[0], -1, 1)), float(np.clip(0.2 * math.cos(2 * t) + n[1], -1, 1))


def flips_setpoint(t):
    if t < 1.0:
        return 0.0, 0.0, False
    if t < 1.5:
        return 0.05, 0.0, True
    if t < 3.0:
        return 1.0, 0.0, True          # punch-out
    if t < 4.5:
        return 0.15, 1.0, True         # full yaw, low throttle
    if t < 6.0:
        return 0.9, -1.0, True         # full yaw, high throttle
    if t < 8.0:
        return 0.6, 0.0, True          # flips below
    return 0.0, 0.0, False


def flips_pid(t, rng):
    if t < 1.5 or t >= 8.0:
        return 0.0, 0.0
    n = rng.normal(0.0, 0.02, size=2)
    if 1.5 <= t < 3.0:
        return float(np.clip(0.5 + n[0], -1, 1)), float(np.clip(n[1], -1, 1))
    if 6.0 <= t < 8.0:
        phase = int((t - 6.0) / 0.5)
        r, p = [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)][phase % 4]
        return r, p
    return float(np.clip(n[0], -1, 1)), float(np.clip(n[1], -1, 1))


def drive_setpoint(t):
    """Ground robot: throttle = forward command, yaw = turn command (left positive)."""
    if t < 1.0:
        return 0.0, 0.0, False
    if t < 1.5:
        return 0.0, 0.0, True
    if t < 3.0:
        return 0.8, 0.0, True      # straight
    if t < 4.5:
        return 0.0, 1.0, True      # spin in place
    if t < 6.0:
        return 0.2, 0.9, True      # the document's move(1.0, 0.9): saturating turn
    if t < 7.5:
        return -0.2, 0.9, True     # and move(-1.0, 0.9)
    if t < 9.0:
        return -0.6, -0.3, True    # reverse, turning right
    return 0.0, 0.0, False


def no_pid(t, rng):
    return 0.0, 0.0


def hexa_setpoint(t):
    if t < 1.0:
        return 0.0, 0.0, False
    if t < 1.5:
        return 0.05, 0.0, True
    if t < 2.5:
        return 0.05 + 0.45 * (t - 1.5), 0.0, True  # take-off
    if t < 9.5:
        # yaw left and right, before and after the failure alike
        yaw = 0.0
        if 3.5 <= t < 4.5 or 7.5 <= t < 8.5:
            yaw = 0.4 if int(t * 2) % 2 else -0.4
        return 0.5, yaw, True
    if t < 10.5:
        return 0.5 * (10.5 - t), 0.0, True  # landing
    return 0.0, 0.0, False


def hexa_pid(t, rng):
    if t < 2.5 or t >= 9.5:
        return 0.0, 0.0
    n = rng.normal(0.0, 0.01, size=2)
    # the same manoeuvres before (2.5..5) and after (6..8.5) the failure
    phase = (t - 2.5) if t < 5.0 else (t - 6.0)
    roll = 0.15 * math.sin(2.0 * math.pi * 0.5 * phase) if 0.0 <= phase < 2.5 else 0.0
    pitch = 0.1 if 1.0 <= phase < 1.5 else (-0.1 if 1.5 <= phase < 2.0 else 0.0)
    return float(np.clip(roll + n[0], -1, 1)), float(np.clip(pitch + n[1], -1, 1))


HEXA_FAILURE_S = 5.0


def hexa_extra(rng, end_s):
    """MOTOR_STATUS at 10 Hz: six healthy motors, then m1 failed from 5.0 s."""
    out = []
    for k in range(int(end_s * 10)):
        t = k / 10.0 + 0.003
        msg = motor_status_t()
        msg.num_motors = 6
        msg.failed = [t >= HEXA_FAILURE_S] + [False] * 5
        out.append((t, "MOTOR_STATUS", msg))
    # the failure is reported the moment it is detected, not at the next tick
    msg = motor_status_t()
    msg.num_motors = 6
    msg.failed = [True] + [False] * 5
    out.append((HEXA_FAILURE_S, "MOTOR_STATUS", msg))
    return out


def sag_setpoint(t):
    if t < 1.0:
        return 0.0, 0.0, False
    if t < 1.5:
        return 0.05, 0.0, True
    if t < 10.0:
        return 0.5, 0.0, True
    return 0.0, 0.0, False


def sag_pid(t, rng):
    if t < 1.5 or t >= 10.0:
        return 0.0, 0.0
    n = rng.normal(0.0, 0.01, size=2)
    return float(np.clip(0.1 * math.sin(t) + n[0], -1, 1)), float(np.clip(n[1], -1, 1))


SAG_FULL_V = 16.8
SAG_EMPTY_V = 13.4


def sag_voltage(t, end_s):
    """The pack voltage: a linear sag under load, deeper while hovering."""
    return SAG_FULL_V - (SAG_FULL_V - SAG_EMPTY_V) * min(1.0, t / end_s)


def sag_extra(rng, end_s):
    """BATTERY at 50 Hz with measurement noise, one 0 V glitch, one 0.8 s silence."""
    out = []
    for k in range(int(end_s * 50)):
        t = k / 50.0 + 0.007
        if 6.0 <= t < 6.8:
            continue  # the battery monitor goes silent
        msg = battery_t()
        msg.voltage = 0.0 if abs(t - 4.007) < 1e-6 else sag_voltage(t, end_s) + float(rng.normal(0.0, 0.05))
        out.append((t, "BATTERY", msg))
    return out


SCENARIOS = {
    # name: (setpoint_at, pid_at, end_s, channels, silent windows (s), bad-value times (s)[,
    #        extra events (rng, end_s) -> [(t, channel, message)]])
    "team_quad": (setpoint_at, pid_at, END_S, ("pos_deseada", "pid"), [], []),
    "dropout": (dropout_setpoint, dropout_pid, 9.0, ("SETPOINT", "PID"), [(5.0, 5.4)],
                [2.5, 3.0, 3.5, 4.0]),
    "flips": (flips_setpoint, flips_pid, 8.5, ("SETPOINT", "PID"), [], []),
    "diff_drive": (drive_setpoint, no_pid, 9.5, ("SETPOINT", "PID"), [], []),
    "hexa_motor_out": (hexa_setpoint, hexa_pid, 11.0, ("SETPOINT", "PID"), [], [], hexa_extra),
    "battery_sag": (sag_setpoint, sag_pid, 10.5, ("SETPOINT", "PID"), [], [], sag_extra),
}


def events(seed, setpoint_channel, pid_channel, scenario="team_quad"):
    sp_at, pid_fn, end_s, _, silent, bad_times = SCENARIOS[scenario][:6]
    extra = SCENARIOS[scenario][6] if len(SCENARIOS[scenario]) > 6 else None
    rng = np.random.default_rng(seed)
    out = []
    for rate, kind in ((SETPOINT_HZ, "setpoint"), (PID_HZ, "pid")):
        n = int(end_s * rate)
        for k in range(n):
            t = k / rate + float(rng.normal(0.0, JITTER_S))
            t = min(max(t, 0.0), end_s)
            if any(a <= t < b for a, b in silent):
                continue  # the publisher is silent
            out.append((t, kind))
    for t in bad_times:  # NaN, infinity and out-of-range messages on both channels
        out.append((t + 0.0001, "bad_setpoint"))
        out.append((t + 0.0002, "bad_pid"))
    out.sort()
    encoded = []
    last_utime = {"setpoint": 0, "pid": 0}
    for t, kind in out:
        utime = START_UTIME + int(round(t * 1e6))
        clock = kind.replace("bad_", "")  # bad messages come from the same publishers
        utime = max(utime, last_utime[clock] + 1)  # each publisher's clock moves forward
        last_utime[clock] = utime
        if kind == "setpoint":
            msg = setpoint_t()
            msg.utime = utime
            msg.throttle, msg.yaw, msg.armed = sp_at(t)
            encoded.append((utime, setpoint_channel, msg.encode()))
        elif kind == "pid":
            msg = pid_t()
            msg.utime = utime
            msg.roll, msg.pitch = pid_fn(t, rng)
            msg.yaw = 0.0
            encoded.append((utime, pid_channel, msg.encode()))
        elif kind == "bad_setpoint":
            msg = setpoint_t()
            msg.utime = utime
            msg.throttle, msg.yaw, msg.armed = float("nan") if int(t * 2) % 2 else 3.0, 0.0, True
            encoded.append((utime, setpoint_channel, msg.encode()))
        else:
            msg = pid_t()
            msg.utime = utime
            msg.roll, msg.pitch = (float("inf"), 0.0) if int(t * 2) % 2 else (0.0, -2.0)
            encoded.append((utime, pid_channel, msg.encode()))
    if extra:
        last = 0
        for t, channel, msg in sorted(extra(rng, end_s), key=lambda e: e[0]):
            utime = max(START_UTIME + int(round(t * 1e6)), last + 1)
            last = utime
            msg.utime = utime
            encoded.append((utime, channel, msg.encode()))
    encoded.sort(key=lambda e: e[0])
    return encoded


def write(path, seed, scenario, setpoint_channel=None, pid_channel=None):
    channels = SCENARIOS[scenario][3]
    evs = events(seed, setpoint_channel or channels[0], pid_channel or channels[1], scenario)
    log = lcm.EventLog(path, "w", overwrite=True)
    for utime, channel, data in evs:
        log.write_event(utime, channel, data)
    log.close()
    return len(evs)


MANIFEST = {
    "team_quad": "the team quad flight",
    "dropout": "hover, 0.4 s publisher silence, return still armed, disarm and re-arm; NaN/Inf/out-of-range messages at 2.5, 3.0, 3.5, 4.0 s",
    "flips": "punch-out with roll, full-yaw spins at low and high throttle, saturating roll+pitch flips",
    "diff_drive": "wheeled robot: straight, spin in place, move(1.0, 0.9) and move(-1.0, 0.9) turns, reverse",
    "hexa_motor_out": "hexa: hover, roll sine and pitch steps, yaw; m1 reported failed on MOTOR_STATUS at 5.0 s; the same manoeuvres on five motors, landing",
    "battery_sag": "hover while the pack sags 16.8 -> 13.4 V on BATTERY (50 Hz), a 0 V glitch at 4.0 s, 0.8 s battery silence at 6.0 s",
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-o", "--output")
    ap.add_argument("--all", metavar="DIR", help="write every scenario and MANIFEST.md into DIR")
    ap.add_argument("--scenario", default="team_quad", choices=sorted(SCENARIOS))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--setpoint-channel")
    ap.add_argument("--pid-channel")
    args = ap.parse_args()
    if args.all:
        os.makedirs(args.all, exist_ok=True)
        lines = ["# Flight library", "", "Generated by `tools/make_flight.py --all test/data/flights --seed "
                 f"{args.seed}`: deterministic, setpoints 50 Hz, pid 400 Hz, timing noise.", "",
                 "| file | channels | duration | events | what |", "|---|---|---|---|---|"]
        for name in sorted(SCENARIOS):
            path = os.path.join(args.all, name + ".lcmlog")
            n = write(path, args.seed, name)
            ch = SCENARIOS[name][3]
            lines.append(f"| {name}.lcmlog | {ch[0]} / {ch[1]} | {SCENARIOS[name][2]:.1f} s | {n} | {MANIFEST[name]} |")
            print(f"{path}: {n} events")
        with open(os.path.join(args.all, "MANIFEST.md"), "w") as f:
            f.write("\n".join(lines) + "\n")
        return
    if not args.output:
        ap.error("-o/--output or --all is required")
    n = write(args.output, args.seed, args.scenario, args.setpoint_channel, args.pid_channel)
    print(f"{args.output}: {n} events ({args.scenario}, seed {args.seed})")


if __name__ == "__main__":
    main()
