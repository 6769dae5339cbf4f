#!/usr/bin/env python3
"""Plots a motormix flight log to PNG: inputs, per-motor commands and PWM,
and armed state over time; for a log of `motormix sim` (vehicle_state_t on
the bus) also the simulated attitude, altitude and battery voltage. With --compare, overlays the motor commands of a
second log (e.g. the same flight through another strategy)."""

import argparse
import json
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flight_log import Flight  # noqa: E402


def motor_labels(motormix, config, count):
    """Legend labels that name each motor as `motormix matrix` does: number or
    name, then where it is ("m1 front right, CCW"). Without a config: m1, m2, ..."""
    if not config:
        return [f"m{i + 1}" for i in range(count)]
    out = subprocess.run([motormix, "matrix", "--config", config, "--format", "json"],
                         check=True, capture_output=True, text=True).stdout
    matrix = json.loads(out)
    names, details = matrix["names"], matrix.get("details") or [""] * len(matrix["names"])
    return [f"{n} {d}".strip() for n, d in zip(names, details)]


def plot(f, output, compare=None, title=None, labels=None):
    labels = labels or [f"m{i + 1}" for i in range(f.motors)]
    simulated = f.state_t.size > 0
    ratios = [2, 2, 2, 0.7] + ([2, 1.5] if simulated else [])
    fig, axes = plt.subplots(len(ratios), 1, figsize=(11, 10 + (5 if simulated else 0)), sharex=True,
                             gridspec_kw={"height_ratios": ratios})
    ax = axes[0]
    ax.plot(f.setpoint_t, f.throttle, label="throttle", color="k")
    ax.plot(f.setpoint_t, f.yaw, label="yaw")
    ax.plot(f.pid_t, f.roll, label="roll", lw=0.8)
    ax.plot(f.pid_t, f.pitch, label="pitch", lw=0.8)
    ax.set_ylabel("inputs")
    ax.set_ylim(-1.1, 1.1)
    ax.legend(loc="upper right", ncol=4, fontsize=8)

    ax = axes[1]
    for i in range(f.motors):
        ax.plot(f.pwm_t, f.command[:, i], lw=0.9, label=labels[i])
    if compare is not None:
        for i in range(compare.motors):
            ax.plot(compare.pwm_t, compare.command[:, i], lw=0.9, ls="--", label=f"{labels[i]} (b)")
    ax.set_ylabel("command (0..1)")
    ax.legend(loc="upper right", ncol=4, fontsize=8)

    ax = axes[2]
    for i in range(f.motors):
        ax.plot(f.pwm_t, f.pwm[:, i], lw=0.9, label=labels[i])
    ax.set_ylabel("PWM (us)")
    ax.legend(loc="upper right", ncol=4, fontsize=8)

    ax = axes[3]
    ax.fill_between(f.pwm_t, 0, f.armed.astype(float), step="post", alpha=0.4, label="armed")
    if f.status:
        sat = [bin(s.saturated_upper | s.saturated_lower).count("1") / max(1, f.motors) for s in f.status]
        ax.step(f.status_t, sat, where="post", color="r", label="saturated motors (share)")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(loc="upper right", ncol=2, fontsize=8)
    if simulated:
        ax = axes[4]
        e = f.euler_deg()
        for i, name in enumerate(("roll", "pitch", "yaw")):
            ax.plot(f.state_t, e[:, i], lw=0.9, label=name)
        ax.set_ylabel("attitude (deg)")
        ax.legend(loc="upper right", ncol=3, fontsize=8)
        ax = axes[5]
        ax.plot(f.state_t, -f.position[:, 2], color="k", label="altitude (m)")
        ax.set_ylabel("altitude (m)")
        ax2 = ax.twinx()
        ax2.plot(f.state_t, f.battery_v, color="tab:orange", lw=0.8, label="battery (V)")
        ax2.set_ylabel("battery (V)")
        ax.legend(loc="upper left", fontsize=8)
        ax2.legend(loc="upper right", fontsize=8)
        if f.crashed:
            ax.axvline(f.state_t[-1], color="r", ls="--")
            ax.text(f.state_t[-1], ax.get_ylim()[1], " crashed", color="r", va="top")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(title or os.path.basename(f.path))
    fig.tight_layout()
    fig.savefig(output, dpi=90)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("log")
    ap.add_argument("-o", "--output", required=True, help="PNG file to write")
    ap.add_argument("--compare", help="a second log whose motor commands are overlaid")
    ap.add_argument("--title")
    ap.add_argument("--config", help="the mixer's configuration: legends name the motors (m1 front right, CCW)")
    ap.add_argument("--motormix", default="motormix", help="motormix binary used to read --config")
    args = ap.parse_args()
    flight = Flight(args.log)
    labels = motor_labels(args.motormix, args.config, flight.motors)
    plot(flight, args.output, Flight(args.compare) if args.compare else None, args.title, labels)
    print(f"plot written to {args.output}")


if __name__ == "__main__":
    main()
