#!/usr/bin/env python3
"""Instructions and mispredicted branches per allocation call, under callgrind.

Timings on a shared 2-core VM move by 10-30 % between runs, and a rebuild
that only moves code shifts an unchanged benchmark by up to 15 %. These
counts do not move: callgrind executes the benchmark binary on a simulated
CPU and counts, for every call of a strategy's allocate(), the instructions
executed (Ir), the conditional branches (Bc) and the ones its simple
branch predictor gets wrong (Bcm). Same binary, same counts; so a change
can be judged by them when the clock cannot tell. The predictor model is
cruder than a real CPU's, so Bcm ranks branches rather than predicts time.

Usage:
  tools/instruction_counts.py --bench build-release/bench/motormix_bench [--markdown]

Needs valgrind (scripts/install-deps --profile).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

VEHICLES = ["quad_x", "hexa_x", "octo_x"]
STRATEGIES = ["clip", "shift", "prioritized_off", "prioritized_rp", "prioritized_rpy", "optimal"]
# Every strategy's entry point; the count is inclusive (what it calls too).
ENTRY = "Allocator::allocate("


def counts(bench, benchmark):
    """(events, per-call values, calls) for the allocate() calls of one benchmark."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        subprocess.run(
            ["valgrind", "--tool=callgrind", "--branch-sim=yes", f"--callgrind-out-file={out}",
             bench, f"--benchmark_filter=^{re.escape(benchmark)}$", "--benchmark_min_time=0.01"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        lines = open(out).read().splitlines()
    events = next(l for l in lines if l.startswith("events:")).split()[1:]
    names = {}
    callee = ""
    calls = 0
    total = [0] * len(events)
    for i, line in enumerate(lines):
        # callgrind names a function once, "(id) name", then by "(id)" alone.
        m = re.match(r"c?fn=\((\d+)\)(?: (.*))?", line)
        if m:
            if m.group(2):
                names[m.group(1)] = m.group(2)
            if line.startswith("cfn="):
                callee = names.get(m.group(1), "")
        elif line.startswith("calls=") and ENTRY in callee:
            calls += int(line.split("=")[1].split()[0])
            for j, value in enumerate(lines[i + 1].split()[1:]):
                total[j] += int(value)
    if calls == 0:
        raise RuntimeError(f"no call of {ENTRY} in {benchmark}")
    return events, [t / calls for t in total], calls


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", required=True, help="the motormix_bench binary")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        sys.exit("instruction_counts: valgrind not found (scripts/install-deps --profile)")
    rows = []
    for vehicle in VEHICLES:
        for strategy in STRATEGIES:
            events, per_call, calls = counts(args.bench, f"BM_Allocate/{vehicle}_{strategy}")
            value = dict(zip(events, per_call))
            rows.append((vehicle, strategy, value["Ir"], value["Bc"], value["Bcm"], calls))
    if args.markdown:
        print("| vehicle | strategy | instructions / call | branches / call | mispredicted / call |")
        print("|---|---|---|---|---|")
        for vehicle, strategy, ir, bc, bcm, _ in rows:
            print(f"| {vehicle} | {strategy} | {ir:.0f} | {bc:.1f} | {bcm:.2f} |")
    else:
        for vehicle, strategy, ir, bc, bcm, calls in rows:
            print(f"{vehicle:8s} {strategy:16s} Ir {ir:8.1f}  Bc {bc:6.2f}  Bcm {bcm:5.2f}  "
                  f"({calls} calls)")


if __name__ == "__main__":
    main()
