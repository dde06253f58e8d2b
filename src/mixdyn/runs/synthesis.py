"""Synthesis runs of a model file: a four-bar, a slider-crank or a six-bar made to draw a path,
carry its coupler through poses or generate a function (:func:`mixdyn.synthesize`).

A ``synthesis`` run describes the task (the linkage, ``four_bar``, ``slider_crank`` or a
six-bar of :data:`mixdyn.synthesis.LINKAGES`, the target points, the timing, bounds of the
linkage's numbers, the least transmission angle), how the links weigh and how the motor
torque counts, and the search (starts, seed); or, with ``motion:``, the coupler's poses
instead of points (:mod:`.synthesis_motion`); or, with ``function:``, a function task
(:mod:`.synthesis_function`). It needs no mechanism in the file: a file whose runs are all
synthesis runs may have no bodies (``mixdyn check`` then reports no mechanism).
Its numbers are read with their units and handed to the search in SI (m, kg, s), the unit
system of the model file it writes.

Example (``examples/synthesis_path.yaml``)::

    - name: path
      kind: synthesis
      points: [[500 mm, 300 mm], [580 mm, 420 mm], [480 mm, 550 mm], [320 mm, 500 mm]]
      masses: {density: 2 kg/m, payload: 0.5 kg}
      speed: 2*pi rad/s
      torque_weight: 1e-4 m^2/(N*m)^2
      starts: 64

``mixdyn run`` writes ``candidates.csv`` (a row per distinct linkage, best first, headers
``name [unit]``), ``best.yaml`` (the best linkage as a model file that ``mixdyn run`` runs:
the coupler point's path and, with masses, the motor torque), ``meta.json`` (the search's
figures and the best candidate), ``synthesis.png`` (the targets and the candidates'
coupler curves) and ``report.html`` (the counts, the candidates, the figure).
"""

from __future__ import annotations

import dataclasses
import datetime
import functools
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError, NumericalError
from ..io import schema as s
from ..synthesis import (
    NAMES,
    SLIDER_NAMES,
    STEPHENSON_NAMES,
    WATT_NAMES,
    FourBar,
    FunctionSynthesis,
    FunctionTask,
    Masses,
    MotionTask,
    Objective,
    PathTask,
    SixBar,
    SliderCrank,
    Synthesis,
    coupler_curve,
)
from ..synthesis._limits import pivot_names
from ..synthesis._task import LINKAGES
from ..units import SI, dimension, factor
from .console import PROGRESS_LOG_EVERY, clean, esc
from .kinds import RunKind, register
from .plan import Plan

#: Candidates whose curves the figure draws at most (the best first).
DRAWN = 5

#: The shaking force's and moment's and the joint reactions' columns of ``candidates.csv``
#: (where the links weigh).
DYNAMIC_COLUMNS = (
    "shaking_force_rms",
    "shaking_force_peak",
    "shaking_moment_rms",
    "shaking_moment_peak",
    "reaction_rms",
    "reaction_peak",
)

#: The kind of quantity of each column of ``candidates.csv`` (SI units written beside).
_COLUMN_KINDS = {
    **{
        n: "length"
        for n in (*NAMES, *SLIDER_NAMES, *STEPHENSON_NAMES, *WATT_NAMES)
        if n != "theta0"
    },
    "theta0": "angle",
    "theta_first": "angle",
    "theta_last": "angle",
    "error": (2, 0, 0),
    "score": (2, 0, 0),
    "torque_rms": "torque",
    "torque_peak": "torque",
    "shaking_force_rms": "force",
    "shaking_force_peak": "force",
    "shaking_moment_rms": "torque",
    "shaking_moment_peak": "torque",
    "reaction_rms": "force",
    "reaction_peak": "force",
    "min_transmission": "angle",
    "coupler_angle": "angle",
}
_SI_LABELS = {"length": "m", "angle": "rad", (2, 0, 0): "m²", "torque": "N·m", "force": "N"}


