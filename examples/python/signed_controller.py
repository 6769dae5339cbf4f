#!/usr/bin/env python3
"""A controller that signs what it sends: fly a quad through motormix with security.mode require.

It reads the vehicle's state (VEHICLE_STATE, as `motormix sim --lcm --no-controller`
publishes it; a signed one must verify), and sends setpoint_t and pid_t signed with
the bus key (python/motormix_signing.py, installed beside the message types). The
flight: disarmed for a moment, armed at zero throttle, a climb to ALTITUDE, a hover
of HOVER seconds, a descent, disarmed on the ground. Attitude is held level by a
proportional-derivative law on the body angles and rates; altitude by a
proportional-integral law on the climb rate around a hover throttle it learns.

    PYTHONPATH=/usr/lib/python3/dist-packages python3 signed_controller.py \
        --key /etc/motormix/bus.key --link-id 2

Exit status: 0 when the hover held its altitude within 0.25 m and stayed level
(tilt under 10 degrees) over its last two seconds, 1 otherwise, 2 on a bad key.
"""
import argparse
import math
import sys
import time

import lcm
import motormix_signing
from motormix import pid_t, setpoint_t, vehicle_state_t

RATE_HZ = 200.0
# Attitude: normalized torque demand per radian and per radian/second.
ATTITUDE_P, RATE_D = 0.35, 0.06
# Altitude: climb rate per metre of error (at most MAX_CLIMB), throttle per
# m/s of climb-rate error, and the integral that learns the hover throttle.
ALTITUDE_P, MAX_CLIMB, CLIMB_P, CLIMB_I = 1.0, 1.0, 0.15, 0.25


def euler(q):
    """Roll, pitch, yaw (rad) of a w, x, y, z quaternion (body FRD to NED)."""
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--key", required=True, help="the bus key file (motormix keygen)")
    p.add_argument("--link-id", type=int, default=2, help="this controller's link id (0..255)")
    p.add_argument("--lcm-url", default="", help="LCM URL (default: $LCM_DEFAULT_URL)")
    p.add_argument("--setpoint-channel", default="SETPOINT")
    p.add_argument("--pid-channel", default="PID")
    p.add_argument("--state-channel", default="VEHICLE_STATE")
    p.add_argument("--altitude", type=float, default=1.0, help="metres above the take-off point")
    p.add_argument("--hover", type=float, default=4.0, help="seconds of hover")
    p.add_argument("--timeout", type=float, default=30.0, help="give up after this many seconds")
    args = p.parse_args()
    try:
        key = motormix_signing.load_key(args.key)
    except motormix_signing.KeyError_ as e:
        print(f"signed_controller: {e}", file=sys.stderr)
        return 2
    signer = motormix_signing.Signer(key, args.link_id)
    verifier = motormix_signing.Verifier(key)
    bus = lcm.LCM(args.lcm_url) if args.lcm_url else lcm.LCM()
    state = {"msg": None, "refused": 0}

    def on_state(channel, data):
        verdict, payload = verifier.verify(channel, data)
        if verdict not in ("signed", "unsigned"):  # an unsigned state: a simulator without a key
            state["refused"] += 1
            return
        state["msg"] = vehicle_state_t.decode(payload)

    bus.subscribe(args.state_channel, on_state)

    def send(armed, throttle, roll=0.0, pitch=0.0, yaw=0.0):
        utime = time.time_ns() // 1000
        sp = setpoint_t()
        sp.utime, sp.armed, sp.throttle, sp.yaw = utime, armed, throttle, yaw
        bus.publish(args.setpoint_channel, signer.sign(args.setpoint_channel, sp.encode(), utime))
        pid = pid_t()
        pid.utime, pid.roll, pid.pitch, pid.yaw = utime, roll, pitch, yaw
        bus.publish(args.pid_channel, signer.sign(args.pid_channel, pid.encode(), utime))

    hover_throttle = 0.3  # learned by the climb-rate integral
    start = time.monotonic()
    phase, phase_start = "disarmed", start
    hover_errors, hover_tilts = [], []
    next_tick = start
    while time.monotonic() - start < args.timeout:
        next_tick += 1.0 / RATE_HZ
        while True:
            left = next_tick - time.monotonic()
            if left <= 0 or bus.handle_timeout(max(1, int(left * 1000))) <= 0:
                break
        now = time.monotonic()
        in_phase = now - phase_start
        s = state["msg"]
        if phase == "disarmed":
            send(False, 0.0)
            if in_phase > 0.5 and s is not None:
                phase, phase_start = "arming", now
            continue
        if phase == "arming":
            send(True, 0.0)
            if in_phase > 0.5:
                phase, phase_start = "climb", now
            continue
        roll, pitch, yaw = euler(s.q)
        altitude, climb = -s.position[2], -s.velocity[2]
        target = {"climb": args.altitude, "hover": args.altitude, "descend": -0.5}[phase]
        climb_sp = max(-0.5, min(MAX_CLIMB, ALTITUDE_P * (target - altitude)))
        hover_throttle += CLIMB_I * (climb_sp - climb) / RATE_HZ
        hover_throttle = max(0.05, min(0.8, hover_throttle))
        tilt = max(0.5, math.cos(roll) * math.cos(pitch))
        throttle = max(0.0, min(1.0, (hover_throttle + CLIMB_P * (climb_sp - climb)) / tilt))
        send(True, throttle,
             roll=-ATTITUDE_P * roll - RATE_D * s.rates[0],
             pitch=-ATTITUDE_P * pitch - RATE_D * s.rates[1],
             yaw=-RATE_D * s.rates[2])
        if s.crashed:
            print("signed_controller: the vehicle crashed", file=sys.stderr)
            break
        if phase == "climb" and abs(args.altitude - altitude) < 0.1:
            phase, phase_start = "hover", now
        elif phase == "hover":
            if in_phase > args.hover - 2.0:
                hover_errors.append(abs(args.altitude - altitude))
                hover_tilts.append(math.degrees(math.acos(min(1.0, math.cos(roll) * math.cos(pitch)))))
            if in_phase > args.hover:
                phase, phase_start = "descend", now
        elif phase == "descend" and (s.landed or in_phase > 10.0):
            break
    for _ in range(20):  # disarmed, on the ground (or giving up)
        send(False, 0.0)
        time.sleep(1.0 / RATE_HZ)
    if not hover_errors:
        print(f"signed_controller: never hovered (phase {phase})", file=sys.stderr)
        return 1
    worst_error, worst_tilt = max(hover_errors), max(hover_tilts)
    print(f"hover at {args.altitude} m: altitude error at most {worst_error:.3f} m, "
          f"tilt at most {worst_tilt:.2f} deg; hover throttle {hover_throttle:.3f}; "
          f"{state['refused']} vehicle states refused")
    return 0 if worst_error < 0.25 and worst_tilt < 10.0 else 1


if __name__ == "__main__":
    sys.exit(main())
