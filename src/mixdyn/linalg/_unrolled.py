"""Factorizations of a small dense matrix as straight-line array code
(:class:`~mixdyn.linalg.UnrolledSolver`).

The factorization of an ``m x m`` matrix is written out at trace time, entry by entry
(Cholesky) or as ``m`` elimination steps on whole rows and columns (LU with partial pivoting),
and each solve as ``2 m`` substitution steps: no LAPACK call (``getrf``/``potrf`` and two
``trsm``), no pivot loop. Inside an integrator's loop on a CPU such a call costs more than
the arithmetic of a few rows; the straight-line code costs a few operations per entry, and
its program grows like ``m^3`` (Cholesky) or ``m^2`` (LU) operations, so the path pays for a
few rows only (measured: :data:`UNROLLED_MAX_ROWS`).

* :func:`cholesky_unrolled`: the symmetric positive definite Schur complement
  ``Phi_q W Phi_q^T``; its pivot ratio ``min L_ii^2 / max L_ii^2`` is that of an LU without
  pivoting, as on the banded path (a non-positive pivot, at a singular position, gives NaN:
  the guard's damped solve takes over).
* :func:`lu_factor_unrolled`: any square matrix, with LAPACK's pivots (``getrf``: in column
  ``k`` the first row of largest magnitude at or below the diagonal); the factors and the
  pivot ratio ``min |U_ii| / max |U_ii|`` are those of ``jax.scipy.linalg.lu_factor`` up to
  the order of the roundings.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ._dense import Factor

#: The most rows for which :class:`~mixdyn.linalg.AutoSolver` takes the straight-line path.
#: Measured (``benchmarks/per_step.py``, ``benchmarks/RESULTS.md``): RK4 steps of pendulum
#: chains, CPU time per step against the dense path's LAPACK calls.
UNROLLED_MAX_ROWS = 6

#: The most rows for the straight-line path in a sweep's one vectorized program, where LAPACK's
#: batched calls loop over members: measured (``benchmarks/gpu_sweep.py --linear-solver``,
#: ``benchmarks/RESULTS.md``) on the paper's model, 10 rows.
UNROLLED_MAX_ROWS_VECTORIZED = 16


def cholesky_unrolled(A: jax.Array) -> Factor:
    """The Cholesky factorization ``A = L L^T`` of the symmetric positive definite ``A``
    (m, m) (its lower triangle read), written out entry by entry.

    Returns:
        ``solve(b)`` for ``b`` (m,) or (m, k), and the pivot ratio ``min L_ii^2 / max L_ii^2``
        (NaN where a pivot is not positive: ``A`` is singular or indefinite to rounding).
    """
    m = A.shape[0]
    if m == 0:
        return Factor(lambda b: b, jnp.ones(()))
    a = [[A[i, j] for j in range(i + 1)] for i in range(m)]
    L: list[list[jax.Array]] = [[] for _ in range(m)]
    for j in range(m):
        s = a[j][j]
        for k in range(j):
            s = s - L[j][k] * L[j][k]
        L[j].append(jnp.sqrt(s))
        for i in range(j + 1, m):
            s = a[i][j]
            for k in range(j):
                s = s - L[i][k] * L[j][k]
            L[i].append(s / L[j][j])

    def solve(b):
        y = []
        for i in range(m):  # L y = b
            s = b[i]
            for k in range(i):
                s = s - L[i][k] * y[k]
            y.append(s / L[i][i])
        x = [None] * m
        for i in range(m - 1, -1, -1):  # L^T x = y
            s = y[i]
            for k in range(i + 1, m):
                s = s - L[k][i] * x[k]
            x[i] = s / L[i][i]
        return jnp.stack(x)

    d = jnp.stack([L[i][i] for i in range(m)]) ** 2
    return Factor(solve, jnp.min(d) / jnp.maximum(jnp.max(d), jnp.finfo(A.dtype).tiny))


def lu_unrolled(A: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(lu, perm)``: the partial-pivoting LU of the square ``A`` (m, m), ``A[perm] = L U``.

    Args:
        A: (m, m) matrix.

    Returns:
        ``lu`` (m, m): ``U`` on and above the diagonal, the multipliers of the unit lower
        triangular ``L`` below it; ``perm`` (m,) int: the rows of ``A`` in pivot order.
    """
    m = A.shape[0]
    idx = jnp.arange(m)
    perm = idx
    for k in range(m):
        col = jnp.where(idx >= k, jnp.abs(A[:, k]), -1.0)
        p = jnp.argmax(col)  # the first of the largest, as LAPACK's idamax
        rk, rp = A[k], A[p]
        A = jnp.where((idx == k)[:, None], rp, jnp.where((idx == p)[:, None], rk, A))
        perm = jnp.where(idx == k, perm[p], jnp.where(idx == p, perm[k], perm))
        below = idx > k
        piv = A[k, k]  # 0 only where the whole column is: getrf leaves it, so does this
        l = jnp.where(below, A[:, k] / jnp.where(piv == 0, 1.0, piv), 0.0)
        A = A - l[:, None] * jnp.where(below, A[k], 0.0)[None, :]
        A = jnp.where(below[:, None] & (idx == k)[None, :], l[:, None], A)
    return A, perm


def lu_solve_unrolled(lu: jax.Array, perm: jax.Array, b: jax.Array) -> jax.Array:
    """``x`` with ``A x = b`` from :func:`lu_unrolled`'s factors; ``b`` (m,) or (m, k)."""
    m = lu.shape[0]
    idx = jnp.arange(m)
    y = b[perm]
    shape = (m,) + (1,) * (b.ndim - 1)
    for k in range(m - 1):  # L y = P b, unit diagonal
        lk = jnp.where(idx > k, lu[:, k], 0.0).reshape(shape)
        y = y - lk * y[k]
    for k in range(m - 1, -1, -1):  # U x = y
        xk = y[k] / lu[k, k]
        uk = jnp.where(idx < k, lu[:, k], 0.0).reshape(shape)
        y = jnp.where((idx == k).reshape(shape), xk, y - uk * xk)
    return y


def lu_factor_unrolled(A: jax.Array) -> Factor:
    """:func:`~mixdyn.linalg.lu_factor_checked` of the square ``A`` (m, m) by
    :func:`lu_unrolled`: the same factors, solves and pivot ratio, as straight-line code."""
    if A.shape[0] == 0:
        return Factor(lambda b: b, jnp.ones(()))
    lu, perm = lu_unrolled(A)
    d = jnp.abs(jnp.diag(lu))
    ratio = jnp.min(d) / jnp.maximum(jnp.max(d), jnp.finfo(A.dtype).tiny)
    return Factor(lambda b: lu_solve_unrolled(lu, perm, b), ratio)


__all__ = [
    "UNROLLED_MAX_ROWS",
    "cholesky_unrolled",
    "lu_factor_unrolled",
    "lu_solve_unrolled",
    "lu_unrolled",
]
