"""EKF: quaternion extended Kalman filter, gyro propagation, gravity direction as the measurement.

State q (w, x, y, z), covariance P (4×4). Per sample (digest §4; the structure of Sabatini 2011 and of
``ahrs.filters.EKF``):

- predict:  ``F = I + ½ dt Ω(ω)`` (so ``F q = q + ½ q ⊗ [0, ω] dt``, seed 000 eq. 6 and 19);
  ``q⁻ = F q`` normalised; ``W = ½ dt [-q_v; q_w I + [q_v]×]`` (∂q⁻/∂ω);
  ``P⁻ = F P Fᵀ + σ_g² W Wᵀ``
- update:   ``h(q) = ĝ(q)``, the down direction in the body frame (seed 000 eq. 8), measured as
  ``â = -acc_g/‖acc_g‖``; ``H = ∂h/∂q``; ``S = H P⁻ Hᵀ + σ_a² I``; ``K = P⁻ Hᵀ S⁻¹``;
  ``q = q⁻ + K (â - h(q⁻))`` normalised; ``P = (I - K H) P⁻``

The three components of â are independent (R = σ_a² I), so the update is made one component at a time
(sequential processing: ``k_i = P H_iᵀ / (H_i P H_iᵀ + σ_a²)``, ``δ += k_i (ν_i - H_i δ)``,
``P -= k_i H_i P``): exactly the batch update above in exact arithmetic, without a 3×3 inverse.

Unlike ``ahrs.filters.EKF`` the predicted q⁻ is normalised before h and H are evaluated (ahrs evaluates
h on the normalised and H on the unnormalised q⁻); the two agree to O((ω dt)²) per step.

σ_g (``gyro_noise_rad_s``) is the per-sample gyro noise the filter assumes: the MPU-6050's own noise is
far smaller (≈ 0.05 °/s at 100 Hz), so the default 0.03 rad/s (1.7 °/s) also covers an uncalibrated
bias. σ_a (``acc_noise``, dimensionless, ≈ rad) covers manoeuvre accelerations of about 0.1 g.
With these defaults the tilt converges with a time constant of a few seconds at 100 Hz.

A compiled kernel (base.py): numpy's per-call overhead on 4×4 matrices cost 90-140 µs a sample, the same
arithmetic on Python lists about 70 µs, compiled a few µs (bench/bench_kernels.out.md).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from groundstation.estimation.base import NO_UPDATE, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, guard, integrate_rate

_P0 = 0.01  # initial variance of each quaternion component (std 0.1 ≈ 11°): the gravity init is rough


@dataclasses.dataclass(frozen=True)
class EkfSettings(CommonSettings):
    gyro_noise_rad_s: float = 0.03  # σ_g: assumed gyro noise per sample, rad/s
    acc_noise: float = 0.1  # σ_a: noise of the normalised accelerometer direction (≈ rad)


class EkfDiagnostics(NamedTuple):
    status: int
    innovation: float  # ‖â - h(q⁻)‖ on this sample (0 when the accelerometer was skipped)
    p_trace: float  # trace of P: the filter's own uncertainty


# Parameters after the guard's: σ_g², σ_a². State after the guard's: the diagnostics, then P (4×4, rows).
_GYRO_VAR, _ACC_VAR = P_OWN, P_OWN + 1
_INNOVATION, _TRACE, _P = STATE_DIAG, STATE_DIAG + 1, STATE_DIAG + 2


@njit(cache=True)
def ekf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One EKF sample: base.py's compiled kernels."""
    status, acc_ok = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    w0, w1, w2, w3 = state[0], state[1], state[2], state[3]
    h = 0.5 * dt_s
    hx, hy, hz = h * gx, h * gy, h * gz
    f = ((1.0, -hx, -hy, -hz), (hx, 1.0, hz, -hy), (hy, -hz, 1.0, hx), (hz, hy, -hx, 1.0))
    # W = ½dt [-q_v; q_w I + [q_v]×] (prior q); P⁻ = F P Fᵀ + σ_g² W Wᵀ
    wm = ((-h * w1, -h * w2, -h * w3), (h * w0, -h * w3, h * w2), (h * w3, h * w0, -h * w1), (-h * w2, h * w1, h * w0))
    fp = np.zeros((4, 4))  # F P
    for i in range(4):
        for j in range(4):
            for k in range(4):
                fp[i, j] += f[i][k] * state[_P + 4 * k + j]
    pm = np.zeros((4, 4))
    for i in range(4):
        for j in range(4):
            for k in range(4):
                pm[i, j] += fp[i, k] * f[j][k]
            pm[i, j] += p[_GYRO_VAR] * (wm[i][0] * wm[j][0] + wm[i][1] * wm[j][1] + wm[i][2] * wm[j][2])
    q = integrate_rate((w0, w1, w2, w3), gx, gy, gz, dt_s)  # q⁻ = F q, normalised
    state[_INNOVATION] = 0.0
    if acc_ok:
        q0, q1, q2, q3 = q
        r = -((ax * ax + ay * ay + az * az) ** -0.5)
        innovation = (ax * r - 2.0 * (q1 * q3 - q0 * q2), ay * r - 2.0 * (q0 * q1 + q2 * q3), az * r - (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3))
        hm = ((-2.0 * q2, 2.0 * q3, -2.0 * q0, 2.0 * q1), (2.0 * q1, 2.0 * q0, 2.0 * q3, 2.0 * q2), (2.0 * q0, -2.0 * q1, -2.0 * q2, 2.0 * q3))
        delta = np.zeros(4)
        ph = np.zeros(4)
        for m in range(3):  # one component of â at a time (module docstring)
            s = p[_ACC_VAR]
            nu = innovation[m]
            for i in range(4):
                ph[i] = pm[i, 0] * hm[m][0] + pm[i, 1] * hm[m][1] + pm[i, 2] * hm[m][2] + pm[i, 3] * hm[m][3]  # P H_iᵀ
                s += hm[m][i] * ph[i]
                nu -= hm[m][i] * delta[i]
            for i in range(4):
                delta[i] += ph[i] / s * nu
            for i in range(4):
                for j in range(4):
                    pm[i, j] -= ph[i] / s * ph[j]  # P -= k_i (P H_iᵀ)ᵀ, P symmetric
        q0, q1, q2, q3 = q0 + delta[0], q1 + delta[1], q2 + delta[2], q3 + delta[3]
        n = (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3) ** -0.5
        q = (q0 * n, q1 * n, q2 * n, q3 * n)
        state[_INNOVATION] = math.sqrt(innovation[0] * innovation[0] + innovation[1] * innovation[1] + innovation[2] * innovation[2])
    state[_P : _P + 16] = pm.reshape(16)
    state[_TRACE] = pm[0, 0] + pm[1, 1] + pm[2, 2] + pm[3, 3]
    state[0], state[1], state[2], state[3] = q
    return status


class Ekf(CompiledEstimator):
    name = "ekf"
    Settings = EkfSettings
    Diagnostics = EkfDiagnostics
    kernel = staticmethod(ekf_kernel)

    def _parameters(self):
        s = self.settings
        return [s.gyro_noise_rad_s**2, s.acc_noise**2]

    def _initial_state(self):
        return [0.0, 4 * _P0, *np.diag([_P0] * 4).reshape(16).tolist()]  # innovation, trace, P
