"""Checks of a file's runs, made before anything is computed.

``mixdyn check`` and ``mixdyn run`` plan and check every run first, so each fault below is an
input error (exit 2) naming the file, line and setting, never a failure after minutes of
computing.

When a run is planned (:meth:`.kinds.RunKind.plan`):

* ``options``: only the names the run's analysis takes (close matches suggested), none that
  repeats a setting of the run itself (``rtol``, ``dt``, ``linear_solver``...), every value of
  the right type, finite and in range (``rho_inf`` in [0, 1], ``max_steps`` >= 1...);
* the step: a fixed-step method needs ``dt``, and ``span / dt`` may not exceed ``max_steps``;
* the outputs: figure and animation files of a known type, each written once; columns the
  run's result has (:func:`columns`);
* the laws: every expression law finite at the run's output times;
* a mixed run's unknown forces and prescribed motions paired one to one.

Once every run is planned: motions replayed ``from_run`` cover the replaying run's span
(:func:`check_replays`) and ``output_units`` are units of their kind (:func:`output_units`).

With numbers, on the run's own set-up (:mod:`.setup`): every body's mass and inertia for a
dynamic run (:func:`check_masses`), the drivers against the degrees of freedom
(:func:`mobility`) and a mixed run's solvability (:func:`check_solvable`).
"""

from __future__ import annotations

import dataclasses
import shutil
from collections.abc import Callable

import numpy as np

from .. import analysis as an
from .. import model as m
from .._hints import count, listed
from ..analysis._options import CHOICES, step_count, suggestions, value_problem
from ..analysis._setup import prepare
from ..analysis._simulate import ENERGY_TOL
from ..analysis.methods import FIXED_STEP, OPTIONS
from ..analysis.mixed import Mixed, bind_prescribed
from ..errors import AssemblyError, ModelError, NumericalError
from ..io import schema as s
from ..io._errors import FileError
from ..io.expressions import ExpressionLaw, evaluate
from . import setup
from .kinds import kind_of
from .plan import Plan

#: Suffixes of the per-body columns of a result.
BODY_COLUMNS = ("x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha")

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


def check_outputs(runner, plan: Plan) -> None:
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


def _check_arrows(runner, plan: Plan, forces, path) -> None:
    """Force arrows: not in a kinematic run; each name a joint or a point force."""
    if not forces:
        return
    if kind_of(plan).motion_only:
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
    dependent = {f.name: f for f in runner.model.forces if f.needs_reactions}
    known += [name for name, f in dependent.items() if f.no_arrow is None]
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
        if name in dependent and dependent[name].no_arrow is not None:
            runner.fail(
                (*path, k),
                f"{name!r} {dependent[name].no_arrow}: it has no arrow",
                f"plot its column instead ({name})",
            )
        if name not in known:
            runner.fail(
                (*path, k),
                f"{name!r} is neither a joint nor a point force",
                did_you_mean(name, known),
            )


def check_laws(runner, plan: Plan) -> None:
    """Every expression law of the run's drivers, prescribed motions and known forces finite
    at its output times; the drivers' and prescribed motions' laws continuous with their
    slopes over the run (:meth:`~mixdyn.model.Driver.check_law`)."""
    r = plan.spec
    used = None if r.drivers is None else set(r.drivers)
    unknown = set(getattr(r, "unknown", ()))
    drivers = [
        (("drivers", i, "law"), d)
        for i, d in enumerate(runner.model.drivers)
        if used is None or d.name in used
    ]
    laws = [(path, d.law) for path, d in drivers]
    for i, f in enumerate(runner.model.forces):
        key = "actuator" if hasattr(f, "actuator") else "law"
        if f.name not in unknown:
            laws.append((("forces", i, key), getattr(f, key, None)))
    for k, p in enumerate(r.prescribed):
        if p.law is not None:
            path = (*plan.path, "prescribed", k)
            driver = setup.prescribed_driver(runner, p, path)
            laws.append(((*path, "law"), driver.law))
            drivers.append(((*path, "law"), driver))
    for path, law in laws:
        if isinstance(law, ExpressionLaw):
            _finite_law(runner, law, plan.times, path)
    for path, driver in drivers:
        try:
            driver.check_law(plan.times[0], plan.times[-1])
        except ModelError as e:
            runner.fail(path, e.message, "")


