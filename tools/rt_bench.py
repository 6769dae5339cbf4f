#!/usr/bin/env python3
"""motormix's loop timing next to the machine's own floor, cyclictest, in one
run (scripts/rt-bench; run it on a private bus).

For each rate (1 kHz, 8 kHz) and each setting, one `motormix run` (idle on
the bus: disarmed, publishing its outputs every cycle and its status at
10 Hz) and one cyclictest thread at the same period, one after the other:

- default: no real-time settings for either (SCHED_OTHER, any CPU);
- realtime: motormix with `realtime: {priority: 80, cpus: [1],
  lock_memory: true}` (SCHED_FIFO, affinity, mlockall and a prefaulted
  stack) and cyclictest with the same (-p 80 -a 1 -m).

Both measure the same thing: how late a periodic thread woke (actual minus
scheduled), in 1 us bins. motormix's comes from its --timing-report, which
also says what the kernel granted. cyclictest runs with --laptop so that
neither process changes /dev/cpu_dma_latency: both see the same power
management. Prints Markdown: p50, p99, p99.9 and max of each, motormix's
period percentiles and overruns, and the target (motormix p99 <= cyclictest
p99 + 10 us, max <= cyclictest max + 50 us) per row.

    scripts/private-bus python3 tools/rt_bench.py --build build-release [--seconds 30]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HISTOGRAM_US = 20000  # cyclictest's histogram range; beyond it, its max still counts

SETTINGS = {
    "default": {"motormix": [], "cyclictest": ["--policy=other"]},
    "realtime": {
        "motormix": ["--set", "realtime.priority=80", "--set", "realtime.cpus=[1]",
                     "--set", "realtime.lock_memory=true"],
        "cyclictest": ["-p", "80", "-a", "1", "-m"],
    },
}


def percentile(histogram, total, fraction):
    """Smallest whole microsecond that `fraction` of the samples do not exceed."""
    wanted = max(1, int(fraction * total + 0.5))
    seen = 0
    for us, count in enumerate(histogram):
        seen += count
        if seen >= wanted:
            return us
    return len(histogram) - 1


def run_cyclictest(rate, seconds, extra):
    interval = int(round(1e6 / rate))
    argv = ["cyclictest", "-q", "--laptop", "-t", "1", "-i", str(interval), "-D", f"{seconds}s",
            "-h", str(HISTOGRAM_US)] + extra
    out = subprocess.run(argv, capture_output=True, text=True, check=True).stdout
    histogram = [0] * HISTOGRAM_US
    stats = {}
    for line in out.splitlines():
        if line.startswith("#"):
            key, _, value = line[1:].partition(":")
            stats[key.strip()] = value.strip()
            continue
        parts = line.split()
        if len(parts) == 2 and parts[0].isdigit():
            us = int(parts[0])
            if us < HISTOGRAM_US:
                histogram[us] = int(parts[1])
    total = int(stats["Total"])
    overflows = int(stats.get("Histogram Overflows", "0").split()[0])
    # Samples past the histogram sit above every bin: percentiles that reach
    # them read as the histogram's end.
    histogram.append(overflows)
    return {
        "p50": percentile(histogram, total, 0.5), "p99": percentile(histogram, total, 0.99),
        "p999": percentile(histogram, total, 0.999), "max": int(stats["Max Latencies"].split()[0]),
        "count": total,
    }


def run_motormix(build, rate, seconds, extra):
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "timing.json")
        argv = [os.path.join(build, "motormix"), "run", "--config",
                os.path.join(ROOT, "config/quad_x.yaml"), "--set", f"loop_rate_hz={rate}",
                "--set", "status_rate_hz=10", "--max-cycles", str(int(rate * seconds)),
                "--timing-report", report] + extra
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        with open(report) as f:
            return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build-release"))
    ap.add_argument("--seconds", type=float, default=30.0)
    args = ap.parse_args()
    if os.environ.get("MOTORMIX_PRIVATE_BUS") != "1":
        sys.exit("run through scripts/private-bus")
    print("| rate | setting | granted to motormix | process | p50 us | p99 us | p99.9 us | max us "
          "| samples | target |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    periods = []
    for rate in (1000, 8000):
        for name, setting in SETTINGS.items():
            floor = run_cyclictest(rate, args.seconds, setting["cyclictest"])
            mm = run_motormix(args.build, rate, args.seconds, setting["motormix"])
            wake = mm["wake_latency_us"]
            rt = mm["realtime"]
            granted = (f"{rt['policy']} {rt['priority']}".strip() + ", cpus "
                       + ",".join(str(c) for c in rt["cpus"])
                       + (", locked" if rt["memory_locked"] else "")
                       + (", stack prefaulted" if rt["stack_prefaulted"] else "")
                       + (f", other threads on cpus {','.join(str(c) for c in rt['other_cpus'])}"
                          if rt.get("other_threads_moved") else ""))
            p99_ok = wake["p99"] <= floor["p99"] + 10
            max_ok = wake["max"] <= floor["max"] + 50
            verdict = ("met" if p99_ok and max_ok else
                       "missed: " + ", ".join(x for x, ok in (("p99", p99_ok), ("max", max_ok)) if not ok))
            print(f"| {rate} Hz | {name} | | cyclictest | {floor['p50']} | {floor['p99']} "
                  f"| {floor['p999']} | {floor['max']} | {floor['count']} | |")
            print(f"| {rate} Hz | {name} | {granted} | motormix | {wake['p50']:.0f} | {wake['p99']:.0f} "
                  f"| {wake['p999']:.0f} | {wake['max']:.0f} | {wake['count']} | {verdict} |")
            per = mm["period_us"]
            periods.append(f"| {rate} Hz | {name} | {per['p50']:.0f} | {per['p99']:.0f} | {per['p999']:.0f} "
                           f"| {per['min']:.0f} | {per['max']:.0f} | {mm['overruns']} |")
    print()
    print(f"Each run {args.seconds:.0f} s; motormix idle on the bus (disarmed, outputs every cycle). "
          "Target: motormix p99 <= cyclictest p99 + 10 us and max <= cyclictest max + 50 us.")
    print()
    print("motormix's period between cycles (its own report):")
    print()
    print("| rate | setting | p50 us | p99 us | p99.9 us | min us | max us | overruns |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(periods))


if __name__ == "__main__":
    main()
