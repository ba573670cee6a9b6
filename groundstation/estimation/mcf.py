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
heading error against the compass heading error. The defaults below (but ``acc_weight``) are that design run on the simulator's
MPU-6050 and magnetometer (``groundstation experiments --only seed003`` prints the design on several seeds).

Compass tilt (reading): the paper's HMR3500 module computes its tilt from an accelerometer of its own.
This craft has one accelerometer, so that reading would repeat the second source. The independent
third source a single magnetometer gives is the tilt that turns the measured field onto the local
3-axis field at the current heading (eq. 13 solved for θ, φ instead of ψ: ``compass.tilt_from_field_rad``).
It needs the field's dip δ (the paper took its local field at a 60-s rest): ``mag_dip_rad``, or NaN to take
it from the first sample with both a usable accelerometer and a reading. The heading it uses is the
filter's, so heading error leaks into the compass roll (× cot δ ≈ 0.44 for the simulator's field).

Disturbances (issue 33): a magnetometer may correct heading only, so the compass tilt is off by default
(``acc_weight`` 1; the seed's design, 0.6, for a field known to be clean), and a reading whose norm or dip
is off the learnt field is used for neither (``base.field_screen``; ``MAG_REJECTED`` in the status).

Initialisation: pitch and roll from gravity (``base``), yaw from the compass when that sample has a
reading, else 0. Readings must be free of hard and soft iron (``magcal``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from numba import njit
from numba.extending import register_jitable

from groundstation.analysis.spectrum import amplitude_spectrum
from groundstation.estimation.base import INITIALISED, NO_UPDATE, P_OWN, REINITIALISED, STATE_DIAG, CommonSettings, CompiledEstimator, field_screen, guard, record, sample
from groundstation.estimation.compass import field_tilt_rad, level_heading_rad
from groundstation.estimation.tilt import acc_pitch_roll, euler_of, euler_rates, quaternion_of, unit_field, wrap_pi


@dataclasses.dataclass(frozen=True)
class McfSettings(CommonSettings):
    # The design (module docstring) on the simulated turntable, seeds 1-3, 300 s: pitch/roll crossover
    # 0.23-0.36 Hz, w_a 0.46-0.79, heading crossover 0.18-0.29 Hz (seed003 prints it); their middles:
    crossover_hz: float = 0.3  # pitch/roll: gyro above, accelerometer + compass tilt below (Hz)
    # w_a, the accelerometer's share of the low band; the compass tilt gets 1 - w_a. 1: no compass tilt, the
    # magnetometer corrects heading only (issue 33: a magnet near the sensor tilts the estimate). The
    # design below gives 0.6 (the seed's fusion, for a field known clean)
    acc_weight: float = 1.0
    heading_crossover_hz: float = 0.23  # heading: gyro above, compass below (Hz)
    mag_dip_rad: float = math.nan  # field dip, positive down; NaN: from the first sample with a reading
    declination_rad: float = 0.0  # added to the compass heading for true north


class McfDiagnostics(NamedTuple):
    status: int
    compass_used: int  # 1 when a compass heading entered this sample
    mag_dip_rad: float  # the dip in use; 0 until known (then the compass tilt is not used)


# Parameters after the guard's (base.P_OWN); state after q, the guard's and the diagnostics: the angles
# (yaw, pitch, roll, rad) and the dip (NaN until known)
_ACC_WEIGHT, _TAU_S, _TAU_HEADING_S, _DECLINATION = range(P_OWN, P_OWN + 4)
_USED, _DIP_SHOWN, _YAW, _PITCH, _ROLL, _DIP = range(STATE_DIAG, STATE_DIAG + 6)


@njit(cache=True)
def mcf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One sample of MCF (module docstring): base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    field, _, _, _ = unit_field(mx, my, mz)  # a usable reading (finite, non-zero)
    if status & (INITIALISED | REINITIALISED):
        # the guard set q from gravity, yaw from the compass (magnetic) when there is a reading
        yaw, pitch, roll = euler_of((state[0], state[1], state[2], state[3]))
        if field:
            yaw += p[_DECLINATION]
            state[0], state[1], state[2], state[3] = quaternion_of(yaw, pitch, roll)
        state[_YAW], state[_PITCH], state[_ROLL] = yaw, pitch, roll
    if status & NO_UPDATE:
        return status
    yaw, pitch, roll = state[_YAW], state[_PITCH], state[_ROLL]
    dyaw, dpitch, droll = euler_rates(roll, pitch, gx, gy, gz)
    yaw, pitch, roll = yaw + dyaw * dt_s, pitch + dpitch * dt_s, roll + droll * dt_s  # gyro source
    status, field = field_screen(state, status, gx, gy, gz, dt_s, mx, my, mz)  # a disturbed reading is none
    # the absolute sources, weighted: the accelerometer's tilt, then the compass's
    total, sum_pitch, sum_roll = 0.0, 0.0, 0.0
    if acc_ok:
        pitch_a, roll_a = acc_pitch_roll(ax, ay, az)
        w = p[_ACC_WEIGHT]
        total, sum_pitch, sum_roll = w, w * (pitch_a - pitch), w * wrap_pi(roll_a - roll)
        if state[_DIP] != state[_DIP] and field:  # NaN: learn the dip now
            state[_DIP] = _dip_rad(ax, ay, az, mx, my, mz)
            state[_DIP_SHOWN] = state[_DIP]
    if field and state[_DIP] == state[_DIP]:
        found, pitch_m, roll_m = field_tilt_rad(mx, my, mz, yaw - p[_DECLINATION], state[_DIP], roll)
        if found:
            w = 1.0 - p[_ACC_WEIGHT]
            total, sum_pitch, sum_roll = total + w, sum_pitch + w * (pitch_m - pitch), sum_roll + w * wrap_pi(roll_m - roll)
    if total > 0.0:
        k = dt_s / (p[_TAU_S] + dt_s)  # 1 - α
        pitch += k * sum_pitch / total
        roll += k * sum_roll / total
    state[_USED] = 0.0
    if field:
        heading = level_heading_rad(pitch, roll, mx, my, mz) + p[_DECLINATION]
        yaw += dt_s / (p[_TAU_HEADING_S] + dt_s) * wrap_pi(heading - yaw)
        state[_USED] = 1.0
    yaw, roll = wrap_pi(yaw), wrap_pi(roll)
    state[_YAW], state[_PITCH], state[_ROLL] = yaw, pitch, roll
    state[0], state[1], state[2], state[3] = quaternion_of(yaw, pitch, roll)
    return status


@njit(cache=True)
def mcf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, mcf_kernel(state, p, *sample(gyr, acc, dt, mag, k)), status_out, q_out, diag_out)


class Mcf(CompiledEstimator):
    name = "mcf"
    uses_magnetometer = True
    Settings = McfSettings
    Diagnostics = McfDiagnostics
    kernel = staticmethod(mcf_kernel)
    run_kernel = staticmethod(mcf_run)

    def __init__(self, settings=None, dtype=None):
        s = self.Settings() if settings is None else settings
        if not (s.crossover_hz > 0 and s.heading_crossover_hz > 0 and 0.0 <= s.acc_weight <= 1.0):
            raise ValueError("need crossover_hz > 0, heading_crossover_hz > 0 and 0 <= acc_weight <= 1")
        super().__init__(s, dtype)

    def _parameters(self):
        s = self.settings
        return [s.acc_weight, 1.0 / (2.0 * math.pi * s.crossover_hz), 1.0 / (2.0 * math.pi * s.heading_crossover_hz), s.declination_rad]

    def reset(self, q0=None) -> None:
        super().reset(q0)
        self._state[_YAW : _ROLL + 1] = euler_of(tuple(self._values()[:4]))  # the angles of q0 (identity: 0)

    def _initial_state(self):
        dip = self.settings.mag_dip_rad
        return [0.0, dip if dip == dip else 0.0, 0.0, 0.0, 0.0, dip]  # compass_used, dip shown, angles, dip


@register_jitable
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
