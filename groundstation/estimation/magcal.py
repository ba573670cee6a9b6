"""Hard- and soft-iron calibration of a magnetometer by a least-squares ellipsoid fit.

A magnetometer turned through many attitudes in a constant field reads points on an ellipsoid: a
sphere of the field strength, distorted by soft iron (a matrix) and shifted by hard iron (an offset).
The general ellipsoid (9 parameters: any centre, any axes and orientation) is fitted algebraically,

    a x² + b y² + c z² + 2f xy + 2g xz + 2h yz + 2p x + 2q y + 2r z = 1       (linear least squares)

so with ``A = [[a, f, g], [f, b, h], [g, h, c]]`` the centre is ``o = -A⁻¹ (p, q, r)`` (the hard iron)
and ``(m - o)ᵀ B (m - o) = 1`` with ``B = A / (1 + oᵀ A o)``. The soft-iron correction is the symmetric
``W = F · B^½``, so that ``‖W (m - o)‖ = F`` on the ellipsoid: readings map to a sphere of radius F. F is
the local field strength when given (µT), otherwise ``det(B)^(-1/6)``, the geometric mean of the semi-axes
(the distortion keeps the sphere's volume). A rotation of W fits equally well and is not observable from
the readings alone; the symmetric W is the one that does not turn the axes.

The readings must cover the sphere in more than one plane: turning about one axis only (a level yaw
turn) puts them on a circle, and the fit raises ``ValueError`` rather than return a guess.
"""

from __future__ import annotations

import dataclasses

import numpy as np

MIN_READINGS = 9  # unknowns of the general ellipsoid
# Spread of the readings across their flattest direction, relative to the widest: below it they lie
# near a plane (one-axis turning) and the ellipsoid's third axis is noise.
MIN_THICKNESS = 0.05


@dataclasses.dataclass(frozen=True)
class MagCalibration:
    offset_ut: np.ndarray  # (3,) hard iron, µT, on the readings' axes
    soft_iron: np.ndarray  # (3, 3) symmetric, maps ``reading - offset`` onto the sphere of ``field_ut``
    field_ut: float  # radius of that sphere, µT

    def apply(self, mag_ut) -> np.ndarray:
        """Corrected readings ``W (m - o)`` for readings (…, 3) in µT; NaN rows stay NaN."""
        return (np.asarray(mag_ut, dtype=float) - self.offset_ut) @ self.soft_iron.T


def fit(mag_ut, field_ut: float | None = None) -> MagCalibration:
    """Ellipsoid fit to readings (N, 3) in µT (rows with NaN are skipped; see the module docstring)."""
    m = np.asarray(mag_ut, dtype=float).reshape(-1, 3)
    m = m[np.isfinite(m).all(axis=1)]
    if len(m) < MIN_READINGS:
        raise ValueError(f"magnetometer calibration needs at least {MIN_READINGS} finite readings, got {len(m)}")
    centre = m.mean(axis=0)
    scale = np.sqrt(((m - centre) ** 2).sum(axis=1).mean())  # conditioning: fit in units of the spread
    spread = np.linalg.svd((m - centre) / max(scale, 1e-300), compute_uv=False) / np.sqrt(len(m))
    if not scale > 0 or spread[2] < MIN_THICKNESS * spread[0]:
        raise ValueError(
            "magnetometer readings lie near a plane (or a point): turn the craft about more than one axis "
            f"(thickness {spread[2] / max(spread[0], 1e-300):.3f} of the width, need {MIN_THICKNESS})"
        )
    x, y, z = ((m - centre) / scale).T
    design = np.column_stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, 2 * x, 2 * y, 2 * z])
    v, *_ = np.linalg.lstsq(design, np.ones(len(m)), rcond=None)
    a = np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])
    o = -np.linalg.solve(a, v[6:])
    b = a / (1.0 + o @ a @ o)
    eigval, eigvec = np.linalg.eigh(b)
    if not eigval.min() > 0:
        raise ValueError("magnetometer readings do not fit an ellipsoid (a hyperboloid fits better): check the data")
    # back to µT: the fit was on (m - centre) / scale
    eigval = eigval / scale**2
    radius = float(np.prod(eigval) ** (-1.0 / 6.0)) if field_ut is None else float(field_ut)
    soft_iron = radius * (eigvec * np.sqrt(eigval)) @ eigvec.T
    return MagCalibration(offset_ut=centre + scale * o, soft_iron=soft_iron, field_ut=radius)
