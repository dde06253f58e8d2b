"""Linkage synthesis: four-bars, slider-cranks and six-bars that draw a given path or
generate a function, searched by gradients, with dynamics in a path's objective.

* :mod:`._linkage` — what the linkages share (:class:`Linkage`): the crank, the coupler
  point and curve, the output a function follows, the transmission angle's contract;
* :mod:`._fourbar` — a four-bar's numbers, its closed-form assembly on a fixed branch with
  implicit derivatives, its transmission angle;
* :mod:`._slidercrank` — the same for an offset slider-crank (:class:`SliderCrank`; the
  path task's ``linkage="slider_crank"``);
* :mod:`._sixbar` — what the six-bars share: a four-bar and a dyad closed by a second
  circle intersection, the coupler point on the dyad; :mod:`._stephenson`
  (:class:`StephensonIII`, ``linkage="stephenson3"``; :class:`StephensonI`,
  ``linkage="stephenson1"``) and :mod:`._watt` (:class:`WattI`,
  ``linkage="watt1"``; :class:`WattII`, ``linkage="watt2"``), searched for a path or a
  motion, with their dynamics as a four-bar's;
* :mod:`._limits` — the Grashof type (:func:`grashof_type`; a task's ``grashof``) and the
  ground pivots' regions (a task's ``pivots``) as gaps: penalties and exact checks;
* :mod:`._dynamics` — the links' inertia from the dimensions, the motor torque, the shaking
  force and moment and the joint reactions;
* :mod:`._task` — what is asked: :class:`PathTask` (targets, timing, bounds, transmission
  angle), :class:`FunctionTask` (input-output pairs of a four-bar, a slider-crank, a
  Stephenson III or a Watt II, or a function over a range) and
  :class:`Objective` (path error, motor torque, shaking force and moment, joint reactions by
  weight);
* :mod:`._synthesize` — :func:`synthesize`, the one entry: a task handed to its search;
* :mod:`._search` — a path or motion task's search (:func:`~._search.synthesize_path`):
  thousands of random starts refined by Levenberg-Marquardt at once, checked, ranked and
  deduplicated;
* :mod:`._motion` — motion generation: :class:`MotionTask` (precision poses of the coupler)
  and its pose error, searched as a timing-free path whose coupler angles count too;
* :mod:`._fourier` and :mod:`._shape` — shape-only path generation: a closed curve's
  normalised elliptic Fourier descriptors, the search for a linkage whose coupler curve over
  a full turn has that shape (:class:`ShapeTask`), placed onto it;
* :mod:`._function` — the same search for a function task (:class:`FunctionSynthesis`);
* :mod:`._solve` — what both searches share: the batched Levenberg-Marquardt solve of many
  starts, chunk by chunk with progress, and the best of a ranked result;
* :mod:`.build` — a synthesized linkage as a :class:`mixdyn.Model` and a model file.

Example::

    import mixdyn as md
    from mixdyn.synthesis import Masses, Objective, PathTask

    task = PathTask(points, timing=None)                 # timing-free path generation
    out = md.synthesize(task, Objective(masses=Masses(density=2.0), torque_weight=1e-4))
    out.best.error, out.best.torque_rms
    out.write("best.yaml")                               # mixdyn run best.yaml
"""

from ._dynamics import Masses, link_inertia, motor_torque, reactions, shaking
from ._fourbar import NAMES, FourBar, coupler_curve, coupler_point, link_angles, transmission_cosine
from ._function import FunctionCandidate, FunctionSynthesis
from ._limits import GRASHOF, grashof_type
from ._linkage import Linkage
from ._motion import MotionTask
from ._search import Candidate, Synthesis
from ._settings import SearchSettings
from ._shape import ShapeCandidate, ShapeSynthesis, ShapeTask
from ._sixbar import SixBar
from ._slidercrank import SLIDER_NAMES, SliderCrank, rod_and_slider
from ._stephenson import STEPHENSON1_NAMES, STEPHENSON_NAMES, StephensonI, StephensonIII
from ._synthesize import synthesize
from ._task import FUNCTION_LINKAGES, LINKAGES, FunctionTask, Objective, PathTask, chebyshev
from ._watt import WATT2_NAMES, WATT_NAMES, WattI, WattII
from .build import (
    four_bar_model,
    linkage_model,
    model_file_text,
    six_bar_model,
    slider_crank_model,
)

__all__ = [
    "FUNCTION_LINKAGES",
    "GRASHOF",
    "LINKAGES",
    "NAMES",
    "SLIDER_NAMES",
    "STEPHENSON1_NAMES",
    "STEPHENSON_NAMES",
    "WATT2_NAMES",
    "WATT_NAMES",
    "Candidate",
    "FourBar",
    "FunctionCandidate",
    "FunctionSynthesis",
    "FunctionTask",
    "Linkage",
    "Masses",
    "MotionTask",
    "Objective",
    "PathTask",
    "SearchSettings",
    "ShapeCandidate",
    "ShapeSynthesis",
    "ShapeTask",
    "SixBar",
    "SliderCrank",
    "StephensonI",
    "StephensonIII",
    "Synthesis",
    "WattI",
    "WattII",
    "chebyshev",
    "coupler_curve",
    "coupler_point",
    "four_bar_model",
    "grashof_type",
    "link_angles",
    "link_inertia",
    "linkage_model",
    "model_file_text",
    "motor_torque",
    "reactions",
    "rod_and_slider",
    "shaking",
    "six_bar_model",
    "slider_crank_model",
    "synthesize",
    "transmission_cosine",
]