def check_replays(runner) -> None:
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


def _finite_law(runner, law: ExpressionLaw, times, path) -> None:
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


def check_settings(runner, plan: Plan) -> None:
    """The run's options, step, outputs and laws."""
    check_options(runner, plan.spec, plan.path)
    check_step(runner, plan)
    check_outputs(runner, plan)
    check_laws(runner, plan)


#: "degree of freedom" in its two numbers, for :func:`mixdyn._hints.count`.
_DOF = ("degree of freedom", "degrees of freedom")


def output_units(runner) -> dict[str, str]:
    """The file's ``output_units`` checked: a preset's name (``SI``, ``mm-N-s``:
    :data:`mixdyn.units.OUTPUT_PRESETS`) or kinds and their units, a ``preset`` among them
    expanded first; known kinds, units of their dimension."""
    from .._hints import did_you_mean
    from ..units import DIMENSIONS, OUTPUT_PRESETS

    given = runner.spec.output_units
    if isinstance(given, str):
        given = {"preset": given}
    out = {}
    if "preset" in given:
        name = given["preset"]
        path = (
            ("output_units",)
            if isinstance(runner.spec.output_units, str)
            else ("output_units", "preset")
        )
        if name not in OUTPUT_PRESETS:
            runner.fail(
                path,
                f"no preset of output units {name!r}",
                did_you_mean(name, OUTPUT_PRESETS, "presets"),
            )
        out.update(OUTPUT_PRESETS[name])
    for kind, unit in given.items():
        if kind == "preset":
            continue
        path = ("output_units", kind)
        if kind not in DIMENSIONS:
            runner.fail(
                path, f"no kind of quantity {kind!r}", did_you_mean(kind, DIMENSIONS, "kinds")
            )
        runner.b.factor(unit, kind, path)  # the dimension checked
        out[kind] = unit
    return out


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


def columns(runner, r) -> tuple[list[str], set[str]]:
    """The columns a run's result has: ``(names, owners of lambda.* columns)`` (the
    multipliers ``lambda.{row}`` of the joints' and drivers' rows; point columns
    ``body.P.x`` are checked apart).

    Args:
        runner: the file's runner.
        r: the description of a run of one analysis.
    """
    kind = kind_of(r)
    model = runner.model
    cols = ["t"] + [f"{b}.{c}" for b in runner.b.body_names for c in BODY_COLUMNS]
    if kind.motion_only:
        return cols, set()
    for j in model.joints:
        if j.generic_reaction:
            cols += [f"{j.name}.Fx", f"{j.name}.Fy"]
            cols += [f"{j.name}.M"] if j.carries_moment else []
        cols += [f"{j.name}.{k}" for k in j.contact_kinds]
    drivers = [d.name for d in model.drivers if r.drivers is None or d.name in r.drivers]
    if not kind.unknown_forces:  # a mixed run's prescribed motions are paired with its unknowns
        drivers += [p.name or f"prescribed {p.coordinate}" for p in r.prescribed]
    unknown = tuple(getattr(r, "unknown", None) or ())
    for name in [*drivers, *unknown]:
        cols += [name, f"{name}.power"]
    if kind.element_columns:
        from ..equations import force_output_kinds

        cols += list(force_output_kinds(model, exclude=unknown))
    cols += ["energy.kinetic", "energy.potential", "energy.total", "constraint.violation"]
    if kind.integrated:
        cols += ["work.nonconservative", "work.constraints"]
    owners = {j.name for j in model.joints} | set(drivers)
    return cols, owners


