"""The one entry of linkage synthesis: :func:`synthesize` hands a task to its search (a path
or motion task's :func:`~._search.synthesize_path`, a function task's
:func:`~._function.synthesize_function`, a shape task's :func:`~._shape.synthesize_shape`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from ..errors import ModelError
from ._function import FunctionSynthesis, synthesize_function
from ._motion import MotionTask
from ._search import Synthesis, synthesize_path
from ._settings import SearchSettings
from ._shape import ShapeSynthesis, ShapeTask, synthesize_shape
from ._task import FunctionTask, Objective, PathTask


def synthesize(
    task: PathTask | MotionTask | FunctionTask | ShapeTask,
    objective: Objective | None = None,
    search: SearchSettings | None = None,
    *,
    starts: int | None = None,
    seed: int | None = None,
    chunk: int | None = None,
    max_steps: int | None = None,
    keep: int | None = None,
    polish: bool | None = None,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> Synthesis | FunctionSynthesis | ShapeSynthesis:
    """Linkages whose coupler point passes ``task``'s targets (a :class:`PathTask`), whose
    coupler passes its poses (a :class:`~._motion.MotionTask`), or whose output follows its
    crank as asked (a :class:`~._task.FunctionTask`: a four-bar's rocker angle, a
    slider-crank's slider position, a Stephenson III's or a Watt II's follower angle), best
    first: four-bars, or the slider-cranks or six-bars of a task made with
    ``linkage="slider_crank"``, ``"stephenson1"``, ``"stephenson3"``, ``"watt1"`` or
    ``"watt2"`` (a function task's: ``"slider_crank"``, ``"stephenson3"``, ``"watt2"``).

    Args:
        task: the path task (linkage, targets, timing, bounds, transmission angle), the motion task
            (poses, bounds, transmission angle: a timing-free path task whose coupler angles
            count too, :mod:`._motion`), or the function task (input-output pairs;
            :func:`~._function.synthesize_function`), or the shape task (a closed curve's
            shape, :class:`~._shape.ShapeTask`: :func:`~._shape.synthesize_shape`, ``polish``
            unused).
        objective: the objective (default: the path error alone; a function task's is its
            output error, and it takes none).
        search: how to search (:class:`~._settings.SearchSettings`: starts, seed, chunk,
            steps, candidates kept, polish); default ``SearchSettings()``.
        starts, seed, chunk, max_steps, keep, polish: the same, one by one, each replacing
            ``search``'s (2048 starts, seed 0, chunks of 512, 300 steps, 10 kept, polished
            by default).
        progress: called after each chunk with ``(stage, starts done, starts, best score so
            far)``, ``stage`` ``"search"`` or ``"polish"``.

    Returns:
        A :class:`Synthesis` (a :class:`~._function.FunctionSynthesis` for a function task):
        for a motion task, its candidates' error is the pose error and their
        ``coupler_angle`` the carried body's line in the coupler; for a shape task a
        :class:`~._shape.ShapeSynthesis`, its candidates' error the shape error.

    Raises:
        ModelError: a bad number of starts, chunk, step count or candidates kept; an
            objective for a function task; a slider-crank's masses without a slider's mass.
    """
    given = dict(starts=starts, seed=seed, chunk=chunk, max_steps=max_steps, keep=keep)
    given = {k: v for k, v in (*given.items(), ("polish", polish)) if v is not None}
    search = dataclasses.replace(search or SearchSettings(), **given)
    if isinstance(task, FunctionTask):
        if objective is not None:
            raise ModelError(
                "a function task's objective is its output error: give no objective", "objective"
            )
        return synthesize_function(task, search, progress=progress)
    if isinstance(task, ShapeTask):
        return synthesize_shape(task, objective, search, progress=progress)
    return synthesize_path(task, objective, search, progress=progress)


__all__ = ["synthesize"]
