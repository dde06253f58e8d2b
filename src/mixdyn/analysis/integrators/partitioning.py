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
from ._common import Trajectory, adaptive_loop, ode_term, runge_kutta

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
    rk, order = runge_kutta(solver)
    tol = 1e-3 * atol
    t0 = ts[0]
    D0, I0 = _choose(problem, q0, t0)

    def predicted(args, t):
        # Newton starts from the last accepted state moved on by its velocity: near a
        # bifurcation (a parallelogram's flat position) the old positions alone are as near
        # the other branch as the one the motion is on.
        q_ref, qd_ref, _, _, t_ref = args
        return q_ref + qd_ref * (t - t_ref)

    def f(t, y, args):
        v, vd, _ = y
        _, _, D, I, _ = args
        q, qd = _complete(problem, predicted(args, t), D, I, v, vd, t, tol)
        qdd, _, _ = problem.accelerations(q, qd, t)
        return (vd, qdd[I], problem.work_rates(q, qd, t, qdd))

    term = ode_term(f)

    def step(t0, t1, y, args):
        state = rk.init(term, t0, t1, y, args)
        y1, yerr, _, _, _ = rk.step(term, t0, t1, y, args, state, made_jump=False)
        # Control the error of every coordinate: an error dv of the independent ones moves
        # the dependent ones by -Phi_qD^-1 Phi_qI dv, which may be much larger.
        q_ref, qd_ref, D, I, _ = args
        if problem.sparse:
            c = problem.c
            vals = c.jacobian_values(q_ref, t0)
            solve, _ = _dependent_solver(problem, q_ref, t0, D, vals)
            E = jnp.stack(
                [solve(c.matvec(vals, jnp.zeros_like(q_ref).at[I].set(e)))[D] for e in yerr[:2]],
                axis=1,
            )
        else:
            J = problem.c.phi_q(q_ref, t0)
            E, _ = lu_solve_checked(J[:, D], J[:, I] @ jnp.stack([yerr[0], yerr[1]], axis=1))
        full_err = (jnp.concatenate([yerr[0], -E[:, 0]]), jnp.concatenate([yerr[1], -E[:, 1]]))
        full0 = (jnp.concatenate([y[0], q_ref[D]]), jnp.concatenate([y[1], qd_ref[D]]))
        return y1, full_err, full0, full0

    def accept(t1, y1, args):
        v, vd, w = y1
        _, _, D, I, _ = args
        q_ref = predicted(args, t1)
        if problem.sparse:
            q, qd, ratio = _complete_sparse(problem, q_ref, D, I, v, vd, t1, tol)
        else:
            q, qd = _complete(problem, q_ref, D, I, v, vd, t1, tol)
        viol = jnp.max(jnp.abs(problem.c(q, t1))) if problem.c.m else jnp.zeros(())
        if problem.sparse:
            # Choose again (dense pivoted LU, in a branch taken only then) when the current
            # dependent block's factorization becomes ill-conditioned.
            D, I = jax.lax.cond(
                ~(ratio >= RECHOOSE_RATIO), lambda: _choose(problem, q, t1), lambda: (D, I)
            )
        else:
            # Choose again when the current dependent block is much worse than a fresh choice.
            D_new, I_new = _choose(problem, q, t1)
            switch = _conditioning(problem, q, t1, D) < 0.5 * _conditioning(problem, q, t1, D_new)
            D = jnp.where(switch, D_new, D)
            I = jnp.where(switch, I_new, I)
        return (q[I], qd[I], w), (q, qd, D, I, t1), viol

    span = ts[-1] - ts[0]
    h0 = jnp.minimum(span * 1e-4, ts[1] - ts[0]) if ts.shape[0] > 1 else span
    if first_step is not None:
        h0 = jnp.asarray(first_step, dtype=ts.dtype)
    # Outputs carry the full state through args; integrate (v, vd, w) and rebuild q at outputs.
    y0 = (q0[I0], qd0[I0], jnp.zeros(2))
    full0 = (q0, qd0)

    def step_full(t0, t1, yfull, args):
        y, _ = yfull
        y1, yerr, a, b = step(t0, t1, y, args)
        return (y1, full0), yerr, a, b

    def accept_full(t1, yfull, args):
        y, _ = yfull
        y1, args1, viol = accept(t1, y, args)
        q, qd, _, _, _ = args1
        return (y1, (q, qd)), args1, viol

    outs, _, n, nrej, viol, status, t, y_last = adaptive_loop(
        step_full,
        accept_full,
        ts,
        (y0, full0),
        (q0, qd0, D0, I0, jnp.asarray(t0, dtype=ts.dtype)),
        rtol=rtol,
        atol=atol,
        order=order,
        dt=dt,
        h0=h0,
        max_steps=max_steps,
        progress=progress,
    )
    (_, _, w), (q, qd) = outs
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[1][0])
