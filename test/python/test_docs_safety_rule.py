#!/usr/bin/env python3
"""The docs check's safety rule (tools/check_docs.py) against sentences a page
once held or could hold: each contradiction of docs/safety.md is caught, a
page that mentions a fact without linking there is caught, and a page that
states the facts and links is not."""

import os
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import check_docs  # noqa: E402

FACTS = check_docs.safety_facts(ROOT)
LINK = "See [safety.md](safety.md).\n\n"

CONTRADICTIONS = [
    # What docs/troubleshooting.md said before the safety page.
    "The motor test moves no pin through `motormix output`.",
    "The motor\ntest never moves a pin.",
    "A motor test is safe with the props on.",
    "`motormix esc-calibrate` without `--props-off` runs all the same.",
    "The mixer arms without an armed=false setpoint first.",
    "It arms at any throttle.",
    "`hardware.motor_pwm_timeout_ms` has a default of 200 ms.",
]
FINE = [
    "The motor test spins a real motor: take the props off.",
    "The motor test drives one pin through `motormix output`.",
    "`motormix esc-calibrate` refuses without `--props-off`.",
    "Arming needs armed=false, then armed=true, below `inputs.arm_max_throttle`.",
    "`hardware.motor_pwm_timeout_ms` has a default of 50 ms.",
]


def failures(text):
    return check_docs.check_safety_facts(os.path.join("docs", "page.md"), text, FACTS)


def main():
    bad = []
    if len(FACTS) < 4:
        bad.append(f"only {len(FACTS)} facts read from docs/safety.md")
    for sentence in CONTRADICTIONS:
        found = [f for f in failures(LINK + sentence + "\n") if "contradicts" in f]
        if not found:
            bad.append(f"not caught: {sentence!r}")
    for sentence in FINE:
        found = failures(LINK + sentence + "\n")
        if found:
            bad.append(f"flagged although it agrees: {sentence!r}: {found}")
    unlinked = failures("The motor test spins a real motor.\n")
    if not any("does not link" in f for f in unlinked):
        bad.append("a page mentioning the motor test without a link was not caught")
    # Code blocks and tables are not prose: a command line is not a claim.
    if failures("```sh\nmotormix motor-test --motor 1 --throttle 0.1\n```\n| motor test | row |\n"):
        bad.append("a code block or a table row was taken for prose")
    for b in bad:
        print("FAILED", b)
    print(f"docs safety rule: {len(CONTRADICTIONS)} contradictions, {len(FINE)} agreements, "
          f"{len(bad)} failures")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
