"""CF1: the first-order complementary filter of seed 002, one angle at a time.

Seed 002 (digest §4): ``θ(n) = α (θ(n-1) + ω dt) + (1 - α) θ_acc(n)``, 0 < α < 1, for pitch and roll;
yaw is integrated from the gyro alone. Two choices the seed leaves open:

- the gyro prediction ``θ(n-1) + ω dt`` is made on the attitude quaternion (seed 000 eq. 6, 19) and
  read back as angles, rather than integrating Euler-angle rates: the same to first order, but without
  the gimbal lock at ±90° pitch that made the Euler integration diverge when the sensor was mounted
  other than flat (BROAD trial 07: 68° at τ = 2 s).
- the accelerometer's pull ``θ_acc - prediction`` is bounded by ``innovation_max_rad``: under fast
  translation a wrong accelerometer angle then moves the estimate no more than a moderate one.
- α is set by a time constant, ``α = τ / (τ + dt)``, so the filter behaves the same at any sample rate:
  τ = 0.5 s gives the classic α ≈ 0.98 at 100 Hz. τ = 0 is accelerometer-only tilt.

The blend acts on the wrapped difference ``θ_acc - prediction`` so roll does not jump at ±180°.
Pitch is kept within ±90° (the ZYX range).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

from numba import njit

from groundstation.estimation.base import NO_UPDATE, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, guard, integrate_rate, record, sample, unmanaged
from groundstation.estimation.tilt import acc_pitch_roll, euler_of, quaternion_of, wrap_pi


@dataclasses.dataclass(frozen=True)
class Cf1Settings(CommonSettings):
    # τ: gyro trusted for changes faster than this; 0 = accelerometer only. 2 s chosen on the BROAD dev set
    time_constant_s: float = 2.0
    # |θ_acc - prediction| bound (rad): a wilder accelerometer angle counts as this much
    innovation_max_rad: float = 0.05


class Cf1Diagnostics(NamedTuple):
    status: int
    alpha: float  # α used on this sample
    pitch_acc_rad: float  # the accelerometer's pitch and roll on this sample
    roll_acc_rad: float


# Parameters after the guard's: τ, innovation_max_rad. State after the guard's: the diagnostics.
_TAU, _INNOVATION_MAX = P_OWN, P_OWN + 1
_ALPHA, _PITCH_ACC, _ROLL_ACC = STATE_DIAG, STATE_DIAG + 1, STATE_DIAG + 2


@njit(cache=True)
def cf1_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One CF1 sample: base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    # Gyro prediction on the quaternion (no gimbal lock, whatever the mounting), blend on the angles.
    q = integrate_rate((state[0], state[1], state[2], state[3]), gx, gy, gz, dt_s)
    if acc_ok:
        yaw, pitch, roll = euler_of(q)
        pitch_acc, roll_acc = acc_pitch_roll(ax, ay, az)
        alpha = p[_TAU] / (p[_TAU] + dt_s)
        m = p[_INNOVATION_MAX]
        pitch += (1.0 - alpha) * min(max(wrap_pi(pitch_acc - pitch), -m), m)
        roll += (1.0 - alpha) * min(max(wrap_pi(roll_acc - roll), -m), m)
        state[_ALPHA], state[_PITCH_ACC], state[_ROLL_ACC] = alpha, pitch_acc, roll_acc
        pitch = min(max(pitch, -math.pi / 2), math.pi / 2)
        q = quaternion_of(yaw, pitch, roll)
    state[0], state[1], state[2], state[3] = q
    return status


@njit(cache=True)
def cf1_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, cf1_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Cf1(CompiledEstimator):
    name = "cf1"
    Settings = Cf1Settings
    Diagnostics = Cf1Diagnostics
    kernel = staticmethod(cf1_kernel)
    run_kernel = staticmethod(cf1_run)

    def _parameters(self):
        return [self.settings.time_constant_s, self.settings.innovation_max_rad]

    def _initial_state(self):
        return [1.0, 0.0, 0.0]  # α, pitch_acc, roll_acc
