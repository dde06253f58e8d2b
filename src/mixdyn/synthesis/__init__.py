"""Linkage synthesis: four-bars that draw a given path, searched by gradients, with dynamics
in the objective.

* :mod:`._fourbar` — a four-bar's numbers, its closed-form assembly on a fixed branch with
  implicit derivatives, its coupler curve and transmission angle;
* :mod:`._dynamics` — the links' inertia from the dimensions and the motor torque;
* :mod:`.build` — a synthesized four-bar as a :class:`mixdyn.Model` and a model file.
"""

from ._dynamics import Masses, link_inertia, motor_torque
from ._fourbar import NAMES, FourBar, coupler_curve, coupler_point, link_angles, transmission_cosine
from .build import four_bar_model, model_file_text

__all__ = [
    "NAMES",
    "FourBar",
    "Masses",
    "coupler_curve",
    "coupler_point",
    "four_bar_model",
    "link_angles",
    "link_inertia",
    "model_file_text",
    "motor_torque",
    "transmission_cosine",
]
