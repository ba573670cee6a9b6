"""KF: the per-axis Kalman filter of the MPU-6050 articles in seed 002, for pitch and for roll.

Each axis has the state (angle, gyro bias); the gyro rate is the input and the accelerometer's angle
the measurement (digest §4). Per axis, with ω dt the angle's change over the sample, read from the
attitude quaternion integrated with the body rates (seed 000 eq. 6, 19; no gimbal lock at ±90° pitch,
whatever the mounting):

- predict:  ``angle += (ω - bias) dt``;  ``P ← F P Fᵀ + diag(q_angle, q_bias) dt``,  F = [[1, -dt], [0, 1]]
- update:   ``y = angle_acc - angle`` (wrapped, bounded by ``innovation_max_rad``); ``S = P00 + r``; ``K = P[:, 0] / S``;
  ``[angle, bias] += K y``; ``P ← (I - K [1, 0]) P``

The bias is bounded, ``|bias| ≤ bias_max_rad_s``: under fast translation the accelerometer angle is
wrong for seconds and the bias state would otherwise wind up to rates no gyro bias has (BROAD trials 16
and 21: 77° and 57°). Yaw is integrated from the gyro alone. The noise defaults are the classic Arduino/MPU-6050 values
(Q_angle = 0.001, Q_bias = 0.003, R_measure = 0.03, in degree units) converted to radians; like the
original, the filter starts with P = 0, i.e. confident in the accelerometer initialisation.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

from groundstation import quaternion
from groundstation.estimation.base import CommonSettings, Estimator, integrate_rate
from groundstation.estimation.tilt import acc_pitch_roll, euler_of, quaternion_of, wrap_pi

_DEG2 = (math.pi / 180.0) ** 2


@dataclasses.dataclass(frozen=True)
class KfSettings(CommonSettings):
    q_angle_rad2_s: float = 0.001 * _DEG2  # angle process noise, rad² per second
    q_bias_rad2_s3: float = 0.003 * _DEG2  # bias random walk, (rad/s)² per second
    r_angle_rad2: float = 0.03 * _DEG2  # accelerometer-angle measurement variance, rad²
    bias_max_rad_s: float = 0.01  # |bias| bound per axis (no wind-up under fast translation); inf = off
    innovation_max_rad: float = 0.01  # |y| bound: a wilder accelerometer angle counts as this much


class KfDiagnostics(NamedTuple):
    status: int
    pitch_bias_rad_s: float  # estimated bias of the pitch and roll rates
    roll_bias_rad_s: float
    pitch_std_rad: float  # √P00: the filter's own angle uncertainty
    roll_std_rad: float


class _Axis:
    """One angle with its rate bias: the two-state filter above."""

    __slots__ = ("angle", "bias", "p00", "p01", "p10", "p11")

    def __init__(self, angle):
        self.angle, self.bias = angle, 0.0
        self.p00 = self.p01 = self.p10 = self.p11 = 0.0

    def predict(self, rate, dt, q_angle, q_bias):
        self.angle += (rate - self.bias) * dt
        p11 = self.p11
        self.p00 += dt * (dt * p11 - self.p01 - self.p10 + q_angle)
        self.p01 -= dt * p11
        self.p10 -= dt * p11
        self.p11 += q_bias * dt

    def correct(self, angle_meas, r, bias_max, innovation_max):
        s = self.p00 + r
        k0, k1 = self.p00 / s, self.p10 / s
        y = min(max(wrap_pi(angle_meas - self.angle), -innovation_max), innovation_max)
        self.angle += k0 * y
        self.bias = min(max(self.bias + k1 * y, -bias_max), bias_max)
        p00, p01 = self.p00, self.p01
        self.p00 -= k0 * p00
        self.p01 -= k0 * p01
        self.p10 -= k1 * p00
        self.p11 -= k1 * p01


class Kf(Estimator):
    name = "kf"
    estimates_gyro_bias = True
    Settings = KfSettings
    Diagnostics = KfDiagnostics

    def _reset_state(self):
        self._yaw, self._pitch, self._roll = 0.0, _Axis(0.0), _Axis(0.0)

    def _set_attitude(self, q):
        # Keep the bias estimates across a re-initialisation; only the angles come from gravity.
        self._yaw, self._pitch.angle, self._roll.angle = quaternion.to_euler_zyx(q).tolist()
        self._q = q

    def _diagnostics(self, status):
        p, r = self._pitch, self._roll
        return KfDiagnostics(status, p.bias, r.bias, max(p.p00, 0.0) ** 0.5, max(r.p00, 0.0) ** 0.5)

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        s, pitch, roll = self.settings, self._pitch, self._roll
        # The gyro's angle change comes from the quaternion (no gimbal lock, whatever the mounting);
        # each axis then subtracts its own bias estimate in predict.
        q = integrate_rate(self._q, gx, gy, gz, dt_s)
        self._yaw, pitch.angle, roll.angle = euler_of(q)
        pitch.predict(0.0, dt_s, s.q_angle_rad2_s, s.q_bias_rad2_s3)
        roll.predict(0.0, dt_s, s.q_angle_rad2_s, s.q_bias_rad2_s3)
        if acc_ok:
            pitch_acc, roll_acc = acc_pitch_roll(ax, ay, az)
            pitch.correct(pitch_acc, s.r_angle_rad2, s.bias_max_rad_s, s.innovation_max_rad)
            roll.correct(roll_acc, s.r_angle_rad2, s.bias_max_rad_s, s.innovation_max_rad)
        pitch.angle = min(max(pitch.angle, -math.pi / 2), math.pi / 2)
        roll.angle = wrap_pi(roll.angle)
        self._q = quaternion_of(self._yaw, pitch.angle, roll.angle)
        return self._q, self._diagnostics(status)
