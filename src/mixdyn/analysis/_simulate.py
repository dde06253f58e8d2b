"""What forward, inverse and mixed dynamics share after their start (:mod:`._prepare`): the
integrator call, failures turned into named errors, and results in physical terms."""

from __future__ import annotations

import dataclasses
import functools
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..equations import force_output_kinds, force_outputs, kinetic_energy, potential_energy
from ..equations._reaction_dependent import check_supported
from ..errors import (
    EnergyBalanceError,
    ModelError,
    NumericalError,
    SingularityError,
    StepSizeError,
)
from ..linalg import AutoSolver, LinearSolver, dependent_rows
from ..model import Model
from ..model._compliant import refuse_rigid, rigid_contacts
from ..runtime._programs import cached_jit
from . import _setup
from ._assembly import length_scale
from ._options import suggestions, value_problem
from ._problem import Problem
from ._reactions import (
    check_contacts,
    contact_columns,
    driver_efforts,
    joint_reactions,
    reaction_columns,
    reaction_kinds,
)
from ._structure import _jac
from .integrators import INTEGRATORS, STATUS_MESSAGES
from .integrators._common import (
    NEWTON_FAILED,
    STEP_COLLAPSE,
    UNCLOSED,
    progress_hook,
)
from .kinematic import output_times
from .methods import IntegratorOptions, Projection, as_method, check_steps, resolve
from .result import Partial, Result

#: Default tolerance of a dynamic run's energy balance (see :func:`energy_tolerance`).
ENERGY_TOL = "auto"
#: The energy balance of a run at relative tolerance ``rtol`` must hold to this many rtol...
ENERGY_PER_RTOL = 1e3
#: ...within these bounds; the upper one is also the fixed-step methods' tolerance.
ENERGY_TOL_RANGE = (1e-9, 1e-4)


def refuse_reaction_dependent_in(model: Model, options: IntegratorOptions) -> None:
    """Reaction-dependent forces are solved with the accelerations of the explicit
    integrators; a method whose iteration does not include them (generalized-alpha's Newton
    iteration: :attr:`~.methods.IntegratorOptions.reaction_dependent` false) refuses them
    (named input error)."""
    if not options.reaction_dependent:
        check_supported(
            model,
            f"the {options.method} method",
            "use projection (the default), partitioning or baumgarte",
        )


def require_masses(model: Model) -> None:
    """Every body of a dynamic run needs a positive mass and inertia."""
    for b in model.bodies:
        if not (float(b.mass) > 0 and float(b.inertia) > 0):
            raise ModelError(
                f"body has mass {float(b.mass):g} and inertia {float(b.inertia):g}; a dynamic "
                "analysis needs both > 0 (give the body a mass and a moment of inertia about its "
                "centre of mass, or weld it to a body that has them)",
                b.name,
            )


@cached_jit
def _post_arrays(problem: Problem, ts, Q, QD):
    """Per output time: accelerations, multipliers, pivot ratio, joint reactions (n_joints, 3),
    multipliers' powers, energies ``[T, V, T + V]`` and the constraint violation.

    ``lax.map`` (one time after the other), not ``vmap``: under ``vmap`` the fallback of the
    acceleration solve at singular positions (a ``lax.cond``) would run at every time. A
    sweep vectorizes this over its members (their constraint sets marked ``batched``: the
    fallback decided once per batch).
    On the sparse path everything comes from the constraints' sparse form: no dense
    ``Phi_q``.
    """
    c = problem.c

    def one(x):
        q, qd, t = x
        st = problem.stages(q, qd, t)  # Phi, Phi_q, accelerations: each evaluated once
        R = joint_reactions(c, q, t, st.mu, st.J)
        powers = problem.powers(q, qd, t, st.mu, st.J)
        T = kinetic_energy(problem.model, qd)
        V = potential_energy(problem.model, q)
        viol = jnp.max(jnp.abs(st.phi)) if c.m else jnp.zeros(())
        forces = force_outputs(problem.model, q, qd, t, exclude=problem.unknown)
        forces.update(contact_columns(c, q, st.mu[: c.m]))
        forces.update(problem.dependent_columns(st))
        return st.qdd, st.mu, st.ratio, R, powers, jnp.stack([T, V, T + V]), viol, forces

    return jax.lax.map(one, (Q, QD, ts))


