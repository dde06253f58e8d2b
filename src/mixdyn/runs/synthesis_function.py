"""Function generation in a synthesis run (``function:``): the task read from the file, and
what its run writes.

A ``function`` gives the linkage's output at given crank angles (``pairs``), or ``y = f(x)``
(``expr`` of ``x`` and the file's parameters) over a range ``x`` mapped linearly onto the
crank's angles ``input`` and the outputs ``output`` at precision points
(:meth:`mixdyn.synthesis.FunctionTask.from_function`). The run's ``linkage`` says whose
output: a four-bar's rocker angle (the default), a slider-crank's slider position [length],
a Stephenson III's or a Watt II's follower angle; a Watt I and a Stephenson I are refused
(:func:`mixdyn.synthesis._task.function_linkage`). The path's keys (``timing``, ``bounds``,
``masses``, the torque) are refused with it: a function's objective is its output error.
Its run writes ``candidates.csv`` (the numbers varied: ratios to the ground link, a
slider-crank's lengths in m; the starts, the error), ``best.yaml`` (the best linkage, a
four-bar's or a six-bar's ground link 1 m, with a kinematic run of the crank's angle and the
output over the inputs), ``meta.json`` and ``synthesis.png`` (the asked pairs against the
achieved output).
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..io import schema as s
from ..io._errors import FileError
from ..synthesis import FunctionSynthesis, FunctionTask
from ..synthesis._limits import check_grashof
from ..synthesis._task import function_linkage
from ..synthesis.build import FUNCTION_OUTPUTS

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
    try:
        linkage = function_linkage(r.linkage)
    except ModelError as e:
        runner.fail((*path, "linkage"), e.message, "")
    try:
        check_grashof(linkage, r.grashof)
    except ModelError as e:
        runner.fail((*path, "grashof"), e.message, "")
    f = r.function
    fp = (*path, "function")
    ratios = tuple(si(v, "dimensionless", (*fp, "ratios", k)) for k, v in enumerate(f.ratios))
    min_mu = si(r.min_transmission, "angle", (*path, "min_transmission"))
    options = {"free_start": f.free_start, "bounds": ratios, "min_transmission": min_mu,
               "grashof": r.grashof, "linkage": linkage}  # fmt: skip
    out = "angle" if linkage.OUTPUT == "angle" else "length"  # the output's kind
    try:
        if f.pairs is not None:
            pairs = np.array(
                [[si(v, ("angle", out)[k], (*fp, "pairs", i, k)) for k, v in enumerate(p)]
                 for i, p in enumerate(f.pairs)]
            )  # fmt: skip
            return FunctionTask(pairs[:, 0], pairs[:, 1], **options)
        x = tuple(si(v, "dimensionless", (*fp, "x", k)) for k, v in enumerate(f.x))
        a = tuple(si(v, "angle", (*fp, "input", k)) for k, v in enumerate(f.input))
        b = tuple(si(v, out, (*fp, "output", k)) for k, v in enumerate(f.output))
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
        if e.element in ("grashof", "min_transmission"):  # the run's own keys
            runner.fail((*path, e.element), e.message, "")
        given = "pairs" if f.pairs is not None else "output"
        where = {"inputs": "pairs", "outputs": given, "f": "expr", "x": "x", "bounds": "ratios"}
        where = where.get(e.element)
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


def error_words(task: FunctionTask) -> tuple[str, str, str]:
    """``(what, error's unit, output's unit)`` of ``task``'s error in words (SI):
    ``("angle error", "rad²", "rad")`` or ``("position error", "m²", "m")``."""
    if task.linkage.OUTPUT == "angle":
        return "angle error", "rad²", "rad"
    return "position error", "m²", "m"


def function_table(out: FunctionSynthesis):
    """``(names, units, rows)``: a row per candidate, least error first: the numbers varied
    (a four-bar's and a six-bar's ratios to the ground link, a slider-crank's lengths [m]),
    the branch, the starts, the error and the least transmission angle."""
    task = out.task
    _, error_unit, unit = error_words(task)
    varied = list(out.varied)
    names = [*varied, "branch", "input_start", "output_start", "error", "min_transmission"]
    units = {"input_start": "rad", "output_start": unit, "error": error_unit}
    units["min_transmission"] = "rad"
    if unit == "m":
        units.update({n: "m" for n in varied})
    rows = [
        [*(float(getattr(c.linkage, n)) for n in varied), float(c.linkage.branch),
         c.input_start, c.output_start, c.error, c.min_transmission]
        for c in out.candidates
    ]  # fmt: skip
    return names, units, np.array(rows, dtype=float)


def curves(out: FunctionSynthesis, drawn: int, samples: int = 241) -> list:
    """Per candidate ``(run, rest)``: the output against the crank's angle (K, 2) over the
    task's inputs (the crank's [deg]; an angle output's [deg], a slider's position [m]), and
    nothing beyond them (the figure's curves)."""
    task = out.task
    inputs = np.linspace(task.inputs[0], task.inputs[-1], samples)
    angle = task.linkage.OUTPUT == "angle"
    shown = []
    for c in out.candidates[:drawn]:
        outputs = c.output(inputs, near=task.outputs[0])
        run = np.column_stack([np.rad2deg(inputs), np.rad2deg(outputs) if angle else outputs])
        shown.append((run, np.zeros((0, 2))))
    return shown


def figure(out: FunctionSynthesis, drawn: int) -> tuple:
    """``(asked (N, 2), curves, options)`` of the run's figure: the asked pairs, the
    candidates' outputs (:func:`curves`) and the plot's axes, units and error unit."""
    task = out.task
    angle = task.linkage.OUTPUT == "angle"
    y = np.rad2deg(task.outputs) if angle else task.outputs
    asked = np.column_stack([np.rad2deg(task.inputs), y])
    body = FUNCTION_OUTPUTS[task.linkage].split(".")[0]
    options = {
        "unit": "deg" if angle else ("deg", "m"),
        "equal": False,
        "axes": ("crank angle", f"{body} {'angle' if angle else 'position'}"),
        "error_unit": error_words(task)[1],
    }
    return asked, curves(out, drawn), options


__all__ = ["PATH_KEYS", "curves", "error_words", "figure", "function_table", "function_task"]
