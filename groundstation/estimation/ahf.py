"""AHF, the adaptive hybrid filter of seed 000 (Fu et al. 2014), and HF, the same filter with λ fixed.

Equations as restated in docs/seeds-digest.md §2 (numbers are the paper's):

- (eq. 6)     ``q̇_ω = ½ q ⊗ [0, ω]``                       gyro rate of change of the attitude
- (eq. 8-9)   ``f = ĝ(q) - â``                              gravity error; ĝ the estimated gravity
  direction in the sensor frame (third row of the rotation), â the measured one, normalised
- (eq. 10)    ``J = [[-2q3, 2q4, -2q1, 2q2], [2q2, 2q1, 2q4, 2q3], [0, -4q2, -4q3, 0]]``
- (eq. 12)    ``∇f = Jᵀ f``
- (eq. 18)    ``q̇ = q̇_ω - λ ∇f / ‖∇f‖``
- (eq. 19)    ``q(k) = q(k-1) + q̇ Δt``, then normalised
- (eq. 20)    ``e = ĝ ⊗ â`` (vector part ĝ × â); ``e_a(k) = 0.9 e_a(k-1) + 0.1 · 10 (|ex| + |ey| + |ez|)``;
  ``λ = clamp(2 - e_a(k), 0.2, 2)`` (the digest's reading: the bracket is a first-order low-pass)

Frames: the paper's q is Madgwick's, with earth z up and â the specific force. Here the earth frame is
NED and the body frame FRD (docs/conventions.md), so the reference direction is earth +z = down and the
measured direction is the *down* direction in the body, ``â = -acc_g / ‖acc_g‖``. With that one sign the
paper's equations hold letter for letter and q rotates body vectors into NED.

One change to eq. 12, so that accuracy does not depend on how the sensor is mounted: the gradient is
projected onto the tangent of the unit sphere at q, ``∇f ← ∇f - (q·∇f) q``, before eq. 18 normalises
it. Eq. 10 is the Jacobian of ``ĝ_z = 1 - 2q2² - 2q3²``, which equals ``q1² - q2² - q3² + q4²`` only on
the unit sphere; the difference adds a radial part ``2(1 - ĝ·â) - 2(ĝ_z - â_z)`` along q, which is zero
for a sensor whose estimated down is body +z (the paper's level board) but large for one held the other
way up (BROAD's sensor, whose z reads +1 g at rest: down is body -z). The radial part changes nothing
after normalising q, but the normalisation in eq. 18 counts it, so the turn per step shrank (to 0.77 of
λ Δt at a 45° error, 0.58 at 70°). Projected, the step is the same for every mounting
(tests/estimation/test_mounting.py) and equals the paper's for the paper's level board up to terms of
second order in the error (a radial part ``≈ ‖f‖²``, against ``‖f‖`` tangential).

λ (and HF's β) is in rad/s: the rate at which the gradient step turns the estimate toward gravity.

Gyro over-range (the paper, in words only: "when the attitude changes so fast that the gyro exceeds its
range, the accelerometer is the more accurate, so λ takes a large value"): with
``gyro_overrange_rad_s`` set (e.g. 0.95 × the configured full scale), any axis at or above it forces
λ = λ_max for that sample. Off by default (``inf``) so that the default filter is eq. 20 exactly.

float32 (the simulated firmware): the kernel uses arithmetic operators and ``np.sqrt`` only (no ``math``
calls, which return Python floats), so interpreted it computes in whatever type its numbers have, and
only operations IEEE 754 rounds correctly (+, −, ×, ÷, square root): x^-0.5 is ``1.0 / np.sqrt(x)``, not
``x ** -0.5``, which NumPy computes with the C library's ``powf``, rounded differently by each C library
(newlib's, the board's, differs from glibc's in 9 % of inputs). So the C core (gs_ahf.c), built for the
STM32 with newlib or for the host, computes the same bits (docs/firmware.md). ``Ahf(settings,
dtype=np.float32)`` runs it interpreted (base.py, compiled estimators) with the settings, the state and
every input as ``numpy.float32``; NumPy 2's promotion rules (NEP 50) keep float32 ⊕ Python-float literals
in float32, so the whole update runs in single precision, as on the STM32. ``step`` then returns float32 numbers;
``run`` returns them widened to float64 (exactly). Each float32 step agrees with a float64 step from the
same state to float32 precision, but whole runs drift apart: eq. 18 normalises the gradient, so when the
error is near zero its direction is set by rounding and still gets a full λ Δt step. To reproduce the
onboard float32 estimate bit for bit, run the host copy with ``dtype=np.float32`` too. The default
(``dtype=None``) is the compiled kernel on float64::

    onboard = Ahf(AhfSettings(), dtype=np.float32)
    onboard.reset()
    q, diag = onboard.step(gyr_rad_s, acc_g, dt_s)     # q: four numpy.float32
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numba.extending import register_jitable

from groundstation.estimation.base import GYRO_OVERRANGE, NO_UPDATE, P_MAGNETOMETER, P_OWN, STATE_DIAG, CommonSettings, CompiledEstimator, field_screen, guard, record, sample, unmanaged
from groundstation.estimation.tilt import about_vertical_q, earth_field_reference, unit_field


@dataclasses.dataclass(frozen=True)
class AhfSettings(CommonSettings):
    lambda_max: float = 2.0  # rad/s; upper clamp of λ, and λ when the error is zero (eq. 20)
    lambda_min: float = 0.2  # rad/s; lower clamp of λ (eq. 20)
    lowpass: float = 0.9  # weight of e_a(k-1) in the error low-pass (eq. 20)
    error_gain: float = 10.0  # scale of |ex| + |ey| + |ez| (eq. 20)
    gyro_overrange_rad_s: float = math.inf  # any |ω_i| >= this forces λ = λ_max; inf = off


@dataclasses.dataclass(frozen=True)
class HfSettings(CommonSettings):
    # rad/s; fixed λ = Madgwick's β. 0.1 is the default of Madgwick's reference implementation (BROAD dev
    # set: 2.42° mean; 0.05 gives 1.96°, 0.033 2.07°, but hfm shares this setting and the sessions record it).
    beta: float = 0.1


class AhfDiagnostics(NamedTuple):
    status: int  # bits, see groundstation.estimation.base
    lam: float  # λ used on this sample, rad/s (eq. 20; HF: β)
    e_a: float  # low-passed, scaled gravity error (eq. 20; HF: 0)
    gravity_error: float  # |ex| + |ey| + |ez| of e = ĝ × â on this sample (eq. 20), ≈ sin of the angle


# Parameters after the guard's (base.P_OWN): adaptive (1: AHF, 0: HF), λ_max (HF: β), λ_min, lowpass,
# (1 - lowpass) error_gain, gyro_overrange_rad_s. State after q and the guard's: the diagnostics.
_ADAPTIVE, _LAM_MAX, _LAM_MIN, _LOWPASS, _GAIN, _OVERRANGE = range(P_OWN, P_OWN + 6)
_LAM, _E_A, _ERR = STATE_DIAG, STATE_DIAG + 1, STATE_DIAG + 2


# error_model="numpy": x / 0 is ±inf or NaN, as in C and NumPy, not ZeroDivisionError (a zero accelerometer
# with acc_min_g = 0 normalises as in the C core and the float32 model)
@njit(cache=True, error_model="numpy")
def ahf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One sample of AHF, HF (λ fixed) or HFM (HF with the magnetometer): base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    if status & NO_UPDATE:
        return status
    q1, q2, q3, q4 = state[0], state[1], state[2], state[3]
    # (eq. 6) q̇_ω = ½ q ⊗ [0, ω]
    d1 = 0.5 * (-q2 * gx - q3 * gy - q4 * gz)
    d2 = 0.5 * (q1 * gx + q3 * gz - q4 * gy)
    d3 = 0.5 * (q1 * gy - q2 * gz + q4 * gx)
    d4 = 0.5 * (q1 * gz + q2 * gy - q3 * gx)
    if acc_ok:
        # â: measured down direction, -acc normalised (see the module docstring on frames)
        r = -(1.0 / np.sqrt(ax * ax + ay * ay + az * az))
        ax, ay, az = ax * r, ay * r, az * r
        # (eq. 8) ĝ: estimated down direction in the body frame
        vx = 2.0 * (q2 * q4 - q1 * q3)
        vy = 2.0 * (q1 * q2 + q3 * q4)
        vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4
        # (eq. 9) f = ĝ - â
        fx, fy, fz = vx - ax, vy - ay, vz - az
        # (eq. 10, 12) ∇f = Jᵀ f
        s1 = -2.0 * q3 * fx + 2.0 * q2 * fy
        s2 = 2.0 * q4 * fx + 2.0 * q1 * fy - 4.0 * q2 * fz
        s3 = -2.0 * q1 * fx + 2.0 * q4 * fy - 4.0 * q3 * fz
        s4 = 2.0 * q2 * fx + 2.0 * q3 * fy
        # Tangent projection ∇f ← ∇f - (q·∇f) q (module docstring: mounting independence)
        s = q1 * s1 + q2 * s2 + q3 * s3 + q4 * s4
        s1, s2, s3, s4 = s1 - s * q1, s2 - s * q2, s3 - s * q3, s4 - s * q4
        # (eq. 20) e = ĝ ⊗ â, vector part ĝ × â
        err = abs(vy * az - vz * ay) + abs(vz * ax - vx * az) + abs(vx * ay - vy * ax)
        lam = p[_LAM_MAX]
        if p[_ADAPTIVE] != 0.0:
            e_a = p[_LOWPASS] * state[_E_A] + p[_GAIN] * err  # (eq. 20) low-pass
            state[_E_A] = e_a
            lam = lam - e_a
            if lam < p[_LAM_MIN]:
                lam = p[_LAM_MIN]
            elif lam > p[_LAM_MAX]:  # only for a negative e_a, i.e. a negative error_gain
                lam = p[_LAM_MAX]
            overrange = p[_OVERRANGE]  # inf: off (no finite rate reaches it)
            if abs(gx) >= overrange or abs(gy) >= overrange or abs(gz) >= overrange:
                lam = p[_LAM_MAX]  # gyro over-range rule (module docstring)
                status |= GYRO_OVERRANGE
        state[_LAM], state[_ERR] = lam, err
        n2 = s1 * s1 + s2 * s2 + s3 * s3 + s4 * s4
        if n2 > 0.0:  # ∇f = 0 when the estimate already matches: nothing to correct
            k = lam * (1.0 / np.sqrt(n2))
            # (eq. 18) q̇ = q̇_ω - λ ∇f/‖∇f‖
            d1, d2, d3, d4 = d1 - k * s1, d2 - k * s2, d3 - k * s3, d4 - k * s4
        if p[P_MAGNETOMETER] != 0.0:  # hfm: Madgwick's magnetometer term about the vertical, its share of his step (marg.py)
            status, field = field_screen(state, status, gx, gy, gz, dt_s, mx, my, mz)
            if field:
                b1, b2, b3, b4 = _field_gradient(q1, q2, q3, q4, mx, my, mz)
                nb2 = b1 * b1 + b2 * b2 + b3 * b3 + b4 * b4
                if nb2 > 0.0:
                    k = lam / math.sqrt(n2 + nb2)
                    d1, d2, d3, d4 = d1 - k * b1, d2 - k * b2, d3 - k * b3, d4 - k * b4
    # (eq. 19) q(k) = q(k-1) + q̇ Δt, normalised
    q1, q2, q3, q4 = q1 + d1 * dt_s, q2 + d2 * dt_s, q3 + d3 * dt_s, q4 + d4 * dt_s
    r = 1.0 / np.sqrt(q1 * q1 + q2 * q2 + q3 * q3 + q4 * q4)
    state[0], state[1], state[2], state[3] = q1 * r, q2 * r, q3 * r, q4 * r
    return status


@register_jitable
def _field_gradient(q1, q2, q3, q4, mx, my, mz):
    """The gradient of Madgwick's magnetometer rows, its part about the vertical only (marg.py); zero
    without a usable reading."""
    usable, mx, my, mz = unit_field(mx, my, mz)
    if not usable:
        return 0.0, 0.0, 0.0, 0.0
    bx, bz = earth_field_reference(q1, q2, q3, q4, mx, my, mz)
    # (Madgwick eq. 31) f_b = Rᵀ(q) b - m̂
    f4 = 2.0 * bx * (0.5 - q3 * q3 - q4 * q4) + 2.0 * bz * (q2 * q4 - q1 * q3) - mx
    f5 = 2.0 * bx * (q2 * q3 - q1 * q4) + 2.0 * bz * (q1 * q2 + q3 * q4) - my
    f6 = 2.0 * bx * (q1 * q3 + q2 * q4) + 2.0 * bz * (0.5 - q2 * q2 - q3 * q3) - mz
    # (Madgwick eq. 32, 34) J_bᵀ f_b, about the vertical
    return about_vertical_q(
        q1, q2, q3, q4,
        -2.0 * bz * q3 * f4 + (-2.0 * bx * q4 + 2.0 * bz * q2) * f5 + 2.0 * bx * q3 * f6,
        2.0 * bz * q4 * f4 + (2.0 * bx * q3 + 2.0 * bz * q1) * f5 + (2.0 * bx * q4 - 4.0 * bz * q2) * f6,
        (-4.0 * bx * q3 - 2.0 * bz * q1) * f4 + (2.0 * bx * q2 + 2.0 * bz * q4) * f5 + (2.0 * bx * q1 - 4.0 * bz * q3) * f6,
        (-4.0 * bx * q4 + 2.0 * bz * q2) * f4 + (-2.0 * bx * q1 + 2.0 * bz * q3) * f5 + 2.0 * bx * q2 * f6,
    )  # fmt: skip


@njit(cache=True)
def ahf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, ahf_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Ahf(CompiledEstimator):
    """Adaptive hybrid filter (eq. 6-20). ``dtype=np.float32`` runs it in single precision."""

    name = "ahf"
    Settings = AhfSettings
    Diagnostics = AhfDiagnostics
    kernel = staticmethod(ahf_kernel)
    run_kernel = staticmethod(ahf_run)
    adaptive = True

    def __init__(self, settings=None, dtype=None):
        s = self.Settings() if settings is None else settings
        if self.adaptive and not 0.0 <= s.lambda_min <= s.lambda_max:
            raise ValueError("need 0 <= lambda_min <= lambda_max")
        if not self.adaptive and s.beta < 0.0:
            raise ValueError("beta must be >= 0")
        super().__init__(s, dtype)

    def _parameters(self):
        s = self.settings
        if not self.adaptive:
            return [0.0, s.beta, 0.0, 0.0, 0.0, math.inf]
        return [1.0, s.lambda_max, s.lambda_min, s.lowpass, (1.0 - s.lowpass) * s.error_gain, s.gyro_overrange_rad_s]

    def _initial_state(self):
        return [self._parameters()[1], 0.0, 0.0]  # λ = λ_max, e_a, gravity_error


class Hf(Ahf):
    """Hybrid filter with λ fixed at ``beta`` (eq. 6-19): Madgwick's IMU filter. β = 0 is gyro-only."""

    name = "hf"
    Settings = HfSettings
    adaptive = False
