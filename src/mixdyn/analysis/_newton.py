"""Newton–Raphson on ``Phi(q, t) = 0`` for a square system, jittable (``lax.while_loop``)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..equations import Constraints


def newton_positions(c: Constraints, q, t, tol, max_iter):
    """Solve ``Phi(q, t) = 0`` (square, or with redundant rows of known rank) from ``q``.

    Each step solves ``Phi_q dq = Phi`` on the constraint set's linear-solver path
    (:meth:`~mixdyn.equations.Constraints.jacobian_solver`: LU, or on the sparse path the
    minimum-norm step ``Phi_q^T (Phi_q Phi_q^T)^-1 Phi`` by a banded Cholesky factorization).

    Converged when the largest residual is below ``tol`` [length] after a step whose size is
    below ``sqrt(tol)``-ish relative motion; the iteration count, the final residual and the
    smallest pivot ratio met are returned for diagnosis.

    Returns:
        ``(q, iterations, residual, pivot_ratio)``.
    """

    def cond(s):
        _, it, res, _ = s
        return (res > tol) & (it < max_iter) & jnp.isfinite(res)

    def body(s):
        q, it, _, ratio = s
        dq, r = c.jacobian_solver(q, t)(c(q, t))
        q = q - dq
        res = jnp.max(jnp.abs(c(q, t)))
        return q, it + 1, res, jnp.minimum(ratio, r)

    res0 = jnp.max(jnp.abs(c(q, t)))
    q, it, res, ratio = jax.lax.while_loop(cond, body, (q, jnp.asarray(0), res0, jnp.asarray(1.0)))
    # One more step for full precision at the converged point costs little and tightens
    # the answer to rounding level; keep the pivot ratio of the final Jacobian.
    dq, r = c.jacobian_solver(q, t)(c(q, t))
    q = jnp.where(jnp.isfinite(res), q - dq, q)
    return q, it, jnp.max(jnp.abs(c(q, t))), jnp.minimum(ratio, r)