def _post(problem: Problem, ts, Q, QD, n_drivers: int, arrays=None):
    """Accelerations, multipliers and pivot ratios (N, ...) at the output times ``ts`` of the
    states ``Q``, ``QD`` (N, nq), and the result columns in physical terms (NumPy arrays):
    reactions, driver efforts and powers, ``lambda.*``, unknown forces and their powers,
    energies and the constraint violation (``arrays``: :func:`_post_arrays`' output if
    already computed, e.g. for a whole sweep at once)."""
    if arrays is None:
        arrays = _post_arrays(problem, ts, Q, QD)
    qdd, mu, ratio, out = post_columns(problem, arrays, n_drivers)
    check_contacts(problem.c, np.asarray(ts), out)
    return qdd, mu, ratio, out


def post_columns(problem: Problem, arrays, n_drivers: int):
    """The result columns of :func:`_post_arrays`' output ``arrays`` (each of leading shape
    (N,), or (M*N,) for M members' times in a row: every column is read time by time),
    without the contacts' check: ``(qdd, mu, ratio, columns)``."""
    c = problem.c
    qdd, mu, ratio, R, powers, E, viol, forces = arrays
    mu, R, powers, E = (np.asarray(a) for a in (mu, R, powers, E))
    out = reaction_columns(c, R)
    out.update({k: np.asarray(v) for k, v in forces.items()})
    out.update(driver_efforts(c, mu, powers, n_drivers))
    for k in range(c.m - problem.p):
        out[f"lambda.{c.labels[c.active[k]]}"] = mu[:, k]
    for k, name in enumerate(problem.unknown):
        out[name] = mu[:, c.m - problem.p + k]
        out[f"{name}.power"] = powers[:, c.m - problem.p + k]
    out["energy.kinetic"], out["energy.potential"], out["energy.total"] = E[:, 0], E[:, 1], E[:, 2]
    out["constraint.violation"] = np.asarray(viol)
    return qdd, mu, ratio, out


def post_kinds(problem: Problem, n_drivers: int) -> dict[str, str]:
    kinds = reaction_kinds(problem.c)
    c = problem.c
    for k in range(c.m - problem.p):
        row = c.active[k]
        owner = c.owners[row]
        if owner >= len(c.joints):
            kind = c.drivers[owner - len(c.joints)].effort_kind
        else:
            kind = "torque" if c.labels[row].endswith(".angle") else "force"
        kinds[f"lambda.{c.labels[row]}"] = kind
    for d in problem.c.drivers[:n_drivers]:
        kinds[d.name] = d.effort_kind
        kinds[f"{d.name}.power"] = "power"
    for name in problem.unknown:
        kinds[name] = problem.model.element(name).magnitude_kind
        kinds[f"{name}.power"] = "power"
    kinds.update(force_output_kinds(problem.model, exclude=problem.unknown))
    kinds.update(
        {
            "energy.kinetic": "energy",
            "energy.potential": "energy",
            "energy.total": "energy",
            "work.nonconservative": "energy",
            "work.constraints": "energy",
            "constraint.violation": "length",
        }
    )
    return kinds


def _raise_failure(problem: Problem, traj, ts, method):
    status = int(traj.status)
    t = float(traj.t_fail)
    # Diagnose at the last accepted state (the failure), not at the last output time.
    q = np.asarray(traj.q_last)
    J = np.asarray(_jac(problem.c, q, np.asarray(t, dtype=np.float64)))
    rows = dependent_rows(J, 1e-8) if J.size else []
    names = []
    for i in rows:
        e = problem.c.element_names[problem.c.owners[problem.c.active[i]]]
        if e not in names:
            names.append(e)
    s = np.linalg.svd(J, compute_uv=False) if J.size else np.ones(1)
    r = problem.c.rank or min(J.shape) if J.size else 1
    # a step size that collapses where the Jacobian is poorly conditioned is a singular position
    limit = 1e-4 if status == STEP_COLLAPSE else 1e-6
    near_singular = bool(s[r - 1] < limit * s[0])
    singular = near_singular or status == UNCLOSED
    msg = f"{method} integrator failed: {STATUS_MESSAGES[status]}"
    if singular:
        where = "; the constraint Jacobian is (nearly) singular here" if near_singular else ""
        raise SingularityError(msg + where, t, names)
    cls = StepSizeError if status == STEP_COLLAPSE else NumericalError
    if status == NEWTON_FAILED:
        from ..errors import ConvergenceError

        cls = ConvergenceError
    raise cls(msg, t, names if singular else ())


