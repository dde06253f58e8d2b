"""A run's settings, checked when it is planned: its ``options`` (only the names its analysis
takes, none that repeats a setting of the run itself, every value of the right type, finite
and in range), its step (a fixed-step method's ``dt``, ``span / dt`` within ``max_steps``;
the projection method's adaptive steps for rigid contacts),
and a mixed run's unknown forces paired one to one with its prescribed motions; then its
outputs (:mod:`.outputs`) and laws (:mod:`.laws`)."""

from __future__ import annotations

from ..._hints import count
from ...analysis._options import (
    CHOICES,
    first_step_problem,
    step_count,
    step_floor,
    suggestions,
    value_problem,
)
from ...analysis._simulate import ENERGY_TOL
from ...analysis.methods import FIXED_STEP, OPTIONS
from ...io import schema as s
from ...model._compliant import rigid_contacts
from ..plan import Plan
from .laws import check_laws
from .outputs import check_outputs

#: Options of an inverse run (passed to :func:`mixdyn.kinematic`) and their defaults.
INVERSE_OPTIONS = {"tol": None, "max_iter": 25, "singular_tol": 1e-7, "assemble_first": True}


#: Options of a dynamic run that are the analysis' own, not the integrator's.
DYNAMIC_OPTIONS = {"energy_tol": ENERGY_TOL}


#: Names an option may not take: they are settings of the run itself.
RUN_SETTINGS = ("rtol", "atol", "dt", "method", "linear_solver", "hold", "q0", "qd0", "drivers")


def known_options(run) -> dict[str, object]:
    """The options a run may give, with their defaults (None: none, or required): an
    inverse run's, else the fields of its method's options class
    (:mod:`mixdyn.analysis.methods`) but the run's own settings, and the analysis' own
    (``energy_tol``).

    Args:
        run: the run's description.
    """
    if isinstance(run, s.InverseRunSpec):
        return dict(INVERSE_OPTIONS)
    known = {
        n: d
        for n, d in OPTIONS[run.method].defaults().items()
        if n not in RUN_SETTINGS and not (n == "solver" and isinstance(run, s.MixedRunSpec))
    }
    return {**known, **DYNAMIC_OPTIONS}


def check_options(runner, run, path) -> dict:
    """A run's ``options``, checked: names, types, ranges.

    Args:
        runner: reports the faults (``runner.fail``).
        run: the run's description.
        path: the run's path in the file.

    Returns:
        The options to pass to the analysis.
    """
    opts = dict(getattr(run, "options", {}) or {})
    if not opts:
        return opts
    known = known_options(run)
    for name, value in opts.items():
        p = (*path, "options", name)
        if name not in known:
            runner.fail(p, *_unknown(run, name, known))
        _check_value(runner, name, value, p)
    return opts


def _unknown(run, name: str, known) -> tuple[str, str]:
    """The problem and hint for an option ``name`` that the run does not take."""
    what = "an inverse run" if isinstance(run, s.InverseRunSpec) else f"the {run.method} method"
    if name in RUN_SETTINGS:
        return (
            f"{name!r} is a setting of the run, not an option of {what}",
            f"write '{name}:' in the run itself and remove it from options",
        )
    if name == "solver" and isinstance(run, s.MixedRunSpec):
        return (
            "a mixed run's integrator keeps its default Runge-Kutta solver ('solver:' of the "
            "run names the mixed solver, augmented or partition)",
            "remove it from options",
        )
    close = suggestions(name, known)
    allowed = ", ".join(known) or "(none)"
    hint = (f"did you mean {' or '.join(map(repr, close))}? " if close else "") + (
        f"the options of {what} are: {allowed}"
    )
    return f"unknown option {name!r} of {what}", hint


def _check_value(runner, name: str, value, path) -> None:
    """Refuse an option value of the wrong type or out of range."""
    problem = value_problem(name, value)
    if problem:
        hint = (
            f"use one of: {', '.join(CHOICES[name])}"
            if name in CHOICES
            else problem.replace("must be", "give", 1)
        )
        runner.fail(path, f"{name} is {value!r}", hint)


