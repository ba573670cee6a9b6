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
  ``Pxy = Σ wc (χᵢ - x⁻)(Yᵢ - ŷ)ᵀ``, ``K = Pxy Pyy⁻¹``, ``x = x⁻ + K (y - ŷ)``, ``P = P⁻ - K Pyy Kᵀ`` (as ``P⁻ - K Pxyᵀ``).
- square root: ``S⁻ = qr([√wc₁..(χ₁.. - x⁻), √Q])`` then a rank-1 ``cholupdate`` with ``χ₀ - x⁻``
  (weight wc0); ``Sy`` likewise with ``√R``; ``K = (Pxy / Syᵀ) / Sy``; ``S = cholupdate(S⁻, K Sy, -1)``
  column by column. The factor is carried instead of P, never re-factorised.

Measurements here are angles (rad): sigma-point outputs are unwrapped around the centre point's and
the innovation wrapped into [-π, π).

Both kinds of step run on plain Python floats (``small_linalg``): on n = 4 numpy's per-call overhead
(``qr`` ~20-50 µs) hid the operation counts. ``*_lists`` take points as a list of L points (sequences
of n floats), angle outputs as m rows of L and matrices as lists of rows; the functions of the same
name without the suffix wrap them for numpy arrays (points and outputs as (n, L) and (m, L) columns).
Both sets are treated alike: ``χ = x + S z`` skips the zero entries of each set's z.
"""

from __future__ import annotations

import math
from operator import mul
from typing import NamedTuple

import numpy as np

from groundstation.estimation import small_linalg as sl


class SigmaSet(NamedTuple):
    z: np.ndarray  # (n, L) unit sigma points: χ = x + S z
    wm: np.ndarray  # (L,) mean weights, sum 1
    wc: np.ndarray  # (L,) covariance weights; wc[1:] >= 0
    sqrt_wc: np.ndarray  # (L - 1,) √wc[1:], precomputed for the square-root steps
    nonzeros: tuple  # per point, the (row, value) pairs of its nonzero z entries
    floats: tuple  # (wm, wc, sqrt_wc) as lists of Python floats


def _scaled(z, w0, wi, alpha, beta) -> SigmaSet:
    """The scaling correction of seed 001 ref. [8] applied to a unit set with weights w0, wi (i >= 1)."""
    wm = np.full(z.shape[1], wi / alpha**2)
    wm[0] = w0 / alpha**2 + 1.0 - 1.0 / alpha**2
    wc = wm.copy()
    wc[0] += 1.0 - alpha**2 + beta
    if wi <= 0.0:
        raise ValueError("sigma-point weights of the outer points must be positive")
    z = alpha * z
    nonzeros = tuple(tuple((j, v) for j, v in enumerate(col) if v != 0.0) for col in z.T.tolist())
    return SigmaSet(z, wm, wc, np.sqrt(wc[1:]), nonzeros, (wm.tolist(), wc.tolist(), np.sqrt(wc[1:]).tolist()))


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



def _wrap(angle_rad):
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def points_lists(x, s, sigma: SigmaSet):
    """Sigma points ``x + S z`` (L tuples of n) around ``x`` with covariance factor ``s`` (rows).
    Component by component, over S's rows: fewer, longer loops than point by point (half the time
    for n = 4), the same sums in the same order."""
    rows = []
    for x_k, s_k in zip(x, s):
        row = []
        for nonzeros in sigma.nonzeros:
            p = x_k
            for j, v in nonzeros:
                p = p + v * s_k[j]
            row.append(p)
        rows.append(row)
    return list(zip(*rows))


def _spread(rows, wm):
    """Weighted mean and deviation rows of component rows (n rows of L values)."""
    mean = [sum(map(mul, wm, r)) for r in rows]
    return mean, [[v - m for v in r] for r, m in zip(rows, mean)]


def _weighted(rows, w):
    return [list(map(mul, w, r)) for r in rows]


def _outer(a, b, symmetric=False):
    """``Σᵢ aᵢ bᵢᵀ`` of component rows (each L values); symmetric: the lower triangle, mirrored."""
    if not symmetric:
        return [[sum(map(mul, ra, rb)) for rb in b] for ra in a]
    lower = [[sum(map(mul, ra, rb)) for rb in b[: i + 1]] for i, ra in enumerate(a)]
    for i in range(len(lower) - 1):
        lower[i] += [lower[j][i] for j in range(i + 1, len(lower))]
    return lower


def _add(a, b):
    return [[p + q for p, q in zip(ra, rb)] for ra, rb in zip(a, b)]


def _compound(d, sigma: SigmaSet, sqrt_noise):
    """Factor of ``Σ wc dᵢ dᵢᵀ + N`` from deviation rows and ``√N``: QR of [√wc d₁.., √N], cholupdate d₀."""
    _, wc, sqrt_wc = sigma.floats
    rows = [list(map(mul, sqrt_wc, r[1:])) + list(n_row) for r, n_row in zip(d, sqrt_noise)]
    return sl.cholupdate(sl.tria(rows), [r[0] for r in d], wc[0])


def time_update_lists(chi_f, sigma: SigmaSet, q):
    """Dense: propagated points ``f(χ)`` (L lists) and process noise ``Q`` -> ``(x⁻, P⁻)``."""
    x, d = _spread(list(zip(*chi_f)), sigma.floats[0])
    return x, _add(_outer(_weighted(d, sigma.floats[1]), d, True), q)


def sqrt_time_update_lists(chi_f, sigma: SigmaSet, sqrt_q):
    """Square root: propagated points and a factor of Q -> ``(x⁻, S⁻)`` by QR and one cholupdate."""
    x, d = _spread(list(zip(*chi_f)), sigma.floats[0])
    return x, _compound(d, sigma, sqrt_q)


def _output_spread(x, chi, y_sigma, y, sigma):
    """``(dy, dx, innovation)`` as rows, of angle output rows ``h(χ)`` unwrapped around the centre's."""
    pi, tau = math.pi, 2.0 * math.pi
    rows = [r if max(r) - min(r) < pi else [r0 + ((v - r0 + pi) % tau - pi) for v in r] for r in y_sigma for r0 in r[:1]]
    y_hat, dy = _spread(rows, sigma.floats[0])
    dx = [[v - c for v in r] for r, c in zip(zip(*chi), x)]
    return dy, dx, [_wrap(a - b) for a, b in zip(y, y_hat)]


