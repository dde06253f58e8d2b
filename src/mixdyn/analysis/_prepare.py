"""The start every analysis shares, made once per set-up: the constraint set, a consistent
start and the mobility analysis (which rows are redundant), before anything is integrated.

:func:`dynamic_start` serves forward and mixed dynamics (positions and velocities made
consistent), :func:`kinematic_start` kinematic, inverse and static analyses (positions
assembled). Both return a :class:`Prepared` record, from which an analysis takes the
constraint rows its solver needs (:meth:`Prepared.constraints`).

Each analysis value makes its start in :func:`~mixdyn.prepare` (:mod:`._setup`), which
carries it in its :class:`~._setup.Setup` (``setup.start``). A start made beforehand,
``prepare(model, analysis, start=...)``, takes the place of a new one where the analysis
would make the same (:func:`matching`): the model-file runner (:mod:`mixdyn.runs`) checks a
run on the start the run then starts from, and runs with the same start share one.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..errors import ModelError
from ..linalg import LinearSolver, as_linear_solver
from ..model import Model
from ._assembly import assemble
from ._reactions import require_held_meshes
from ._start import consistent_state
from ._structure import DofReport, analyse, require_balanced


@dataclasses.dataclass(frozen=True)
class Prepared:
    """A run's consistent start and its mobility analysis.

    Attributes:
        model: the mechanism.
        drivers: the drivers of the run (the model's, plus a mixed run's prescribed motions).
        t0: start time [time].
        q: (nq,) consistent positions [model units].
        qd: (nq,) consistent velocities, or None (kinematic runs: the drivers give them).
        report: the degrees-of-freedom report at ``(q, t0)``.
        keep: the constraint rows kept (independent joint rows, then the drivers).
        linear_solver: the solver asked for (:class:`~mixdyn.linalg.LinearSolver`).
        inputs: what the start was made from (the kind of start, the start time, the rough
            positions and velocities, the held coordinates, the linear solver), compared by
            :func:`matching`.
    """

    model: Model
    drivers: tuple
    t0: float
    q: jax.Array
    qd: jax.Array | None
    report: DofReport
    keep: tuple[int, ...]
    linear_solver: LinearSolver
    inputs: tuple = ()

    def constraints(self, independent_rows_only: bool = False) -> Constraints:
        """The constraint set of the run on its path: only the independent rows (for the
        solvers that need a regular ``Phi_q``: partitioning, the paper's partition), or every
        row declared of rank ``len(keep)`` (least-squares solves, robust where a redundancy
        moves from row to row)."""
        m = self.model
        c = Constraints(m.joints, self.drivers, m.nq, linear_solver=self.linear_solver)
        c = c.with_active(self.keep) if independent_rows_only else c.with_rank(len(self.keep))
        return c.with_linear_solver(self.linear_solver)


def dynamic_start(
    model: Model,
    t0: float,
    given=None,
    *,
    drivers=None,
    q0=None,
    qd0=None,
    hold=(),
    linear_solver="auto",
) -> Prepared:
    """The start of forward and mixed dynamics: positions and velocities made consistent
    (:func:`~mixdyn.analysis._start.consistent_state`), then the mobility analysis there;
    ``given`` (a start made beforehand, :func:`~mixdyn.prepare`'s ``start``) in its place
    where it was made from the same model, drivers, start time and settings
    (:func:`matching`)."""
    drivers = tuple(model.drivers if drivers is None else drivers)
    inputs = _dynamic_inputs(t0, q0, qd0, hold, linear_solver)
    if given is not None:
        return matching(given, model, drivers, inputs)
    c_full = Constraints(model.joints, drivers, model.nq, linear_solver=linear_solver)
    q, qd = consistent_state(model, c_full, t0, q0, qd0, hold)
    report, keep = analyse(model, np.asarray(q), t0, drivers)
    require_held_meshes(model, q, t0, drivers)
    solver = as_linear_solver(linear_solver)
    return Prepared(model, drivers, t0, q, qd, report, keep, solver, inputs)


def kinematic_start(
    model: Model,
    t0: float,
    given=None,
    *,
    drivers=None,
    q0=None,
    hold=(),
    assemble_first: bool = True,
    linear_solver="auto",
    balanced: bool = False,
) -> Prepared:
    """The start of kinematic, inverse and static analyses: the rough pose assembled (unless
    ``assemble_first=False``), then the mobility analysis there, with ``balanced`` the
    drivers checked to fix every degree of freedom
    (:class:`~mixdyn.errors.DegreesOfFreedomError` otherwise); ``given`` in its place as in
    :func:`dynamic_start`."""
    drivers = tuple(model.drivers if drivers is None else drivers)
    inputs = _kinematic_inputs(t0, q0, hold, assemble_first, linear_solver)
    if given is not None:
        given = matching(given, model, drivers, inputs)
        if balanced:
            require_balanced(given.report)
        return given
    q = model.q0 if q0 is None else jnp.asarray(q0, dtype=jnp.float64)
    if assemble_first:
        q = jnp.asarray(assemble(model, q, hold=hold, linear_solver=linear_solver).q)
    report, keep = analyse(model, q, t0, drivers)
    if balanced:
        require_balanced(report)
    require_held_meshes(model, q, t0, drivers)
    solver = as_linear_solver(linear_solver)
    return Prepared(model, drivers, t0, q, None, report, keep, solver, inputs)


def matching(start, model: Model, drivers: tuple, inputs: tuple) -> Prepared:
    """``start``, made beforehand, where it is the start its analysis would make: of the
    same model and drivers, from the same inputs (:attr:`Prepared.inputs`: the kind of start,
    the start time, the rough start, the held coordinates, the linear solver).

    Raises:
        ModelError: ``start`` is no :class:`Prepared`, or was made otherwise.
    """
    if not isinstance(start, Prepared):
        raise ModelError(
            "start must be the start of a set-up (setup.start, made by mixdyn.prepare), got "
            f"{type(start).__name__}",
            "start",
        )
    same = (
        start.inputs == inputs
        and _same_model(start.model, model)
        and _same_drivers(start.drivers, drivers)
    )
    if not same:
        raise ModelError(
            "the start was made for another model, other drivers, another start time or "
            "other start settings (q0, qd0, hold, assemble_first, linear_solver) than this "
            "analysis': leave start out (the analysis makes its own), or give the start of "
            "a set-up of the same model and start settings",
            "start",
        )
    return start


def _same_model(a: Model, b: Model) -> bool:
    """Whether two models are the same: the same object, or equal structure and numbers."""
    return a is b or _same_tree(a, b)


def _same_drivers(a, b) -> bool:
    """Whether two driver sequences are equal, driver by driver (kinds, bodies, laws)."""
    a, b = tuple(a), tuple(b)
    return len(a) == len(b) and all(x is y or _same_tree(x, y) for x, y in zip(a, b, strict=True))


def _same_tree(a, b) -> bool:
    """Equal PyTrees: the same structure and static data, leaf by leaf the same numbers."""
    la, ta = jax.tree_util.tree_flatten(a)
    lb, tb = jax.tree_util.tree_flatten(b)
    try:
        if ta != tb:
            return False
    except (TypeError, ValueError):  # static data that does not compare (arrays)
        return False
    for x, y in zip(la, lb, strict=True):
        if x is y:
            continue
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape or x.dtype != y.dtype or x.tobytes() != y.tobytes():
            return False
    return True


def _key(x):
    """A comparable record of an argument: its numbers (shape and bytes), else its text."""
    if x is None:
        return None
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        return ("text", repr(x))
    return (a.shape, a.tobytes())


def _dynamic_inputs(t0, q0, qd0, hold, linear_solver) -> tuple:
    """What a dynamic start is made from (see :attr:`Prepared.inputs`)."""
    if isinstance(qd0, Mapping):
        qd = ("conditions", tuple(sorted((str(k), _key(v)) for k, v in qd0.items())))
    else:
        qd = _key(qd0)
    solver = as_linear_solver(linear_solver)
    return ("dynamic", float(t0), _key(q0), qd, tuple(hold), solver)


def _kinematic_inputs(t0, q0, hold, assemble_first, linear_solver) -> tuple:
    """What a kinematic start is made from (see :attr:`Prepared.inputs`)."""
    solver = as_linear_solver(linear_solver)
    return ("kinematic", float(t0), _key(q0), tuple(hold), bool(assemble_first), solver)


__all__ = ["Prepared", "dynamic_start", "kinematic_start", "matching"]
