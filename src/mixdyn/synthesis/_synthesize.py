"""The one entry of linkage synthesis: :func:`synthesize` hands a task to its search (a path
or motion task's :func:`~._search.synthesize_path`, a function task's
:func:`~._function.synthesize_function`, a shape task's :func:`~._shape.synthesize_shape`)."""

from __future__ import annotations

from collections.abc import Callable

from ..errors import ModelError
from ._function import FunctionSynthesis, synthesize_function
from ._motion import MotionTask
from ._search import Synthesis, synthesize_path
from ._shape import ShapeSynthesis, ShapeTask, synthesize_shape
from ._task import FunctionTask, Objective, PathTask


def synthesize(
    task: PathTask | MotionTask | FunctionTask | ShapeTask,
    objective: Objective | None = None,
    *,
    starts: int = 2048,
    seed: int = 0,
    chunk: int = 512,
    max_steps: int = 300,
    keep: int = 10,
    polish: bool = True,
    progress: Callable[[str, int, int, float], None] | None = None,
) -> Synthesis | FunctionSynthesis | ShapeSynthesis:
    """Linkages whose coupler point passes ``task``'s targets (a :class:`PathTask`), whose
    coupler passes its poses (a :class:`~._motion.MotionTask`), or whose rocker follows its
    crank as asked (a :class:`~._function.FunctionTask`), best first: four-bars, or the
    slider-cranks or six-bars of a path or motion task made with ``linkage="slider_crank"``,
    ``"stephenson1"``, ``"stephenson3"``, ``"watt1"`` or ``"watt2"``.

    Args:
        task: the path task (linkage, targets, timing, bounds, transmission angle), the motion task
            (poses, bounds, transmission angle: a timing-free path task whose coupler angles
            count too, :mod:`._motion`), or the function task (input-output angle pairs;
            :func:`~._function.synthesize_function`, which takes ``starts``, ``seed``,
            ``chunk``, ``max_steps``, ``keep`` and ``progress``), or the shape task (a
            closed curve's shape, :class:`~._shape.ShapeTask`: :func:`~._shape.synthesize_shape`,
            ``polish`` unused).
        objective: the objective (default: the path error alone; a function task's is its
            angle error, and it takes none).
        starts: random starts, half on each assembly branch.
        seed: the random generator's seed (the same seed, the same starts and outcome).
        chunk: starts solved together (one vectorized program, compiled once).
        max_steps: Levenberg-Marquardt's steps at most per start.
        keep: distinct candidates returned at most.
        polish: with a torque weight, each outcome solved once more for the path (a motion
            task's poses) alone from where the weighted search left it (the nearest linkage
            that draws the path as well as it can, at nearly the same torque), then scored by
            the objective.
        progress: called after each chunk with ``(stage, starts done, starts, best score so
            far)``, ``stage`` ``"search"`` or ``"polish"``.

    Returns:
        A :class:`Synthesis` (a :class:`~._function.FunctionSynthesis` for a function task):
        for a motion task, its candidates' error is the pose error and their
        ``coupler_angle`` the carried body's line in the coupler; for a shape task a
        :class:`~._shape.ShapeSynthesis`, its candidates' error the shape error.

    Raises:
        ModelError: a bad number of starts, chunk or step count; an objective for a
            function task; a slider-crank's masses without a slider's mass.
    """
    if isinstance(task, FunctionTask):
        if objective is not None:
            raise ModelError(
                "a function task's objective is its angle error: give no objective", "objective"
            )
        return synthesize_function(
            task,
            starts=starts,
            seed=seed,
            chunk=chunk,
            max_steps=max_steps,
            keep=keep,
            progress=progress,
        )
    if isinstance(task, ShapeTask):
        return synthesize_shape(
            task,
            objective,
            starts=starts,
            seed=seed,
            chunk=chunk,
            max_steps=max_steps,
            keep=keep,
            progress=progress,
        )
    return synthesize_path(
        task,
        objective,
        starts=starts,
        seed=seed,
        chunk=chunk,
        max_steps=max_steps,
        keep=keep,
        polish=polish,
        progress=progress,
    )


__all__ = ["synthesize"]
