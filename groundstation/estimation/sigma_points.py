"""Sigma-point sets and the unscented Kalman filter's two steps, dense and square-root (seed 001 §2).

State ``x`` (n,), covariance ``P = S Sᵀ`` with ``S`` lower triangular; sigma points ``χ = x + S Z``,
``Z`` the unit set (n, L) of a ``SigmaSet`` with mean weights ``wm`` and covariance weights ``wc``.
The noises are additive, so the state is not augmented with them (seed 001 §2.2, "additive
non-augmented form"): the time update adds ``Q``, the measurement update ``R``.

Sets:

- ``symmetric``: Julier's scaled unscented transform (seed 001 ref. [8]), 2n + 1 points
  ``Z = [0, γ I, -γ I]``, ``γ = √(n + λ)``, ``λ = α² (n + κ) - n``; ``wm0 = λ / (n + λ)``,
  ``wc0 = wm0 + 1 - α² + β``, ``wi = 1 / (2 (n + λ))``.
- ``spherical_simplex``: seed 001 §2.1 steps 1-6 (Julier's spherical simplex), n + 2 points:
  choose ``0 <= W0 < 1``; ``Wi = (1 - W0) / (n + 1)``; the 1-D sequence ``[0, -1/√(2 W1), 1/√(2 W1)]``
  grown one dimension j = 2..n at a time: the old points get a new coordinate ``-1/√(j (j+1) W1)``,
  the new point ``j/√(j (j+1) W1)`` (and zeros before), the centre 0; then the scaling correction of
  ref. [8]: ``Z -> α Z``, ``W0 -> W0/α² + 1 - 1/α²``, ``Wi -> Wi/α²``, ``wc0 = wm0 + 1 - α² + β``.

Steps (van der Merwe and Wan's square-root UKF with additive noise, which seed 001 §2.2 follows):

- dense: ``P⁻ = Σ wc (χᵢ - x⁻)(χᵢ - x⁻)ᵀ + Q``; ``Pyy = Σ wc (Yᵢ - ŷ)(Yᵢ - ŷ)ᵀ + R``,
  ``Pxy = Σ wc (χᵢ - x⁻)(Yᵢ - ŷ)ᵀ``, ``K = Pxy Pyy⁻¹``, ``x = x⁻ + K (y - ŷ)``, ``P = P⁻ - K Pyy Kᵀ``.
- square root: ``S⁻ = qr([√wc₁..(χ₁.. - x⁻), √Q])`` then a rank-1 ``cholupdate`` with ``χ₀ - x⁻``
  (weight wc0); ``Sy`` likewise with ``√R``; ``K = (Pxy / Syᵀ) / Sy``; ``S = cholupdate(S⁻, K Sy, -1)``
  column by column. The factor is carried instead of P, never re-factorised.

Measurements here are angles (rad): sigma-point outputs are unwrapped around the centre point's and
the innovation wrapped into [-π, π).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class SigmaSet(NamedTuple):
    z: np.ndarray  # (n, L) unit sigma points: χ = x + S z
    wm: np.ndarray  # (L,) mean weights, sum 1
    wc: np.ndarray  # (L,) covariance weights; wc[1:] >= 0
    sqrt_wc: np.ndarray  # (L - 1,) √wc[1:], precomputed for the square-root steps


def _scaled(z, w0, wi, alpha, beta) -> SigmaSet:
    """The scaling correction of seed 001 ref. [8] applied to a unit set with weights w0, wi (i >= 1)."""
    wm = np.full(z.shape[1], wi / alpha**2)
    wm[0] = w0 / alpha**2 + 1.0 - 1.0 / alpha**2
    wc = wm.copy()
    wc[0] += 1.0 - alpha**2 + beta
    if wi <= 0.0:
        raise ValueError("sigma-point weights of the outer points must be positive")
    return SigmaSet(alpha * z, wm, wc, np.sqrt(wc[1:]))


def symmetric(n: int, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0) -> SigmaSet:
    """2n + 1 points, ``±√(n + λ)`` along each axis (the standard UKF's set)."""
    lam = alpha**2 * (n + kappa) - n
    if not n + lam > 0.0:
        raise ValueError(f"need n + λ > 0, got {n + lam}")
    gamma = math.sqrt(n + lam)
    z = np.hstack([np.zeros((n, 1)), gamma * np.eye(n), -gamma * np.eye(n)])
    # Built unscaled (α folded into λ), so the scaling below is the identity: α = 1.
    return _scaled(z, lam / (n + lam), 0.5 / (n + lam), 1.0, beta + 1.0 - alpha**2)


def spherical_simplex(n: int, w0: float = 0.0, alpha: float = 1.0, beta: float = 2.0) -> SigmaSet:
    """n + 2 points on a hypersphere around the centre (seed 001 §2.1, steps 1-6)."""
    if not 0.0 <= w0 < 1.0:
        raise ValueError(f"need 0 <= W0 < 1, got {w0}")
    w1 = (1.0 - w0) / (n + 1)  # step 2
    z = np.zeros((n, n + 2))
    z[0, 1], z[0, 2] = -1.0 / math.sqrt(2.0 * w1), 1.0 / math.sqrt(2.0 * w1)  # step 4: j = 1
    for j in range(2, n + 1):  # step 5
        c = 1.0 / math.sqrt(j * (j + 1) * w1)
        z[j - 1, 1 : j + 1] = -c
        z[j - 1, j + 1] = j * c
    return _scaled(z, w0, w1, alpha, beta)  # steps 3 and 6


def points(x: np.ndarray, s: np.ndarray, sigma: SigmaSet) -> np.ndarray:
    """Sigma points (n, L) around ``x`` with covariance factor ``s``."""
    return x[:, None] + s @ sigma.z


def cholupdate(s: np.ndarray, v: np.ndarray, weight: float = 1.0) -> np.ndarray:
    """Lower-triangular ``S'`` with ``S' S'ᵀ = S Sᵀ + weight v vᵀ`` (a downdate for weight < 0).

    The classic rank-1 Cholesky modification, column by column; raises ``np.linalg.LinAlgError`` when a
    downdate would leave the matrix indefinite. Plain floats: n is 4 here.
    """
    n = len(v)
    sign = 1.0 if weight >= 0.0 else -1.0
    a = s.tolist()
    x = (v * math.sqrt(abs(weight))).tolist()
    for k in range(n):
        akk = a[k][k]
        r2 = akk * akk + sign * x[k] * x[k]
        if not r2 > 0.0:
            raise np.linalg.LinAlgError("Cholesky downdate lost positive definiteness")
        r = math.sqrt(r2)
        c, t = r / akk, x[k] / akk
        a[k][k] = r
        for i in range(k + 1, n):
            a[i][k] = (a[i][k] + sign * t * x[i]) / c
            x[i] = c * x[i] - t * a[i][k]
    return np.array(a)


def _tria(a: np.ndarray) -> np.ndarray:
    """Lower-triangular ``S`` with ``S Sᵀ = A Aᵀ`` from a QR of ``Aᵀ`` (diagonal made positive)."""
    r = np.linalg.qr(a.T, mode="r")
    signs = np.where(np.diagonal(r) < 0.0, -1.0, 1.0)
    return (r * signs[:, None]).T


def _wrap(angle_rad):
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def _spread(values: np.ndarray, sigma: SigmaSet) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean and deviations of propagated points (rows, L columns)."""
    mean = values @ sigma.wm
    return mean, values - mean[:, None]


def _angles(y_sigma: np.ndarray) -> np.ndarray:
    """Angle outputs unwrapped around the centre point's."""
    return y_sigma[:, :1] + _wrap(y_sigma - y_sigma[:, :1])


def time_update(chi_f: np.ndarray, sigma: SigmaSet, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dense: propagated points ``f(χ)`` and process noise ``Q`` -> ``(x⁻, P⁻)``."""
    x, d = _spread(chi_f, sigma)
    return x, (d * sigma.wc) @ d.T + q


def sqrt_time_update(chi_f: np.ndarray, sigma: SigmaSet, sqrt_q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Square root: propagated points and a factor of Q -> ``(x⁻, S⁻)`` by QR and one cholupdate."""
    x, d = _spread(chi_f, sigma)
    s = _tria(np.hstack([d[:, 1:] * sigma.sqrt_wc, sqrt_q]))
    return x, cholupdate(s, d[:, 0], sigma.wc[0])


def measurement_update(x, p, chi, y_sigma, y, r, sigma: SigmaSet):
    """Dense: prior ``(x, P)``, its points ``χ``, their angle outputs ``h(χ)`` (m, L), the measured
    angles ``y`` and noise ``R`` -> ``(x, P, innovation)``."""
    y_hat, dy = _spread(_angles(y_sigma), sigma)
    dx = chi - x[:, None]
    p_yy = (dy * sigma.wc) @ dy.T + r
    p_xy = (dx * sigma.wc) @ dy.T
    k = np.linalg.solve(p_yy, p_xy.T).T  # Pyy is symmetric
    innovation = _wrap(y - y_hat)
    return x + k @ innovation, p - k @ p_yy @ k.T, innovation


def sqrt_measurement_update(x, s, chi, y_sigma, y, sqrt_r, sigma: SigmaSet):
    """Square root: as ``measurement_update`` with factors ``S`` and ``√R`` -> ``(x, S, innovation)``."""
    y_hat, dy = _spread(_angles(y_sigma), sigma)
    dx = chi - x[:, None]
    s_y = cholupdate(_tria(np.hstack([dy[:, 1:] * sigma.sqrt_wc, sqrt_r])), dy[:, 0], sigma.wc[0])
    p_xy = (dx * sigma.wc) @ dy.T
    k = np.linalg.solve(s_y.T, np.linalg.solve(s_y, p_xy.T)).T  # Pxy (Sy Syᵀ)⁻¹
    innovation = _wrap(y - y_hat)
    for column in (k @ s_y).T:
        s = cholupdate(s, column, -1.0)
    return x + k @ innovation, s, innovation
