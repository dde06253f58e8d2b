"""``baumgarte``: the classic textbook baseline. Fixed-step classical Runge–Kutta (order 4) on
the index-1 equations with Baumgarte stabilization of the acceleration constraints,
``C qdd = gamma - 2 alpha Phi_dot - beta**2 Phi``; no projection."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._problem import Problem
from ._common import Trajectory, adaptive_loop


@eqx.filter_jit
def baumgarte(
    problem: Problem,
    ts,
    q0,
    qd0,
    *,
    dt,
    alpha=10.0,
    beta=10.0,
    max_steps=10_000_000,
    progress=None,
) -> Trajectory:
    """Integrate with fixed-step RK4 and Baumgarte stabilization.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time].
        q0, qd0: (nq,) consistent initial state.
        dt: step [time]; shortened where needed to land on the output times.
        alpha, beta: stabilization parameters [1/time].
    """

    def f(t, y):
        q, qd, _ = y
        qdd, _, _ = problem.accelerations(q, qd, t, alpha, beta)
        return (qd, qdd, problem.work_rates(q, qd, t, qdd))

    def step(t0, t1, y, args):
        h = t1 - t0

        def add(y, k, c):
            return jax.tree.map(lambda a, b: a + c * b, y, k)

        k1 = f(t0, y)
        k2 = f(t0 + h / 2, add(y, k1, h / 2))
        k3 = f(t0 + h / 2, add(y, k2, h / 2))
        k4 = f(t1, add(y, k3, h))
        y1 = jax.tree.map(
            lambda a, b, c, d, e: a + h / 6 * (b + 2 * c + 2 * d + e), y, k1, k2, k3, k4
        )
        return y1, None, None, None

    def accept(t1, y1, args):
        viol = jnp.max(jnp.abs(problem.c(y1[0], t1))) if problem.c.m else jnp.zeros(())
        return y1, args, viol

    outs, _, n, nrej, viol, status, t, y_last = adaptive_loop(
        step,
        accept,
        ts,
        (q0, qd0, jnp.zeros(2)),
        jnp.zeros(()),
        rtol=0.0,
        atol=0.0,
        order=4,
        dt=dt,
        h0=dt,
        max_steps=max_steps,
        progress=progress,
    )
    q, qd, w = outs
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[0])
