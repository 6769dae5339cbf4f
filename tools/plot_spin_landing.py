#!/usr/bin/env python3
"""Plots a spin landing from a `motormix sim --log` of a quad losing a motor:
altitude, body rate (the spin), thrust-axis tilt and the motor commands over
time, with the failure marked. Used for docs/motor-loss-landing.md:

    motormix sim --config config/quad_x.yaml --scenario spin_landing --log /tmp/spin.lcmlog
    tools/plot_spin_landing.py /tmp/spin.lcmlog docs/spin_landing.png --fail-at 8
"""

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flight_log import Flight  # noqa: E402


def tilt_deg(q):
    """Angle between the body z axis and the world's, per row of w, x, y, z."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    zz = 1.0 - 2.0 * (x * x + y * y)  # the body z axis' world z component
    return np.degrees(np.arccos(np.clip(zz, -1.0, 1.0)))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("log")
    p.add_argument("output")
    p.add_argument("--fail-at", type=float, default=None, help="seconds: marks the failure")
    p.add_argument("--title", default=None)
    a = p.parse_args()
    f = Flight(a.log)
    if f.state_t.size == 0:
        sys.exit("plot_spin_landing: no vehicle_state_t in the log (a `motormix sim --log` is needed)")
    t0 = f.state_t[0]
    ts = f.state_t - t0
    fig, axes = plt.subplots(4, 1, figsize=(10, 10), sharex=True)
    axes[0].plot(ts, -f.position[:, 2], color="tab:blue")
    axes[0].set_ylabel("altitude (m)")
    axes[1].plot(ts, np.linalg.norm(f.body_rates, axis=1), color="tab:red", label="|body rate|")
    axes[1].axhline(np.radians(2000), color="grey", linestyle=":", label="gyro range")
    axes[1].set_ylabel("spin (rad/s)")
    axes[1].legend(loc="upper left")
    axes[2].plot(ts, tilt_deg(f.q), color="tab:purple")
    axes[2].axhline(90, color="grey", linestyle=":")
    axes[2].set_ylabel("thrust-axis tilt (deg)")
    tp = f.pwm_t - t0
    for i in range(f.command.shape[1]):
        axes[3].plot(tp, f.command[:, i], label=f"m{i + 1}", linewidth=0.8)
    axes[3].set_ylabel("motor command")
    axes[3].set_xlabel("time (s)")
    axes[3].legend(loc="upper right", ncol=4)
    for ax in axes:
        ax.grid(alpha=0.3)
        if a.fail_at is not None:
            ax.axvline(a.fail_at, color="black", linestyle="--", linewidth=0.8)
    fig.suptitle(a.title or os.path.basename(a.log))
    fig.tight_layout()
    fig.savefig(a.output, dpi=90)


if __name__ == "__main__":
    main()
