#!/usr/bin/env python3
"""Flies `motormix run` against RotorPy, an outside simulator (MIT licence,
installed into .venv by scripts/python-env), in lockstep over LCM
(docs/lockstep.md): RotorPy's own Multirotor dynamics, its SE(3) controller
hovering at a height and its wind models; here only the ESCs, the sensors,
the failures and the ground that RotorPy leaves to its user.

    scripts/private-bus .venv/bin/python tools/rotorpy_bridge.py hummingbird \\
        --motormix build/motormix --fail 1@5:stop --duration 20 --json

Each step of 1/loop_rate s, at simulated time t:
  1. RotorPy's SE3Control gives the collective thrust (N) and body moments
     (N m); they go out as setpoint_t and pid_t in physical units (the
     configuration tools/rotorpy_config.py writes has inputs.units physical),
     (pid_t every step, setpoint_t every fourth), with attitude_t (attitude,
     body rates, velocity, FRD/NED) every step and esc_telemetry_t (every
     rotor's rpm) every other step;
  2. lockstep_t {t}; the bridge waits for motor_pwm_t stamped t;
  3. the ESC: rotor speed command = rotor_speed_max * (pwm - esc.min) /
     (esc.max - esc.min) (0 below esc.min: disarmed); the rotors follow with
     RotorPy's motor time constant, RotorPy integrates the step.
The vehicle starts in hover at --altitude, held in place (a hand launch)
until motormix has armed and spooled up.

Failures (--fail MOTOR@SECONDS[:KIND], motor numbered from 1), as `motormix
sim` plays them (src/sim/include/sim/motor_health.hpp): stop (commanded
speed 0: the rotor brakes with the motor's time constant, as RotorPy's
motors do), half_thrust, intermittent (150 ms off in every 500 ms), desync
(spins down over 200 ms), telemetry (the ESC's readings stop), prop_lost
(no thrust or drag; the unloaded motor runs 1.33x faster, 5x quicker, and
past the loaded motor's top speed, where RotorPy would hold it),
prop_damaged (45 % less thrust, 1.11x faster). The bridge does not tell
motormix: its detector has to find the motor.

Reported (--json): which motor motormix declared and when (motor_pwm_t's
failed_motors), the landing (first ground contact: vertical and horizontal
speed, tilt), the worst tilt and the yaw rate during the descent, and
whether motormix disarmed on the ground.
"""

import argparse
import importlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402
import rotorpy_config  # noqa: E402

KINDS = ("stop", "half_thrust", "intermittent", "desync", "telemetry", "prop_lost", "prop_damaged")
# As motormix's simulator plays them (src/sim/include/sim/motor_health.hpp).
PROP_LOST_SPEED_UP = 1.0 / 0.75
PROP_LOST_LAG = 0.2
PROP_DAMAGED_SPEED_UP = 0.831 / 0.75
PROP_DAMAGED_THRUST = 0.55 / PROP_DAMAGED_SPEED_UP ** 2
DESYNC_S = 0.2
INTERMITTENT_PERIOD_S, INTERMITTENT_OFF_S = 0.5, 0.15
# FLU <-> FRD, ENU-like world (z up) <-> NED: a half turn about x.
FLIP = np.diag([1.0, -1.0, -1.0])
EPOCH_US = int(time.time()) * 1_000_000  # simulated time starts at the wall clock (a plausible utime)
ANSWER_TIMEOUT_S = 10.0


def die_with_parent():
    """In the mixer's process before exec: SIGTERM when the bridge dies, even
    killed outright (a lockstep mixer without its simulator would wait for
    ticks forever: --max-cycles counts ticks)."""
    import ctypes
    import signal
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def parse_failure(text):
    try:
        motor, rest = text.split("@", 1)
        at, _, kind = rest.partition(":")
        kind = kind or "stop"
        if kind not in KINDS:
            raise ValueError(f"unknown kind {kind!r} (known: {', '.join(KINDS)})")
        return int(motor) - 1, float(at), kind
    except ValueError as e:
        raise argparse.ArgumentTypeError(f"--fail {text!r}: MOTOR@SECONDS[:KIND]: {e}")


