"""Gains of the position correction loops from a crossover frequency and a damping ratio.

Per axis the accelerometer channel is a double integrator corrected by an aiding position ``z``
(barometer or GPS) through the error ``e = z - p`` (seed 004 section 2, "correction loops"):

- single channel (the paper's algorithm 2, proportional only)::

      p' = v + kp e          v' = a + kv e
      error poles: s² + kp s + kv = s² + 2ζω s + ω²  ->  kp = 2ζω, kv = ω²

  A constant accelerometer bias ``b`` leaves a steady position error ``b / kv`` (the paper: "the
  single channel cannot remove the steady-state error").

- dual channel (algorithm 3: proportional loops plus the integral "feedback loop" into the
  accelerometer channel; ``b̂`` is the accelerometer bias estimate, NED m/s²)::

      p' = v + kp e          v' = a - b̂ + kv e          b̂' = -ki e
      error poles: s³ + kp s² + kv s + ki = (s + ρω)(s² + 2ζω s + ω²)
          ->  kp = (2ζ + ρ)ω, kv = (1 + 2ζρ)ω², ki = ρω³

  The bias pole ``ρω`` sits below the crossover (``ρ`` = ``bias_pole_ratio``, 0.25 by default) so
  that the bias estimate averages over several loop time constants instead of following the aid's
  noise; at ``ρ → 0`` the dual channel becomes the single one, at ``ρ = 1`` it is the common
  "(s + ω)(s² + 2ζωs + ω²)" third-order filter, noisier by its larger ``kp``.

  and, where the receiver gives velocity ``u`` (GPS), a velocity loop on ``e_v = u - v``::

      v' += kvv e_v          b̂' -= kvi e_v         s² + kvv s + kvi = s² + 2ζω_v s + ω_v²

Choosing ω (the design, not a fit to one run): for white acceleration error of density ``σ_a``
(PSD ``q = σ_a²``) and white aiding noise ``σ_z`` at ``f`` Hz (PSD ``r = σ_z² / f``), the
steady-state Kalman-Bucy filter of the double integrator *is* the single-channel filter with
``ω = (q / r)^(1/4)`` and ``ζ = 1/√2`` (the algebraic Riccati equation solved in closed form: gains
``√2 (q/r)^(1/4)`` and ``(q/r)^(1/2)``); for a velocity aid (single integrator) ``ω_v = (q / r)^(1/2)``.
``crossover_rad_s`` computes it; above ω the estimate follows the accelerometer, below it the aid.
"""

from __future__ import annotations

import math
from typing import NamedTuple

SQRT_HALF = 1.0 / math.sqrt(2.0)


class Gains(NamedTuple):
    """One correction loop's gains: ``kp_1_s`` into position, ``kv_1_s2`` into velocity,
    ``ki_1_s3`` into the accelerometer bias (0 for the single channel)."""

    kp_1_s: float
    kv_1_s2: float
    ki_1_s3: float


class VelocityGains(NamedTuple):
    """The velocity aid's gains: ``kv_1_s`` into velocity, ``ki_1_s2`` into the accelerometer bias."""

    kv_1_s: float
    ki_1_s2: float


def crossover_rad_s(acc_error_m_s2_rt_hz: float, aid_noise: float, aid_rate_hz: float, aid_order: int = 2) -> float:
    """Kalman-optimal crossover ω (rad/s) for white errors: ``(q / r)^(1/aid_order)``.

    ``aid_noise`` is the aid's σ per reading (m for a position aid, ``aid_order`` 2; m/s for a
    velocity aid, ``aid_order`` 1), ``aid_rate_hz`` its reading rate.
    """
    if not (acc_error_m_s2_rt_hz > 0 and aid_noise > 0 and aid_rate_hz > 0 and aid_order in (1, 2)):
        raise ValueError("need positive noise densities and rate, and aid_order 1 (velocity) or 2 (position)")
    q = acc_error_m_s2_rt_hz**2
    r = aid_noise**2 / aid_rate_hz
    return (q / r) ** (1.0 / (2 * aid_order))


def single_channel_gains(omega_rad_s: float, damping: float) -> Gains:
    """Proportional position loop with error poles ``s² + 2ζω s + ω²``."""
    _check(omega_rad_s, damping)
    return Gains(2.0 * damping * omega_rad_s, omega_rad_s**2, 0.0)


def dual_channel_gains(omega_rad_s: float, damping: float, bias_pole_ratio: float) -> Gains:
    """Proportional + integral position loop with error poles ``(s + ρω)(s² + 2ζω s + ω²)``."""
    _check(omega_rad_s, damping)
    if not 0.0 < bias_pole_ratio <= 1.0:
        raise ValueError(f"bias_pole_ratio must be in (0, 1], not {bias_pole_ratio!r}")
    rho = bias_pole_ratio
    return Gains((2.0 * damping + rho) * omega_rad_s, (1.0 + 2.0 * damping * rho) * omega_rad_s**2, rho * omega_rad_s**3)


def velocity_gains(omega_rad_s: float, damping: float) -> VelocityGains:
    """Velocity aid loop with error poles ``s² + 2ζω s + ω²`` on velocity and bias."""
    _check(omega_rad_s, damping)
    return VelocityGains(2.0 * damping * omega_rad_s, omega_rad_s**2)


def _check(omega_rad_s: float, damping: float) -> None:
    if not (omega_rad_s > 0 and damping > 0 and math.isfinite(omega_rad_s) and math.isfinite(damping)):
        raise ValueError(f"crossover and damping must be positive and finite, not {omega_rad_s!r} rad/s, {damping!r}")
