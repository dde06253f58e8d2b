"""The explicit integrators on diffrax: ``diffeqsolve`` with a Runge–Kutta method wrapped so that
every step ends on the constraints.

- :class:`ConstrainedSolver` (a ``diffrax.AbstractWrappedSolver``) makes one step of the
  wrapped method and hands the result to :meth:`ConstrainedSolver.finish`, which each integrator
  defines: projection puts positions and velocities back on the constraints, partitioning
  completes the dependent coordinates from the independent ones, Baumgarte only measures the
  drift. A step that cannot be closed (or is not finite) is rejected (its error set to
  infinity); once the next try would fall below the controller's minimum step, the run ends
  with a named result (:func:`status`).
- The step size: integral control landing on every output time (:class:`Landing`, a diffrax
  step-size controller; diffrax's own PID controller clipped to the output times leaves
  slivers of steps that end runs), or a fixed step landing on them too (:class:`FixedStep`).
- Outputs: the state at the end of each step landing on an output time (the one put on the
  constraints), collected in the step-size controller's state (:func:`solve` says why not
  ``SaveAt(ts)``); the controller calls the progress callback there.

This module imports diffrax: it is imported when an integrator is traced, never by a run whose
programs come from the persistent cache.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ...runtime._private import chained_floor
from .. import _options
from ._common import MAX_STEPS, NOT_FINITE, OK, STEP_COLLAPSE, UNCLOSED, report_progress

#: The explicit Runge–Kutta methods of the adaptive integrators: diffrax's class name.
METHODS = {"tsit5": "Tsit5", "dopri5": "Dopri5", "dopri8": "Dopri8"}

#: The step-size controller's bounds on the change of the step (diffrax's defaults, and those
#: of the loop this replaced): at most 10x longer, at least 5x shorter after a rejection.
FACTOR_MAX, FACTOR_MIN, SAFETY = 10.0, 0.2, 0.9

#: A step shorter than this fraction of the time (at least 1) is a collapsed step
#: (:data:`mixdyn.analysis._options.DT_MIN`, which a first step is checked against).
DT_MIN = _options.DT_MIN


class RK4(diffrax.AbstractERK):
    """The classical fourth-order Runge–Kutta method, for fixed steps only: it has no
    embedded method, and its error estimate (zero) is never used (:class:`FixedStep`)."""

    tableau = diffrax.ButcherTableau(
        c=np.array([0.5, 0.5, 1.0]),
        b_sol=np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
        b_error=np.zeros(4),
        a_lower=(np.array([0.5]), np.array([0.0, 0.5]), np.array([0.0, 0.0, 1.0])),
    )
    interpolation_cls = diffrax.LocalLinearInterpolation

    def order(self, terms):
        return 4


class FirstStep(diffrax.PIDController):
    """diffrax's PID controller whose first step is ``first`` [time], for a ``diffeqsolve``
    given no ``dt0``: diffrax checks a traced ``dt0``'s sign by a host callback, which keeps
    the program from being exported to the persistent cache."""

    first: jax.Array | None = eqx.field(default=None, kw_only=True)

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        return super().init(terms, t0, t1, y0, self.first, args, func, error_order)


def equations_of_motion(problem, *stabilization):
    """The vector field of the whole state ``(q, qd, w)``: ``(qd, qdd, work rates)``
    (``stabilization``: Baumgarte's ``alpha, beta``), jitted so that diffrax's repeated traces
    of its loop body reuse one trace."""

    @jax.jit
    def f(t, y, args):
        q, qd, _ = y
        qdd, mu, _ = problem.accelerations(q, qd, t, *stabilization)
        return (qd, qdd, problem.work_rates(q, qd, t, qdd, mu))

    return f


def first_step_size(ts, first_step=None):
    """The first step [time]: ``first_step``, else 1e-4 of the span or the first output
    interval, whichever is shorter."""
    if first_step is not None:
        return jnp.asarray(first_step, dtype=ts.dtype)
    span = ts[-1] - ts[0]
    return jnp.minimum(span * 1e-4, ts[1] - ts[0]) if ts.shape[0] > 1 else span


def ode_term(f):
    """``diffrax.ODETerm(f)``."""
    return diffrax.ODETerm(f)


def runge_kutta(name: str):
    """A diffrax Runge–Kutta method by its name (a key of :data:`METHODS`)."""
    return getattr(diffrax, METHODS[name])()


class StepEnd(diffrax.LocalLinearInterpolation):
    """Linear interpolation within a step that gives the step's end state exactly at its
    end time (``y0 + 1.0 * (y1 - y0)`` may differ from ``y1`` in the last bit): diffrax's
    ``SaveAt(ts)`` evaluates it at output times, which are step ends (:class:`Landing`)."""

    def evaluate(self, t0, t1=None, left=True):
        out = super().evaluate(t0, t1, left)
        if t1 is not None:
            return out
        return jax.tree.map(lambda a, b: jnp.where(t0 == self.t1, b, a), out, self.y1)


class ConstrainedSolver(diffrax.AbstractWrappedSolver, diffrax.AbstractAdaptiveSolver):
    """A Runge–Kutta step followed by :meth:`finish`, which puts the state back on the
    constraints.

    The state ``y`` is ``(q, qd, w)``: (nq,) coordinates and velocities and the (2,)
    accumulated work. :meth:`reduce` gives the variables the wrapped method integrates and
    the ``args`` of the vector field (all of ``y`` for projection; the independent
    coordinates for partitioning); the solver state carries the integrator's own data between
    steps (kept only on accepted steps) and, last, the largest constraint violation met
    before :meth:`finish`.

    Attributes:
        solver: the wrapped method (a diffrax Runge–Kutta solver).
        dt_min: the controller's smallest step [time]: a step that cannot be closed and whose
            retry would be shorter ends the run (``nonlinear_divergence``, or ``nonfinite``
            for a non-finite state).
        fixed: whether the step is fixed (no error estimate; a step that cannot be closed ends
            the run at once).
        ts: (N,) output times [time] (the controller stores the state of a step ending on
            one, :class:`Landing`).
    """

    solver: diffrax.AbstractSolver
    dt_min: jax.Array
    fixed: bool = eqx.field(static=True)
    ts: jax.Array
    #: The Runge–Kutta stages' loop, set by diffrax's ``ForwardMode`` adjoint to ``"lax"`` (so
    #: that ``jax.jvp`` passes it) and handed to the wrapped method; None: its default.
    scan_kind: str | None = eqx.field(default=None, kw_only=True)

    term_structure = diffrax.AbstractTerm
    # Evaluated only by ``SaveAt(ts)`` in a run made for reverse mode (:func:`solve`), at
    # step ends; otherwise diffrax builds it per step and nothing evaluates it.
    interpolation_cls = StepEnd

    # -- what each integrator defines
    def reduce(self, y, data, t):
        """``(z, args)``: the variables the wrapped method integrates from ``y`` at ``t``,
        and the vector field's ``args``."""
        return y, None

    def finish(self, t0, t1, y0, z1, z_err, data):
        """After the wrapped method's step to ``t1``: ``(y1, y_err, data1, closed,
        violation)``, with ``y_err`` shaped like ``y`` (None on a fixed step)."""
        raise NotImplementedError

    def inner_terms(self, terms):
        """The terms the wrapped method steps (default: diffeqsolve's, the equations of
        motion of the whole state ``y``)."""
        return terms

    def initial_data(self, y0, t0):
        """The integrator's data at the start (carried in the solver state)."""
        return ()

    # -- diffrax's solver interface
    def order(self, terms):
        return self.solver.order(terms)

    def error_order(self, terms):
        return self.solver.error_order(terms)

    def init(self, terms, t0, t1, y0, args):
        worst = jnp.zeros((), jnp.result_type(t0))
        return (self.initial_data(y0, t0), worst)

    def func(self, terms, t0, y0, args):
        return self.solver.func(terms, t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        return _traced_once(self, terms, t0, t1, y0, args, solver_state, made_jump)

    def step_body(self, terms, t0, t1, y0, args, solver_state, made_jump):
        """diffrax's ``step``, as :func:`_traced_once` traces it."""
        data, worst = solver_state
        z0, inner_args = self.reduce(y0, data, t0)
        inner_terms = self.inner_terms(terms)
        rk = self.solver
        if self.scan_kind is not None and hasattr(rk, "scan_kind"):
            rk = eqx.tree_at(lambda s: s.scan_kind, rk, self.scan_kind, is_leaf=lambda x: x is None)
        inner = rk.init(inner_terms, t0, t1, z0, inner_args)
        z1, z_err, _, _, _ = rk.step(inner_terms, t0, t1, z0, inner_args, inner, made_jump=False)
        y1, y_err, data1, closed, violation = self.finish(t0, t1, y0, z1, z_err, data)
        finite = jnp.all(jnp.array([jnp.all(jnp.isfinite(a)) for a in jax.tree.leaves(y1)]))
        closed = closed & finite
        # Rejected by the controller: an infinite error (5x shorter retry).
        if y_err is not None:
            y_err = jax.tree.map(lambda e: jnp.where(closed, e, jnp.inf), y_err)
        # No shorter retry left: the run ends here, at the last accepted state.
        end = ~closed if self.fixed else ~closed & ((t1 - t0) * FACTOR_MIN < self.dt_min)
        result = diffrax.RESULTS.where(
            end,
            diffrax.RESULTS.where(
                finite, diffrax.RESULTS.nonlinear_divergence, diffrax.RESULTS.nonfinite
            ),
            diffrax.RESULTS.successful,
        )
        keep = lambda a, b: jnp.where(end, b, a)  # noqa: E731
        y1 = jax.tree.map(keep, y1, y0)
        if y_err is not None:
            y_err = jax.tree.map(lambda e: jnp.where(end, 0.0, e), y_err)
        data1 = jax.tree.map(keep, data1, data)
        worst = jnp.where(end, worst, jnp.maximum(worst, violation))
        dense = dict(y0=y0, y1=y1)
        return y1, y_err, dense, (data1, worst), result


@eqx.filter_jit
def _traced_once(solver, terms, t0, t1, y0, args, solver_state, made_jump):
    """``solver.step_body(...)`` as a function JAX traces once per structure: diffrax traces
    the body of its loop three times (twice for its state's structure, then the loop itself),
    and the second and third find this step traced."""
    return solver.step_body(terms, t0, t1, y0, args, solver_state, made_jump)


def _outputs(ts, y0, collect: bool):
    """The outputs' buffer of a controller's state: ``y0`` in the first of ``N`` rows (one
    row when the outputs are not collected there)."""
    N = ts.shape[0] if collect else 1
    return jax.tree.map(lambda a: jnp.zeros((N, *a.shape), a.dtype).at[0].set(a), y0)


def _store(outs, k, y1, landed):
    """``outs`` with row ``k`` set to ``y1`` where ``landed`` (one row written, not a
    select over all of them: under ``vmap`` a select over every member's outputs at every
    step was measured to cost 25% of a batch of 512)."""
    k = jnp.minimum(k, jax.tree.leaves(outs)[0].shape[0] - 1)
    return jax.tree.map(lambda o, a: o.at[k].set(jnp.where(landed, a, o[k])), outs, y1)


def _reached(controller, k, outs, t1, y1, accepted):
    """At the end ``t1`` of a step of a controller (:class:`FixedStep`, :class:`Landing`):
    ``(landed, k, outs)``: whether an accepted step landed on the next output time
    ``ts[k]``, where the progress callback is called and ``y1`` stored, and the next
    output's index."""
    ts = controller.ts
    landed = accepted & (t1 == ts[jnp.minimum(k, ts.shape[0] - 1)])
    report_progress(controller.progress, t1, landed)
    if controller.collect:
        outs = _store(outs, k, y1, landed)
    return landed, k + landed, outs


def _land(ts, k, t, h):
    """The end of a step of ``h`` from ``t``, the next output time being ``ts[k]``: that
    output time if it is within ``h`` (to 1e-8 relative), so that no sliver of a step is left
    before it; and whether it is."""
    target = ts[jnp.minimum(k, ts.shape[0] - 1)]
    hit = (target - t) <= h * (1 + 1e-8)
    return jnp.where(hit, target, t + h), hit


class FixedStep(diffrax.AbstractStepSizeController):
    """Steps of ``dt``, each shortened where needed to land on the next output time; the
    progress callback called at each output time. Its state ``(k, outs)``: the next output
    and the states at the output times (see :class:`Landing`)."""

    dt: jax.Array
    ts: jax.Array
    progress: object
    collect: bool = eqx.field(static=True, default=True, kw_only=True)

    def wrap(self, direction):
        return self

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        k = jnp.asarray(1)
        return _land(self.ts, 1, t0, self.dt)[0], (k, _outputs(self.ts, y0, self.collect))

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, state):
        _, k, outs = _reached(self, *state, t1, y1_candidate, True)
        next_t1, _ = _land(self.ts, k, t1, self.dt)
        return True, t1, next_t1, False, (k, outs), diffrax.RESULTS.successful


class Landing(diffrax.AbstractAdaptiveStepSizeController):
    """Integral step-size control (``h * clip(0.9 err**(-1/order), 0.2, 10)``, Hairer's
    scaled RMS error) landing on every output time; the progress callback called there.

    diffrax's ``PIDController`` wrapped in ``ClipStepSizeController(step_ts=ts)`` lands on
    the output times too, but leaves slivers: a step that ends a rounding error short of an
    output time is followed by a step of that length, from which the controller grows at most
    10x, below its ``dtmin`` (measured: a five-pendulum chain failed at t = 0.98). Here a step
    within 1e-8 of an output time goes there, and a step shortened to land does not shorten
    the next one.

    Attributes:
        rtol, atol: tolerances of the local error.
        ts: (N,) output times [time].
        h0: the first step [time].
        dt_min: a next step shorter than this ends the run (``dt_min_reached``) [time].
        norm: the error norm of a scaled error (a pytree shaped like the state).
        progress: None, or the run's :class:`~._common.Progress`.
        collect: whether the state collects the outputs (else diffrax's ``SaveAt(ts)``
            does: :func:`solve`).

    Its state ``(h, k, outs)``: the step, the next output, and the states at the output
    times, each written when an accepted step lands there. The controller holds them
    because it alone knows whether a step is accepted: diffrax keeps or reverts the solver
    state with a select over all of it at every step (under ``vmap``, over every member's
    outputs), and leaves the controller's state to the controller.
    """

    rtol: jax.Array
    atol: jax.Array
    ts: jax.Array
    h0: jax.Array
    dt_min: jax.Array
    norm: Callable = eqx.field(static=True)
    progress: object = None
    collect: bool = eqx.field(static=True, default=True, kw_only=True)

    def wrap(self, direction):
        return self

    def init(self, terms, t0, t1, y0, dt0, args, func, error_order):
        outs = _outputs(self.ts, y0, self.collect)
        return _land(self.ts, 1, t0, self.h0)[0], (self.h0, jnp.asarray(1), outs)

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order, state):
        h, k, outs = state

        def scaled(a, b, e):
            return e / (self.atol + self.rtol * jnp.maximum(jnp.abs(a), jnp.abs(b)))

        err = self.norm(jax.tree.map(scaled, y0, y1_candidate, y_error))
        ok = err <= 1.0
        factor = jnp.clip(
            SAFETY * jnp.where(err > 0, err, 1e-10) ** (-1.0 / error_order),
            FACTOR_MIN,
            FACTOR_MAX,
        )
        # The step sizes are held in derivatives (as diffrax's PID controller does): the
        # derivative of the error estimate's control loop is noise where the estimate
        # meets rounding (measured: a run through singular positions at rtol 1e-12,
        # 30% of its steps rejected, gave a derivative 6e-4 off central differences).
        factor = jax.lax.stop_gradient(factor)
        used = t1 - t0
        h_new = used * jnp.where(ok, factor, jnp.minimum(factor, SAFETY))
        landed, k, outs = _reached(self, k, outs, t1, y1_candidate, ok)
        # A step shortened to land on an output time does not shorten the next one.
        h_new = jnp.where(landed & (used < h), jnp.maximum(h_new, h), h_new)
        next_t0 = jnp.where(ok, t1, t0)
        next_t1, _ = _land(self.ts, k, next_t0, h_new)
        result = diffrax.RESULTS.where(
            h_new < self.dt_min, diffrax.RESULTS.dt_min_reached, diffrax.RESULTS.successful
        )
        return ok, next_t0, next_t1, False, (h_new, k, outs), result


