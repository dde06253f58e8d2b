"""Function generation in a synthesis run (``function:``): the task read from the file, and
what its run writes.

A ``function`` gives the rocker's angle at given crank angles (``pairs``), or ``y = f(x)``
(``expr`` of ``x`` and the file's parameters) over a range ``x`` mapped linearly onto the
crank's angles ``input`` and the rocker's angles ``output`` at precision points
(:meth:`mixdyn.synthesis.FunctionTask.from_function`). The path's keys (``timing``,
``bounds``, ``masses``, the torque) are refused with it: a function's objective is its angle
error. Its run writes ``candidates.csv`` (the ratios to the ground link, the start angles,
the error), ``best.yaml`` (the best four-bar, its ground link 1 m, with a kinematic run of the
crank's and rocker's angles over the inputs), ``meta.json`` and ``synthesis.png`` (the asked
pairs against the achieved rocker angle).
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..io import schema as s
from ..io._errors import FileError
from ..synthesis import FunctionSynthesis, FunctionTask

#: The path generation's keys, refused beside ``function``.
PATH_KEYS = (
    "timing",
    "timing_from",
    "bounds",
    "masses",
    "speed",
    "torque",
    "torque_weight",
    "shaking",
    "shaking_force_weight",
    "shaking_moment_weight",
    "reaction",
    "reaction_weight",
    "pivots",
)


def function_task(runner, path, r: s.SynthesisRunSpec, si) -> FunctionTask:
    """The function task of run ``r`` at ``path`` (``si``: a number of the file in SI)."""
    for key in PATH_KEYS:
        if key in r.model_fields_set:
            runner.fail(
                (*path, key),
                f"{key!r} is for path generation (points), not for a function",
                "a function's objective is its angle error: remove it",
            )
    f = r.function
    fp = (*path, "function")
    ratios = tuple(si(v, "dimensionless", (*fp, "ratios", k)) for k, v in enumerate(f.ratios))
    min_mu = si(r.min_transmission, "angle", (*path, "min_transmission"))
    options = {"free_start": f.free_start, "bounds": ratios, "min_transmission": min_mu,
               "grashof": r.grashof}  # fmt: skip
    try:
        if f.pairs is not None:
            pairs = np.array(
                [[si(v, "angle", (*fp, "pairs", i, k)) for k, v in enumerate(p)]
                 for i, p in enumerate(f.pairs)]
            )  # fmt: skip
            return FunctionTask(pairs[:, 0], pairs[:, 1], **options)
        x = tuple(si(v, "dimensionless", (*fp, "x", k)) for k, v in enumerate(f.x))
        a = tuple(si(v, "angle", (*fp, "input", k)) for k, v in enumerate(f.input))
        b = tuple(si(v, "angle", (*fp, "output", k)) for k, v in enumerate(f.output))
        return FunctionTask.from_function(
            _function_of(runner, f.expr, (*fp, "expr")),
            x,
            a[1] - a[0],
            b[1] - b[0],
            points=f.points,
            input_start=a[0],
            output_start=b[0],
            spacing=f.spacing,
            **options,
        )
    except FileError:  # a number read at its own line
        raise
    except ModelError as e:
        where = {"inputs": "pairs", "f": "expr", "x": "x", "bounds": "ratios"}.get(e.element)
        runner.fail((*fp, where) if where else fp, e.message, "")


def _function_of(runner, text: str, path):
    """``f(x)`` (NumPy, elementwise) of the expression ``text`` of ``x`` and the file's
    parameters, checked: it parses, and is finite where it is asked."""
    from ..io.expressions import ExpressionError, evaluate, parse

    values = dict(runner.b.parameters)
    values.pop("x", None)
    try:
        parsed = parse(text, [*values, "x"], time=False)
    except ExpressionError as e:
        runner.fail(path, e.message, e.hint)

    def f(x):
        x = np.asarray(x, dtype=float)
        args = [x if n == "x" else values[n] for n in parsed.parameters]
        with np.errstate(all="ignore"):
            y = np.asarray(evaluate(parsed.tree, None, args, xp=np), dtype=float) + 0 * x
        if not np.all(np.isfinite(y)):
            runner.fail(path, f"{text!r} is not finite at x = {x[~np.isfinite(y)][0]:g}", "")
        return y

    return f


def function_table(out: FunctionSynthesis):
    """``(names, units, rows)``: a row per candidate, least error first."""
    names = ["r2", "r3", "r4", "branch", "input_start", "output_start", "error"]
    names.append("min_transmission")
    units = {"input_start": "rad", "output_start": "rad", "error": "rad²"}
    units["min_transmission"] = "rad"
    rows = [
        [float(c.fourbar.r2), float(c.fourbar.r3), float(c.fourbar.r4), float(c.fourbar.branch),
         c.input_start, c.output_start, c.error, c.min_transmission]
        for c in out.candidates
    ]  # fmt: skip
    return names, units, np.array(rows, dtype=float)


def curves(out: FunctionSynthesis, drawn: int, samples: int = 241) -> list:
    """Per candidate ``(run, rest)``: the rocker's angle against the crank's (K, 2) [deg]
    over the task's inputs, and nothing beyond them (the figure's curves)."""
    task = out.task
    inputs = np.linspace(task.inputs[0], task.inputs[-1], samples)
    shown = []
    for c in out.candidates[:drawn]:
        outputs = c.output(inputs, near=task.outputs[0])
        shown.append((np.rad2deg(np.column_stack([inputs, outputs])), np.zeros((0, 2))))
    return shown


__all__ = ["PATH_KEYS", "curves", "function_table", "function_task"]
