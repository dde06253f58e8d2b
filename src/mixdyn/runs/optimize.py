"""Optimization runs of a model file: numbers chosen to minimize a scalar of another run.

An ``optimize`` run names a forward, mixed or inverse run (``run:``), the scalar
(``objective:``: a result column reduced over the output times, ``sense:`` minimize or
maximize) and the numbers to choose with their bounds (``vary:``). It runs
:func:`mixdyn.optimize` (reverse-mode gradients, scipy's L-BFGS-B), then the run at the optimum.

Example (``examples/slider_crank_spring.yaml``)::

    - name: spring
      kind: optimize
      run: revolution                          # an inverse run over a revolution
      objective: {column: motor, reduce: rms}
      vary:
        spring.stiffness: {bounds: [0 N/mm, 100 N/mm]}
        spring.free_length: {bounds: [0 mm, 1000 mm]}

``mixdyn run`` writes ``optimum.csv`` (a row per number: bounds, start, optimum, gradient),
``results.csv`` and ``meta.json`` of the run at the optimum (the objective at the start and at
the optimum, the iterations) and ``optimize.png`` (the objective per iteration; the column at
the start and at the optimum).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import paths
from ..analysis import Result
from ..analysis.fit import _RATES
from ..analysis.optimize import Optimum, reduce
from ..errors import ModelError
from ..io import schema as s
from . import setup
from .console import esc
from .kinds import KINDS, RunKind, register
from .outputs import write_study_run
from .plan import Plan, check_value, model_number, study_base


@dataclasses.dataclass(frozen=True)
class OptimizePlan(Plan):
    """A checked optimization run.

    Attributes:
        bounds: path -> ``(low, high)`` [model units].
        start: path -> first guess (absent: the model's value within the bounds).

    Its ``base`` is the plan of the run whose result the objective reduces.
    """

    bounds: dict = dataclasses.field(default_factory=dict)
    start: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class FileOptimum:
    """The result of an optimization run: the optimum, the runs at the start and optimum."""

    plan: OptimizePlan
    optimum: Optimum
    result: Result
    first: Result

    @property
    def kind(self) -> str:
        return "optimize"


def _selector(runner, column: str, kind: str):
    """``outputs -> (N,)`` for ``column`` of the differentiable outputs of a run of ``kind``,
    or None."""
    body, _, suffix = column.rpartition(".")
    coord = _RATES.get(suffix, suffix)
    if body in runner.b.body_index and coord in ("x", "y", "phi"):
        k = runner.model.coordinate_index(f"{body}.{coord}")
        which = "qd" if suffix in _RATES else "q"
        return lambda o: o[which][:, k]
    if KINDS[kind].differentiable_efforts:
        joints = {j.name for j in runner.model.joints}
        drivers = {d.name for d in runner.model.drivers}
        name, _, comp = column.partition(".")
        if (name in joints and comp in ("Fx", "Fy", "M")) or (column in drivers):
            return lambda o: o[column]
    return None


def plan(runner, index: int, r: s.OptimizeRunSpec) -> OptimizePlan:
    """Check an optimization run against the file and its model."""
    path = ("runs", index)
    base = study_base(runner, index, r, ("forward", "mixed", "inverse"), "optimize")
    if _selector(runner, r.objective.column, base.spec.kind) is None:
        what = "a body coordinate or velocity"
        if KINDS[base.spec.kind].differentiable_efforts:
            what += ", a joint's Fx/Fy/M or a driver's effort"
        runner.fail((*path, "objective", "column"), f"{r.objective.column!r} is not {what}", "")
    bounds, start = {}, {}
    for name, v in r.vary.items():
        vp = (*path, "vary", name)
        kind = model_number(runner, name, vp, "vary")
        lo = runner.b.scalar(v.bounds[0], kind, (*vp, "bounds", 0))
        hi = runner.b.scalar(v.bounds[1], kind, (*vp, "bounds", 1))
        if not hi > lo:
            runner.fail((*vp, "bounds"), f"the bounds [{lo:g}, {hi:g}] are empty", "")
        for k, end in enumerate((lo, hi)):  # values a model may take, or refused here
            check_value(runner, name, end, paths.BOUND_ENDS[k], (*vp, "bounds", k))
        bounds[name] = (lo, hi)
        if v.start is not None:
            x = runner.b.scalar(v.start, kind, (*vp, "start"))
            if not lo <= x <= hi:
                runner.fail((*vp, "start"), f"the start {x:g} is outside [{lo:g}, {hi:g}]", "")
            start[name] = x
    return OptimizePlan(r, index, base.times, (), base=base, bounds=bounds, start=start)


def execute(runner, plan: OptimizePlan) -> FileOptimum:
    """Optimize, then run at the start and at the optimum."""
    import equinox as eqx
    import jax.numpy as jnp

    from ..analysis._keywords import from_keywords
    from ..analysis.optimize import optimize

    r: s.OptimizeRunSpec = plan.spec
    analysis, model, kwargs = setup.call(runner, plan.base, {}, checked=False)
    params = list(r.vary)
    select = _selector(runner, r.objective.column, analysis)
    sign = 1.0 if r.sense == "minimize" else -1.0

    def objective(o):
        return sign * reduce(r.objective.reduce, select(o))

    start = None
    if plan.start:
        nominal = [float(paths.getter(model, p)[0](model)) for p in params]
        start = [
            plan.start.get(p, float(np.clip(v, *plan.bounds[p])))
            for p, v in zip(params, nominal, strict=True)
        ]
    try:
        # the repeated run's analysis as a value (its keywords read once)
        value, recorded = from_keywords(analysis, plan.times, kwargs)
        opt = optimize(
            model,
            plan.times,
            objective,
            params,
            plan.bounds,
            start=start,
            analysis=value,
            max_iterations=r.max_iterations,
        )
    except ModelError as e:
        runner.fail(plan.path, str(e), "")
    if sign < 0:  # report the objective itself, not its negative
        opt = dataclasses.replace(
            opt,
            objective=-opt.objective,
            objective_start=-opt.objective_start,
            gradient=-opt.gradient,
            history=-opt.history,
        )

    def at(values):
        m = model
        for p, v in zip(params, values, strict=True):
            get, _ = paths.getter(m, p)
            m = eqx.tree_at(get, m, jnp.asarray(float(v)))
        return setup.RunAnalysis(analysis, m, value, recorded).run(plan.times)

    return FileOptimum(plan, opt, at(opt.values), at(opt.start))


@register
class OptimizeKind(RunKind):
    """An optimization: numbers chosen to minimize (or maximize) a scalar of another run."""

    name = "optimize"
    repeats = True
    not_replayable = "an optimize run"

    def plan(self, runner, index: int, spec) -> OptimizePlan:
        return plan(runner, index, spec)

    def execute(self, runner, plan: OptimizePlan, results: dict, progress) -> FileOptimum:
        return execute(runner, plan)

    def output_files(self, runner, plan: OptimizePlan, figures: bool) -> list[str]:
        names = ["optimum.csv", "results.csv", "meta.json", "report.html"]
        return names + (["optimize.png"] if figures else [])

    def draws(self, runner, plan: OptimizePlan) -> bool:
        return True

    def write(self, runner, plan: OptimizePlan, result: FileOptimum, seconds: float, outputs):
        from ..io.results import write_frame
        from .run_reports import optimum_report

        o, r = result.optimum, plan.spec
        details = {
            "objective": r.objective.model_dump(),
            "sense": r.sense,
            "parameters": list(o.params),
            "optimum": o.values,
            "start": o.start,
            "bounds": o.bounds,
            "gradient": o.gradient,
            "objective_start": o.objective_start,
            "objective_optimum": o.objective,
            "history": o.history,
            "iterations": o.iterations,
            "evaluations": o.evaluations,
            "message": o.message,
        }
        folder = outputs.folder(plan)
        files = write_study_run(
            runner, plan, result.result, seconds, outputs, "optimize", details, "optimize.png"
        )
        files.append(write_frame(o.table(), folder / "optimum.csv"))
        if outputs.painter is not None:
            from ..units import in_units
            from ..viz.plots import result_columns

            col = r.objective.column  # drawn in its output unit, as the report and the tables
            first, units = result_columns(result.first, ["t", col])
            best, _ = result_columns(result.result, [col])
            history = {col: np.asarray(o.history, dtype=float)}
            first, _ = in_units(result.first, first, units, runner.output_units)
            best, _ = in_units(result.result, best, units, runner.output_units)
            history, units = in_units(result.result, history, units, runner.output_units)
            outputs.painter.draw(
                "optimum",
                history[col],
                np.asarray(first["t"]),
                np.asarray(first[col]),
                np.asarray(best[col]),
                folder / "optimize.png",
                column=col,
                reduce=r.objective.reduce,
                units=units,
                title=f"{plan.name}: {r.sense} the {r.objective.reduce} of {col}",
            )
        files += outputs.add_report(optimum_report(runner, plan, result, seconds, outputs))
        return files

    def describe(self, plan: OptimizePlan, report, model) -> str:
        r = plan.spec
        o = r.objective
        return (
            f"run [bold]{esc(r.name)}[/bold] (optimize with {esc(r.run)}): "
            f"{r.sense} the {o.reduce} of {esc(o.column)} over {esc(', '.join(r.vary))}"
        )

    def task(self, plan: OptimizePlan, mode: str) -> tuple[str, float | None]:
        return f"{plan.name} (optimize with {plan.base.name})", None

    def done(self, plan: OptimizePlan, result: FileOptimum, seconds: float, folder) -> str:
        o = result.optimum
        return (
            f"{plan.name}: optimize, {plan.spec.objective.reduce} of "
            f"{plan.spec.objective.column} {o.objective_start:.6g} -> "
            f"{o.objective:.6g} in {o.iterations} iterations, {seconds:.2f} s -> {folder}"
        )


__all__ = ["FileOptimum", "OptimizeKind", "OptimizePlan", "execute", "plan"]
