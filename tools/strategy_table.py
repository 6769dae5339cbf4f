#!/usr/bin/env python3
"""Runs the same saturating manoeuvres through every strategy with
`motormix mix --json` and prints a markdown table of what each leaves
undelivered: demand minus produced, produced = pinv(M) * command, in the
normalized units of the team quad's sign table.

    tools/strategy_table.py --motormix build/motormix > table.md
"""

import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

STRATEGIES = [
    ("legacy_budget", "{strategy: legacy_budget}"),
    ("budget", "{strategy: budget}"),
    ("clip", "{strategy: clip}"),
    ("shift", "{strategy: shift}"),
    ("prioritized", "{strategy: prioritized, prioritized: {airmode: off}}"),
    ("prioritized + airmode", "{strategy: prioritized, prioritized: {airmode: roll_pitch}}"),
    ("optimal", "{strategy: optimal}"),
]

# (name, throttle, roll, pitch, yaw)
MANOEUVRES = [
    ("full roll at hover", 0.5, 1.0, 0.0, 0.0),
    ("roll at low throttle", 0.1, 0.8, 0.0, 0.0),
    ("full yaw at full throttle", 1.0, 0.0, 0.0, 1.0),
    ("flip: roll+pitch 0.9", 0.6, 0.9, 0.9, 0.0),
    ("punch-out with roll", 1.0, 0.5, 0.0, 0.0),
    ("yaw spin at low throttle", 0.2, 0.0, 0.0, 1.0),
]


def run(binary, args):
    out = subprocess.run([binary] + args, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--motormix", required=True)
    args = ap.parse_args()
    matrix = np.array(run(args.motormix, ["matrix", "--preset", "team_quad", "--format", "json"])["matrix"])
    produced_of = np.linalg.pinv(matrix)
    header = "| manoeuvre (throttle, roll, pitch, yaw) | " + " | ".join(s for s, _ in STRATEGIES) + " |"
    print(header)
    print("|" + "---|" * (len(STRATEGIES) + 1))
    with tempfile.TemporaryDirectory() as tmp:
        for name, t, r, p, y in MANOEUVRES:
            cells = []
            for _, mixer in STRATEGIES:
                cfg = os.path.join(tmp, "c.yaml")
                with open(cfg, "w") as f:
                    f.write(f"geometry: {{preset: team_quad}}\nmixer: {mixer}\n")
                res = run(args.motormix, ["mix", "--config", cfg, "--throttle", str(t), "--roll", str(r),
                                          "--pitch", str(p), "--yaw", str(y), "--json"])
                err = np.array([r, p, y, t]) - produced_of @ np.array(res["command"])
                cells.append(f"{np.hypot(err[0], err[1]):.2f} / {abs(err[2]):.2f} / {abs(err[3]):.2f}")
            print(f"| {name} ({t}, {r}, {p}, {y}) | " + " | ".join(cells) + " |")
    print()
    print("Each cell: roll+pitch error (norm) / yaw error / thrust error, in normalized units; 0 is "
          "delivered exactly. legacy_budget and budget scale every axis by their budgets by design.")


if __name__ == "__main__":
    main()
