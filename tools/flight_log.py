"""Reads a motormix flight log (inputs and outputs recorded from the bus, or
written by a replay) into plain numpy arrays, one record type per channel."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

lcm_python.add_types_path()
import lcm  # noqa: E402
from motormix import mixer_status_t, motor_pwm_t, pid_t, setpoint_t  # noqa: E402

DEFAULT_CHANNELS = {
    "setpoint": "pos_deseada",
    "pid": "pid",
    "motor_pwm": "motor_pwm",
    "status": "MIXER_STATUS",
}


class Flight:
    """Arrays per channel; times in seconds from the first event of the log."""

    def __init__(self, path, channels=None):
        channels = dict(DEFAULT_CHANNELS, **(channels or {}))
        decoders = {
            channels["setpoint"]: ("setpoint", setpoint_t),
            channels["pid"]: ("pid", pid_t),
            channels["motor_pwm"]: ("pwm", motor_pwm_t),
            channels["status"]: ("status", mixer_status_t),
        }
        rows = {k: [] for k in ("setpoint", "pid", "pwm", "status")}
        self.undecodable = 0
        t0 = None
        for event in lcm.EventLog(path, "r"):
            if t0 is None:
                t0 = event.timestamp
            kind = decoders.get(event.channel)
            if kind is None:
                continue
            try:
                msg = kind[1].decode(event.data)
            except Exception:  # a corrupt or foreign message: counted, not fatal
                self.undecodable += 1
                continue
            rows[kind[0]].append(((event.timestamp - t0) / 1e6, msg))
        self.path = path
        self.setpoint_t = np.array([t for t, _ in rows["setpoint"]])
        self.throttle = np.array([m.throttle for _, m in rows["setpoint"]])
        self.yaw = np.array([m.yaw for _, m in rows["setpoint"]])
        self.armed_cmd = np.array([m.armed for _, m in rows["setpoint"]], dtype=bool)
        self.pid_t = np.array([t for t, _ in rows["pid"]])
        self.roll = np.array([m.roll for _, m in rows["pid"]])
        self.pitch = np.array([m.pitch for _, m in rows["pid"]])
        self.pwm_t = np.array([t for t, _ in rows["pwm"]])
        self.pwm = np.array([m.pwm for _, m in rows["pwm"]]).reshape(len(rows["pwm"]), -1)
        self.command = np.array([m.command for _, m in rows["pwm"]]).reshape(len(rows["pwm"]), -1)
        self.armed = np.array([m.armed for _, m in rows["pwm"]], dtype=bool)
        self.status = [m for _, m in rows["status"]]
        self.status_t = np.array([t for t, _ in rows["status"]])

    @property
    def motors(self):
        return self.pwm.shape[1] if self.pwm.size else 0
