"""``generalized-alpha``: implicit, index 3 (Arnold & Brüls, *Multibody System Dynamics* 18,
2007), Newton on the full system ``M qdd + G mu = Q``, ``Phi(q, t) = 0``, for stiff springs.

Second order; numerical damping set by ``rho_inf`` (1: none, 0: asymptotic annihilation).
After each step the velocities are projected onto ``Phi_q qd + Phi_t = 0`` (optional), which
removes the index-3 velocity drift.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._problem import Problem
from ._common import NEWTON_FAILED, NOT_FINITE, OK, Trajectory


def coefficients(rho_inf):
    """``(alpha_m, alpha_f, gamma, beta)`` of Chung & Hulbert / Arnold & Brüls."""
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    g = 0.5 + af - am
    b = 0.25 * (g + 0.5) ** 2
    return am, af, g, b


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
        project_velocities: project velocities onto the velocity constraints after a step.
    """
    am, af, gm, bt = coefficients(rho_inf)
    Minv = problem.Minv
    Mdiag = problem.model.mass_diagonal
    n = q0.shape[0]
    m = problem.c.m
    qdd0, mu0, _ = problem.accelerations(q0, qd0, ts[0])
    fscale = jnp.maximum(
        jnp.max(jnp.abs(Mdiag * qdd0)) + jnp.max(jnp.abs(problem.known_forces(q0, qd0, ts[0]))),
        1e-300,
    )
    lscale = jnp.maximum(jnp.max(jnp.abs(q0)), 1.0)
    ftol = 1e-10 * fscale if tol is None else tol
    ptol = 1e-13 * lscale
    del Minv

    def one_step(state, h, t1):
        q, qd, a, qdd, mu, w, newt = state
        beta_p = h**2 * bt * (1 - af) / (1 - am)
        gamma_p = h * gm * (1 - af) / (1 - am)

        def predict(x):
            qdd1, _ = x[:n], x[n:]
            a1 = ((1 - af) * qdd1 + af * qdd - am * a) / (1 - am)
            q1 = q + h * qd + h**2 * (0.5 - bt) * a + h**2 * bt * a1
            qd1 = qd + h * (1 - gm) * a + h * gm * a1
            return q1, qd1, a1

        def residual(x):
            qdd1, mu1 = x[:n], x[n:]
            q1, qd1, _ = predict(x)
            C = problem.c.phi_q(q1, t1)
            r1 = Mdiag * qdd1 + problem.G(q1, qd1, t1, C) @ mu1 - problem.known_forces(q1, qd1, t1)
            r2 = problem.c(q1, t1) / beta_p
            return jnp.concatenate([r1, r2])

        def error(x):
            r = residual(x)
            # Force residual against ftol; position residual (r2 * beta_p) against ptol.
            return jnp.maximum(
                jnp.max(jnp.abs(r[:n])) / ftol, jnp.max(jnp.abs(r[n:]) * beta_p, initial=0.0) / ptol
            )

        def cond(s):
            _, it, res, _ = s
            return (res > 1.0) & (it < max_newton) & jnp.isfinite(res)

        def body(s):
            x, it, _, _ = s
            J = jax.jacfwd(residual)(x)
            dx, ratio = problem.c.solve(J, residual(x), extra_rank=n)
            x = x - dx
            return x, it + 1, error(x), ratio

        x0 = jnp.concatenate([qdd, mu])
        x, it, res, _ = jax.lax.while_loop(cond, body, (x0, 0, error(x0), jnp.asarray(1.0)))
        del gamma_p
        q1, qd1, a1 = predict(x)
        qdd1, mu1 = x[:n], x[n:]
        if project_velocities:
            qd1 = problem.project_velocities(q1, qd1, t1)
        rates0 = problem.work_rates(q, qd, t1 - h, qdd)
        rates1 = problem.work_rates(q1, qd1, t1, qdd1)
        w1 = w + 0.5 * h * (rates0 + rates1)
        ok = res <= 1.0
        return (q1, qd1, a1, qdd1, mu1, w1, newt + it), ok, jnp.isfinite(res)

    N = ts.shape[0]
    zeros = jnp.zeros((N, n))
    init = (
        jnp.asarray(1),
        (q0, qd0, qdd0, qdd0, mu0, jnp.zeros(2), jnp.asarray(0)),
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
