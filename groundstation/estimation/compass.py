"""The electronic compass of seed 003: heading from the magnetometer given the tilt, and tilt given the heading.

Heading (seed 003 eq. 13-15): the magnetometer reading on the body axes is rotated onto the horizontal
plane with the estimated pitch and roll only (yaw 0), ``m_h = R(0, θ, φ) m_b``; the horizontal field then
points magnetic north, so the craft's heading is ``ψ = atan2(-m_h,y, m_h,x)`` (NED, clockwise from north,
the yaw of docs/conventions.md), plus the local declination for true north.

Tilt (the compass as a third pitch/roll source, ``mcf``): with the heading known and the local field's
direction in the magnetic-north frame, ``m̂_n = (cos δ, 0, sin δ)`` (δ the dip, positive down), eq. 13
``m_d = Rz(ψ)ᵀ m̂_n`` is known and ``Ry(θ) Rx(φ) m̂_b = m_d`` is solved for φ then θ (two roll solutions;
the one nearest a hint is taken).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import register_jitable

from groundstation import quaternion
from groundstation.estimation.tilt import wrap_pi


def heading_rad(q_body_to_ned, mag_body, declination_rad: float = 0.0) -> np.ndarray:
    """Heading in [-π, π) from attitude quaternions (…, 4) and magnetometer readings (…, 3), any unit.

    Only the pitch and roll of ``q_body_to_ned`` are used. NaN where the reading is NaN.
    """
    _, pitch, roll = np.moveaxis(quaternion.to_euler_zyx(q_body_to_ned), -1, 0)
    mag = np.asarray(mag_body, dtype=float)
    psi = _level_heading_rad_each(pitch, roll, mag[..., 0], mag[..., 1], mag[..., 2]) + declination_rad
    return wrap_pi(psi)


def reading_heading_rad(q_body_to_ned, mag_body) -> float:
    """``heading_rad`` of one reading in plain floats, for per-sample code (a few µs, not a numpy call's 100).

    The same eq. 14-15, written through the whole rotation: ``m_h = Rz(ψ)ᵀ R(q) m_b``, so the heading
    is the attitude's yaw ψ minus the direction of the field turned into NED, ``atan2(m_n,y, m_n,x)``.
    """
    return math.remainder(_unwrapped_heading_rad(q_body_to_ned, mag_body), 2 * math.pi)


def reading_headings_deg(q_rows: np.ndarray, mag_rows: np.ndarray) -> np.ndarray:
    """``reading_heading_rad`` in degrees of each row of ``q_rows`` (n, 4) and ``mag_rows`` (n, 3): the
    same floats, the rotation compiled (numba has no ``math.remainder``: that and the degrees per row)."""
    unwrapped = np.empty(len(q_rows))
    _unwrapped_each(np.ascontiguousarray(q_rows, dtype=float), np.ascontiguousarray(mag_rows, dtype=float), unwrapped)
    return np.array([math.degrees(math.remainder(u, 2 * math.pi)) for u in unwrapped.tolist()])


@register_jitable
def _unwrapped_heading_rad(q_body_to_ned, mag_body):
    """``reading_heading_rad`` before its wrap into [-π, π]."""
    w, x, y, z = q_body_to_ned[0], q_body_to_ned[1], q_body_to_ned[2], q_body_to_ned[3]
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return yaw + heading_offset_rad(w, x, y, z, mag_body[0], mag_body[1], mag_body[2])


@register_jitable  # also compiled: mcf's kernel
def heading_offset_rad(w, x, y, z, mx, my, mz):
    """The compass heading minus the attitude's yaw (unwrapped): the turn about the vertical that points the
    reading's horizontal part, turned into NED by the attitude, north. Defined at any tilt (no Euler angle
    is taken: at ±90° pitch yaw is not, but this turn still is), any unit for the reading."""
    north = (1 - 2 * (y * y + z * z)) * mx + 2 * (x * y - w * z) * my + 2 * (x * z + w * y) * mz
    east = 2 * (x * y + w * z) * mx + (1 - 2 * (x * x + z * z)) * my + 2 * (y * z - w * x) * mz
    return -math.atan2(east, north)


@njit(cache=True)
def _unwrapped_each(q_rows, mag_rows, out):  # pragma: no cover - compiled (tests compare it with reading_heading_rad)
    for k in range(len(q_rows)):
        out[k] = _unwrapped_heading_rad(q_rows[k], mag_rows[k])


@register_jitable  # also compiled: the compiled MARG filters' yaw on initialising (base.py)
def level_heading_rad(pitch_rad, roll_rad, mx, my, mz):
    """Magnetic heading ψ = atan2(-m_h,y, m_h,x) with ``m_h = Ry(θ) Rx(φ) m_b`` (eq. 14-15), one reading.

    ``math``, not NumPy: compiled, numba calls libm for either; interpreted, NumPy's ``arctan2`` takes its
    own SIMD code on some CPUs (AVX-512), 1 ulp from libm on ~7 % of inputs, and hfm's normalised
    gradient step turns that ulp at initialisation into a β·dt step (tests/estimation/test_kernels.py).
    """
    sp, cp, sr, cr = math.sin(pitch_rad), math.cos(pitch_rad), math.sin(roll_rad), math.cos(roll_rad)
    m_hx = cp * mx + sp * (sr * my + cr * mz)
    m_hy = cr * my - sr * mz
    return math.atan2(-m_hy, m_hx)


_level_heading_rad_each = np.vectorize(level_heading_rad, otypes=[float])  # arrays: the same rule per element


def tilt_from_field_rad(mx, my, mz, heading_rad_: float, dip_rad: float, roll_hint_rad: float):
    """Pitch and roll (rad) that turn the reading ``m_b`` onto the field at ``heading_rad_`` (module docstring).

    Scalars (per-sample code); any unit for ``m_b``. None when the reading's direction cannot match the
    field at that heading (its east component exceeds what rolling can give) or is zero.
    """
    found, pitch, roll = field_tilt_rad(mx, my, mz, heading_rad_, dip_rad, roll_hint_rad)
    return (pitch, roll) if found else None


@register_jitable  # also compiled: mcf's kernel
def field_tilt_rad(mx, my, mz, heading_rad_, dip_rad, roll_hint_rad):
    """``tilt_from_field_rad`` as ``(found, pitch, roll)``, (False, 0, 0) for None."""
    n = math.sqrt(mx * mx + my * my + mz * mz)
    if not n > 0.0:
        return False, 0.0, 0.0
    mx, my, mz = mx / n, my / n, mz / n
    cd = math.cos(dip_rad)
    dx, dy, dz = math.cos(heading_rad_) * cd, -math.sin(heading_rad_) * cd, math.sin(dip_rad)  # eq. 13
    rho = math.hypot(my, mz)
    if not abs(dy) <= rho:
        return False, 0.0, 0.0
    # (Rx(φ) m)_y = cos φ m_y - sin φ m_z = ρ cos(φ + α) = d_y: two rolls, the one nearer the hint
    alpha = math.atan2(mz, my)
    spread = math.acos(dy / rho)
    roll = spread - alpha
    other = -spread - alpha
    if abs(wrap_pi(other - roll_hint_rad)) < abs(wrap_pi(roll - roll_hint_rad)):
        roll = other
    ux, uz = mx, math.sin(roll) * my + math.cos(roll) * mz
    # Ry(θ) turns (u_x, u_z) by -θ in the x-z plane onto (d_x, d_z)
    pitch = math.atan2(uz * dx - ux * dz, ux * dx + uz * dz)
    return True, pitch, wrap_pi(roll)
