"""``projection``: adaptive explicit Runge–Kutta (diffrax Tsit5, Dopri5 or Dopri8) on the
index-1 equations, with positions and velocities projected back onto the constraints after
each accepted step (mass-weighted least-norm projection)."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._problem import Problem
from ._common import Trajectory, adaptive_loop, ode_term, runge_kutta


def _vector_field(problem: Problem):
    def f(t, y, args):
        q, qd, _ = y
        qdd, _, _ = problem.accelerations(q, qd, t)
        return (qd, qdd, problem.work_rates(q, qd, t, qdd))

    return ode_term(f)


@eqx.filter_jit
def projection(
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
    """Integrate with an adaptive explicit RK method and project after every step.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time]; ``ts[0]`` is the start.
        q0, qd0: (nq,) consistent initial state.
        rtol, atol: tolerances of the local error (on ``q`` and ``qd``, model units).
        dt: a fixed step [time] instead of error control (for convergence studies).
        solver: ``"tsit5"`` (order 5), ``"dopri5"`` or ``"dopri8"`` (order 8).
        max_steps: step limit.
        first_step: the first step's size [time] (default: 1e-4 of the span or the first
            output interval, whichever is shorter); the controller adapts it from there.
        progress: optional callback ``f(t)`` at each output time.
    """
    rk, order = runge_kutta(solver)
    term = _vector_field(problem)
    tol_pos = 1e-3 * atol

    def step(t0, t1, y, args):
        state = rk.init(term, t0, t1, y, None)
        y1, yerr, _, _, _ = rk.step(term, t0, t1, y, None, state, made_jump=False)
        return y1, yerr[:2], y[:2], y1[:2]

    # A projection that cannot close the constraints (past a dead point, at a lock-up) is a
    # rejected step; a step size that collapses on it is then a named failure.
    tol_closed = 1e-6 * jnp.maximum(jnp.max(jnp.abs(q0)), 1.0)

    def accept(t1, y1, args):
        q, qd, w = y1
        viol = jnp.max(jnp.abs(problem.c(q, t1))) if problem.c.m else jnp.zeros(())
        q, residual = problem.project_positions(q, t1, tol_pos)
        qd = problem.project_velocities(q, qd, t1)
        return (q, qd, w), args, viol, residual <= tol_closed

    span = ts[-1] - ts[0]
    h0 = jnp.minimum(span * 1e-4, ts[1] - ts[0]) if ts.shape[0] > 1 else span
    if first_step is not None:
        h0 = jnp.asarray(first_step, dtype=ts.dtype)
    outs, _, n, nrej, viol, status, t, y_last = adaptive_loop(
        step,
        accept,
        ts,
        (q0, qd0, jnp.zeros(2)),
        jnp.zeros(()),
        rtol=rtol,
        atol=atol,
        order=order,
        dt=dt,
        h0=h0,
        max_steps=max_steps,
        progress=progress,
    )
    q, qd, w = outs
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[0])
