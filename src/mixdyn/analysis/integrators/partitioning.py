"""``partitioning``: Wehage–Haug generalized coordinate partitioning, the paper's family.

The coordinates split into dependent ``D`` (as many as constraint rows, chosen by pivoted LU on
``Phi_q`` so that ``Phi_qD`` is well conditioned) and independent ``I``. Only the independent
positions and velocities are integrated (adaptive explicit RK from diffrax); at every stage the
dependent positions are solved from ``Phi(q, t) = 0`` by Newton and the dependent velocities
from ``Phi_q qd = -Phi_t``, so the constraints hold to Newton tolerance throughout.

The dependent solves go through the constraint set's operator
(:meth:`~mixdyn.equations.JacobianOperator.partition`): the LU of ``Phi_qD`` on the dense path,
a minimum-norm solve with weights 1 on ``D`` and 0 on ``I`` through the banded Cholesky
factorization of ``Phi_q W Phi_q^T`` on the sparse one (one pattern whatever the partition).
A better partition is looked for when the dependent block's pivot ratio has fallen below
:data:`RECHOOSE_FACTOR` times its ratio when chosen, and taken when clearly better.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._problem import Problem, pivot_columns
from ..methods import Partitioning
from ._common import Trajectory

#: A better partition is looked for (pivoted LU of ``Phi_q^T``) when the pivot ratio of the
#: dependent block ``Phi_qD`` (:meth:`~mixdyn.equations.JacobianOperator.partition`) has fallen
#: below this fraction of its ratio when chosen (or last looked at), and taken when its block's
#: ratio is at least twice the current one. (A fixed threshold, 1e-4, let the paper mechanism's
#: block degrade far enough to break the energy balance by 1e-7 at t = 0.7; a fresh choice at
#: every step costs a dense LU per step.)
RECHOOSE_FACTOR = 0.5


def _complete(problem: Problem, q_ref, D, I, v, vd, t, tol, iters=8):
    """Full ``(q, qd)`` from independent ``(v, vd)``: the dependent positions by Newton from
    ``q_ref`` (a fixed number of iterations, each skipped once the residual is below ``tol``:
    a loop of static length, which reverse-mode differentiation goes through; a sweep's
    one program stops once all its members are closed), the dependent
    velocities from ``Phi_q qd = -Phi_t``; also the pivot ratio of the final ``Phi_qD``."""
    c = problem.c
    q = q_ref.at[I].set(v)

    def newton(q, r):
        return q - c.jacobian(q, t).partition(D).solve(r)

    def far(r):
        return jnp.max(jnp.abs(r), initial=0.0) > tol

    if c.batched:
        # A sweep's one program (not differentiated): under ``vmap`` a ``cond`` runs its
        # branch for every member; this loop stops once every member is closed (the
        # residual carried, evaluated once per step).
        def go_on(state):
            k, _, r = state
            return (k < iters) & far(r)

        def step(state):
            k, q, r = state
            q = newton(q, r)
            return k + 1, q, c(q, t)

        _, q, _ = jax.lax.while_loop(go_on, step, (0, q, c(q, t)))
    else:

        def body(_, q):
            r = c(q, t)
            # Once closed, the Jacobian and its solve are skipped (a ``cond``, not a
            # ``where`` that computes them anyway): most stages close in one or two steps.
            return jax.lax.cond(far(r), newton, lambda q, r: q, q, r)

        q = jax.lax.fori_loop(0, iters, body, q)
    J = c.jacobian(q, t)
    f = J.partition(D)
    qd_i = jnp.zeros_like(q).at[I].set(vd)
    return q, qd_i + f.solve(-c.phi_t(q, t) - J.mv(qd_i)), f.ratio


def _choose(problem: Problem, q, t):
    """A partition ``(D, I)`` with a well-conditioned dependent block: pivoted LU of
    ``Phi_q^T`` (dense, done at the start and where the block degrades); and the block's
    pivot ratio."""
    D, I = pivot_columns(problem.c.phi_q(q, t), problem.c.m)
    return D, I, problem.c.jacobian(q, t).partition(D).ratio


@eqx.filter_jit  # traced once, however often diffrax traces its loop's body
def _finish(problem: Problem, tol, fixed: bool, t0, t1, y0, z1, z_err, data):
    """The end of a partitioning step (:meth:`ConstrainedSolver.finish`): the dependent
    coordinates completed, the error of every coordinate, and the partition kept or chosen
    again."""
    q0, qd0, _ = y0
    D, I, chosen = data
    v, vd, w = z1
    # Newton starts from the last accepted state moved on by its velocity: near a bifurcation
    # (a parallelogram's flat position) the old positions alone are as near the other branch
    # as the one the motion is on.
    q_ref = q0 + qd0 * (t1 - t0)
    q, qd, ratio = _complete(problem, q_ref, D, I, v, vd, t1, tol)
    qd, w = problem.halt_sticking(q, qd, w, t1, q0, qd0)  # sticking elements at rest
    viol = jnp.max(jnp.abs(problem.c(q, t1))) if problem.c.m else jnp.zeros(())
    err = None if fixed else _full_error(problem, q0, t0, D, I, z_err)

    # Look for a better partition (a dense pivoted LU, in a branch taken only then) once the
    # block has degraded; take it if its block is clearly better.
    def look():
        fresh = _choose(problem, q, t1)
        better = fresh[2] > 2.0 * ratio
        # no better one: look again only after the block degrades further
        return jax.tree.map(
            lambda a, b: jnp.where(better, a, b), fresh, (D, I, jnp.minimum(chosen, ratio))
        )

    data = jax.lax.cond(~(ratio >= RECHOOSE_FACTOR * chosen), look, lambda: (D, I, chosen))
    return (q, qd, w), err, data, jnp.asarray(True), viol


def _full_error(problem: Problem, q_ref, t0, D, I, z_err):
    """The error of every coordinate: an error ``dv`` of the independent ones moves the
    dependent ones by ``-Phi_qD^-1 Phi_qI dv``, which may be much larger."""
    ev, evd, ew = z_err
    J = problem.c.jacobian(q_ref, t0)
    solve = J.partition(D).solve
    E = jnp.stack([solve(J.mv(jnp.zeros_like(q_ref).at[I].set(e)))[D] for e in (ev, evd)], axis=1)
    full = lambda e, k: jnp.zeros_like(q_ref).at[I].set(e).at[D].set(-E[:, k])  # noqa: E731
    return full(ev, 0), full(evd, 1), jnp.zeros_like(ew)


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
            D, I, _ = data
            return (q[I], qd[I], w), (q, qd, D, I, t)

        def finish(self, t0, t1, y0, z1, z_err, data):
            return _finish(self.problem, self.tol, self.fixed, t0, t1, y0, z1, z_err, data)

    return Partitioned


@eqx.filter_jit
def partitioning(
    problem: Problem, ts, q0, qd0, options: Partitioning, progress=None, derivatives=None
) -> Trajectory:
    """Integrate the independent coordinates; solve the dependent ones by Newton.

    Args: as :func:`~.projection.projection` (``options``: a
    :class:`~mixdyn.analysis.methods.Partitioning`).
    """
    from . import _constrained as cs

    rtol, atol, dt = options.rtol, options.atol, options.dt
    tol = 1e-3 * jnp.asarray(atol, ts.dtype)

    @jax.jit  # traced once, however often diffrax traces its loop's body
    def f(t, z, args):
        v, vd, _ = z
        q_ref, qd_ref, D, I, t_ref = args
        q, qd, _ = _complete(problem, q_ref + qd_ref * (t - t_ref), D, I, v, vd, t, tol)
        qdd, mu, _ = problem.accelerations(q, qd, t)
        return (vd, qdd[I], problem.work_rates(q, qd, t, qdd, mu))

    f_full = cs.equations_of_motion(problem)  # diffeqsolve's term (checked, not stepped)
    dt_min = cs.DT_MIN * jnp.maximum(jnp.max(jnp.abs(ts)), 1.0)
    step = _solver_class()(
        cs.runge_kutta(options.solver), dt_min, dt is not None, ts, problem, tol, cs.ode_term(f)
    )
    h0 = cs.first_step_size(ts, options.first_step)
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
        cs.ode_term(f_full),
        step,
        (q0, qd0, jnp.zeros(2)),
        ctrl,
        max_steps=options.max_steps,
        derivatives=derivatives,
    )
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[0])