def measurement_update_lists(x, p, chi, y_sigma, y, r, sigma: SigmaSet):
    """Dense: prior ``(x, P)``, its points ``χ``, their angle outputs ``h(χ)`` (m rows of L), the
    measured angles ``y`` and noise ``R`` -> ``(x, P, innovation)``."""
    dy, dx, innovation = _output_spread(x, chi, y_sigma, y, sigma)
    w_dy = _weighted(dy, sigma.floats[1])
    p_yy = _add(_outer(w_dy, dy, True), r)
    p_xy = _outer(dx, w_dy)
    k = sl.solve_right(sl.cholesky(p_yy), p_xy)  # Pxy Pyy⁻¹
    p = [[a - c for a, c in zip(pr, kr)] for pr, kr in zip(p, _outer(k, p_xy, True))]  # P - K Pyy Kᵀ = P - K Pxyᵀ
    return [a + sum(map(mul, kr, innovation)) for a, kr in zip(x, k)], p, innovation


def sqrt_measurement_update_lists(x, s, chi, y_sigma, y, sqrt_r, sigma: SigmaSet):
    """Square root: as ``measurement_update_lists`` with factors ``S`` and ``√R`` -> ``(x, S, innovation)``."""
    dy, dx, innovation = _output_spread(x, chi, y_sigma, y, sigma)
    s_y = _compound(dy, sigma, sqrt_r)
    k = sl.solve_right(s_y, _outer(dx, _weighted(dy, sigma.floats[1])))  # Pxy (Sy Syᵀ)⁻¹
    for column in zip(*s_y):
        s = sl.cholupdate(s, [sum(map(mul, kr, column)) for kr in k], -1.0)  # columns of K Sy
    return [a + sum(map(mul, kr, innovation)) for a, kr in zip(x, k)], s, innovation


# numpy-array forms (points as (n, L) columns, y_sigma (m, L)), as the tests and notebooks use them.


def _cols(a):
    return np.asarray(a, dtype=float).T.tolist()


def _rows(a):
    return np.asarray(a, dtype=float).tolist()


def points(x, s, sigma: SigmaSet) -> np.ndarray:
    """Sigma points (n, L) around ``x`` with covariance factor ``s``."""
    return np.array(points_lists(_rows(x), _rows(s), sigma)).T


def cholupdate(s, v, weight: float = 1.0) -> np.ndarray:
    """``small_linalg.cholupdate`` on arrays."""
    return np.array(sl.cholupdate(_rows(s), _rows(v), weight))


def time_update(chi_f, sigma: SigmaSet, q):
    return tuple(map(np.array, time_update_lists(_cols(chi_f), sigma, _rows(q))))


def sqrt_time_update(chi_f, sigma: SigmaSet, sqrt_q):
    return tuple(map(np.array, sqrt_time_update_lists(_cols(chi_f), sigma, _rows(sqrt_q))))


def measurement_update(x, p, chi, y_sigma, y, r, sigma: SigmaSet):
    args = _rows(x), _rows(p), _cols(chi), _rows(y_sigma), _rows(y), _rows(r)
    return tuple(map(np.array, measurement_update_lists(*args, sigma)))


def sqrt_measurement_update(x, s, chi, y_sigma, y, sqrt_r, sigma: SigmaSet):
    args = _rows(x), _rows(s), _cols(chi), _rows(y_sigma), _rows(y), _rows(sqrt_r)
    return tuple(map(np.array, sqrt_measurement_update_lists(*args, sigma)))
