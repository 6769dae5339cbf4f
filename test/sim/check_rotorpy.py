#!/usr/bin/env python3
"""motormix in an outside world: RotorPy's AscTec Hummingbird (identified
parameters, RotorPy's own dynamics, SE(3) controller and wind), driving
`motormix run --lockstep` through tools/rotorpy_bridge.py with the
configuration tools/rotorpy_config.py writes and the default detection
settings. ctest runs it under scripts/private-bus.

Seeds are drawn fresh at each run and printed (rerun one with --seed).
Three flights in RotorPy's wind:
  - 20 s of healthy hover: no motor declared, height held within 0.5 m;
  - a motor (drawn) stopped at 3 s: that motor named first, within 50 ms,
    no other, and landed (touchdown at or below 2 m/s, tilt at or below 60
    deg) with the motors disarmed on the ground;
  - a prop (drawn) thrown at 3 s: that motor named first, within 50 ms, no
    other.
And one on RotorPy's PX4 SIH quad X, whose motors lag 50 ms both ways: a
prop (drawn) thrown at 3 s, named first within 50 ms, and never the motor
across from it, which slows exactly as commanded (no landing asked: this
quad does not land on three rotors yet).
    check_rotorpy.py PYTHON MOTORMIX [--seed N]
"""

import json
import os
import random
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
BRIDGE = os.path.join(HERE, "..", "..", "tools", "rotorpy_bridge.py")
NAMED_WITHIN_S = 0.050
LANDED_SPEED_MPS = 2.0
LANDED_TILT_DEG = 60.0
HOVER_BAND_M = 0.5


def fly(python, motormix, seed, *args, vehicle="hummingbird"):
    cmd = [python, BRIDGE, vehicle, "--motormix", motormix, "--wind", "gusts", "--seed", str(seed),
           "--json", *args]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=240, check=False)
    lines = [l for l in out.stdout.splitlines() if l.startswith("{")]
    if out.returncode != 0 or not lines:
        print(out.stdout, out.stderr)
        raise SystemExit(f"FAILED: the bridge exited {out.returncode}: {' '.join(cmd)}")
    r = json.loads(lines[-1])
    print(json.dumps(r))
    return r


def main():
    python, motormix = sys.argv[1], sys.argv[2]
    if subprocess.run([python, "-c", "import rotorpy, lcm"], capture_output=True, check=False).returncode:
        print(f"SKIPPED: RotorPy or LCM's Python bindings are not in {python} (scripts/python-env installs them)")
        return 0
    seed = int(sys.argv[sys.argv.index("--seed") + 1]) if "--seed" in sys.argv else random.SystemRandom().randrange(1, 10**6)
    rng = random.Random(seed)
    stopped, thrown, sih_thrown = rng.randrange(1, 5), rng.randrange(1, 5), rng.randrange(1, 5)
    print(f"check_rotorpy: seed {seed} (rerun: --seed {seed}); stop motor {stopped}, throw prop {thrown}, "
          f"SIH quad's prop {sih_thrown}")
    failures = []

    healthy = fly(python, motormix, seed, "--duration", "20", "--altitude", "10")
    if healthy["declared"]:
        failures.append(f"healthy hover: motors {healthy['declared']} declared")
    if healthy["min_altitude_m"] < 10.0 - HOVER_BAND_M:
        failures.append(f"healthy hover: down to {healthy['min_altitude_m']} m")

    for vehicle, kind, motor, must_land, duration in (
            ("hummingbird", "stop", stopped, True, "20"), ("hummingbird", "prop_lost", thrown, False, "20"),
            ("px4_sih_quadx", "prop_lost", sih_thrown, False, "4")):
        r = fly(python, motormix, seed, "--duration", duration, "--fail", f"{motor}@3:{kind}", vehicle=vehicle)
        name = f"{vehicle}: {kind} of motor {motor}"
        if r["declared"][:1] != [motor]:
            failures.append(f"{name}: declared {r['declared']}")
        elif r["declared_s"] is None or r["declared_s"] > NAMED_WITHIN_S:
            failures.append(f"{name}: named after {r['declared_s']} s (bound {NAMED_WITHIN_S})")
        if len(r["declared"]) > 1:
            failures.append(f"{name}: also declared {r['declared'][1:]}")
        if must_land:
            if not r["landed"]:
                failures.append(f"{name}: not landed (touchdown {r['touchdown_speed_mps']} m/s, "
                                f"tilt {r['touchdown_tilt_deg']} deg; bounds {LANDED_SPEED_MPS}, {LANDED_TILT_DEG})")
            if not r["disarmed_on_ground"]:
                failures.append(f"{name}: not disarmed on the ground")
    for f in failures:
        print("FAILED", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