def energy_tolerance(energy_tol, options: IntegratorOptions) -> float | None:
    """The relative tolerance of a run's energy balance: ``energy_tol`` itself, or for
    ``"auto"`` 1000 times the relative tolerance of an adaptive run (between 1e-9 and 1e-4: a
    run that drifts far beyond what its tolerance promises does not meet its tolerance) and
    1e-4 for a run at a fixed step."""
    if energy_tol != "auto":
        return energy_tol
    lo, hi = ENERGY_TOL_RANGE
    if options.fixed_step or options.dt is not None:
        return hi
    return min(hi, max(lo, ENERGY_PER_RTOL * float(options.rtol)))


def run_options(
    method: str | IntegratorOptions, ts, options: dict, energy_tol=ENERGY_TOL
) -> tuple[IntegratorOptions, dict]:
    """The checked integrator options of a run (before any computing) as their typed object,
    and the options it records: a bad ``energy_tol``, an unknown method or option, a value
    out of range, an absurd step count, or an options object given with integrator keywords
    too, are input errors (:func:`~.methods.resolve`).

    Args:
        method: a method's name or its options object (:mod:`.methods`).
        ts: (N,) output times [time].
        options: the integrator keywords of the run (``rtol``, ``atol``, ``dt`` and the
            method's own; None: not given).
        energy_tol: the run's energy tolerance (checked here).
    """
    problem = value_problem("energy_tol", energy_tol)
    if problem:
        raise ModelError(f"energy_tol {problem}, got {energy_tol!r}", "energy_tol")
    return resolve(method, np.asarray(ts), options)


def check_energy_balance(
    problem: Problem, ts, Q, extra, ratio, options: IntegratorOptions, energy_tol
) -> float:
    """The energy balance of a dynamic run, ``T + V - E0 - W_nc - W_c`` [energy], relative to
    its energy scale; raise past ``energy_tol``.

    Every dynamic run obeys ``T(t) + V(t) = T(0) + V(0) + W_nc(t) + W_c(t)``: the work of the
    non-conservative applied forces and of the constraint forces (drivers, prescribed
    motions, unknown forces, Baumgarte terms) is integrated along with the motion. Projection
    and integration errors keep the balance at the level of the tolerances; a jump to
    another branch at a singular position (a parallelogram that folds, a crank that locks)
    changes the velocities at one instant and breaks the balance by a finite amount, which is
    how it is detected. The scale is the largest of the energies' ranges and the works
    (and the model's mass times its length scale squared over the span squared, so that a
    run at rest is not held to rounding).

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time].
        Q: (N, nq) positions at ``ts`` (to name the elements at the failure).
        extra: result columns (``energy.*``, ``work.*``).
        ratio: (N,) pivot ratios at ``ts`` (to tell a singular position).
        options: the integrator's options (its name and whether it damps, for the message).
        energy_tol: relative tolerance, or None to skip the check.

    Returns:
        The largest relative balance error.

    Raises:
        EnergyBalanceError: at the first output time past the tolerance.
    """
    T, V = extra["energy.kinetic"], extra["energy.potential"]
    Wn, Wc = extra["work.nonconservative"], extra["work.constraints"]
    bal = (T + V) - (T[0] + V[0]) - Wn - Wc
    span = float(ts[-1] - ts[0])
    mass = float(sum(np.asarray(b.mass) for b in problem.model.bodies))
    rest = mass * (length_scale(problem.model) / span) ** 2
    scale = max(np.ptp(T), np.ptp(V), np.max(np.abs(Wn)), np.max(np.abs(Wc)), rest, 1e-300)
    rel = np.abs(bal) / scale
    if not np.all(np.isfinite(rel)):
        return float("nan")  # the result's own check names the non-finite column
    worst = float(np.max(rel))
    if energy_tol is None or worst <= energy_tol:
        return worst
    k = int(np.argmax(~(rel <= energy_tol)))
    k0 = max(k - 1, 0)
    near = k0 + int(np.argmin(ratio[k0 : k + 1]))
    singular = float(np.min(ratio[: k + 1])) < 1e-3
    names = []
    if singular:
        J = np.asarray(_jac(problem.c, Q[near], np.asarray(ts[near], dtype=np.float64)))
        for i in dependent_rows(J, 1e-3) if J.size else []:
            e = problem.c.element_names[problem.c.owners[problem.c.active[i]]]
            if e not in names:
                names.append(e)
    cause = (
        "the motion most likely left its branch at a singular position (the constraint "
        f"Jacobian's pivot ratio fell to {float(np.min(ratio[: k + 1])):.1e} before this time)"
        if singular
        else "the steps are too large for the accuracy asked, or the motion left its branch"
    )
    method = options.method
    if options.damps:
        cause += (
            f" ({method} also damps unresolved high frequencies by design, rho_inf "
            "< 1: if that loss is intended, set energy_tol=None)"
        )
    raise EnergyBalanceError(
        f"{method} run broke its energy balance by {abs(bal[k]):.3g} [energy], "
        f"{rel[k]:.1e} of its energy scale {scale:.3g} (tolerance {energy_tol:g}): {cause}; "
        "use a smaller step or tighter tolerances, another method (projection with "
        "solver='tsit5' passes singular positions best), or energy_tol=None to accept it",
        float(ts[k]),
        names,
    )


