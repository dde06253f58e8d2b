"""The runs of one analysis: ``kinematic``, ``statics``, ``inverse``, ``forward`` and
``mixed``, each a registered :class:`~.kinds.RunKind`.

A run names its analysis, its output times, solver settings and, for a mixed run, the
unknown forces and the prescribed motions. A prescribed motion may replay a coordinate of
another run's result (``from_run``), so a file can hold the paper's round trip: a forward run,
then a mixed run that recovers the force from its motion. Each run writes ``results.csv``
(``results.parquet``), ``meta.json``, its plots (by default its drivers' efforts, unknown
forces and joint reactions) and its animation.
"""

from __future__ import annotations

import pathlib
import shutil
from collections.abc import Callable

import numpy as np

from .._hints import count
from ..io import schema as s
from ..io.expressions import ExpressionError
from ..io.expressions import parse as parse_expression
from . import checks, setup
from .console import esc
from .kinds import KINDS, RunKind, register
from .plan import Plan, times
from .run_reports import REPORT_HTML


def _prescribed_ref(runner, ref: str, path) -> None:
    """A prescribed coordinate: a body's ``x``, ``y`` or ``phi``, or a point's ``x`` or ``y``."""
    parts = ref.split(".")
    if len(parts) == 3:
        runner.b.point(f"{parts[0]}.{parts[1]}", path, ground=False)
        if parts[2] not in ("x", "y"):
            runner.fail(path, f"{ref!r}: a point coordinate is x or y", "write body.point.x")
        return
    runner.b.coordinate(ref, path)


#: "degree of freedom" in its two numbers.
_DOF = ("degree of freedom", "degrees of freedom")


