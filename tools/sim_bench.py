#!/usr/bin/env python3
"""Speed of `motormix sim` in lockstep: simulated seconds per wall second for
the vehicles and strategies of the scorecard, median of several runs of
--duration seconds each (the run's own clock, set-up excluded). Prints a
Markdown table for BENCHMARKS.md."""

import argparse
import json
import statistics
import subprocess

CASES = [
    ("quad_x", "prioritized", "hover"),
    ("quad_x", "prioritized", "gusts"),
    ("hexa_x", "optimal", "hover"),
    ("octo_x", "optimal", "hover"),
    ("octo_x", "optimal", "gusts"),
    ("octo_x", "prioritized", "gusts"),
    ("diff_drive", "shift", "drive"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build-release")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--duration", type=float, default=60.0)
    args = ap.parse_args()
    print(f"| vehicle | strategy | scenario | simulated s per wall s (median of {args.runs}) | range |")
    print("|---|---|---|---|---|")
    for vehicle, strategy, scenario in CASES:
        factors = []
        for _ in range(args.runs):
            out = subprocess.run([f"{args.build}/motormix", "sim", "--config", f"config/{vehicle}.yaml",
                                  "--set", f"mixer.strategy={strategy}", "--scenario", scenario,
                                  "--duration", str(args.duration), "--json"],
                                 check=False, capture_output=True, text=True).stdout
            factors.append(json.loads(out)["realtime_factor"])
        print(f"| {vehicle} | {strategy} | {scenario} | {statistics.median(factors):.0f}x | "
              f"{min(factors):.0f}-{max(factors):.0f}x |")


if __name__ == "__main__":
    main()