@functools.cache
def _integrator(method: str):
    """The integrator ``method``, its traced programs kept in the persistent cache (one
    wrapper per method: a program read or prepared once serves every later run)."""
    return cached_jit(INTEGRATORS[method])


@dataclasses.dataclass(frozen=True)
class Case:
    """One dynamic run, set up (consistent start, constraint set, checked options) and not
    yet integrated: what :func:`integrate` and :func:`finish` need, so that a sweep
    (:mod:`.sweep`) can integrate many cases as one program and finish each alike.

    Attributes:
        kind: ``"forward"`` or ``"mixed"``.
        problem: the equations of motion.
        ts: (N,) output times [time].
        q0, qd0: (nq,) consistent start [model units].
        options: the integrator's options (checked by :func:`run_options`).
        n_drivers: the model's own drivers (the first rows of the drivers).
        energy_tol: the run's energy tolerance (see :func:`energy_tolerance`).
        recorded: the options the result records (default: ``options.recorded()``).
        stats: what the analysis adds to the result's ``stats``.
    """

    kind: str
    problem: Problem
    ts: np.ndarray
    q0: jax.Array
    qd0: jax.Array
    options: IntegratorOptions
    n_drivers: int
    energy_tol: float | str | None = ENERGY_TOL
    recorded: dict | None = None
    stats: dict = dataclasses.field(default_factory=dict)


