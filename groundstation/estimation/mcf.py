"""MCF: seed 003's multi-sensor complementary filter (Ma et al.; digest §4), and its design from error spectra.

Per angle, as the paper fuses angles (its figures 4-7, eq. 16-19; the transfer functions themselves did
not survive the text extraction, so their form here is the reading below):

- pitch θ and roll φ from three sources: the gyro integrated through the ZYX Euler kinematics
  (``tilt.euler_rates``), the accelerometer tilt (``tilt.acc_pitch_roll``) and the compass tilt;
- heading ψ from two: the integrated gyro and the tilt-compensated compass heading (eq. 13-15,
  ``compass.level_heading_rad`` with the fused pitch and roll).

Filters (reading of eq. 16-17): ``G_g + G_a + G_m = 1`` with ``G_g(s) = τs/(τs + 1)`` (the gyro angle
high-passed) and ``G_a = w_a/(τs + 1)``, ``G_m = (1 - w_a)/(τs + 1)`` (the absolute sources low-passed,
blended); in discrete time, with ``α = τ/(τ + Δt)`` and ``τ = 1/(2π f_c)``::

    θ(k) = α (θ(k-1) + θ̇_gyro Δt) + (1 - α) (w_a θ_acc + (1 - w_a) θ_compass)

(when one absolute source is missing on a sample the other takes its weight; with neither, gyro only).
Heading (eq. 18-19): ``ψ(k) = ψ_g + (1 - α_ψ) wrap(ψ_compass - ψ_g)``, ``ψ_g = ψ(k-1) + ψ̇_gyro Δt``.

Design (the paper's method: each source's angle error against a reference, its FFT amplitude spectrum,
the filters placed where the errors are complementary): ``crossover_hz`` is where the gyro's error
spectrum (low-frequency: bias drift) falls below the absolute source's (broadband noise), found by
``crossover_from_spectra``; ``w_a`` is the inverse-variance weight of the accelerometer against the compass
tilt (both broadband in this band, ``inverse_variance_weight``); the heading crossover likewise from the gyro
heading error against the compass heading error. The defaults below are that design run on the simulator's
MPU-6050 and magnetometer (``groundstation experiments --only seed003`` prints the design on several seeds).

Compass tilt (reading): the paper's HMR3500 module computes its tilt from an accelerometer of its own.
This craft has one accelerometer, so that reading would repeat the second source. The independent
third source a single magnetometer gives is the tilt that turns the measured field onto the local
3-axis field at the current heading (eq. 13 solved for θ, φ instead of ψ: ``compass.tilt_from_field_rad``).
It needs the field's dip δ (the paper took its local field at a 60-s rest): ``mag_dip_rad``, or NaN to take
it from the first sample with both a usable accelerometer and a reading. The heading it uses is the
filter's, so heading error leaks into the compass roll (× cot δ ≈ 0.44 for the simulator's field).

Initialisation: pitch and roll from gravity (``base``), yaw from the compass when that sample has a
reading, else 0. Readings must be free of hard and soft iron (``magcal``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from groundstation import quaternion
from groundstation.analysis.spectrum import amplitude_spectrum
from groundstation.estimation.base import CommonSettings, Estimator
from groundstation.estimation.compass import level_heading_rad, tilt_from_field_rad
from groundstation.estimation.tilt import acc_pitch_roll, euler_rates, wrap_pi


@dataclasses.dataclass(frozen=True)
class McfSettings(CommonSettings):
    # The design (module docstring) on the simulated turntable, seeds 1-3, 300 s: pitch/roll crossover
    # 0.23-0.36 Hz, w_a 0.46-0.79, heading crossover 0.18-0.29 Hz (seed003 prints it); their middles:
    crossover_hz: float = 0.3  # pitch/roll: gyro above, accelerometer + compass tilt below (Hz)
    acc_weight: float = 0.6  # w_a, the accelerometer's share of the low band; the compass tilt gets 1 - w_a
    heading_crossover_hz: float = 0.23  # heading: gyro above, compass below (Hz)
    mag_dip_rad: float = math.nan  # field dip, positive down; NaN: from the first sample with a reading
    declination_rad: float = 0.0  # added to the compass heading for true north


class McfDiagnostics(NamedTuple):
    status: int
    compass_used: int  # 1 when a compass heading entered this sample
    mag_dip_rad: float  # the dip in use; 0 until known (then the compass tilt is not used)


class Mcf(Estimator):
    name = "mcf"
    label = "MCF"
    colour = "sand"
    needs = frozenset({"mag"})
    uses_magnetometer = True
    Settings = McfSettings
    Diagnostics = McfDiagnostics

    def __init__(self, settings=None):
        s = self.Settings() if settings is None else settings
        if not (s.crossover_hz > 0 and s.heading_crossover_hz > 0 and 0.0 <= s.acc_weight <= 1.0):
            raise ValueError("need crossover_hz > 0, heading_crossover_hz > 0 and 0 <= acc_weight <= 1")
        self._tau_s = 1.0 / (2.0 * math.pi * s.crossover_hz)
        self._tau_heading_s = 1.0 / (2.0 * math.pi * s.heading_crossover_hz)
        super().__init__(s)

    def _reset_state(self):
        self._angles = (0.0, 0.0, 0.0)  # yaw, pitch, roll (rad)
        self._dip = self.settings.mag_dip_rad
        self._used = 0

    def _set_attitude(self, q):
        self._q = q
        self._angles = tuple(quaternion.to_euler_zyx(np.array(q)).tolist())

    def _diagnostics(self, status):
        return McfDiagnostics(status, self._used, self._dip if self._dip == self._dip else 0.0)

    def _attitude_from_acc(self, ax, ay, az, yaw_rad):
        pitch, roll = acc_pitch_roll(float(ax), float(ay), float(az))
        m = self._field()
        if m is not None:
            yaw_rad = float(level_heading_rad(pitch, roll, *m)) + self.settings.declination_rad
        return tuple(quaternion.from_euler_zyx(yaw_rad, pitch, roll).tolist())

    def _field(self):
        """The reading as three floats, or None when missing or not finite and non-zero."""
        m = self._mag
        if m is None or not 0.0 < m[0] * m[0] + m[1] * m[1] + m[2] * m[2] < math.inf:
            return None
        return m

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        yaw, pitch, roll = self._angles
        dyaw, dpitch, droll = euler_rates(roll, pitch, gx, gy, gz)
        yaw, pitch, roll = yaw + dyaw * dt_s, pitch + dpitch * dt_s, roll + droll * dt_s  # gyro source
        sources = []  # (weight, pitch, roll) of the absolute sources
        if acc_ok:
            pitch_a, roll_a = acc_pitch_roll(ax, ay, az)
            sources.append((self.settings.acc_weight, pitch_a, roll_a))
            if self._dip != self._dip and (m := self._field()) is not None:  # NaN: learn the dip now
                self._dip = _dip_rad(ax, ay, az, *m)
        m = self._field()
        tilt_m = None if m is None or self._dip != self._dip else tilt_from_field_rad(*m, yaw - self.settings.declination_rad, self._dip, roll)
        if tilt_m is not None:
            sources.append((1.0 - self.settings.acc_weight, *tilt_m))
        total = sum(w for w, _, _ in sources)
        if total > 0.0:
            k = dt_s / (self._tau_s + dt_s)  # 1 - α
            pitch += k * sum(w * (p - pitch) for w, p, _ in sources) / total
            roll += k * sum(w * wrap_pi(r - roll) for w, _, r in sources) / total
        self._used = 0
        if m is not None:
            heading = float(level_heading_rad(pitch, roll, *m)) + self.settings.declination_rad
            yaw += dt_s / (self._tau_heading_s + dt_s) * wrap_pi(heading - yaw)
            self._used = 1
        self._angles = (wrap_pi(yaw), pitch, wrap_pi(roll))
        self._q = tuple(quaternion.from_euler_zyx(*self._angles).tolist())
        return self._q, self._diagnostics(status)


def _dip_rad(ax, ay, az, mx, my, mz):
    """Dip of the field below the horizontal: asin of the reading's component along the measured down."""
    dot = -(ax * mx + ay * my + az * mz) / math.sqrt((ax * ax + ay * ay + az * az) * (mx * mx + my * my + mz * mz))
    return math.asin(max(-1.0, min(1.0, dot)))


