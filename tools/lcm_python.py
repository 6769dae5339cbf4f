"""Locates motormix's generated Python LCM types (build/lcmtypes/python) and
the lcm module, so every tool imports them the same way."""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def add_types_path(build_dir=None):
    build_dir = build_dir or os.environ.get("MOTORMIX_BUILD_DIR", os.path.join(ROOT, "build"))
    types = os.path.join(build_dir, "lcmtypes", "python")
    if not os.path.isdir(os.path.join(types, "motormix")):
        sys.exit(f"generated LCM types not found under {types}: build the project first")
    if types not in sys.path:
        sys.path.insert(0, types)
