"""Inverse dynamics: motion fully prescribed; driver efforts and joint reactions sought.

The motion comes from the kinematic analysis (positions, velocities, accelerations from the
drivers alone); the multipliers then solve ``Phi_q^T lambda = Q^A - M qdd`` (through the same
constrained solve as forward dynamics). Each driver's effort is ``-lambda`` of its row.
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
import numpy as np

from ..linalg import LinearSolver
from ..model import Model
from . import _setup
from ._prepare import Prepared
from ._problem import Problem
from ._setup import Setup, keyword_setup
from ._simulate import _post, output_times, post_kinds, require_masses
from .kinematic import _Driven
from .result import Result


class Inverse(_Driven):
    """Inverse dynamics as a value: the driver efforts and joint reactions of a fully driven
    mechanism (``md.inverse``'s options, for :func:`~mixdyn.prepare` and the studies).
    Preparing it checks the masses, assembles the start and checks that the drivers fix every
    degree of freedom.

    Attributes:
        q0: (nq,) rough starting configuration [model units], or None (the bodies' ``q0``).
        hold: coordinates kept at their rough value while assembling.
        assemble_first: close the joints from the rough pose before applying the drivers
            (default True).
        tol, max_iter, singular_tol: the kinematic analysis' options, as in
            :class:`~mixdyn.analyses.Kinematic`.
        linear_solver: a :class:`~mixdyn.LinearSolver` or its name (``"auto"``, default;
            ``"dense"``, ``"sparse"``): the path of the kinematic analysis and of the
            multipliers' solve.
    """

    name: ClassVar[str] = "inverse"

    def _prepare(self, model: Model, t0: float, given: Prepared | None = None) -> Setup:
        require_masses(model)
        prep = self._initial(model, t0, given, balanced=True)
        # the kinematic run's rows: assembled and analysed once
        return Setup(self, model, t0, prep, Problem(model, prep.constraints()))

    def _run(self, setup: Setup, t, progress=None) -> Result:
        _setup.no_progress(self, progress)
        ts = output_times(t)
        _setup.check_start(setup, ts)
        model, problem = setup.model, setup.problem
        kin = self._kinematics(setup, ts)
        _, _, ratio, cols = _post(
            problem, jnp.asarray(ts), jnp.asarray(kin.q), jnp.asarray(kin.qd), len(model.drivers)
        )
        extra = {k: np.asarray(v) for k, v in cols.items()}
        stats = dict(
            kin.stats,
            min_pivot_ratio_dynamics=float(np.min(np.asarray(ratio))),
            linear_solver=problem.c.linear_solver.name,
        )
        return Result(
            kind="inverse",
            model=model,
            t=ts,
            q=kin.q,
            qd=kin.qd,
            qdd=kin.qdd,
            extra=extra,
            kinds=post_kinds(problem, len(model.drivers)),
            stats=stats,
        )


def inverse(
    model: Model,
    t,
    *,
    q0=None,
    hold=(),
    linear_solver: str | LinearSolver = "auto",
    prepared: Prepared | None = None,
    **kinematic_options,
) -> Result:
    """Driver efforts and joint reactions of a fully driven mechanism over time.

    Args:
        model: the mechanism; its drivers must fix every degree of freedom, and every body
            needs mass and inertia > 0.
        t: (N,) increasing output times [time].
        q0: (nq,) rough starting configuration.
        hold: coordinates kept at their rough value while assembling.
        linear_solver: a :class:`~mixdyn.LinearSolver`, or its name: ``"dense"``, ``"sparse"`` or
            ``"auto"`` (sparse for large mechanisms of small bandwidth, see :mod:`mixdyn.linalg`):
            the path of the kinematic analysis and of the multipliers' solve.
        prepared: deprecated, as in :func:`~mixdyn.kinematic`:
            ``mixdyn.prepare(model, mixdyn.analyses.Inverse(...), t0=t[0], start=...)``.
        **kinematic_options: passed to :func:`~mixdyn.kinematic` (``tol``, ``max_iter``...).

    Returns:
        A :class:`Result` with the motion, each driver's effort (force or torque, column named
        after the driver) and power (``{driver}.power``), the joint reactions and the energies.
    """
    ts = output_times(t)
    analysis = Inverse(q0=q0, hold=hold, linear_solver=linear_solver, **kinematic_options)
    return analysis._run(keyword_setup(model, analysis, float(ts[0]), prepared=prepared), ts)


__all__ = ["Inverse", "inverse"]
