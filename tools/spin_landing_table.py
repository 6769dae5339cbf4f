#!/usr/bin/env python3
"""SIM.md's table for the spin landing (docs/motor-loss-landing.md), flown
with the CLI in lockstep:

  tools/spin_landing_table.py --motormix build-release/motormix [--seeds N] [--first-seed S] > spin.md

Each row: a quad configuration, a scenario (spin_landing, spin_landing_gusts),
how the failure became known (reported after the scenario's 100 ms, found by
motormix's detector; "detected prop_lost" and "detected prop_damaged": a
thrown prop or a broken tip instead of a stop, found by the detector) and what of the real world the simulator plays
(docs/simulation.md: "realism on" is the default; a model error flies a
vehicle other than the configured one); every motor stopping at 8 s at 10 m
on N seeds from S (by default drawn fresh, printed on standard error for a
replay with --first-seed). Columns:
flights landed (not crashed, touched down no faster than 2 m/s), the worst
touchdown speed, tilt of the flights that landed and of all, spin and drift,
and the spin and opposite/neighbour thrusts settled before touchdown next to
the relaxed-hover equilibrium (motor 1's flights, first seed). Then the
robustness table: landed share against rotor inertia and model error. Then
two opposite motors stopping together (two_motor_landing and
two_motor_landing_gusts, each opposite pair): landed means not tipped over,
reached 10 m first, and touched down no faster than 3 m/s.
"""

import argparse
import json
import random
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

ON = ("realism on", [])
NO_MOMENTUM = ("without rotor momentum", ["--realism", "rotor_momentum=off",
                                          "--set", "vehicle.rotor_inertia_kgm2=0"])
ROWS = [
    ("quad_x", "spin_landing", "reported", ON),
    ("quad_x", "spin_landing", "detected", ON),
    ("quad_x", "spin_landing_gusts", "reported", ON),
    ("quad_x", "spin_landing_gusts", "detected", ON),
    ("team_quad", "spin_landing", "reported", ON),
    ("team_quad", "spin_landing", "detected", ON),
    ("team_quad", "spin_landing_gusts", "detected", ON),
    ("quad_x", "spin_landing", "reported", NO_MOMENTUM),
    ("quad_x", "spin_landing", "detected", NO_MOMENTUM),
    ("quad_x", "spin_landing_gusts", "detected", NO_MOMENTUM),
    ("team_quad", "spin_landing", "detected", NO_MOMENTUM),
    ("quad_x", "spin_landing", "detected", ("idealized (--ideal)", ["--ideal"])),
    ("quad_x", "spin_landing", "detected", ("rotor inertia x2", ["--truth", "rotor_inertia=2"])),
    # The other failures that lose a motor's thrust, found by the detector:
    # a thrown prop (its thrust gone at once) and a broken tip.
    ("quad_x", "spin_landing", "detected prop_lost", ON),
    ("quad_x", "spin_landing_gusts", "detected prop_lost", ON),
    ("team_quad", "spin_landing_gusts", "detected prop_lost", ON),
    ("quad_x", "spin_landing_gusts", "detected prop_damaged", ON),
    ("team_quad", "spin_landing_gusts", "detected prop_damaged", ON),
]
# The robustness table: the simulated vehicle off its configuration (realism
# on), each motor reported after 100 ms; columns vehicle x scenario.
ERRORS = ["rotor_inertia=2", "rotor_inertia=0.5", "mass=1.3", "mass=0.7", "inertia=1.3",
          "inertia=0.7", "drag=1.3", "drag=0.7", "time_constant=1.3", "time_constant=0.7",
          "mass=1.3,inertia=1.3,drag=1.3", "mass=0.7,inertia=0.7,drag=0.7"]
COLUMNS = [("quad_x", "spin_landing"), ("quad_x", "spin_landing_gusts"),
           ("team_quad", "spin_landing"), ("team_quad", "spin_landing_gusts")]
# Two opposite motors: the pairs (numbered as motormix matrix prints them),
# and the worlds flown: scenario, how the failures became known, model error.
PAIRS = {"quad_x": [(1, 2), (3, 4)], "team_quad": [(1, 4), (2, 3)]}
TWO_ROWS = [("two_motor_landing", "reported", ON), ("two_motor_landing", "detected", ON),
            ("two_motor_landing_gusts", "reported", ON),
            ("two_motor_landing_gusts", "detected", ON)] + [
    ("two_motor_landing", "reported", (e, ["--truth", e]))
    for e in ["rotor_inertia=2", "mass=1.3", "mass=0.7", "inertia=1.3", "inertia=0.7", "drag=1.3",
              "drag=0.7", "time_constant=1.3", "time_constant=0.7"]]