class Integrated(_setup.Analysis):
    """The options that forward and mixed dynamics share (see either): the integration
    method with its options, the energy balance's tolerance, the start and the linear
    solver."""

    integrated: ClassVar[bool] = True

    _: dataclasses.KW_ONLY
    method: IntegratorOptions = eqx.field(default=Projection(), converter=as_method)
    energy_tol: float | str | None = eqx.field(
        default=ENERGY_TOL, converter=_setup.checked("energy_tol")
    )
    q0: np.ndarray | None = eqx.field(default=None, converter=_setup.start_positions)
    qd0: np.ndarray | dict | None = eqx.field(default=None, converter=_setup.start_velocities)
    hold: tuple[str, ...] = eqx.field(default=(), converter=_setup.held)
    linear_solver: LinearSolver = eqx.field(default=AutoSolver(), converter=_setup.linear_solver)

    @classmethod
    def _elsewhere(cls, key: str, kwargs: dict) -> str:
        method = kwargs.get("method", "projection")
        from .methods import OPTIONS

        options = type(method) if isinstance(method, IntegratorOptions) else OPTIONS.get(method)
        if options is None:
            return ""
        spelled = f"method=mixdyn.{options.__name__}({{}}=...)"
        if key in options.defaults():
            return f"{key} is an option of the integrator: give {spelled.format(key)}; "
        close = suggestions(key, options.defaults())
        return f"did you mean {spelled.format(close[0])}? " if close else ""

    def _start(self) -> dict:
        """The start settings, as the keywords of :func:`~._prepare.dynamic_start`."""
        return _setup.start_of(self, "q0", "qd0", "hold", "linear_solver")

    def _start_forces(self) -> tuple[str, ...]:
        """The force elements whose numbers enter the start (a mixed run's unknown forces,
        whose directions its solvability check reads)."""
        return ()

    def _shares_setup(self, setup: _setup.Setup) -> bool:
        """Whether members of a sweep that differ only in masses, inertias and the numbers
        of known forces can share ``setup`` (:func:`~.sweep.shares_start`)."""
        return True

    def _case(self, setup: _setup.Setup, t) -> Case:
        """The run of ``setup`` over the output times ``t`` (N,) [time], set up and not yet
        integrated (its step count checked against ``max_steps``)."""
        ts = output_times(t)
        _setup.check_start(setup, ts)
        check_steps(self.method, ts)
        start = setup.start
        return Case(
            self.name,
            setup.problem,
            ts,
            start.q,
            start.qd,
            self.method,
            len(setup.model.drivers),
            self.energy_tol,
            setup.recorded,
            dict(setup.stats),
        )

    def _run(self, setup: _setup.Setup, t, progress=None) -> Result:
        return simulate(self._case(setup, t), progress)

    @classmethod
    def _from_keywords(cls, t, kwargs: dict) -> tuple[Integrated, dict]:
        """The keyword spelling (``method`` a name or an object, ``rtol``, ``atol``, ``dt``
        and the method's own options beside the analysis' fields) as the value, and the
        options its results record (:func:`run_options`: the options given, with a name)."""
        fields = {f.name for f in dataclasses.fields(cls)}
        kw = {k: v for k, v in kwargs.items() if k != "prepared"}
        method = kw.pop("method", "projection")
        rtol, atol, dt = (kw.pop(k, None) for k in ("rtol", "atol", "dt"))
        energy_tol = kw.pop("energy_tol", ENERGY_TOL)
        own = {k: kw.pop(k) for k in list(kw) if k in fields}
        ts = output_times(t)
        options, recorded = run_options(
            method, ts, dict(kw, rtol=rtol, atol=atol, dt=dt), energy_tol
        )
        return cls(method=options, energy_tol=energy_tol, **own), recorded

    @classmethod
    def _spelling(cls, kwargs: dict) -> str:
        """The value that the keyword spelling ``kwargs`` reads as, for a message."""
        fields = {f.name for f in dataclasses.fields(cls)}
        method = kwargs.get("method", "projection")
        options = [k for k in kwargs if k not in fields and k not in ("method", "prepared")]
        if isinstance(method, IntegratorOptions):
            spelled = [f"method={type(method).__name__}(...)"]
        elif options or method != "projection":
            from .methods import OPTIONS

            name = getattr(OPTIONS.get(method), "__name__", "Projection")
            spelled = [f"method=mixdyn.{name}({', '.join(f'{k}=...' for k in options)})"]
        else:
            spelled = []
        spelled += [f"{k}=..." for k in kwargs if k in fields and k != "method"]
        return f"mixdyn.analyses.{cls.__name__}({', '.join(spelled)})"


def integrate(case: Case, progress=None):
    """The trajectory of ``case`` (an :class:`~.integrators.Trajectory`); ``progress``: an
    optional ``f(t)`` called at each output time."""
    refuse_rigid(case.problem.model, "a run integrated in one program (a sweep)")
    integrator = _integrator(case.options.method)
    # A progress callback is passed as a key into a registry: one program for every callback.
    with progress_hook(progress) as cb:
        return integrator(*_integrator_args(case), progress=cb)


def _integrator_args(case: Case) -> tuple:
    """The integrator's positional arguments for ``case``."""
    ts = np.asarray(case.ts, dtype=np.float64)
    return case.problem, ts, case.q0, case.qd0, case.options.as_argument()


