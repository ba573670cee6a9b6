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

Plain Python floats on 4×4 lists (``small_linalg``), as ahf/hf: numpy's per-call overhead on 4×4
matrices cost 90-140 µs a sample; the same arithmetic in loops costs a fraction (bench_estimators.out.md).
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

from operator import mul

from groundstation.estimation import small_linalg as sl
from groundstation.estimation.base import CommonSettings, Estimator, integrate_rate

_new_tuple = tuple.__new__

_P0 = 0.01  # initial variance of each quaternion component (std 0.1 ≈ 11°): the gravity init is rough


@dataclasses.dataclass(frozen=True)
class EkfSettings(CommonSettings):
    gyro_noise_rad_s: float = 0.03  # σ_g: assumed gyro noise per sample, rad/s
    acc_noise: float = 0.1  # σ_a: noise of the normalised accelerometer direction (≈ rad)


class EkfDiagnostics(NamedTuple):
    status: int
    innovation: float  # ‖â - h(q⁻)‖ on this sample (0 when the accelerometer was skipped)
    p_trace: float  # trace of P: the filter's own uncertainty


class Ekf(Estimator):
    name = "ekf"
    Settings = EkfSettings
    Diagnostics = EkfDiagnostics

    def _reset_state(self):
        self._p = [[_P0 if i == j else 0.0 for j in range(4)] for i in range(4)]
        self._innovation = 0.0

    def _set_attitude(self, q):
        self._q = q

    def _diagnostics(self, status):
        p = self._p
        return EkfDiagnostics(status, self._innovation, p[0][0] + p[1][1] + p[2][2] + p[3][3])

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        s = self.settings
        w0, w1, w2, w3 = self._q
        h = 0.5 * dt_s
        hx, hy, hz = h * gx, h * gy, h * gz
        f = ((1.0, -hx, -hy, -hz), (hx, 1.0, hz, -hy), (hy, -hz, 1.0, hx), (hz, hy, -hx, 1.0))
        # W = ½dt [-q_v; q_w I + [q_v]×] (prior q); σ_g² W Wᵀ
        wm = ((-h * w1, -h * w2, -h * w3), (h * w0, -h * w3, h * w2), (h * w3, h * w0, -h * w1), (-h * w2, h * w1, h * w0))
        g2 = s.gyro_noise_rad_s**2
        fp = [[sum(map(mul, fr, col)) for col in zip(*self._p)] for fr in f]
        p = [[sum(map(mul, a, fr)) + g2 * sum(map(mul, wa, wb)) for fr, wb in zip(f, wm)] for a, wa in zip(fp, wm)]
        q0, q1, q2, q3 = integrate_rate(self._q, gx, gy, gz, dt_s)  # q⁻ = F q, normalised
        self._innovation = 0.0
        if acc_ok:
            r = -((ax * ax + ay * ay + az * az) ** -0.5)
            innovation = (
                ax * r - 2.0 * (q1 * q3 - q0 * q2),
                ay * r - 2.0 * (q0 * q1 + q2 * q3),
                az * r - (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3),
            )
            hm = ((-2.0 * q2, 2.0 * q3, -2.0 * q0, 2.0 * q1), (2.0 * q1, 2.0 * q0, 2.0 * q3, 2.0 * q2), (2.0 * q0, -2.0 * q1, -2.0 * q2, 2.0 * q3))
            pht = [[sum(map(mul, row, hr)) for hr in hm] for row in p]  # P Hᵀ (4 x 3)
            a2 = s.acc_noise**2
            hpht = [[sum(map(mul, hr, col)) + (a2 if i == j else 0.0) for j, col in enumerate(zip(*pht))] for i, hr in enumerate(hm)]
            k = sl.solve_right(sl.cholesky(hpht), pht)  # K = P Hᵀ S⁻¹
            q0, q1, q2, q3 = (c + sum(map(mul, kr, innovation)) for c, kr in zip((q0, q1, q2, q3), k))
            n = (q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3) ** -0.5
            q0, q1, q2, q3 = q0 * n, q1 * n, q2 * n, q3 * n
            # P = (I - K H) P⁻ = P⁻ - K (P⁻ Hᵀ)ᵀ, P⁻ symmetric
            p = [[pij - sum(map(mul, kr, ph)) for pij, ph in zip(prow, pht)] for prow, kr in zip(p, k)]
            self._innovation = sum(map(mul, innovation, innovation)) ** 0.5
        self._p = p
        self._q = (q0, q1, q2, q3)
        return self._q, _new_tuple(EkfDiagnostics, (status, self._innovation, p[0][0] + p[1][1] + p[2][2] + p[3][3]))
