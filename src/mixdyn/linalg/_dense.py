"""Dense linear algebra used by every analysis: checked LU solves, the constrained-dynamics
(KKT) solve and rank-revealing analysis of Jacobians.

The conditioning of each factorization is monitored by the *pivot ratio*
``min |U_ii| / max |U_ii|`` of its LU factors: a value near machine precision means the matrix
lost rank (a singular configuration, a mixed problem that cannot be solved).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np


class Factor(NamedTuple):
    """A factorization done once and solved with many times (lineax's ``init``/``compute``).

    Attributes:
        solve: ``b -> x``, ``b`` (m,) or (m, k).
        ratio: the pivot ratio of the factorization (scale free; near 0: the matrix lost rank),
            comparable between the dense and the sparse path.
    """

    solve: Callable[[jax.Array], jax.Array]
    ratio: jax.Array


def lu_factor_checked(A: jax.Array) -> Factor:
    """Partial-pivoting LU of the square ``A`` (n, n), factorized once."""
    if A.shape[0] == 0:
        return Factor(lambda b: b, jnp.ones(()))
    lu, piv = jsl.lu_factor(A)
    d = jnp.abs(jnp.diag(lu))
    ratio = jnp.min(d) / jnp.maximum(jnp.max(d), jnp.finfo(A.dtype).tiny)
    return Factor(lambda b: jsl.lu_solve((lu, piv), b), ratio)


def lu_solve_checked(A: jax.Array, b: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Solve ``A x = b`` by partial-pivoting LU; return ``(x, pivot_ratio)``.

    Args:
        A: (n, n) matrix.
        b: (n,) or (n, k) right-hand side.
    """
    f = lu_factor_checked(A)
    return f.solve(b), f.ratio


#: Pivot ratio under which a guarded factorization (:func:`guarded`) switches to the damped SVD
#: solve.
SINGULAR_RATIO = 1e-10
#: Relative Tikhonov damping ``kappa`` of the solve near a singular position
#: (:func:`damped_solve`): the singular values ``s`` of the Schur complement ``S`` are inverted
#: as ``s / (s^2 + (kappa s_max)^2)``, with ``s = sigma^2`` from the SVD of ``F`` where
#: ``S = F F^T``. Their rounding there, ``~eps sigma_max sigma``, moves the result by up to
#: ``~eps / kappa`` of ``|b| / s_max``, most where ``sigma_min ~ kappa sigma_max``. Measured on
#: the N-four-bar (N = 5, 40) at every distance from a flat position, between NumPy's, JAX's
#: and a QR-then-gesvd SVD: 4e-10 of the largest component (3e-8 with ``kappa = 1e-9``).
SINGULAR_DAMPING = 1e-7
#: ``kappa`` where the damped solve takes the SVD of ``S`` itself (a Schur complement
#: ``C W G`` that is not a Gram matrix: a mixed problem's unknown forces). ``S``'s singular
#: values are then known to ``~eps s_max`` only, and the filter's slope, up to
#: ``1 / (kappa s_max)^2``, turns that into ``~eps / kappa^2`` of ``|b| / s_max`` (measured
#: as above with ``S`` formed: 3e-10 of the largest component, 3e-8 with ``kappa = 1e-4``).
SINGULAR_DAMPING_FORMED = 1e-3


def factor_ranked(
    A: jax.Array, rank: int | None = None, rcond: float = 0.0, damping: float = 0.0
) -> Factor:
    """Factorize ``A`` (m, n) once for :func:`solve_ranked`'s least-squares, minimum-norm
    solves knowing ``rank(A)`` (see there); the ratio is ``s[rank-1] / s[0]`` (or the LU
    pivot ratio)."""
    if rank is None and A.shape[0] == A.shape[1] and rcond == 0.0 and damping == 0.0:
        return lu_factor_checked(A)
    U, s, Vt = jnp.linalg.svd(A, full_matrices=False)
    r = min(A.shape) if rank is None else rank
    keep = (jnp.arange(s.shape[0]) < r) & (s > rcond * s[0])
    mu2 = (damping * s[0]) ** 2 if s.shape[0] else 0.0
    inv = jnp.where(keep, s / jnp.where(keep, s * s + mu2, 1.0), 0.0)

    def solve(b):
        Ub = U.T @ b
        return Vt.T @ (inv[:, None] * Ub if b.ndim == 2 else inv * Ub)

    ratio = s[r - 1] / jnp.maximum(s[0], jnp.finfo(A.dtype).tiny) if r > 0 else jnp.ones(())
    return Factor(solve, ratio)


def solve_ranked(
    A: jax.Array, b: jax.Array, rank: int | None = None, rcond: float = 0.0, damping: float = 0.0
):
    """Solve ``A x = b`` (least squares, minimum norm) knowing ``rank(A)``; ``(x, ratio)``.

    With ``rank=None`` and a square ``A`` this is :func:`lu_solve_checked`. Otherwise a truncated
    SVD keeps the ``rank`` largest singular values: redundant but consistent equations (a
    parallelogram's extra link) are solved exactly, and the multipliers of redundant constraints
    come out as the minimum-norm set; singular values below ``rcond * s_max`` are dropped too.
    ``ratio = s[rank-1] / s[0]`` tells a loss of rank. With ``damping = kappa > 0`` the kept
    singular values are inverted as ``s / (s^2 + (kappa s[0])^2)`` (Tikhonov filter factors):
    exact for ``s >> kappa s[0]``, smoothly to zero below, so that the solution stays a
    smooth, bounded function of ``A`` and ``b`` through a loss of rank.
    """
    f = factor_ranked(A, rank, rcond, damping)
    return f.solve(b), f.ratio


def gram_factor(J: jax.Array, W: jax.Array, shift=None) -> jax.Array:
    """``F`` with ``F F^T = J diag(W) J^T`` (plus ``shift I``): ``J W^(1/2)`` (m, n), or
    ``[J W^(1/2) | shift^(1/2) I]`` (m, n + m) with a ``shift``. ``W`` (n,) >= 0 (zeros keep
    coordinates out; their derivative is 0, not NaN)."""
    pos = W > 0
    F = J * jnp.where(pos, jnp.sqrt(jnp.where(pos, W, 1.0)), 0.0)
    if shift is not None:
        F = jnp.concatenate([F, jnp.sqrt(shift) * jnp.eye(J.shape[0], dtype=F.dtype)], axis=1)
    return F


def damped_solve(A: jax.Array, b: jax.Array, rank: int | None = None, gram: bool = False):
    """The damped SVD solve of ``S y = b`` at a singular position (:func:`guarded`): the
    singular values ``s`` of ``S`` (m, m) inverted as ``s / (s^2 + (kappa s_max)^2)``
    (Tikhonov filter factors: exact for ``s >> kappa s_max``, smoothly to zero below), the
    ``rank`` largest only where rows are redundant.

    With ``gram``, ``A`` is a factor ``F`` (m, k) of ``S = F F^T`` (:func:`gram_factor`) and
    ``S = U diag(sigma^2) U^T`` comes from ``F``'s SVD: ``S`` is never formed. Forming it
    would square ``F``'s condition and leave its small singular values at rounding level
    (``~eps s_max``), where the filter's slope ``1 / (kappa s_max)^2`` turns them into
    whatever the installed SVD makes of them; from ``F`` they are known to
    ``~eps sigma_max sigma`` and ``kappa`` is :data:`SINGULAR_DAMPING`. Otherwise ``A`` is
    ``S`` itself and ``kappa`` is :data:`SINGULAR_DAMPING_FORMED`, above that floor.

    Args:
        A: ``F`` (m, k) with ``gram``, else ``S`` (m, m).
        b: (m,) or (m, p) right-hand side.
        rank: the rank of ``S`` when rows are redundant (its ``rank`` largest singular values
            are kept), else None.
        gram: whether ``A`` is ``F``.

    Returns:
        ``y``, the shape of ``b``.
    """
    if not gram:
        return solve_ranked(A, b, rank, damping=SINGULAR_DAMPING_FORMED)[0]
    U, sigma, _ = jnp.linalg.svd(A, full_matrices=False)
    s = sigma * sigma
    keep = jnp.arange(s.shape[0]) < (s.shape[0] if rank is None else rank)
    den = s * s + (SINGULAR_DAMPING * s[0]) ** 2
    inv = jnp.where(keep & (den > 0), s / jnp.where(den > 0, den, 1.0), 0.0)
    Ub = U.T @ b
    return U @ (inv[:, None] * Ub if b.ndim == 2 else inv * Ub)


def guarded(
    f: Factor,
    A: Callable[[], jax.Array],
    rank: int | None = None,
    batched: bool = False,
    gram: bool = False,
) -> Factor:
    """``f`` with :func:`damped_solve` below :data:`SINGULAR_RATIO` (a singular position, a
    NaN ratio too): near a loss of rank the part of ``b`` along the vanishing direction
    (rounding, an RK stage off the constraints) is not amplified like ``1/s`` into a jump.
    ``A()`` is ``S`` (m, m), or with ``gram`` a factor ``F`` of ``S = F F^T``
    (:func:`gram_factor`); it is formed only in the branch taken there.

    Under ``vmap`` a ``lax.cond`` whose predicate differs between members becomes a select
    that runs both branches: the SVD at every step of every member (measured on the paper's
    model, 32 members on a CPU: 144 ms a member against 21 ms without it). With ``batched``
    (a sweep's one program, :func:`~mixdyn.analysis.sweep.sweep`) the guard decides once for
    the whole batch: the SVD runs (for all members, each keeping its own branch's result)
    only at a step where some member needs it. Same results member by member; not
    reverse-differentiable (``custom_vmap``), so only for programs that are not.
    """
    if batched:

        def solve_any(b):
            return _fallback_where(rank, gram)(f.ratio, A(), b, f.solve(b))

        return Factor(solve_any, f.ratio)

    def solve(b):
        return jax.lax.cond(
            ~(f.ratio >= SINGULAR_RATIO),
            lambda b: damped_solve(A(), b, rank, gram),
            f.solve,
            b,
        )

    return Factor(solve, f.ratio)


@functools.cache
def _fallback_where(rank: int | None, gram: bool):
    """``pick(ratio, A, b, x)``: :func:`damped_solve` of ``S y = b`` (``A``: ``S``, or ``F``
    with ``gram``) where the pivot ratio is below :data:`SINGULAR_RATIO`, else ``x`` (the
    factorization's solve); under ``vmap`` the SVD runs for the batch only when some member
    needs it (:func:`guarded`)."""
    from jax.custom_batching import custom_vmap

    def slow(A, b):
        return damped_solve(A, b, rank, gram)

    @custom_vmap
    def pick(ratio, S, b, x):
        return jax.lax.cond(
            ~(ratio >= SINGULAR_RATIO), lambda S, b, x: slow(S, b), lambda S, b, x: x, S, b, x
        )

    @pick.def_vmap
    def _rule(axis_size, in_batched, ratio, S, b, x):
        r_b, S_b, b_b, x_b = in_batched
        bad = ~(ratio >= SINGULAR_RATIO)
        if not r_b:
            bad = jnp.broadcast_to(bad, (axis_size,))
        if not x_b:
            x = jnp.broadcast_to(x, (axis_size, *x.shape))

        def both(S, b, x):
            y = jax.vmap(slow, in_axes=(0 if S_b else None, 0 if b_b else None))(S, b)
            y = jnp.broadcast_to(y, x.shape)
            return jnp.where(bad.reshape(bad.shape + (1,) * (x.ndim - 1)), y, x)

        out = jax.lax.cond(jnp.any(bad), both, lambda S, b, x: x, S, b, x)
        return out, True

    return pick


def min_pivot(A: jax.Array) -> jax.Array:
    """Smallest ``|U_ii|`` of the partial-pivoting LU of the square ``A``: compare choices of
    a square block of one matrix by it (it is not scale free, unlike the pivot ratio)."""
    if A.shape[0] == 0:
        return jnp.asarray(jnp.inf)
    lu, _ = jsl.lu_factor(A)
    return jnp.min(jnp.abs(jnp.diag(lu)))


def min_norm_step(J, r, weights=None, damping=0.0) -> jax.Array:
    """The least-norm correction ``dx`` with ``J dx = -r``: ``dx = -W J^T (J W J^T + mu I)^-1 r``.

    Args:
        J: (m, n) Jacobian, m <= n.
        r: (m,) residual.
        weights: (n,) diagonal metric ``W`` (e.g. ``M^-1`` for a mass-weighted projection).
        damping: Levenberg–Marquardt parameter ``mu`` (0 for Gauss–Newton).
    """
    W = jnp.ones(J.shape[1]) if weights is None else weights
    JW = J * W[None, :]
    S = JW @ J.T + damping * jnp.eye(J.shape[0])
    y, _ = lu_solve_checked(S, r)
    return -(JW.T @ y)


def independent_rows(A, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray, int]:
    """Rank-revealing QR (column-pivoted, on ``A^T``) of a Jacobian.

    Rows are scaled to unit norm first, so the decision does not depend on the units of the
    equations.

    Args:
        A: (m, n) matrix.
        rtol: a diagonal entry of ``R`` below ``rtol * |R_00|`` counts as zero.

    Returns:
        ``(independent, redundant, rank)``: sorted row indices of a maximal independent set,
        the other rows, and the numerical rank.
    """
    import scipy.linalg as sl  # here, not at import: only a redundancy needs the pivoted QR

    A = np.asarray(A, dtype=float)
    m = A.shape[0]
    if m == 0:
        return np.zeros(0, int), np.zeros(0, int), 0
    norms = np.linalg.norm(A, axis=1)
    zero = norms == 0
    As = A / np.where(zero, 1.0, norms)[:, None]
    _, R, piv = sl.qr(As.T, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    rank = int(np.sum(d > rtol * max(d[0], 1e-300))) if d.size else 0
    independent = np.sort(piv[:rank])
    redundant = np.sort(piv[rank:])
    return independent, redundant, rank


def dependent_rows(A, rtol: float = 1e-9) -> np.ndarray:
    """Rows taking part in the (near) linear dependency of ``A``'s rows: the rows with large
    components in the left singular vectors of the smallest singular values."""
    A = np.asarray(A, dtype=float)
    if A.size == 0:
        return np.zeros(0, int)
    norms = np.linalg.norm(A, axis=1)
    As = A / np.where(norms == 0, 1.0, norms)[:, None]
    U, s, _ = np.linalg.svd(As)
    k = int(np.sum(s > rtol * s[0])) if s.size else 0
    m = A.shape[0]
    if k >= m:
        U_small = U[:, [int(np.argmin(s))]] if s.size == m else U[:, k:]
    else:
        U_small = U[:, k:]
    weight = np.max(np.abs(U_small), axis=1)
    rows = np.where(weight > 0.1 * weight.max())[0] if weight.size else np.zeros(0, int)
    return rows


__all__ = [
    "Factor",
    "damped_solve",
    "dependent_rows",
    "factor_ranked",
    "gram_factor",
    "guarded",
    "independent_rows",
    "lu_factor_checked",
    "lu_solve_checked",
    "min_norm_step",
    "min_pivot",
    "solve_ranked",
]
