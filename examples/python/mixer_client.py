#!/usr/bin/env python3
"""Talk to a running motormix from Python: publish setpoint and pid, print the motor outputs.

Uses the message types installed with motormix (lib/python3/dist-packages/motormix on
Debian) and LCM's Python bindings (PyPI package `lcm`). It arms the mixer the way a
flight controller must (disarmed, then armed at low throttle, both inputs fresh), holds
the requested demand until COUNT armed outputs were printed, then disarms.

    PYTHONPATH=/usr/lib/python3/dist-packages python3 mixer_client.py \
        --throttle 0.5 --roll 0.2 --count 5

Exit status: 0 when COUNT armed outputs arrived, 1 on timeout.
"""
import argparse
import sys
import time

import lcm
from motormix import motor_pwm_t, pid_t, setpoint_t


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lcm-url", default="", help="LCM URL (default: $LCM_DEFAULT_URL)")
    p.add_argument("--setpoint-channel", default="SETPOINT")
    p.add_argument("--pid-channel", default="PID")
    p.add_argument("--pwm-channel", default="MOTOR_PWM")
    p.add_argument("--throttle", type=float, default=0.5)
    p.add_argument("--roll", type=float, default=0.0)
    p.add_argument("--pitch", type=float, default=0.0)
    p.add_argument("--yaw", type=float, default=0.0)
    p.add_argument("--count", type=int, default=5, help="armed outputs to print")
    p.add_argument("--timeout", type=float, default=10.0, help="give up after this many seconds")
    args = p.parse_args()

    bus = lcm.LCM(args.lcm_url) if args.lcm_url else lcm.LCM()
    printed = 0
    demand_since = None  # utime of the first message carrying the demand

    def on_pwm(_channel, data):
        nonlocal printed
        msg = motor_pwm_t.decode(data)
        # Every output names the setpoint it came from: print only those mixed
        # from the demand, not from the arming sequence.
        from_demand = demand_since is not None and msg.setpoint_utime >= demand_since
        if msg.armed and from_demand and printed < args.count:
            printed += 1
            motors = "  ".join(f"m{i + 1} {pwm:7.1f}" for i, pwm in enumerate(msg.pwm))
            print(f"armed  {motors}", flush=True)

    bus.subscribe(args.pwm_channel, on_pwm)

    def publish(armed, throttle, roll=0.0, pitch=0.0, yaw=0.0):
        nonlocal demand_since
        now = int(time.time() * 1e6)
        if demand_since is None and armed and throttle != 0.0:
            demand_since = now
        sp = setpoint_t()
        sp.utime, sp.throttle, sp.yaw, sp.armed = now, throttle, yaw, armed
        pid = pid_t()
        pid.utime, pid.roll, pid.pitch, pid.yaw = now, roll, pitch, yaw
        bus.publish(args.setpoint_channel, sp.encode())
        bus.publish(args.pid_channel, pid.encode())

    start = time.monotonic()
    # Arming sequence: disarmed, then armed at zero throttle, then the demand.
    phases = [(0.2, False, 0.0), (0.2, True, 0.0)]
    for duration, armed, throttle in phases:
        end = time.monotonic() + duration
        while time.monotonic() < end:
            publish(armed, throttle)
            bus.handle_timeout(10)
    while printed < args.count and time.monotonic() - start < args.timeout:
        publish(True, args.throttle, args.roll, args.pitch, args.yaw)
        bus.handle_timeout(10)
    for _ in range(5):
        publish(False, 0.0)
        time.sleep(0.01)
    if printed < args.count:
        print(f"timeout: {printed} of {args.count} armed outputs on {args.pwm_channel}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
