#!/usr/bin/env python3
"""Flies tools/rotorpy_bridge.py over a grid (vehicles x failure kinds x
motors x winds x seeds), two flights at a time, and prints SIM.md's
"Outside world: RotorPy" table: which motor was named and how fast, landed
or not (touchdown at or below 2 m/s, tilt at or below 60 deg), touchdown
speed, worst tilt after the failure, yaw rate at touchdown; and healthy
hovers for false declarations. Seeds are drawn fresh unless given, and
printed for replay.

    scripts/private-bus .venv/bin/python tools/rotorpy_campaign.py --motormix build-release/motormix \\
        --vehicles hummingbird --kinds stop prop_lost --seeds 5 --json-out /tmp/rotorpy.jsonl
"""

import argparse
import concurrent.futures
import json
import os
import random
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def fly(motormix, vehicle, failure, wind, seed, duration, extra, slot):
    # One bus per flight in flight at once: its own multicast port.
    url = f"udpm://239.255.76.67:{7700 + slot}?ttl=0"
    cmd = [sys.executable, os.path.join(HERE, "rotorpy_bridge.py"), vehicle, "--motormix", motormix,
           "--duration", str(duration), "--wind", wind, "--seed", str(seed), "--json",
           "--lcm-url", url] + extra
    if failure:
        cmd += ["--fail", failure]
    out = subprocess.run(cmd, capture_output=True, text=True, check=False)
    lines = [l for l in out.stdout.splitlines() if l.startswith("{")]
    if not lines:
        return {"vehicle": vehicle, "failures": [failure] if failure else [], "wind": wind, "seed": seed,
                "error": (out.stderr or out.stdout)[-400:]}
    return json.loads(lines[-1])


def pct(values, q):
    values = sorted(values)
    if not values:
        return None
    return values[min(len(values) - 1, int(round(q * (len(values) - 1))))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--motormix", required=True)
    ap.add_argument("--vehicles", nargs="+", default=["hummingbird"])
    ap.add_argument("--kinds", nargs="+", default=["stop", "prop_lost", "prop_damaged"])
    ap.add_argument("--winds", nargs="+", default=["none", "gusts"])
    ap.add_argument("--seeds", type=int, default=5, help="seeds per cell (drawn fresh, printed)")
    ap.add_argument("--seed-base", type=int, help="seeds seed_base.. instead of fresh ones")
    ap.add_argument("--healthy-s", type=float, default=60.0, help="healthy hover per vehicle and wind, s")
    ap.add_argument("--fail-at", type=float, default=3.0)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json-out")
    ap.add_argument("--set", action="append", default=[])
    args = ap.parse_args()
    base = args.seed_base if args.seed_base is not None else random.SystemRandom().randrange(1, 10**6)
    print(f"rotorpy_campaign: seeds {base}..{base + args.seeds - 1} (replay with --seed-base {base})",
          file=sys.stderr)
    extra = []
    for s in args.set:
        extra += ["--set", s]
    jobs = []
    for v in args.vehicles:
        for wind in args.winds:
            jobs.append((v, None, wind, base, args.healthy_s))
            for kind in args.kinds:
                for motor in range(1, 5):
                    for k in range(args.seeds):
                        # The seed also moves the failure within half a second
                        # (a gust's phase, the gyro noise's, the motors' state).
                        at = args.fail_at + random.Random(base + k).uniform(0.0, 0.5)
                        jobs.append((v, f"{motor}@{at:.4f}:{kind}", wind, base + k, args.duration))
    results = []
    import queue
    slots = queue.Queue()
    for k in range(args.jobs):
        slots.put(k)

    def run(job):
        slot = slots.get()
        try:
            return fly(args.motormix, *job, extra, slot)
        finally:
            slots.put(slot)

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run, job) for job in jobs]
        for fut in concurrent.futures.as_completed(futures):
            r = fut.result()
            results.append(r)
            print(json.dumps(r), file=sys.stderr)
    if args.json_out:
        with open(args.json_out, "w") as f:
            for r in results:
                f.write(json.dumps(r) + "\n")
    print(table(results))
    return 0


def table(results):
    rows = ["| Vehicle | Failure | Wind | Flights | Right motor named | Named in, ms (median / worst) | "
            "Wrong motor named in the air | Landed | Touchdown, m/s (worst) | Tilt after failure, deg (worst) | "
            "Yaw rate at touchdown, rad/s | False declarations in healthy hover |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    cells = {}
    healthy = {}
    for r in results:
        if not r.get("failures"):
            healthy[(r["vehicle"], r["wind"])] = r
            continue
        kind = r["failures"][0].split(":")[-1]
        cells.setdefault((r["vehicle"], kind, r["wind"]), []).append(r)
    for (v, kind, wind), rs in sorted(cells.items()):
        ok = [r for r in rs if "error" not in r]
        right = [r for r in ok if r["declared"][:1] == [int(r["failures"][0].split("@")[0])]]
        # In the air: what is declared after the first ground contact (a
        # crash's impact) names nothing about the failure.
        wrong = [r for r in ok
                 if any(m != int(r["failures"][0].split("@")[0]) and (r.get("touchdown_s") is None or at < r["touchdown_s"])
                        for m, at in zip(r["declared"], r.get("declared_at_s", [0.0] * len(r["declared"]))))]
        times = [1e3 * r["declared_s"] for r in right if r["declared_s"] is not None]
        landed = [r for r in ok if r["landed"]]
        speeds = [r["touchdown_speed_mps"] for r in ok if r["touchdown_speed_mps"] is not None]
        tilts = [r["max_tilt_after_failure_deg"] for r in ok]
        yaws = [r["yaw_rate_at_touchdown_rad_s"] for r in ok if r["yaw_rate_at_touchdown_rad_s"] is not None]
        h = healthy.get((v, wind))
        hs = (f"{h['false_declarations']} in {h['simulated_s']:g} s" if h and "error" not in h else "not flown")
        rows.append(
            f"| {v} | {kind} | {wind} | {len(rs)} | {len(right)} | "
            + (f"{pct(times, 0.5):.1f} / {max(times):.1f}" if times else "-")
            + f" | {len(wrong)} | {len(landed)} | " + (f"{max(speeds):.2f}" if speeds else "-")
            + " | " + (f"{max(tilts):.0f}" if tilts else "-") + " | " + (f"{pct(yaws, 0.5):.0f}" if yaws else "-") + f" | {hs} |"
            + ("" if len(ok) == len(rs) else f" ({len(rs) - len(ok)} errors)"))
    return "\n".join(rows)


if __name__ == "__main__":
    sys.exit(main())
