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

from numba import njit
from numba.extending import register_jitable

from groundstation.estimation.base import NO_UPDATE, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, guard, integrate_rate, record, sample, unmanaged
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


# Parameters after the guard's: the settings in their order. State after the guard's: the diagnostics,
# then P (p00, p01, p10, p11) of pitch and of roll. The angles are read from q on every sample.
_Q_ANGLE, _Q_BIAS, _R_ANGLE, _BIAS_MAX, _INNOVATION_MAX = range(P_OWN, P_OWN + 5)
_BIAS, _STD, _P = STATE_DIAG, STATE_DIAG + 2, STATE_DIAG + 4  # + axis (0 pitch, 1 roll); P: + 4 axis


@register_jitable
def _axis(state, p, axis, angle, angle_acc, acc_ok, dt):
    """One axis's two-state filter (module docstring): predict, and correct when the accelerometer is
    usable; returns the new angle, keeps the bias, P and √P00 in ``state``."""
    k = _P + 4 * axis
    bias, p00, p01, p10, p11 = state[_BIAS + axis], state[k], state[k + 1], state[k + 2], state[k + 3]
    angle -= bias * dt  # the rate is in the quaternion already: only the bias is taken off
    p00 += dt * (dt * p11 - p01 - p10 + p[_Q_ANGLE])
    p01 -= dt * p11
    p10 -= dt * p11
    p11 += p[_Q_BIAS] * dt
    if acc_ok:
        s = p00 + p[_R_ANGLE]
        k0, k1 = p00 / s, p10 / s
        y = min(max(wrap_pi(angle_acc - angle), -p[_INNOVATION_MAX]), p[_INNOVATION_MAX])
        angle += k0 * y
        bias = min(max(bias + k1 * y, -p[_BIAS_MAX]), p[_BIAS_MAX])
        p00, p01, p10, p11 = p00 - k0 * p00, p01 - k0 * p01, p10 - k1 * p00, p11 - k1 * p01
    state[_BIAS + axis], state[k], state[k + 1], state[k + 2], state[k + 3] = bias, p00, p01, p10, p11
    state[_STD + axis] = math.sqrt(max(p00, 0.0))
    return angle


@njit(cache=True)
def kf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One KF sample: base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    # The gyro's angle change comes from the quaternion (no gimbal lock, whatever the mounting);
    # each axis then subtracts its own bias estimate.
    yaw, pitch, roll = euler_of(integrate_rate((state[0], state[1], state[2], state[3]), gx, gy, gz, dt_s))
    pitch_acc, roll_acc = acc_pitch_roll(ax, ay, az) if acc_ok else (0.0, 0.0)
    pitch = _axis(state, p, 0, pitch, pitch_acc, acc_ok, dt_s)
    roll = _axis(state, p, 1, roll, roll_acc, acc_ok, dt_s)
    pitch = min(max(pitch, -math.pi / 2), math.pi / 2)
    state[0], state[1], state[2], state[3] = quaternion_of(yaw, pitch, wrap_pi(roll))
    return status


@njit(cache=True)
def kf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, kf_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Kf(CompiledEstimator):
    name = "kf"
    estimates_gyro_bias = True
    Settings = KfSettings
    Diagnostics = KfDiagnostics
    kernel = staticmethod(kf_kernel)
    run_kernel = staticmethod(kf_run)

    def _parameters(self):
        s = self.settings
        return [s.q_angle_rad2_s, s.q_bias_rad2_s3, s.r_angle_rad2, s.bias_max_rad_s, s.innovation_max_rad]

    def _initial_state(self):
        return [0.0] * 12  # biases, stds, P of both axes: like the original, confident in the initialisation
