#!/usr/bin/env python3
"""Turns a `motormix replay --every-input` log into a golden file: for every
pair of inputs (setpoint utime, pid utime) for which the mixer produced armed
outputs, those outputs. When some output had failed motors, the failure set
in force (motor_pwm_t.failed_motors) is part of the key too. Plain CSV, one line per pair, sorted, so a change in
the mixer shows up as a reviewable diff.

    tools/golden.py REPLAY.lcmlog --title "..." -o GOLDEN.csv
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

lcm_python.add_types_path()
import lcm  # noqa: E402
from motormix import motor_pwm_t  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log")
    ap.add_argument("--channel", help="the motor_pwm channel (default: every event of that type)")
    ap.add_argument("--title", default="")
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args()
    rows = {}
    for ev in lcm.EventLog(args.log, "r"):
        if args.channel and ev.channel != args.channel:
            continue
        try:
            m = motor_pwm_t.decode(ev.data)  # the type's fingerprint picks the outputs out
        except ValueError:
            continue
        if m.armed:
            rows[(m.setpoint_utime, m.pid_utime, m.failed_motors)] = list(m.pwm) + list(m.direction)
    with_failures = any(key[2] != 0 for key in rows)
    if not with_failures:
        rows = {key[:2]: values for key, values in rows.items()}
    # Directions only where an output uses them (H-bridges); PWM to 0.001.
    with_direction = any(any(v != 0 for v in values[len(values) // 2:]) for values in rows.values())
    with open(args.output, "w") as f:
        f.write(f"# {args.title}\n")
        f.write("# setpoint_utime,pid_utime," + ("failed_motors," if with_failures else "") + "pwm per motor"
                + (",direction per motor" if with_direction else "") + "\n")
        for key, values in sorted(rows.items()):
            n = len(values) // 2
            cells = [f"{v:.3f}" for v in values[:n]] + ([str(v) for v in values[n:]] if with_direction else [])
            f.write(",".join(str(k) for k in key) + "," + ",".join(cells) + "\n")
    print(f"{args.output}: {len(rows)} input pairs")


if __name__ == "__main__":
    main()
