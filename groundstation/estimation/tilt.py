"""Scalar helpers for the per-sample filters: Euler angles (cf1, kf), initialisation from gravity, products.

Body axes FRD, earth NED, ZYX Euler angles (docs/conventions.md). Per-sample code, so plain ``math``.
"""

from __future__ import annotations

import math

# cos θ floor in the Euler kinematics: at ±90° pitch yaw and roll rates are undefined (gimbal lock);
# the floor keeps them finite (the per-angle filters are not meant for vertical flight).
_COS_PITCH_MIN = 1e-6


def acc_pitch_roll(ax, ay, az):
    """Pitch θ and roll φ (rad) from the specific force in body axes, any unit.

    At rest the accelerometer reads g·(sin θ, -sin φ cos θ, -cos φ cos θ), hence these two lines.
    """
    return math.atan2(ax, math.sqrt(ay * ay + az * az)), math.atan2(-ay, -az)


def euler_rates(roll_rad, pitch_rad, gx, gy, gz):
    """ZYX Euler angle rates (yaw, pitch, roll) in rad/s from body rates (rad/s)."""
    s, c = math.sin(roll_rad), math.cos(roll_rad)
    cos_pitch = math.cos(pitch_rad)
    if abs(cos_pitch) < _COS_PITCH_MIN:
        cos_pitch = math.copysign(_COS_PITCH_MIN, cos_pitch)
    turn = gy * s + gz * c
    return turn / cos_pitch, gy * c - gz * s, gx + turn * math.sin(pitch_rad) / cos_pitch


def wrap_pi(angle_rad):
    """Angle wrapped into [-π, π)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


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


def quaternion_of(yaw_rad, pitch_rad, roll_rad):
    """``qz(ψ) ⊗ qy(θ) ⊗ qx(φ)`` as a tuple: ``quaternion.from_euler_zyx`` for one sample on plain floats."""
    cy, sy = math.cos(0.5 * yaw_rad), math.sin(0.5 * yaw_rad)
    cp, sp = math.cos(0.5 * pitch_rad), math.sin(0.5 * pitch_rad)
    cr, sr = math.cos(0.5 * roll_rad), math.sin(0.5 * roll_rad)
    return (cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr, cy * sp * cr + sy * cp * sr, sy * cp * cr - cy * sp * sr)


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
