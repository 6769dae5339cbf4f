#!/usr/bin/env python3
"""Independent numpy oracle for motormix's mixing matrices.

Builds every preset's effectiveness matrix from its own transcription of the
frames (angles and spins as PX4/ArduPilot number them), and seeded random
rotor geometries, computes pinv + normalization with numpy, and compares with
what `motormix matrix --format json` prints. Exit status 0 when all agree.

With --px4-params FILE...: each QGroundControl parameter file is read here
(its own parser), PX4's effectiveness is built from CA_ROTOR* as PX4's
control allocation builds it (thrust ct * axis, moment ct * (position x axis)
- ct * km * axis, defaults ct 6.5, km 0.05, axis straight up), inverted and
normalized as PX4 normalizes it, and compared with the matrix of the
configuration `motormix import px4-params` writes for that file.

    tools/mixing_oracle.py --motormix build/motormix [--random 200] [--seed 12345]
    tools/mixing_oracle.py --motormix build/motormix --px4-params hexa.params octo.params
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

TOLERANCE = 1e-9  # matrix entries, normalized units
RANK_TOL = 1e-9   # relative singular value threshold, as motormix uses
ARM = 0.25
CW, CCW = -1, +1


def rotor_e(rotors):
    """rotors: list of (position xyz, axis xyz, spin, kt, km) -> 4 x n."""
    cols = []
    for pos, axis, spin, kt, km in rotors:
        a = np.asarray(axis, float)
        t = kt * a / np.linalg.norm(a)
        torque = np.cross(np.asarray(pos, float), t) + spin * km * -t
        cols.append([torque[0], torque[1], torque[2], -t[2]])
    return np.array(cols).T


def ring(spec, arm=ARM, km=0.05):
    out = []
    for ang, spin in spec:
        r = math.radians(ang)
        out.append(((arm * math.cos(r), arm * math.sin(r), 0.0), (0, 0, -1), spin, 1.0, km))
    return rotor_e(out)


def wheels(per_side):
    n = 2 * per_side
    e = np.zeros((4, n))
    for i in range(n):
        e[2, i] = (-1 if i % 2 == 0 else 1) / n
        e[3, i] = 1.0 / n
    return e


def presets():
    h = [(-0.35, 0.17), (-0.35, -0.17), (0, 0.25), (0, -0.25), (0.35, 0.33), (0.35, -0.33)]
    hs = [CW, CCW, CCW, CW, CW, CCW]
    s = ARM * 0.75
    right, left, rear = (2 / 3 * s, s, 0), (2 / 3 * s, -s, 0), (-4 / 3 * s, 0, 0)
    y6 = [(right, CCW), (left, CW), (left, CCW), (rear, CW), (right, CW), (rear, CCW)]
    team = np.array([[1, -1, 1, 1], [-1, -1, -1, 1], [1, 1, -1, 1], [-1, 1, 1, 1]], float)
    return {
        "quad_x": ring([(45, CCW), (-135, CCW), (-45, CW), (135, CW)]),
        "quad_plus": ring([(90, CCW), (-90, CCW), (0, CW), (180, CW)]),
        "hexa_x": ring([(90, CW), (-90, CCW), (-30, CW), (150, CCW), (30, CCW), (-150, CW)]),
        "hexa_plus": ring([(0, CW), (180, CCW), (-120, CW), (60, CCW), (-60, CCW), (120, CW)]),
        "octo_x": ring([(22.5, CW), (-157.5, CW), (67.5, CCW), (157.5, CCW), (-22.5, CCW),
                        (-112.5, CCW), (-67.5, CW), (112.5, CW)]),
        "octo_plus": ring([(0, CW), (180, CW), (45, CCW), (135, CCW), (-45, CCW), (-135, CCW),
                           (-90, CW), (90, CW)]),
        "octo_coax_x8": ring([(45, CCW), (-45, CW), (-135, CCW), (135, CW), (-45, CCW), (45, CW),
                              (135, CCW), (-135, CW)]),
        "h_hexa": rotor_e([((x, y, 0), (0, 0, -1), sp, 1.0, 0.1) for (x, y), sp in zip(h, hs)]),
        "y6": rotor_e([(p, (0, 0, -1), sp, 1.0, 0.05) for p, sp in y6]),
        "differential_drive": wheels(1),
        "skid_steer_4": wheels(2),
        "skid_steer_6": wheels(3),
        "team_quad": ("table", team),
    }


def controlled_rows(e):
    return [a for a in range(4) if np.any(e[a] != 0)]


def normalize(raw, mode):
    m = raw.copy()
    if mode == "none":  # torques raw; thrust by the mean of its non-zero magnitudes
        nz = np.sum(np.abs(m[:, 3]) > np.finfo(float).eps)
        if nz:
            m[:, 3] /= np.sum(np.abs(m[:, 3])) / nz
        return m
    if mode == "axis_max":
        for a in range(4):
            s = np.max(np.abs(m[:, a]))
            if s > 0:
                m[:, a] /= s
        return m
    # px4
    def rms(a):
        nz = np.sum(np.abs(m[:, a]) > 1e-3)
        return math.sqrt(np.sum(m[:, a] ** 2) / (nz / 2.0)) if nz else 0.0
    rp = max(rms(0), rms(1))
    scales = [rp, rp, np.max(m[:, 2]), 0.0]
    nz = np.sum(np.abs(m[:, 3]) > np.finfo(float).eps)
    scales[3] = np.sum(np.abs(m[:, 3])) / nz if nz else 0.0
    for a in range(4):
        if scales[a] > 0:
            m[:, a] /= scales[a]
    return m


def oracle(e, mode="axis_max"):
    """Returns the normalized mixing matrix, or None when an axis is uncontrollable."""
    rows = controlled_rows(e)
    sv = np.linalg.svd(e, compute_uv=False)
    rank = int(np.sum(sv > RANK_TOL * sv[0])) if sv.size and sv[0] > 0 else 0
    if rank < len(rows):
        return None
    raw = np.linalg.pinv(e, rcond=RANK_TOL)
    for a in range(4):  # an axis no motor acts on is not commanded: its column is zero, not noise
        if a not in rows:
            raw[:, a] = 0.0
    return normalize(raw, mode)


def motormix_json(binary, args):
    r = subprocess.run([binary, "matrix", "--format", "json"] + args, capture_output=True, text=True)
    if r.returncode != 0:
        return r.returncode, None
    return 0, np.array(json.loads(r.stdout)["matrix"], float)


def random_rotors(rng):
    n = int(rng.integers(4, 9))
    rotors = []
    for i in range(n):
        pos = rng.uniform(-1, 1, 3) * [1, 1, 0.2]
        tilt = rng.uniform(-0.3, 0.3, 2) if rng.random() < 0.3 else np.zeros(2)
        axis = np.array([tilt[0], tilt[1], -1.0])
        spin = CW if rng.random() < 0.5 else CCW
        rotors.append((pos, axis, spin, float(rng.uniform(0.5, 1.5)), float(rng.uniform(0.01, 0.1))))
    if rng.random() < 0.1:  # now and then a degenerate one: everything on a line, one spin
        rotors = [((float(x), 0.0, 0.0), (0, 0, -1), CW, 1.0, 0.05) for x in rng.uniform(-1, 1, n)]
    return rotors


def rotors_yaml(rotors):
    lines = ["geometry:", "  rotors:"]
    for pos, axis, spin, kt, km in rotors:
        lines.append(
            f"    - {{position: [{pos[0]!r}, {pos[1]!r}, {pos[2]!r}], axis: [{axis[0]!r}, {axis[1]!r}, "
            f"{axis[2]!r}], spin: {'cw' if spin == CW else 'ccw'}, thrust_coefficient: {kt!r}, "
            f"torque_ratio: {km!r}}}")
    return "\n".join(lines) + "\n"


def px4_params(path):
    """A QGroundControl parameter file: name -> value (its own reading)."""
    values = {}
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            values[fields[2]] = float(fields[3])
    return values


def px4_effectiveness(values):
    """PX4's 6 x n rotor effectiveness (moments, then thrust), FRD."""
    n = int(values["CA_ROTOR_COUNT"])
    cols = []
    for i in range(n):
        k = f"CA_ROTOR{i}_"
        pos = np.array([values.get(k + a, 0.0) for a in ("PX", "PY", "PZ")])
        axis = np.array([values.get(k + "AX", 0.0), values.get(k + "AY", 0.0), values.get(k + "AZ", -1.0)])
        axis /= np.linalg.norm(axis)
        ct, km = values.get(k + "CT", 6.5), values.get(k + "KM", 0.05)
        cols.append(np.concatenate([ct * np.cross(pos, axis) - ct * km * axis, ct * axis]))
    return np.array(cols).T


