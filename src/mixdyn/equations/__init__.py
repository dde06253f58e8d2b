"""Assembly of the equations of motion from the model's pure functions."""

from ._constraints import Constraints
from ._dynamics import (
    applied_forces,
    force_directions,
    force_output_kinds,
    force_outputs,
    gravity_force,
    kinetic_energy,
    largest_load,
    nonconservative_power,
    potential_energy,
)

__all__ = [
    "Constraints",
    "applied_forces",
    "force_directions",
    "force_output_kinds",
    "force_outputs",
    "gravity_force",
    "kinetic_energy",
    "largest_load",
    "nonconservative_power",
    "potential_energy",
]
