"""EKF: quaternion extended Kalman filter, gyro propagation, gravity direction as the measurement.

State q (w, x, y, z), covariance P (4×4). Per sample (digest §4; the structure of Sabatini 2011 and of
``ahrs.filters.EKF``):

- predict:  ``F = I + ½ dt Ω(ω)`` (so ``F q = q + ½ q ⊗ [0, ω] dt``, seed 000 eq. 6 and 19);
  ``q⁻ = F q`` normalised; ``W = ½ dt [-q_v; q_w I + [q_v]×]`` (∂q⁻/∂ω);
  ``P⁻ = F P Fᵀ + σ_g² W Wᵀ``
- update:   ``h(q) = ĝ(q)``, the down direction in the body frame (seed 000 eq. 8), measured as
  ``â = -acc_g/‖acc_g‖``; ``H = ∂h/∂q``; ``S = H P⁻ Hᵀ + σ_a² I``; ``K = P⁻ Hᵀ S⁻¹``;
  ``q = q⁻ + K (â - h(q⁻))`` normalised; ``P = (I - K H) P⁻``

Unlike ``ahrs.filters.EKF`` the predicted q⁻ is normalised before h and H are evaluated (ahrs evaluates
h on the normalised and H on the unnormalised q⁻); the two agree to O((ω dt)²) per step.

σ_g (``gyro_noise_rad_s``) is the per-sample gyro noise the filter assumes: the MPU-6050's own noise is
far smaller (≈ 0.05 °/s at 100 Hz), so the default 0.03 rad/s (1.7 °/s) also covers an uncalibrated
bias. σ_a (``acc_noise``, dimensionless, ≈ rad) covers manoeuvre accelerations of about 0.1 g.
With these defaults the tilt converges with a time constant of a few seconds at 100 Hz.

numpy on 4×4 matrices: about 30 µs a sample, an order slower than the scalar filters.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from groundstation.estimation.base import CommonSettings, Estimator

_P0 = 0.01  # initial variance of each quaternion component (std 0.1 ≈ 11°): the gravity init is rough


@dataclasses.dataclass(frozen=True)
class EkfSettings(CommonSettings):
    gyro_noise_rad_s: float = 0.03  # σ_g: assumed gyro noise per sample, rad/s
    acc_noise: float = 0.1  # σ_a: noise of the normalised accelerometer direction (≈ rad)


class EkfDiagnostics(NamedTuple):
    status: int
    innovation: float  # ‖â - h(q⁻)‖ on this sample (0 when the accelerometer was skipped)
    p_trace: float  # trace of P: the filter's own uncertainty


def _omega(wx, wy, wz):
    return np.array([[0.0, -wx, -wy, -wz], [wx, 0.0, wz, -wy], [wy, -wz, 0.0, wx], [wz, wy, -wx, 0.0]])


class Ekf(Estimator):
    name = "ekf"
    Settings = EkfSettings
    Diagnostics = EkfDiagnostics

    def _reset_state(self):
        self._p = np.eye(4) * _P0
        self._innovation = 0.0

    def _set_attitude(self, q):
        self._q = q

    def _diagnostics(self, status):
        return EkfDiagnostics(status, self._innovation, float(np.trace(self._p)))

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        s = self.settings
        q = np.array(self._q)
        f = np.eye(4) + 0.5 * dt_s * _omega(gx, gy, gz)
        w = 0.5 * dt_s * np.vstack([-q[1:], q[0] * np.eye(3) + _skew(q[1:])])
        q = f @ q
        q /= np.linalg.norm(q)
        p = f @ self._p @ f.T + s.gyro_noise_rad_s**2 * (w @ w.T)
        self._innovation = 0.0
        if acc_ok:
            measured = -np.array([ax, ay, az]) / (ax * ax + ay * ay + az * az) ** 0.5
            qw, qx, qy, qz = q
            predicted = np.array([2 * (qx * qz - qw * qy), 2 * (qw * qx + qy * qz), qw * qw - qx * qx - qy * qy + qz * qz])
            h = 2.0 * np.array([[-qy, qz, -qw, qx], [qx, qw, qz, qy], [qw, -qx, -qy, qz]])
            innovation = measured - predicted
            k = p @ h.T @ np.linalg.inv(h @ p @ h.T + s.acc_noise**2 * np.eye(3))
            q = q + k @ innovation
            q /= np.linalg.norm(q)
            p = (np.eye(4) - k @ h) @ p
            self._innovation = float(np.linalg.norm(innovation))
        self._p = p
        self._q = tuple(q.tolist())
        return self._q, self._diagnostics(status)


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
