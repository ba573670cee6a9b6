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

Measurements: the first ``linear_rows`` outputs are plain numbers (ukf's gravity direction), the rest
angles (rad): an angle row's sigma-point outputs are unwrapped around the centre point's and its
innovation wrapped into [-π, π); a linear row is taken as it is (wrapping a gravity component of up to
±4 g under vibration would fold it).

The steps are ``register_jitable`` (``small_linalg``): compiled into the ukf kernel (ukf.py), plain
Python on numpy arrays elsewhere; on n = 4 LAPACK's per-call cost (``qr`` ~20-50 µs) would hide the
operation counts. Points are rows ``chi`` (L, n), outputs rows (m, L), noises their diagonals (the
filters' Q and R are diagonal). A failed factorisation is ``ok`` False (a kernel cannot catch
``LinAlgError``). Both sets are treated alike: ``χ = x + S z`` skips the zero entries of each set's z.
Each step takes an optional ``work``, a flat float array of ``work_size`` floats that holds its
intermediate matrices and its results (views of it, valid until ``work`` is used again): the kernel
passes a part of its state, so a sample allocates nothing; without it a new one is allocated.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba.extending import register_jitable

from groundstation.estimation import small_linalg as sl
from groundstation.estimation.tilt import wrap_pi


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
    return SigmaSet(np.ascontiguousarray(alpha * z), wm, wc, np.sqrt(wc[1:]))


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


@register_jitable
def work_size(n, count, m):
    """Floats of ``work`` that any step below needs for n states, ``count`` points and m <= n outputs."""
    time = 2 * n + n * count + n * (count - 1 + n) + n * n
    measurement = 4 * m + m * count + n * count + m * (count - 1 + m) + 2 * m * m + 2 * n * m + 2 * n + n * n
    return max(time, measurement)


@register_jitable
def _work(work, size):
    """The caller's work space (a flat float array), or a new one."""
    if work is None:
        work = np.empty(size)
    return work


@register_jitable
def _take(work, offset, rows, cols):
    """A (rows, cols) view of ``work`` at ``offset``, and the offset after it."""
    return sl.matrix_view(work, offset, rows, cols), offset + rows * cols


@register_jitable
def points(x, s, z, chi=None):
    """Sigma points ``x + S z`` (L, n) around ``x`` with covariance factor ``s`` (into ``chi`` when given);
    each sum over the set's nonzero z entries in row order."""
    n, count = z.shape
    if chi is None:
        chi = np.empty((count, n))
    for k in range(n):
        for point in range(count):
            p = x[k]
            for j in range(n):
                v = z[j, point]
                if v != 0.0:
                    p = p + v * s[k, j]
            chi[point, k] = p
    return chi


@register_jitable
def _spread(values, wm, by_rows, mean, d):
    """Weighted mean (m,) and deviations (m, L) of rows (m, L), or of points (L, m) unless ``by_rows``;
    ``d`` may be ``values`` (rows)."""
    count, m = (values.shape[1], values.shape[0]) if by_rows else (values.shape[0], values.shape[1])
    for i in range(m):
        acc = 0.0
        for point in range(count):
            acc += wm[point] * (values[i, point] if by_rows else values[point, i])
        mean[i] = acc
        for point in range(count):
            d[i, point] = (values[i, point] if by_rows else values[point, i]) - acc


@register_jitable
def _weighted_outer(a, w, b, symmetric, out):
    """``Σᵢ wᵢ aᵢ bᵢᵀ`` of rows a (r, L) and b (c, L), each term as ``a (w b)``; ``symmetric`` (b is a):
    the upper triangle, mirrored."""
    r, c, count = a.shape[0], b.shape[0], a.shape[1]
    for i in range(r):
        for j in range(i if symmetric else 0, c):
            acc = 0.0
            for point in range(count):
                acc += a[i, point] * (w[point] * b[j, point])
            out[i, j] = acc
            if symmetric:
                out[j, i] = acc
    return out


@register_jitable
def _add_diagonal(a, noise):
    """``A + diag(noise)``, in place."""
    for i in range(noise.shape[0]):
        a[i, i] = a[i, i] + noise[i]
    return a


@register_jitable
def _minus_product(p, k, b, out):
    """``P - K Bᵀ`` for a symmetric ``K Bᵀ`` (the dense update's ``K Pxyᵀ``): its lower triangle, mirrored."""
    n, m = k.shape
    for i in range(n):
        for j in range(i + 1):
            acc = 0.0
            for c in range(m):
                acc += k[i, c] * b[j, c]
            out[i, j] = p[i, j] - acc
            out[j, i] = p[j, i] - acc
    return out


@register_jitable
def _compound(d, wc, sqrt_wc, sqrt_noise, work, offset):
    """``(ok, factor)`` of ``Σ wc dᵢ dᵢᵀ + diag(sqrt_noise)²`` from deviation rows (m, L): QR of
    ``[√wc d₁.., √N]`` (``tria``), then a rank-1 ``cholupdate`` with d₀ of weight wc₀ (seed 001 §2.2);
    the factor and the QR's matrix in ``work`` from ``offset``."""
    m, count = d.shape
    a, offset = _take(work, offset, m, count - 1 + m)
    s, offset = _take(work, offset, m, m)
    d0 = work[offset : offset + m]
    for i in range(m):
        for c in range(count - 1 + m):
            a[i, c] = 0.0
        for point in range(1, count):
            a[i, point - 1] = sqrt_wc[point - 1] * d[i, point]
        a[i, count - 1 + i] = sqrt_noise[i]
        d0[i] = d[i, 0]
    return sl.cholupdate(sl.tria(a, s), d0, wc[0], s)


@register_jitable
def time_update(chi_f, wm, wc, q_diag, work=None):
    """Dense: propagated points ``f(χ)`` (L, n) and the process noise's diagonal -> ``(x⁻, P⁻)`` (views of
    ``work`` when given)."""
    count, n = chi_f.shape
    work = _work(work, work_size(n, count, n))
    x = work[0:n]
    d, offset = _take(work, n, n, count)
    p, _ = _take(work, offset, n, n)
    _spread(chi_f, wm, False, x, d)
    return x, _add_diagonal(_weighted_outer(d, wc, d, True, p), q_diag)


@register_jitable
def sqrt_time_update(chi_f, wm, wc, sqrt_wc, sqrt_q, work=None):
    """Square root: propagated points and √Q's diagonal -> ``(ok, x⁻, S⁻)`` by QR and one cholupdate
    (views of ``work`` when given)."""
    count, n = chi_f.shape
    work = _work(work, work_size(n, count, n))
    x = work[0:n]
    d, offset = _take(work, n, n, count)
    _spread(chi_f, wm, False, x, d)
    ok, s = _compound(d, wc, sqrt_wc, sqrt_q, work, offset)
    return ok, x, s


@register_jitable
def _output_spread(x, chi, y_sigma, y, wm, work, linear_rows):
    """``(dy, dx, innovation, work, offset)`` of outputs ``h(χ)`` (m, L): rows from ``linear_rows`` on are
    angles, each unwrapped around its centre point's when it spans π or more, its innovation wrapped into
    [-π, π); in ``work`` (a new one for None; ``offset``: what they use of it), the measurement updates'
    first step."""
    m, count = y_sigma.shape
    n = x.shape[0]
    work = _work(work, work_size(n, count, m))
    y_hat, innovation = work[0:m], work[m : 2 * m]
    dy, offset = _take(work, 2 * m, m, count)
    dx, offset = _take(work, offset, n, count)
    for i in range(m):
        r0 = y_sigma[i, 0]
        low, high = r0, r0
        for point in range(count):
            v = y_sigma[i, point]
            low, high = min(low, v), max(high, v)
        for point in range(count):
            dy[i, point] = y_sigma[i, point] if i < linear_rows or high - low < math.pi else r0 + wrap_pi(y_sigma[i, point] - r0)
    _spread(dy, wm, True, y_hat, dy)
    for i in range(n):
        for point in range(count):
            dx[i, point] = chi[point, i] - x[i]
    for i in range(m):
        innovation[i] = y[i] - y_hat[i] if i < linear_rows else wrap_pi(y[i] - y_hat[i])
    return dy, dx, innovation, work, offset


@register_jitable
def _corrected(x, k, innovation, out):
    """``x + K ν``."""
    for i in range(x.shape[0]):
        acc = 0.0
        for c in range(innovation.shape[0]):
            acc += k[i, c] * innovation[c]
        out[i] = x[i] + acc
    return out


@register_jitable
def measurement_update(x, p, chi, y_sigma, y, r_diag, wm, wc, work=None, linear_rows=0):
    """Dense: prior ``(x, P)``, its points ``χ`` (L, n), their outputs ``h(χ)`` (m, L), the measurements
    ``y`` (the first ``linear_rows`` plain numbers, the rest angles) and the noise's diagonal ->
    ``(ok, x, P, innovation)`` (views of ``work`` when given)."""
    n, m = x.shape[0], y.shape[0]
    dy, dx, innovation, work, offset = _output_spread(x, chi, y_sigma, y, wm, work, linear_rows)
    p_yy, offset = _take(work, offset, m, m)
    p_xy, offset = _take(work, offset, n, m)
    low, offset = _take(work, offset, m, m)
    k, offset = _take(work, offset, n, m)
    p_new, offset = _take(work, offset, n, n)
    x_new = work[offset : offset + n]
    _add_diagonal(_weighted_outer(dy, wc, dy, True, p_yy), r_diag)
    _weighted_outer(dx, wc, dy, False, p_xy)
    ok, low = sl.cholesky(p_yy, low)
    if not ok:
        return False, x, p, innovation
    sl.solve_right(low, p_xy, k)  # Pxy Pyy⁻¹
    return True, _corrected(x, k, innovation, x_new), _minus_product(p, k, p_xy, p_new), innovation  # P - K Pyy Kᵀ = P - K Pxyᵀ


@register_jitable
def sqrt_measurement_update(x, s, chi, y_sigma, y, sqrt_r, wm, wc, sqrt_wc, work=None, linear_rows=0):
    """Square root: as ``measurement_update`` with the factor ``S`` and √R's diagonal -> ``(ok, x, S,
    innovation)``: ``Sy`` by QR and cholupdate, ``K = Pxy (Sy Syᵀ)⁻¹``, ``S`` downdated by each column of
    ``K Sy``."""
    n, m = x.shape[0], y.shape[0]
    dy, dx, innovation, work, offset = _output_spread(x, chi, y_sigma, y, wm, work, linear_rows)
    k, offset = _take(work, offset, n, m)
    s_new, offset = _take(work, offset, n, n)
    x_new = work[offset : offset + n]
    u = work[offset + n : offset + 2 * n]
    ok, s_y = _compound(dy, wc, sqrt_wc, sqrt_r, work, offset + 2 * n)
    if not ok:
        return False, x, s, innovation
    sl.solve_right(s_y, _weighted_outer(dx, wc, dy, False, k), k)
    down = s
    for j in range(m):
        for i in range(n):
            acc = 0.0
            for c in range(m):
                acc += k[i, c] * s_y[c, j]
            u[i] = acc
        ok, down = sl.cholupdate(down, u, -1.0, s_new)
        if not ok:
            return False, x, down, innovation
    return True, _corrected(x, k, innovation, x_new), down, innovation
