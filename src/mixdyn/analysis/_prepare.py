"""The set-up every analysis shares, done once per run: the constraint set, a consistent start
and the mobility analysis (which rows are redundant), before anything is integrated.

``prepare_dynamic`` serves forward and mixed dynamics (positions and velocities made
consistent), ``prepare_kinematic`` kinematic and inverse dynamics (positions assembled, the
drivers checked against the degrees of freedom). Both return a :class:`Prepared` record, from
which an analysis takes the constraint rows its solver needs
(:meth:`Prepared.constraints`).

The analysis values make theirs in :func:`~mixdyn.prepare` (:mod:`._setup`), which carries
it in its :class:`~._setup.Setup`. A :class:`Prepared` made here beforehand is also taken by
the analysis functions' deprecated ``prepared=`` keyword (the model-file runner,
:mod:`mixdyn.runs`, checks a run on the start the run then starts from):
:func:`use_prepared` refuses one made for another call (model, drivers, start time, rough
start, held coordinates, linear solver).
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
        inputs: what the start was made from (the kind of set-up, the rough positions and
            velocities, the held coordinates...), compared by :func:`use_prepared`.
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


def prepare_dynamic(
    model: Model, t0: float, *, drivers=None, q0=None, qd0=None, hold=(), linear_solver="auto"
) -> Prepared:
    """Forward and mixed dynamics: positions and velocities made consistent
    (:func:`~mixdyn.analysis._start.consistent_state`), then the mobility analysis there."""
    drivers = tuple(model.drivers if drivers is None else drivers)
    c_full = Constraints(model.joints, drivers, model.nq, linear_solver=linear_solver)
    inputs = _dynamic_inputs(q0, qd0, hold)
    q, qd = consistent_state(model, c_full, t0, q0, qd0, hold)
    report, keep = analyse(model, np.asarray(q), t0, drivers)
    require_held_meshes(model, q, t0, drivers)
    solver = as_linear_solver(linear_solver)
    return Prepared(model, drivers, t0, q, qd, report, keep, solver, inputs)


def prepare_kinematic(
    model: Model,
    t0: float,
    *,
    drivers=None,
    q0=None,
    hold=(),
    assemble_first: bool = True,
    linear_solver="auto",
    balanced: bool = True,
) -> Prepared:
    """Kinematic and inverse dynamics: the rough pose assembled (unless
    ``assemble_first=False``), the mobility analysis there, and the drivers checked to fix
    every degree of freedom (:class:`~mixdyn.errors.DegreesOfFreedomError` otherwise; not with
    ``balanced=False``, for a caller that reports the balance itself: the analysis checks it
    again when handed the set-up)."""
    drivers = tuple(model.drivers if drivers is None else drivers)
    inputs = _kinematic_inputs(q0, hold, assemble_first)
    q = model.q0 if q0 is None else jnp.asarray(q0, dtype=jnp.float64)
    if assemble_first:
        q = jnp.asarray(assemble(model, q, hold=hold, linear_solver=linear_solver).q)
    report, keep = analyse(model, q, t0, drivers)
    if balanced:
        require_balanced(report)
    require_held_meshes(model, q, t0, drivers)
    solver = as_linear_solver(linear_solver)
    return Prepared(model, drivers, t0, q, None, report, keep, solver, inputs)


def use_prepared(
    prepared,
    model: Model,
    t0: float,
    *,
    what: str,
    dynamic: bool,
    drivers=None,
    q0=None,
    qd0=None,
    hold=(),
    assemble_first: bool = True,
    linear_solver="auto",
) -> Prepared:
    """A set-up handed to an analysis, checked to be the one the analysis would make itself.

    Args:
        prepared: the :class:`Prepared` handed over.
        model: the analysis' model.
        t0: its start time [time].
        what: the analysis' name, for the messages.
        dynamic: whether the analysis makes a dynamic start (positions and velocities:
            forward, mixed) or a kinematic one (kinematic, inverse).
        drivers: the drivers of the run (default: the model's).
        q0, qd0, hold, assemble_first, linear_solver: the analysis' arguments.

    Returns:
        ``prepared``; a kinematic set-up with its drivers checked against the degrees of
        freedom (:func:`~mixdyn.analysis._structure.require_balanced`).

    Raises:
        ModelError: ``prepared`` is no :class:`Prepared`, or was made for another model,
            other drivers, another start time, another rough start or held coordinates
            (or, for a kinematic set-up, ``assemble_first``) or another linear solver.
    """
    if not isinstance(prepared, Prepared):
        raise ModelError(
            f"prepared must be the set-up of a run (mixdyn.analysis._prepare.Prepared), got "
            f"{type(prepared).__name__}",
            "prepared",
        )
    drivers = tuple(model.drivers if drivers is None else drivers)
    wrong = []
    if not _same_model(prepared.model, model):
        wrong.append("another model")
    if not _same_drivers(prepared.drivers, drivers):
        names = ", ".join(d.name for d in prepared.drivers) or "none"
        wrong.append(f"other drivers ({names})")
    if prepared.t0 != float(t0):
        wrong.append(f"another start time (t = {prepared.t0:g}, not {float(t0):g})")
    inputs = (
        _dynamic_inputs(q0, qd0, hold) if dynamic else _kinematic_inputs(q0, hold, assemble_first)
    )
    if prepared.inputs[:1] != inputs[:1]:
        kind = {("dynamic",): "a dynamic run's", ("kinematic",): "a kinematic run's"}
        wrong.append(f"{kind.get(prepared.inputs[:1], 'an unrecorded')} start")
    elif prepared.inputs != inputs:
        wrong.append("another rough start (q0, qd0, hold or assemble_first)")
    if prepared.linear_solver != as_linear_solver(linear_solver):
        asked = as_linear_solver(linear_solver).name
        wrong.append(f"the linear solver {prepared.linear_solver.name!r}, not {asked!r}")
    if wrong:
        raise ModelError(
            f"the prepared set-up does not match this {what} analysis: it was made for "
            + "; ".join(wrong)
            + ". Leave prepared out (the analysis prepares its own start), or prepare it from "
            "the same arguments",
            "prepared",
        )
    if not dynamic:
        require_balanced(prepared.report)  # as prepare_kinematic checks it
    return prepared


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


def _dynamic_inputs(q0, qd0, hold) -> tuple:
    """What a dynamic start is made from (see :attr:`Prepared.inputs`)."""
    if isinstance(qd0, Mapping):
        qd = ("conditions", tuple(sorted((str(k), _key(v)) for k, v in qd0.items())))
    else:
        qd = _key(qd0)
    return ("dynamic", _key(q0), qd, tuple(hold))


def _kinematic_inputs(q0, hold, assemble_first) -> tuple:
    """What a kinematic start is made from (see :attr:`Prepared.inputs`)."""
    return ("kinematic", _key(q0), tuple(hold), bool(assemble_first))


__all__ = ["Prepared", "prepare_dynamic", "prepare_kinematic", "use_prepared"]