def check_column(runner, col: str, r, path) -> None:
    """Refuse a column the run's result does not have (a point's ``body.P.x`` checked as a
    point of the body)."""
    parts = col.split(".")
    if len(parts) == 3 and parts[0] in runner.b.body_index and parts[1] not in BODY_COLUMNS:
        runner.b.point(f"{parts[0]}.{parts[1]}", path)
        if parts[2] in ("x", "y", "vx", "vy", "ax", "ay"):
            return
    names, owners = columns(runner, r)
    if col in names:
        return
    if col.startswith("lambda.") and any(
        col == f"lambda.{o}" or col.startswith(f"lambda.{o}.") for o in owners
    ):
        return
    from .._hints import did_you_mean

    what = "a kinematic run has the motion only" if kind_of(r).motion_only else ""
    runner.fail(
        path,
        f"no column {col!r} in run {r.name!r}" + (f" ({what})" if what else ""),
        did_you_mean(col, names) + "; points: body.P.x (.y, .vx, .vy, .ax, .ay)",
    )


# --------------------------------------------------------------------------- with numbers
def check_masses(runner, plan: Plan) -> None:
    """A dynamic run needs every body's mass and inertia > 0."""
    plan = plan.subject
    if not kind_of(plan).dynamic:
        return
    for i, body in enumerate(runner.model.bodies):
        for key in ("mass", "inertia"):
            if not float(getattr(body, key)) > 0:
                runner.fail(
                    ("bodies", i, key),
                    f"{key} is {float(getattr(body, key)):g}, but run {plan.name!r} "
                    f"({plan.spec.kind}) is dynamic",
                    f"give the body a {key} > 0, or make the run kinematic",
                )


def mobility(runner, plan: Plan):
    """Degrees of freedom of a run's model with its drivers and prescribed motions, at the
    assembled start.

    The check is made on the run's own set-up where it can be (:func:`.setup.prepare`: the
    start the run will start from and its mobility analysis), which the run then hands to its
    analysis, so that the check and the run share one assembly and one rank analysis. A run
    replaying another run's motion (``from_run``) is checked with a stand-in for that motion
    and prepares itself when it runs.

    The prescribed motions are bound to their bodies as :func:`mixdyn.mixed` binds them, so
    the check counts the coordinates the run will drive. A mixed run is then checked as
    :func:`check_solvable` does (its start with the held coordinates, the pairing of forces
    and motions), so that ``mixdyn run`` refuses it before any long computation.

    Args:
        runner: the file's runner.
        plan: the run (a sweep, fit or optimization: the run it repeats, at its nominal
            numbers).

    Returns:
        The :class:`~mixdyn.DofReport` of the run's model and drivers.

    Raises:
        FileError: a fully driven run (kinematic, inverse) does not have one driver per
            degree of freedom, another run is over-driven, or a mixed run fails a check of
            :func:`check_solvable`.
    """
    plan = plan.subject
    r = plan.spec
    kind = kind_of(plan)
    mixed = isinstance(r, s.MixedRunSpec)
    report = None
    if plan.replays:
        if mixed:
            report = _standin_report(runner, plan)
    else:
        try:
            report = setup.prepare(runner, plan).report
        except FileError:
            raise
        except (ModelError, NumericalError):
            pass  # checked as before below; the run prepares itself and says why it fails
    if report is None:
        report = _rough_report(runner, plan)
    n = report.n_drivers
    if kind.fully_driven:
        if report.redundant_drivers:
            runner.fail(
                plan.path,
                f"{listed(report.redundant_drivers, 'driver')} prescribe"
                f"{'s' if len(report.redundant_drivers) == 1 else ''} a motion the joints or "
                "other drivers already fix",
                "remove them or drive another coordinate",
            )
        if n != report.dof:
            more = "remove" if n > report.dof else "add"
            runner.fail(
                plan.path,
                f"the mechanism has {count(report.dof, *_DOF)} but the {r.kind} run "
                f"has {count(n, 'driver')}",
                f"{more} {count(abs(n - report.dof), 'driver')} (drivers: or prescribed:)",
            )
    elif n > report.dof or report.redundant_drivers:
        runner.fail(
            plan.path,
            f"the mechanism has {count(report.dof, *_DOF)} but the run prescribes "
            f"{count(n, 'motion')}"
            + (
                f" (redundant: {', '.join(report.redundant_drivers)})"
                if report.redundant_drivers
                else ""
            ),
            "prescribe fewer motions, or motions of coordinates the joints leave free",
        )
    if mixed:
        check_solvable(runner, plan)
    return report


