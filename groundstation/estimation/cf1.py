"""CF1: the first-order complementary filter of seed 002, one angle at a time.

Seed 002 (digest §4): ``θ(n) = α (θ(n-1) + ω dt) + (1 - α) θ_acc(n)``, 0 < α < 1, for pitch and roll;
yaw is integrated from the gyro alone. Two choices the seed leaves open:

- ω is the Euler-angle rate from the body rates (``tilt.euler_rates``), not the raw gyro axis, so a
  yaw turn while banked does not leak into pitch; the two agree when level.
- α is set by a time constant, ``α = τ / (τ + dt)``, so the filter behaves the same at any sample rate:
  τ = 0.5 s gives the classic α ≈ 0.98 at 100 Hz. τ = 0 is accelerometer-only tilt.

The blend acts on the wrapped difference ``θ_acc - prediction`` so roll does not jump at ±180°.
Pitch is kept within ±90° (the ZYX range).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

from groundstation import quaternion
from groundstation.estimation.base import CommonSettings, Estimator
from groundstation.estimation.tilt import acc_pitch_roll, euler_rates, wrap_pi


@dataclasses.dataclass(frozen=True)
class Cf1Settings(CommonSettings):
    time_constant_s: float = 0.5  # τ: gyro trusted for changes faster than this; 0 = accelerometer only


class Cf1Diagnostics(NamedTuple):
    status: int
    alpha: float  # α used on this sample
    pitch_acc_rad: float  # the accelerometer's pitch and roll on this sample
    roll_acc_rad: float


class Cf1(Estimator):
    name = "cf1"
    Settings = Cf1Settings
    Diagnostics = Cf1Diagnostics

    def _reset_state(self):
        self._ypr = (0.0, 0.0, 0.0)
        self._diag = (1.0, 0.0, 0.0)

    def _set_attitude(self, q):
        self._ypr = tuple(quaternion.to_euler_zyx(q).tolist())
        self._q = q

    def _diagnostics(self, status):
        return Cf1Diagnostics(status, *self._diag)

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        yaw, pitch, roll = self._ypr
        yaw_rate, pitch_rate, roll_rate = euler_rates(roll, pitch, gx, gy, gz)
        yaw, pitch, roll = yaw + yaw_rate * dt_s, pitch + pitch_rate * dt_s, roll + roll_rate * dt_s
        if acc_ok:
            pitch_acc, roll_acc = acc_pitch_roll(ax, ay, az)
            tau = self.settings.time_constant_s
            alpha = tau / (tau + dt_s)
            pitch += (1.0 - alpha) * wrap_pi(pitch_acc - pitch)
            roll += (1.0 - alpha) * wrap_pi(roll_acc - roll)
            self._diag = (alpha, pitch_acc, roll_acc)
        pitch = min(max(pitch, -math.pi / 2), math.pi / 2)
        self._ypr = (wrap_pi(yaw), pitch, wrap_pi(roll))
        self._q = tuple(quaternion.from_euler_zyx(*self._ypr).tolist())
        return self._q, self._diagnostics(status)
