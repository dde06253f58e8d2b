"""The analyses: kinematic, forward, inverse and mixed dynamics."""

from ._assembly import Assembly, assemble
from ._structure import DofReport, degrees_of_freedom
from .fit import Fit, fit
from .forward import forward
from .gradients import differentiable
from .integrators import INTEGRATORS
from .inverse import inverse
from .kinematic import kinematic
from .methods import Baumgarte, GeneralizedAlpha, IntegratorOptions, Partitioning, Projection
from .mixed import check_mixed, mixed, prescribe
from .optimize import Optimum, optimize
from .result import Result
from .statics import Statics, quasi_static, statics
from .sweep import Sweep, grid, latin_hypercube, sweep

__all__ = [
    "INTEGRATORS",
    "Assembly",
    "Baumgarte",
    "DofReport",
    "Fit",
    "GeneralizedAlpha",
    "IntegratorOptions",
    "Optimum",
    "Partitioning",
    "Projection",
    "Result",
    "Statics",
    "Sweep",
    "assemble",
    "check_mixed",
    "degrees_of_freedom",
    "differentiable",
    "fit",
    "forward",
    "grid",
    "inverse",
    "kinematic",
    "latin_hypercube",
    "mixed",
    "optimize",
    "prescribe",
    "quasi_static",
    "statics",
    "sweep",
]