class Health:
    """Per rotor at time t: the factor on the commanded speed, on the thrust
    and drag torque at a given speed (through an effective speed), on the
    time constant; whether its telemetry is alive."""

    def __init__(self, n, failures):
        self.n = n
        self.failures = failures

    def at(self, t):
        drive, prop, lag, telemetry = np.ones(self.n), np.ones(self.n), np.ones(self.n), [True] * self.n
        for motor, at, kind in self.failures:
            if t < at:
                continue
            if kind == "stop":
                drive[motor] = 0.0
            elif kind == "half_thrust":
                prop[motor] = 0.5
            elif kind == "intermittent":
                if (t - at) % INTERMITTENT_PERIOD_S < INTERMITTENT_OFF_S:
                    drive[motor] = 0.0
            elif kind == "desync":
                drive[motor] = max(0.0, 1.0 - (t - at) / DESYNC_S)
            elif kind == "telemetry":
                telemetry[motor] = False
            elif kind == "prop_lost":
                prop[motor], drive[motor], lag[motor] = 0.0, PROP_LOST_SPEED_UP, PROP_LOST_LAG
            elif kind == "prop_damaged":
                prop[motor], drive[motor] = PROP_DAMAGED_THRUST, PROP_DAMAGED_SPEED_UP
        return drive, prop, lag, telemetry


def make_vehicle(params, altitude):
    from rotorpy.vehicles.multirotor import Multirotor

    class Failing(Multirotor):
        """RotorPy's Multirotor with a per-rotor thrust factor (a thrown or
        damaged prop) and time constant: the rotor's thrust, drag torque and
        hub drag are those of a rotor turning sqrt(prop) as fast."""

        prop = None

        def compute_body_wrench(self, body_rates, rotor_speeds, body_airspeed_vector):
            speeds = rotor_speeds if self.prop is None else rotor_speeds * np.sqrt(self.prop)
            return super().compute_body_wrench(body_rates, speeds, body_airspeed_vector)

    d = rotorpy_config.derived(params)
    state = {"x": np.array([0.0, 0.0, altitude]), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]),
             "w": np.zeros(3), "wind": np.zeros(3), "rotor_speeds": np.full(params["num_rotors"], d["w_hover"])}
    vehicle = Failing(params, initial_state=state, control_abstraction="cmd_motor_speeds",
                      aero=True, enable_ground=True)
    vehicle.tau_nominal = params["tau_m"]
    return vehicle, state


class Wind:
    """RotorPy's wind models summed: a steady breeze (ConstantWind) and gusts
    (SinusoidWind) at periods of a few seconds, phases drawn from the seed.
    (RotorPy's Dryden model needs torch, which the project does not install.)"""

    def __init__(self, kind, seed):
        from rotorpy.wind.default_winds import ConstantWind, NoWind, SinusoidWind
        rng = np.random.default_rng(seed + 7919)
        if kind == "none":
            self.parts = [NoWind()]
            return
        heading = rng.uniform(0.0, 2.0 * math.pi)
        mean = 3.0 * np.array([math.cos(heading), math.sin(heading), 0.0])
        self.parts = [ConstantWind(*mean),
                      SinusoidWind(amplitudes=np.array([1.5, 1.5, 0.5]),
                                   frequencies=rng.uniform(0.15, 0.6, 3),
                                   phase=rng.uniform(0.0, 2.0 * math.pi, 3)),
                      SinusoidWind(amplitudes=np.array([0.7, 0.7, 0.3]),
                                   frequencies=rng.uniform(0.8, 2.0, 3),
                                   phase=rng.uniform(0.0, 2.0 * math.pi, 3))]

    def update(self, t, position):
        return sum(np.asarray(p.update(t, position), dtype=float) for p in self.parts)


