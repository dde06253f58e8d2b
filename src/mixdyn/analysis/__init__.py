"""The analyses: kinematic, forward, inverse and mixed dynamics, statics; their values,
set-ups and runs (:mod:`._setup`); the studies on top of them."""

from ._assembly import Assembly, assemble
from ._setup import Analysis, Setup, prepare, run
from ._structure import DofReport, degrees_of_freedom
from .fit import Fit, fit
from .forward import Forward, forward
from .gradients import differentiable
from .integrators import INTEGRATORS
from .inverse import Inverse, inverse
from .kinematic import Kinematic, kinematic
from .methods import Baumgarte, GeneralizedAlpha, IntegratorOptions, Partitioning, Projection
from .mixed import Mixed, check_mixed, mixed, prescribe
from .optimize import Optimum, optimize
from .result import Result
from .statics import QuasiStatic, Static, Statics, quasi_static, statics
from .sweep import Sweep, grid, latin_hypercube, sweep

__all__ = [
    "INTEGRATORS",
    "Analysis",
    "Assembly",
    "Baumgarte",
    "DofReport",
    "Fit",
    "Forward",
    "GeneralizedAlpha",
    "IntegratorOptions",
    "Inverse",
    "Kinematic",
    "Mixed",
    "Optimum",
    "Partitioning",
    "Projection",
    "QuasiStatic",
    "Result",
    "Setup",
    "Static",
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
    "prepare",
    "prescribe",
    "quasi_static",
    "run",
    "statics",
    "sweep",
]