def check_px4_params(binary, paths):
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for path in paths:
            e6 = px4_effectiveness(px4_params(path))
            if np.any(np.abs(e6[3:5]) > 0):
                failures.append(f"{path}: tilted rotors (thrust in x or y): not checked by this oracle")
                continue
            # The thrust row as motormix keeps it: upwards, positive.
            e = np.vstack([e6[0:3], -e6[5]])
            expected = oracle(e, "px4")
            out = os.path.join(tmp, "imported.yaml")
            r = subprocess.run([binary, "import", "px4-params", path, "-o", out, "--force"], capture_output=True,
                               text=True)
            if r.returncode != 0:
                failures.append(f"{path}: import exit {r.returncode}: {r.stderr.strip()}")
                continue
            rc, got = motormix_json(binary, ["--config", out])
            diff = np.max(np.abs(got - expected)) if rc == 0 and got.shape == expected.shape else None
            print(f"{os.path.basename(path)}: {e.shape[1]} rotors, largest difference from PX4's "
                  f"normalized inverse {diff if diff is not None else 'exit ' + str(rc)}")
            if diff is None or diff > TOLERANCE:
                failures.append(f"{path}: motormix {got} vs PX4 {expected}")
    for f in failures:
        print("MISMATCH", f)
    print(f"{len(paths) - len(failures)} of {len(paths)} PX4 parameter files agree, tolerance {TOLERANCE}")
    return 1 if failures else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--motormix", required=True)
    ap.add_argument("--random", type=int, default=200)
    ap.add_argument("--seed", type=int, default=12345)
    ap.add_argument("--px4-params", nargs="+", metavar="FILE")
    args = ap.parse_args()
    if args.px4_params:
        return check_px4_params(args.motormix, args.px4_params)
    failures = []
    checked = 0

    for name, e in presets().items():
        modes = ["axis_max", "px4", "none"] if not isinstance(e, tuple) else ["axis_max"]
        for mode in modes:
            expected = e[1] if isinstance(e, tuple) else oracle(e, mode)
            rc, got = motormix_json(args.motormix, ["--preset", name, "--set", f"geometry.normalization={mode}"])
            checked += 1
            if rc != 0 or got.shape != expected.shape or np.max(np.abs(got - expected)) > TOLERANCE:
                failures.append(f"preset {name} ({mode}): motormix {got} vs oracle {expected}")

    rng = np.random.default_rng(args.seed)
    degenerate = 0
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "random.yaml")
        for k in range(args.random):
            rotors = random_rotors(rng)
            with open(path, "w") as f:
                f.write(rotors_yaml(rotors))
            mode = ["axis_max", "px4", "none"][k % 3]
            expected = oracle(rotor_e(rotors), mode)
            rc, got = motormix_json(args.motormix, ["--config", path, "--set", f"geometry.normalization={mode}"])
            checked += 1
            if expected is None:
                degenerate += 1
                if rc != 2:
                    failures.append(f"random geometry {k}: oracle says uncontrollable, motormix exit {rc}")
                continue
            if rc != 0 or np.max(np.abs(got - expected)) > TOLERANCE:
                failures.append(f"random geometry {k} ({mode}): max difference "
                                f"{np.max(np.abs(got - expected)) if got is not None else 'exit ' + str(rc)}")

    for f in failures[:20]:
        print("MISMATCH", f)
    print(f"mixing oracle: {checked} matrices checked ({degenerate} degenerate geometries rejected "
          f"by both), tolerance {TOLERANCE}")
    print(f"{checked - len(failures)} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