def controller(ts, *, rtol, atol, norm: Callable | None, h0=None, dt=None, dt_min, progress):
    """The step-size controller of a run: :class:`FixedStep` for a fixed ``dt``, else
    :class:`Landing` with the tolerances, error norm and first step ``h0``."""
    if dt is not None:
        return FixedStep(jnp.asarray(dt, ts.dtype), ts, progress)
    dtype = ts.dtype
    return Landing(
        jnp.asarray(rtol, dtype),
        jnp.asarray(atol, dtype),
        ts,
        jnp.asarray(h0, dtype),
        jnp.asarray(dt_min, dtype),
        norm,
        progress,
    )


def rms_of_first(n: int):
    """Hairer's scaled RMS norm over the first ``n`` leaves of a state (the coordinates and
    velocities; the accumulated work is not under error control)."""

    def norm(scaled):
        leaves = jax.tree.leaves(scaled)[:n]
        total = sum(jnp.sum(a**2) for a in leaves)
        count = sum(a.size for a in leaves)
        return jnp.sqrt(total / max(count, 1))

    return norm


#: The adjoint of each mode of differentiation through a run (None: a run that is not
#: differentiated; reverse mode still passes through it).
ADJOINTS = {
    None: diffrax.RecursiveCheckpointAdjoint,
    "reverse": diffrax.RecursiveCheckpointAdjoint,
    "forward": diffrax.ForwardMode,
}


