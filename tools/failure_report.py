#!/usr/bin/env python3
"""Demanded against delivered, per axis, before and after a motor failure.

Reads a `motormix replay` output log made with a status on every cycle
(`--set status_rate_hz=<loop rate>`): the demand in force is rebuilt from the
setpoint and pid events, and what the motors delivered is that demand minus
the mixer's own `unallocated` report. Prints, for the armed time before the
first failure and after it, the RMS and largest error per axis, and writes a
plot.

    tools/failure_report.py --label prioritized --label optimal OUT1.lcmlog OUT2.lcmlog -o PNG
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

lcm_python.add_types_path()
import lcm  # noqa: E402
from motormix import mixer_status_t, pid_t, setpoint_t  # noqa: E402

AXES = ["roll", "pitch", "yaw", "thrust"]


def read(path, setpoint_channel, pid_channel, status_channel):
    sp = None
    pid = None
    first = None
    rows = []  # t, demand[4], unallocated[4], failed mask
    for ev in lcm.EventLog(path, "r"):
        first = ev.timestamp if first is None else first
        if ev.channel == setpoint_channel:
            sp = setpoint_t.decode(ev.data)
        elif ev.channel == pid_channel:
            pid = pid_t.decode(ev.data)
        elif ev.channel == status_channel:
            s = mixer_status_t.decode(ev.data)
            if s.state != mixer_status_t.STATE_ARMED or sp is None or pid is None:
                continue
            demand = [pid.roll, pid.pitch, sp.yaw, sp.throttle * s.thrust_gain]
            rows.append([(ev.timestamp - first) / 1e6] + demand + list(s.unallocated) + [s.failed_motors])
    a = np.array(rows)
    return a[:, 0], a[:, 1:5], a[:, 5:9], a[:, 9].astype(int)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--label", action="append", default=[])
    ap.add_argument("--setpoint-channel", default="SETPOINT")
    ap.add_argument("--pid-channel", default="PID")
    ap.add_argument("--status-channel", default="MIXER_STATUS")
    ap.add_argument("--title", default="")
    ap.add_argument("-o", "--output")
    args = ap.parse_args()
    labels = args.label + [os.path.basename(p) for p in args.logs[len(args.label):]]

    runs = [read(p, args.setpoint_channel, args.pid_channel, args.status_channel) for p in args.logs]
    print("| strategy | armed | " + " | ".join(f"{a} RMS / max" for a in AXES) + " |")
    print("|---|---|" + "---|" * len(AXES))
    for label, (t, demand, unallocated, failed) in zip(labels, runs):
        for name, sel in (("healthy", failed == 0), ("motor out", failed != 0)):
            if not sel.any():
                continue
            e = np.abs(unallocated[sel])
            cells = [f"{np.sqrt(np.mean(e[:, k] ** 2)):.4f} / {e[:, k].max():.4f}" for k in range(4)]
            print(f"| {label} | {name}, {sel.sum() / 400.0:.2f} s | " + " | ".join(cells) + " |")

    if args.output:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(4, 1, figsize=(11, 9), sharex=True)
        t0, demand0, _, failed0 = runs[0]
        for k, ax in enumerate(axes):
            ax.plot(t0, demand0[:, k], color="k", lw=1.6, label="demanded")
            for label, (t, demand, unallocated, failed) in zip(labels, runs):
                ax.plot(t, demand[:, k] - unallocated[:, k], lw=0.9, label=f"delivered, {label}")
            if (failed0 != 0).any():
                ax.axvline(t0[np.argmax(failed0 != 0)], color="r", ls="--", lw=1)
            ax.set_ylabel(AXES[k])
        axes[0].legend(loc="upper right", fontsize=8, ncol=3)
        axes[0].set_title(args.title or "demanded against delivered (red: the failure is reported)")
        axes[-1].set_xlabel("flight time (s)")
        fig.tight_layout()
        fig.savefig(args.output, dpi=90)
        print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
