"""Body-axis accelerometer + attitude -> linear acceleration in NED (seed 004: the accelerometer
channel, "rotated to the inertial frame, gravity removed, then integrated").

The accelerometer measures specific force ``f = a - g`` on the body axes (docs/conventions.md: level
at rest it reads (0, 0, -1) g). With the attitude ``q`` (w, x, y, z) rotating body vectors into NED,
``a_ned = R(q) f + (0, 0, g)``: zero at rest, gravity ``g`` = ``units.STANDARD_GRAVITY_M_S2`` down.
"""

from __future__ import annotations

import numpy as np

from groundstation.units import STANDARD_GRAVITY_M_S2


def linear_acc_ned_m_s2(acc_g, q_body_to_ned):
    """NED linear acceleration (m/s², gravity removed) from body specific force (g) and attitude.

    One sample as plain sequences (``acc_g`` 3 floats, ``q_body_to_ned`` 4 floats) returns a tuple of
    3 floats, cheap enough per sample (no numpy); arrays ``(..., 3)`` and ``(..., 4)`` return an
    ``(..., 3)`` array. NaN in either input gives NaN (the filters skip such samples). The rotation is
    ``R(q)`` of ``groundstation.quaternion.to_matrix`` written out.
    """
    scalar = isinstance(acc_g, (tuple, list)) and isinstance(q_body_to_ned, (tuple, list))
    if scalar:
        fx, fy, fz = acc_g
        w, x, y, z = q_body_to_ned
    else:
        fx, fy, fz = np.moveaxis(np.asarray(acc_g, dtype=float), -1, 0)
        w, x, y, z = np.moveaxis(np.asarray(q_body_to_ned, dtype=float), -1, 0)
    g = STANDARD_GRAVITY_M_S2
    north = g * ((1.0 - 2.0 * (y * y + z * z)) * fx + 2.0 * (x * y - w * z) * fy + 2.0 * (x * z + w * y) * fz)
    east = g * (2.0 * (x * y + w * z) * fx + (1.0 - 2.0 * (x * x + z * z)) * fy + 2.0 * (y * z - w * x) * fz)
    down = g * (2.0 * (x * z - w * y) * fx + 2.0 * (y * z + w * x) * fy + (1.0 - 2.0 * (x * x + y * y)) * fz + 1.0)
    if scalar:
        return (north, east, down)
    return np.stack(np.broadcast_arrays(north, east, down), axis=-1)
