"""The set-up every analysis shares, done once per run: the constraint set, a consistent start
and the mobility analysis (which rows are redundant), before anything is integrated.

``prepare_dynamic`` serves forward and mixed dynamics (positions and velocities made
consistent), ``prepare_kinematic`` kinematic and inverse dynamics (positions assembled, the
drivers checked against the degrees of freedom). Both return a :class:`Prepared` record, from
which an analysis takes the constraint rows its solver needs
(:meth:`Prepared.constraints`).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..model import Model
from ._assembly import assemble
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
        linear_solver: the path asked for (``"auto"``, ``"dense"``, ``"sparse"``).
    """

    model: Model
    drivers: tuple
    t0: float
    q: jax.Array
    qd: jax.Array | None
    report: DofReport
    keep: tuple[int, ...]
    linear_solver: str

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
    q, qd = consistent_state(model, c_full, t0, q0, qd0, hold)
    report, keep = analyse(model, np.asarray(q), t0, drivers)
    return Prepared(model, drivers, t0, q, qd, report, keep, linear_solver)


def prepare_kinematic(
    model: Model,
    t0: float,
    *,
    drivers=None,
    q0=None,
    hold=(),
    assemble_first: bool = True,
    linear_solver="auto",
) -> Prepared:
    """Kinematic and inverse dynamics: the rough pose assembled (unless
    ``assemble_first=False``), the mobility analysis there, and the drivers checked to fix
    every degree of freedom (:class:`~mixdyn.errors.DegreesOfFreedomError` otherwise)."""
    drivers = tuple(model.drivers if drivers is None else drivers)
    q = model.q0 if q0 is None else jnp.asarray(q0, dtype=jnp.float64)
    if assemble_first:
        q = jnp.asarray(assemble(model, q, hold=hold, linear_solver=linear_solver).q)
    report, keep = analyse(model, q, t0, drivers)
    require_balanced(report)
    return Prepared(model, drivers, t0, q, None, report, keep, linear_solver)


__all__ = ["Prepared", "prepare_dynamic", "prepare_kinematic"]