def crossover_from_spectra(gyro_error, absolute_error, dt_s: float, bands_per_decade: int = 10) -> float:
    """The frequency (Hz) above which the gyro's angle error spectrum stays below the absolute source's.

    Both errors (N,) against the same truth, in the same unit. Their amplitude spectra (mean removed,
    Hann window: ``analysis.spectrum``) are averaged over log-spaced bands (``bands_per_decade``) so that
    single bins' scatter does not decide; the crossover is the geometric centre of the lowest band from
    which the gyro's band level is below the absolute source's in every band up to Nyquist.
    """
    f, a_gyro = amplitude_spectrum(gyro_error, dt_s)
    _, a_abs = amplitude_spectrum(absolute_error, dt_s)
    edges = np.logspace(np.log10(f[1]), np.log10(f[-1]), int(np.log10(f[-1] / f[1]) * bands_per_decade) + 2)
    band = np.digitize(f[1:], edges) - 1
    keep = np.unique(band)
    gyro_level = np.array([a_gyro[1:][band == b].mean() for b in keep])
    abs_level = np.array([a_abs[1:][band == b].mean() for b in keep])
    above = np.flatnonzero(gyro_level >= abs_level)
    if len(above) == len(keep):
        raise ValueError("the gyro's error never falls below the absolute source's: no crossover")
    first = 0 if len(above) == 0 else above[-1] + 1
    return float(np.sqrt(edges[keep[first]] * edges[keep[first] + 1]))


def inverse_variance_weight(error_a, error_b) -> float:
    """Weight of source a in the minimum-variance blend ``w a + (1 - w) b`` of two independent errors."""
    var_a, var_b = np.var(error_a), np.var(error_b)
    return float(var_b / (var_a + var_b))
