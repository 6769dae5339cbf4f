#!/usr/bin/env python3
"""Publish attitude_t for motormix's failure detector (source rates) and the spin landing.

The estimator's attitude, body rates and velocity, stamped with the gyro sample
time, on every gyro update, in body FRD relative to NED (frames.py converts from
FLU/ENU). The estimator here is a stand-in (a vehicle turning slowly on the spot);
replace estimate() with yours. Publish at 250 Hz or more: the rates source
differentiates the rates between stamps, and below that the detector is slower and
the spin landing's attitude goes stale (motor_loss.attitude_timeout_ms).

    PYTHONPATH=/usr/lib/python3/dist-packages python3 attitude_publisher.py --count 1000

Runs until Ctrl-C without --count. With --key it signs each message
(signing_option.py), as a configuration with security.mode require needs.
"""
import argparse
import math
import signal
import time

import lcm
from motormix import attitude_t

import frames
import signing_option


def estimate(t):
    """Stand-in FLU/ENU estimate: level, turning left at 0.2 rad/s, not moving."""
    yaw_rate = 0.2
    half = 0.5 * yaw_rate * t
    return (math.cos(half), 0.0, 0.0, math.sin(half)), (0.0, 0.0, yaw_rate), (0.0, 0.0, 0.0)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lcm-url", default="", help="LCM URL (default: $LCM_DEFAULT_URL)")
    p.add_argument("--channel", default="ATTITUDE")
    p.add_argument("--rate-hz", type=float, default=500.0)
    p.add_argument("--count", type=int, default=-1, help="messages to send (default: until Ctrl-C)")
    signing_option.add_arguments(p)
    args = p.parse_args()
    if not 0.0 < args.rate_hz <= 10000.0:
        p.error("--rate-hz: 0 < rate <= 10000")
    bus = lcm.LCM(args.lcm_url) if args.lcm_url else lcm.LCM()
    publish = signing_option.publisher(args, bus)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    start = time.time()
    next_t = time.monotonic()
    sent = 0
    try:
        while not stop and (args.count < 0 or sent < args.count):
            utime = int(time.time() * 1e6)  # stamp with the gyro sample time
            q_enu_flu, rates_flu, velocity_enu = estimate(utime / 1e6 - start)
            msg = attitude_t()
            msg.utime = utime
            msg.q = list(frames.frd_ned_from_flu_enu(q_enu_flu))
            msg.rates = list(frames.frd_from_flu(rates_flu))
            # Unknown? Publish NaN: the spin landing then follows the throttle.
            msg.velocity = list(frames.ned_from_enu(velocity_enu))
            publish(args.channel, msg.encode(), utime)
            sent += 1
            next_t += 1.0 / args.rate_hz
            time.sleep(max(0.0, next_t - time.monotonic()))
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
