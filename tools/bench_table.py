#!/usr/bin/env python3
"""Turns motormix_bench's JSON (--benchmark_format=json, repetitions with
aggregates) into the Markdown comparison table of BENCHMARKS.md: per vehicle
and strategy, motormix's allocation next to the bare matrix-vector product of
the same size and, for `prioritized`, the PX4-style sequential desaturation
under PX4's current rule (weak entries below 0.2 ignored) and its older one
(below float epsilon), with ratios. Uses the median CPU time of the
repetitions."""
import json
import sys

MOTORS = {"quad_x": 4, "hexa_x": 6, "octo_x": 8}
PX4_MODE = {"prioritized_off": "off", "prioritized_rp": "rp", "prioritized_rpy": "rpy"}


def scaling(median):
    """Allocation step against motor count (BM_Scaling/<strategy>/<n>) next to the bare product."""
    rows = {}
    for name, t in median.items():
        if name.startswith("BM_Scaling/"):
            _, strategy, n = name.split("/")
            rows.setdefault(strategy, {})[int(n)] = t
    if not rows:
        return
    counts = sorted({n for r in rows.values() for n in r})
    print()
    print("### Scaling with the motor count (a ring of rotors, alternating spin; ns per call)")
    print()
    print("| strategy | " + " | ".join(f"{n} motors" for n in counts) + " |")
    print("|---|" + "---|" * len(counts))
    for strategy in ("clip", "shift", "prioritized", "optimal"):
        if strategy in rows:
            print(f"| {strategy} | " + " | ".join(f"{rows[strategy].get(n, float('nan')):.1f}" for n in counts) + " |")
    bare = [median.get(f"BM_BareProduct<{n}>") for n in counts]
    print("| bare product | " + " | ".join("-" if b is None else f"{b:.1f}" for b in bare) + " |")


def unsaturated(median):
    """prioritized on demands whose linear mix fits, next to the PX4-style sequence on the same."""
    rows = []
    for preset in MOTORS:
        for strategy, mode in PX4_MODE.items():
            ours = median.get(f"BM_Unsaturated/{preset}_{strategy}")
            px4 = median.get(f"BM_Px4Unsaturated/{preset}_{mode}")
            if ours and px4:
                rows.append(f"| {preset} | {strategy} | {ours:.1f} | {px4:.1f} | {ours / px4:.2f}x |")
    if not rows:
        return
    print()
    print("### Unsaturated demands (torques within 0.1, thrust 0.4..0.6: the linear mix fits)")
    print()
    print("| vehicle | strategy | motormix ns | PX4-style ns | ratio |")
    print("|---|---|---|---|---|")
    print("\n".join(rows))


def main():
    data = json.load(open(sys.argv[1]))
    median = {}
    for b in data["benchmarks"]:
        if b.get("aggregate_name") == "median":
            median[b["run_name"]] = b["cpu_time"]
    print("| vehicle | strategy | motormix ns | bare product ns | ratio "
          "| PX4-style (0.2) ns | ratio | PX4-style (epsilon) ns | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for preset, n in MOTORS.items():
        bare = median.get(f"BM_BareProduct<{n}>")
        for name, t in sorted(median.items()):
            prefix = f"BM_Allocate/{preset}_"
            if not name.startswith(prefix):
                continue
            strategy = name[len(prefix):]
            cells = [preset, strategy, f"{t:.1f}",
                     f"{bare:.1f}" if bare else "-", f"{t / bare:.1f}x" if bare else "-"]
            for baseline in ("BM_Px4Baseline", "BM_Px4EpsilonBaseline"):
                px4 = median.get(f"{baseline}/{preset}_{PX4_MODE[strategy]}") if strategy in PX4_MODE else None
                cells += [f"{px4:.1f}" if px4 else "-", f"{t / px4:.2f}x" if px4 else "-"]
            print("| " + " | ".join(cells) + " |")
    unsaturated(median)
    scaling(median)


if __name__ == "__main__":
    main()