class AnalysisKind(RunKind):
    """A run of one analysis, its value made from the keywords of the run's settings
    (:meth:`keywords`, :func:`.setup.analysis_of`), prepared and run on the run's model and
    output times."""

    # ----------------------------------------------------------------- planning and checks
    def plan(self, runner, index: int, r) -> Plan:
        path = ("runs", index)
        b = runner.b
        ts = times(runner, r.time, (*path, "time"))
        if self.dynamic and ts.size < 2:
            runner.fail((*path, "time"), "a dynamic run needs at least two output times", "")
        model_drivers = {d.name for d in runner.model.drivers}
        if r.drivers is not None:
            for k, name in enumerate(r.drivers):
                if name not in model_drivers:
                    runner.fail(
                        (*path, "drivers", k),
                        f"unknown driver {name!r}",
                        f"the model's drivers: {', '.join(model_drivers) or '(none)'}",
                    )
        for k, ref in enumerate(r.hold or ()):
            b.coordinate(ref, (*path, "hold", k))
        if r.velocities and not self.integrated:
            runner.fail(
                (*path, "velocities"),
                f"initial velocities have no effect in a {r.kind} run (the drivers fix them)",
                "remove them",
            )
        for key, kind_of_value in (
            ("initial", setup.position_kind),
            ("velocities", setup.velocity_kind),
        ):
            for ref, value in getattr(r, key).items():
                _, coord = b.coordinate(ref, (*path, key, ref))
                b.scalar(value, kind_of_value(coord), (*path, key, ref))
        depends = []
        model = runner.model
        names = {e.name for e in (*model.joints, *model.drivers, *model.forces)}
        for k, p in enumerate(r.prescribed):
            pp = (*path, "prescribed", k)
            _prescribed_ref(runner, p.coordinate, (*pp, "coordinate"))
            if p.name is not None and p.name in names:
                runner.fail((*pp, "name"), f"the name {p.name!r} is taken by the model", "rename")
            if p.from_run is not None:
                if p.from_run == r.name:
                    runner.fail((*pp, "from_run"), "a run cannot replay itself", "name another run")
                src = next((x for x in runner.spec.runs if x.name == p.from_run), None)
                if src is None:
                    runner.fail(
                        (*pp, "from_run"),
                        f"unknown run {p.from_run!r}",
                        f"runs: {', '.join(x.name for x in runner.spec.runs)}",
                    )
                refusal = KINDS[src.kind].not_replayable
                if refusal is not None:
                    runner.fail(
                        (*pp, "from_run"),
                        f"run {p.from_run!r} is {refusal}",
                        "replay a forward, inverse, kinematic or mixed run",
                    )
                depends.append(p.from_run)
            else:
                setup.prescribed_driver(runner, p, pp)
        self.check_own(runner, r, path)
        for k, plot in enumerate(r.plots):
            pp = (*path, "plots", k)
            for c, col in enumerate(plot.columns):
                checks.check_column(runner, col, r, (*pp, "columns", c))
            if plot.x != "t":
                checks.check_column(runner, plot.x, r, (*pp, "x"))
                if plot.reference is not None:
                    runner.fail(
                        (*pp, "reference"),
                        "a reference curve is a law of t: it needs the plot against t",
                        "remove 'x' or the reference",
                    )
            if plot.reference is not None:
                _check_reference(runner, plot, r, (*pp, "reference"))
        if r.animation is not None:
            for k, ref in enumerate(r.animation.trace):
                b.point(ref, (*path, "animation", "trace", k))
        if getattr(r, "dt", None) is not None:
            dt = b.scalar(r.dt, "time", (*path, "dt"))
            if not dt > 0:
                runner.fail((*path, "dt"), "dt must be positive", "")
        plan = Plan(r, index, ts, tuple(dict.fromkeys(depends)))
        checks.check_settings(runner, plan)
        return plan

    def check_own(self, runner, r, path) -> None:
        """The checks of this kind's own settings, when the run is planned."""

    def plots(self, runner, plan: Plan) -> list:
        """The figures a run draws: its ``plots``, or for a dynamic or inverse run without
        any, the plots every designer draws first: the drivers' efforts, the unknown forces
        (mixed) and the joints' reactions (a panel per unit each). A run with the motion only
        has none by default."""
        r = plan.spec
        if r.plots or self.motion_only:
            return list(r.plots)
        names, _ = checks.columns(runner, r)
        model = runner.model
        drivers = [d.name for d in model.drivers if r.drivers is None or d.name in r.drivers]
        if not self.unknown_forces:
            drivers += [p.name or f"prescribed {p.coordinate}" for p in r.prescribed]
        joints = {j.name for j in model.joints}
        reactions = [c for c in names if c.rsplit(".", 1)[-1] in ("Fx", "Fy", "M")]
        reactions = [c for c in reactions if c.rsplit(".", 1)[0] in joints]
        out = []
        for file, cols, title in (
            ("efforts.png", drivers, "Driver efforts"),
            ("unknown_forces.png", list(getattr(r, "unknown", None) or ()), "Unknown forces"),
            ("reactions.png", reactions, "Joint reactions (on body j)"),
        ):
            if cols:
                out.append(s.PlotSpec(file=file, columns=cols, title=f"{r.name}: {title}"))
        return out

    # ----------------------------------------------------------------- set-up and executing
    def assembles_first(self, options: dict) -> bool:
        """Whether the run's start is assembled with its drivers (else the rough start is
        closed with its held coordinates only)."""
        return True

    def keywords(self, r, args: dict, options: dict, dt, drivers) -> dict:
        """The keywords of the run's analysis (those of its function, ``mixdyn.forward``...),
        read as its analysis value (:func:`.setup.analysis_of`).

        Args:
            r: the run's description.
            args: the start's arguments (:func:`.setup.start_args`).
            options: the run's ``options`` (but ``linear_solver``).
            dt: the run's fixed step [time], or None.
            drivers: its prescribed motions, as drivers.
        """
        raise NotImplementedError

    def execute(self, runner, plan: Plan, results: dict, progress: Callable | None):
        run = setup.analysis_of(runner, plan, results)
        return run.run(plan.times, progress if self.integrated else None)

    def progress(self, plan: Plan, console) -> Callable | None:
        return console.times(plan) if self.integrated else None

    # ----------------------------------------------------------------- outputs
    def output_files(self, runner, plan: Plan, figures: bool) -> list[str]:
        names = ["results.csv", "meta.json", REPORT_HTML]
        if figures:
            names += [p.file for p in runner.plots(plan)]
            if plan.spec.animation is not None:
                names.append(plan.spec.animation.file)
        return names

    def draws(self, runner, plan: Plan) -> bool:
        return bool(plan.spec.plots or runner.plots(plan) or plan.spec.animation is not None)

    def write(self, runner, plan: Plan, result, seconds: float, outputs) -> list[pathlib.Path]:
        from ..io.results import run_settings, write_result

        folder = outputs.folder(plan)
        figures = outputs.figures
        figs = [p.file for p in runner.plots(plan)] if figures else []
        anim = []
        if figures and plan.spec.animation is not None:
            a = plan.spec.animation
            anim = [a.file] + ([str(pathlib.Path(a.file).with_suffix(".html"))] if a.html else [])
        files = write_result(
            result,
            folder,
            parquet=outputs.parquet,
            excel=outputs.excel,
            settings=run_settings(plan.spec),
            output_units=runner.output_units,
            points=plan.spec.outputs,
            extra={
                "file": str(outputs.file),
                "run": plan.name,
                "wall_time_s": round(seconds, 3),
                "figures": figs,
                "animation": anim,
                "report": REPORT_HTML,
            },
        )
        if outputs.painter is not None:
            _figures(runner, plan, result, folder, outputs.painter)
        report = _report(runner, plan, result, seconds, outputs, [*figs, *anim])
        return [*files, *outputs.add_report(report)]  # now, or once its figures are drawn

    # ----------------------------------------------------------------- shown
    def describe(self, plan: Plan, report, model) -> str:
        r = plan.spec
        n = report.n_drivers
        free = report.dof - n
        state = "balanced" if n == report.dof else f"{free} free {_DOF[free != 1]}"
        return (
            f"run [bold]{esc(r.name)}[/bold] ({r.kind}): {count(len(plan.times), 'output time')} "
            f"{plan.times[0]:g}..{plan.times[-1]:g} {model.units.time}, "
            f"{count(n, 'prescribed motion')} for {report.dof} DOF ({state}){self.described(r)}"
        )

    def described(self, r) -> str:
        """What ``mixdyn check``'s line adds about a run of this kind (``", ..."``)."""
        return ""

    def done(self, plan: Plan, result, seconds: float, folder: pathlib.Path) -> str:
        return f"{plan.name}: {result.kind}, {len(result.t)} rows, {seconds:.2f} s -> {folder}"


