"""Integrator options checked before any computing: known names only (close matches
suggested), every value of the right type, finite and in range, and the work bounded (a
fixed-step run's step count estimated and refused past ``max_steps``).

The one vocabulary of options: the Python API (:func:`check_options`) and the model-file
checks (:mod:`mixdyn.io.settings`) both use it.
"""

from __future__ import annotations

import difflib
import inspect
import math

import numpy as np

from ..errors import ModelError

#: Methods whose step is fixed (``dt`` required, no error control).
FIXED_STEP = ("baumgarte", "generalized-alpha")

#: Arguments of an integrator that are not options.
NOT_OPTIONS = ("problem", "ts", "q0", "qd0", "progress")

#: Choices of the options that take a name.
CHOICES = {
    "solver": ("tsit5", "dopri5", "dopri8"),
    "newton": ("auto", "modified", "full"),
}

#: Options that are switches.
SWITCHES = ("project_velocities", "assemble_first")


def _positive(v: float) -> bool:
    return math.isfinite(v) and v > 0


def _whole(v: float) -> bool:
    return math.isfinite(v) and v >= 1 and float(v).is_integer()


#: Range of each numeric option: ``(test, what the value must be)``.
RANGES = {
    "rtol": (_positive, "a finite number > 0 (e.g. 1e-8)"),
    "atol": (_positive, "a finite number > 0 (e.g. 1e-10)"),
    "dt": (_positive, "a finite step > 0 [time]"),
    "first_step": (_positive, "a finite step > 0 [time]"),
    "tol": (_positive, "a finite number > 0"),
    "energy_tol": (_positive, "auto, a finite number > 0 (e.g. 1e-4), or null/None (no check)"),
    "singular_tol": (lambda v: 0 < v < 1, "a number in (0, 1)"),
    "alpha": (lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0 [1/time]"),
    "beta": (lambda v: math.isfinite(v) and v >= 0, "a finite number >= 0 [1/time]"),
    "rho_inf": (lambda v: 0 <= v <= 1, "a number in [0, 1] (1: no numerical damping)"),
    "max_steps": (_whole, "a whole number >= 1"),
    "max_newton": (lambda v: _whole(v) and v <= 1000, "a whole number from 1 to 1000"),
    "max_iter": (lambda v: _whole(v) and v <= 1000, "a whole number from 1 to 1000"),
}

#: Options that may be None (a check turned off).
NULLABLE = ("energy_tol", "tol")


def known_options(integrator) -> dict[str, object]:
    """The options an integrator function takes (its keyword arguments) with their
    defaults."""
    params = inspect.signature(integrator).parameters
    return {
        n: p.default
        for n, p in params.items()
        if n not in NOT_OPTIONS and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)
    }


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


def step_count(times, dt: float) -> float:
    """Steps of a fixed-step run: each output interval split into steps no longer than
    ``dt``."""
    with np.errstate(all="ignore"):
        per = np.ceil(np.diff(np.asarray(times, dtype=float)) / dt * (1 - 1e-12))
    return float(np.sum(np.maximum(per, 1.0)))


def check_options(method: str, integrator, options: dict, ts: np.ndarray) -> dict:
    """Check the options of one integrator run; return them with ``None`` values dropped.

    Args:
        method: integrator name (for messages).
        integrator: the integrator function (its signature lists its options).
        options: the options given (``rtol``, ``atol``, ``dt`` and the method's own).
        ts: (N,) output times [time].

    Raises:
        ModelError: an unknown option (with close matches), a value out of range, a missing
            ``dt`` of a fixed-step method, or a fixed-step run longer than ``max_steps``.
    """
    known = known_options(integrator)
    opts = {k: v for k, v in options.items() if v is not None}
    if method in FIXED_STEP:
        # rtol/atol are the adaptive methods' (they have defaults in every analysis).
        opts.pop("rtol", None)
        opts.pop("atol", None)
    for name, value in opts.items():
        if name not in known:
            close = suggestions(name, known)
            hint = f"did you mean {' or '.join(close)}? " if close else ""
            raise ModelError(
                f"unknown option {name!r} of the {method} integrator; {hint}"
                f"its options are {', '.join(known)}",
                name,
            )
        problem = value_problem(name, value)
        if problem:
            raise ModelError(f"{name} {problem}, got {value!r}", name)
    if method in FIXED_STEP and "dt" not in opts:
        raise ModelError(
            f"the {method} integrator has a fixed step: give dt [time], e.g. "
            f"dt={(ts[-1] - ts[0]) / 2000:.3g}",
            "dt",
        )
    if "dt" in opts:
        dt = float(opts["dt"])
        steps = int(step_count(ts, dt))
        limit = int(opts.get("max_steps", known["max_steps"]))
        if steps > limit:
            fair = min(limit, 20_000)
            raise ModelError(
                f"dt = {dt:g} needs {steps:,} steps over {ts[-1] - ts[0]:g} [time], more than "
                f"max_steps = {limit:,}: use a larger step (dt = "
                f"{(ts[-1] - ts[0]) / fair:.3g} gives {fair:,} steps) or raise max_steps",
                "dt",
            )
    return opts


__all__ = [
    "CHOICES",
    "FIXED_STEP",
    "NULLABLE",
    "RANGES",
    "SWITCHES",
    "check_options",
    "known_options",
    "step_count",
    "suggestions",
    "value_problem",
]
