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
import math
from typing import NamedTuple

from numba import njit
from numba.extending import register_jitable

from groundstation.estimation.base import NO_UPDATE, P_MAGNETOMETER, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, field_screen, guard, integrate_rate, record, sample, unmanaged
from groundstation.estimation.tilt import about_vertical, earth_field_reference, unit_field


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


# Parameters after the guard's: kp, ki, bias_max_rad_s, error_max. State after the guard's: the diagnostics.
_KP, _KI, _BIAS_MAX, _ERROR_MAX = range(P_OWN, P_OWN + 4)
_BX, _BY, _BZ, _ERR = range(STATE_DIAG, STATE_DIAG + 4)


@njit(cache=True)
def ecf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One sample of ECF or ECFM (with the magnetometer): base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    q1, q2, q3, q4 = state[0], state[1], state[2], state[3]
    bx, by, bz = state[_BX], state[_BY], state[_BZ]
    if acc_ok:
        r = -((ax * ax + ay * ay + az * az) ** -0.5)
        ax, ay, az = ax * r, ay * r, az * r  # â: measured down direction
        vx = 2.0 * (q2 * q4 - q1 * q3)  # ĝ: estimated down direction (seed 000 eq. 8)
        vy = 2.0 * (q1 * q2 + q3 * q4)
        vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4
        ex, ey, ez = ay * vz - az * vy, az * vx - ax * vz, ax * vy - ay * vx  # e = â × ĝ
        err = math.sqrt(ex * ex + ey * ey + ez * ez)  # not ** 0.5: compiled, that is sqrt, interpreted libm's pow
        state[_ERR] = err
        if err > p[_ERROR_MAX]:
            c = p[_ERROR_MAX] / err
            ex, ey, ez = ex * c, ey * c, ez * c
        if p[P_MAGNETOMETER] != 0.0:  # ecfm: e += m × w about the vertical (marg.py)
            status, field = field_screen(state, status, gx, gy, gz, dt_s, mx, my, mz)
            if field:
                ex, ey, ez = _field_error(q1, q2, q3, q4, ex, ey, ez, mx, my, mz, vx, vy, vz)
        ki, kp, m = p[_KI] * dt_s, p[_KP], p[_BIAS_MAX]
        bx, by, bz = bx - ki * ex, by - ki * ey, bz - ki * ez  # ḃ = -Ki e
        bx, by, bz = min(max(bx, -m), m), min(max(by, -m), m), min(max(bz, -m), m)
        state[_BX], state[_BY], state[_BZ] = bx, by, bz
        gx, gy, gz = gx + kp * ex, gy + kp * ey, gz + kp * ez
    # ω' = ω - b + Kp e
    state[0], state[1], state[2], state[3] = integrate_rate((q1, q2, q3, q4), gx - bx, gy - by, gz - bz, dt_s)
    return status


@register_jitable
def _field_error(q1, q2, q3, q4, ex, ey, ez, mx, my, mz, vx, vy, vz):
    """e with Mahony's magnetometer term ``m̂ × w`` added about the estimated vertical (vx, vy, vz) (marg.py);
    unchanged without a usable reading."""
    usable, mx, my, mz = unit_field(mx, my, mz)
    if not usable:
        return ex, ey, ez
    bx, bz = earth_field_reference(q1, q2, q3, q4, mx, my, mz)
    # w = Rᵀ(q) b: the estimated field direction on the body axes
    wx = bx * (1.0 - 2.0 * (q3 * q3 + q4 * q4)) + bz * 2.0 * (q2 * q4 - q1 * q3)
    wy = bx * 2.0 * (q2 * q3 - q1 * q4) + bz * 2.0 * (q1 * q2 + q3 * q4)
    wz = bx * 2.0 * (q2 * q4 + q1 * q3) + bz * (1.0 - 2.0 * (q2 * q2 + q3 * q3))
    # (Mahony eq. 48a) e += m̂ × w, its part about the vertical only
    cx, cy, cz = about_vertical(vx, vy, vz, my * wz - mz * wy, mz * wx - mx * wz, mx * wy - my * wx)
    return ex + cx, ey + cy, ez + cz


@njit(cache=True)
def ecf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, ecf_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Ecf(CompiledEstimator):
    name = "ecf"
    estimates_gyro_bias = True
    Settings = EcfSettings
    Diagnostics = EcfDiagnostics
    kernel = staticmethod(ecf_kernel)
    run_kernel = staticmethod(ecf_run)

    def _parameters(self):
        s = self.settings
        return [s.kp, s.ki, s.bias_max_rad_s, s.error_max]

    def _initial_state(self):
        return [0.0, 0.0, 0.0, 0.0]  # bias, gravity_error
