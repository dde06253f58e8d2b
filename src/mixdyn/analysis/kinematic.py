"""Kinematic analysis: motion prescribed for every degree of freedom.

At each output time: positions by Newton–Raphson on ``Phi(q, t) = 0`` (warm-started by a
second-order Taylor prediction from the previous time), velocities from
``Phi_q qd = -Phi_t``, accelerations from ``Phi_q qdd = gamma``. The time loop is one
``lax.scan``, compiled once per model structure.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..errors import ConvergenceError, ModelError, NumericalError, SingularityError
from ..linalg import AutoSolver, LinearSolver, dependent_rows
from ..model import Driver, Model
from ..model._compliant import refuse_contacts
from ..runtime._programs import cached_jit
from . import _setup
from ._assembly import length_scale
from ._newton import newton_positions
from ._prepare import Prepared, kinematic_start
from ._setup import Setup, keyword_setup
from .result import Partial, Result


def output_times(t, minimum: int = 2) -> np.ndarray:
    """Check and convert output times: increasing, finite, at least ``minimum`` of them."""
    from ..errors import ModelError

    ts = np.atleast_1d(np.asarray(t, dtype=float))
    if ts.ndim != 1 or ts.size < minimum or np.any(np.diff(ts) <= 0) or not np.all(np.isfinite(ts)):
        raise ModelError(
            f"output times must be an increasing sequence of at least {minimum} "
            "finite times (e.g. numpy.linspace(0, 2, 201))",
            "t",
        )
    return ts


@cached_jit
def _kinematic_scan(c: Constraints, q_start, ts, tol, max_iter):
    def step(carry, t):
        q, qd, qdd, t_prev = carry
        dt = t - t_prev
        guess = q + qd * dt + 0.5 * qdd * dt**2
        q, it, res, ratio = newton_positions(c, guess, t, tol, max_iter)
        # one factorization for both solves; on the sparse path one step of iterative
        # refinement each (the Schur complement squares the condition number)
        solve = c.jacobian_solver(q, t, refine=1)
        qd, r1 = solve(-c.phi_t(q, t))
        qdd, r2 = solve(c.gamma(q, qd, t))
        ratio = jnp.minimum(ratio, jnp.minimum(r1, r2))
        return (q, qd, qdd, t), (q, qd, qdd, it, res, ratio)

    zeros = jnp.zeros_like(q_start)
    _, out = jax.lax.scan(step, (q_start, zeros, zeros, ts[0]), ts)
    return out


@cached_jit(optimize=False)  # runs a few times per analysis
def _jacobian(c: Constraints, q, t):
    return c.phi_q(q, t)


def _fail(c: Constraints, q, t, message, cls, J=None):
    J = np.asarray(_jacobian(c, jnp.asarray(q), jnp.asarray(t))) if J is None else J
    rows = dependent_rows(J, 1e-8)
    names = []
    for i in rows:
        e = c.element_names[c.owners[c.active[i]]]
        if e not in names:
            names.append(e)
    raise cls(message, float(t), names)


def check_run(c, ts, q, it, res, ratio, tol, max_iter, singular_tol):
    """Raise the named error for the first failed time of a scan, if any."""
    it, res, ratio = np.asarray(it), np.asarray(res), np.asarray(ratio)
    bad_ratio = ratio < singular_tol
    bad_newton = ~(res <= tol)
    if not (bad_ratio.any() or bad_newton.any()):
        return
    k = int(np.argmax(bad_ratio | bad_newton))
    if bad_ratio[k] or (k > 0 and ratio[k - 1] < 1e3 * singular_tol):
        _fail(
            c,
            q[k - 1] if bad_newton[k] and k > 0 else q[k],
            ts[k],
            f"singular configuration: the Jacobian lost rank (pivot ratio {ratio[k]:.2e}); "
            "the mechanism is at a dead point or bifurcation, where the drivers do not "
            "determine the motion. Drive another coordinate or stop before this time",
            SingularityError,
        )
    _fail(
        c,
        q[k - 1] if k > 0 else q[k],
        ts[k],
        f"Newton-Raphson did not converge in {max_iter} iterations (residual {res[k]:.3g}); "
        "the prescribed motion may leave the reachable workspace, or the time step between "
        "outputs is too large for the motion",
        ConvergenceError,
    )


def _drivers(value) -> tuple[Driver, ...] | None:
    """``drivers``: None (the model's) or a tuple of drivers."""
    if value is None:
        return None
    out = (value,) if isinstance(value, Driver) else tuple(value)
    for d in out:
        if not isinstance(d, Driver):
            raise ModelError(f"drivers must be drivers, got {type(d).__name__}", "drivers")
    return out


class _Driven(_setup.Analysis):
    """The options that kinematic and inverse analyses share (see either)."""

    _: dataclasses.KW_ONLY
    q0: np.ndarray | None = eqx.field(default=None, converter=_setup.start_positions)
    hold: tuple[str, ...] = eqx.field(default=(), converter=_setup.held)
    assemble_first: bool = eqx.field(default=True, converter=_setup.switch("assemble_first"))
    tol: float | None = eqx.field(default=None, converter=_setup.checked("tol"))
    max_iter: int = eqx.field(default=25, converter=_setup.checked("max_iter"))
    singular_tol: float = eqx.field(default=1e-7, converter=_setup.checked("singular_tol"))
    linear_solver: LinearSolver = eqx.field(default=AutoSolver(), converter=_setup.linear_solver)

    def _start(self) -> dict:
        """The start settings, as the keywords of :func:`~._prepare.kinematic_start`."""
        return _setup.start_of(self, "q0", "hold", "assemble_first", "linear_solver")

    def _drivers(self, model: Model) -> tuple:
        """The drivers of the run: the model's."""
        return model.drivers

    def _initial(self, model: Model, t0: float, given: Prepared | None = None, balanced=False):
        """As :meth:`~._setup.Analysis._initial`; with ``balanced`` the drivers checked to fix
        every degree of freedom. A model with compliant contacts (a clearance joint) is
        refused: its contacts leave free a motion that these analyses prescribe."""
        refuse_contacts(model, self.name)
        drivers = self._drivers(model)
        return kinematic_start(
            model, t0, given, drivers=drivers, balanced=balanced, **self._start()
        )

    def _kinematics(self, setup: Setup, ts) -> Result:
        """The kinematic run of ``setup`` over the output times ``ts`` (N,) [time]."""
        return run_kinematic(
            setup.start, ts, tol=self.tol, max_iter=self.max_iter, singular_tol=self.singular_tol
        )


class Kinematic(_Driven):
    """Kinematic analysis as a value: positions, velocities and accelerations of a fully
    driven mechanism (``md.kinematic``'s options, for :func:`~mixdyn.prepare` and the
    studies). Preparing it assembles the start and checks that the drivers fix every degree
    of freedom.

    Attributes:
        drivers: drivers to use instead of the model's, or None (default: the model's).
        q0: (nq,) rough starting configuration [model units], or None (the bodies' ``q0``).
        hold: coordinates (``"crank.phi"``) kept at their rough value while assembling.
        assemble_first: close the joints from the rough pose before applying the drivers
            (default True).
        tol: Newton tolerance on the largest residual [length], or None (default:
            ``1e-12 x`` the model's size).
        max_iter: Newton iterations per time, 1 to 1000 (default 25).
        singular_tol: a pivot ratio of ``Phi_q`` below this is a singularity, in (0, 1)
            (default 1e-7).
        linear_solver: a :class:`~mixdyn.LinearSolver` or its name (``"auto"``, default;
            ``"dense"``, ``"sparse"``); the assembly takes the same path.
    """

    name: ClassVar[str] = "kinematic"

    _: dataclasses.KW_ONLY
    drivers: tuple[Driver, ...] | None = eqx.field(default=None, converter=_drivers)

    def _drivers(self, model: Model) -> tuple:
        """The drivers of the run: :attr:`drivers` bound to the model's bodies, or the
        model's."""
        if self.drivers is None:
            return model.drivers
        return tuple(d.bind(_resolver(model)) for d in self.drivers)

    def _prepare(self, model: Model, t0: float, given: Prepared | None = None) -> Setup:
        return Setup(self, model, t0, self._initial(model, t0, given, balanced=True))

    def _run(self, setup: Setup, t, progress=None) -> Result:
        _setup.no_progress(self, progress)
        ts = output_times(t, minimum=1)
        _setup.check_start(setup, ts)
        return self._kinematics(setup, ts)


def kinematic(
    model: Model,
    t,
    *,
    drivers=None,
    q0=None,
    assemble_first: bool = True,
    hold=(),
    tol: float | None = None,
    max_iter: int = 25,
    singular_tol: float = 1e-7,
    linear_solver: str | LinearSolver = "auto",
    prepared: Prepared | None = None,
) -> Result:
    """Positions, velocities and accelerations of a fully driven mechanism over time.

    Args:
        model: the mechanism; its drivers (or ``drivers``) must fix every degree of freedom.
        t: (N,) increasing output times [time].
        drivers: drivers to use instead of the model's.
        q0: (nq,) rough starting configuration (default: the bodies' ``q0``).
        assemble_first: close the joints from the rough pose before applying the drivers.
        hold: coordinates (``"crank.phi"``) kept at their rough value while assembling.
        tol: Newton tolerance on the largest residual [length] (default ``1e-12 x`` size).
        max_iter: Newton iterations per time.
        singular_tol: a pivot ratio of ``Phi_q`` below this is reported as a singularity.
        linear_solver: a :class:`~mixdyn.LinearSolver`, or its name: ``"dense"`` (LU of ``Phi_q``),
            ``"sparse"`` (minimum-norm solves through the banded Cholesky factorization of ``Phi_q
            Phi_q^T``, with one step of iterative refinement for velocities and accelerations; the
            pivot ratio compared with ``singular_tol`` is the square root of that factorization's)
            or ``"auto"`` (sparse for large mechanisms of small bandwidth, see
            :mod:`mixdyn.linalg`). The assembly takes the same path.
        prepared: deprecated (a DeprecationWarning names the new spelling): the start of an
            earlier set-up (``setup.start``) made from the same model, drivers, start time
            ``t[0]``, ``q0``, ``hold``, ``assemble_first`` and ``linear_solver``, as
            ``mixdyn.prepare(model, mixdyn.analyses.Kinematic(...), t0=t[0], start=...)``
            takes it; a start made otherwise is refused (:class:`~mixdyn.errors.ModelError`).

    Returns:
        A :class:`Result` with the body coordinates, velocities and accelerations and, in
        ``stats``, the Newton iterations and the largest residual.

    Raises:
        DegreesOfFreedomError: the drivers do not match the degrees of freedom.
        AssemblyError, ConvergenceError, SingularityError: with the time and the elements.
    """
    ts = output_times(t, minimum=1)
    analysis = Kinematic(
        drivers=drivers,
        q0=q0,
        assemble_first=assemble_first,
        hold=hold,
        tol=tol,
        max_iter=max_iter,
        singular_tol=singular_tol,
        linear_solver=linear_solver,
    )
    return analysis._run(keyword_setup(model, analysis, float(ts[0]), prepared=prepared), ts)


def run_kinematic(
    prep: Prepared, ts, *, tol: float | None = None, max_iter: int = 25, singular_tol=1e-7
) -> Result:
    """:func:`kinematic` from its prepared start (:func:`~mixdyn.analysis._prepare.
    kinematic_start`): the jitted scan over the output times ``ts`` (N,), then the checks."""
    c = prep.constraints()
    tol = tolerance(prep.model, tol)
    scan = _kinematic_scan(c, prep.q, jnp.asarray(ts), jnp.asarray(tol), jnp.asarray(max_iter))
    return kinematic_result(prep, c, ts, scan, tol, max_iter, singular_tol)


def tolerance(model: Model, tol: float | None) -> float:
    """The Newton tolerance of a kinematic run [length]: ``tol``, or ``1e-12 x`` the model's
    size."""
    return 1e-12 * length_scale(model) if tol is None else tol


def kinematic_result(
    prep: Prepared, c: Constraints, ts, scan, tol: float, max_iter: int, singular_tol
) -> Result:
    """The result of a kinematic scan ``scan`` (``q, qd, qdd, it, res, ratio``, each with
    the output times ``ts`` (N,) first) of the start ``prep`` on the constraint set ``c``,
    checked (:func:`check_run`: the named error of its first failed time)."""
    model = prep.model
    q_all, qd, qdd, it, res, ratio = scan
    q_all = np.asarray(q_all)
    try:
        check_run(c, ts, q_all, it, res, ratio, tol, max_iter, singular_tol)
    except NumericalError as e:  # the output times before it were solved
        e.partial = Partial.before(model, ts, q_all, qd, e.time, strict=True)
        raise
    return Result(
        kind="kinematic",
        model=model,
        t=ts,
        q=q_all,
        qd=np.asarray(qd),
        qdd=np.asarray(qdd),
        stats={
            "newton_iterations": int(np.sum(it)),
            "max_newton_iterations": int(np.max(it)),
            "max_residual": float(np.max(res)),
            "min_pivot_ratio": float(np.min(ratio)),
            "redundant_equations": prep.report.redundant,
            "tolerance": tol,
            "linear_solver": c.linear_solver.name,
        },
    )


def _resolver(model: Model):
    from ..model._element import Resolver

    return Resolver(model.ground, model.bodies)
