"""Small dense linear algebra on plain Python floats, for the n = 4 filters (ukf, sssrukf).

On 4 x 4 matrices numpy's per-call overhead (``numpy.linalg.qr`` ~50 µs) dwarfs the arithmetic, so
these loops are faster and their cost follows the operation count. Matrices are lists of rows,
vectors lists; triangular factors are lower (``P = L Lᵀ``). Failures raise ``numpy.linalg.LinAlgError``
like the numpy routines they replace.
"""

from __future__ import annotations

import math
from operator import mul

from numpy.linalg import LinAlgError


def dot(a, b) -> float:
    return sum(map(mul, a, b))


def cholesky(a):
    """Lower ``L`` with ``L Lᵀ = a`` (symmetric; only its lower triangle is read), column by column."""
    n = len(a)
    low = [[0.0] * n for _ in range(n)]
    for j in range(n):
        lj = low[j]
        d = a[j][j]
        for k in range(j):
            d -= lj[k] * lj[k]
        if not d > 0.0:
            raise LinAlgError("matrix is not positive definite")
        r = lj[j] = math.sqrt(d)
        for i in range(j + 1, n):
            li = low[i]
            t = a[i][j]
            for k in range(j):
                t -= li[k] * lj[k]
            li[j] = t / r
    return low


def tria(a):
    """Lower ``L`` with ``L Lᵀ = A Aᵀ`` for A (n, m), m >= n: Householder QR of ``Aᵀ`` applied to the
    rows of A (``A H₁..Hₙ = [L 0]``), the diagonal made positive. The square-root filters' compound-matrix QR."""
    rows = list(a)  # row i keeps only its columns k.. as k advances
    n = len(rows)
    low = [[0.0] * n for _ in range(n)]
    for k in range(n):
        v = list(rows[k])
        norm = math.sqrt(sum(map(mul, v, v)))
        if norm == 0.0:
            continue
        x0 = v[0]
        alpha = -norm if x0 >= 0.0 else norm  # row k becomes alpha e_k
        v[0] = x0 - alpha
        beta = 1.0 / (norm * (norm + abs(x0)))  # 2 / vᵀv
        sign = -1.0 if alpha < 0.0 else 1.0  # flips column k so that L[k][k] > 0
        low[k][k] = abs(alpha)
        for i in range(k + 1, n):
            t = rows[i]
            f = beta * sum(map(mul, t, v))
            t = [c - f * w for c, w in zip(t, v)]
            low[i][k] = sign * t[0]
            rows[i] = t[1:]
    return low


def cholupdate(s, v, weight: float = 1.0):
    """Lower ``S'`` with ``S' S'ᵀ = S Sᵀ + weight v vᵀ`` (a downdate for weight < 0): the classic
    rank-1 modification column by column; raises ``LinAlgError`` when a downdate would leave the
    matrix indefinite."""
    n = len(v)
    sign = 1.0 if weight >= 0.0 else -1.0
    a = [list(r) for r in s]
    w = math.sqrt(abs(weight))
    x = [w * c for c in v]
    for k in range(n):
        akk = a[k][k]
        xk = x[k]
        r2 = akk * akk + sign * xk * xk
        if not r2 > 0.0:
            raise LinAlgError("Cholesky downdate lost positive definiteness")
        r = math.sqrt(r2)
        c, t = r / akk, xk / akk
        st = sign * t
        a[k][k] = r
        for i in range(k + 1, n):
            ai = a[i]
            aik = ai[k] = (ai[k] + st * x[i]) / c
            x[i] = c * x[i] - t * aik
    return a


def solve_right(low, b):
    """``X`` with ``X L Lᵀ = B`` (B a list of rows, e.g. the gain ``Pxy (Sy Syᵀ)⁻¹``): two triangular
    substitutions, column by column of B."""
    m = len(low)
    cols = [list(c) for c in zip(*b)]
    for i in range(m):  # Y Lᵀ = B
        li, c = low[i], cols[i]
        for j in range(i):
            lij = li[j]
            c = [p - lij * q for p, q in zip(c, cols[j])]
        d = li[i]
        cols[i] = [p / d for p in c]
    for i in reversed(range(m)):  # X L = Y
        c = cols[i]
        for j in range(i + 1, m):
            lji = low[j][i]
            c = [p - lji * q for p, q in zip(c, cols[j])]
        d = low[i][i]
        cols[i] = [p / d for p in c]
    return [list(r) for r in zip(*cols)]


def diag(values):
    """Diagonal matrix (list of rows) of a sequence."""
    n = len(values)
    rows = [[0.0] * n for _ in range(n)]
    for i, v in enumerate(values):
        rows[i][i] = v
    return rows
