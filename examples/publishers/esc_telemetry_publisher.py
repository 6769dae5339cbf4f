#!/usr/bin/env python3
"""Publish esc_telemetry_t for motormix's failure detector (source telemetry).

What your ESC driver reads back (bidirectional DShot eRPM, BLHeli_32/AM32/KISS
telemetry frames), one message per read-out. `motormix output` already publishes
this from KISS telemetry wires; this is for ESCs read by something else. The driver
here is a stand-in (every motor at 9000 rpm, eRPM only, as bidirectional DShot gives
it); replace read_escs() with yours. Motors are numbered as `motormix matrix`
numbers them (1-based); a message may carry any subset of them. Unknown fields are
NaN. 100 Hz per ESC or more keeps detection under 100 ms.

    PYTHONPATH=/usr/lib/python3/dist-packages python3 esc_telemetry_publisher.py --count 400
"""
import argparse
import math
import signal
import time

import lcm
from motormix import esc_telemetry_t

import signing_option

NAN = math.nan
POLE_PAIRS = 7  # a 14-pole motor: eRPM = rpm * 7 (failure_detection.motor_poles: 14)


def read_escs(motors):
    """Stand-in driver: (motor, rpm, erpm, current_a, voltage_v, temperature_c)."""
    return [(m, NAN, 9000.0 * POLE_PAIRS, NAN, 16.0, 40.0) for m in range(1, motors + 1)]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lcm-url", default="", help="LCM URL (default: $LCM_DEFAULT_URL)")
    p.add_argument("--channel", default="ESC_TELEMETRY")
    p.add_argument("--motors", type=int, default=4)
    p.add_argument("--rate-hz", type=float, default=200.0)
    p.add_argument("--count", type=int, default=-1, help="messages to send (default: until Ctrl-C)")
    signing_option.add_arguments(p)
    args = p.parse_args()
    if not 0.0 < args.rate_hz <= 10000.0 or not 1 <= args.motors <= 16:
        p.error("--rate-hz: 0 < rate <= 10000; --motors: 1..16")
    bus = lcm.LCM(args.lcm_url) if args.lcm_url else lcm.LCM()
    publish = signing_option.publisher(args, bus)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    next_t = time.monotonic()
    sent = 0
    try:
        while not stop and (args.count < 0 or sent < args.count):
            readings = read_escs(args.motors)
            msg = esc_telemetry_t()
            msg.utime = int(time.time() * 1e6)
            msg.count = len(readings)
            msg.motor = [r[0] for r in readings]
            msg.rpm = [r[1] for r in readings]
            msg.erpm = [r[2] for r in readings]
            msg.current_a = [r[3] for r in readings]
            msg.voltage_v = [r[4] for r in readings]
            msg.temperature_c = [r[5] for r in readings]
            msg.consumption_mah = [NAN] * len(readings)
            publish(args.channel, msg.encode(), msg.utime)
            sent += 1
            next_t += 1.0 / args.rate_hz
            time.sleep(max(0.0, next_t - time.monotonic()))
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
