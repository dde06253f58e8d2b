"""``projection``: adaptive explicit Runge–Kutta (diffrax Tsit5, Dopri5 or Dopri8) on the
index-1 equations, with positions and velocities projected back onto the constraints after
each accepted step (mass-weighted least-norm projection)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from .._problem import Problem
from ..methods import Projection
from ._common import Trajectory


@eqx.filter_jit  # traced once, however often diffrax traces its loop's body
def _project(p: Problem, q, qd, w, t, tol, start):
    """Positions, then velocities, projected on the constraints at ``t``, the sticking
    reaction-dependent elements brought to rest
    (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`, ``start``: the step's starting
    ``(q, qd)``; their stops' work added to ``w``); the position residual after and the
    violation before [length]."""
    viol = jnp.max(jnp.abs(p.c(q, t))) if p.c.m else jnp.zeros(())
    q, residual = p.project_positions(q, t, tol)
    qd, w = p.halt_sticking(q, p.project_velocities(q, qd, t), w, t, *start)
    return q, qd, w, residual, viol


def _solver_class():
    """The projection step as a diffrax wrapped solver (diffrax imported when traced)."""
    from ._constrained import ConstrainedSolver

    class Projected(ConstrainedSolver):
        """A Runge–Kutta step, then positions and velocities projected onto the constraints;
        a projection that cannot close the constraints (past a dead point, at a lock-up)
        rejects the step."""

        problem: Problem
        tol_pos: jax.Array
        tol_closed: jax.Array

        def finish(self, t0, t1, y0, z1, z_err, data):
            q, qd, w = z1
            q, qd, w, residual, viol = _project(self.problem, q, qd, w, t1, self.tol_pos, y0[:2])
            err = None if self.fixed else (z_err[0], z_err[1], jnp.zeros_like(w))
            return (q, qd, w), err, data, residual <= self.tol_closed, viol

    return Projected


@eqx.filter_jit
def projection(
    problem: Problem, ts, q0, qd0, options: Projection, progress=None, derivatives=None
) -> Trajectory:
    """Integrate with an adaptive explicit RK method and project after every step.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time]; ``ts[0]`` is the start.
        q0, qd0: (nq,) consistent initial state.
        options: the method's options (:class:`~mixdyn.analysis.methods.Projection`: the
            tolerances, a fixed step ``dt``, the Runge–Kutta ``solver``, ``max_steps``,
            ``first_step``); the tolerances and first step may be arrays.
        progress: optional callback ``f(t)`` at each output time.
        derivatives: None (default: a run; reverse mode passes through it), ``"reverse"``
            (a run made for reverse mode: outputs in diffrax's buffers) or ``"forward"``:
            the mode of differentiation (:func:`~mixdyn.differentiable`).
    """
    from . import _constrained as cs

    rtol, atol, dt = options.rtol, options.atol, options.dt
    f = cs.equations_of_motion(problem)
    dt_min = cs.DT_MIN * jnp.maximum(jnp.max(jnp.abs(ts)), 1.0)
    step = _solver_class()(
        cs.runge_kutta(options.solver),
        dt_min,
        dt is not None,
        ts,
        problem,
        1e-3 * jnp.asarray(atol, ts.dtype),
        1e-6 * jnp.maximum(jnp.max(jnp.abs(q0)), 1.0),
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
        cs.ode_term(f),
        step,
        (q0, qd0, jnp.zeros(2)),
        ctrl,
        max_steps=options.max_steps,
        derivatives=derivatives,
    )
    return Trajectory(q, qd, w, n, nrej, jnp.asarray(0), viol, status, t, y_last[0])