def check_step(runner, plan: Plan) -> None:
    """A first step that advances time and fits the span, a fixed step where needed, and no
    more steps than ``max_steps``."""
    r = plan.spec
    if isinstance(r, s.KinematicRunSpec | s.InverseRunSpec | s.StaticsRunSpec):
        return
    path = plan.path
    check_first_step(runner, plan)
    check_rigid_method(runner, plan)
    if r.dt is None:
        if r.method in FIXED_STEP:
            span = float(plan.times[-1] - plan.times[0])
            runner.fail(
                (*path, "method"),
                f"the {r.method} method has a fixed step but the run gives no dt",
                f"add 'dt:' to the run, e.g. dt: {span / 2000:.3g}",
            )
        return
    dt = runner.b.scalar(r.dt, "time", (*path, "dt"))
    limit = r.options.get("max_steps", known_options(r).get("max_steps"))
    if not isinstance(limit, int | float) or isinstance(limit, bool):
        return
    steps = step_count(plan.times, dt)
    if steps > limit:
        span = float(plan.times[-1] - plan.times[0])
        fair = min(int(limit), 20_000)
        runner.fail(
            (*path, "dt"),
            f"dt = {dt:g} needs {steps:.3g} steps over the span {span:g}, more than "
            f"max_steps = {int(limit):,}",
            f"use a larger step (dt: {span / fair:.3g} gives {fair:,} steps) or raise "
            "options.max_steps",
        )


def check_rigid_method(runner, plan: Plan) -> None:
    """A forward or mixed run of a model with rigid contacts: the projection method with its
    adaptive steps (impacts are found by events), as the run itself refuses otherwise."""
    r = plan.spec
    rigid = rigid_contacts(runner.model) if runner.model is not None else ()
    if not rigid:
        return
    if r.method != "projection":
        runner.fail(
            (*plan.path, "method"),
            f"{rigid[0].name}: rigid contacts are integrated with the projection method, not "
            f"{r.method}",
            "use method: projection (the default), or give the contacts a compliant contact_model",
        )
    if r.dt is not None:
        runner.fail(
            (*plan.path, "dt"),
            f"{rigid[0].name}: rigid contacts need the adaptive steps (their impacts are found "
            "by events)",
            "remove dt",
        )


def check_first_step(runner, plan: Plan) -> None:
    """A run's ``options.first_step`` [time] between the shortest step that advances its
    times in float64 and its span (:func:`~mixdyn.analysis._options.first_step_problem`);
    a value of the wrong type or not > 0 is refused with the other options."""
    value = (getattr(plan.spec, "options", None) or {}).get("first_step")
    if value is None or value_problem("first_step", value) or len(plan.times) < 2:
        return
    problem = first_step_problem(float(value), plan.times)
    if problem:
        span = float(plan.times[-1] - plan.times[0])
        runner.fail(
            (*plan.path, "options", "first_step"),
            f"first_step is {value!r}: it {problem}",
            f"give a first step from {step_floor(plan.times):.3g} to {span:g} (e.g. "
            f"{span * 1e-4:.3g}), or leave it out (the default: 1e-4 of the span or the first "
            "output interval)",
        )


def check_settings(runner, plan: Plan) -> None:
    """The run's options, step, outputs and laws."""
    check_options(runner, plan.spec, plan.path)
    check_step(runner, plan)
    check_outputs(runner, plan)
    check_laws(runner, plan)


def check_mixed(runner, r: s.MixedRunSpec, path) -> None:
    """A mixed run's unknown forces (each a force of the model with a magnitude, listed once,
    one per prescribed motion), its independent coordinates and its hold."""
    forces = {f.name: f for f in runner.model.forces}
    seen = set()
    for k, name in enumerate(r.unknown):
        pp = (*path, "unknown", k)
        if name not in forces:
            runner.fail(
                pp,
                f"unknown force {name!r}",
                f"the model's forces: {', '.join(forces) or '(none)'}",
            )
        if not forces[name].has_magnitude:
            runner.fail(pp, f"force {name!r} has no magnitude that could be unknown", "")
        if name in seen:
            runner.fail(pp, f"force {name!r} is listed twice", "list it once")
        seen.add(name)
    if len(r.unknown) != len(r.prescribed):
        runner.fail(
            path,
            f"{count(len(r.unknown), 'unknown force')} but "
            f"{count(len(r.prescribed), 'prescribed motion')}",
            "a mixed run needs one prescribed motion per unknown force",
        )
    for k, ref in enumerate(r.independent or ()):
        runner.b.coordinate(ref, (*path, "independent", k))
    prescribed = {p.coordinate: k for k, p in enumerate(r.prescribed)}
    for k, ref in enumerate(r.hold or ()):
        if ref in prescribed:
            runner.fail(
                (*path, "hold", k),
                f"{ref} is held, but the run prescribes it (prescribed[{prescribed[ref]}]): "
                "a held coordinate cannot follow a prescribed motion",
                "remove it from the run's hold",
            )


__all__ = [
    "DYNAMIC_OPTIONS",
    "INVERSE_OPTIONS",
    "RUN_SETTINGS",
    "check_first_step",
    "check_mixed",
    "check_options",
    "check_settings",
    "check_step",
    "known_options",
]
