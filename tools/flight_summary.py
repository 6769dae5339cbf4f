#!/usr/bin/env python3
"""Prints what a mixer did during a recorded flight: inputs and outputs seen,
time armed, PWM range per motor, time each motor spent saturated, what could
not be delivered per axis, and the mixer's own counters."""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flight_log import Flight  # noqa: E402

AXES = ("roll", "pitch", "yaw", "thrust")
STATES = {0: "disarmed", 1: "armed", 2: "failsafe"}


def summarize(f, out=sys.stdout):
    duration = f.pwm_t[-1] - f.pwm_t[0] if len(f.pwm_t) > 1 else 0.0
    p = lambda *a: print(*a, file=out)  # noqa: E731
    p(f"flight log      {f.path}")
    p(f"inputs          {len(f.setpoint_t)} setpoints, {len(f.pid_t)} pid messages")
    rate = (len(f.pwm_t) - 1) / duration if duration > 0 else 0.0
    p(f"outputs         {len(f.pwm_t)} motor_pwm over {duration:.2f} s ({rate:.0f} Hz), "
      f"{len(f.status)} status")
    if not len(f.pwm_t):
        return
    dt = np.diff(f.pwm_t, append=f.pwm_t[-1])
    armed_s = float(np.sum(dt[f.armed]))
    p(f"armed           {armed_s:.2f} s ({100 * armed_s / max(duration, 1e-9):.0f} % of outputs)")
    p(f"last output     {'ARMED' if f.armed[-1] else 'disarmed'}")
    if f.armed.any():
        p("motor   pwm min   pwm mean  pwm max   at max     at min (armed)")
        cmd = f.command[f.armed]
        for i in range(f.motors):
            pw = f.pwm[f.armed, i]
            at_max = float(np.sum(dt[f.armed][cmd[:, i] >= 1.0 - 1e-6]))
            at_min = float(np.sum(dt[f.armed][cmd[:, i] <= 1e-6]))
            p(f"{i:<7d} {pw.min():<9.1f} {pw.mean():<9.1f} {pw.max():<9.1f} "
              f"{at_max:<6.2f} s   {at_min:.2f} s")
    if f.status:
        un = np.array([s.unallocated for s in f.status if s.state == 1]).reshape(-1, 4)
        if un.size:
            worst = np.max(np.abs(un), axis=0)
            p("unallocated     " + ", ".join(f"{a} {w:.3f}" for a, w in zip(AXES, worst))
              + "  (largest, from status)")
        last = f.status[-1]
        p(f"final state     {STATES.get(last.state, last.state)}; cycles {last.cycles}; "
          f"accepted {last.setpoint_received} setpoints, {last.pid_received} pid")
        p(f"refused         truncated {last.rejected_truncated}, trailing bytes {last.rejected_trailing}, "
          f"wrong type {last.rejected_wrong_type}, bad length {last.rejected_bad_length}, "
          f"undecodable {last.rejected_undecodable}")
        p(f"rejected        non-finite {last.rejected_nonfinite}, range {last.rejected_range}, "
          f"order {last.rejected_stale_order}, future {last.rejected_future}, array size {last.rejected_size}; "
          f"failsafe events {last.failsafe_events}")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("log")
    args = ap.parse_args()
    summarize(Flight(args.log))


if __name__ == "__main__":
    main()
