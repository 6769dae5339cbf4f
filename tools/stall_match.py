#!/usr/bin/env python3
"""Did the machine stall, or only motormix? Matches the largest wake-up
lateness of a `motormix run` (its --timing-report) with cyclictest's samples
taken beside it over the same minutes (cyclictest -v, one thread), on the
same clock (CLOCK_MONOTONIC).

cyclictest -v prints "thread: loop: latency_us" per cycle. Sample k woke at
start + (k + skipped) * interval + latency, where `skipped` counts the
periods cyclictest jumped over after earlier late wake-ups; `start` is read
from CLOCK_MONOTONIC just before cyclictest was started (its first period
starts a few milliseconds later: the match window allows for that).

    python3 tools/stall_match.py --cyclictest FILE --start-monotonic-us T --interval-us 1000 \\
        --motormix-timing FILE [--window-ms 50]
Prints a Markdown table: each process's largest stall and when, cyclictest's
largest within the window around motormix's, and the verdict.
"""

import argparse
import json


def samples(path, start_us, interval_us):
    """(time_us, latency_us) per cyclictest sample, on CLOCK_MONOTONIC."""
    skipped = 0
    with open(path) as f:
        for line in f:
            parts = line.replace(":", " ").split()
            if len(parts) != 3 or not all(p.isdigit() for p in parts):
                continue
            loop, latency = int(parts[1]), int(parts[2])
            t = start_us + (loop + 1 + skipped) * interval_us + latency
            yield t, latency
            skipped += latency // interval_us


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cyclictest", required=True)
    ap.add_argument("--start-monotonic-us", type=int, required=True)
    ap.add_argument("--interval-us", type=int, required=True)
    ap.add_argument("--motormix-timing", required=True)
    ap.add_argument("--window-ms", type=float, default=50.0)
    args = ap.parse_args()
    with open(args.motormix_timing) as f:
        wake = json.load(f)["wake_latency_us"]
    mm_max, mm_at = wake["max"], wake["max_at_monotonic_us"]
    worst = (0, 0)
    near = (0, 0)
    count = 0
    for t, latency in samples(args.cyclictest, args.start_monotonic_us, args.interval_us):
        count += 1
        if latency > worst[1]:
            worst = (t, latency)
        if abs(t - mm_at) <= args.window_ms * 1e3 and latency > near[1]:
            near = (t, latency)
    stalled_together = near[1] >= 0.5 * mm_max
    print("| process | largest wake-up lateness | at (CLOCK_MONOTONIC, s) |")
    print("|---|---|---|")
    print(f"| motormix run | {mm_max / 1e3:.2f} ms | {mm_at / 1e6:.3f} |")
    print(f"| cyclictest beside it ({count} samples) | {worst[1] / 1e3:.2f} ms | {worst[0] / 1e6:.3f} |")
    print(f"| cyclictest within {args.window_ms:.0f} ms of motormix's largest | {near[1] / 1e3:.2f} ms "
          f"| {near[0] / 1e6:.3f} |")
    print()
    if stalled_together:
        print(f"Verdict: the machine. cyclictest was late by {near[1] / 1e3:.2f} ms within "
              f"{args.window_ms:.0f} ms of motormix's largest stall ({mm_max / 1e3:.2f} ms): both "
              "threads were kept off the CPU together.")
    elif worst[1] >= mm_max:
        print(f"Verdict: the machine stalls this long without motormix's help. Around motormix's "
              f"largest stall ({mm_max / 1e3:.2f} ms) cyclictest was late by {near[1] / 1e3:.2f} ms "
              f"at most, but at another moment cyclictest itself stalled longer "
              f"({worst[1] / 1e3:.2f} ms): stalls of this size hit any thread on this machine, one "
              "at a time.")
    else:
        print(f"Verdict: motormix alone. cyclictest was never late by more than {near[1] / 1e3:.2f} ms "
              f"within {args.window_ms:.0f} ms of motormix's largest stall ({mm_max / 1e3:.2f} ms), "
              f"nor by more than {worst[1] / 1e3:.2f} ms anywhere.")


if __name__ == "__main__":
    main()
