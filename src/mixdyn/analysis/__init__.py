"""The analyses: kinematic, forward, inverse and mixed dynamics."""

from ._assembly import Assembly, assemble
from ._structure import DofReport, degrees_of_freedom
from .forward import forward
from .kinematic import kinematic
from .result import Result

__all__ = [
    "Assembly",
    "DofReport",
    "Result",
    "assemble",
    "degrees_of_freedom",
    "forward",
    "kinematic",
]
