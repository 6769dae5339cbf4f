#!/usr/bin/env python3
"""CPU and timing of `motormix run`'s loop against a bare LCM timer process
(bench/raw_loop: timerfd, drain, publish one message per tick), in the same
run, on a private bus (run through scripts/private-bus). Both are idle on
the bus (disarmed, no inputs): the cost of keeping the loop alive.

For each rate: CPU seconds used by each process over the same number of
cycles (from the kernel's accounting, os.wait4), and the ratio. At 8 kHz,
motormix's own period statistics over a longer run (from mixer_status_t:
the median of the per-window p99 and the largest max, and the overruns),
with and without the `realtime:` settings (SCHED_FIFO 50, mlockall), next to
the bare process's own period p50/p99/max.

    scripts/private-bus .venv/bin/python tools/loop_bench.py --build build-release [--seconds 10] [--jitter-seconds 60]
"""

import argparse
import os
import statistics
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def cpu_of(argv, stderr=subprocess.DEVNULL, stdout=subprocess.PIPE):
    p = subprocess.Popen(argv, stdout=stdout, stderr=stderr)
    _, status, ru = os.wait4(p.pid, 0)
    out = p.stdout.read().decode() if p.stdout else ""
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{argv[0]} failed")
    return ru.ru_utime + ru.ru_stime, out


def motormix_argv(build, rate, cycles, extra=()):
    return [os.path.join(build, "motormix"), "run", "--config", os.path.join(ROOT, "config/quad_x.yaml"),
            "--set", f"loop_rate_hz={rate}", "--set", "status_rate_hz=10",
            "--max-cycles", str(cycles)] + list(extra)


def status_windows(build, rate, seconds, extra):
    import lcm
    from motormix import mixer_status_t

    lc = lcm.LCM()
    windows = []

    def on_status(channel, data):
        windows.append(mixer_status_t.decode(data))

    lc.subscribe("MIXER_STATUS", on_status)
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            lc.handle_timeout(50)

    t = threading.Thread(target=spin)
    t.start()
    p = subprocess.Popen(motormix_argv(build, rate, int(rate * seconds), extra), stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE)
    _, err = p.communicate()
    time.sleep(0.2)
    stop.set()
    t.join()
    refused = "refused" in err.decode()
    useful = [w for w in windows if w.cycles > rate][1:-1]  # whole windows only
    if not useful:
        return None
    p99 = statistics.median(w.period_us[3] for w in useful)
    mean = statistics.mean(w.period_us[1] for w in useful)
    worst = max(w.period_us[2] for w in useful)
    return mean, p99, worst, useful[-1].overruns, refused


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build-release"))
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--jitter-seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    if os.environ.get("MOTORMIX_PRIVATE_BUS") != "1":
        sys.exit("run through scripts/private-bus")
    lcm_python.add_types_path(args.build)
    raw = os.path.join(args.build, "bench", "raw_loop")

    print("| rate | cycles | bare LCM timer process CPU s | motormix run CPU s | ratio | ratio of each pair of runs |")
    print("|---|---|---|---|---|---|")
    raw_periods = {}
    for rate in (400, 8000):
        cycles = int(rate * args.seconds)
        raw_runs, mm_runs = [], []
        for _ in range(args.repeats):  # alternating, median: this machine is noisy
            raw_cpu, raw_out = cpu_of([raw, str(rate), str(cycles)])
            mm_cpu, _ = cpu_of(motormix_argv(args.build, rate, cycles))
            raw_runs.append(raw_cpu)
            mm_runs.append(mm_cpu)
        raw_periods[rate] = raw_out.strip()
        raw_cpu, mm_cpu = statistics.median(raw_runs), statistics.median(mm_runs)
        pairs = sorted(m / r for m, r in zip(mm_runs, raw_runs))
        spread = ", ".join(f"{x:.2f}" for x in pairs)
        print(f"| {rate} Hz | {cycles} | {raw_cpu:.3f} | {mm_cpu:.3f} | {mm_cpu / raw_cpu:.2f}x | {spread} |")
    print()
    print(f"CPU seconds (user + system, from the kernel) over the whole process life, median of "
          f"{args.repeats} alternating runs; the last column shows how far single pairs of runs "
          f"scatter on this machine.")
    print()
    print("Bare process, its own periods: " + "; ".join(raw_periods.values()))
    print()
    print(f"8 kHz period jitter of motormix run over {args.jitter_seconds:.0f} s (from its status windows):")
    print()
    print("| settings | mean period us | median window p99 us | max us | overruns | real-time granted |")
    print("|---|---|---|---|---|---|")
    for label, extra in (("default", []),
                         ("realtime: {priority: 50, lock_memory: true}",
                          ["--set", "realtime.priority=50", "--set", "realtime.lock_memory=true"])):
        r = status_windows(args.build, 8000, args.jitter_seconds, extra)
        if r is None:
            print(f"| {label} | no status received | | | | |")
            continue
        mean, p99, worst, overruns, refused = r
        granted = "not requested" if not extra else ("no (refused)" if refused else "yes")
        print(f"| {label} | {mean:.1f} | {p99:.1f} | {worst:.1f} | {overruns} | {granted} |")


if __name__ == "__main__":
    main()
