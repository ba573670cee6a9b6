"""Small dense linear algebra for the n = 4 filters (ukf, sssrukf), compiled into their kernels.

``register_jitable`` (base.py's compiled estimators): compiled inside the ukf kernel, plain Python on
numpy arrays elsewhere (the tests; the interpreted kernel). On 4 x 4 matrices LAPACK's per-call cost
dwarfs the arithmetic, so these are plain loops whose cost follows the operation count. Matrices are
2-D float64 arrays; triangular factors are lower (``P = L Lᵀ``). A compiled kernel cannot catch an
exception, so a failure is a returned flag: ``ok`` False where numpy would raise ``LinAlgError``.
Every sum runs from 0 upward over its index, the order the filter's equations are written in.

Outputs: a new array by default; the kernel passes its own (``low``, ``out``: views of its work space),
so that a sample allocates nothing (an allocation, ~25 ns, costs about as much as a 4 x 4 Cholesky).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic, overload, register_jitable


def matrix_view(flat, start, rows, cols):
    """The (rows, cols) matrix stored row by row in ``flat`` (1-D, contiguous) from ``start``: a view. Compiled,
    it is made directly, without numba's reshape (a call into its helper library, ~10 ns; the ukf kernel
    takes ~20 views a sample) and without a bounds check: the callers' layouts are fixed (ukf's state,
    sigma_points' work), and the interpreted path, this function, checks them."""
    return flat[start : start + rows * cols].reshape((rows, cols))


@intrinsic
def _matrix_view(typingctx, flat, start, rows, cols):
    matrix = types.Array(flat.dtype, 2, "C")

    def codegen(context, builder, signature, args):
        source = context.make_array(signature.args[0])(context, builder, value=args[0])
        start, rows, cols = (context.cast(builder, v, t, types.intp) for v, t in zip(args[1:], signature.args[1:]))
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(flat.dtype)))
        view = context.make_array(matrix)(context, builder)
        context.populate_array(
            view, data=cgutils.gep_inbounds(builder, source.data, start), shape=cgutils.pack_array(builder, [rows, cols]),
            strides=cgutils.pack_array(builder, [builder.mul(cols, itemsize), itemsize]), itemsize=itemsize,
            meminfo=source.meminfo, parent=source.parent,
        )
        return impl_ret_borrowed(context, builder, matrix, view._getvalue())

    return matrix(flat, start, rows, cols), codegen


@overload(matrix_view)
def _matrix_view_compiled(flat, start, rows, cols):
    if isinstance(flat, types.Array) and flat.ndim == 1 and flat.layout == "C":
        return lambda flat, start, rows, cols: _matrix_view(flat, start, rows, cols)


@register_jitable
def _zeroed(low):
    for i in range(low.shape[0]):
        for j in range(low.shape[1]):
            low[i, j] = 0.0


@register_jitable
def cholesky(a, low=None):
    """``(ok, L)``, ``L Lᵀ = a`` (symmetric; only its lower triangle is read), column by column, into
    ``low`` when given."""
    n = a.shape[0]
    if low is None:
        low = np.empty((n, n))
    _zeroed(low)
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= low[j, k] * low[j, k]
        if not d > 0.0:
            return False, low
        r = math.sqrt(d)
        low[j, j] = r
        for i in range(j + 1, n):
            t = a[i, j]
            for k in range(j):
                t -= low[i, k] * low[j, k]
            low[i, j] = t / r
    return True, low


@register_jitable
def tria(a, low=None):
    """Lower ``L`` with ``L Lᵀ = A Aᵀ`` for A (n, m), m >= n: Householder QR of ``Aᵀ`` applied to the
    rows of A (``A H₁..Hₙ = [L 0]``), the diagonal made positive. The square-root filters' compound-matrix
    QR. ``a`` is overwritten (its rows reduced column by column; row k holds the k-th Householder vector)."""
    n, m = a.shape
    if low is None:
        low = np.empty((n, n))
    _zeroed(low)
    for k in range(n):
        v = a[k]
        norm2 = 0.0
        for c in range(k, m):
            norm2 += v[c] * v[c]
        norm = math.sqrt(norm2)
        if norm == 0.0:
            continue
        x0 = v[k]
        alpha = -norm if x0 >= 0.0 else norm  # row k becomes alpha e_k
        v[k] = x0 - alpha
        beta = 1.0 / (norm * (norm + abs(x0)))  # 2 / vᵀv
        sign = -1.0 if alpha < 0.0 else 1.0  # flips column k so that L[k][k] > 0
        low[k, k] = abs(alpha)
        for i in range(k + 1, n):
            f = 0.0
            for c in range(k, m):
                f += a[i, c] * v[c]
            f = beta * f
            for c in range(k, m):
                a[i, c] = a[i, c] - f * v[c]
            low[i, k] = sign * a[i, k]
    return low


@register_jitable
def cholupdate(s, v, weight, out=None):
    """``(ok, S')``, ``S' S'ᵀ = S Sᵀ + weight v vᵀ`` (a downdate for weight < 0): the classic rank-1
    modification column by column; not ok when a downdate would leave the matrix indefinite. Into
    ``out`` when given (it may be ``s``; ``v`` is then overwritten)."""
    n = v.shape[0]
    sign = 1.0 if weight >= 0.0 else -1.0
    if out is None:
        a, x = s.copy(), np.empty(n)
    else:
        a, x = out, v
        for i in range(n):
            for j in range(n):
                a[i, j] = s[i, j]
    w = math.sqrt(abs(weight))
    for i in range(n):
        x[i] = w * v[i]
    for k in range(n):
        akk = a[k, k]
        xk = x[k]
        r2 = akk * akk + sign * xk * xk
        if not r2 > 0.0:
            return False, a
        r = math.sqrt(r2)
        c, t = r / akk, xk / akk
        st = sign * t
        a[k, k] = r
        for i in range(k + 1, n):
            aik = (a[i, k] + st * x[i]) / c
            a[i, k] = aik
            x[i] = c * x[i] - t * aik
    return True, a


@register_jitable
def solve_right(low, b, out=None):
    """``X`` with ``X L Lᵀ = B`` (B (r, m), e.g. the gain ``Pxy (Sy Syᵀ)⁻¹``): two triangular
    substitutions, column by column of B; into ``out`` when given (it may be ``b``)."""
    m = low.shape[0]
    rows = b.shape[0]
    if out is None:
        x = b.copy()
    else:
        x = out
        for r in range(rows):
            for i in range(m):
                x[r, i] = b[r, i]
    for i in range(m):  # Y Lᵀ = B
        for j in range(i):
            lij = low[i, j]
            for r in range(rows):
                x[r, i] = x[r, i] - lij * x[r, j]
        d = low[i, i]
        for r in range(rows):
            x[r, i] = x[r, i] / d
    for i in range(m - 1, -1, -1):  # X L = Y
        for j in range(i + 1, m):
            lji = low[j, i]
            for r in range(rows):
                x[r, i] = x[r, i] - lji * x[r, j]
        d = low[i, i]
        for r in range(rows):
            x[r, i] = x[r, i] / d
    return x
