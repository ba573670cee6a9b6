"""Tilt-compensated compass heading (seed 003: heading from the magnetometer with the local field).

The magnetometer reading on the body axes is rotated onto the horizontal plane with the estimated
pitch and roll only (yaw 0), ``m_h = R(0, θ, φ) m_b``; the horizontal field then points magnetic north,
so the craft's heading is ``ψ = atan2(-m_h,y, m_h,x)`` (NED, clockwise from north, the yaw of
docs/conventions.md), plus the local declination for true north.
"""

from __future__ import annotations

import numpy as np

from groundstation import quaternion


def heading_rad(q_body_to_ned, mag_body, declination_rad: float = 0.0) -> np.ndarray:
    """Heading in (-π, π] from attitude quaternions (…, 4) and magnetometer readings (…, 3), any unit.

    Only the pitch and roll of ``q_body_to_ned`` are used. NaN where the reading is NaN.
    """
    _, pitch, roll = np.moveaxis(quaternion.to_euler_zyx(q_body_to_ned), -1, 0)
    level = quaternion.from_euler_zyx(np.zeros_like(pitch), pitch, roll)
    m_h = quaternion.rotate(level, np.asarray(mag_body, dtype=float))
    psi = np.arctan2(-m_h[..., 1], m_h[..., 0]) + declination_rad
    return np.angle(np.exp(1j * psi))
