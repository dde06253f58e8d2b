"""Identification runs of a model file: numbers of the model fitted to a measured motion.

An ``identify`` run names a forward or mixed run whose settings it uses (``run:``), a CSV file
of measurements (``data:``, relative to the model file: a column ``t`` and the measured
columns, in model units), which result column each measured column measures and its noise
(``measured:``), and the numbers to fit (``fit:``, paths of body and force-element numbers with
an optional start and bounds). It runs :func:`mixdyn.fit` over the data's times, then the run
at the estimate.

Example (``examples/identify_slider_crank.yaml``)::

    - name: identify
      kind: identify
      run: forward
      data: data/slider_crank_recording.csv
      measured:
        - {column: slider.x, data: x, noise: 0.1 mm}
        - {column: crank.phi, data: phi, noise: 1 mrad}
      fit:
        slider.mass: {start: 1.3, bounds: [0.1, 10]}
        damper.damping: {start: 1.2}

``mixdyn run`` writes ``fit.csv`` (a row per number: start, estimate, standard deviation),
``results.csv`` and ``meta.json`` of the run at the estimate (the fit's chi-square and
evaluations in ``meta.json``) and ``fit.png`` (the measurements against the fitted motion).
"""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np

from .. import paths
from .._hints import count
from ..analysis import Result
from ..analysis.fit import _RATES, Fit, check_noise
from ..errors import ModelError
from ..io import schema as s
from ..io._errors import FileError
from . import setup
from .console import esc
from .kinds import RunKind, register
from .outputs import write_study_run
from .plan import Plan, check_value, model_number, study_base

#: Kinds of quantity of a measured column, by its suffix.
_KINDS = {
    "x": "length",
    "y": "length",
    "phi": "angle",
    "vx": "velocity",
    "vy": "velocity",
    "omega": "angular_velocity",
}


@dataclasses.dataclass(frozen=True)
class IdentifyPlan(Plan):
    """A checked identification run.

    Attributes:
        measured: result column -> (N,) its measured values [model units].
        noise: result column -> its standard deviation [model units].
        start: path -> first guess (None: the model's value).
        bounds: path -> ``(low, high)``.

    Its ``base`` is the plan of the run whose settings the fit uses.
    """

    measured: dict = dataclasses.field(default_factory=dict)
    noise: dict = dataclasses.field(default_factory=dict)
    start: dict = dataclasses.field(default_factory=dict)
    bounds: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class FileFit:
    """The result of an identification run: the fit and the run at the estimate."""

    plan: IdentifyPlan
    fit: Fit
    result: Result

    @property
    def kind(self) -> str:
        return "identify"


def _data_path(runner, name: str) -> pathlib.Path:
    file = runner.b.file
    folder = pathlib.Path(file).parent if file and not file.startswith("<") else pathlib.Path()
    return folder / name


def _read_data(runner, r: s.IdentifyRunSpec, path):
    """The recording: a regular CSV file of at most :data:`~mixdyn.io.tables.MAX_DATA_BYTES`
    bytes (:func:`mixdyn.io.tables.read_csv`)."""
    import pandas as pd

    from ..io import tables

    file = _data_path(runner, r.data)
    hint = "thin the recording (every k-th row) to a file that size"
    try:
        table = tables.read_csv(file, limit=tables.MAX_DATA_BYTES, hint=hint)
    except FileError as e:
        if e.problem == "no such file":
            runner.fail((*path, "data"), f"no data file {str(file)!r}", "give a CSV file's path")
        runner.fail((*path, "data"), f"data file {str(file)!r}: {e.problem}", e.hint)
    table = _header_units(runner, table, file, path)
    if "t" not in table.columns:
        runner.fail((*path, "data"), f"{str(file)!r} has no column 't'", "add the times as 't'")
    t = pd.to_numeric(table["t"], errors="coerce").to_numpy(dtype=float)
    if len(t) < 2 or not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0):
        runner.fail(
            (*path, "data"),
            f"the times of {str(file)!r} are not at least two finite, increasing numbers",
            "",
        )
    return file, table, t


