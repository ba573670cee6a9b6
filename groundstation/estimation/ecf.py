"""ECF: Mahony's explicit complementary filter with gyro-bias estimation (seed 002's PI filter).

Seed 002 (Nan et al., restated in the digest §4): the error between the measured and the estimated
gravity direction, ``e = â × ĝ``, drives a PI correction of the gyro rate,

- ``ḃ = -Ki e``                     (the integral term, kept as a gyro-bias estimate b)
- ``ω' = ω - b + Kp e``             (the corrected rate)
- ``q̇ = ½ q ⊗ [0, ω']``, ``q ← q + q̇ Δt``, normalised   (seed 000 eq. 6, 19)

ĝ is the estimated down direction in the body frame (seed 000 eq. 8) and â the measured one,
``-acc_g/‖acc_g‖`` (body FRD, earth NED). The bias is updated before it is used, as in
``ahrs.filters.Mahony``; with that order and the same Euler integration the two filters agree to
rounding (tests/estimation/test_oracles.py).

The integral is bounded, ``|b_i| ≤ bias_max_rad_s``: under fast translation the accelerometer's
direction is wrong for seconds, and an unbounded integral winds up to rates no gyro bias has (ECF went
33° off on BROAD trial 21 and 101° on another fast-translation trial); the bound keeps it a bias.

Kp is in rad/s (a 1-rad error turns the estimate at Kp rad/s), Ki in rad/s² per unit error. Kp = 1 is
Mahony et al.'s (and ahrs's); their Ki = 0.3 winds the bias up under translation, so the default Ki
(0.01), the bounds ``bias_max_rad_s`` and ``error_max`` (‖e‖ larger than it counts as it: one wild
accelerometer sample moves the estimate no more than a moderate one) were chosen on the BROAD dev set.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

from groundstation.estimation.base import CommonSettings, Estimator, integrate_rate


@dataclasses.dataclass(frozen=True)
class EcfSettings(CommonSettings):
    kp: float = 1.0  # rad/s, proportional gain
    # rad/s², integral gain (gyro-bias estimation); 0 = none. Mahony's 0.3 winds up under translation;
    # 0.01 chosen on the BROAD dev set (bench/bench_estimators.out.md)
    ki: float = 0.01
    # |b_i| bound: the integral cannot wind up beyond a plausible gyro bias (rad/s); inf = unbounded (Mahony)
    bias_max_rad_s: float = 0.05
    # ‖e‖ bound (≈ rad): a larger disagreement counts as this much, so one wild sample moves the
    # estimate no more than a moderate one (Madgwick's normalised step has the same robustness)
    error_max: float = 0.05


class EcfDiagnostics(NamedTuple):
    status: int
    bias_x_rad_s: float  # estimated gyro bias b, body axes
    bias_y_rad_s: float
    bias_z_rad_s: float
    gravity_error: float  # ‖e‖ = sine of the angle between measured and estimated gravity


class Ecf(Estimator):
    name = "ecf"
    estimates_gyro_bias = True
    Settings = EcfSettings
    Diagnostics = EcfDiagnostics
    marg = False  # True in marg.Ecfm: adds the magnetometer's error term

    def _reset_state(self):
        self._bias = (0.0, 0.0, 0.0)
        self._err = 0.0

    def _set_attitude(self, q):
        self._q = q

    def _diagnostics(self, status):
        return EcfDiagnostics(status, *self._bias, self._err)

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        q1, q2, q3, q4 = self._q
        bx, by, bz = self._bias
        if acc_ok:
            r = -((ax * ax + ay * ay + az * az) ** -0.5)
            ax, ay, az = ax * r, ay * r, az * r  # â: measured down direction
            vx = 2.0 * (q2 * q4 - q1 * q3)  # ĝ: estimated down direction (seed 000 eq. 8)
            vy = 2.0 * (q1 * q2 + q3 * q4)
            vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4
            ex, ey, ez = ay * vz - az * vy, az * vx - ax * vz, ax * vy - ay * vx  # e = â × ĝ
            err = self._err = (ex * ex + ey * ey + ez * ez) ** 0.5
            if err > self.settings.error_max:
                c = self.settings.error_max / err
                ex, ey, ez = ex * c, ey * c, ez * c
            if self.marg and self._mag is not None:  # ecfm: e += m × w (marg.py)
                ex, ey, ez = self._mag_error(q1, q2, q3, q4, ex, ey, ez)
            ki, kp = self.settings.ki * dt_s, self.settings.kp
            m = self.settings.bias_max_rad_s
            bx, by, bz = bx - ki * ex, by - ki * ey, bz - ki * ez  # ḃ = -Ki e
            bx, by, bz = min(max(bx, -m), m), min(max(by, -m), m), min(max(bz, -m), m)
            self._bias = (bx, by, bz)
            gx, gy, gz = gx + kp * ex, gy + kp * ey, gz + kp * ez
        self._q = integrate_rate(self._q, gx - bx, gy - by, gz - bz, dt_s)  # ω' = ω - b + Kp e
        return self._q, self._diagnostics(status)