@dataclasses.dataclass(frozen=True)
class SynthesisPlan(Plan):
    """A checked synthesis run: the task and objective built (SI) and the search's settings.

    Attributes:
        task: the path task, the motion task or the function task.
        objective: the path's objective (None for a function).
    """

    task: PathTask | MotionTask | FunctionTask | None = None
    objective: Objective | None = None

    @property
    def polished(self) -> bool:
        """Whether the search polishes its outcomes for the path (with a dynamic weight)."""
        return self.objective is not None and self.objective.dynamic


@dataclasses.dataclass
class FileSynthesis:
    """The result of a synthesis run."""

    plan: SynthesisPlan
    synthesis: Synthesis

    @property
    def kind(self) -> str:
        return "synthesis"


def _si(runner, value, kind, path) -> float:
    """A number of the file in SI: read in the model's units, then converted."""
    x = runner.b.scalar(value, kind, path)
    units = runner.b.units
    exps = dimension(kind)
    base = (units.length, units.mass, units.time)
    for k, (unit, e) in enumerate(zip(base, exps, strict=True)):
        if e:
            x *= factor(unit, ("length", "mass", "time")[k], SI) ** e
    return x


def plan(runner, index: int, r: s.SynthesisRunSpec) -> SynthesisPlan:
    """Check a synthesis run: its numbers read with their units, the task and objective built
    (every fault an input error at its line)."""
    path = ("runs", index)
    if r.function is not None:
        from .synthesis_function import function_task

        si = functools.partial(_si, runner)
        task = function_task(runner, path, r, si)
        return SynthesisPlan(r, index, np.zeros(1), (), task=task, objective=None)
    points = None if r.points is None else np.array(
        [[_si(runner, v, "length", (*path, "points", i, k)) for k, v in enumerate(p)]
         for i, p in enumerate(r.points)]
    )  # fmt: skip
    linkage = LINKAGES[r.linkage]
    timing = None
    if r.timing != "free":
        timing = np.array(
            [_si(runner, v, "angle", (*path, "timing", i)) for i, v in enumerate(r.timing)]
        )
    bounds = {}
    for name, ends in r.bounds.items():
        if name not in linkage.NAMES:
            runner.fail(
                (*path, "bounds", name),
                f"no number {name!r} of a {linkage.TITLE}",
                f"bound one of {', '.join(linkage.NAMES)}",
            )
        kind = "angle" if name == "theta0" else "length"
        bounds[name] = tuple(
            _si(runner, v, kind, (*path, "bounds", name, k)) for k, v in enumerate(ends)
        )
    min_mu = _si(runner, r.min_transmission, "angle", (*path, "min_transmission"))
    options = {
        "bounds": bounds,
        "min_transmission": min_mu,
        "linkage": linkage,
        "grashof": r.grashof,
        "pivots": _pivots(runner, path, r, linkage),
    }
    if r.shape == "fourier":
        from .synthesis_shape import shape_task

        task = shape_task(runner, path, r, points, min_mu, linkage)
    elif r.motion is not None:
        from .synthesis_motion import motion_task

        task = motion_task(runner, path, r, functools.partial(_si, runner), options, task_element)
    else:
        try:
            task = PathTask(points, timing=timing, timing_from=r.timing_from, **options)
        except ModelError as e:
            runner.fail(task_element(path, e.element, options), e.message, "")
    masses = None
    if r.masses is not None:
        mp = (*path, "masses")
        density = _si(runner, r.masses.density, (-1, 1, 0), (*mp, "density"))
        payload = _si(runner, r.masses.payload, "mass", (*mp, "payload"))
        if not density > 0:
            runner.fail((*mp, "density"), f"the density must be > 0, got {density:g}", "")
        if not payload >= 0:
            runner.fail((*mp, "payload"), f"the payload must be >= 0, got {payload:g}", "")
        slider = _si(runner, r.masses.slider, "mass", (*mp, "slider"))
        if linkage is SliderCrank and not slider > 0:
            runner.fail(
                mp,
                f"a slider-crank's slider needs a mass > 0, got {slider:g}",
                "give masses: {density: 2 kg/m, slider: 0.5 kg}",
            )
        gravity = tuple(_si(runner, g, "acceleration", ("gravity", k)) for k, g in
                        enumerate(runner.spec.gravity))  # fmt: skip
        masses = Masses(density=density, payload=payload, gravity=gravity, slider=slider)
    speed = _si(runner, r.speed, "angular_velocity", (*path, "speed"))
    weights = {
        key: _si(runner, getattr(r, key), dims, (*path, key))
        for key, dims in (
            ("torque_weight", (-2, -2, 4)),  # length**2 / torque**2
            ("shaking_force_weight", (0, -2, 4)),  # length**2 / force**2
            ("shaking_moment_weight", (-2, -2, 4)),
            ("reaction_weight", (0, -2, 4)),
        )
    }
    for key, weight in weights.items():
        if weight > 0 and masses is None:
            runner.fail(
                (*path, key),
                f"a {key.removesuffix('_weight').replace('_', ' ')} objective needs the links' "
                "masses",
                f"give masses: {{density: 2 kg/m}}, or leave {key} out",
            )
    try:
        objective = Objective(
            masses=masses,
            speed=speed,
            torque=r.torque,
            shaking=r.shaking,
            reaction=r.reaction,
            **weights,
        )
    except ModelError as e:
        runner.fail((*path, e.element) if e.element else path, e.message, "")
    return SynthesisPlan(r, index, np.zeros(1), (), task=task, objective=objective)


