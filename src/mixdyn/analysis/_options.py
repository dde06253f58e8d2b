"""The vocabulary of the integrators' options: the choices of the options that take a name,
the switches, the range of every number and the step count of a fixed-step run.

The options themselves are typed objects (:mod:`.methods`), checked against this vocabulary
when made; the model-file checks (:mod:`mixdyn.runs.checks`) use it too.
"""

from __future__ import annotations

import difflib
import math
import sys

import numpy as np

#: Choices of the options that take a name.
CHOICES = {
    "solver": ("tsit5", "dopri5", "dopri8"),
    "newton": ("auto", "modified", "full"),
}

#: Options that are switches.
SWITCHES = ("project_velocities", "assemble_first")


def _positive(v: float) -> bool:
    return math.isfinite(v) and v > 0


def _normal_positive(v: float) -> bool:
    return math.isfinite(v) and v >= sys.float_info.min


def _whole(v: float) -> bool:
    return math.isfinite(v) and v >= 1 and float(v).is_integer()


#: A step shorter than this fraction of the run's largest time (at least 1 [time]) cannot
#: advance time by more than a few hundred roundings of float64: the adaptive integrators
#: end a run whose step falls below it (a collapsed step), and a first step below it is
#: refused before the run (:func:`first_step_problem`).
DT_MIN = 1e-13

#: The largest step limit (2**31 - 1 steps, beyond any run's time): the limit is an integer
#: argument of the compiled loop, which a number such as 1e300 overflows.
MAX_STEPS = 2**31 - 1

#: Range of each numeric option: ``(test, what the value must be)``.
RANGES = {
    "rtol": (_positive, "a finite number > 0 (e.g. 1e-8)"),
    "atol": (_positive, "a finite number > 0 (e.g. 1e-10)"),
    "dt": (_positive, "a finite step > 0 [time]"),
    "first_step": (
        _normal_positive,
        f"a finite step > 0 [time], not subnormal (at least {sys.float_info.min:.3g})",
    ),
    "tol": (_positive, "a finite number > 0"),
    "energy_tol": (_positive, "auto, a finite number > 0 (e.g. 1e-4), or null/None (no check)"),
    "singular_tol": (lambda v: 0 < v < 1, "a number in (0, 1)"),
    "alpha": (lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0 [1/time]"),
    "beta": (lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0 [1/time]"),
    "rho_inf": (lambda v: 0 <= v <= 1, "a number in [0, 1] (1: no numerical damping)"),
    "max_steps": (
        lambda v: _whole(v) and v <= MAX_STEPS,
        f"a whole number from 1 to {MAX_STEPS:,}",
    ),
    "max_newton": (lambda v: _whole(v) and v <= 1000, "a whole number from 1 to 1000"),
    "max_iter": (lambda v: _whole(v) and v <= 1000, "a whole number from 1 to 1000"),
}

#: Options that may be None (a check turned off).
NULLABLE = ("energy_tol", "tol")


def suggestions(name: str, known) -> list[str]:
    """Names in ``known`` close to ``name``: similar spellings (difflib) and abbreviations
    (``tol`` for ``tolerance``)."""
    lower = str(name).lower()
    close = difflib.get_close_matches(lower, list(known), n=3, cutoff=0.5)
    close += [k for k in known if len(k) >= 3 and lower.startswith(k) and k not in close]
    return close[:3]


def value_problem(name: str, value) -> str | None:
    """What is wrong with the value of option ``name`` (``"must be ..."``), or None."""
    if value is None and name in NULLABLE:
        return None
    if name == "energy_tol" and value == "auto":
        return None
    if name in CHOICES:
        ok = value in CHOICES[name]
        return None if ok else f"must be one of {', '.join(CHOICES[name])}"
    if name in SWITCHES:
        return None if isinstance(value, bool) else "must be true or false"
    test, what = RANGES.get(name, (math.isfinite, "a finite number"))
    try:
        ok = not isinstance(value, bool) and test(float(value))
    except (TypeError, ValueError, OverflowError):
        ok = False
    return None if ok else f"must be {what}"


def step_floor(times) -> float:
    """The shortest step [time] that advances the output times ``times`` (N,) [time]:
    :data:`DT_MIN` times the largest ``|t|``, at least 1 [time] (the adaptive integrators'
    collapsed step)."""
    largest = float(np.max(np.abs(np.asarray(times, dtype=float))))
    return DT_MIN * max(largest, 1.0)


def first_step_problem(first_step: float, times) -> str | None:
    """What is wrong with a first step ``first_step`` [time] of a run over the output times
    ``times`` (N,) [time] (``"must be ..."``), or None: it must be at least
    :func:`step_floor` (shorter, it cannot advance time in float64) and at most the span."""
    lo = step_floor(times)
    span = float(np.ptp(np.asarray(times, dtype=float)))
    if first_step < lo:
        return (
            f"must be at least {lo:.3g} [time] = {DT_MIN:g} * max(|t|, 1): a shorter step "
            "cannot advance time in float64"
        )
    if first_step > span:
        return f"must be at most the run's span {span:g} [time]"
    return None


def step_count(times, dt: float) -> float:
    """Steps of a fixed-step run: each output interval split into steps no longer than
    ``dt``."""
    with np.errstate(all="ignore"):
        per = np.ceil(np.diff(np.asarray(times, dtype=float)) / dt * (1 - 1e-12))
    return float(np.sum(np.maximum(per, 1.0)))


__all__ = [
    "CHOICES",
    "DT_MIN",
    "NULLABLE",
    "RANGES",
    "SWITCHES",
    "first_step_problem",
    "step_count",
    "step_floor",
    "suggestions",
    "value_problem",
]
