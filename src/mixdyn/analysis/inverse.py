"""Inverse dynamics: motion fully prescribed; driver efforts and joint reactions sought.

The motion comes from the kinematic analysis (positions, velocities, accelerations from the
drivers alone); the multipliers then solve ``Phi_q^T lambda = Q^A - M qdd`` (through the same
constrained solve as forward dynamics). Each driver's effort is ``-lambda`` of its row.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from ..linalg import LinearSolver
from ..model import Model
from ._prepare import Prepared, prepare_kinematic, use_prepared
from ._problem import Problem
from ._simulate import _post, output_times, post_kinds, require_masses
from .kinematic import run_kinematic
from .result import Result


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
        prepared: the run's set-up, as in :func:`~mixdyn.kinematic` (made by
            :func:`~mixdyn.analysis._prepare.prepare_kinematic` from the same model, start
            time, ``q0``, ``hold``, ``assemble_first`` and ``linear_solver``; another is
            refused). Default None: the run prepares its own.
        **kinematic_options: passed to :func:`~mixdyn.kinematic` (``tol``, ``max_iter``...).

    Returns:
        A :class:`Result` with the motion, each driver's effort (force or torque, column named
        after the driver) and power (``{driver}.power``), the joint reactions and the energies.
    """
    ts = output_times(t)
    require_masses(model)
    kin_options = dict(kinematic_options)
    assemble_first = kin_options.pop("assemble_first", True)
    args = dict(q0=q0, hold=hold, assemble_first=assemble_first, linear_solver=linear_solver)
    if prepared is None:
        prep = prepare_kinematic(model, float(ts[0]), **args)
    else:
        prep = use_prepared(prepared, model, float(ts[0]), what="inverse", **args)
    kin = run_kinematic(prep, ts, **kin_options)
    c = prep.constraints()  # the kinematic run's rows: assembled and analysed once
    problem = Problem(model, c)
    _, _, ratio, cols = _post(
        problem, jnp.asarray(ts), jnp.asarray(kin.q), jnp.asarray(kin.qd), len(model.drivers)
    )
    extra = {k: np.asarray(v) for k, v in cols.items()}
    stats = dict(
        kin.stats,
        min_pivot_ratio_dynamics=float(np.min(np.asarray(ratio))),
        linear_solver=c.linear_solver.name,
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
