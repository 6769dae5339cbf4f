#!/usr/bin/env python3
"""Compares two scorecards (SIM.md) cell by cell for each vehicle's own strategy:
the healthy scenarios and the first motor out, reported and detected.

  tools/scorecard_diff.py OLD_SIM.md NEW_SIM.md > table.md

What docs/sim/realism_0.10.md was written with (OLD: SIM.md of 0.9.0).
"""
import re, sys
def tables(path):
    out = {}; veh = None; cols = None
    for line in open(path):
        m = re.match(r"^## (\w+)$", line)
        if m: veh = m.group(1); cols = None; continue
        if veh and line.startswith("| scenario"):
            cols = [c.strip() for c in line.strip().strip("|").split("|")]; continue
        if veh and cols and line.startswith("| ") and not line.startswith("|---"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            out[(veh, cells[0])] = dict(zip(cols, cells))
    return out
b, a = tables(sys.argv[1]), tables(sys.argv[2])
col = {"quad_x": "prio rp", "hexa_x": "optimal", "octo_x": "optimal", "team_quad": "legacy", "diff_drive": "shift"}
print("| vehicle (strategy) | scenario | before | after |")
print("|---|---|---|---|")
for (veh, scen), row in a.items():
    if scen not in ("hover", "steps", "flips", "battery_sag", "gusts", "drive") and not scen.startswith("motor_out m1 reported") and not scen.startswith("motor_out m1 detected both"): continue
    c = col.get(veh)
    if c not in row: continue
    print(f"| {veh} ({c}) | {scen} | {b.get((veh, scen), {}).get(c, 'n/a')} | {row[c]} |")