def _header_units(runner, table, file, path):
    """The recording with ``name [unit]`` headers (as ``results.csv`` writes them) split into
    names, the units in ``table.attrs["units"]``, its times converted into the model's time
    unit (a unit of time, checked); the measured columns are converted where their kind is
    known (:func:`_measured_values`). Columns without a unit are in the model's units."""
    import pandas as pd

    from ..io.results import split_headers

    names, units = split_headers(table.columns)
    table = table.set_axis(names, axis=1)
    if units.get("t"):
        scale = runner.b.factor(units["t"], "time", (*path, "data"))
        table["t"] = pd.to_numeric(table["t"], errors="coerce") * scale
    table.attrs["units"] = units
    return table


def plan(runner, index: int, r: s.IdentifyRunSpec) -> IdentifyPlan:
    """Check an identification run against the file, its model and its data."""
    path = ("runs", index)
    base = study_base(runner, index, r, ("forward", "mixed"), "fit")
    import pandas as pd

    file, table, t = _read_data(runner, r, path)
    measured, noise = {}, {}
    for k, m in enumerate(r.measured):
        mp = (*path, "measured", k)
        body, _, suffix = m.column.rpartition(".")
        coord = _RATES.get(suffix, suffix)
        if body not in runner.b.body_index or coord not in ("x", "y", "phi"):
            runner.fail(
                (*mp, "column"),
                f"{m.column!r} is not a body coordinate or velocity",
                "measure e.g. slider.x, crank.phi, slider.vx or crank.omega",
            )
        if m.column in measured:
            runner.fail((*mp, "column"), f"{m.column!r} is measured twice", "list it once")
        if m.data not in table.columns:
            runner.fail(
                (*mp, "data"),
                f"{str(file)!r} has no column {m.data!r}",
                f"its columns: {', '.join(map(str, table.columns))}",
            )
        v = pd.to_numeric(table[m.data], errors="coerce").to_numpy(dtype=float)
        unit = table.attrs["units"].get(m.data)
        if unit:  # a header's unit: of the measured column's kind, converted
            v = v * runner.b.factor(unit, _KINDS[suffix], (*mp, "data"))
        if not np.all(np.isfinite(v)):
            row = int(np.argmax(~np.isfinite(v)))
            runner.fail(
                (*mp, "data"),
                f"column {m.data!r} of {str(file)!r} has a value that is not a finite number "
                f"(row {row + 2})",
                "",
            )
        sigma = runner.b.scalar(m.noise, _KINDS[suffix], (*mp, "noise"))
        if not sigma > 0:
            runner.fail((*mp, "noise"), "the noise must be > 0", "")
        try:
            check_noise(m.column, v, sigma, lambda k: f"line {k + 2} of {str(file)!r}")
        except ModelError as e:
            runner.fail((*mp, "noise"), e.message, "")
        measured[m.column], noise[m.column] = v, sigma
    start, bounds = {}, {}
    for name, f in r.fit.items():
        fp = (*path, "fit", name)
        kind = model_number(runner, name, fp, "fit")
        if f.start is not None:
            start[name] = runner.b.scalar(f.start, kind, (*fp, "start"))
            check_value(runner, name, start[name], "the start", (*fp, "start"))
        if f.bounds is not None:
            lo = runner.b.scalar(f.bounds[0], kind, (*fp, "bounds", 0))
            hi = runner.b.scalar(f.bounds[1], kind, (*fp, "bounds", 1))
            if not hi > lo:
                runner.fail((*fp, "bounds"), f"the bounds [{lo:g}, {hi:g}] are empty", "")
            for k, end in enumerate((lo, hi)):  # values a model may take, or refused here
                check_value(runner, name, end, paths.BOUND_ENDS[k], (*fp, "bounds", k))
            bounds[name] = (lo, hi)
    return IdentifyPlan(
        r, index, t, (), base=base, measured=measured, noise=noise, start=start, bounds=bounds
    )