def _mixed_setup(runner, plan: Plan):
    """What :func:`check_solvable` checks a mixed run on: ``(model, q0, qd0, prescribed
    motions, Prepared)``, the run's own set-up (:func:`.setup.prepare`) or, for a run
    replaying another run's motion, the stand-ins' (:func:`_standin_report`); None where the
    start cannot be made."""
    if plan.replays:
        if plan.name not in runner.setups.checked:
            _standin_report(runner, plan)
        return runner.setups.checked.get(plan.name)
    try:
        prep = setup.prepare(runner, plan)
    except FileError:
        raise
    except (ModelError, NumericalError):
        return None
    args, _ = runner.setups.prepared[plan.name]
    prescribed = prep.drivers[len(prep.model.drivers) :]
    return prep.model, args["q0"], args["qd0"], prescribed, prep


def _standin_report(runner, plan: Plan):
    """A mixed run replaying another run's motion, checked with stand-ins held at their value
    at the assembled start (:func:`prescribed_motions`): the start the checks of
    :func:`mixdyn.check_mixed` make, kept for :func:`check_solvable`. None where that start
    cannot be made (the checks then report as before)."""
    r = plan.spec
    model = setup.run_model(runner, plan, ())
    hold = setup.hold_of(runner, plan)
    try:
        q = _assembled(runner, plan, model, hold)
        prescribed = prescribed_motions(runner, plan, model, q)
    except ModelError as e:
        runner.model_error(plan, e)
    value = Mixed(
        prescribed=prescribed, unknown=r.unknown, q0=q, hold=hold, linear_solver=r.linear_solver
    )
    try:
        prep = value._initial(model, float(plan.times[0]))
    except FileError:
        raise
    except (ModelError, NumericalError):
        return None
    runner.setups.checked[plan.name] = (model, q, None, prescribed, prep)
    return prep.report


def _assembled(runner, plan: Plan, model: m.Model, hold) -> np.ndarray:
    """The rough start closed on the joints (the run's drivers aside) with ``hold``, made once
    for runs that share it."""
    cache = runner.setups.mobility
    q_rough = np.asarray(setup.q_start(runner, plan, model), dtype=float)
    key = ("assemble", setup.drivers_key(model.drivers), hold, q_rough.tobytes())
    if key not in cache:
        cache[key] = np.asarray(an.assemble(model, q_rough, hold=hold).q)
    return cache[key]


def _rough_report(runner, plan: Plan):
    """The mobility of a run at its rough start closed on the joints, where the run's own
    start could not be made (the run then fails there, saying why)."""
    r = plan.spec
    mixed = isinstance(r, s.MixedRunSpec)
    if mixed:
        model = setup.run_model(runner, plan, ())
    else:
        model = setup.run_model(
            runner,
            plan,
            [
                setup.dummy_driver(k, p)
                if p.from_run is not None
                else setup.prescribed_driver(runner, p, (*plan.path, "prescribed", k))
                for k, p in enumerate(r.prescribed)
            ],
        )
    # Assembly and analysis are cached by what they depend on (the drivers, the held
    # coordinates, the start, the time): runs that share them are analysed once.
    cache = runner.setups.mobility
    hold = setup.hold_of(runner, plan)
    try:
        q = _assembled(runner, plan, model, hold)
        prescribed = prescribed_motions(runner, plan, model, q) if mixed else ()
    except ModelError as e:
        runner.model_error(plan, e)
    drivers = (*model.drivers, *prescribed)
    t0 = float(plan.times[0])
    key = ("dof", setup.drivers_key(drivers), q.tobytes(), t0)
    if key not in cache:
        cache[key] = an.degrees_of_freedom(model, q, t0, drivers=drivers)
    return cache[key]


