"""Linkage synthesis: four-bars that draw a given path or generate a function, searched by
gradients, with dynamics in a path's objective.

* :mod:`._fourbar` — a four-bar's numbers, its closed-form assembly on a fixed branch with
  implicit derivatives, its coupler curve and transmission angle;
* :mod:`._dynamics` — the links' inertia from the dimensions and the motor torque;
* :mod:`._task` — what is asked: :class:`PathTask` (targets, timing, bounds, transmission
  angle), :class:`FunctionTask` (input-output angle pairs, or a function over a range) and
  :class:`Objective` (path error, motor torque by weight);
* :mod:`._search` — :func:`synthesize`: thousands of random starts refined by
  Levenberg-Marquardt at once, checked, ranked and deduplicated;
* :mod:`._function` — the same search for a function task (:class:`FunctionSynthesis`);
* :mod:`._solve` — what both searches share: the batched Levenberg-Marquardt solve of many
  starts, chunk by chunk with progress, and the best of a ranked result;
* :mod:`.build` — a synthesized four-bar as a :class:`mixdyn.Model` and a model file.

Example::

    import mixdyn as md
    from mixdyn.synthesis import Masses, Objective, PathTask

    task = PathTask(points, timing=None)                 # timing-free path generation
    out = md.synthesize(task, Objective(masses=Masses(density=2.0), torque_weight=1e-4))
    out.best.error, out.best.torque_rms
    out.write("best.yaml")                               # mixdyn run best.yaml
"""

from ._dynamics import Masses, link_inertia, motor_torque
from ._fourbar import NAMES, FourBar, coupler_curve, coupler_point, link_angles, transmission_cosine
from ._function import FunctionCandidate, FunctionSynthesis
from ._search import Candidate, Synthesis, synthesize
from ._task import FunctionTask, Objective, PathTask, chebyshev
from .build import four_bar_model, model_file_text

__all__ = [
    "NAMES",
    "Candidate",
    "FourBar",
    "FunctionCandidate",
    "FunctionSynthesis",
    "FunctionTask",
    "Masses",
    "Objective",
    "PathTask",
    "Synthesis",
    "chebyshev",
    "coupler_curve",
    "coupler_point",
    "four_bar_model",
    "link_angles",
    "link_inertia",
    "model_file_text",
    "motor_torque",
    "synthesize",
    "transmission_cosine",
]
