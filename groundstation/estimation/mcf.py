"""MCF: seed 003's multi-sensor complementary filter (Ma et al.; digest §4), and its design from error spectra.

The paper fuses angles (its figures 4-7, eq. 16-19; the transfer functions themselves did not survive the
text extraction, so their form here is the reading below):

- pitch θ and roll φ from three sources: the gyro integrated, the accelerometer tilt and the compass tilt;
- heading ψ from two: the integrated gyro and the tilt-compensated compass heading (eq. 13-15).

Filters (reading of eq. 16-17): ``G_g + G_a + G_m = 1`` with ``G_g(s) = τs/(τs + 1)`` (the gyro angle
high-passed) and ``G_a = w_a/(τs + 1)``, ``G_m = (1 - w_a)/(τs + 1)`` (the absolute sources low-passed,
blended); in discrete time, with ``1 - α = Δt/(τ + Δt)`` and ``τ = 1/(2π f_c)``::

    v(k) = v_g + (1 - α) (w_a d_acc + (1 - w_a) d_compass - v_g),   v_g = v(k-1) turned by the gyro over Δt

on the direction of gravity on the body axes v, not on the angles θ and φ themselves (for the paper's
turntable, ±25°, the two agree to first order): ``d_acc = -a/g`` is the specific force as measured and
``d_compass`` the down of the compass's pitch and roll; when one absolute source is missing on a sample the
other takes its weight; with neither, gyro only. The gyro turns the attitude quaternion (``base.integrate_rate``)
and the blend tilts it by the smallest turn that moves its down to v. Why not the angles (issue 33, item 2:
BROAD's fast trials, 45° RMS and 180° off): the Euler-angle rates are singular at ±90° pitch, which fast
rotation passes; and ``atan2`` of an accelerometer a few g off gravity averages to no angle of gravity
(roll is undefined where it points along x), while the reading itself, linear, averages its zero-mean
linear acceleration out at the crossover.
Heading (eq. 18-19): ``ψ(k) = ψ_g + (1 - α_ψ) wrap(ψ_compass - ψ_g)``, ``ψ_g`` the gyro's, as a turn about the
vertical; ``ψ_compass - ψ_g`` is the turn that points the reading's horizontal part north
(``compass.heading_offset_rad``, defined at any tilt).

Design (the paper's method: each source's angle error against a reference, its FFT amplitude spectrum,
the filters placed where the errors are complementary): ``crossover_hz`` is where the gyro's error
spectrum (low-frequency: bias drift) falls below the absolute source's (broadband noise), found by
``crossover_from_spectra``; ``w_a`` is the inverse-variance weight of the accelerometer against the compass
tilt (both broadband in this band, ``inverse_variance_weight``); the heading crossover likewise from the gyro
heading error against the compass heading error. The defaults below (but ``acc_weight`` and ``crossover_hz``) are that design run on the simulator's
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

from groundstation.spectrum import amplitude_spectrum
from groundstation.estimation.base import INITIALISED, NO_UPDATE, P_OWN, REINITIALISED, STATE_DIAG, CommonSettings, CompiledEstimator, field_screen, guard, integrate_rate, record, sample, unmanaged
from groundstation.estimation.compass import field_tilt_rad, heading_offset_rad
from groundstation.estimation.tilt import euler_of, quaternion_product, unit_field, wrap_pi


@dataclasses.dataclass(frozen=True)
class McfSettings(CommonSettings):
    # The design (module docstring) on the simulated turntable, seeds 1-3, 300 s: pitch/roll crossover
    # 0.23-0.36 Hz, w_a 0.46-0.79, heading crossover 0.18-0.29 Hz (seed003 prints it); their middles but
    # for the pitch/roll crossover. A turntable does not translate: held by hand and shaken by a few g, the
    # accelerometer's error reaches far lower, and at 0.3 Hz BROAD dev trial 16 was 14° RMS off (63° at
    # most); at 0.05 Hz every dev trial is within 2.9° RMS, 8.2° at most (issue 33; 0.03-0.15 Hz tried)
    crossover_hz: float = 0.05  # pitch/roll: gyro above, accelerometer + compass tilt below (Hz)
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


# Parameters after the guard's (base.P_OWN); state after q, the guard's and the diagnostics: the dip (NaN
# until known)
_ACC_WEIGHT, _TAU_S, _TAU_HEADING_S, _DECLINATION = range(P_OWN, P_OWN + 4)
_USED, _DIP_SHOWN, _DIP = range(STATE_DIAG, STATE_DIAG + 3)


@register_jitable
def _down_of_tilt(pitch_rad, roll_rad):
    """Down on the body axes at this pitch and roll (``tilt.acc_pitch_roll`` inverted, any heading)."""
    cp = math.cos(pitch_rad)
    return -math.sin(pitch_rad), math.sin(roll_rad) * cp, math.cos(roll_rad) * cp


@njit(cache=True)
def mcf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """One sample of MCF (module docstring): base.py's compiled kernels."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    field, _, _, _ = unit_field(mx, my, mz)  # a usable reading (finite, non-zero)
    if status & (INITIALISED | REINITIALISED) and field:
        # the guard set q from gravity, yaw from the compass (magnetic): turned to true north
        q = quaternion_product(_about_down(p[_DECLINATION]), (state[0], state[1], state[2], state[3]))
        state[0], state[1], state[2], state[3] = q
    if status & NO_UPDATE:
        return status
    q = integrate_rate((state[0], state[1], state[2], state[3]), gx, gy, gz, dt_s)  # the gyro source
    state[0], state[1], state[2], state[3] = q
    status, field = field_screen(state, status, gx, gy, gz, dt_s, mx, my, mz)  # a disturbed reading is none
    # the absolute sources' down on the body axes, weighted: the accelerometer's, then the compass tilt's
    total, dx, dy, dz = 0.0, 0.0, 0.0, 0.0
    if acc_ok:
        w = p[_ACC_WEIGHT]  # the reading as it is, in g: not normalised (module docstring)
        total, dx, dy, dz = w, -w * ax, -w * ay, -w * az
        if state[_DIP] != state[_DIP] and field:  # NaN: learn the dip now
            state[_DIP] = _dip_rad(ax, ay, az, mx, my, mz)
            state[_DIP_SHOWN] = state[_DIP]
    if field and state[_DIP] == state[_DIP] and p[_ACC_WEIGHT] < 1.0:
        yaw, _, roll = euler_of(q)
        found, pitch_m, roll_m = field_tilt_rad(mx, my, mz, yaw - p[_DECLINATION], state[_DIP], roll)
        if found:
            w = 1.0 - p[_ACC_WEIGHT]
            ux, uy, uz = _down_of_tilt(pitch_m, roll_m)
            total, dx, dy, dz = total + w, dx + w * ux, dy + w * uy, dz + w * uz
    if total > 0.0:
        q = _tilt_toward(q, dx / total, dy / total, dz / total, dt_s / (p[_TAU_S] + dt_s))  # 1 - α
    state[_USED] = 0.0
    if field:
        offset = heading_offset_rad(q[0], q[1], q[2], q[3], mx, my, mz) + p[_DECLINATION]
        q = quaternion_product(_about_down(dt_s / (p[_TAU_HEADING_S] + dt_s) * wrap_pi(offset)), q)
        state[_USED] = 1.0
    state[0], state[1], state[2], state[3] = q
    return status


