"""Motion generation in a synthesis run (``motion:``): the poses read from the file.

A ``motion`` gives the poses of the coupler, ``[x, y, angle]`` each (the coupler point
[length] and the angle of a line fixed in the coupler, with its unit), and optionally the
characteristic length that weighs the angle error (:class:`mixdyn.synthesis.MotionTask`).
The path's bounds, transmission angle, masses and torque apply as they do to a path;
``timing`` is refused beside it (a motion's crank angles are found). An angle written without
a unit is refused: ``30`` beside a length in mm would be read as 30 rad, and a pose's angle
is most often meant in degrees. The run writes what a path's run writes, with the carried
body's angle in the coupler (``coupler_angle``) in ``candidates.csv``, and ``best.yaml``'s
coupler turned so that its ``coupler.phi`` is the poses' angle.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from ..io import schema as s
from ..synthesis import MotionTask


def motion_task(runner, path, r: s.SynthesisRunSpec, si, options: dict, place) -> MotionTask:
    """The motion task of run ``r`` at ``path`` (``si``: a number of the file in SI;
    ``options``: the task's ``bounds``, ``min_transmission``, ``linkage``, ``grashof`` and
    ``pivots``, read as a path's; ``place(path, element, options)``: where a fault of the
    task's ``element`` lies, as a path's)."""
    for key in ("timing", "timing_from"):
        if key in r.model_fields_set:
            runner.fail(
                (*path, key),
                f"{key!r} is for path generation (points), not for a motion",
                "a motion's crank angles at the poses are found: remove it",
            )
    mp = (*path, "motion")
    poses = []
    for i, pose in enumerate(r.motion.poses):
        where = (*mp, "poses", i)
        x, y = (si(v, "length", (*where, k)) for k, v in enumerate(pose[:2]))
        poses.append((x, y, _angle(runner, pose[2], (*where, 2), si)))
    length = None
    if r.motion.length is not None:
        length = si(r.motion.length, "length", (*mp, "length"))
    try:
        return MotionTask(np.array(poses), length=length, **options)
    except ModelError as e:
        where = {"poses": mp, "length": (*mp, "length")}.get(e.element)
        runner.fail(where or place(path, e.element, options), e.message, "")


def _angle(runner, value, where, si) -> float:
    """A pose's angle in rad, refused without a unit (other than 0, or an expression of
    parameters with units)."""
    x = si(value, "angle", where)
    reading = runner.b.readings.records.get(tuple(where))
    if reading is not None and reading.unit is None and not reading.from_parameters and x != 0:
        runner.fail(
            where,
            f"the pose's angle {value!r} has no unit",
            f"write `{value} deg` or `{value} rad`",
        )
    return x


__all__ = ["motion_task"]
