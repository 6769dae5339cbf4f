#!/usr/bin/env python3
"""Writes a motormix configuration for one of RotorPy's identified vehicles
(its parameter files: geometry, mass, inertia, rotor and motor constants),
as `motormix import px4-params` does for a PX4 airframe.

    scripts/python-env                               # RotorPy in .venv, once
    .venv/bin/python tools/rotorpy_config.py hummingbird > hummingbird.yaml
    .venv/bin/python tools/rotorpy_config.py --list

What maps, and how (RotorPy's body frame is x forward, y left, z up;
motormix's is x forward, y right, z down):

- rotor positions: (x, -y, -z); spin: RotorPy's rotor direction +1 makes a
  yaw moment about its up axis (the prop turns clockwise seen from above),
  so +1 -> cw, -1 -> ccw;
- max_thrust_n = k_eta * rotor_speed_max^2 (one rotor at full speed);
  torque_ratio_m = k_m / k_eta;
- the motors lag in speed with tau_m both ways (motor_lag: speed);
- the ESC: RotorPy takes a commanded rotor speed; tools/rotorpy_bridge.py
  commands speed = rotor_speed_max * (pwm - 1000) / 1000, so thrust goes as
  the square of the command (esc.thrust_expo 1), and the output stage
  linearizes it (thrust_model_factor 1);
- yaw damping (drag.rotational, N m per rad/s of body yaw rate): the rotor
  drag k_d acting at each hub, k_d * w_hover * r^2 summed over the rotors;
  0 when the model has no rotor drag (PX4's SIH quad X), which the spin
  landing cannot balance: the configuration is still written, and `motormix
  run --check` says so;
- drag.linear: the rotor drag at hover, k_d * w_hover per rotor (N per
  m/s). RotorPy's parasitic drag (c_D, quadratic) is not mapped;
- inputs are physical (newtons and newton-metres), what RotorPy's SE3
  controller gives.
Not mapped: rotor_speed_min (0 in these models), k_z, k_h, k_flap, the
motor noise, the lower-level controller gains.
"""

import argparse
import importlib
import math
import os
import re
import subprocess
import sys
import tempfile

VEHICLES = {
    "hummingbird": "rotorpy.vehicles.hummingbird_params",
    "crazyflie": "rotorpy.vehicles.crazyflie_params",
    "px4_sih_quadx": "rotorpy.vehicles.px4_sihsim_quadx_params",
}
GRAVITY = 9.81  # RotorPy's own
ESC_MIN, ESC_MAX = 1000.0, 2000.0


def load_params(name):
    if name not in VEHICLES:
        sys.exit(f"rotorpy_config: unknown vehicle {name!r}; known: {', '.join(VEHICLES)}")
    try:
        return importlib.import_module(VEHICLES[name]).quad_params
    except ImportError as e:
        sys.exit(f"rotorpy_config: RotorPy is not installed ({e}): run scripts/python-env and use "
                 ".venv/bin/python")


def derived(p):
    """The numbers the configuration and the bridge share."""
    n = p["num_rotors"]
    k_eta, k_m, w_max = p["k_eta"], p["k_m"], p["rotor_speed_max"]
    w_hover = math.sqrt(p["mass"] * GRAVITY / (n * k_eta))
    radii2 = [float(r[0]) ** 2 + float(r[1]) ** 2 for r in p["rotor_pos"].values()]
    return {
        "max_thrust_n": k_eta * w_max ** 2,
        "torque_ratio_m": k_m / k_eta,
        "w_hover": w_hover,
        "hover_fraction": w_hover / w_max,
        "rotational_drag": sum(p.get("k_d", 0.0) * w_hover * r2 for r2 in radii2),
        "linear_drag": n * p.get("k_d", 0.0) * w_hover,
    }


def fmt(x):
    return f"{x:.6g}"


