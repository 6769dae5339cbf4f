#!/usr/bin/env python3
"""Runs the real-time end-to-end tests (the firmware in simavr paced to the
wall clock beside `motormix run` and `motormix output`), and runs again a
failed test whose simulated chip could not keep real time.

A machine busy for long (a VM whose host takes its CPU, other work on the
two cores) stops the simulated chip's clock for much of a run; the tests
judge timing only where it ran, but the host processes starve too, and a
run like that says nothing either way. The bridge prints a line tagged
[chip-busy] when the chip was absent for more than 2 % of its life or
fell behind by more than 5 ms at once
(test/avr/realtime_bridge.hpp). A failed test with that line is run again,
alone, PAUSE_S later, up to ATTEMPTS runs in all; a failed test without it
fails at once, as does one still failing on a busy machine after the last
attempt.

    retry_when_busy.py TEST_BINARY [ARGS...]
"""

import re
import subprocess
import sys
import time

ATTEMPTS = 3
BUSY_TAG = "[chip-busy]"
# Before a second attempt: a burst of other work (a build, a VM's host
# taking its CPU) often passes within seconds.
PAUSE_S = 15


def run(argv):
    """Runs the binary; returns its exit code and, per test, (failed, busy)."""
    proc = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    sys.stdout.write(proc.stdout)
    sys.stdout.flush()
    tests = {}
    current = None
    for line in proc.stdout.splitlines():
        m = re.match(r"\[ RUN      \] (\S+)", line)
        if m:
            current = m.group(1)
            tests[current] = [False, False]
            continue
        if current is None:
            continue
        if BUSY_TAG in line:
            tests[current][1] = True
        m = re.match(r"\[  FAILED  \] (\S+) \(", line)
        if m and m.group(1) == current:
            tests[current][0] = True
            current = None
        elif re.match(r"\[       OK \] ", line):
            current = None
    return proc.returncode, tests


def main():
    binary = sys.argv[1:]
    code, tests = run(binary)
    for attempt in range(2, ATTEMPTS + 1):
        if code == 0:
            return 0
        failed = [name for name, (f, _) in tests.items() if f]
        quiet = [name for name, (f, busy) in tests.items() if f and not busy]
        if quiet or not failed:
            # A failure with the chip in real time, or one outside any test
            # (the binary crashed): no second chance.
            return code or 1
        print(f"retry_when_busy: {', '.join(failed)} failed on a machine too busy to keep the "
              f"simulated chip in real time; attempt {attempt} of {ATTEMPTS}", flush=True)
        time.sleep(PAUSE_S)
        code, tests = run(binary + ["--gtest_filter=" + ":".join(failed)])
    return code


if __name__ == "__main__":
    sys.exit(main())
