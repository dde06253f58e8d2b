"""A run's set-up: its model, its start and its analysis.

:func:`analysis_of` reads a run as what it computes (:class:`RunAnalysis`): its analysis value
(:mod:`mixdyn.analyses`, made from the run's settings), its model and the start it starts
from; :meth:`RunAnalysis.run` prepares and runs it (:func:`mixdyn.prepare`,
:func:`mixdyn.run`). :func:`prepare` makes a run's start as its analysis makes it (the
consistent start of a dynamic run or the assembled one of a kinematic, inverse or statics
run, and the mobility analysis there), once per run and once for runs with the same start
(:class:`Setups`). The checks (:func:`.checks.mobility`) make it, and the run is prepared
from it (``mixdyn.prepare(..., start=...)``), so that the check and the run share one
assembly and one rank analysis.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from .. import analysis as an
from .. import model as m
from ..analysis._keywords import from_keywords
from ..analysis._prepare import Prepared
from ..analysis._setup import Analysis, Setup
from ..analysis._setup import prepare as prepare_analysis
from ..analysis._setup import run as run_setup
from ..analysis.mixed import bind_prescribed
from ..errors import ModelError, NumericalError
from ..io import schema as s
from .kinds import kind_of
from .plan import Plan


@dataclasses.dataclass(frozen=True)
class RunAnalysis:
    """What a run computes: its analysis value on its model, from its start.

    Attributes:
        kind: the run kind's name (``"forward"``...).
        model: the run's model (its drivers selected; a mixed run's prescribed motions are
            the analysis').
        analysis: the analysis value made from the run's settings.
        recorded: the integrator options its result records (``stats["options"]``: the
            run's settings), or None (the method object's own).
        start: the start the checks made (:func:`prepare`), or None (the analysis makes its
            own).
    """

    kind: str
    model: m.Model
    analysis: Analysis
    recorded: dict | None = None
    start: Prepared | None = None

    def setup(self, t0: float) -> Setup:
        """The run's set-up from the start time ``t0`` [time] (:func:`mixdyn.prepare`)."""
        setup = prepare_analysis(self.model, self.analysis, t0=t0, start=self.start)
        if self.recorded is None:
            return setup
        return dataclasses.replace(setup, recorded=self.recorded)

    def run(self, times, progress: Callable | None = None):
        """The run over the output times ``times`` (N,) [time] (:func:`mixdyn.run`)."""
        return run_setup(self.setup(float(times[0])), times, progress=progress)


@dataclasses.dataclass
class Setups:
    """What a runner keeps of its runs' set-ups.

    Attributes:
        prepared: run name -> ``(start arguments, Prepared)``: the start the checks made,
            which the run starts from.
        made: the starts by what they are made from (runs with the same start share one), or
            the error met making one (not made again by the checks that follow).
        checked: mixed runs' set-ups for :func:`.checks.check_solvable`: run name ->
            ``(model, q0, qd0, prescribed motions, Prepared)``.
        mobility: assemblies and mobility analyses of the checks, by what they depend on.
        solvable: the mixed runs found solvable.
    """

    prepared: dict = dataclasses.field(default_factory=dict)
    made: dict = dataclasses.field(default_factory=dict)
    checked: dict = dataclasses.field(default_factory=dict)
    mobility: dict = dataclasses.field(default_factory=dict)
    solvable: set = dataclasses.field(default_factory=set)


def start_q(model: m.Model) -> np.ndarray:
    """The bodies' rough start ``q0`` stacked with NumPy (``Model.q0`` compiles a JAX
    concatenation of every body, whose compile time grows quadratically with their number)."""
    return np.concatenate([np.asarray(b.q0, dtype=float) for b in model.bodies])


def q_start(runner, plan: Plan, model: m.Model) -> np.ndarray:
    """Rough starting coordinates of a run: the bodies' q0 with the run's ``initial``."""
    q = start_q(model)
    for ref, value in plan.spec.initial.items():
        _, coord = ref.split(".")
        q[model.coordinate_index(ref)] = runner.b.scalar(
            value, position_kind(coord), (*plan.path, "initial", ref)
        )
    return q


