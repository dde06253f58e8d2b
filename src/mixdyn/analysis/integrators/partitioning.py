"""``partitioning``: Wehage–Haug generalized coordinate partitioning, the paper's family.

The coordinates split into dependent ``D`` (as many as constraint rows, chosen by pivoted LU on
``Phi_q`` so that ``Phi_qD`` is well conditioned) and independent ``I``. Only the independent
positions and velocities are integrated (adaptive explicit RK from diffrax); at every stage the
dependent positions are solved from ``Phi(q, t) = 0`` by Newton and the dependent velocities
from ``Phi_q qd = -Phi_t``, so the constraints hold to Newton tolerance throughout. The
partition is chosen again when ``Phi_qD`` becomes ill-conditioned compared with a fresh choice.

On the sparse path the dependent solves are minimum-norm solves with weights 1 on ``D`` and 0
on ``I`` through the banded Cholesky factorization of ``Phi_q W Phi_q^T`` (one pattern whatever
the partition), and the partition is chosen again only when that factorization's pivot ratio
collapses (:data:`RECHOOSE_RATIO`), by the dense pivoted LU of the first choice.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ...linalg import lu_solve_checked
from .._problem import Problem, pivot_columns
from ._common import Trajectory

#: Sparse path: the partition is chosen again (dense pivoted LU) only when the square root of
#: the pivot ratio of ``Phi_qD Phi_qD^T``'s Cholesky factors falls below this.
RECHOOSE_RATIO = 1e-4


def _dependent_solver(problem: Problem, q, t, D, values=None):
    """Sparse path: ``(solve, ratio)`` with ``solve(b)`` the ``dq`` (nq,), zero outside ``D``,
    with ``Phi_qD dq_D = b``: the minimum-norm solution with weights 1 on ``D`` and 0 on the
    independent coordinates, ``W Phi_q^T (Phi_q W Phi_q^T)^-1 b`` (exact for a regular square
    ``Phi_qD``), banded Cholesky with one step of iterative refinement; ``values``: the
    Jacobian values at ``(q, t)`` if already evaluated."""
    c = problem.c
    w = jnp.zeros(q.shape[0], q.dtype).at[D].set(1.0)
    return c.min_norm_solver(c.jacobian_values(q, t) if values is None else values, w, refine=1)


def _complete_sparse(problem: Problem, q_ref, D, I, v, vd, t, tol, iters=8):
    """:func:`_complete` on the sparse path; also returns the pivot ratio of the final
    factorization (for the choice of a new partition)."""
    c = problem.c
    q = q_ref.at[I].set(v)

    def cond(s):
        k, _, r = s
        return (k < iters) & (jnp.max(jnp.abs(r), initial=0.0) > tol)

    def body(s):
        k, q, r = s
        q = q - _dependent_solver(problem, q, t, D)[0](r)
        return k + 1, q, c(q, t)

    _, q, _ = jax.lax.while_loop(cond, body, (0, q, c(q, t)))
    qd_i = jnp.zeros_like(q).at[I].set(vd)
    vals = c.jacobian_values(q, t)
    solve, ratio = _dependent_solver(problem, q, t, D, vals)
    return q, qd_i + solve(-c.phi_t(q, t) - c.matvec(vals, qd_i)), ratio


def _complete(problem: Problem, q_ref, D, I, v, vd, t, tol, iters=8):
    """Full ``(q, qd)`` from independent ``(v, vd)``, dependent parts by Newton from ``q_ref``."""
    if problem.sparse:
        return _complete_sparse(problem, q_ref, D, I, v, vd, t, tol, iters)[:2]
    q = q_ref.at[I].set(v)

    def body(_, q):
        r = problem.c(q, t)
        J = problem.c.phi_q(q, t)
        dqD, _ = lu_solve_checked(J[:, D], r)
        return jnp.where(jnp.max(jnp.abs(r)) > tol, q.at[D].add(-dqD), q)

    q = jax.lax.fori_loop(0, iters, body, q)
    J = problem.c.phi_q(q, t)
    rhs = -problem.c.phi_t(q, t) - J[:, I] @ vd
    qdD, _ = lu_solve_checked(J[:, D], rhs)
    qd = jnp.zeros_like(q).at[I].set(vd).at[D].set(qdD)
    return q, qd


def _choose(problem: Problem, q, t):
    m = problem.c.m
    return pivot_columns(problem.c.phi_q(q, t), m)


def _conditioning(problem: Problem, q, t, D):
    """Smallest singular value of ``Phi_qD``: how far the partition is from singular."""
    return jnp.linalg.svd(problem.c.phi_q(q, t)[:, D], compute_uv=False)[-1]


def _solver_class():
    """The partitioning step as a diffrax wrapped solver (diffrax imported when traced)."""
    from ._constrained import ConstrainedSolver

    class Partitioned(ConstrainedSolver):
        """A Runge–Kutta step of the independent coordinates, the dependent ones completed
        by Newton; the partition ``(D, I)`` is carried in the solver state and chosen again
        where the dependent block becomes ill-conditioned."""

        problem: Problem
        tol: jax.Array
        reduced: object  # the vector field of the independent coordinates (an ODETerm)

        def inner_terms(self, terms):
            return self.reduced

        def initial_data(self, y0, t0):
            return _choose(self.problem, y0[0], t0)

        def reduce(self, y, data, t):
            q, qd, w = y
            D, I = data
            return (q[I], qd[I], w), (q, qd, D, I, t)

        def finish(self, t0, t1, y0, z1, z_err, data):
            problem = self.problem
            q0, qd0, _ = y0
            D, I = data
            v, vd, w = z1
            # Newton starts from the last accepted state moved on by its velocity: near a
            # bifurcation (a parallelogram's flat position) the old positions alone are as
            # near the other branch as the one the motion is on.
            q_ref = q0 + qd0 * (t1 - t0)
            if problem.sparse:
                q, qd, ratio = _complete_sparse(problem, q_ref, D, I, v, vd, t1, self.tol)
            else:
                q, qd = _complete(problem, q_ref, D, I, v, vd, t1, self.tol)
            viol = jnp.max(jnp.abs(problem.c(q, t1))) if problem.c.m else jnp.zeros(())
            err = None if self.fixed else self._full_error(q0, t0, D, I, z_err)
            if problem.sparse:
                # Choose again (dense pivoted LU, in a branch taken only then) when the
                # current dependent block's factorization becomes ill-conditioned.
                D, I = jax.lax.cond(
                    ~(ratio >= RECHOOSE_RATIO), lambda: _choose(problem, q, t1), lambda: (D, I)
                )
            else:
                # Choose again when the current dependent block is much worse than a fresh
                # choice.
                D_new, I_new = _choose(problem, q, t1)
                worse = _conditioning(problem, q, t1, D) < 0.5 * _conditioning(
                    problem, q, t1, D_new
                )
                D = jnp.where(worse, D_new, D)
                I = jnp.where(worse, I_new, I)
            return (q, qd, w), err, (D, I), jnp.asarray(True), viol

        def _full_error(self, q_ref, t0, D, I, z_err):
            """The error of every coordinate: an error ``dv`` of the independent ones moves
            the dependent ones by ``-Phi_qD^-1 Phi_qI dv``, which may be much larger."""
            problem = self.problem
            ev, evd, ew = z_err
            if problem.sparse:
                c = problem.c
                vals = c.jacobian_values(q_ref, t0)
                solve, _ = _dependent_solver(problem, q_ref, t0, D, vals)
                E = jnp.stack(
                    [
                        solve(c.matvec(vals, jnp.zeros_like(q_ref).at[I].set(e)))[D]
                        for e in (ev, evd)
                    ],
                    axis=1,
                )
            else:
                J = problem.c.phi_q(q_ref, t0)
                E, _ = lu_solve_checked(J[:, D], J[:, I] @ jnp.stack([ev, evd], axis=1))
            full = lambda e, k: jnp.zeros_like(q_ref).at[I].set(e).at[D].set(-E[:, k])  # noqa: E731
            return full(ev, 0), full(evd, 1), jnp.zeros_like(ew)

    return Partitioned


@eqx.filter_jit
def partitioning(
    problem: Problem,
    ts,
    q0,
    qd0,
    *,
    rtol=1e-8,
    atol=1e-10,
    dt=None,
    solver="tsit5",
    max_steps=1_000_000,
    first_step=None,
    progress=None,
) -> Trajectory:
    """Integrate the independent coordinates; solve the dependent ones by Newton.

    Args: as :func:`~.projection.projection`.
    """
    from . import _constrained as cs

    tol = 1e-3 * jnp.asarray(atol, ts.dtype)

    def f(t, z, args):
        v, vd, _ = z
        q_ref, qd_ref, D, I, t_ref = args
        q, qd = _complete(problem, q_ref + qd_ref * (t - t_ref), D, I, v, vd, t, tol)
        qdd, _, _ = problem.accelerations(q, qd, t)
        return (vd, qdd[I], problem.work_rates(q, qd, t, qdd))

    def f_full(t, y, args):
        q, qd, _ = y
        qdd, _, _ = problem.accelerations(q, qd, t)
        return (qd, qdd, problem.work_rates(q, qd, t, qdd))

    dt_min = cs.DT_MIN * jnp.maximum(jnp.max(jnp.abs(ts)), 1.0)
    step = _solver_class()(
        cs.runge_kutta(solver), dt_min, dt is not None, ts, problem, tol, cs.ode_term(f)
    )
    span = ts[-1] - ts[0]
    h0 = jnp.minimum(span * 1e-4, ts[1] - ts[0]) if ts.shape[0] > 1 else span
    if first_step is not None:
        h0 = jnp.asarray(first_step, dtype=ts.dtype)
    ctrl = cs.controller(
        ts,
        rtol=rtol,
        atol=atol,
        norm=cs.rms_of_first(2),
        h0=h0,
        dt=dt,
        dt_min=dt_min,
        progress=progress,
    )
    (q, qd, w), n, nrej, viol, status, t, y_last = cs.solve(
        cs.ode_term(f_full), step, (q0, qd0, jnp.zeros(2)), ctrl, max_steps=max_steps
    )
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[0])
