#!/usr/bin/env python3
"""Replays seeded, damaged copies of flight logs through `motormix replay` and
reports how each ended: damaged copies (flipped bytes, broken headers,
truncation, shifted or garbled timestamps, random garbage), each run under a
time limit. Checks that no run crashes or hangs, that the exit status says
whether the log was damaged, and that the output stays within the bound the
README promises (one cycle per loop period of the time covered, plus inputs).
Prints a Markdown table; exits 1 on any violation.

    tools/corrupt_logs.py --motormix build/motormix --config config/team_quad.yaml \\
        --count 100 --seed 1 test/data/flights/*.lcmlog
"""
import argparse
import os
import random
import re
import struct
import subprocess
import sys
import tempfile

SYNC = 0xEDA1DA01


def events(data):
    """Offsets of the events of an intact log."""
    out, off = [], 0
    while off + 28 <= len(data):
        sync, _num, _ts, cl, dl = struct.unpack(">IqqII", data[off:off + 28])
        if sync != SYNC:
            break
        out.append(off)
        off += 28 + cl + dl
    return out


def damage(data, offs, rng, kind):
    b = bytearray(data)
    if kind == "flip":
        for _ in range(rng.randint(1, 30)):
            b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)
    elif kind == "header":
        for _ in range(rng.randint(1, 5)):
            o = rng.choice(offs)
            b[o + rng.randrange(28)] = rng.randrange(256)
    elif kind == "truncate":
        del b[rng.randrange(len(b)):]
    elif kind == "timestamp":
        for _ in range(rng.randint(1, 5)):
            o = rng.choice(offs)
            struct.pack_into(">q", b, o + 12, rng.choice(
                [0, -1, 2**62, struct.unpack(">q", b[o + 12:o + 20])[0] + rng.randint(-10**12, 10**12)]))
    elif kind == "shift":
        k = rng.randrange(len(offs))
        delta = rng.choice([-1, 1]) * rng.randint(20, 10**6) * 10**6
        for o in offs[k:]:
            ts = struct.unpack(">q", b[o + 12:o + 20])[0]
            struct.pack_into(">q", b, o + 12, ts + delta)
    elif kind == "garbage":
        at = rng.randrange(len(b))
        b[at:at] = os.urandom(rng.randint(1, 5000)) if rng.random() < 0.5 else bytes(rng.randint(1, 5000))
    return bytes(b)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--motormix", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--count", type=int, default=100, help="damaged copies per log")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per replay")
    ap.add_argument("logs", nargs="+")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    kinds = ["flip", "header", "truncate", "timestamp", "shift", "garbage"]
    rate = float(re.search(r"loop_rate_hz:\s*([0-9.]+)", open(args.config).read() + "loop_rate_hz: 400").group(1))
    stats = {k: {"runs": 0, "ok": 0, "damaged": 0, "no_events": 0, "bad": 0} for k in kinds}
    problems = []
    with tempfile.TemporaryDirectory() as tmp:
        for log in args.logs:
            data = open(log, "rb").read()
            offs = events(data)
            for i in range(args.count):
                kind = kinds[i % len(kinds)]
                src = os.path.join(tmp, "in.lcmlog")
                out = os.path.join(tmp, "out.lcmlog")
                open(src, "wb").write(damage(data, offs, rng, kind))
                if os.path.exists(out):
                    os.remove(out)
                s = stats[kind]
                s["runs"] += 1
                try:
                    r = subprocess.run([args.motormix, "replay", "--config", args.config, src, out],
                                       capture_output=True, text=True, timeout=args.timeout)
                except subprocess.TimeoutExpired:
                    s["bad"] += 1
                    problems.append(f"{log} #{i} ({kind}): hung past {args.timeout} s")
                    continue
                if r.returncode in (0, 3):
                    s["ok" if r.returncode == 0 else "damaged"] += 1
                    m = re.search(r"duration\s+([0-9.]+) s", r.stdout)
                    n = re.search(r"(\d+) inputs, (\d+) other events copied, (\d+) outputs", r.stdout)
                    d = re.search(r"(\d+) time discontinuities", r.stdout)
                    if not (m and n and d):
                        s["bad"] += 1
                        problems.append(f"{log} #{i} ({kind}): no summary: {r.stdout[-200:]}")
                        continue
                    outputs, segments = int(n.group(3)), int(d.group(1)) + 1
                    if outputs > rate * float(m.group(1)) + segments + 1:
                        s["bad"] += 1
                        problems.append(f"{log} #{i} ({kind}): {outputs} outputs over {m.group(1)} s")
                elif r.returncode == 1 and "holds no valid events" in r.stderr:
                    s["no_events"] += 1
                else:
                    s["bad"] += 1
                    problems.append(f"{log} #{i} ({kind}): exit {r.returncode}: {r.stderr[-300:]}")
    print("| damage | replays | exit 0 (intact structure) | exit 3 (damaged, reported) | no valid event | crash, hang or bound broken |")
    print("|---|---|---|---|---|---|")
    for k in kinds:
        s = stats[k]
        print(f"| {k} | {s['runs']} | {s['ok']} | {s['damaged']} | {s['no_events']} | {s['bad']} |")
    for p in problems:
        print(f"\n- {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
