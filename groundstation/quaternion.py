"""Quaternion math shared by the estimators, the simulator and the exports.

Conventions (docs/conventions.md): quaternions are numpy arrays ``[w, x, y, z]`` (scalar first) in the
last axis, so every function takes one quaternion of shape (4,) or a stack of shape (..., 4) and
broadcasts. A unit quaternion ``q`` stands for the rotation that takes body-frame vectors into the
earth frame: ``v_earth = rotate(q, v_body) = q ⊗ [0, v_body] ⊗ q*``; ``to_matrix(q)`` is the same
rotation as a matrix, ``v_earth = R @ v_body``. Angles are radians here; degrees only at the UI and in
exports. Euler angles are ZYX (yaw ψ about z, then pitch θ about the new y, then roll φ about the new
x): ``R = Rz(ψ) Ry(θ) Rx(φ)``.

The estimators' per-sample steps do not call these functions (numpy on four numbers costs microseconds);
they are for setup, batch work, tests and the simulator.
"""

from __future__ import annotations

import numpy as np

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def _asarray(q) -> np.ndarray:
    return np.asarray(q, dtype=float)


def multiply(p, q) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` (apply q first, then p, when both rotate body to earth)."""
    p, q = _asarray(p), _asarray(q)
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def conjugate(q) -> np.ndarray:
    """``q*``: the inverse rotation for a unit quaternion."""
    return _asarray(q) * np.array([1.0, -1.0, -1.0, -1.0])


def normalise(q) -> np.ndarray:
    """Scale to unit norm. Raises ValueError on a zero quaternion rather than returning NaN."""
    q = _asarray(q)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise ValueError("cannot normalise a zero quaternion")
    return q / norm


def rotate(q, v) -> np.ndarray:
    """Rotate 3-vectors ``v`` (shape (..., 3)) by unit quaternions ``q``: ``q ⊗ [0, v] ⊗ q*``."""
    q, v = _asarray(q), _asarray(v)
    w = q[..., :1]
    u = q[..., 1:]
    # Expanded product: v + 2w (u × v) + 2 u × (u × v); cheaper than two Hamilton products.
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def to_matrix(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions, ``v_earth = R @ v_body``."""
    w, x, y, z = np.moveaxis(_asarray(q), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def from_matrix(r) -> np.ndarray:
    """Unit quaternions (w >= 0) from rotation matrices (..., 3, 3).

    Shepperd's method: take the square root of the largest of 1 + trace and 1 + 2 R_ii - trace, so the
    divisor is never small.
    """
    r = _asarray(r)
    trace = r[..., 0, 0] + r[..., 1, 1] + r[..., 2, 2]
    candidates = np.stack(
        [
            np.stack([1 + trace, r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], -1),
            np.stack([r[..., 2, 1] - r[..., 1, 2], 1 + 2 * r[..., 0, 0] - trace, r[..., 0, 1] + r[..., 1, 0], r[..., 0, 2] + r[..., 2, 0]], -1),
            np.stack([r[..., 0, 2] - r[..., 2, 0], r[..., 0, 1] + r[..., 1, 0], 1 + 2 * r[..., 1, 1] - trace, r[..., 1, 2] + r[..., 2, 1]], -1),
            np.stack([r[..., 1, 0] - r[..., 0, 1], r[..., 0, 2] + r[..., 2, 0], r[..., 1, 2] + r[..., 2, 1], 1 + 2 * r[..., 2, 2] - trace], -1),
        ],
        axis=-2,
    )
    # Row i of `candidates` is 4 q_i q and its i-th entry 4 q_i²: use the row whose q_i is largest.
    best = np.argmax(np.diagonal(candidates, axis1=-2, axis2=-1), axis=-1)
    q = np.take_along_axis(candidates, best[..., None, None], axis=-2)[..., 0, :]
    q = normalise(q)
    return np.where(q[..., :1] < 0, -q, q)


def from_euler_zyx(yaw_rad, pitch_rad, roll_rad) -> np.ndarray:
    """Quaternion of ZYX Euler angles: ``q = qz(ψ) ⊗ qy(θ) ⊗ qx(φ)``; inputs broadcast."""
    hy, hp, hr = (np.asarray(a, dtype=float) / 2.0 for a in (yaw_rad, pitch_rad, roll_rad))
    cy, sy, cp, sp, cr, sr = np.cos(hy), np.sin(hy), np.cos(hp), np.sin(hp), np.cos(hr), np.sin(hr)
    return np.stack(
        [
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ],
        axis=-1,
    )


def to_euler_zyx(q) -> np.ndarray:
    """ZYX Euler angles ``[..., (yaw, pitch, roll)]`` in radians of unit quaternions.

    Pitch is in [-π/2, π/2]; at exactly ±90° pitch yaw and roll are not separable and the split
    between them is arbitrary (the rotation is still exact).
    """
    w, x, y, z = np.moveaxis(_asarray(q), -1, 0)
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    pitch = np.arcsin(np.clip(2 * (w * y - x * z), -1.0, 1.0))
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    return np.stack([yaw, pitch, roll], axis=-1)


def euler_deg(q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(yaw, pitch, roll)`` in degrees of ``to_euler_zyx``: the one conversion every view and export
    shows. Yaw in (-180°, 180°] (docs/conventions.md); a compass shows it as ``heading_deg(yaw)``."""
    yaw, pitch, roll = np.moveaxis(np.degrees(to_euler_zyx(q)), -1, 0)
    return yaw, pitch, roll


def heading_deg(yaw_deg):
    """Yaw as a compass reads it: 0..360°, clockwise from north (the same angle as ``euler_deg``'s yaw)."""
    return np.mod(yaw_deg, 360.0)


def from_rotation_vector(rv) -> np.ndarray:
    """Exponential map: rotation vector (axis × angle, rad; shape (..., 3)) to unit quaternion.

    Used to integrate a constant body rate ω over dt exactly: ``q ⊗ from_rotation_vector(ω dt)``.
    """
    rv = _asarray(rv)
    angle = np.linalg.norm(rv, axis=-1, keepdims=True)
    half = angle / 2.0
    # sin(θ/2)/θ, with its Taylor series below 1e-4 rad where the division loses precision.
    small = angle < 1e-4
    safe = np.where(small, 1.0, angle)
    scale = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    return np.concatenate([np.cos(half), rv * scale], axis=-1)


def to_rotation_vector(q) -> np.ndarray:
    """Logarithm map: unit quaternion to rotation vector (rad, angle in [0, π])."""
    q = _asarray(q)
    q = np.where(q[..., :1] < 0, -q, q)
    vec_norm = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(vec_norm, q[..., :1])
    small = vec_norm < 1e-12
    scale = np.where(small, 2.0, angle / np.where(small, 1.0, vec_norm))
    return q[..., 1:] * scale


def angle_between(p, q) -> np.ndarray:
    """Rotation angle (rad, in [0, π]) of ``p* ⊗ q``: how far apart two attitudes are."""
    d = multiply(conjugate(p), q)
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))
