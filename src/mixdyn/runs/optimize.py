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

from ..analysis import Result
from ..analysis.fit import _RATES
from ..analysis.optimize import Optimum, reduce
from ..analysis.sweep import _leaf_getter
from ..errors import ModelError
from ..io import schema as s
from .runner import ANALYSES, Plan, Runner, register_study


@dataclasses.dataclass(frozen=True)
class OptimizePlan(Plan):
    """A checked optimization run.

    Attributes:
        base: the plan of the run whose result the objective reduces.
        bounds: path -> ``(low, high)`` [model units].
        start: path -> first guess (absent: the model's value within the bounds).
    """

    base: Plan | None = None
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


def _selector(runner: Runner, column: str, kind: str):
    """``outputs -> (N,)`` for ``column`` of a differentiable run's outputs, or None."""
    body, _, suffix = column.rpartition(".")
    coord = _RATES.get(suffix, suffix)
    if body in runner.b.body_index and coord in ("x", "y", "phi"):
        k = runner.model.coordinate_index(f"{body}.{coord}")
        which = "qd" if suffix in _RATES else "q"
        return lambda o: o[which][:, k]
    if kind == "inverse":
        joints = {j.name for j in runner.model.joints}
        drivers = {d.name for d in runner.model.drivers}
        name, _, comp = column.partition(".")
        if (name in joints and comp in ("Fx", "Fy", "M")) or (column in drivers):
            return lambda o: o[column]
    return None


def plan(runner: Runner, index: int, r: s.OptimizeRunSpec) -> OptimizePlan:
    """Check an optimization run against the file and its model."""
    path = ("runs", index)
    base = runner.study_base(index, r, ("forward", "mixed", "inverse"), "optimize")
    if _selector(runner, r.objective.column, base.spec.kind) is None:
        what = "a body coordinate or velocity"
        if base.spec.kind == "inverse":
            what += ", a joint's Fx/Fy/M or a driver's effort"
        runner.fail((*path, "objective", "column"), f"{r.objective.column!r} is not {what}", "")
    bounds, start = {}, {}
    for name, v in r.vary.items():
        vp = (*path, "vary", name)
        kind = runner.model_number(name, vp, "vary")
        lo = runner.b.scalar(v.bounds[0], kind, (*vp, "bounds", 0))
        hi = runner.b.scalar(v.bounds[1], kind, (*vp, "bounds", 1))
        if not hi > lo:
            runner.fail((*vp, "bounds"), f"the bounds [{lo:g}, {hi:g}] are empty", "")
        bounds[name] = (lo, hi)
        if v.start is not None:
            x = runner.b.scalar(v.start, kind, (*vp, "start"))
            if not lo <= x <= hi:
                runner.fail((*vp, "start"), f"the start {x:g} is outside [{lo:g}, {hi:g}]", "")
            start[name] = x
    return OptimizePlan(r, index, base.times, (), base=base, bounds=bounds, start=start)


def execute(runner: Runner, plan: OptimizePlan) -> FileOptimum:
    """Optimize, then run at the start and at the optimum."""
    import equinox as eqx
    import jax.numpy as jnp

    from ..analysis.optimize import optimize

    r: s.OptimizeRunSpec = plan.spec
    analysis, model, kwargs = runner.call(plan.base, {}, checked=False)
    params = list(r.vary)
    select = _selector(runner, r.objective.column, analysis)
    sign = 1.0 if r.sense == "minimize" else -1.0

    def objective(o):
        return sign * reduce(r.objective.reduce, select(o))

    start = None
    if plan.start:
        nominal = [float(_leaf_getter(model, p)[0](model)) for p in params]
        start = [
            plan.start.get(p, float(np.clip(v, *plan.bounds[p])))
            for p, v in zip(params, nominal, strict=True)
        ]
    try:
        opt = optimize(
            model,
            plan.times,
            objective,
            params,
            plan.bounds,
            start=start,
            analysis=analysis,
            max_iterations=r.max_iterations,
            **kwargs,
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
            get, _ = _leaf_getter(m, p)
            m = eqx.tree_at(get, m, jnp.asarray(float(v)))
        return ANALYSES[analysis](m, plan.times, **kwargs)

    return FileOptimum(plan, opt, at(opt.values), at(opt.start))


register_study("optimize", plan, OptimizePlan, lambda runner, plan, progress: execute(runner, plan))

__all__ = ["FileOptimum", "OptimizePlan", "execute", "plan"]