def execute(runner, plan: IdentifyPlan) -> FileFit:
    """Fit, then run at the estimate."""
    import equinox as eqx
    import jax.numpy as jnp

    from ..analysis._keywords import from_keywords
    from ..analysis.fit import fit

    r: s.IdentifyRunSpec = plan.spec
    analysis, model, kwargs = setup.call(runner, plan.base, {}, checked=False)
    params = list(r.fit)
    nominal = [float(paths.getter(model, p)[0](model)) for p in params]
    x0 = [plan.start.get(p, v) for p, v in zip(params, nominal, strict=True)]
    try:
        # the repeated run's analysis as a value (its keywords read once)
        value, recorded = from_keywords(analysis, plan.times, kwargs)
        result = fit(
            model,
            plan.times,
            plan.measured,
            params,
            noise=plan.noise,
            start=x0,
            bounds=plan.bounds or None,
            analysis=value,
            max_evaluations=r.max_evaluations,
        )
    except ModelError as e:
        runner.fail(plan.path, str(e), "")
    fitted = model
    for p, v in zip(params, result.values, strict=True):
        get, _ = paths.getter(fitted, p)
        fitted = eqx.tree_at(get, fitted, jnp.asarray(float(v)))
    run = setup.RunAnalysis(analysis, fitted, value, recorded).run(plan.times)
    return FileFit(plan, result, run)


@register
class IdentifyKind(RunKind):
    """An identification: numbers of the model fitted to a measured motion."""

    name = "identify"
    repeats = True
    not_replayable = "an identify run"

    def plan(self, runner, index: int, spec) -> IdentifyPlan:
        return plan(runner, index, spec)

    def execute(self, runner, plan: IdentifyPlan, results: dict, progress) -> FileFit:
        return execute(runner, plan)

    def output_files(self, runner, plan: IdentifyPlan, figures: bool) -> list[str]:
        names = ["fit.csv", "results.csv", "meta.json", "report.html"]
        return names + (["fit.png"] if figures else [])

    def draws(self, runner, plan: IdentifyPlan) -> bool:
        return True

    def write(self, runner, plan: IdentifyPlan, result: FileFit, seconds: float, outputs):
        from ..io.results import write_frame
        from .run_reports import fit_report

        f = result.fit
        details = {
            "parameters": list(f.params),
            "estimate": f.values,
            "std_dev": f.deviations,
            "start": f.start,
            "chi2_reduced": f.chi2,
            "evaluations": f.evaluations,
            "message": f.message,
            "noise": plan.noise,
        }
        folder = outputs.folder(plan)
        files = write_study_run(
            runner, plan, result.result, seconds, outputs, "fit", details, "fit.png"
        )
        files.append(write_frame(f.table(), folder / "fit.csv"))
        if outputs.painter is not None:
            from ..viz.plots import result_columns

            cols, units = result_columns(result.result, list(plan.measured))
            outputs.painter.draw(
                "fit",
                np.asarray(plan.times),
                {k: np.asarray(v) for k, v in plan.measured.items()},
                {k: np.asarray(cols[k]) for k in plan.measured},
                folder / "fit.png",
                units=units,
                title=f"{plan.name}: measured and fitted ({', '.join(f.params)})",
            )
        files += outputs.add_report(fit_report(runner, plan, result, seconds, outputs))
        return files

    def describe(self, plan: IdentifyPlan, report, model) -> str:
        r = plan.spec
        return (
            f"run [bold]{esc(r.name)}[/bold] (identify with {esc(r.run)}): "
            f"{esc(', '.join(r.fit))} from {len(plan.times)} times of "
            f"{esc(', '.join(plan.measured))}"
        )

    def task(self, plan: IdentifyPlan, mode: str) -> tuple[str, float | None]:
        return f"{plan.name} (identify with {plan.base.name})", None

    def done(self, plan: IdentifyPlan, result: FileFit, seconds: float, folder) -> str:
        f = result.fit
        return (
            f"{plan.name}: identify, {count(len(f.params), 'number')}, chi-square "
            f"{f.chi2:.3g}, {count(f.evaluations, 'run')}, {seconds:.2f} s -> {folder}"
        )


__all__ = ["FileFit", "IdentifyKind", "IdentifyPlan", "execute", "plan"]