def landed_ok(r):
    """Not crashed, touched down no faster than 2 m/s."""
    return (not r["crashed"] and r.get("touchdown_speed_mps") is not None
            and r["touchdown_speed_mps"] <= 2.0)


def two_landed_ok(r):
    """Reached 10 m, not tipped over, touched down no faster than 3 m/s (the
    simulator calls above 2 m/s a crash)."""
    hard = r["crashed"] and r.get("crash_reason", "").startswith("hit the ground")
    return (r["reached_altitude"] and (not r["crashed"] or hard)
            and r.get("touchdown_speed_mps") is not None and r["touchdown_speed_mps"] <= 3.0)


def fly(motormix, config, scenario, known, world, motor, seed):
    """motor: 0-based, or a pair of 1-based motors stopping together."""
    args = [motormix, "sim", "--config", f"config/{config}.yaml", "--scenario", scenario,
            "--seed", str(seed), "--json"] + world[1]
    if known.startswith("detected"):
        args += ["--undetected", "--set", "failure_detection.enabled=true"]
    # "detected KIND": a failure of that kind rather than a stop.
    kind = known.split()[1] if len(known.split()) > 1 else "stop"
    # The scenario stops motor 1 (and 2); others instead.
    args += ["--no-scenario-failures"]
    for m in (motor if isinstance(motor, tuple) else (motor + 1,)):
        args += ["--fail", f"{m}@8:{kind}"]
    out = subprocess.run(args, capture_output=True, text=True)
    return json.loads(out.stdout)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--motormix", required=True)
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first-seed", type=int, default=None,
                   help="first seed (default: drawn fresh and printed)")
    p.add_argument("--jobs", type=int, default=2)
    a = p.parse_args()
    if a.first_seed is None:
        a.first_seed = random.SystemRandom().randrange(1_000_000, 1_000_000_000)
    print(f"spin_landing_table: seeds {a.first_seed}..{a.first_seed + a.seeds - 1} "
          f"(replay with --first-seed {a.first_seed})", file=sys.stderr)
    jobs = []
    for row in ROWS:
        for motor in range(4):
            for seed in range(a.first_seed, a.first_seed + a.seeds):
                jobs.append((row, motor, seed))
    robust = []
    for error in ERRORS:
        for (config, scenario) in COLUMNS:
            row = (config, scenario, "reported", (error, ["--truth", error]))
            for motor in range(4):
                for seed in range(a.first_seed, a.first_seed + a.seeds):
                    robust.append((row, motor, seed))
    two = []
    for config, pairs in PAIRS.items():
        for (scenario, known, world) in TWO_ROWS:
            for pair in pairs:
                for seed in range(a.first_seed, a.first_seed + a.seeds):
                    two.append(((config, scenario, known, world), pair, seed))
    with ThreadPoolExecutor(a.jobs) as pool:
        results = list(pool.map(lambda j: fly(a.motormix, *j[0], j[1], j[2]), jobs))
        robust_results = list(pool.map(lambda j: fly(a.motormix, *j[0], j[1], j[2]), robust))
        two_results = list(pool.map(lambda j: fly(a.motormix, *j[0], j[1], j[2]), two))
    print(f"Seeds {a.first_seed} to {a.first_seed + a.seeds - 1} for every motor (replay: "
          f"--first-seed {a.first_seed} --seeds {a.seeds}).")
    print()
    print("| vehicle | scenario | failure | world | landed | touchdown max (m/s) "
          "| tilt max, landed / all (deg) | spin max (rad/s) | drift max (m) "
          "| settled spin / equilibrium (rad/s) "
          "| settled opposite, neighbours / equilibrium (N) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for row in ROWS:
        rs = [r for (j, r) in zip(jobs, results) if j[0] == row]
        landed = [r for r in rs if landed_ok(r)]
        first = next(r for (j, r) in zip(jobs, results)
                     if j[0] == row and j[1] == 0 and j[2] == a.first_seed)
        settled = "n/a"
        thrusts = "n/a"
        if "spin" in first and not first["crashed"]:
            s, e = first["spin"]["settled"], first["spin"]["equilibrium"]
            settled = f"{s['rate_rad_s']:.1f} / {e['rate_rad_s']:.1f}"
            # Motor 1 failed: m2 is across from it on both quads' numbering? Name by equilibrium:
            # the largest equilibrium thrust is the opposite motor.
            eq = e["thrust_n"]
            opp = max(range(4), key=lambda i: eq[i])
            nb = [i for i in range(4) if i != opp and eq[i] > 0]
            settled_n = s["thrust_n"]
            thrusts = (f"{settled_n[opp]:.2f}, {sum(settled_n[i] for i in nb) / len(nb):.2f} / "
                       f"{eq[opp]:.2f}, {sum(eq[i] for i in nb) / len(nb):.2f}")

        def worst(key):
            vals = [r[key] for r in landed if r.get(key) is not None]
            return f"{max(vals):.2f}" if vals else "n/a"
        tilt = max(r["max_thrust_axis_tilt_deg"] for r in rs)
        tilt_landed = (f'{max(r["max_thrust_axis_tilt_deg"] for r in landed):.1f}' if landed
                       else "n/a")
        spin = max(r["max_spin_rate_rad_s"] for r in rs)
        print(f"| {row[0]} | {row[1]} | {row[2]} | {row[3][0]} | {len(landed)} of {len(rs)} "
              f"| {worst('touchdown_speed_mps')} | {tilt_landed} / {tilt:.1f} | {spin:.1f} "
              f"| {worst('drift_m')} | {settled} | {thrusts} |")
    print()
    print("Robustness: the simulated vehicle off its configuration by the factor named (all the")
    print("realism on; motormix and the controller fly the configured vehicle), each motor reported")
    print("after 100 ms: flights landed, and the largest thrust-axis tilt of all of them.")
    print()
    print("| simulated vehicle against its configuration | "
          + " | ".join(f"{c} {s}" for c, s in COLUMNS) + " |")
    print("|---|" + "---|" * len(COLUMNS))
    for error in ERRORS:
        cells = []
        for (config, scenario) in COLUMNS:
            rs = [r for (j, r) in zip(robust, robust_results)
                  if j[0][0] == config and j[0][1] == scenario and j[0][3][0] == error]
            n = sum(1 for r in rs if landed_ok(r))
            cells.append(f"{n} of {len(rs)}, {max(r['max_thrust_axis_tilt_deg'] for r in rs):.0f} deg")
        print(f"| {error.replace(',', ', ')} | " + " | ".join(cells) + " |")
    print()
    print("Two opposite motors stopping together at 8 s at 10 m, each opposite pair (quad X 1+2 and")
    print("3+4, team quad 1+4 and 2+3): landed (reached 10 m, not tipped over, touchdown no faster")
    print("than 3 m/s), the worst touchdown, tilt and spin of the flights that landed, and the")
    print("detector's latency for the later of the two motors.")
    print()
    print("| vehicle | scenario | failure | world | landed | touchdown max (m/s) "
          "| tilt max, landed / all (deg) | spin max (rad/s) | named within (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for config in PAIRS:
        for (scenario, known, world) in TWO_ROWS:
            rs = [r for (j, r) in zip(two, two_results) if j[0] == (config, scenario, known, world)]
            landed = [r for r in rs if two_landed_ok(r)]
            touchdown = max((r["touchdown_speed_mps"] for r in landed), default=None)
            tilt_landed = max((r["max_thrust_axis_tilt_deg"] for r in landed), default=None)
            spin = max((r["max_spin_rate_rad_s"] for r in landed), default=None)
            latency = [f["detected_at_s"] - f["at_s"] for r in rs for f in r["failures"]
                       if f.get("detected_at_s") is not None]
            fmt = lambda v, d: "n/a" if v is None else f"{v:.{d}f}"
            print(f"| {config} | {scenario} | {known} | {world[0]} | {len(landed)} of {len(rs)} "
                  f"| {fmt(touchdown, 2)} | {fmt(tilt_landed, 1)} / "
                  f"{max(r['max_thrust_axis_tilt_deg'] for r in rs):.1f} | {fmt(spin, 1)} "
                  f"| {fmt(max(latency) * 1000 if latency and known == 'detected' else None, 0)} |")


if __name__ == "__main__":
    main()