def finish(case: Case, traj, arrays=None) -> Result:
    """The result of ``case`` from its trajectory ``traj``, in physical terms; a failed or
    unbalanced run raises its named error (:class:`~mixdyn.errors.NumericalError`), which
    carries as ``partial`` the states computed up to its time (:class:`~.result.Partial`).
    ``arrays``: the post-processing's arrays (:func:`_post_arrays`) if already computed."""
    try:
        return _finish(case, traj, arrays)
    except NumericalError as e:
        if getattr(e, "partial", None) is None:
            e.partial = Partial.before(case.problem.model, case.ts, traj.q, traj.qd, e.time)
        raise


def _finish(case: Case, traj, arrays=None) -> Result:
    problem, ts, options = case.problem, case.ts, case.options
    method = options.method
    if int(traj.status) != 0:
        _raise_failure(problem, traj, ts, method)
    Q, QD, W = np.asarray(traj.q), np.asarray(traj.qd), np.asarray(traj.w)
    qdd, _, ratio, cols = _post(
        problem, np.asarray(ts, dtype=np.float64), Q, QD, case.n_drivers, arrays
    )
    extra = {k: np.asarray(v) for k, v in cols.items()}
    extra["work.nonconservative"] = W[:, 0]
    extra["work.constraints"] = W[:, 1]
    ratio = np.asarray(ratio)
    if not np.all(np.isfinite(np.asarray(qdd))):
        k = int(np.argmax(~np.all(np.isfinite(np.asarray(qdd)), axis=1)))
        raise SingularityError(
            "accelerations are not finite: singular equations of motion", float(ts[k])
        )
    tol = energy_tolerance(case.energy_tol, options)
    balance = check_energy_balance(problem, ts, Q, extra, ratio, options, tol)
    stats = {
        "method": method,
        "options": dict(options.recorded() if case.recorded is None else case.recorded),
        "steps": int(traj.steps),
        "rejected_steps": int(traj.rejected),
        "newton_iterations": int(traj.newton),
        "max_violation_before_projection": float(traj.max_violation),
        "max_violation": float(np.max(extra["constraint.violation"])),
        "min_pivot_ratio": float(np.min(ratio)),
        "energy_balance_error": balance,
        "constraint_rows": problem.c.active_labels,
        "unknown_forces": problem.unknown,
        "linear_solver": problem.c.linear_solver.name,
    }
    stats.update(case.stats)
    return Result(
        kind=case.kind,
        model=problem.model,
        t=ts,
        q=Q,
        qd=QD,
        qdd=np.asarray(qdd),
        extra=extra,
        kinds=post_kinds(problem, case.n_drivers),
        stats=stats,
    )


def simulate(case: Case, progress=None) -> Result:
    """Integrate ``case`` from its consistent start and build the result (``progress``: an
    optional ``f(t)`` called at each output time). A run whose energy balance breaks by more
    than its energy tolerance fails (:func:`check_energy_balance`).

    The post-processing's program is prepared beside the integration (read, or traced and
    compiled, in a second thread: :meth:`mixdyn.runtime._programs._CachedJit.ahead`).
    A forward or mixed run of a model with rigid contacts is integrated impact by impact
    instead (:func:`~._impacts.simulate_impacts`, which those analyses call)."""
    _post_ahead(case)
    return finish(case, integrate(case, progress))


def _post_ahead(case: Case) -> None:
    n, nq = len(case.ts), int(np.shape(case.q0)[-1])
    states = np.zeros((n, nq))
    _post_arrays.ahead(case.problem, np.asarray(case.ts, dtype=np.float64), states, states)


def ahead(case: Case) -> None:
    """Prepare the programs :func:`simulate` will call for ``case`` (its integrator's and
    its post-processing's) in second threads (:meth:`mixdyn.runtime._programs._CachedJit.ahead`),
    while earlier work goes on: a model file's next run while the one before it computes.
    ``case`` counts by its structure and shapes only. Without a progress callback."""
    if rigid_contacts(case.problem.model):
        return
    _integrator(case.options.method).ahead(*_integrator_args(case), progress=None)
    _post_ahead(case)


__all__ = [
    "Case",
    "Integrated",
    "ahead",
    "finish",
    "integrate",
    "output_times",
    "require_masses",
    "simulate",
]
