"""An analysis as a value, its set-up and its run.

An analysis is an immutable, keyword-only object that says what to compute and how
(:class:`Analysis`: :class:`~mixdyn.analyses.Kinematic`, :class:`~mixdyn.analyses.Forward`,
:class:`~mixdyn.analyses.Inverse`, :class:`~mixdyn.analyses.Mixed`,
:class:`~mixdyn.analyses.Static`, :class:`~mixdyn.analyses.QuasiStatic`), checked when made.
Two functions serve every entry point, as ``diffrax.diffeqsolve`` takes its problem, solver
and options apart:

* :func:`prepare` ``(model, analysis, t0) -> Setup``: everything done once before the time
  loop (the consistent start, the mobility analysis, the constraint set on its linear-solver
  path, the equations; a mixed run's solvability), by the analysis' own ``_prepare``;
* :func:`run` ``(setup, t) -> Result``: the time loop over the output times ``t`` and the
  result, by the analysis' own ``_run``. A set-up is used as it is, for any number of runs
  and time grids that start at its ``t0``.

``md.forward(model, t, ...)`` and the other analysis functions make the value from their
keywords, then prepare and run it; the studies (:func:`~mixdyn.sweep`,
:func:`~mixdyn.differentiable`, :func:`~mixdyn.fit`, :func:`~mixdyn.optimize`) take the value.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from typing import Any, ClassVar

import equinox as eqx
import numpy as np

from ..errors import ModelError
from ..linalg import LinearSolver, as_linear_solver
from ..model import Model
from ._options import suggestions, value_problem


class Analysis(eqx.Module):
    """What to compute and how: the base of the analysis values.

    Keyword-only, checked when made (an unknown option is a
    :class:`~mixdyn.errors.ModelError` with the close matches; a bad value names its option),
    immutable. Hand one to :func:`prepare`, then :func:`run` the set-up; or to a study
    (:func:`~mixdyn.sweep`, :func:`~mixdyn.differentiable`, :func:`~mixdyn.fit`,
    :func:`~mixdyn.optimize`).
    """

    #: The analysis' name, in messages (``"forward"``...).
    name: ClassVar[str]
    #: Whether a run is integrated in time by one of the integrators (forward and mixed
    #: dynamics): its set-up gives the integrator's case (:meth:`_case`), which a sweep
    #: integrates member by member or as one vectorized program.
    integrated: ClassVar[bool] = False

    def __new__(cls, *args, **kwargs):
        if not hasattr(cls, "name"):
            raise TypeError(
                "Analysis is the base of the analysis values: make a Kinematic, Forward, "
                "Inverse, Mixed, Static or QuasiStatic (mixdyn.analyses)"
            )
        known = [f.name for f in dataclasses.fields(cls)]
        for key in kwargs:
            if key not in known:
                close = suggestions(key, known)
                hint = cls._elsewhere(key, kwargs) or (
                    f"did you mean {' or '.join(close)}? " if close else ""
                )
                raise ModelError(
                    f"unknown option {key!r} of the {cls.name} analysis; {hint}its options "
                    f"are {', '.join(known)}",
                    key,
                )
        return super().__new__(cls, *args, **kwargs)

    @classmethod
    def _elsewhere(cls, key: str, kwargs: dict) -> str:
        """A hint for an unknown option ``key`` that belongs to another object (an
        integrator's option), or ``""``."""
        return ""

    def _initial(self, model: Model, t0: float, given=None):
        """The start this analysis makes of ``model`` at ``t0`` [time]: its consistent start
        and the mobility analysis there (:class:`~._prepare.Prepared`; the drivers not
        checked against the degrees of freedom); ``given``, a start made beforehand, in its
        place where it is the same (:func:`~._prepare.matching`)."""
        raise NotImplementedError

    def _prepare(self, model: Model, t0: float, given=None) -> Setup:
        """The set-up of this analysis of ``model`` from the start time ``t0`` [time]
        (``given``: a start made beforehand, in place of the analysis' own where it is the
        same: :meth:`_initial`)."""
        raise NotImplementedError

    def _run(self, setup: Setup, t, progress=None):
        """The run of ``setup`` over the output times ``t`` (N,) [time]."""
        raise NotImplementedError

    @classmethod
    def _from_keywords(cls, t, kwargs: dict) -> tuple[Analysis, dict | None]:
        """The keyword spelling of the analysis (its function's keywords) as the value, and
        the integrator options its results record (None: the value's own)."""
        return cls(**{k: v for k, v in kwargs.items() if k != "prepared"}), None

    @classmethod
    def _spelling(cls, kwargs: dict) -> str:
        """The value that the keyword spelling ``kwargs`` reads as, for a message."""
        given = ", ".join(f"{k}=..." for k in kwargs if k != "prepared")
        return f"mixdyn.analyses.{cls.__name__}({given})"


@dataclasses.dataclass(frozen=True)
class Setup:
    """An analysis prepared for one model from one start time: what :func:`run` needs, made
    once by :func:`prepare`.

    Attributes:
        analysis: the analysis value it was made for.
        model: the mechanism.
        t0: the start time [time]; a run's output times start there.
        start: the consistent start and its mobility analysis
            (:class:`~mixdyn.analysis._prepare.Prepared`: positions ``q`` (nq,), velocities
            ``qd`` (nq,) or None, the degrees-of-freedom report, the rows kept), or None
            (a quasi-static run, which starts each time from the one before).
        problem: the equations of motion (:class:`~mixdyn.analysis._problem.Problem`) of a
            forward, mixed or inverse run, or None.
        stats: what the analysis adds to a result's ``stats``.
        recorded: the integrator options a forward or mixed run records
            (``stats["options"]``), or None: the method object's own
            (:meth:`~mixdyn.IntegratorOptions.recorded`).
    """

    analysis: Analysis
    model: Model
    t0: float
    start: Any = None
    problem: Any = None
    stats: Mapping = dataclasses.field(default_factory=dict)
    recorded: dict | None = None


def prepare(model: Model, analysis: Analysis, *, t0: float = 0.0, start=None) -> Setup:
    """Prepare ``analysis`` of ``model`` from the start time ``t0``: every check and every
    computation done once before the time loop.

    Args:
        model: the mechanism.
        analysis: the analysis value (:mod:`mixdyn.analyses`: ``Forward(...)``,
            ``Mixed(...)``...).
        t0: the start time [time]: the consistent start is made there, and a run of the
            set-up has output times that start there.
        start: the start of an earlier set-up (``setup.start``: the consistent positions
            and velocities and the mobility analysis there), taken instead of making it again
            where ``analysis`` makes the same start: the same model and drivers, ``t0``, and
            start settings (``q0``, ``qd0``, ``hold``, ``assemble_first``,
            ``linear_solver``), e.g. a forward analysis with another integration method.
            Default None: the analysis makes its own. A static or quasi-static analysis
            makes its own in any case.

    Returns:
        A :class:`Setup`, for :func:`run` (as often as wanted, over any time grid from
        ``t0``).

    Raises:
        ModelError: ``analysis`` is not an analysis value, a ``start`` made otherwise, or an
            input error of the analysis (its subclasses: a degree-of-freedom imbalance, an
            unsolvable mixed problem...).
        NumericalError: the start cannot be made (an assembly that does not close).
    """
    if not isinstance(analysis, Analysis):
        raise ModelError(
            "analysis must be an analysis value of mixdyn.analyses (Kinematic(...), "
            f"Forward(...), Inverse(...), Mixed(...), Static(...), QuasiStatic(...)), got "
            f"{analysis!r}",
            "analysis",
        )
    if not isinstance(model, Model):
        raise ModelError(f"model must be a mixdyn.Model, got {type(model).__name__}", "model")
    return analysis._prepare(model, _time(t0), start)


def run(setup: Setup, t, *, progress=None):
    """Run a set-up over the output times ``t``.

    Args:
        setup: made by :func:`prepare`; used as it is (nothing is checked or prepared again).
        t: (N,) increasing output times [time] from the set-up's ``t0``; a static analysis
            takes its one time ``t0``.
        progress: optional ``f(t)`` called at each output time of a forward or mixed run
            (from inside the jitted loop).

    Returns:
        The analysis' result: a :class:`~mixdyn.Result` (a :class:`~mixdyn.Statics` for a
        :class:`~mixdyn.analyses.Static` analysis), the same as the analysis function's
        (``md.forward(model, t, ...)`` is ``run(prepare(model, Forward(...), t0=t[0]), t)``).

    Raises:
        ModelError: ``setup`` is not a set-up, the times do not start at its ``t0``, or a
            progress callback for a run that has none.
        NumericalError: the run failed (with the time and the elements involved).
    """
    if not isinstance(setup, Setup):
        raise ModelError(
            f"setup must be made by mixdyn.prepare(model, analysis), got {type(setup).__name__}",
            "setup",
        )
    return setup.analysis._run(setup, t, progress)


def keyword_setup(
    model: Model, analysis: Analysis, t0: float, recorded: dict | None = None, prepared=None
) -> Setup:
    """The set-up of an analysis function's call (``md.forward(model, t, ...)``): its
    analysis value prepared from ``t0``, recording ``recorded`` (the integrator options
    given by keywords); ``prepared``: a start made beforehand (the deprecated ``prepared=``
    keyword: :func:`prepare`'s ``start``)."""
    if prepared is not None:
        warnings.warn(
            "prepared= is deprecated: prepare the analysis once, setup = "
            f"mixdyn.prepare(model, mixdyn.analyses.{type(analysis).__name__}(...), t0=t[0]), "
            "and run it with mixdyn.run(setup, t); a start made beforehand is "
            "mixdyn.prepare(..., start=...)",
            DeprecationWarning,
            stacklevel=3,
        )
    setup = analysis._prepare(model, t0, prepared)
    return setup if recorded is None else dataclasses.replace(setup, recorded=recorded)


def _time(t0) -> float:
    try:
        value = float(t0)
    except (TypeError, ValueError):
        value = float("nan")
    if not np.isfinite(value):
        raise ModelError(f"the start time must be a finite number, got {t0!r}", "t0")
    return value


def check_start(setup: Setup, ts: np.ndarray, accelerations: bool = True) -> None:
    """Refuse output times ``ts`` (N,) that do not start at the set-up's ``t0``, and drivers
    whose laws jump in value or slope over them, or, for a run that reports
    ``accelerations``, in their second derivative (unless a driver's ``continuity`` is
    ``"C1"``; :meth:`~mixdyn.model.Driver.check_law`)."""
    if float(ts[0]) != setup.t0:
        raise ModelError(
            f"the set-up was made from t0 = {setup.t0:g} but the output times start at "
            f"{float(ts[0]):g}: run it over times from t0, or prepare it with "
            f"t0={float(ts[0]):g}",
            "t",
        )
    drivers = setup.model.drivers if setup.start is None else setup.start.drivers
    for driver in drivers:
        driver.check_law(float(ts[0]), float(ts[-1]), accelerations)


def no_progress(analysis: Analysis, progress) -> None:
    """Refuse a per-time progress callback for an analysis that has none."""
    if progress is not None:
        raise ModelError(f"a {analysis.name} run has no per-time progress callback", "progress")


# ------------------------------------------------------------------ the options' converters
def start_positions(value) -> np.ndarray | None:
    """``q0``: None (the bodies' ``q0``) or a read-only (nq,) float64 copy [model units]."""
    if value is None:
        return None
    try:
        q = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ModelError(f"q0 must be numbers (nq,), got {value!r}", "q0") from None
    if q.ndim != 1:
        raise ModelError(f"q0 must be one row of numbers (nq,), got shape {q.shape}", "q0")
    q.setflags(write=False)
    return q


def start_velocities(value):
    """``qd0``: None, velocity conditions ``{coordinate: velocity}`` (a dict, in the given
    order) or a read-only (nq,) float64 copy [model units]."""
    if value is None:
        return None
    if isinstance(value, Mapping):
        return {str(k): v for k, v in value.items()}
    try:
        qd = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ModelError(
            f"qd0 must be numbers (nq,) or a mapping {{coordinate: velocity}}, got {value!r}",
            "qd0",
        ) from None
    qd.setflags(write=False)
    return qd


def names(value, option: str) -> tuple[str, ...]:
    """A tuple of names (one name alone: a tuple of one)."""
    if value is None:
        return ()
    if isinstance(value, str):
        return (value,)
    try:
        out = tuple(value)
    except TypeError:
        raise ModelError(f"{option} must be names, got {value!r}", option) from None
    for v in out:
        if not isinstance(v, str):
            raise ModelError(f"{option} must be names (strings), got {v!r}", option)
    return out


def held(value) -> tuple[str, ...]:
    """``hold``: the coordinates held while the start is assembled (``"crank.phi"``)."""
    return names(value, "hold")


def linear_solver(value) -> LinearSolver:
    """``linear_solver``: the object (a name taken once: ``as_linear_solver``)."""
    return as_linear_solver(value)


def checked(option: str):
    """A converter that checks ``option``'s value against the options' vocabulary
    (:func:`~._options.value_problem`) and keeps it as a Python number (or None, "auto")."""

    def convert(value):
        problem = value_problem(option, value)
        if problem:
            raise ModelError(f"{option} {problem}, got {value!r}", option)
        if value is None or isinstance(value, (str, bool)):
            return value
        number = float(value)
        return int(number) if option.startswith("max_") else number

    convert.__name__ = f"checked_{option}"
    return convert


def switch(option: str):
    """A converter for a true/false option."""

    def convert(value):
        if not isinstance(value, (bool, np.bool_)):
            raise ModelError(f"{option} must be true or false, got {value!r}", option)
        return bool(value)

    return convert


def start_of(analysis: Analysis, *fields: str) -> dict[str, Any]:
    """The start settings of ``analysis`` as the keywords of the start's functions
    (:func:`~._prepare.dynamic_start`, :func:`~._prepare.kinematic_start`)."""
    return {f: getattr(analysis, f) for f in fields}


__all__ = ["Analysis", "Setup", "check_start", "no_progress", "prepare", "run"]
