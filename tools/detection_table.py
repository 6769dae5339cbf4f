#!/usr/bin/env python3
"""SIM.md's tables for motormix's own failure detector, flown with the CLI.

  tools/detection_table.py --motormix build-ci-release/motormix [--seeds N] [--jobs N]
                           [--false-alarm-seeds N] [--first-seed S] > detection.md

The detected and false-alarm tables fly seeds S, S + 1, ...: drawn fresh on
every run (so the tables never rest on seeds the detector was tuned on) and
printed above the tables, so a run can be replayed with --first-seed S.

Three tables, every flight in lockstep through `motormix sim --json`:
- detected: hexa X and octo X, optimal and prioritized, each motor stopping
  at hover (steps at 10.5 s, gusts at 7.0 s), never reported, found by each
  source alone and by telemetry and rates together: worst detection time,
  motors named right, crashes, altitude loss, the attitude error of the
  failure's first second and of the whole flight;
- false alarms: every aircraft configuration, healthy scenario and strategy
  on N seeds, per source: simulated hours and flights with a false
  detection, in the air and on the ground (within ON_GROUND_M of it, or
  after a crash: a strategy that cannot fly the scenario drags the vehicle
  along the ground, where contact and ground effect push it as a lost
  motor would);
- other failures (half a prop, an intermittent motor, a desync, dead
  telemetry on a working motor) with the default sources, against the same
  flights without the detector.
"""

import argparse
import json
import random
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

VEHICLES = ["quad_x", "quad_plus", "team_quad", "hexa_x", "hexa_plus", "h_hexa", "y6",
            "octo_x", "octo_plus", "octo_coax_x8"]
STRATEGIES = ["legacy_budget", "budget", "shift", "clip", "prioritized", "optimal"]
HEALTHY = ["hover", "steps", "flips", "gusts", "battery_sag"]
SOURCES = {"telemetry": "[telemetry]", "rates": "[rates]", "both": "[telemetry, rates]",
           "outputs": "[outputs]"}
AT = {"steps": 10.5, "gusts": 7.0}
ON_GROUND_M = 0.5  # a declaration this close to the ground is not one in flight
MOTORS = {"hexa_x": 6, "octo_x": 8}


def fly(motormix, config, scenario, seed, sets, fail=None):
    args = [motormix, "sim", "--config", f"config/{config}.yaml", "--scenario", scenario,
            "--seed", str(seed), "--json", "--undetected"]
    for s in sets:
        args += ["--set", s]
    if fail:
        args += ["--fail", fail]
    out = subprocess.run(args, capture_output=True, text=True, check=False)
    if not out.stdout.strip():
        raise RuntimeError(" ".join(args) + ": " + out.stderr.strip())
    return json.loads(out.stdout)


