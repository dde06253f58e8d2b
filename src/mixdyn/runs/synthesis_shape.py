"""Shape-only path generation in a synthesis run (``shape: fourier``): the points are a
closed curve's, and the coupler curve over a full crank turn takes its shape
(:class:`mixdyn.synthesis.ShapeTask`).

The points, the linkage and the least transmission angle are read as a path's; ``harmonics``
gives the elliptic Fourier harmonics compared, ``sense`` whether the points may be run through
against the crank's positive sense (``either``, the default: the crank then turns backwards)
or not (``positive``). The shape fixes no place, size or orientation,
so ``timing``, ``bounds``, ``pivots`` and ``grashof`` are refused beside it (the crank turns
fully; the linkage is placed onto the points after the search), and so are the torque,
shaking and reaction weights (the search is for the shape alone; with ``masses`` the motor
torque and the rest are reported). The run writes what a path's run writes; in
``candidates.csv`` the error is the dimensionless shape error, ``distance`` the largest
distance of a point from the placed coupler curve, ``scale`` the placement's scale and
``sense`` the crank's (+1, or -1 where it turns backwards).
"""

from __future__ import annotations

from ..errors import ModelError
from ..io import schema as s
from ..synthesis import ShapeTask

#: The keys a shape task refuses, each with what to do instead.
_REFUSED = {
    "timing": "a shape has no timing: remove it",
    "timing_from": "a shape has no timing: remove it",
    "bounds": "a shape fixes no size or place: remove them (the linkage is placed onto the points)",
    "pivots": "a shape fixes no place: remove them (the linkage is placed onto the points)",
    "grashof": "the crank of a shape turns fully: remove it",
}

#: The weights a shape task refuses.
_WEIGHTS = ("torque_weight", "shaking_force_weight", "shaking_moment_weight", "reaction_weight")


def shape_task(runner, path, r: s.SynthesisRunSpec, points, min_transmission, linkage):
    """The shape task of run ``r`` at ``path`` (``points`` (N, 2) [m] read, ``min_transmission``
    [rad], ``linkage`` the class); every fault an input error at its line."""
    if r.points is None:
        runner.fail((*path, "shape"), "'shape: fourier' is a path's: give points", "")
    for key, fix in _REFUSED.items():
        if key in r.model_fields_set:
            runner.fail((*path, key), f"'{key}' does not go with 'shape: fourier'", fix)
    for key in _WEIGHTS:
        if key in r.model_fields_set:
            runner.fail(
                (*path, key),
                f"'{key}' does not go with 'shape: fourier': the search is for the shape alone",
                "remove it (with masses the motor torque is reported), or search the points",
            )
    try:
        return ShapeTask(
            points,
            harmonics=r.harmonics,
            min_transmission=min_transmission,
            linkage=linkage,
            sense=r.sense,
        )
    except ModelError as e:
        runner.fail((*path, e.element) if e.element else path, e.message, "")


def shape_columns(out, names: list, units: dict, rows: list) -> None:
    """A shape synthesis's columns of ``candidates.csv``, added in place: the error
    dimensionless, ``distance`` [m], ``scale`` and ``sense``."""
    if not isinstance(out.task, ShapeTask):
        return
    units["error"] = units["score"] = ""
    names += ["distance", "scale", "sense"]
    units["distance"] = "m"
    for row, c in zip(rows, out.candidates, strict=True):
        row += [c.distance, c.scale, c.sense]


def shape_words(task) -> str | None:
    """What a shape task asks, in words (None for another task)."""
    if not isinstance(task, ShapeTask):
        return None
    n, h = len(task.points), task.harmonics
    sense = "either sense" if task.sense == "either" else "the crank's sense"
    return f"{n} points of a closed curve, its shape alone ({h} harmonics, {sense})"


def figure_options(task) -> dict:
    """The figure's options of a shape task: its errors are shape errors (dimensionless)."""
    return {"error_unit": "(shape)"} if isinstance(task, ShapeTask) else {}


__all__ = ["figure_options", "shape_columns", "shape_task", "shape_words"]