def spin_rate_chosen(motormix, text):
    """The spin rate motormix flies this vehicle's spin landing at, as its
    `run --check` says (`motor loss: spin landing (R rad/s ...`): the default
    when the vehicle has an equilibrium there, else the middle of the widest
    run of rates that have one (motormix chooses it at load); None when no
    rate has one (the line then says why)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "vehicle.yaml")
        with open(path, "w") as f:
            f.write(text)
        out = subprocess.run([motormix, "run", "--check", "--config", path],
                             capture_output=True, text=True, check=False).stdout
    m = re.search(r"motor loss: spin landing \(([0-9.]+) rad/s", out)
    line = next((l for l in out.splitlines() if l.startswith("motor loss:")), "")
    return (float(m.group(1)) if m else None), line


def write(name, p, spin_rate=None, spin_note=""):
    d = derived(p)
    lines = [
        f"# {name}: written by tools/rotorpy_config.py from RotorPy's {VEHICLES[name]}",
        "# (RotorPy 3.0.0, MIT licence). Fly it beside RotorPy: tools/rotorpy_bridge.py;",
        "# what maps and how: the tool's header.",
        f"name: rotorpy_{name}",
        "geometry:",
        "  rotors:",
    ]
    for key, pos in p["rotor_pos"].items():
        spin = "cw" if p["rotor_directions"][list(p["rotor_pos"]).index(key)] > 0 else "ccw"
        x, y, z = (float(v) for v in pos)
        lines.append(f"    - {{position: [{fmt(x)}, {fmt(-y)}, {fmt(-z + 0.0)}], spin: {spin}, "
                     f"torque_ratio: {fmt(d['torque_ratio_m'])}}}   # RotorPy {key}")
    lines += [
        "mixer:",
        "  strategy: prioritized",
        "  prioritized: {airmode: roll_pitch, yaw_headroom: 0.15}",
        "output:",
        "  mode: unipolar",
        f"  min: {ESC_MIN:g}",
        f"  max: {ESC_MAX:g}",
        "  disarmed: 900",
        "  idle: 0.05",
        "  thrust_model_factor: 1      # the bridge's ESC: rotor speed linear in the command",
        "inputs:",
        "  units: physical             # newtons and newton-metres, as RotorPy's SE3 controller",
        "  yaw_source: pid",
        "loop_rate_hz: 400",
        "failure_detection:",
        "  sources: [telemetry, rates]",
        "vehicle:",
        f"  mass_kg: {fmt(p['mass'])}",
        f"  max_thrust_n: {fmt(d['max_thrust_n'])}   # k_eta * rotor_speed_max^2, per rotor",
        f"  torque_ratio_m: {fmt(d['torque_ratio_m'])}   # k_m / k_eta",
        f"  inertia_kgm2: [{fmt(p['Ixx'])}, {fmt(p['Iyy'])}, {fmt(p['Izz'])}]",
        f"  drag: {{linear: {fmt(d['linear_drag'])}, rotational: {fmt(d['rotational_drag'])}}}",
        "  motor_lag: speed",
        f"  time_constant_up_s: {fmt(p['tau_m'])}",
        f"  time_constant_down_s: {fmt(p['tau_m'])}",
        f"  max_rotor_speed_rad_s: {fmt(p['rotor_speed_max'])}",
    ]
    if "rotor_radius" in p:
        lines.append(f"  prop_diameter_m: {fmt(2.0 * p['rotor_radius'])}")
    lines += [
        f"  esc: {{min: {ESC_MIN:g}, max: {ESC_MAX:g}, thrust_expo: 1}}",
        "motor_loss:",
        "  mode: auto",
    ]
    if spin_rate is not None:
        lines.append(f"  spin_rate_rad_s: {spin_rate:g}   # {spin_note}")
    elif spin_note:
        lines.append(f"  # {spin_note}")
    lines.append("")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("vehicle", nargs="?", help=", ".join(VEHICLES))
    ap.add_argument("--list", action="store_true", help="list the vehicles")
    ap.add_argument("--out", help="file to write (default: standard output)")
    ap.add_argument("--motormix", help="a motormix binary: write the motor_loss.spin_rate_rad_s its "
                    "`run --check` chooses (the default, or the middle of the rates where every motor's "
                    "loss has a relaxed hover)")
    args = ap.parse_args()
    if args.list or not args.vehicle:
        for name, module in VEHICLES.items():
            print(f"{name}\t{module}")
        return 0 if args.list else 2
    params = load_params(args.vehicle)
    text = write(args.vehicle, params)
    if args.motormix:
        rate, line = spin_rate_chosen(args.motormix, text)
        if rate is None:
            note = "no spin rate has a relaxed hover for this vehicle: the spin landing stays off"
            print(f"rotorpy_config: {args.vehicle}: {line}", file=sys.stderr)
            text = write(args.vehicle, params, None, note)
        else:
            text = write(args.vehicle, params, rate, "as motormix's `run --check` chose it")
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