def _pivots(runner, path, r: s.SynthesisRunSpec, linkage) -> dict:
    """The run's ground-pivot regions in SI: ``name -> ((x_lo, x_hi), (y_lo, y_hi))``; a
    pivot the linkage lacks an input error at its line."""
    out = {}
    for name, region in r.pivots.items():
        where = (*path, "pivots", name)
        if name not in pivot_names(linkage):
            runner.fail(
                where,
                f"no ground pivot {name!r} of a {linkage.TITLE}",
                f"give a region for one of {', '.join(pivot_names(linkage))}",
            )
        out[name] = tuple(
            tuple(_si(runner, v, "length", (*where, axis, k)) for k, v in enumerate(ends))
            for axis, ends in (("x", region.x), ("y", region.y))
        )
    return out


def task_element(path, element: str | None, options: dict) -> tuple:
    """Where in run ``path`` the task's fault at ``element`` lies: a bound's or a pivot's line
    (of ``options``' ``bounds``, ``pivots``), else the key's."""
    if not element:
        return path
    for key in ("bounds", "pivots"):
        if element in options.get(key, {}):
            return (*path, key, element)
    return (*path, element)


def execute(runner, plan: SynthesisPlan, progress) -> FileSynthesis:
    """Search (:func:`mixdyn.synthesize`); no feasible linkage is a numerical failure."""
    from ..synthesis import SearchSettings, synthesize

    r: s.SynthesisRunSpec = plan.spec
    search = SearchSettings(starts=r.starts, seed=r.seed, max_steps=r.max_steps, keep=r.keep)
    out = synthesize(plan.task, plan.objective, search, progress=progress)
    if not out.candidates:
        raise NumericalError(
            f"no feasible {_title(plan.task)} among {r.starts} starts (none closes its loop "
            "along the motion, in order, within the bounds and the transmission angle): give more "
            "starts, wider bounds or a smaller min_transmission"
        )
    return FileSynthesis(plan, out)


def _title(task) -> str:
    """The task's linkage in words."""
    return getattr(task, "linkage", FourBar).TITLE


def _form(task) -> str:
    """What a path's or a motion's task asks of the linkage's form, in words: its Grashof type
    and its ground pivots' regions [m] ("" where nothing)."""
    words = []
    if task.grashof != "any":
        words.append(task.grashof.replace("_", "-"))
    for name, ((x0, x1), (y0, y1)) in task.pivots.items():
        words.append(f"{name} in x [{x0:.4g}, {x1:.4g}] m, y [{y0:.4g}, {y1:.4g}] m")
    return f" ({'; '.join(words)})" if words else ""


def _task_name(task) -> str:
    """``"path"``, ``"motion"`` or ``"function"``: what the task generates."""
    if isinstance(task, FunctionTask):
        return "function"
    return "motion" if isinstance(task, MotionTask) else "path"