@register
class Kinematic(AnalysisKind):
    """A kinematic run: the drivers fix the motion (:func:`mixdyn.kinematic`)."""

    name = "kinematic"
    fully_driven = True
    motion_only = True

    def keywords(self, r, args, options, dt, drivers) -> dict:
        kw = {"max_iter": r.max_iter}
        if r.tol is not None:
            kw["tol"] = r.tol
        return dict(**args, **kw)


@register
class Statics(AnalysisKind):
    """A quasi-static run: the mechanism in equilibrium along its drivers' motion
    (:func:`mixdyn.quasi_static`)."""

    name = "statics"
    element_columns = False

    def keywords(self, r, args, options, dt, drivers) -> dict:
        return dict(**args, tol=r.tol, max_iter=r.max_iter)


@register
class Inverse(AnalysisKind):
    """An inverse-dynamics run: the drivers' efforts and the reactions along the motion the
    drivers fix (:func:`mixdyn.inverse`)."""

    name = "inverse"
    dynamic = True
    fully_driven = True
    differentiable_efforts = True

    def assembles_first(self, options: dict) -> bool:
        return bool(options.get("assemble_first", True))

    def keywords(self, r, args, options, dt, drivers) -> dict:
        options.pop("assemble_first", None)
        return dict(**args, **options)


class _Integrated(AnalysisKind):
    """A run integrated in time by one of the integrators."""

    dynamic = True
    integrated = True

    def keywords(self, r, args, options, dt, drivers) -> dict:
        return dict(method=r.method, rtol=r.rtol, atol=r.atol, dt=dt, **args, **options)


@register
class Forward(_Integrated):
    """A forward-dynamics run: the motion under the forces (:func:`mixdyn.forward`)."""

    name = "forward"


@register
class Mixed(_Integrated):
    """A mixed run: unknown forces and the motion, given as many prescribed motions
    (:func:`mixdyn.mixed`)."""

    name = "mixed"
    unknown_forces = True

    def check_own(self, runner, r, path) -> None:
        checks.check_mixed(runner, r, path)

    def keywords(self, r, args, options, dt, drivers) -> dict:
        return dict(
            prescribed=drivers,
            unknown=list(r.unknown),
            solver=r.solver,
            independent=None if r.independent is None else list(r.independent),
            **super().keywords(r, args, options, dt, drivers),
        )

    def described(self, r) -> str:
        return f", unknown {', '.join(r.unknown)}, solver {r.solver}"


# --------------------------------------------------------------------------- report
def _report(runner, plan: Plan, result, seconds: float, outputs, figures: list):
    """The run's report (:class:`mixdyn.viz.report.Report`): its facts, the mechanism at the
    start, its figures (``figures``, names in its folder), its columns as written (output
    units) and its settings. No compiled program runs: the columns are the result's."""
    from .._version import __version__
    from ..analysis.result import in_units, point_columns
    from ..io.results import run_settings
    from ..units import engineering
    from ..viz.report import Report, start_drawing

    folder = outputs.folder(plan)
    model = result.model
    cols, units = in_units(result, *point_columns(result, plan.spec.outputs), runner.output_units)
    units = {c: engineering(u) for c, u in units.items()}
    t = np.asarray(result.t)
    facts = [
        ("model", f"{model.name} ({outputs.file})"),
        ("run", f"{plan.name} ({plan.spec.kind})"),
        ("status", "ok"),
        ("output times", f"{len(t)}, {t[0]:g} .. {t[-1]:g} {model.units.time}" if len(t) else "0"),
        ("wall time", f"{seconds:.3f} s"),
        ("mixdyn", __version__),
    ]
    return Report(
        path=folder / REPORT_HTML,
        title=f"{model.name}: run {plan.name}",
        facts=facts,
        drawing=start_drawing(result),
        figures=[folder / f for f in figures],
        columns=cols,
        units=units,
        settings=run_settings(plan.spec),
    )


