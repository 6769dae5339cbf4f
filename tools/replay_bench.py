#!/usr/bin/env python3
"""`motormix replay` against the floor of its job, in the same run: LCM's own
C log API (bench/log_baseline) reading the same flight and writing the same
number of events (every input event plus as many extra events, of
motor_pwm_t's size, as the replay writes outputs and statuses), nothing
computed. Wall time of each, median of N alternating runs.

    tools/replay_bench.py --build build-release [--runs 21]

The third flight, a minute of `motormix sim --scenario gusts --log`, is written
by the tool itself: per-event cost, where the bundled flights show start-up.
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build-release"))
    ap.add_argument("--runs", type=int, default=21)
    args = ap.parse_args()
    lcm_python.add_types_path(args.build)
    import lcm
    from motormix import motor_pwm_t

    # The two bundled flights (about a second each: start-up weighs), and a
    # minute of flight written here by `motormix sim --log` (the events weigh).
    flights = [("team_quad", "config/team_quad.yaml", []),
               ("hexa_motor_out", "config/hexa_x.yaml", ["--set", "inputs.yaw_source=setpoint"]),
               ("team_quad_gusts_60s", "config/team_quad.yaml", [])]
    print("| flight | events in | events out | LCM C log API ms | motormix replay ms | ratio |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, config, sets in flights:
            flight = os.path.join(ROOT, "test/data/flights", name + ".lcmlog")
            if not os.path.exists(flight):
                flight = os.path.join(tmp, name + ".lcmlog")
                subprocess.run([os.path.join(args.build, "motormix"), "sim", "--config", os.path.join(ROOT, config),
                                "--scenario", "gusts", "--duration", "60", "--log", flight],
                               check=True, capture_output=True)
            out = os.path.join(tmp, "replay.lcmlog")
            replay = [os.path.join(args.build, "motormix"), "replay", "--config", os.path.join(ROOT, config)] + sets + [flight, out]
            subprocess.run(replay, check=True, capture_output=True)
            events_in = sum(1 for _ in lcm.EventLog(flight, "r"))
            events_out = sum(1 for _ in lcm.EventLog(out, "r"))
            m = motor_pwm_t()
            m.num_motors = 4 if "team" in name else 6
            m.command = [0.0] * m.num_motors
            m.pwm = [0.0] * m.num_motors
            m.direction = [0] * m.num_motors
            size = len(m.encode())
            base = [os.path.join(args.build, "bench", "log_baseline"), flight, os.path.join(tmp, "base.lcmlog"),
                    str(events_in), str(events_out - events_in), str(size)]
            t_base, t_replay = [], []
            for _ in range(args.runs):
                t0 = time.perf_counter()
                subprocess.run(base, check=True, capture_output=True)
                t_base.append((time.perf_counter() - t0) * 1e3)
                t0 = time.perf_counter()
                subprocess.run(replay, check=True, capture_output=True)
                t_replay.append((time.perf_counter() - t0) * 1e3)
            b, r = statistics.median(t_base), statistics.median(t_replay)
            print(f"| {name} | {events_in} | {events_out} | {b:.1f} | {r:.1f} | {r / b:.2f}x |")
    print()
    print("Wall time of the whole process (start-up, configuration and exit included for both), "
          f"median of {args.runs} alternating runs.")


if __name__ == "__main__":
    main()
