"""Forward dynamics: forces known, motion sought.

``M qdd + Phi_q^T lambda = Q^A``, ``Phi_q qdd = gamma``, integrated in time by a chosen
integrator. The model's drivers, if any, act as motion constraints; their efforts are reported.
"""

from __future__ import annotations

from ..linalg import LinearSolver
from ..model import Model
from ._prepare import Prepared, prepare_dynamic, use_prepared
from ._problem import Problem
from ._simulate import (
    ENERGY_TOL,
    Case,
    output_times,
    refuse_friction_in,
    require_masses,
    run_options,
    simulate,
)
from .methods import IntegratorOptions
from .result import Result


def forward(
    model: Model,
    t,
    *,
    method: str | IntegratorOptions = "projection",
    rtol: float | None = None,
    atol: float | None = None,
    dt: float | None = None,
    q0=None,
    qd0=None,
    hold=(),
    progress=None,
    linear_solver: str | LinearSolver = "auto",
    energy_tol: float | str | None = ENERGY_TOL,
    prepared: Prepared | None = None,
    **options,
) -> Result:
    """Simulate the mechanism under its forces from a consistent initial state.

    Args:
        model: the mechanism (every body with mass and inertia > 0).
        t: (N,) increasing output times [time]; ``t[0]`` is the start.
        method: the integration method and its options: an object of
            :class:`~mixdyn.Projection` (adaptive RK + projection), :class:`~mixdyn.Baumgarte`
            (fixed-step RK4), :class:`~mixdyn.Partitioning` (Wehage–Haug) or
            :class:`~mixdyn.GeneralizedAlpha` (implicit, index 3), e.g.
            ``method=md.Projection(rtol=1e-10, solver="dopri8")``; or a method's name,
            ``"projection"`` (default), ``"baumgarte"``, ``"partitioning"`` or
            ``"generalized-alpha"``, with its options as keywords (``rtol``, ``atol``, ``dt``
            and ``**options``: the same run). Generalized-alpha's ``newton``: ``"auto"``
            (default: modified Newton on the acceleration-level KKT matrix, switching within
            a step to the exact Newton matrix where it contracts poorly, e.g. a stiff spring
            at a large step), ``"modified"`` or ``"full"``. For a mechanism that passes
            through singular positions again and again (the IFToMM N-four-bar) keep the
            projection's default ``solver="tsit5"`` (or use generalized-alpha): ``"dopri8"``
            loses its grip there (``benchmarks/RESULTS.md``, the IFToMM N-four-bar).
        rtol, atol: local error tolerances of the adaptive methods (on q and qd, model units;
            default 1e-8 and 1e-10), with a method's name only.
        dt: step [time] of the fixed-step methods (or a fixed step for the adaptive ones),
            with a method's name only.
        q0, qd0: (nq,) rough initial positions (default: the bodies' ``q0``) and velocities
            (default 0); made consistent before the run.
        hold: coordinates (``"crank.phi"``) kept at their given values while assembling.
        progress: optional ``f(t)`` called at each output time (from inside the jitted loop).
        linear_solver: a :class:`~mixdyn.LinearSolver`, or its name: ``"dense"``, ``"sparse"`` or
            ``"auto"`` (sparse for large mechanisms of small bandwidth, see :mod:`mixdyn.linalg`):
            the path of every linear solve of the run: the consistent start (assembly and
            velocities), the acceleration equations, the projections, generalized-alpha's Newton
            iterations and the reactions at the output times.
        energy_tol: relative tolerance of the run's energy balance ``T + V - E0 - W``,
            against its energy scale: ``"auto"`` (default: 1000 x ``rtol`` for the adaptive
            methods, within [1e-9, 1e-4]; 1e-4 for the fixed-step ones), a number, or None
            (not checked). A run that breaks it, e.g. by jumping to another branch at a
            singular position, raises :class:`~mixdyn.errors.EnergyBalanceError` rather
            than returning a wrong motion.
        prepared: the run's set-up (consistent start and mobility analysis), made beforehand
            by :func:`~mixdyn.analysis._prepare.prepare_dynamic` from the same model, start
            time ``t[0]``, ``q0``, ``qd0``, ``hold`` and ``linear_solver`` (the model-file
            runner checks a run on it, then runs from it, so that the run is assembled and
            analysed once). Default None: the run prepares its own. A set-up made for another
            call is refused (:class:`~mixdyn.errors.ModelError`).
        **options: integrator options with a method's name (``solver="dopri8"``,
            ``alpha``, ``beta``, ``rho_inf``, ``max_steps``...: the fields of its class).

    Returns:
        A :class:`Result` with the motion, the multipliers' physical meaning (joint reactions
        ``{joint}.Fx``, ``.Fy``, ``.M``, driver efforts by driver name and their ``.power``),
        the force elements' columns (``{force}`` its magnitude, a spring's ``.length`` and
        ``.tension``, a rotary spring's ``.angle`` and ``.torque``, each one's ``.power``),
        energies (``energy.kinetic``, ``energy.potential``, ``energy.total``), accumulated
        work (``work.nonconservative``, ``work.constraints``), and counters in ``stats``.
    """
    case = forward_case(
        model,
        t,
        method=method,
        rtol=rtol,
        atol=atol,
        dt=dt,
        q0=q0,
        qd0=qd0,
        hold=hold,
        linear_solver=linear_solver,
        energy_tol=energy_tol,
        prepared=prepared,
        **options,
    )
    return simulate(case, progress)


def forward_case(
    model: Model,
    t,
    *,
    method: str | IntegratorOptions = "projection",
    rtol: float | None = None,
    atol: float | None = None,
    dt: float | None = None,
    q0=None,
    qd0=None,
    hold=(),
    linear_solver: str | LinearSolver = "auto",
    energy_tol: float | str | None = ENERGY_TOL,
    prepared: Prepared | None = None,
    **options,
) -> Case:
    """The set-up of a forward run (:func:`forward`'s arguments but ``progress``): its
    checked options, consistent start and equations, not yet integrated."""
    ts = output_times(t)
    opts, recorded = run_options(method, ts, dict(options, rtol=rtol, atol=atol, dt=dt), energy_tol)
    refuse_friction_in(model, opts.method)
    require_masses(model)
    if prepared is None:
        prep = prepare_dynamic(
            model, float(ts[0]), q0=q0, qd0=qd0, hold=hold, linear_solver=linear_solver
        )
    else:
        prep = use_prepared(
            prepared,
            model,
            float(ts[0]),
            what="forward",
            q0=q0,
            qd0=qd0,
            hold=hold,
            linear_solver=linear_solver,
        )
    # The partitioning integrator needs independent rows; the others solve redundant
    # constraints in the least-squares sense (robust where the redundancy moves).
    problem = Problem(model, prep.constraints(opts.method == "partitioning"))
    return Case(
        "forward",
        problem,
        ts,
        prep.q,
        prep.qd,
        opts,
        len(model.drivers),
        energy_tol,
        recorded,
        {"redundant_equations": prep.report.redundant},
    )
