#!/usr/bin/env python3
"""tools/rotorpy_config.py against RotorPy's own allocation: for each of
RotorPy's identified vehicles, the mixing matrix motormix builds from the
written configuration (`motormix matrix --format json`) must be RotorPy's
inverse allocation (SE3Control.TM_to_f: thrust and body moments to rotor
forces), turned from RotorPy's body frame (x forward, y left, z up) into
motormix's (x forward, y right, z down) and scaled per axis as motormix's
axis_max normalization does. A wrong spin, a mirrored rotor or a swapped
axis fails it.
    check_rotorpy_config.py MOTORMIX
"""

import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
import rotorpy_config  # noqa: E402

TOLERANCE = 1e-9  # both are exact inverses of the same 4x4 table


def main():
    motormix = sys.argv[1]
    try:
        from rotorpy.controllers.quadrotor_control import SE3Control
    except ImportError as e:
        print(f"SKIPPED: RotorPy is not installed ({e}; scripts/python-env installs it)")
        return 0
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name in rotorpy_config.VEHICLES:
            params = rotorpy_config.load_params(name)
            path = os.path.join(tmp, f"{name}.yaml")
            with open(path, "w") as f:
                f.write(rotorpy_config.write(name, params))
            out = subprocess.run([motormix, "matrix", "--config", path, "--format", "json"],
                                 capture_output=True, text=True, check=True).stdout
            mm = np.array(json.loads(out)["matrix"])  # rows: motors; columns: roll, pitch, yaw, thrust
            tm_to_f = SE3Control(params).TM_to_f      # columns: thrust, Mx, My, Mz (FLU)
            expected = np.column_stack([tm_to_f[:, 1], -tm_to_f[:, 2], -tm_to_f[:, 3], tm_to_f[:, 0]])
            expected = expected / np.abs(expected).max(axis=0)
            worst = float(np.abs(mm - expected).max())
            ok = worst <= TOLERANCE
            failed += not ok
            print(f"{name}: worst difference {worst:.2e} ({'ok' if ok else 'FAILED'})")
            if not ok:
                print("motormix:\n", mm, "\nRotorPy:\n", expected)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
