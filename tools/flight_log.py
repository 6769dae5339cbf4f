"""Reads a motormix flight log (inputs and outputs recorded from the bus, or
written by a replay) into plain numpy arrays, one record type per channel."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lcm_python  # noqa: E402

lcm_python.add_types_path()
import lcm  # noqa: E402
from motormix import mixer_status_t, motor_pwm_t, pid_t, setpoint_t, vehicle_state_t  # noqa: E402

TYPES = (("setpoint", setpoint_t), ("pid", pid_t), ("pwm", motor_pwm_t), ("status", mixer_status_t),
         ("state", vehicle_state_t))


class Flight:
    """Arrays per message type; times in seconds from the first event of the log.

    Messages are told apart by their LCM type fingerprint, not by channel
    name, so any log works: the bundled flights, `motormix replay` output, or
    a recording made with lcm-logger under any channel names. Pass
    `channels={"setpoint": NAME, ...}` to read only those channels.
    """

    def __init__(self, path, channels=None):
        wanted = {v: k for k, v in (channels or {}).items()}
        rows = {k: [] for k, _ in TYPES}
        self.undecodable = 0
        t0 = None
        for event in lcm.EventLog(path, "r"):
            if t0 is None:
                t0 = event.timestamp
            if wanted and event.channel not in wanted:
                continue
            for kind, cls in TYPES:
                if wanted and wanted[event.channel] != kind:
                    continue
                try:
                    msg = cls.decode(event.data)
                except Exception:  # another type, or corrupt: try the next
                    continue
                rows[kind].append(((event.timestamp - t0) / 1e6, msg))
                break
            else:
                self.undecodable += 1
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
        # vehicle_state_t, in logs of `motormix sim` (empty otherwise).
        st = rows["state"]
        self.state_t = np.array([t for t, _ in st])
        self.position = np.array([m.position for _, m in st]).reshape(len(st), 3)
        self.q = np.array([m.q for _, m in st]).reshape(len(st), 4)
        self.body_rates = np.array([m.rates for _, m in st]).reshape(len(st), 3)
        self.thrust = [list(m.thrust) for _, m in st]
        self.battery_v = np.array([m.battery_v for _, m in st])
        self.crashed = bool(st) and bool(st[-1][1].crashed)

    def euler_deg(self):
        """Roll, pitch, yaw in degrees (Z-Y-X) of the simulated attitude."""
        w, x, y, z = self.q.T
        roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
        yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return np.degrees(np.stack([roll, pitch, yaw], axis=1))

    @property
    def motors(self):
        return self.pwm.shape[1] if self.pwm.size else 0
