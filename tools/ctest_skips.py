#!/usr/bin/env python3
"""Lists the tests a ctest run skipped (from its --output-junit file), and
fails on a skip that is not on the allowed list (test/allowed_skips.txt):
ctest reports a skipped test as a success, so a test that silently stops
running would otherwise pass CI.

    python3 tools/ctest_skips.py JUNIT.xml --allowed test/allowed_skips.txt --preset NAME
"""

import argparse
import sys
import xml.etree.ElementTree as ET


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("junit")
    ap.add_argument("--allowed", required=True)
    ap.add_argument("--preset", default="")
    a = ap.parse_args()
    allowed = {}
    for line in open(a.allowed):
        line = line.strip()
        if line and not line.startswith("#"):
            name, _, why = line.partition(" ")
            allowed[name] = why.strip()
    root = ET.parse(a.junit).getroot()
    ran = skipped = 0
    unexpected = []
    for case in root.iter("testcase"):
        ran += 1
        if case.find("skipped") is None and case.get("status") not in ("notrun", "disabled"):
            continue
        skipped += 1
        name = case.get("name")
        if name in allowed:
            print(f"ctest {a.preset}: skipped {name} (allowed: {allowed[name]})")
        else:
            print(f"ctest {a.preset}: skipped {name}: NOT on the allowed list {a.allowed}")
            unexpected.append(name)
    print(f"ctest {a.preset}: {ran} tests, {skipped} skipped, {len(unexpected)} skipped unexpectedly")
    if ran == 0:
        print(f"ctest {a.preset}: no test ran")
        return 1
    return 1 if unexpected else 0


if __name__ == "__main__":
    sys.exit(main())