def tilt_deg(q):
    from scipy.spatial.transform import Rotation
    up = Rotation.from_quat(q).as_matrix()[:, 2]
    return math.degrees(math.acos(max(-1.0, min(1.0, up[2]))))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("vehicle", help=", ".join(rotorpy_config.VEHICLES))
    ap.add_argument("--motormix", required=True, help="the motormix binary")
    ap.add_argument("--config", help="motormix configuration (default: tools/rotorpy_config.py's, "
                    "with the spin rate chosen by `run --check`)")
    ap.add_argument("--set", action="append", default=[], help="passed to motormix run")
    ap.add_argument("--fail", action="append", type=parse_failure, default=[], help="MOTOR@SECONDS[:KIND]")
    ap.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    ap.add_argument("--altitude", type=float, default=10.0, help="hover height, m (default 10)")
    ap.add_argument("--wind", choices=("none", "gusts"), default="none",
                    help="gusts: 3 m/s from a seeded heading, gusts of 1.5 and 0.7 m/s")
    ap.add_argument("--seed", type=int, default=1, help="wind and sensor noise (default 1)")
    ap.add_argument("--gyro-noise", type=float, default=0.01, help="gyro noise, rad/s (default 0.01)")
    ap.add_argument("--build-dir", help="where motormix's generated Python types are (default: beside --motormix)")
    ap.add_argument("--json", action="store_true", help="one JSON line of results")
    ap.add_argument("--log", help="keep motormix run's log here")
    ap.add_argument("--lcm-url", help="the bus for this flight (default: $LCM_DEFAULT_URL); flights at "
                    "the same time need one each")
    args = ap.parse_args()
    if os.environ.get("MOTORMIX_PRIVATE_BUS") != "1" and not os.environ.get("LCM_DEFAULT_URL", "").startswith("memq"):
        sys.exit("rotorpy_bridge: run it on a private bus: scripts/private-bus .venv/bin/python tools/rotorpy_bridge.py ...")

    lcm_python.add_types_path(args.build_dir or os.path.dirname(os.path.abspath(args.motormix)))
    import lcm
    from motormix import attitude_t, esc_telemetry_t, lockstep_t, motor_pwm_t, pid_t, setpoint_t
    from rotorpy.controllers.quadrotor_control import SE3Control
    from scipy.spatial.transform import Rotation

    params = rotorpy_config.load_params(args.vehicle)
    n = params["num_rotors"]
    w_max = params["rotor_speed_max"]
    rate_hz = 400.0
    dt = 1.0 / rate_hz
    tmp = tempfile.TemporaryDirectory()
    config = args.config
    if not config:
        # The spin rate: motormix's own choice at load (the default, or the
        # middle of the rates where every motor's loss has a relaxed hover).
        text = rotorpy_config.write(args.vehicle, params)
        config = os.path.join(tmp.name, f"{args.vehicle}.yaml")
        with open(config, "w") as f:
            f.write(text)

    log_path = args.log or os.path.join(tmp.name, "run.log")
    cycles = int(args.duration * rate_hz) + 400
    mixer_cmd = [args.motormix, "run", "--config", config, "--lockstep", "--max-cycles", str(cycles)]
    if args.lcm_url:
        mixer_cmd += ["--lcm-url", args.lcm_url]
    for s in args.set:
        mixer_cmd += ["--set", s]
    log = open(log_path, "w")
    mixer = subprocess.Popen(mixer_cmd, stdout=log, stderr=subprocess.STDOUT, preexec_fn=die_with_parent)

    lc = lcm.LCM(args.lcm_url) if args.lcm_url else lcm.LCM()
    answer = {}

    def on_pwm(channel, data):
        m = motor_pwm_t.decode(data)
        answer[m.utime] = m

    lc.subscribe("MOTOR_PWM", on_pwm)

    vehicle, state = make_vehicle(params, args.altitude)
    held_state = {k: np.array(v, dtype=float) for k, v in state.items()}
    wind = Wind(args.wind, args.seed)
    rng = np.random.default_rng(args.seed)
    controller = SE3Control(params)
    hover = {"x": np.array([0.0, 0.0, args.altitude]), "x_dot": np.zeros(3), "x_ddot": np.zeros(3),
             "x_dddot": np.zeros(3), "x_ddddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0, "yaw_ddot": 0.0}
    health = Health(n, args.fail)
    first_failure = min((f[1] for f in args.fail), default=None)

    result = {"vehicle": args.vehicle, "failures": [f"{m + 1}@{a:g}:{k}" for m, a, k in args.fail],
              "wind": args.wind, "seed": args.seed, "declared": [], "declared_at_s": [], "declared_s": None,
              "landed": False, "touchdown_speed_mps": None, "touchdown_horizontal_mps": None,
              "touchdown_tilt_deg": None, "max_tilt_deg": 0.0, "max_tilt_after_failure_deg": 0.0,
              "yaw_rate_at_touchdown_rad_s": None, "disarmed_on_ground": False, "lockstep_lost": False,
              "false_declarations": 0, "min_altitude_m": args.altitude}
    utime = EPOCH_US
    released_at = None
    armed_since = None
    declared_mask = 0
    t = 0.0
    wall0 = time.monotonic()
    step = 0
    steps = int(args.duration * rate_hz)
    touched = False
    after_touchdown = 0
    try:
        while step < steps:
            utime = EPOCH_US + int(round(step * dt * 1e6))
            held = released_at is None
            # The controller; the hand holds the vehicle until armed and spooled.
            ctrl = controller.update(t, state, hover)
            thrust = float(ctrl["cmd_thrust"])
            moment = FLIP @ np.asarray(ctrl["cmd_moment"], dtype=float)
            # A disarmed setpoint first (arming needs the transition), then
            # armed at zero thrust until motormix says armed (arming is
            # refused above inputs.arm_max_throttle), then the controller's.
            arm = step >= 4
            sp = setpoint_t()
            sp.utime, sp.throttle, sp.yaw, sp.armed = (
                utime, (thrust if armed_since is not None else 0.0), 0.0, arm)
            pid = pid_t()
            pid.utime, pid.roll, pid.pitch, pid.yaw = utime, float(moment[0]), float(moment[1]), float(moment[2])
            att = attitude_t()
            att.utime = utime
            r_ned = FLIP @ Rotation.from_quat(state["q"]).as_matrix() @ FLIP
            qx, qy, qz, qw = Rotation.from_matrix(r_ned).as_quat()
            att.q = [float(qw), float(qx), float(qy), float(qz)]
            rates = FLIP @ state["w"] + rng.normal(0.0, args.gyro_noise, 3)
            att.rates = [float(v) for v in rates]
            att.velocity = [float(v) for v in FLIP @ state["v"]]
            # Nothing before the first tick: until then the mixer has no time
            # and would refuse every input as from the future.
            if step > 0:
                if step % 4 == 0 or armed_since is None:
                    lc.publish("SETPOINT", sp.encode())
                lc.publish("PID", pid.encode())
                lc.publish("ATTITUDE", att.encode())
            _, _, _, telemetry = health.at(t)
            if step % 2 == 0:
                esc = esc_telemetry_t()
                esc.utime = utime
                alive = [i for i in range(n) if telemetry[i]]
                esc.count = len(alive)
                esc.motor = [i + 1 for i in alive]
                esc.rpm = [float(state["rotor_speeds"][i] * 60.0 / (2.0 * math.pi)) for i in alive]
                nan = [float("nan")] * len(alive)
                esc.erpm, esc.current_a, esc.voltage_v, esc.temperature_c, esc.consumption_mah = (
                    nan, nan, nan, nan, nan)
                if esc.count > 0 and step > 0:
                    lc.publish("ESC_TELEMETRY", esc.encode())
            tick = lockstep_t()
            tick.utime = utime
            lc.publish("MOTORMIX_LOCKSTEP", tick.encode())
            deadline = time.monotonic() + ANSWER_TIMEOUT_S
            sent = time.monotonic()
            while utime not in answer:
                if time.monotonic() > deadline or mixer.poll() is not None:
                    result["lockstep_lost"] = True
                    raise StopIteration
                lc.handle_timeout(50)
                # The first tick again until the mixer answers: it may not
                # have been listening yet (a slow start, a sanitizer build).
                # A repeat it did hear is refused and counted, nothing more.
                if step == 0 and utime not in answer and time.monotonic() - sent > 0.25:
                    lc.publish("MOTORMIX_LOCKSTEP", tick.encode())
                    sent = time.monotonic()
            out = answer.pop(utime)
            answer.clear()
            # What motormix declared, and when.
            if out.failed_motors & ~declared_mask:
                for i in range(n):
                    if (out.failed_motors >> i) & 1 and not (declared_mask >> i) & 1:
                        result["declared"].append(i + 1)
                        result["declared_at_s"].append(round(t, 4))
                        when = t - first_failure if first_failure is not None else None
                        if first_failure is None or t < first_failure:
                            result["false_declarations"] += 1
                        if result["declared_s"] is None and when is not None and when >= 0:
                            result["declared_s"] = round(when, 4)
                declared_mask |= out.failed_motors
            if out.armed and armed_since is None:
                armed_since = t
            if held and armed_since is not None and t - armed_since > 0.7:
                released_at = t
            # The ESCs and the rotors.
            drive, prop, lag, _ = health.at(t)
            pwm = np.array(out.pwm[:n], dtype=float)
            x = np.clip((pwm - rotorpy_config.ESC_MIN) / (rotorpy_config.ESC_MAX - rotorpy_config.ESC_MIN), 0.0, 1.0)
            command = np.where(pwm >= rotorpy_config.ESC_MIN, x * w_max, 0.0) * drive
            vehicle.prop = prop
            vehicle.tau_m = vehicle.tau_nominal * lag
            # RotorPy caps every rotor at the loaded motor's top speed; a
            # motor without its prop (or with less of one) is not held there:
            # unloaded, it runs on toward its no-load speed at full command.
            # The healthy rotors' commands never exceed the cap (x <= 1).
            vehicle.rotor_speed_max = w_max * max(1.0, float(np.max(drive)))
            state["wind"] = wind.update(t, state["x"])
            before = {k: np.array(v, dtype=float) for k, v in state.items()}
            state = vehicle.step(state, {"cmd_motor_speeds": command}, dt)
            if held:
                speeds = state["rotor_speeds"]
                state = {k: np.array(v, dtype=float) for k, v in held_state.items()}
                state["rotor_speeds"] = speeds
            t += dt
            step += 1
            tilt = tilt_deg(state["q"])
            result["max_tilt_deg"] = max(result["max_tilt_deg"], tilt)
            result["min_altitude_m"] = min(result["min_altitude_m"], float(state["x"][2]))
            if first_failure is not None and t >= first_failure and not touched:
                result["max_tilt_after_failure_deg"] = max(result["max_tilt_after_failure_deg"], tilt)
            if not touched and state["x"][2] <= 0.001 and before["x"][2] > 0.001:
                touched = True
                result["touchdown_speed_mps"] = round(float(-before["v"][2]), 3)
                result["touchdown_horizontal_mps"] = round(float(np.linalg.norm(before["v"][:2])), 3)
                result["touchdown_tilt_deg"] = round(tilt_deg(before["q"]), 2)
                result["yaw_rate_at_touchdown_rad_s"] = round(float(abs(before["w"][2])), 2)
                result["touchdown_s"] = round(t, 3)
            if touched:
                after_touchdown += 1
                if not out.armed:
                    result["disarmed_on_ground"] = True
                if after_touchdown > rate_hz * 1.5:
                    break
    except StopIteration:
        pass
    finally:
        mixer.terminate()
        try:
            mixer.wait(timeout=5)
        except subprocess.TimeoutExpired:
            mixer.kill()
        log.close()
    result["max_tilt_deg"] = round(result["max_tilt_deg"], 2)
    result["max_tilt_after_failure_deg"] = round(result["max_tilt_after_failure_deg"], 2)
    result["min_altitude_m"] = round(result["min_altitude_m"], 3)
    ts = result["touchdown_speed_mps"]
    result["landed"] = bool(touched and ts is not None and ts <= 2.0 and result["touchdown_tilt_deg"] <= 60.0)
    result["simulated_s"] = round(t, 3)
    result["wall_s"] = round(time.monotonic() - wall0, 2)
    if args.json:
        print(json.dumps(result))
    else:
        for k, v in result.items():
            print(f"{k}: {v}")
    with open(log_path) as f:
        text = f.read()
    if args.log is None and (result["lockstep_lost"] or os.environ.get("ROTORPY_BRIDGE_VERBOSE")):
        sys.stderr.write(text)
    return 3 if result["lockstep_lost"] else 0


if __name__ == "__main__":
    sys.exit(main())