def check_solvable(runner, plan: Plan) -> None:
    """For a mixed run, every solvability check of :func:`mixdyn.check_mixed` at the assembled
    start, without integrating.

    The prescribed motions are those of the run, built and bound as the run builds them
    (:func:`prescribed_motions`); a motion taken from another run is held at its value at the
    assembled start for the check. A start the held coordinates make impossible (a hold that
    fights a prescribed motion) is reported at the hold, naming where it comes from (the
    run's ``hold`` or ``assembly.hold``). Checked once per run.

    Args:
        runner: the file's runner.
        plan: the run (other kinds pass).

    Raises:
        FileError: the run cannot be solved, with the reason.
    """
    plan = plan.subject
    r = plan.spec
    if not isinstance(r, s.MixedRunSpec):
        return
    done = runner.setups.solvable
    if plan.name in done:
        return
    hold = setup.hold_of(runner, plan)
    found = _mixed_setup(runner, plan)
    if found is not None:  # on the set-up the run starts from (no second assembly)
        model, q0, qd0, prescribed, prep = found
        try:
            _solvable_at(plan, model, prescribed, q0, qd0, hold, prep.linear_solver, prep)
        except (ModelError, NumericalError):
            runner.setups.prepared.pop(plan.name, None)  # the run prepares itself; see below
        else:
            done.add(plan.name)
            return
    model = setup.run_model(runner, plan, ())
    try:
        q = np.asarray(an.assemble(model, setup.q_start(runner, plan, model), hold=hold).q)
        prescribed = prescribed_motions(runner, plan, model, q)
    except ModelError as e:
        runner.model_error(plan, e)
    # A stand-in for another run's motion has no speed: the run's start speeds are
    # checked only where every prescribed motion is a law.
    laws_only = all(p.from_run is None for p in r.prescribed)

    def check(hold):
        qd0 = setup.qd_start(runner, plan, model) if laws_only else None
        _solvable_at(plan, model, prescribed, q, qd0, hold, r.linear_solver)

    try:
        check(hold)
    except (ModelError, AssemblyError) as e:
        if hold and _passes(check, ()):
            path, source = setup.hold_source(plan)
            cause = str(e)
            element = getattr(e, "element", None)
            if element and cause.startswith(f"{element}: "):
                cause = cause[len(element) + 2 :]
            runner.fail(
                path,
                f"run {plan.name!r}: the held {listed(hold, 'coordinate')} (from "
                f"{source}) conflict{'s' if len(hold) == 1 else ''} with its "
                f"{listed((d.name for d in prescribed), 'prescribed motion')} at "
                f"t = {plan.times[0]:g}: {cause}",
                "remove them from the run's hold"
                if r.hold is not None
                else "give the run its own hold: (hold: [] holds nothing)",
            )
        if isinstance(e, AssemblyError):
            raise
        runner.model_error(plan, e)
    done.add(plan.name)


def _solvable_at(plan: Plan, model, prescribed, q0, qd0, hold, linear_solver, start=None):
    """The checks of :func:`mixdyn.check_mixed` of a mixed run's unknown forces and solver:
    its set-up (:func:`mixdyn.prepare`), from ``start`` (a start made beforehand) where
    given."""
    r = plan.spec
    value = Mixed(
        prescribed=prescribed,
        unknown=tuple(r.unknown),
        solver=r.solver,
        independent=r.independent,
        q0=q0,
        qd0=qd0,
        hold=hold,
        linear_solver=linear_solver,
    )
    prepare(model, value, t0=float(plan.times[0]), start=start)