def qd_start(runner, plan: Plan, model: m.Model) -> dict[str, float] | None:
    """The run's ``velocities``: velocity conditions ``{coordinate: value}`` (model units)
    that the analysis keeps exactly, the other velocities following; None if none."""
    if not plan.spec.velocities:
        return None
    qd = {}
    for ref, value in plan.spec.velocities.items():
        _, coord = ref.split(".")
        model.coordinate_index(ref)
        qd[ref] = runner.b.scalar(value, velocity_kind(coord), (*plan.path, "velocities", ref))
    return qd


def hold_of(runner, plan: Plan) -> tuple[str, ...]:
    """The coordinates a run holds at its start: kept at their starting value while the
    joints are closed (and, in a dynamic run, at their starting speed).

    The run's own ``hold``, else the file's ``assembly.hold``. A mixed run does not inherit a
    hold on a coordinate it prescribes: the prescribed motion fixes that coordinate's start
    position and speed, so it wins and that hold is dropped for the run (a run's own ``hold``
    naming a coordinate it prescribes is refused when the run is planned).

    Args:
        runner: the file's runner.
        plan: the run.

    Returns:
        The held coordinates, e.g. ``("crank.phi",)``.
    """
    if plan.spec.hold is not None:
        return tuple(plan.spec.hold)
    prescribed = _prescribed_coordinates(plan)
    return tuple(h for h in runner.spec.assembly.hold if h not in prescribed)


def _prescribed_coordinates(plan: Plan) -> set[str]:
    """The body coordinates (``body.x``, ``.y``, ``.phi``) a mixed run prescribes."""
    if not isinstance(plan.spec, s.MixedRunSpec):
        return set()
    return {p.coordinate for p in plan.spec.prescribed if p.coordinate.count(".") == 1}


def hold_source(plan: Plan) -> tuple[tuple, str]:
    """Where a run's hold comes from: its path in the file and how to name it."""
    if plan.spec.hold is not None:
        return (*plan.path, "hold"), "the run's hold"
    return ("assembly", "hold"), "assembly.hold"


def run_model(runner, plan: Plan, drivers: Sequence[m.Driver] = ()) -> m.Model:
    """The model of a run: the model's drivers it selects, plus extra drivers."""
    r = plan.spec
    model = runner.model
    selected = (
        model.drivers
        if r.drivers is None
        else tuple(d for d in model.drivers if d.name in set(r.drivers))
    )
    all_drivers = (*selected, *drivers)
    if tuple(all_drivers) == tuple(model.drivers):
        return model
    return model.replace(drivers=all_drivers)


def prescribed_driver(runner, p: s.PrescribedSpec, path) -> m.Driver:
    """The driver of a prescribed motion given by a law (unbound: :func:`mixdyn.mixed` binds
    a mixed run's motions to its bodies)."""
    parts = p.coordinate.split(".")
    name = p.name or f"prescribed {p.coordinate}"
    if len(parts) == 3:
        law = runner.b.law(p.law, "length", (*path, "law"))
        return m.PointDriver(
            name, f"{parts[0]}.{parts[1]}", parts[2], law=law, continuity=p.continuity
        )
    kind = "angle" if parts[1] == "phi" else "length"
    return m.CoordinateDriver(
        name,
        parts[0],
        parts[1],
        law=runner.b.law(p.law, kind, (*path, "law")),
        continuity=p.continuity,
    )


def dummy_driver(k, p: s.PrescribedSpec) -> m.Driver:
    """An unbound stand-in (law 0) for the motion ``p`` replays from another run."""
    parts = p.coordinate.split(".")
    name = p.name or f"prescribed {p.coordinate}"
    if len(parts) == 3:
        return m.PointDriver(name, f"{parts[0]}.{parts[1]}", parts[2], law=0.0)
    return m.CoordinateDriver(name, parts[0], parts[1], law=0.0)


