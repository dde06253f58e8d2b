from __future__ import annotations

from typing import ClassVar

from ..linalg import LinearSolver
from ..model import Model
from ..model._compliant import rigid_contacts
from ._prepare import Prepared, dynamic_start
from ._problem import Problem
from ._setup import Setup, keyword_setup
from ._simulate import (
    ENERGY_TOL,
    Integrated,
    output_times,
    refuse_reaction_dependent_in,
    require_masses,
    simulate,
)
from .methods import IntegratorOptions
from .result import Result


class Forward(Integrated):
    """Forward dynamics as a value: the forces known, the motion sought from a consistent
    start (``md.forward``'s options, for :func:`~mixdyn.prepare` and the studies).

    ``Forward(method=md.Projection(rtol=1e-10))`` prepared and run over ``t`` is
    ``md.forward(model, t, method=md.Projection(rtol=1e-10))``, bit for bit.

    Attributes:
        method: the integration method with its options: an object of
            :class:`~mixdyn.Projection` (default), :class:`~mixdyn.Partitioning`,
            :class:`~mixdyn.Baumgarte` or :class:`~mixdyn.GeneralizedAlpha`, or a method's
            name with its default options (``"projection"``; a fixed-step method needs its
            object, with ``dt``).
        energy_tol: relative tolerance of the run's energy balance ``T + V - E0 - W``
            against its energy scale [-]: ``"auto"`` (default: 1000 x ``rtol`` of an
            adaptive method within [1e-9, 1e-4], 1e-4 at a fixed step), a number, or None
            (not checked).
        q0: (nq,) rough initial positions [model units], or None (the bodies' ``q0``).
        qd0: initial velocities [model units / time]: None (the least consistent ones),
            velocity conditions ``{"crank.phi": 1.0}`` (kept exactly, the others follow) or a
            full (nq,) vector (consistent).
        hold: coordinates (``"crank.phi"``) kept at their given values while assembling.
        linear_solver: a :class:`~mixdyn.LinearSolver` or its name (``"auto"``, default;
            ``"dense"``, ``"sparse"``): the path of every linear solve of the run.
    """

    name: ClassVar[str] = "forward"

    def _initial(self, model: Model, t0: float, given: Prepared | None = None) -> Prepared:
        return dynamic_start(model, t0, given, **self._start())

    def _prepare(self, model: Model, t0: float, given: Prepared | None = None) -> Setup:
        refuse_reaction_dependent_in(model, self.method)
        if rigid_contacts(model):  # (the impacts' module is loaded where there are some)
            from ._impacts import refuse_rigid_method

            refuse_rigid_method(model, self.method)
        require_masses(model)
        prep = self._initial(model, t0, given)
        # The partitioning integrator needs independent rows; the others solve redundant
        # constraints in the least-squares sense (robust where the redundancy moves).
        problem = Problem(model, prep.constraints(self.method.independent_rows))
        stats = {"redundant_equations": prep.report.redundant}
        return Setup(self, model, t0, prep, problem, stats)

    def _shares_setup(self, setup: Setup) -> bool:
        """A sweep's members with rigid contacts run one by one (each impact by impact)."""
        return not rigid_contacts(setup.model)

    def _run(self, setup: Setup, t, progress=None) -> Result:
        if rigid_contacts(setup.model):  # integrated impact by impact
            from ._impacts import simulate_impacts

            return simulate_impacts(self._case(setup, t), progress)
        return simulate(self._case(setup, t), progress)


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
        prepared: deprecated (a DeprecationWarning names the new spelling): the start of an
            earlier set-up (``setup.start``) made from the same model, start time ``t[0]``,
            ``q0``, ``qd0``, ``hold`` and ``linear_solver``, as
            ``mixdyn.prepare(model, mixdyn.analyses.Forward(...), t0=t[0], start=...)``
            takes it; a start made otherwise is refused (:class:`~mixdyn.errors.ModelError`).
        **options: integrator options with a method's name (``solver="dopri8"``,
            ``alpha``, ``beta``, ``rho_inf``, ``max_steps``...: the fields of its class).

    Returns:
        A :class:`Result` with the motion, the multipliers' physical meaning (joint reactions
        ``{joint}.Fx``, ``.Fy``, ``.M``, driver efforts by driver name and their ``.power``),
        the force elements' columns (``{force}`` its magnitude, a spring's ``.length`` and
        ``.tension``, a rotary spring's ``.angle`` and ``.torque``, each one's ``.power``),
        energies (``energy.kinetic``, ``energy.potential``, ``energy.total``), accumulated
        work (``work.nonconservative``, ``work.constraints``), and counters in ``stats``.
        A model with rigid contacts (``contact_model="rigid"``) is integrated from impact to
        impact (:mod:`mixdyn.analysis._impacts`, with ``method="projection"``): columns
        ``{contact}.impulse``, ``{contact}.normal`` (the normal force of a resting
        contact) and ``work.impacts``, each impact in ``stats["impacts"]`` and each rest in
        ``stats["rests"]``; a body coming to rest on one rests on it until it lifts off.
    """
    ts = output_times(t)
    analysis, recorded = Forward._from_keywords(
        ts,
        dict(
            method=method,
            rtol=rtol,
            atol=atol,
            dt=dt,
            q0=q0,
            qd0=qd0,
            hold=hold,
            linear_solver=linear_solver,
            energy_tol=energy_tol,
            **options,
        ),
    )
    setup = keyword_setup(model, analysis, float(ts[0]), recorded, prepared)
    return analysis._run(setup, ts, progress)


__all__ = ["Forward", "forward"]
