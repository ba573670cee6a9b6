"""EKF: quaternion extended Kalman filter, gyro propagation, gravity direction as the measurement.

State q (w, x, y, z), covariance P (4×4). Per sample (digest §4; the structure of Sabatini 2011 and of
``ahrs.filters.EKF``):

- predict:  ``F = I + ½ dt Ω(ω)`` (so ``F q = q + ½ q ⊗ [0, ω] dt``, seed 000 eq. 6 and 19);
  ``q⁻ = F q`` normalised; ``W = ½ dt [-q_v; q_w I + [q_v]×]`` (∂q⁻/∂ω);
  ``P⁻ = F P Fᵀ + σ_g² W Wᵀ``
- update:   ``h(q) = ĝ(q)``, the down direction in the body frame (seed 000 eq. 8), measured as
  ``â = -acc_g``, the specific force in g as it is; ``H = ∂h/∂q``; ``S = H P⁻ Hᵀ + σ_a² I``; ``K = P⁻ Hᵀ S⁻¹``;
  ``q = q⁻ + K (â - h(q⁻))`` normalised; ``P = (I - K H) P⁻``

The three components of â are independent (R = σ_a² I), so the update is made one component at a time
(sequential processing: ``k_i = P H_iᵀ / (H_i P H_iᵀ + σ_a²)``, ``δ += k_i (ν_i - H_i δ)``,
``P -= k_i H_i P``): exactly the batch update above in exact arithmetic, without a 3×3 inverse.

Unlike ``ahrs.filters.EKF`` the accelerometer is not normalised: the update is linear in the innovation, so
it averages ``â``, and the mean of ``a/‖a‖`` under zero-mean linear acceleration is not gravity's direction
(±3 g of vibration at 100 Hz along a tilted axis: 30° off it, where the EKF drifted; BROAD dev trial 16,
shaken by a few g: 9.3° RMS normalised, 2.2° as measured; issue 33). And the predicted q⁻ is normalised
before h and H are evaluated (ahrs evaluates h on the normalised and H on the unnormalised q⁻); the two
agree to O((ω dt)²) per step.

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
from numba.extending import register_jitable

from groundstation.estimation.base import NO_UPDATE, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, guard, integrate_rate, record, sample, unmanaged

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

# 4×4 matrices as tuples of rows, vectors as 4-tuples: straight-line code once compiled (no loops, no
# heap), quick to compile, and quick interpreted too.


@register_jitable
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]


@register_jitable
def _times(m, v):
    """M v."""
    return (_dot(m[0], v), _dot(m[1], v), _dot(m[2], v), _dot(m[3], v))


@register_jitable
def _times_transposed(a, b):
    """A Bᵀ."""
    return (_times(b, a[0]), _times(b, a[1]), _times(b, a[2]), _times(b, a[3]))


@register_jitable
def _plus_outer(m, u, v, c):
    """M + c u vᵀ."""
    return (
        (m[0][0] + c * u[0] * v[0], m[0][1] + c * u[0] * v[1], m[0][2] + c * u[0] * v[2], m[0][3] + c * u[0] * v[3]),
        (m[1][0] + c * u[1] * v[0], m[1][1] + c * u[1] * v[1], m[1][2] + c * u[1] * v[2], m[1][3] + c * u[1] * v[3]),
        (m[2][0] + c * u[2] * v[0], m[2][1] + c * u[2] * v[1], m[2][2] + c * u[2] * v[2], m[2][3] + c * u[2] * v[3]),
        (m[3][0] + c * u[3] * v[0], m[3][1] + c * u[3] * v[1], m[3][2] + c * u[3] * v[2], m[3][3] + c * u[3] * v[3]),
    )


@njit(cache=True)
def ekf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One EKF sample: base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    w0, w1, w2, w3 = state[0], state[1], state[2], state[3]
    h = 0.5 * dt_s
    hx, hy, hz = h * gx, h * gy, h * gz
    f = ((1.0, -hx, -hy, -hz), (hx, 1.0, hz, -hy), (hy, -hz, 1.0, hx), (hz, hy, -hx, 1.0))
    prior = (
        (state[_P], state[_P + 1], state[_P + 2], state[_P + 3]),
        (state[_P + 4], state[_P + 5], state[_P + 6], state[_P + 7]),
        (state[_P + 8], state[_P + 9], state[_P + 10], state[_P + 11]),
        (state[_P + 12], state[_P + 13], state[_P + 14], state[_P + 15]),
    )
    pm = _times_transposed(_times_transposed(f, prior), f)  # F P Fᵀ (P symmetric: P = Pᵀ)
    # + σ_g² W Wᵀ, W = ½dt [-q_v; q_w I + [q_v]×] (prior q), one column of W at a time
    g2 = p[_GYRO_VAR]
    pm = _plus_outer(pm, (-h * w1, h * w0, h * w3, -h * w2), (-h * w1, h * w0, h * w3, -h * w2), g2)
    pm = _plus_outer(pm, (-h * w2, -h * w3, h * w0, h * w1), (-h * w2, -h * w3, h * w0, h * w1), g2)
    pm = _plus_outer(pm, (-h * w3, h * w2, -h * w1, h * w0), (-h * w3, h * w2, -h * w1, h * w0), g2)
    q = integrate_rate((w0, w1, w2, w3), gx, gy, gz, dt_s)  # q⁻ = F q, normalised
    state[_INNOVATION] = 0.0
    if acc_ok:
        q0, q1, q2, q3 = q
        # â = -acc_g as measured, not normalised (module docstring)
        nu = (-ax - 2.0 * (q1 * q3 - q0 * q2), -ay - 2.0 * (q0 * q1 + q2 * q3), -az - (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3))
        state[_INNOVATION] = math.sqrt(nu[0] * nu[0] + nu[1] * nu[1] + nu[2] * nu[2])
        # One component of â at a time (module docstring): H's rows, δ the correction so far
        delta = (0.0, 0.0, 0.0, 0.0)
        for row, innovation in (
            ((-2.0 * q2, 2.0 * q3, -2.0 * q0, 2.0 * q1), nu[0]),
            ((2.0 * q1, 2.0 * q0, 2.0 * q3, 2.0 * q2), nu[1]),
            ((2.0 * q0, -2.0 * q1, -2.0 * q2, 2.0 * q3), nu[2]),
        ):
            ph = _times(pm, row)  # P H_iᵀ
            s = _dot(row, ph) + p[_ACC_VAR]
            c = (innovation - _dot(row, delta)) / s
            delta = (delta[0] + c * ph[0], delta[1] + c * ph[1], delta[2] + c * ph[2], delta[3] + c * ph[3])
            pm = _plus_outer(pm, ph, ph, -1.0 / s)  # P -= k_i (P H_iᵀ)ᵀ, k_i = P H_iᵀ / s
        q0, q1, q2, q3 = q0 + delta[0], q1 + delta[1], q2 + delta[2], q3 + delta[3]
        n = (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3) ** -0.5
        q = (q0 * n, q1 * n, q2 * n, q3 * n)
    for i in range(4):
        state[_P + 4 * i], state[_P + 4 * i + 1], state[_P + 4 * i + 2], state[_P + 4 * i + 3] = pm[i]
    state[_TRACE] = pm[0][0] + pm[1][1] + pm[2][2] + pm[3][3]
    state[0], state[1], state[2], state[3] = q
    return status


@njit(cache=True)
def ekf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, ekf_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Ekf(CompiledEstimator):
    name = "ekf"
    Settings = EkfSettings
    Diagnostics = EkfDiagnostics
    kernel = staticmethod(ekf_kernel)
    run_kernel = staticmethod(ekf_run)

    def _parameters(self):
        s = self.settings
        return [s.gyro_noise_rad_s**2, s.acc_noise**2]

    def _initial_state(self):
        return [0.0, 4 * _P0, *np.diag([_P0] * 4).reshape(16).tolist()]  # innovation, trace, P