def prepare(runner, plan: Plan) -> Prepared:
    """The run's start, made as its analysis makes it (the analysis value's own start: the
    consistent start of a dynamic run or the assembled one of a kinematic, inverse or
    statics run, and the mobility analysis there). Kept for :func:`analysis_of`, whose run
    is prepared from it; made once per run (and once for runs with the same start).

    Args:
        runner: the file's runner.
        plan: a run that replays no other run's motion (``from_run``: that motion is known
            only once the other run has run).

    Returns:
        The :class:`~mixdyn.analysis._prepare.Prepared` start (its drivers are not checked
        against the degrees of freedom here: :func:`.checks.mobility` reports that).

    Raises:
        ModelError, NumericalError: the start cannot be made (the run itself would fail
            there).
    """
    setups = runner.setups
    kept = setups.prepared.get(plan.name)
    if kept is not None:
        return kept[1]
    if plan.replays:
        raise ModelError("a run replaying another run's motion prepares itself", plan.name)
    r = plan.spec
    mixed = isinstance(r, s.MixedRunSpec)
    laws = [
        prescribed_driver(runner, p, (*plan.path, "prescribed", k))
        for k, p in enumerate(r.prescribed)
    ]
    model = run_model(runner, plan, () if mixed else laws)
    args = start_args(runner, plan, model)
    t0 = float(plan.times[0])
    value, _ = from_keywords(kind_of(plan).name, plan.times, _keywords(runner, plan, args, laws))
    drivers = (*model.drivers, *(bind_prescribed(model, laws) if mixed else ()))
    key = (
        type(value)._initial,  # the analyses that make their start alike share it
        drivers_key(drivers),
        t0,
        tuple(sorted((k, _arg_key(v)) for k, v in args.items())),
    )
    made = setups.made
    if key not in made:
        try:
            made[key] = value._initial(model, t0)
        except (ModelError, NumericalError) as e:
            made[key] = e  # not made again by the checks that follow
    if isinstance(made[key], Exception):
        raise made[key]
    setups.prepared[plan.name] = (args, made[key])
    return made[key]


def start_args(runner, plan: Plan, model: m.Model) -> dict:
    """The arguments a run's analysis makes its start from: ``q0`` (the rough start),
    ``hold``, ``linear_solver``, and ``qd0`` (a run integrated in time) or ``assemble_first``
    (a run whose drivers fix the motion; an inverse run's option). A run that does not
    assemble first starts from the rough start closed with its held coordinates."""
    r = plan.spec
    kind = kind_of(plan)
    opts = getattr(r, "options", {}) or {}
    ls = opts.get("linear_solver", r.linear_solver)
    q0 = q_start(runner, plan, model)
    hold = hold_of(runner, plan)
    if kind.integrated:
        qd0 = qd_start(runner, plan, model)
        return dict(q0=q0, qd0=qd0, hold=hold, linear_solver=ls)
    first = kind.assembles_first(opts)
    if hold and not first:
        q0 = np.asarray(an.assemble(model, q0, hold=hold, linear_solver=ls).q)
        hold = ()
    return dict(q0=q0, hold=hold, assemble_first=first, linear_solver=ls)


def call(
    runner, plan: Plan, results: dict, *, checked: bool = True, stand_ins: bool = False
) -> tuple[str, m.Model, dict]:
    """What a run computes as ``(kind, model, keywords)``: the keyword spelling of its
    analysis (:func:`mixdyn.analysis._keywords.from_keywords` reads it as the value).

    Args:
        runner: the file's runner.
        plan: the run.
        results: the results of the runs it replays (``from_run``).
        checked: on the model of the start the checks made (:func:`.checks.mobility`), if
            any.
        stand_ins: a replayed motion by the stand-in its checks made (held at its start
            value, in the replayed law's form: :func:`.checks.start.held`) instead of ``results``.
    """
    kind, model, keywords, _ = _call(runner, plan, results, checked, stand_ins)
    return kind, model, keywords