# --------------------------------------------------------------------------- figures
def _figures(runner, plan: Plan, result, folder: pathlib.Path, painter) -> None:
    """Hand the plots and animation a run asks for to ``painter`` (the data is prepared here:
    columns, references, the scene; the HTML player is written here, after). The animation
    goes first: the longest task, it then has a channel of the worker to itself while the
    plots share the other."""
    from ..io.quantities import factor
    from ..io.results import in_units
    from ..units import engineering
    from ..viz import html, movie_data, result_columns

    a = plan.spec.animation
    pages = []  # the player's HTML pages, written here once the worker has its tasks
    if a is not None:
        path = folder / a.file
        if path.suffix.lower() == ".mp4" and shutil.which("ffmpeg") is None:
            raise ValueError(
                "writing MP4 needs ffmpeg, which is not installed; write a .gif or .html"
            )
        if path.suffix.lower() == ".html":
            pages.append(path)
        else:
            data = movie_data(result, frames=a.frames, trace=a.trace, forces=a.forces)
            painter.draw("movie", data, path, fps=a.fps)
        if a.html:
            pages.append(path.with_suffix(".html"))
    for k, p in enumerate(runner.plots(plan)):
        try:
            cols, units = result_columns(result, [*p.columns, p.x])
        except KeyError as e:
            runner.fail((*plan.path, "plots", k, "columns"), str(e.args[0]), "fix the column name")
        shown, units = in_units(result, cols, units, runner.output_units)
        units = {c: engineering(u) for c, u in units.items()}
        reference = None
        if p.reference is not None:
            y = _reference(runner, p.reference, result.t)
            kind = result.kind_of(p.columns[0])  # drawn in the first column's unit
            if kind in runner.output_units:
                y = y / factor(runner.output_units[kind], kind, result.model.units)
            reference = (result.t, y, p.reference.label or p.reference.expr)
        painter.draw(
            "plot",
            shown,
            p.columns,
            folder / p.file,
            units=units,
            title=p.title,
            ylabel=p.ylabel,
            reference=reference,
            x=p.x,
        )
    for page in pages:
        painter.done(
            html(
                result,
                page,
                fps=a.fps,
                trace=a.trace,
                forces=a.forces,
                columns=a.plot,
                plot_x=a.plot_x,
            )
        )


def _check_reference(runner, plot: s.PlotSpec, r, path) -> None:
    """A plot's reference curve, checked as a law of ``t`` of the kind of the plot's first
    column (it is drawn in that column's panel and unit): its expression's dimension, as a
    law's (:mod:`mixdyn.io.readings`), and its ``unit``'s; where the kind is not known before
    the run, the expression's form and the unit alone."""
    ref = plot.reference
    kind = checks.column_kind(runner, plot.columns[0], r)
    if kind is not None:
        runner.b.law(s.ExpressionSpec(expr=ref.expr, unit=ref.unit), kind, path)
        return
    try:
        parse_expression(ref.expr, runner.b.parameters)
    except ExpressionError as e:
        runner.fail((*path, "expr"), e.message, e.hint)
    if ref.unit is not None:
        runner.b.factor(ref.unit, None, (*path, "unit"))


def _reference(runner, ref, t) -> np.ndarray:
    """A plot's reference curve, a law of ``t`` [model units of its ``unit``]."""
    from ..io.expressions import ExpressionLaw, evaluate
    from ..io.quantities import factor

    scale = 1.0 if ref.unit is None else factor(ref.unit, None, runner.b.units)
    law = ExpressionLaw(ref.expr, runner.b.parameters, ref.unit, scale)
    # evaluated by NumPy: each jax.numpy operation outside a compiled program is one of its own
    t = np.asarray(t, dtype=float)
    values = np.asarray(law.values)
    return float(law.scale) * (np.asarray(evaluate(law.tree, t, values, xp=np)) + 0.0 * t)


__all__ = ["AnalysisKind", "Forward", "Inverse", "Kinematic", "Mixed", "Statics"]
