"""Motor vibration for the simulated IMU: rotor harmonics at a frequency that follows the thrust.

A multirotor's rotors turn at ``ω ∝ √thrust`` (thrust ∝ ω²), and an unbalanced rotor shakes the frame
at its turning frequency and harmonics with a force ∝ ω². The thrust is read from the truth: the
specific force along the body's -z (FRD), 1 g in hover. So, with ``r = max(-f_z, 0) / g``::

    f(t)      = hover_hz √r                        (the rotor frequency)
    φ(t)      = 2π ∫ f dt                          (continued from block to block)
    accel(t)  = accel_m_s2 · r · g_axis · Σ_k h_k sin(k φ + θ_k)     per axis, m/s²
    gyro(t)   = gyro_dps   · r · g_axis · Σ_k h_k sin(k φ + θ_k)     per axis, °/s

with the harmonics ``h = HARMONICS`` (fundamental 1, second ½), axis gains strongest along the thrust for
the accelerometer and in roll and pitch for the gyro, and the whole faded in over 2 s after the
profile's rest (``profiles.REST_S``): the motors start after the board calibrated at rest. It is
added to the sensor's analog reading (``imu.MPU6050.analog``), not to the truth: the attitude the
estimators are scored against stays the rigid body's. Off (``hover_hz`` 0) it costs nothing and
changes no other output.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation.sim.profiles import REST_S, Moves
from groundstation.sim.settings import VibrationSettings
from groundstation.units import STANDARD_GRAVITY_M_S2

HARMONICS = (1.0, 0.5)  # amplitude of the fundamental and the second harmonic
PHASES_RAD = (0.0, math.pi / 3.0)
ACCEL_AXIS_GAIN = np.array([0.5, 0.5, 1.0])  # the rotors shake the frame most along their thrust
GYRO_AXIS_GAIN = np.array([1.0, 1.0, 0.3])  # and rock it in roll and pitch
SPIN_UP_S = 2.0


class MotorVibration:
    """The vibration at consecutive blocks of sample times (the rotor phase carries over)."""

    def __init__(self, settings: VibrationSettings):
        self.settings = settings
        self._fade = Moves([REST_S, REST_S + SPIN_UP_S], [0.0, 1.0])
        self._t_s: float | None = None
        self._f_hz = 0.0
        self._phase_rad = 0.0

    @staticmethod
    def thrust_ratio(specific_force_body_m_s2: np.ndarray) -> np.ndarray:
        return np.maximum(-specific_force_body_m_s2[:, 2], 0.0) / STANDARD_GRAVITY_M_S2

    def __call__(self, t_s: np.ndarray, specific_force_body_m_s2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gyro (°/s) and accelerometer (m/s²) vibration (n, 3) on the body axes."""
        s = self.settings
        ratio = self.thrust_ratio(specific_force_body_m_s2)
        f = s.hover_hz * np.sqrt(ratio)
        t_prev = t_s[0] if self._t_s is None else self._t_s
        f_prev = f[0] if self._t_s is None else self._f_hz
        steps = np.diff(np.concatenate([[t_prev], t_s])) * (np.concatenate([[f_prev], f[:-1]]) + f) / 2.0  # trapezoid
        phase = self._phase_rad + 2.0 * math.pi * np.cumsum(steps)
        self._t_s, self._f_hz, self._phase_rad = float(t_s[-1]), float(f[-1]), float(phase[-1] % (2.0 * math.pi))
        wave = sum(h * np.sin(k * phase + p) for k, (h, p) in enumerate(zip(HARMONICS, PHASES_RAD), start=1))
        shake = (self._fade(np.asarray(t_s, dtype=float))[0] * ratio * wave)[:, None]
        return shake * s.gyro_dps * GYRO_AXIS_GAIN, shake * s.accel_m_s2 * ACCEL_AXIS_GAIN