def _passes(check: Callable, hold) -> bool:
    """Whether ``check(hold)`` raises no :class:`ModelError` or :class:`NumericalError`."""
    try:
        check(hold)
    except (ModelError, NumericalError):
        return False
    return True


def prescribed_motions(runner, plan: Plan, model: m.Model, q) -> tuple[m.Driver, ...]:
    """A mixed run's prescribed motions as the checks see them, bound to the bodies of
    ``model`` exactly as :func:`mixdyn.mixed` binds them: a ``law`` as written, a motion
    ``from_run`` by a stand-in held at its value in ``q`` (that run has not run yet)."""
    r = plan.spec
    drivers = [
        setup.dummy_driver(k, p)
        if p.from_run is not None
        else setup.prescribed_driver(runner, p, (*plan.path, "prescribed", k))
        for k, p in enumerate(r.prescribed)
    ]
    bound = bind_prescribed(model, drivers)
    q = np.asarray(q, dtype=float)
    return tuple(
        d if p.from_run is None else dataclasses.replace(d, law=held(runner, p, d, q))
        for d, p in zip(bound, r.prescribed, strict=True)
    )


def held(runner, p: s.PrescribedSpec, d: m.Driver, q) -> m.Law:
    """The stand-in's law: held at its value in ``q``, in the form the replayed motion will
    have (:func:`mixdyn.analysis.prescribe`: a quintic Hermite interpolant on the source run's
    output times, here of constant samples, exactly constant), so that the programs the
    checks compile are the ones the run then calls."""
    value = float(d.measure(q))
    source = runner.plans.get(p.from_run)
    if source is None or len(source.times) < 2 or np.any(np.diff(source.times) <= 0):
        return m.Constant(value)
    n = len(source.times)
    return m.QuinticHermite(source.times, np.full(n, value), np.zeros(n), np.zeros(n))


# --------------------------------------------------------------------------- the command's
def require_size(spec: s.ModelFile, file) -> None:
    """Refuse, before building anything, a model too large to check in bounded time."""
    from ..analysis._structure import require_checkable

    require_checkable(len(spec.bodies), str(file))


def file_warnings(spec: s.ModelFile, model: m.Model, report) -> list[str]:
    """What ``mixdyn check`` warns of: no runs, redundant joint equations, bodies connected to
    nothing, forces that no run uses.

    Args:
        spec: the file's description.
        model: its model.
        report: the model's degrees of freedom at its assembled start.
    """
    out = []
    if not spec.runs:
        out.append("the file has no runs; `mixdyn run` has nothing to do")
    if report.redundant:
        out.append(
            f"redundant joint equations {', '.join(report.redundant)} are dropped by the solvers "
            "(their reactions are not unique)"
        )
    used = set()
    for j in (*model.joints, *model.drivers, *model.forces):
        used.update(j.body_indices())
    for i, b in enumerate(model.bodies):
        if i not in used:
            out.append(f"body {b.name!r} is not connected to anything")
    if model.forces and spec.runs and all(kind_of(r).motion_only for r in spec.runs):
        out.append("the forces have no effect: every run is kinematic")
    return out


__all__ = [
    "BODY_COLUMNS",
    "DYNAMIC_OPTIONS",
    "INVERSE_OPTIONS",
    "RUN_SETTINGS",
    "check_column",
    "check_laws",
    "check_masses",
    "check_mixed",
    "check_options",
    "check_outputs",
    "check_replays",
    "check_settings",
    "check_solvable",
    "check_step",
    "columns",
    "file_warnings",
    "known_options",
    "mobility",
    "output_units",
    "require_size",
]