def solve(term, solver: ConstrainedSolver, y0, step_controller, *, max_steps, derivatives=None):
    """``diffeqsolve`` from the first to the last output time of ``solver.ts``.

    The states at the output times are collected by the step-size controller (its state
    holds them, written when an accepted step lands on an output time: :class:`Landing`):
    diffrax's ``SaveAt(ts=...)`` checks traced output times with a host callback, and a
    program with one is neither exported nor kept in the persistent cache
    (:mod:`mixdyn.runtime`); for the same reason the first step is the controller's, not
    ``dt0``. A run made to be reverse-differentiated (``derivatives="reverse"``,
    :func:`~mixdyn.differentiable`) saves them with ``SaveAt(ts)`` instead: there they are
    diffrax's write-only buffers, which the checkpoints of the adjoint do not copy (in the
    loop's state the checkpoints hold a copy of all of them at every step: measured, the
    paper model's gradient 8.6x the run against 6.5x).

    Returns:
        ``(ys, steps, rejected, max_violation, status, t_last, y_last)``: the states at the
        output times (stacked over N; rows after a failure are not meaningful), the counters,
        the largest violation before :meth:`ConstrainedSolver.finish`, the status (a key of
        :data:`~._common.STATUS_MESSAGES`) and the last accepted time and state.
    """
    ts = solver.ts
    buffered = derivatives == "reverse"
    if buffered:
        step_controller = dataclasses.replace(step_controller, collect=False)
        subs = [diffrax.SubSaveAt(ts=ts), diffrax.SubSaveAt(t1=True)]
        saveat = diffrax.SaveAt(subs=subs, solver_state=True)
    else:
        saveat = diffrax.SaveAt(t1=True, solver_state=True, controller_state=True)
    with chained_floor():  # diffrax's end-of-interval floor: one loop, not 100 copies
        sol = diffrax.diffeqsolve(
            term,
            solver,
            ts[0],
            ts[-1],
            None,
            y0,
            saveat=saveat,
            stepsize_controller=step_controller,
            max_steps=max_steps,
            throw=False,
            adjoint=ADJOINTS[derivatives](),
        )
    _, worst = sol.solver_state
    ys, t_end = sol.ys, sol.ts
    if buffered:
        (outs, ys), (_, t_end) = ys, t_end
    else:
        outs = sol.controller_state[-1]
    return (
        outs,
        sol.stats["num_accepted_steps"],
        sol.stats["num_rejected_steps"],
        worst,
        status(sol.result),
        t_end[0],
        jax.tree.map(lambda a: a[0], ys),
    )


def status(result) -> jax.Array:
    """diffrax's result as a key of :data:`~._common.STATUS_MESSAGES`."""
    R = diffrax.RESULTS
    codes = (
        (R.successful, OK),
        (R.max_steps_reached, MAX_STEPS),
        (R.dt_min_reached, STEP_COLLAPSE),
        (R.nonlinear_divergence, UNCLOSED),
    )
    out = jnp.asarray(NOT_FINITE)
    for r, code in codes:
        out = jnp.where(result == r, code, out)
    return out


__all__ = [
    "METHODS",
    "RK4",
    "ConstrainedSolver",
    "FixedStep",
    "Landing",
    "controller",
    "equations_of_motion",
    "first_step_size",
    "ode_term",
    "rms_of_first",
    "runge_kutta",
    "solve",
    "status",
]
