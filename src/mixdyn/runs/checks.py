"""Checks of a run's settings made when the run is planned, before anything is computed.

``mixdyn check`` and ``mixdyn run`` plan every run first, so each fault below is an input
error (exit 2) naming the file, line and setting, never a failure after minutes of computing:

* ``options``: only the names the run's analysis takes (close matches suggested), none that
  repeats a setting of the run itself (``rtol``, ``dt``, ``linear_solver``...), every value of
  the right type, finite and in range (``rho_inf`` in [0, 1], ``max_steps`` >= 1...);
* the step: a fixed-step method needs ``dt``, and ``span / dt`` may not exceed ``max_steps``;
* the outputs: figure and animation files of a known type, each written once;
* the laws: every expression law finite at the run's output times.
"""

from __future__ import annotations

import shutil

import numpy as np

from ..analysis._options import CHOICES, step_count, suggestions, value_problem
from ..analysis._simulate import ENERGY_TOL
from ..analysis.methods import FIXED_STEP, OPTIONS
from ..io import schema as s
from ..io.expressions import ExpressionLaw, evaluate
from .plan import Checker, Plan

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


def check_options(runner: Checker, run, path) -> dict:
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


def _check_value(runner: Checker, name: str, value, path) -> None:
    """Refuse an option value of the wrong type or out of range."""
    problem = value_problem(name, value)
    if problem:
        hint = (
            f"use one of: {', '.join(CHOICES[name])}"
            if name in CHOICES
            else problem.replace("must be", "give", 1)
        )
        runner.fail(path, f"{name} is {value!r}", hint)


def check_step(runner: Checker, plan: Plan) -> None:
    """A fixed step where needed, and no more steps than ``max_steps``."""
    r = plan.spec
    if isinstance(r, s.KinematicRunSpec | s.InverseRunSpec | s.StaticsRunSpec):
        return
    path = plan.path
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


def check_outputs(runner: Checker, plan: Plan) -> None:
    """Figure and animation files: a writable type each, no file written twice."""
    r = plan.spec
    seen: dict[str, tuple] = {}

    def claim(name: str, path) -> None:
        key = name.lower()
        if key in seen or key in ("results.csv", "results.parquet", "meta.json"):
            runner.fail(path, f"the run writes {name!r} twice", "give each output its own file")
        seen[key] = path

    for k, plot in enumerate(r.plots):
        claim(plot.file, (*plan.path, "plots", k, "file"))
    for k, ref in enumerate(getattr(r, "outputs", None) or ()):
        runner.b.point(ref, (*plan.path, "outputs", k))
    a = r.animation
    if a is None:
        return
    p = (*plan.path, "animation", "file")
    claim(a.file, p)
    if a.file.lower().endswith(".mp4") and shutil.which("ffmpeg") is None:
        runner.fail(p, "writing MP4 needs ffmpeg, which is not installed", "write a .gif")
    if a.html and not a.file.lower().endswith(".html"):
        stem = a.file.rsplit(".", 1)[0]
        claim(f"{stem}.html", (*plan.path, "animation", "html"))
    _check_arrows(runner, plan, a.forces, (*plan.path, "animation", "forces"))


def _check_arrows(runner: Checker, plan: Plan, forces, path) -> None:
    """Force arrows: not in a kinematic run; each name a joint or a point force."""
    if not forces:
        return
    if plan.spec.kind == "kinematic":
        runner.fail(
            path,
            "a kinematic run has no forces to draw",
            "drop 'forces', or animate an inverse, forward or mixed run",
        )
    if forces is True:
        return
    from .._hints import did_you_mean
    from ..model import PointForce

    known = [j.name for j in runner.model.joints]
    known += [f.name for f in runner.model.forces if isinstance(f, PointForce)]
    friction = {f.name: f for f in runner.model.forces if f.needs_reactions}
    known += [name for name, f in friction.items() if not f.rotary]
    contacts = {
        j.name: j
        for j in runner.model.joints
        if not j.generic_reaction and getattr(j, "motion", "") == "oscillating"
    }
    for k, name in enumerate(forces):
        if name in contacts:
            cols = ", ".join(f"{name}.{c}" for c in contacts[name].contact_kinds)
            runner.fail(
                (*path, k),
                f"{name!r} acts by a moment: it has no arrow",
                f"plot its contact forces instead ({cols})",
            )
        if name in friction and friction[name].rotary:
            runner.fail(
                (*path, k),
                f"{name!r} is a pin's friction torque: it has no arrow",
                f"plot its column instead ({name})",
            )
        if name not in known:
            runner.fail(
                (*path, k),
                f"{name!r} is neither a joint nor a point force",
                did_you_mean(name, known),
            )


def check_laws(runner: Checker, plan: Plan) -> None:
    """Every expression law of the run's drivers, prescribed motions and known forces finite
    at its output times."""
    r = plan.spec
    used = None if r.drivers is None else set(r.drivers)
    unknown = set(getattr(r, "unknown", ()))
    laws = [
        (("drivers", i, "law"), d.law)
        for i, d in enumerate(runner.model.drivers)
        if used is None or d.name in used
    ]
    for i, f in enumerate(runner.model.forces):
        key = "actuator" if hasattr(f, "actuator") else "law"
        if f.name not in unknown:
            laws.append((("forces", i, key), getattr(f, key, None)))
    for k, p in enumerate(r.prescribed):
        if p.law is not None:
            path = (*plan.path, "prescribed", k)
            laws.append(((*path, "law"), runner._prescribed_driver(p, path).law))
    for path, law in laws:
        if isinstance(law, ExpressionLaw):
            _finite_law(runner, law, plan.times, path)


def check_replays(runner: Checker) -> None:
    """A motion replayed ``from_run`` covers the replaying run's time span."""
    for plan in runner.plans.values():
        for k, p in enumerate(getattr(plan.spec, "prescribed", ())):
            if p.from_run is None or p.from_run not in runner.plans:
                continue
            src = runner.plans[p.from_run].times
            t0, t1 = float(src[0]), float(src[-1])
            tol = 1e-12 * max(abs(t0), abs(t1), 1.0)
            if plan.times[0] < t0 - tol or plan.times[-1] > t1 + tol:
                runner.fail(
                    (*plan.path, "prescribed", k, "from_run"),
                    f"run {p.from_run!r} covers t = {t0:g}..{t1:g}, but run {plan.name!r} "
                    f"needs its motion over {plan.times[0]:g}..{plan.times[-1]:g}",
                    f"run {p.from_run!r} over at least this run's time span, or shorten it",
                )


def _finite_law(runner: Checker, law: ExpressionLaw, times, path) -> None:
    values = [float(v) for v in np.asarray(law.values)]
    try:
        with np.errstate(all="ignore"):
            y = np.asarray(evaluate(law.tree, times, values, xp=np), dtype=float)
    except (ArithmeticError, ValueError, TypeError):
        return
    y = np.broadcast_to(y, np.shape(times))
    bad = ~np.isfinite(y)
    if bad.any():
        k = int(np.argmax(bad))
        runner.fail(
            path,
            f"the law {law.source!r} is not finite at t = {float(times[k]):g} ({y[k]!r})",
            "change the law or the run's time span",
        )


__all__ = [
    "DYNAMIC_OPTIONS",
    "INVERSE_OPTIONS",
    "RUN_SETTINGS",
    "check_laws",
    "check_options",
    "check_outputs",
    "check_replays",
    "check_step",
    "known_options",
]
