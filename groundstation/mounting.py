"""How the MPU-6050 sits on the airframe: the 24 axis-aligned mountings, numbered 0-23.

A mounting is the rotation matrix ``M`` with ``v_body = M @ v_sensor``: it takes a vector measured
on the sensor's x, y, z axes into the body frame (x forward, y right, z down; docs/conventions.md).
Each mounting is named by which signed sensor axis points forward and which points right; the
down axis follows (forward × right). The index is what the protocol's CONFIG frame carries (uint8).

Numbering (fixed; never reorder, recordings store it): the forward axis runs through
``+x, -x, +y, -y, +z, -z``; for each, the right axis runs through the same list, skipping the two
axes parallel to forward. So index 0 is ``+x forward, +y right`` (sensor axes already FRD) and
index 1 is ``+x forward, -y right``.

Default: index 1 (``DEFAULT_MOUNTING``): the breakout board flat, components up, with its x arrow
toward the nose. The MPU-6050's axes are then x forward, y left, z up, which is how nearly every
quadrotor flight board carries it; the body frame is the sensor's turned upside down about x.
"""

from __future__ import annotations

import numpy as np

_AXES = ("+x", "-x", "+y", "-y", "+z", "-z")


def _unit(axis: str) -> np.ndarray:
    v = np.zeros(3)
    v["xyz".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
    return v


def _build() -> tuple[tuple[str, str], ...]:
    names = []
    for forward in _AXES:
        for right in _AXES:
            if right[1] != forward[1]:
                names.append((forward, right))
    return tuple(names)


# MOUNTING_NAMES[i] = (sensor axis pointing forward, sensor axis pointing right).
MOUNTING_NAMES: tuple[tuple[str, str], ...] = _build()
MOUNTING_MATRICES: tuple[np.ndarray, ...] = tuple(
    # Rows are the body axes written in sensor coordinates: body_i = row_i · v_sensor.
    np.array([_unit(f), _unit(r), np.cross(_unit(f), _unit(r))]) for f, r in MOUNTING_NAMES
)
for _m in MOUNTING_MATRICES:
    _m.setflags(write=False)

DEFAULT_MOUNTING = 1


def matrix(index: int) -> np.ndarray:
    """The rotation ``M`` (3×3, read-only) of mounting ``index``: ``v_body = M @ v_sensor``."""
    if not isinstance(index, (int, np.integer)) or not 0 <= index < len(MOUNTING_MATRICES):
        raise ValueError(f"mounting index must be an integer 0-23, not {index!r}")
    return MOUNTING_MATRICES[int(index)]


def index_of(m) -> int:
    """The index of an axis-aligned rotation matrix; ValueError if it is not one of the 24."""
    m = np.asarray(m, dtype=float)
    for i, candidate in enumerate(MOUNTING_MATRICES):
        if np.allclose(m, candidate, atol=1e-9):
            return i
    raise ValueError("not one of the 24 axis-aligned mountings")


def describe(index: int) -> str:
    matrix(index)  # validates the index
    forward, right = MOUNTING_NAMES[index]
    return f"sensor {forward} forward, {right} right"


def sensor_to_body(v_sensor, index: int = DEFAULT_MOUNTING) -> np.ndarray:
    """Vectors (shape (3,) or (N, 3)) on the sensor's axes, expressed on the body axes."""
    return np.asarray(v_sensor, dtype=float) @ matrix(index).T


def body_to_sensor(v_body, index: int = DEFAULT_MOUNTING) -> np.ndarray:
    """The inverse of ``sensor_to_body`` (the simulator uses it to make sensor readings)."""
    return np.asarray(v_body, dtype=float) @ matrix(index)