@register_jitable
def _about_down(angle_rad):
    """The turn by ``angle_rad`` about the NED vertical (heading += angle), to multiply on the left."""
    return math.cos(0.5 * angle_rad), 0.0, 0.0, math.sin(0.5 * angle_rad)


@register_jitable
def _tilt_toward(q, dx, dy, dz, k):
    """q tilted so that its down on the body axes, ``v = R(q)ᵀ e_z``, becomes the direction of
    ``v + k (d - v)``: the complementary blend of the module docstring, on the gravity direction. The
    smallest turn that does it (about a horizontal axis), applied on the body side."""
    w, x, y, z = q
    vx, vy, vz = 2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z
    nx, ny, nz = vx + k * (dx - vx), vy + k * (dy - vy), vz + k * (dz - vz)
    # r = q⁻¹ ⊗ q' turns the new down onto the old one: about n × v, by the angle between them
    cx, cy, cz = ny * vz - nz * vy, nz * vx - nx * vz, nx * vy - ny * vx
    s, c = math.sqrt(cx * cx + cy * cy + cz * cz), nx * vx + ny * vy + nz * vz
    if not s > 0.0:
        return q
    half = 0.5 * math.atan2(s, c)
    f = math.sin(half) / s
    r = (math.cos(half), f * cx, f * cy, f * cz)
    return quaternion_product(q, r)


@njit(cache=True)
def mcf_run(state, p, gyr, acc, dt, mag, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
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

    def _initial_state(self):
        dip = self.settings.mag_dip_rad
        return [0.0, dip if dip == dip else 0.0, dip]  # compass_used, dip shown, dip


@register_jitable
def _dip_rad(ax, ay, az, mx, my, mz):
    """Dip of the field below the horizontal: asin of the reading's component along the measured down."""
    dot = -(ax * mx + ay * my + az * mz) / math.sqrt((ax * ax + ay * ay + az * az) * (mx * mx + my * my + mz * mz))
    return math.asin(max(-1.0, min(1.0, dot)))


def crossover_from_spectra(gyro_error, absolute_error, dt_s: float, bands_per_decade: int = 10) -> float:
    """The frequency (Hz) above which the gyro's angle error spectrum stays below the absolute source's.

    Both errors (N,) against the same truth, in the same unit. Their amplitude spectra (mean removed,
    Hann window: ``spectrum``) are averaged over log-spaced bands (``bands_per_decade``) so that
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