def detected_table(motormix, seeds, pool, first=1):
    jobs = []
    for vehicle, n in MOTORS.items():
        for strategy in ("optimal", "prioritized"):
            for source, sources in SOURCES.items():
                for scenario, at in AT.items():
                    for motor in range(1, n + 1):
                        for seed in range(first, first + seeds):
                            sets = [f"mixer.strategy={strategy}",
                                    f"failure_detection.sources={sources}"]
                            jobs.append(((vehicle, strategy, source, scenario),
                                         (vehicle, scenario, seed, sets, f"{motor}@{at}")))
    results = pool.map(lambda j: (j[0], fly(motormix, *j[1])), jobs)
    cells = {}
    for key, r in results:
        c = cells.setdefault(key, {"flights": 0, "named": 0, "missed": 0, "crashed": 0,
                                   "worst_ms": 0.0, "loss": 0.0, "fatt": 0.0, "att": 0.0})
        f = r["failures"][0]
        c["flights"] += 1
        if f["detected_at_s"] is None:
            c["missed"] += 1
        else:
            c["worst_ms"] = max(c["worst_ms"], (f["detected_at_s"] - f["at_s"]) * 1e3)
            c["named"] += f["detected_motor"] == f["motor"]
        c["crashed"] += r["crashed"]
        c["loss"] = max(c["loss"], r["altitude_loss_m"])
        c["fatt"] = max(c["fatt"], r["failure_attitude_error_max_deg"])
        c["att"] = max(c["att"], r["attitude_error_max_deg"])
    lines = ["| vehicle | strategy | source | scenario | flights | named right | missed | crashed "
             "| worst detection ms | altitude loss m | attitude error, first second ° "
             "| attitude error, whole flight ° |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (vehicle, strategy, source, scenario), c in cells.items():
        worst = f"{c['worst_ms']:.1f}" if c["named"] else "-"
        lines.append(f"| {vehicle} | {strategy} | {source} | {scenario} | {c['flights']} "
                     f"| {c['named']} | {c['missed']} | {c['crashed']} | {worst} "
                     f"| {c['loss']:.2f} | {c['fatt']:.1f} | {c['att']:.1f} |")
    return "\n".join(lines)


def false_alarm_table(motormix, seeds, pool, first=1):
    sets_by_source = {"default": ["failure_detection.enabled=true"]}
    for source in ("telemetry", "rates", "outputs"):
        sets_by_source[source] = [f"failure_detection.sources={SOURCES[source]}"]
    jobs = []
    for source, sets in sets_by_source.items():
        for vehicle in VEHICLES:
            if source == "outputs" and vehicle in ("quad_x", "quad_plus", "team_quad"):
                continue  # outputs need six rotors or more
            for strategy in STRATEGIES:
                for scenario in HEALTHY:
                    for seed in range(first, first + seeds):
                        jobs.append(((source, vehicle), (vehicle, scenario, seed,
                                                         sets + [f"mixer.strategy={strategy}"])))
    results = pool.map(lambda j: (j[0], fly(motormix, *j[1]), j[1]), jobs)
    cells = {}
    for key, r, job in results:
        c = cells.setdefault(key, {"flights": 0, "air": 0, "ground": 0, "seconds": 0.0,
                                   "where": set()})
        c["flights"] += 1
        c["seconds"] += r["sim_seconds"]
        if r["false_detections"]:
            # A healthy flight has no failure: every declaration is false.
            in_air = any(d["height_m"] >= ON_GROUND_M and not d["crashed"]
                         for d in r["detections"])
            c["air" if in_air else "ground"] += 1
            c["where"].add(f"{job[3][-1].split('=')[1]} {job[1]}"
                           + ("" if in_air else " (ground)"))
    lines = ["| sources | vehicle | flights | simulated h | flights with a false detection in the "
             f"air | on the ground (below {ON_GROUND_M} m, or crashed) | where |",
             "|---|---|---|---|---|---|---|"]
    for (source, vehicle), c in cells.items():
        where = ", ".join(sorted(c["where"])[:4]) + (" ..." if len(c["where"]) > 4 else "")
        lines.append(f"| {source} | {vehicle} | {c['flights']} | {c['seconds'] / 3600:.2f} "
                     f"| {c['air']} | {c['ground']} | {where} |")
    return "\n".join(lines)


def other_failures_table(motormix, pool):
    jobs = []
    for vehicle, n in MOTORS.items():
        for kind in ("half_thrust", "intermittent", "desync", "telemetry"):
            for motor in range(1, n + 1):
                for detector in (False, True):
                    sets = ["failure_detection.enabled=true"] if detector else []
                    jobs.append(((vehicle, kind, detector),
                                 (vehicle, "steps", 1, sets, f"{motor}@10.5:{kind}")))
    results = pool.map(lambda j: (j[0], fly(motormix, *j[1])), jobs)
    cells = {}
    for key, r in results:
        c = cells.setdefault(key, {"flights": 0, "crashed": 0, "detected": 0, "false": 0,
                                   "by": set(), "fatt": 0.0})
        f = r["failures"][0]
        c["flights"] += 1
        c["crashed"] += r["crashed"]
        c["false"] += r["false_detections"]
        c["fatt"] = max(c["fatt"], r.get("failure_attitude_error_max_deg", 0.0))
        if f["detected_at_s"] is not None:
            c["detected"] += 1
            c["by"].add(f["detected_by"])
    lines = ["| vehicle | failure | detector | flights | crashed | detected | by "
             "| healthy motors declared | attitude error, first second ° |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (vehicle, kind, detector), c in cells.items():
        lines.append(f"| {vehicle} | {kind} | {'on' if detector else 'off'} | {c['flights']} "
                     f"| {c['crashed']} | {c['detected']} | {', '.join(sorted(c['by'])) or '-'} "
                     f"| {c['false']} | {c['fatt']:.1f} |")
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--motormix", required=True)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--false-alarm-seeds", type=int, default=10)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--only", choices=["detected", "false", "other"], default=None)
    p.add_argument("--first-seed", type=int, default=None,
                   help="the campaigns' first seed (default: drawn fresh, printed)")
    a = p.parse_args()
    first = a.first_seed if a.first_seed is not None else random.randrange(1_000_000, 1_000_000_000)
    print(f"Seeds drawn for this run: from {first} (replay: `--first-seed {first}`).\n")
    with ThreadPoolExecutor(a.jobs) as pool:
        if a.only in (None, "detected"):
            print(f"### Detected: each motor stopping at hover, never reported "
                  f"(seeds {first}-{first + a.seeds - 1})\n")
            print(detected_table(a.motormix, a.seeds, pool, first) + "\n")
        if a.only in (None, "false"):
            print(f"### False alarms: healthy flights, {a.false_alarm_seeds} seeds "
                  f"({first}-{first + a.false_alarm_seeds - 1})\n")
            print(false_alarm_table(a.motormix, a.false_alarm_seeds, pool, first) + "\n")
        if a.only in (None, "other"):
            print("### Other failures (steps, at 10.5 s, seed 1, default sources)\n")
            print(other_failures_table(a.motormix, pool) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
