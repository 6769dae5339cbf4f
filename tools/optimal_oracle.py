#!/usr/bin/env python3
"""Independent oracle for motormix's `optimal` strategy.

`optimal` minimizes gamma |W (E u - d)|^2 + |u - u_p|^2 over lower <= u <= upper
(E: the normalized effectiveness, pinv of the mixing matrix; W: the axis
weights; u_p: the linear mix clipped; gamma = 1e6). The problem is a strictly
convex quadratic program, so its optimum is the one point that satisfies the
KKT conditions. This oracle finds it by brute force, with none of motormix's
code: every assignment of each motor to "at its lower limit", "at its upper
limit" or "free" is tried (3^n of them), the free motors solved exactly, and
the assignment kept whose solution is feasible and whose multipliers have the
right signs. motormix's answers (`motormix mix --batch`, many demands in one
process) must agree to 1e-6.

    tools/optimal_oracle.py --motormix build/motormix --demands 200 --seed 7
"""

import argparse
import itertools
import json
import os
import subprocess
import sys

import numpy as np

GAMMA = 1e6
AGREEMENT = 1e-6  # normalized command units
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def kkt_optimum(E, w, d, u_pref, lo, hi):
    n = E.shape[1]
    B = w[:, None] * E
    wd = w * d
    best = None
    for states in itertools.product((0, 1, 2), repeat=n):  # 0 lower, 1 upper, 2 free
        u = np.where(np.array(states) == 0, lo, hi).astype(float)
        free = [i for i in range(n) if states[i] == 2]
        fixed = [i for i in range(n) if states[i] != 2]
        if free:
            Bf = B[:, free]
            rhs = GAMMA * Bf.T @ (wd - B[:, fixed] @ u[fixed]) + u_pref[free]
            H = GAMMA * Bf.T @ Bf + np.eye(len(free))
            u[free] = np.linalg.solve(H, rhs)
            if (u[free] < lo - 1e-9).any() or (u[free] > hi + 1e-9).any():
                continue
        # Gradient of the cost: at a lower limit it must point up (>= 0), at an
        # upper limit down (<= 0). Scaled by gamma, so the tolerance is too.
        grad = 2 * GAMMA * B.T @ (B @ u - wd) + 2 * (u - u_pref)
        tol = 1e-6 * (1 + GAMMA * np.abs(B).max())
        ok = all(grad[i] >= -tol if states[i] == 0 else grad[i] <= tol for i in fixed)
        if ok:
            cost = GAMMA * np.sum((B @ u - wd) ** 2) + np.sum((u - u_pref) ** 2)
            if best is None or cost < best[0] - 1e-12:
                best = (cost, u.copy())
    return best[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--motormix", required=True)
    ap.add_argument("--demands", type=int, default=200)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    failures = []
    checked = 0
    # Weights as configured (the defaults, and a second set that favours yaw).
    cases = [("quad_x", []), ("hexa_x", []), ("y6", []),
             ("hexa_x", ["mixer.optimal.weights={roll: 1, pitch: 2, yaw: 1, thrust: 0.1}"])]
    for preset, overrides in cases:
        sets = []
        for o in overrides:
            sets += ["--set", o]
        config = f"geometry: {{preset: {preset}}}\nmixer: {{strategy: optimal}}\n"
        path = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"oracle_{preset}_{os.getpid()}.yaml")
        with open(path, "w") as f:
            f.write(config)
        matrix = json.loads(subprocess.run([args.motormix, "matrix", "--config", path, "--format", "json"] + sets,
                                           check=True, capture_output=True, text=True).stdout)
        M = np.array(matrix["matrix"])
        E = np.linalg.pinv(M)
        w = np.array([1.0, 1.0, 0.2, 0.5])
        for o in overrides:
            if "weights" in o:
                w = np.array([1.0, 2.0, 1.0, 0.1])
        demands = np.column_stack([rng.uniform(-1, 1, (args.demands, 3)), rng.uniform(0, 1, args.demands)])
        text = "\n".join(" ".join(f"{x:.17g}" for x in d) for d in demands) + "\n"
        out = subprocess.run([args.motormix, "mix", "--config", path, "--batch"] + sets, input=text,
                             check=True, capture_output=True, text=True).stdout.splitlines()
        os.unlink(path)
        for d, line in zip(demands, out):
            got = np.array(json.loads(line)["command"])
            u_pref = np.clip(M @ d, 0.0, 1.0)
            want = kkt_optimum(E, w, d, u_pref, 0.0, 1.0)
            checked += 1
            if np.abs(got - want).max() > AGREEMENT:
                failures.append(f"{preset} {overrides} demand {d.round(4)}: motormix {got.round(7)} oracle {want.round(7)}")
    print(f"optimal oracle: {checked} demands checked by exhaustive KKT search, {len(failures)} disagreements "
          f"beyond {AGREEMENT}")
    for f in failures[:10]:
        print("  " + f)
    if failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
