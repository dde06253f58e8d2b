"""mixdyn: kinematics and forward, inverse and mixed dynamics of planar mechanisms.

All numerics run in JAX with float64 (enabled on import). Every quantity is expressed in the
model's :class:`~mixdyn.UnitSystem`; angles are in radians.

Compiled programs (traced and compiled) are kept between processes in a cache folder
(``$MIXDYN_CACHE_DIR``, else ``~/.cache/mixdyn/jax``), so a second process does not trace or
compile them again: ``MIXDYN_NO_CACHE=1`` (read on import) or :func:`set_cache` turns that
off (see :mod:`mixdyn.runtime`); JAX's own persistent cache is left as the user set it.

mixdyn compiles its own programs with XLA CPU options of its own (multi-threaded Eigen off,
which buys its small matrices nothing, the concurrency-optimized scheduler off, which hung a
vmapped loop, and where jaxlib knows the option the MLIR fusion emitters off, which compile
~30% slower) unless ``$XLA_FLAGS`` names them: see :mod:`mixdyn.runtime._xla`. Other JAX
programs of the process and ``$XLA_FLAGS`` are left as they are.
"""

import sys as _sys

from .runtime import _command

_command.hand_over()  # `mixdyn check`, `show`, `plot`, `schema`: a command server's answer
_command.pace_collector()  # the `mixdyn` command: cycles collected less often
_command.start_for_command_line()  # `mixdyn run` with figures: its drawing worker, before JAX

import jax as _jax  # noqa: E402

_jax.config.update("jax_enable_x64", True)

from .runtime._programs import set_cache  # noqa: E402

set_cache.__module__ = __name__
from .runtime._programs import configure_from_env as _configure_cache  # noqa: E402

if _configure_cache() is not None and (_tag := _command.job_tag(_sys.argv)) is not None:
    from .runtime._programs import prefetch as _prefetch

    _prefetch(_tag)  # `mixdyn run FILE`: its programs read while the rest imports

from . import (  # noqa: E402
    _moved,
    analyses,
    errors,
    paths,
)
from ._version import __version__  # noqa: E402
from .analysis import (  # noqa: E402
    Analysis,
    Assembly,
    Baumgarte,
    DofReport,
    Fit,
    GeneralizedAlpha,
    IntegratorOptions,
    Optimum,
    Partitioning,
    Projection,
    Result,
    Setup,
    Statics,
    Sweep,
    assemble,
    check_mixed,
    degrees_of_freedom,
    differentiable,
    fit,
    forward,
    grid,
    inverse,
    kinematic,
    latin_hypercube,
    mixed,
    optimize,
    prepare,
    prescribe,
    quasi_static,
    run,
    statics,
    sweep,
)
from .errors import (  # noqa: E402
    AssemblyError,
    ContactLostError,
    ConvergenceError,
    DegreesOfFreedomError,
    EnergyBalanceError,
    ImpactAccumulationError,
    MixdynError,
    ModelError,
    NonFiniteError,
    NumericalError,
    RedundantConstraintError,
    SingularityError,
    SolvabilityError,
    StepSizeError,
)
from .linalg import AutoSolver, BandedSolver, DenseSolver, LinearSolver, UnrolledSolver  # noqa: E402
from .model import *  # noqa: E402, F403
from .model import __all__ as _model_all  # noqa: E402
from .units import SI, UnitSystem  # noqa: E402


def _model_html(model) -> str:
    """A notebook's view of a model, drawn by :func:`mixdyn.viz.show.model_html` (the plots
    load on first use; attached here, above both, so that the model does not import them)."""
    from .viz.show import model_html

    return model_html(model)


def _result_html(result) -> str:
    """A notebook's view of a result, by :func:`mixdyn.viz.show.result_html` (as above)."""
    from .viz.show import result_html

    return result_html(result)


Model._repr_html_ = _model_html  # noqa: F405  (Model comes from .model's *)
Result._repr_html_ = _result_html


def _from_runs(name: str):
    """:mod:`mixdyn.runs`' ``name``, for its old spelling ``mixdyn.io.name`` (registered
    here, above both, so that the file formats do not import the runs of a file)."""
    from . import runs

    return getattr(runs, name)


for _name in ("Plan", "Runner", "execute"):
    _moved.register("mixdyn.io", _name, f"mixdyn.runs.{_name}", lambda n=_name: _from_runs(n))


#: Names of the file layer reached from the top, by their module (loaded on first use, and
#: left out of ``__all__`` so that ``import *`` does not load it): :func:`mixdyn.load` and
#: :func:`mixdyn.run_file` (a model file from Python), :func:`mixdyn.read_table` (written
#: results), :func:`mixdyn.write_excel` (a result as an Excel workbook);
#: :func:`mixdyn.synthesize` (linkage synthesis, :mod:`mixdyn.synthesis`), loaded on first
#: use too.
_FILE_NAMES = {
    "load": "runs.files",
    "run_file": "runs.files",
    "LoadedFile": "runs.files",
    "read_table": "io.results",
    "write_excel": "io.results",
    "synthesize": "synthesis",
}


def __getattr__(name):
    # The file layer (pydantic, pint) and the plots (matplotlib) load on first use.
    if name in ("io", "runs", "synthesis", "viz"):
        import importlib

        return importlib.import_module(f".{name}", __name__)
    if name in _FILE_NAMES:
        import importlib

        return getattr(importlib.import_module(f".{_FILE_NAMES[name]}", __name__), name)
    from . import model

    if name in model._REPLACED:  # deprecated registries: mixdyn.model warns
        return getattr(model, name)
    raise AttributeError(f"module 'mixdyn' has no attribute {name!r}")


__all__ = [
    "AutoSolver",
    "BandedSolver",
    "DenseSolver",
    "LinearSolver",
    "UnrolledSolver",
    "SI",
    "Analysis",
    "Assembly",
    "AssemblyError",
    "Baumgarte",
    "ConvergenceError",
    "DegreesOfFreedomError",
    "DofReport",
    "EnergyBalanceError",
    "GeneralizedAlpha",
    "IntegratorOptions",
    "MixdynError",
    "ModelError",
    "ImpactAccumulationError",
    "NonFiniteError",
    "ContactLostError",
    "NumericalError",
    "Partitioning",
    "Projection",
    "RedundantConstraintError",
    "Result",
    "Setup",
    "Fit",
    "Optimum",
    "Statics",
    "Sweep",
    "SingularityError",
    "SolvabilityError",
    "StepSizeError",
    "UnitSystem",
    "__version__",
    "analyses",
    "assemble",
    "check_mixed",
    "degrees_of_freedom",
    "differentiable",
    "fit",
    "optimize",
    "quasi_static",
    "statics",
    "errors",
    "forward",
    "grid",
    "latin_hypercube",
    "inverse",
    "mixed",
    "paths",
    "prepare",
    "prescribe",
    "run",
    "sweep",
    "set_cache",
    "kinematic",
    *_model_all,
]