def analysis_of(
    runner, plan: Plan, results: dict, *, checked: bool = True, stand_ins: bool = False
) -> RunAnalysis:
    """What a run computes (:class:`RunAnalysis`), from the start the checks made where
    ``checked`` (:func:`prepare`); arguments as :func:`call`.

    Raises:
        ModelError: a setting the analysis refuses.
    """
    kind, model, keywords, start = _call(runner, plan, results, checked, stand_ins)
    value, recorded = from_keywords(kind, plan.times, keywords)
    return RunAnalysis(kind, model, value, recorded, start)


def _call(runner, plan: Plan, results: dict, checked: bool, stand_ins: bool):
    """``(kind, model, keywords, start)`` of a run (:func:`call`)."""
    r = plan.spec
    drivers = []
    for k, p in enumerate(r.prescribed):
        if p.from_run is not None and stand_ins:
            law = runner.setups.checked[plan.name][3][k].law  # KeyError: not checked so
            drivers.append(dataclasses.replace(dummy_driver(k, p), law=law))
        elif p.from_run is not None:
            src = results[p.from_run]
            t0, t1 = float(src.t[0]), float(src.t[-1])
            if plan.times[0] < t0 - 1e-12 or plan.times[-1] > t1 + 1e-12:
                runner.fail(
                    (*plan.path, "prescribed", k, "from_run"),
                    f"run {p.from_run!r} covers t = {t0:g}..{t1:g}, this run needs "
                    f"{plan.times[0]:g}..{plan.times[-1]:g}",
                    "run the source over at least this run's time span",
                )
            try:
                drivers.append(an.prescribe(src, p.coordinate, p.name))
            except ModelError as e:
                runner.model_error(plan, e)
        else:
            drivers.append(prescribed_driver(runner, p, (*plan.path, "prescribed", k)))
    mixed = isinstance(r, s.MixedRunSpec)
    # The start the check made (mobility), if any: the run starts from it, not assembled
    # and analysed again.
    no_setup = (None, None)
    args, prep = runner.setups.prepared.get(plan.name, no_setup) if checked else no_setup
    model = prep.model if prep is not None else run_model(runner, plan, () if mixed else drivers)
    if args is None:
        args = start_args(runner, plan, model)
    return kind_of(plan).name, model, _keywords(runner, plan, args, drivers), prep


def _keywords(runner, plan: Plan, args: dict, drivers: Sequence[m.Driver]) -> dict:
    """The keywords of a run's analysis (:meth:`.analyses.AnalysisKind.keywords`): its start
    arguments ``args``, options, step and prescribed motions ``drivers``."""
    r = plan.spec
    opts = dict(getattr(r, "options", {}) or {})
    opts.pop("linear_solver", None)
    dt = None
    if getattr(r, "dt", None) is not None:
        dt = runner.b.scalar(r.dt, "time", (*plan.path, "dt"))
    return kind_of(plan).keywords(r, args, opts, dt, drivers)


def drivers_key(drivers) -> tuple:
    """The drivers' kinds, structure and numbers, for the caches of set-ups."""
    import jax

    out = []
    for d in drivers:
        leaves, treedef = jax.tree_util.tree_flatten(d)
        out.append((treedef, tuple(np.asarray(x).tobytes() for x in leaves)))
    return tuple(out)


def _arg_key(value):
    """A start argument (an array, a mapping of velocities, a hold...) as a key."""
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, dict):
        return ("map", tuple(sorted((k, _arg_key(v)) for k, v in value.items())))
    return value


def position_kind(coord: str) -> str:
    """The kind of quantity of a body coordinate (``x``, ``y`` or ``phi``)."""
    return "angle" if coord == "phi" else "length"


def velocity_kind(coord: str) -> str:
    """The kind of quantity of a body coordinate's rate."""
    return "angular_velocity" if coord == "phi" else "velocity"


__all__ = [
    "RunAnalysis",
    "Setups",
    "analysis_of",
    "call",
    "drivers_key",
    "dummy_driver",
    "hold_of",
    "hold_source",
    "prepare",
    "prescribed_driver",
    "q_start",
    "qd_start",
    "run_model",
    "start_args",
    "start_q",
]