def candidates_table(out: Synthesis):
    """``(names, units, rows)``: a row per candidate, best first (SI); the motor torque's
    columns where the links weigh, a motion's carried body's angle in the coupler."""
    names = [*out.task.linkage.NAMES, "branch", "theta_first", "theta_last", "error", "score"]
    if out.objective.masses is not None:
        names += ["torque_rms", "torque_peak", *DYNAMIC_COLUMNS]
    names.append("min_transmission")
    if isinstance(out.task, MotionTask):
        names.append("coupler_angle")
    rows = []
    for c in out.candidates:
        row = c.numbers()
        row.update(
            theta_first=float(c.angles[0]),
            theta_last=float(c.angles[-1]),
            error=c.error,
            score=c.score,
            torque_rms=c.torque_rms,
            torque_peak=c.torque_peak,
            **{k: getattr(c, k) for k in DYNAMIC_COLUMNS},
            min_transmission=c.min_transmission,
            coupler_angle=c.coupler_angle,
        )
        rows.append([row[n] for n in names])
    units = {n: _SI_LABELS[k] for n, k in _COLUMN_KINDS.items() if n in names}
    from .synthesis_shape import shape_columns

    shape_columns(out, names, units, rows)
    return names, units, np.array(rows, dtype=float)


@jax.jit
def _transmission_cosines(lk, theta):
    """(K,) ``lk``'s transmission cosine at the input angles ``theta`` (K,) [rad]."""
    return jax.vmap(lk.transmission_cosine)(theta)


def _curves(c, samples: int = 241) -> tuple[np.ndarray, np.ndarray]:
    """A candidate's coupler curve (K, 2) [m] over its traversed motion (first target to
    last), and over the rest of the turn (NaN where the loop does not close there: a
    four-bar's triangle ``A B O4`` impossible, a slider-crank's rod too short to reach the
    slide; ``|cos mu| > 1``, as :func:`transmission_cosine`)."""
    fb = c.fourbar
    a0, a1 = float(c.angles[0]), float(c.angles[-1])
    run = np.asarray(coupler_curve(fb, np.linspace(a0, a1, samples)))
    rest_angles = np.linspace(a1, a0 + 2 * np.pi, samples)
    rest = np.array(coupler_curve(fb, rest_angles))
    if isinstance(fb, SixBar):  # either loop open: its transmission cosine beyond 1
        cos = np.asarray(_transmission_cosines(fb, jnp.asarray(rest_angles)))
        rest[np.abs(cos) > 1.0] = np.nan
        return run, rest
    if isinstance(fb, SliderCrank):  # the crank pin's height above the slide against r3
        r2, r3, e = (float(getattr(fb, n)) for n in ("r2", "r3", "e"))
        rest[np.abs(r2 * np.sin(rest_angles) - e) > r3] = np.nan
        return run, rest
    r1, r2, r3, r4, t0 = (float(getattr(fb, n)) for n in ("r1", "r2", "r3", "r4", "theta0"))
    crank = t0 + rest_angles  # |A O4|^2 in the ground link's frame, O2 at the origin
    gap = (r1 - r2 * np.cos(crank - t0)) ** 2 + (r2 * np.sin(crank - t0)) ** 2
    rest[np.abs((r3**2 + r4**2 - gap) / (2 * r3 * r4)) > 1.0] = np.nan
    return run, rest


def _report(runner, plan, out, names, units, table, seconds, outputs):
    """The run's page (``report.html``): the search's counts, the candidates with their
    units (best first), the figure and the settings."""
    from ..io.results import run_settings
    from ..viz.report import Report, Table, number

    task = _task_name(out.task)
    facts = [
        ("file", str(outputs.file)),
        ("run", f"{plan.name} (synthesis, {task} generation)"),
        ("status", "ok"),
        ("starts", f"{out.starts} (seed {out.seed})"),
        ("feasible", f"{out.feasible} ({len(out.candidates)} distinct kept)"),
        ("wall time", f"{seconds:.3f} s"),
        (f"best {_title(out.task)}", "best.yaml (mixdyn run best.yaml)"),
    ]
    rows = [[str(k + 1), *(number(v) for v in row)] for k, row in enumerate(table)]
    head = ["#", *(f"{n} [{units[n]}]" if units.get(n) else n for n in names)]
    candidates = Table(
        "Candidates, best first (candidates.csv)",
        head,
        rows,
        numeric=tuple(range(len(head))),
        cls="candidates",
    )
    folder = outputs.folder(plan)
    return Report(
        path=folder / "report.html",
        title=f"{runner.spec.name}: synthesis {plan.name}",
        facts=facts,
        drawing="",
        figures=[folder / "synthesis.png"] if outputs.painter is not None else [],
        columns={},
        units={},
        settings=run_settings(plan.spec),
        tables=[candidates],
    )


