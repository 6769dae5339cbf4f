#!/usr/bin/env python3
"""Where the pulse firmware's cycles go in simavr, by function.

Run a firmware test with MOTORMIX_AVR_PROFILE=FILE (test/avr/avr_board.hpp
appends "address cycles" lines there), then:

  tools/avr_profile.py FILE --elf build-release/firmware/motormix_pulses.elf [--top N]

Each address is given to the function whose code holds it (avr-nm's sizes);
a share is of all the cycles simulated, so with several boards in one run
they add up.
"""
import argparse
import bisect
import collections
import subprocess
import sys


def functions(elf):
    out = subprocess.run(["avr-nm", "-n", "-S", "-C", elf], check=True, capture_output=True,
                         text=True).stdout
    spans = []
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[2] in "tTwW":
            spans.append((int(parts[0], 16), int(parts[1], 16), parts[3]))
        elif len(parts) == 3 and parts[1] in "tTwW":  # no size: up to the next symbol
            spans.append((int(parts[0], 16), 0, parts[2]))
    spans.sort()
    # A symbol without a size (a linker symbol such as __stack) names an
    # address only where no sized function holds it.
    sized = [(a, n) for a, n, _ in spans if n]
    return [s for s in spans if s[1] or not any(a <= s[0] < a + n for a, n in sized)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("profile")
    ap.add_argument("--elf", required=True)
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args()
    spans = functions(args.elf)
    starts = [s[0] for s in spans]
    by_function = collections.Counter()
    total = 0
    with open(args.profile) as f:
        for line in f:
            address, cycles = (int(x) for x in line.split())
            total += cycles
            i = bisect.bisect_right(starts, address) - 1
            name = "?"
            if i >= 0:
                start, size, sym = spans[i]
                name = sym if size == 0 or address < start + size else "?"
            by_function[name] += cycles
    if total == 0:
        sys.exit("avr_profile: no cycles in " + args.profile)
    print(f"{total} cycles ({total / 16e6:.3f} s at 16 MHz)")
    for name, cycles in by_function.most_common(args.top):
        print(f"{100.0 * cycles / total:6.2f} %  {cycles:>12}  {name}")


if __name__ == "__main__":
    main()
