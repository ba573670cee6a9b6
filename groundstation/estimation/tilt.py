"""Scalar helpers for the per-sample filters: Euler angles (cf1, kf), initialisation from gravity, products,
the magnetometer's earth reference (hfm, ecfm).

Body axes FRD, earth NED, ZYX Euler angles (docs/conventions.md). Per-sample code, so plain ``math``;
``register_jitable``: compiled inside the compiled estimators' kernels (base.py), plain Python elsewhere.
"""

from __future__ import annotations

import math

from numba.extending import register_jitable

# cos θ floor in the Euler kinematics: at ±90° pitch yaw and roll rates are undefined (gimbal lock);
# the floor keeps them finite (the per-angle filters are not meant for vertical flight).
_COS_PITCH_MIN = 1e-6


@register_jitable
def acc_pitch_roll(ax, ay, az):
    """Pitch θ and roll φ (rad) from the specific force in body axes, any unit.

    At rest the accelerometer reads g·(sin θ, -sin φ cos θ, -cos φ cos θ), hence these two lines.
    """
    return math.atan2(ax, math.sqrt(ay * ay + az * az)), math.atan2(-ay, -az)


@register_jitable
def euler_rates(roll_rad, pitch_rad, gx, gy, gz):
    """ZYX Euler angle rates (yaw, pitch, roll) in rad/s from body rates (rad/s)."""
    s, c = math.sin(roll_rad), math.cos(roll_rad)
    cos_pitch = math.cos(pitch_rad)
    if abs(cos_pitch) < _COS_PITCH_MIN:
        cos_pitch = math.copysign(_COS_PITCH_MIN, cos_pitch)
    turn = gy * s + gz * c
    return turn / cos_pitch, gy * c - gz * s, gx + turn * math.sin(pitch_rad) / cos_pitch


@register_jitable
def wrap_pi(angle_rad):
    """Angle wrapped into [-π, π)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


@register_jitable
def euler_of(q):
    """ZYX (yaw, pitch, roll) in rad of a unit quaternion tuple: ``quaternion.to_euler_zyx`` for one
    sample on plain floats (numpy's per-call cost is most of a per-sample filter's time)."""
    w, x, y, z = q
    s = 2.0 * (w * y - x * z)
    return (
        math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)),
        math.asin(1.0 if s > 1.0 else -1.0 if s < -1.0 else s),
        math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
    )


@register_jitable
def quaternion_of(yaw_rad, pitch_rad, roll_rad):
    """``qz(ψ) ⊗ qy(θ) ⊗ qx(φ)`` as a tuple: ``quaternion.from_euler_zyx`` for one sample on plain floats."""
    cy, sy = math.cos(0.5 * yaw_rad), math.sin(0.5 * yaw_rad)
    cp, sp = math.cos(0.5 * pitch_rad), math.sin(0.5 * pitch_rad)
    cr, sr = math.cos(0.5 * roll_rad), math.sin(0.5 * roll_rad)
    return (cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr, cy * sp * cr + sy * cp * sr, sy * cp * cr - cy * sp * sr)


@register_jitable
def quaternion_product(p, q):
    """``p ⊗ q`` (Hamilton, w first) as a tuple: ``quaternion.multiply`` for one sample on plain floats."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (
        pw * qw - px * qx - py * qy - pz * qz,
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
    )


@register_jitable
def unit_field(mx, my, mz):
    """``(usable, m̂)``: the magnetometer reading normalised; not usable (and m̂ zero) when it is missing
    (NaN), infinite or zero."""
    n2 = mx * mx + my * my + mz * mz
    if not (0.0 < n2 and n2 < math.inf):  # NaN fails, Inf and 0 excluded
        return False, 0.0, 0.0, 0.0
    r = n2**-0.5
    return True, mx * r, my * r, mz * r


@register_jitable
def earth_field_reference(q1, q2, q3, q4, mx, my, mz):
    """``b = (bx, 0, bz)``: the measured field m̂ turned into NED by q, its horizontal part onto north
    (Madgwick eq. 45-46): ``h = R(q) m̂``, ``bx = ‖(h_n, h_e)‖``, ``bz = h_d`` (marg.py)."""
    hx = (1.0 - 2.0 * (q3 * q3 + q4 * q4)) * mx + 2.0 * (q2 * q3 - q1 * q4) * my + 2.0 * (q2 * q4 + q1 * q3) * mz
    hy = 2.0 * (q2 * q3 + q1 * q4) * mx + (1.0 - 2.0 * (q2 * q2 + q4 * q4)) * my + 2.0 * (q3 * q4 - q1 * q2) * mz
    hz = 2.0 * (q2 * q4 - q1 * q3) * mx + 2.0 * (q3 * q4 + q1 * q2) * my + (1.0 - 2.0 * (q2 * q2 + q3 * q3)) * mz
    return math.sqrt(hx * hx + hy * hy), hz


@register_jitable
def about_vertical(vx, vy, vz, x, y, z):
    """The part of a body-axes turn rate (x, y, z) about the estimated vertical, the unit (vx, vy, vz) on the
    body axes: a turn about it moves heading only. Every magnetometer correction passes through this (or
    ``about_vertical_q``): the field may correct heading, never pitch and roll (a magnet near the sensor
    would tilt the estimate)."""
    c = vx * x + vy * y + vz * z
    return c * vx, c * vy, c * vz


@register_jitable
def about_vertical_q(q1, q2, q3, q4, s1, s2, s3, s4):
    """``about_vertical`` for a quaternion rate (s1..s4) at q: its part along ``[0, 0, 0, 1] ⊗ q`` (unit), the
    rate of a turn about the NED vertical. (The body rate ``2 q* ⊗ s`` projected onto the body's vertical and
    turned back, ``½ q ⊗ [0, ω]``, is the same vector.)"""
    t1, t2, t3, t4 = -q4, -q3, q2, q1
    c = t1 * s1 + t2 * s2 + t3 * s3 + t4 * s4
    return c * t1, c * t2, c * t3, c * t4
