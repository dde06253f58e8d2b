"""``generalized-alpha``: implicit, index 3 (Arnold & Brüls, *Multibody System Dynamics* 18,
2007), Newton on the full system ``M qdd + G mu = Q``, ``Phi(q, t) = 0``, for stiff springs.

Second order; numerical damping set by ``rho_inf`` (1: none, 0: asymptotic annihilation).
After each step the velocities are projected onto ``Phi_q qd + Phi_t = 0`` (optional), which
removes the index-3 velocity drift.

The Newton iteration of a step solves for ``x = (qdd1, mu1)`` the residual
``r1 = M qdd1 + G(q1) mu1 - Q(q1, qd1)``, ``r2 = Phi(q1) / beta'``, where
``q1 = q_pred + beta' qdd1``, ``qd1 = qd_pred + gamma' qdd1`` (``beta' ~ h^2 / 4``). Its exact
Jacobian is ``[[M + beta' (K_c - Q_q) - gamma' Q_qd, G], [C, 0]]`` (``K_c`` the derivative
of ``G mu`` with respect to ``q``, ``C = Phi_q``). Two iterations are available:

* *modified* Newton drops the ``O(beta')`` stiffness and damping terms: the matrix
  ``[[M, G], [C(q1), 0]]`` is the acceleration-level KKT matrix, solved by the Schur
  complement ``C M^-1 G`` (dense, or sparse on the sparse path) without any Jacobian of the
  residual. It contracts by a factor ``~ beta' |K| / M`` per iteration (``~1e-3`` for
  pendulum chains at ``h = 1e-3``);
* *full* Newton builds the exact matrix by forward differentiation of the residual (dense,
  ``(nq + m)`` directions) and solves it by dense LU: quadratic convergence, for stiff forces
  (``h^2 K / M`` not small) where the modified iteration contracts slowly or diverges.

``newton="auto"`` (the default) starts each step with the modified iteration and switches,
within the step, to full Newton from the best iterate as soon as an iteration contracts the
error by less than :data:`SWITCH_RATE` (or diverges), or half of ``max_newton`` is used.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ...errors import ModelError
from ...linalg import solve_kkt, solve_ranked
from ...linalg._dense import SINGULAR_RATIO, SINGULAR_RCOND
from .._problem import Problem
from ._common import NEWTON_FAILED, NOT_FINITE, OK, Trajectory

#: The Newton iterations of ``newton=...`` (see the module docstring).
NEWTON_CHOICES = ("auto", "modified", "full")
#: ``newton="auto"``: an iteration of the modified Newton method that does not reduce the
#: scaled error at least by this factor makes the step switch to full Newton.
SWITCH_RATE = 0.5


def coefficients(rho_inf):
    """``(alpha_m, alpha_f, gamma, beta)`` of Chung & Hulbert / Arnold & Brüls."""
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    g = 0.5 + af - am
    b = 0.25 * (g + 0.5) ** 2
    return am, af, g, b


def _linear_algebra(problem: Problem):
    """``(linearize, constraint_force, kkt_solve)`` on the problem's linear-solver path.

    ``linearize(q, t)``: ``Phi_q`` (dense (m, nq), or its values on the sparse pattern);
    ``constraint_force(q, qd, t, lin, mu)``: ``G mu`` (nq,);
    ``kkt_solve(q, qd, t, lin, r1, r2)``: ``(dqdd, dmu)`` solving
    ``[[M, G], [C, 0]] [dqdd; dmu] = [r1; r2]``.
    """
    c, Minv = problem.c, problem.Minv
    if problem.sparse:

        def linearize(q, t):
            return c.jacobian_values(q, t)

        def constraint_force(q, qd, t, v, mu):
            return c.rmatvec(v, mu)

        def kkt_solve(q, qd, t, v, r1, r2):
            rhs = c.matvec(v, Minv * r1) - r2
            dmu, ratio = c.schur_solve(v, Minv, rhs)

            def truncated_svd():
                # At a singular position, as in Problem.accelerations (dense only there).
                C = c.phi_q(q, t)
                S = C @ (Minv[:, None] * C.T)
                return solve_ranked(S, rhs, None, rcond=SINGULAR_RCOND)[0]

            dmu = jax.lax.cond(ratio < SINGULAR_RATIO, truncated_svd, lambda: dmu)
            return Minv * (r1 - c.rmatvec(v, dmu)), dmu

        return linearize, constraint_force, kkt_solve

    def linearize(q, t):
        return c.phi_q(q, t)

    def constraint_force(q, qd, t, C, mu):
        return problem.G(q, qd, t, C) @ mu

    def kkt_solve(q, qd, t, C, r1, r2):
        dqdd, dmu, _ = solve_kkt(Minv, C, problem.G(q, qd, t, C), r1, r2, c.rank)
        return dqdd, dmu

    return linearize, constraint_force, kkt_solve


@eqx.filter_jit
def generalized_alpha(
    problem: Problem,
    ts,
    q0,
    qd0,
    *,
    dt,
    rho_inf=0.9,
    tol=None,
    max_newton=20,
    newton="auto",
    project_velocities=True,
    max_steps=10_000_000,
    progress=None,
    **_,
) -> Trajectory:
    """Integrate with the index-3 generalized-alpha method at fixed step ``dt``.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time].
        q0, qd0: (nq,) consistent initial state.
        dt: step [time]; each output interval is split into equal steps no longer than it.
        rho_inf: spectral radius at infinite frequency, in [0, 1].
        tol: Newton tolerance on the scaled residual (default ``1e-10 x`` force scale).
        max_newton: Newton iterations per step.
        newton: ``"auto"`` (default: modified Newton, switching to full Newton within a step
            where it contracts poorly, e.g. a stiff spring at a large step), ``"modified"``
            (the acceleration-level KKT matrix only: cheap, no Jacobian of the residual,
            sparse on the sparse path) or ``"full"`` (the exact Newton matrix, dense).
        project_velocities: project velocities onto the velocity constraints after a step.
    """
    if newton not in NEWTON_CHOICES:
        raise ModelError(
            f"newton must be one of {', '.join(NEWTON_CHOICES)}, got {newton!r}", "newton"
        )
    am, af, gm, bt = coefficients(rho_inf)
    Mdiag = problem.model.mass_diagonal
    n = q0.shape[0]
    m = problem.c.m
    linearize, constraint_force, kkt_solve = _linear_algebra(problem)
    qdd0, mu0, _ = problem.accelerations(q0, qd0, ts[0])
    fscale = jnp.maximum(
        jnp.max(jnp.abs(Mdiag * qdd0)) + jnp.max(jnp.abs(problem.known_forces(q0, qd0, ts[0]))),
        1e-300,
    )
    lscale = jnp.maximum(jnp.max(jnp.abs(q0)), 1.0)
    ftol = 1e-10 * fscale if tol is None else tol
    ptol = 1e-13 * lscale

    def one_step(state, h, t1):
        q, qd, a, qdd, mu, w, newt, x_old, h_old = state
        beta_p = h**2 * bt * (1 - af) / (1 - am)

        def predict(qdd1):
            a1 = ((1 - af) * qdd1 + af * qdd - am * a) / (1 - am)
            q1 = q + h * qd + h**2 * (0.5 - bt) * a + h**2 * bt * a1
            qd1 = qd + h * (1 - gm) * a + h * gm * a1
            return q1, qd1, a1

        def residual(x):
            """``(r (nq + m,), lin)``: the residual and ``Phi_q`` at the iterate's ``q1``."""
            qdd1, mu1 = x[:n], x[n:]
            q1, qd1, _ = predict(qdd1)
            lin = linearize(q1, t1)
            r1 = (
                Mdiag * qdd1
                + constraint_force(q1, qd1, t1, lin, mu1)
                - problem.known_forces(q1, qd1, t1)
            )
            r2 = problem.c(q1, t1) / beta_p
            return jnp.concatenate([r1, r2]), lin

        def error(r):
            # Force residual against ftol; position residual (r2 * beta_p) against ptol.
            return jnp.maximum(
                jnp.max(jnp.abs(r[:n])) / ftol, jnp.max(jnp.abs(r[n:]) * beta_p, initial=0.0) / ptol
            )

        def modified_dx(x, r, lin):
            q1, qd1, _ = predict(x[:n])
            dqdd, dmu = kkt_solve(q1, qd1, t1, lin, r[:n], r[n:])
            return jnp.concatenate([dqdd, dmu])

        def full_dx(x, r, lin):
            J = jax.jacfwd(lambda x: residual(x)[0])(x)
            return problem.c.solve(J, r, extra_rank=n)[0]

        def cond(s):
            _, _, _, res, it, _ = s
            return (res > 1.0) & (it < max_newton) & jnp.isfinite(res)

        def body(s):
            x, r, lin, res, it, full = s
            if newton == "modified":
                dx = modified_dx(x, r, lin)
            elif newton == "full":
                dx = full_dx(x, r, lin)
            else:
                dx = jax.lax.cond(full, full_dx, modified_dx, x, r, lin)
            x1 = x - dx
            r1, lin1 = residual(x1)
            res1 = error(r1)
            if newton == "auto":
                # A modified iteration that contracts poorly, or has used half the budget,
                # hands the step to full Newton, from the better of the last two iterates.
                slow = ~full & ~(res1 <= 1.0)
                slow = slow & (~(res1 <= SWITCH_RATE * res) | (it + 1 >= max_newton // 2))
                back = slow & ~(res1 < res)
                x1, r1, lin1, res1 = jax.tree.map(
                    lambda old, new: jnp.where(back, old, new),
                    (x, r, lin, res),
                    (x1, r1, lin1, res1),
                )
                full = full | slow
            return x1, r1, lin1, res1, it + 1, full

        # Starting iterate: (qdd, mu) extrapolated linearly from the last two steps.
        x_last = jnp.concatenate([qdd, mu])
        x0 = x_last + (h / h_old) * (x_last - x_old)
        r0, lin0 = residual(x0)
        init = (x0, r0, lin0, error(r0), 0, jnp.asarray(newton == "full"))
        x, _, _, res, it, _ = jax.lax.while_loop(cond, body, init)
        q1, qd1, a1 = predict(x[:n])
        qdd1, mu1 = x[:n], x[n:]
        if project_velocities:
            qd1 = problem.project_velocities(q1, qd1, t1)
        rates0 = problem.work_rates(q, qd, t1 - h, qdd)
        rates1 = problem.work_rates(q1, qd1, t1, qdd1)
        w1 = w + 0.5 * h * (rates0 + rates1)
        ok = res <= 1.0
        return (q1, qd1, a1, qdd1, mu1, w1, newt + it, x_last, h), ok, jnp.isfinite(res)

    N = ts.shape[0]
    zeros = jnp.zeros((N, n))
    init = (
        jnp.asarray(1),
        (
            q0,
            qd0,
            qdd0,
            qdd0,
            mu0,
            jnp.zeros(2),
            jnp.asarray(0),
            jnp.concatenate([qdd0, mu0]),
            jnp.ones((), ts.dtype),
        ),
        zeros.at[0].set(q0),
        zeros.at[0].set(qd0),
        jnp.zeros((N, 2)),
        jnp.asarray(0),
        jnp.asarray(OK),
        ts[0],
        jnp.asarray(0.0),
    )

    def outer_cond(s):
        k, _, _, _, _, _, status, _, _ = s
        return (k < N) & (status == OK)

    def outer_body(s):
        k, state, Q, QD, W, nsteps, status, t, viol = s
        span = ts[k] - ts[k - 1]
        nsub = jnp.maximum(jnp.ceil(span / dt * (1 - 1e-12)).astype(int), 1)
        h = span / nsub

        def inner_cond(c):
            i, _, st, _, _ = c
            return (i < nsub) & (st == OK)

        def inner_body(c):
            i, state, st, t, viol = c
            t1 = ts[k - 1] + (i + 1) * h
            new, ok, finite = one_step(state, h, t1)
            st = jnp.where(ok, st, jnp.where(finite, NEWTON_FAILED, NOT_FINITE))
            v = jnp.max(jnp.abs(problem.c(new[0], t1))) if m else jnp.zeros(())
            return i + 1, new, st, jnp.where(ok, t1, t), jnp.maximum(viol, v)

        i, state, status, t, viol = jax.lax.while_loop(
            inner_cond, inner_body, (0, state, status, t, viol)
        )
        if progress is not None:
            jax.debug.callback(progress, t)
        Q, QD, W = Q.at[k].set(state[0]), QD.at[k].set(state[1]), W.at[k].set(state[5])
        return k + 1, state, Q, QD, W, nsteps + i, status, t, viol

    _, state, Q, QD, W, nsteps, status, t, viol = jax.lax.while_loop(outer_cond, outer_body, init)
    del max_steps
    return Trajectory(Q, QD, W, nsteps, jnp.asarray(0), state[6], viol, status, t, state[0])