def _log(plan: SynthesisPlan, every: float = PROGRESS_LOG_EVERY):
    """A progress callback writing a plain line on stderr at most every ``every`` seconds."""
    start = time.monotonic()
    last = [start]

    def at(stage, done, total, best):
        now = time.monotonic()
        if now - last[0] < every and done < total:
            return
        last[0] = now
        sys.stderr.write(
            clean(f"{plan.name}: {stage} {done} of {total} starts, best score {best:.3g}, ")
            + f"{now - start:.0f} s\n"
        )
        sys.stderr.flush()

    return at


@register
class SynthesisKind(RunKind):
    """A synthesis: a four-bar, a slider-crank or a six-bar searched to draw a path, with the
    motor torque by weight, or to generate a function."""

    name = "synthesis"
    needs_mechanism = False
    not_replayable = "a synthesis run"

    def plan(self, runner, index: int, spec) -> SynthesisPlan:
        return plan(runner, index, spec)

    def execute(self, runner, plan: SynthesisPlan, results: dict, progress) -> FileSynthesis:
        return execute(runner, plan, progress)

    def output_files(self, runner, plan: SynthesisPlan, figures: bool) -> list[str]:
        names = ["candidates.csv", "best.yaml", "meta.json", "report.html"]
        return names + (["synthesis.png"] if figures else [])

    def draws(self, runner, plan: SynthesisPlan) -> bool:
        return True

    def write(self, runner, plan: SynthesisPlan, result: FileSynthesis, seconds: float, outputs):
        from .._version import __version__
        from ..io.results import _write_csv, headers, jsonable, write_meta
        from . import synthesis_function as fn

        out, r = result.synthesis, plan.spec
        function = isinstance(out, FunctionSynthesis)
        folder = outputs.folder(plan)
        folder.mkdir(parents=True, exist_ok=True)
        names, units, table = (fn.function_table if function else candidates_table)(out)
        csv = folder / "candidates.csv"
        _write_csv(csv, headers(names, units), table)
        best = folder / "best.yaml"
        if function:
            best.write_text(out.model_file(name=f"run {plan.name}"), encoding="utf-8")
        else:
            out.write(best)
        figures = ["synthesis.png"] if outputs.painter is not None else []
        meta = {
            "mixdyn_version": __version__,
            "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "file": str(outputs.file),
            "run": plan.name,
            "kind": "synthesis",
            "status": "ok",
            "wall_time_s": round(seconds, 3),
            "unit_system": {"length": "m", "mass": "kg", "time": "s", "angle": "rad"},
            "settings": r.model_dump(mode="json"),
            "synthesis": {
                "task": _task_name(out.task),
                "starts": out.starts,
                "feasible": out.feasible,
                "candidates": len(out.candidates),
                "seed": out.seed,
                "seconds": out.seconds,
                "best": dict(zip(names, table[0], strict=True)),
                **({} if function else {"angles": np.asarray(out.best.angles)}),
                "units": units,
            },
            "figures": figures,
        }
        files = [csv, best, write_meta(folder, jsonable(meta))]
        if outputs.painter is not None:
            drawn = out.candidates[:DRAWN]
            title = f"{plan.name}: {len(out.candidates)} {_title(out.task)}s, best first"
            errors = [cand.error for cand in drawn]
            if function:
                asked, curves, options = fn.figure(out, DRAWN)
            else:
                asked, curves, options = out.task.points, [_curves(c) for c in drawn], {}
                from .synthesis_shape import figure_options

                options.update(figure_options(out.task))
                if isinstance(out.task, MotionTask):
                    options["angles"] = out.task.angles
            outputs.painter.draw(
                "synthesis", asked, curves, errors, folder / "synthesis.png", title=title, **options
            )
        page = _report(runner, plan, out, names, units, table, seconds, outputs)
        return files + outputs.add_report(page)

    def describe(self, plan: SynthesisPlan, report, model) -> str:
        r, o = plan.spec, plan.objective
        if o is None:
            start = ", start angles free" if plan.task.free_start else ""
            if plan.task.grashof != "any":
                start += f", {plan.task.grashof.replace('_', '-')}"
            return (
                f"run [bold]{esc(r.name)}[/bold] (synthesis): a {_title(plan.task)} generating "
                f"a function at {len(plan.task.inputs)} points{start}, {r.starts} starts, seed "
                f"{r.seed}"
            )
        timing = "timing free" if plan.task.timing is None else "timing given"
        what = f", torque ({r.torque}) weight {o.torque_weight:.3g}" if o.torque_weight else ""
        for key, label in (("shaking_force_weight", "shaking force"),
                           ("shaking_moment_weight", "shaking moment"),
                           ("reaction_weight", "joint reactions")):  # fmt: skip
            if getattr(o, key):
                measure = r.reaction if key == "reaction_weight" else r.shaking
                what += f", {label} ({measure}) weight {getattr(o, key):.3g}"
        through = f"{len(plan.task.points)} points, {timing}"
        if isinstance(plan.task, MotionTask):
            through = f"{len(plan.task.poses)} poses (L = {plan.task.weight_length:.4g} m)"
        from .synthesis_shape import shape_words

        through = shape_words(plan.task) or through
        return (
            f"run [bold]{esc(r.name)}[/bold] (synthesis): a {_title(plan.task)}"
            f"{_form(plan.task)} through {through}{what}, {r.starts} starts, seed {r.seed}"
        )

    def task(self, plan: SynthesisPlan, mode: str) -> tuple[str, float | None]:
        total = plan.spec.starts * (2 if plan.polished else 1)
        return f"{plan.name} (synthesis)", total if mode == "steps" else None

    def progress(self, plan: SynthesisPlan, console):
        if console.mode == "log":
            return _log(plan)
        if console.mode != "steps":
            return None
        task, starts = console.tasks[plan.name], plan.spec.starts

        def at(stage, done, total, best):
            console.bar.update(task, completed=done + (starts if stage == "polish" else 0))

        return at

    def animation_refusal(self, plan: SynthesisPlan) -> tuple[str, str] | None:
        return (
            f"run {plan.name!r} is a synthesis run: it makes a linkage, not a motion",
            "mixdyn run it, then animate a run of the best.yaml it writes",
        )

    def done(self, plan: SynthesisPlan, result: FileSynthesis, seconds: float, folder) -> str:
        out = result.synthesis
        c = out.best
        if isinstance(out, FunctionSynthesis):
            from .synthesis_function import error_words

            best = f"best {error_words(out.task)[0]} {c.error:.3g} {error_words(out.task)[1]}"
        else:
            best = f"best {_task_name(out.task).replace('motion', 'pose')} error {c.error:.3g} m²"
            if hasattr(c, "distance"):  # a shape's (mixdyn.synthesis.ShapeCandidate)
                best = f"best shape error {c.error:.3g}, farthest point {c.distance:.3g} m off"
            if np.isfinite(c.torque_rms):
                best += f", motor torque RMS {c.torque_rms:.4g} N·m"
            if plan.objective is not None and plan.objective.shakes:
                best += f", shaking force RMS {c.shaking_force_rms:.4g} N"
        return (
            f"{plan.name}: synthesis, {len(out.candidates)} {_title(out.task)}s of {out.feasible} "
            f"feasible from {out.starts} starts, {best}, {seconds:.2f} s -> {folder}"
        )


__all__ = ["FileSynthesis", "SynthesisKind", "SynthesisPlan", "candidates_table", "execute", "plan"]
