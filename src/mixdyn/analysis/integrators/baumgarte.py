"""``baumgarte``: the classic textbook baseline. Fixed-step classical Runge–Kutta (order 4) on
the index-1 equations with Baumgarte stabilization of the acceleration constraints,
``C qdd = gamma - 2 alpha Phi_dot - beta**2 Phi``; no projection."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._problem import Problem
from ..methods import Baumgarte
from ._common import Trajectory


def _solver_class():
    """The Baumgarte step as a diffrax wrapped solver (diffrax imported when traced)."""
    from ._constrained import ConstrainedSolver

    class Stabilized(ConstrainedSolver):
        """A classical RK4 step; the drift from the constraints is measured, not removed."""

        problem: Problem

        def finish(self, t0, t1, y0, z1, z_err, data):
            c = self.problem.c
            q, qd, w = z1
            viol = jnp.max(jnp.abs(c(q, t1))) if c.m else jnp.zeros(())
            qd, w = self.problem.halt_sticking(q, qd, w, t1, *y0[:2])  # stuck joints at rest
            return (q, qd, w), None, data, jnp.asarray(True), viol

    return Stabilized


@eqx.filter_jit
def baumgarte(
    problem: Problem, ts, q0, qd0, options: Baumgarte, progress=None, derivatives=None
) -> Trajectory:
    """Integrate with fixed-step RK4 and Baumgarte stabilization.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time].
        q0, qd0: (nq,) consistent initial state.
        options: the method's options (:class:`~mixdyn.analysis.methods.Baumgarte`: the step
            ``dt`` [time], shortened where needed to land on the output times; ``alpha``,
            ``beta`` [1/time]; ``max_steps``).
        progress: optional callback ``f(t)`` at each output time.
        derivatives: None (default: a run; reverse mode passes through it), ``"reverse"``
            (a run made for reverse mode: outputs in diffrax's buffers) or ``"forward"``:
            the mode of differentiation (:func:`~mixdyn.differentiable`).
    """
    from . import _constrained as cs

    f = cs.equations_of_motion(problem, options.alpha, options.beta)
    step = _solver_class()(cs.RK4(), jnp.zeros((), ts.dtype), True, ts, problem)
    ctrl = cs.controller(
        ts, rtol=0.0, atol=0.0, norm=None, dt=options.dt, dt_min=None, progress=progress
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
