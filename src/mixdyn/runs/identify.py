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

from ..analysis import Result
from ..analysis.fit import _RATES, Fit
from ..analysis.sweep import _leaf_getter
from ..errors import ModelError
from ..io import schema as s
from .runner import ANALYSES, Plan, Runner, register_study

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
        base: the plan of the run whose settings the fit uses.
        measured: result column -> (N,) its measured values [model units].
        noise: result column -> its standard deviation [model units].
        start: path -> first guess (None: the model's value).
        bounds: path -> ``(low, high)``.
    """

    base: Plan | None = None
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


def _data_path(runner: Runner, name: str) -> pathlib.Path:
    file = runner.b.file
    folder = pathlib.Path(file).parent if file and not file.startswith("<") else pathlib.Path()
    return folder / name


def _read_data(runner: Runner, r: s.IdentifyRunSpec, path):
    import pandas as pd

    file = _data_path(runner, r.data)
    try:
        table = pd.read_csv(file)
    except FileNotFoundError:
        runner.fail((*path, "data"), f"no data file {str(file)!r}", "give a CSV file's path")
    except (OSError, ValueError, pd.errors.ParserError) as e:
        runner.fail((*path, "data"), f"{str(file)!r} cannot be read as CSV: {e}", "")
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


def plan(runner: Runner, index: int, r: s.IdentifyRunSpec) -> IdentifyPlan:
    """Check an identification run against the file, its model and its data."""
    path = ("runs", index)
    base = runner.study_base(index, r, ("forward", "mixed"), "fit")
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
        import pandas as pd

        v = pd.to_numeric(table[m.data], errors="coerce").to_numpy(dtype=float)
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
        measured[m.column], noise[m.column] = v, sigma
    start, bounds = {}, {}
    for name, f in r.fit.items():
        fp = (*path, "fit", name)
        kind = runner.model_number(name, fp, "fit")
        if f.start is not None:
            start[name] = runner.b.scalar(f.start, kind, (*fp, "start"))
        if f.bounds is not None:
            lo = runner.b.scalar(f.bounds[0], kind, (*fp, "bounds", 0))
            hi = runner.b.scalar(f.bounds[1], kind, (*fp, "bounds", 1))
            if not hi > lo:
                runner.fail((*fp, "bounds"), f"the bounds [{lo:g}, {hi:g}] are empty", "")
            bounds[name] = (lo, hi)
    return IdentifyPlan(
        r, index, t, (), base=base, measured=measured, noise=noise, start=start, bounds=bounds
    )


def execute(runner: Runner, plan: IdentifyPlan) -> FileFit:
    """Fit, then run at the estimate."""
    import equinox as eqx
    import jax.numpy as jnp

    from ..analysis.fit import fit

    r: s.IdentifyRunSpec = plan.spec
    analysis, model, kwargs = runner.call(plan.base, {}, checked=False)
    params = list(r.fit)
    nominal = [float(_leaf_getter(model, p)[0](model)) for p in params]
    x0 = [plan.start.get(p, v) for p, v in zip(params, nominal, strict=True)]
    try:
        result = fit(
            model,
            plan.times,
            plan.measured,
            params,
            noise=plan.noise,
            start=x0,
            bounds=plan.bounds or None,
            analysis=analysis,
            max_evaluations=r.max_evaluations,
            **kwargs,
        )
    except ModelError as e:
        runner.fail(plan.path, str(e), "")
    fitted = model
    for p, v in zip(params, result.values, strict=True):
        get, _ = _leaf_getter(fitted, p)
        fitted = eqx.tree_at(get, fitted, jnp.asarray(float(v)))
    run = ANALYSES[analysis](fitted, plan.times, **kwargs)
    return FileFit(plan, result, run)


register_study("identify", plan, IdentifyPlan, lambda runner, plan, progress: execute(runner, plan))

__all__ = ["FileFit", "IdentifyPlan", "execute", "plan"]
