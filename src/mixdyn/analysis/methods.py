"""The integration methods of forward and mixed dynamics, each with its options as one typed,
immutable object (as diffrax separates the problem, the solver and its options):

* :class:`Projection` — adaptive explicit Runge–Kutta, positions and velocities projected onto
  the constraints after each step (the default);
* :class:`Partitioning` — Wehage–Haug coordinate partitioning (adaptive explicit RK);
* :class:`Baumgarte` — fixed-step RK4 with Baumgarte stabilization;
* :class:`GeneralizedAlpha` — implicit, index 3, fixed step (stiff forces).

``md.forward(model, t, method=md.Projection(rtol=1e-10, solver="dopri8"))`` is the same run
as ``md.forward(model, t, method="projection", rtol=1e-10, solver="dopri8")``: a method name
with keyword options is turned into its object here (:func:`resolve`), in one place.

Every option is checked when the object is made (a :class:`~mixdyn.errors.ModelError` naming
the option): unknown names (with close matches), values of the wrong type or out of range
(the vocabulary of :mod:`._options`), and a fixed-step method without ``dt``. Numbers are
kept as Python numbers, so an object is hashable and equal to another with the same options.

Inside the integrators, the numbers that do not shape the computation (tolerances, first
step, the step ``dt``, Baumgarte's ``alpha`` and ``beta``, ``rho_inf``) are arrays
(:meth:`IntegratorOptions.as_argument`): another value is not another traced program, as with
keyword options; the other options (the Runge–Kutta method, the step limit, Newton's
variant...) and whether ``dt`` is given at all decide the program.
"""

from __future__ import annotations

import dataclasses
import difflib
from typing import ClassVar

import equinox as eqx
import numpy as np

from ..errors import ModelError
from ._options import first_step_problem, step_count, suggestions, value_problem


def _real(v: float) -> float:
    return float(v)


def _optional(v: float | None) -> float | None:
    return None if v is None else float(v)


def _count(v: int) -> int:
    return int(v)


def _switch(v: bool) -> bool:
    return bool(v)


def _name(v: str) -> str:
    return str(v)


class IntegratorOptions(eqx.Module):
    """The options of one integration method (the base of :class:`Projection`,
    :class:`Partitioning`, :class:`Baumgarte` and :class:`GeneralizedAlpha`).

    Keyword-only, checked when made (:class:`~mixdyn.errors.ModelError` naming the option),
    immutable and hashable. ``method`` is the method's name (``"projection"``...).
    """

    #: The method's name, as ``method=`` of :func:`~mixdyn.forward` takes it.
    method: ClassVar[str]
    #: Whether the method steps at a fixed ``dt`` (required; no error control).
    fixed_step: ClassVar[bool] = False
    #: Options passed to the integrator as float64 arrays (not part of the traced program).
    _arrays: ClassVar[tuple[str, ...]] = ()
    #: Whether the method integrates the independent coordinates only, and so needs the
    #: independent constraint rows (a regular ``Phi_q``); the others solve redundant rows in
    #: the least-squares sense.
    independent_rows: ClassVar[bool] = False
    #: Whether the method's step includes the reaction-dependent forces (solved with the
    #: accelerations).
    reaction_dependent: ClassVar[bool] = True
    #: Whether a run is differentiable (``jax.grad``, ``jax.jvp``) through the method's loop.
    differentiable: ClassVar[bool] = True
    #: Whether the method damps unresolved high frequencies by design (energy lost on
    #: purpose, named when the energy balance breaks).
    damps: ClassVar[bool] = False

    def __new__(cls, *args, **kwargs):
        if not hasattr(cls, "method"):
            raise TypeError(
                "IntegratorOptions is the base of the methods' options: make a Projection, "
                "Partitioning, Baumgarte or GeneralizedAlpha"
            )
        check(cls, kwargs, step=False)  # the step: once made (a copy is made without kwargs)
        return super().__new__(cls, *args, **kwargs)

    def __check_init__(self):
        if self.fixed_step and getattr(self, "dt", None) is None:
            check(type(self), {})  # a fixed-step method without its step

    @classmethod
    def defaults(cls) -> dict[str, object]:
        """The options and their defaults (``dt`` of a fixed-step method: None, required)."""
        return {f.name: f.default for f in dataclasses.fields(cls)}

    def recorded(self) -> dict[str, object]:
        """The options recorded with a run (``stats["options"]``, ``meta.json``): the
        tolerances of an adaptive method, and every other option set to another value than
        its default."""
        return {
            f.name: v
            for f in dataclasses.fields(self)
            if (v := getattr(self, f.name)) is not None
            and (f.name in ("rtol", "atol") or v != f.default)
        }

    def as_argument(self) -> IntegratorOptions:
        """The object the integrator is called with: the options of :attr:`_arrays` (tolerances,
        steps, stabilization and damping numbers) as float64 arrays, so that another value
        is another argument of the same program, not another program."""
        names = [n for n in self._arrays if getattr(self, n) is not None]
        if not names:
            return self
        return eqx.tree_at(
            lambda o: [getattr(o, n) for n in names],
            self,
            [np.asarray(getattr(self, n), dtype=np.float64) for n in names],
        )


class _AdaptiveRungeKutta(IntegratorOptions):
    """The options that projection and partitioning share (see either)."""

    _arrays: ClassVar[tuple[str, ...]] = ("rtol", "atol", "first_step", "dt")

    _: dataclasses.KW_ONLY
    rtol: float = eqx.field(default=1e-8, converter=_real)
    atol: float = eqx.field(default=1e-10, converter=_real)
    dt: float | None = eqx.field(default=None, converter=_optional)
    solver: str = eqx.field(default="tsit5", converter=_name)
    max_steps: int = eqx.field(default=1_000_000, converter=_count)
    first_step: float | None = eqx.field(default=None, converter=_optional)


class Projection(_AdaptiveRungeKutta):
    """``projection``: adaptive explicit Runge–Kutta on the index-1 equations of motion, with
    positions and velocities projected back onto the constraints after each accepted step
    (mass-weighted least-norm projection). The default method.

    Attributes:
        rtol: relative tolerance of the local error (on ``q`` and ``qd``) [-]. Default 1e-8.
        atol: absolute tolerance of the local error, in the model's units of each coordinate
            and velocity ([length] or [rad]; [length/time] or [rad/time]). Default 1e-10.
        dt: a fixed step [time] instead of error control (for convergence studies), or None
            (default: adaptive).
        solver: the Runge–Kutta method: ``"tsit5"`` (default, order 5), ``"dopri5"`` or
            ``"dopri8"`` (order 8).
        max_steps: step limit [steps]; default 1,000,000.
        first_step: the first step's size [time], or None (default: 1e-4 of the span or the
            first output interval, whichever is shorter); the controller adapts it from there.
            A normal float64 > 0, and for a run over the times ``t``, from
            ``1e-13 * max(max|t|, 1)`` (a shorter step cannot advance time in float64: the
            integrator's collapsed step) to the span; else refused before the run.
    """

    method: ClassVar[str] = "projection"


class Partitioning(_AdaptiveRungeKutta):
    """``partitioning``: Wehage–Haug generalized coordinate partitioning. The independent
    coordinates are integrated by adaptive explicit Runge–Kutta, the dependent ones solved
    from the constraints by Newton at every stage.

    Attributes:
        rtol: relative tolerance of the local error (on ``q`` and ``qd``) [-]. Default 1e-8.
        atol: absolute tolerance of the local error, in the model's units of each coordinate
            and velocity ([length] or [rad]; [length/time] or [rad/time]); the dependent
            coordinates' Newton tolerance is 1e-3 of it. Default 1e-10.
        dt: a fixed step [time] instead of error control, or None (default: adaptive).
        solver: the Runge–Kutta method: ``"tsit5"`` (default), ``"dopri5"`` or ``"dopri8"``.
        max_steps: step limit [steps]; default 1,000,000.
        first_step: the first step's size [time], or None (default: 1e-4 of the span or the
            first output interval, whichever is shorter); from ``1e-13 * max(max|t|, 1)``
            to the span, as :class:`Projection`'s.
    """

    method: ClassVar[str] = "partitioning"
    independent_rows: ClassVar[bool] = True


class Baumgarte(IntegratorOptions):
    """``baumgarte``: the textbook baseline. Fixed-step classical Runge–Kutta (order 4) on the
    index-1 equations with Baumgarte stabilization of the acceleration constraints,
    ``C qdd = gamma - 2 alpha Phi_dot - beta**2 Phi``; no projection.

    Attributes:
        dt: step [time], required; each output interval is split into equal steps no longer
            than it.
        alpha, beta: stabilization parameters [1/time], >= 0; default 10 each.
        max_steps: step limit [steps] (a run needing more is refused before it starts);
            default 10,000,000.
    """

    method: ClassVar[str] = "baumgarte"
    fixed_step: ClassVar[bool] = True
    _arrays: ClassVar[tuple[str, ...]] = ("dt", "alpha", "beta")

    _: dataclasses.KW_ONLY
    dt: float | None = eqx.field(default=None, converter=_optional)
    alpha: float = eqx.field(default=10.0, converter=_real)
    beta: float = eqx.field(default=10.0, converter=_real)
    max_steps: int = eqx.field(default=10_000_000, converter=_count)


class GeneralizedAlpha(IntegratorOptions):
    """``generalized-alpha``: implicit, index 3 (Arnold & Brüls 2007), Newton on the full
    system at a fixed step; for stiff forces.

    Attributes:
        dt: step [time], required; each output interval is split into equal steps no longer
            than it.
        rho_inf: spectral radius at infinite frequency [-], in [0, 1] (1: no numerical
            damping, 0: asymptotic annihilation); default 0.9.
        tol: Newton tolerance on the force residual [force, or torque for an angle], or None
            (default: 1e-10 of the initial force scale).
        max_newton: Newton iterations per step [-], 1 to 1000; default 20.
        newton: ``"auto"`` (default: modified Newton on the acceleration-level KKT matrix,
            switching within a step to the exact Newton matrix where it contracts poorly,
            e.g. a stiff spring at a large step), ``"modified"`` or ``"full"``.
        project_velocities: project the velocities onto the velocity constraints after each
            step (removes the index-3 velocity drift); default True.
        max_steps: step limit [steps] (a run needing more is refused before it starts);
            default 10,000,000.
    """

    method: ClassVar[str] = "generalized-alpha"
    fixed_step: ClassVar[bool] = True
    reaction_dependent: ClassVar[bool] = False
    differentiable: ClassVar[bool] = False
    damps: ClassVar[bool] = True
    _arrays: ClassVar[tuple[str, ...]] = ("dt", "rho_inf", "tol")

    _: dataclasses.KW_ONLY
    dt: float | None = eqx.field(default=None, converter=_optional)
    rho_inf: float = eqx.field(default=0.9, converter=_real)
    tol: float | None = eqx.field(default=None, converter=_optional)
    max_newton: int = eqx.field(default=20, converter=_count)
    newton: str = eqx.field(default="auto", converter=_name)
    project_velocities: bool = eqx.field(default=True, converter=_switch)
    max_steps: int = eqx.field(default=10_000_000, converter=_count)


#: The options' class of each method, by name.
OPTIONS: dict[str, type[IntegratorOptions]] = {
    c.method: c for c in (Projection, Baumgarte, Partitioning, GeneralizedAlpha)
}

#: Methods whose step is fixed (``dt`` required, no error control).
FIXED_STEP = tuple(name for name, c in OPTIONS.items() if c.fixed_step)


def check(cls: type[IntegratorOptions], given: dict, ts=None, step: bool = True) -> None:
    """Check the options ``given`` to method ``cls``: known names, values in range, and the
    step of a fixed-step method.

    Args:
        cls: the method's options class.
        given: the options given (a value None: the option's default where that is None).
        ts: (N,) output times [time], for the example step of the message, or None.
        step: whether a fixed-step method's ``dt`` is required among ``given``.

    Raises:
        ModelError: an unknown option (with close matches), a value out of range or of the
            wrong type, or a fixed-step method without ``dt``.
    """
    known = cls.defaults()
    for name, value in given.items():
        if name not in known:
            close = suggestions(name, known)
            hint = f"did you mean {' or '.join(close)}? " if close else ""
            raise ModelError(
                f"unknown option {name!r} of the {cls.method} integrator; {hint}"
                f"its options are {', '.join(known)}",
                name,
            )
        if value is None and known[name] is None:
            continue
        problem = value_problem(name, value)
        if problem:
            raise ModelError(f"{name} {problem}, got {value!r}", name)
    if step and cls.fixed_step and given.get("dt") is None:
        example = "" if ts is None else f", e.g. dt={(ts[-1] - ts[0]) / 2000:.3g}"
        raise ModelError(
            f"the {cls.method} integrator has a fixed step: give dt [time]{example}", "dt"
        )


def check_steps(options: IntegratorOptions, ts) -> None:
    """Refuse, before anything is computed, a run over the output times ``ts`` (N,) [time]
    whose first step cannot advance time or is longer than the span
    (:func:`~._options.first_step_problem`), or at a fixed step ``dt`` that needs more than
    ``max_steps`` steps."""
    ts = np.asarray(ts, dtype=float)
    first = getattr(options, "first_step", None)
    if first is not None and (problem := first_step_problem(float(first), ts)):
        raise ModelError(f"first_step {problem}, got {float(first)!r}", "first_step")
    if options.dt is None:
        return
    dt = float(options.dt)
    steps = int(step_count(ts, dt))
    limit = int(options.max_steps)
    if steps > limit:
        fair = min(limit, 20_000)
        raise ModelError(
            f"dt = {dt:g} needs {steps:,} steps over {ts[-1] - ts[0]:g} [time], more than "
            f"max_steps = {limit:,}: use a larger step (dt = "
            f"{(ts[-1] - ts[0]) / fair:.3g} gives {fair:,} steps) or raise max_steps",
            "dt",
        )


def _method_class(method) -> type[IntegratorOptions]:
    if isinstance(method, type) and issubclass(method, IntegratorOptions):
        raise ModelError(
            f"method is the class {method.__name__}: give an object of it, e.g. "
            f"method={method.__name__}(...)",
            "method",
        )
    if isinstance(method, str) and method in OPTIONS:
        return OPTIONS[method]
    close = difflib.get_close_matches(str(method), OPTIONS, n=2, cutoff=0.5)
    hint = f"did you mean {' or '.join(close)}? " if close else ""
    raise ModelError(
        f"unknown integrator {method!r}; {hint}choose one of {', '.join(OPTIONS)} (or an "
        f"object of {', '.join(c.__name__ for c in OPTIONS.values())})",
        "method",
    )


def as_method(method: str | IntegratorOptions) -> IntegratorOptions:
    """``method`` as its options object: the object itself, or a method's name with its
    default options (a fixed-step method's name alone is refused: it needs ``dt``).

    Raises:
        ModelError: an unknown method, a class instead of an object, or a fixed-step
            method's name.
    """
    if isinstance(method, IntegratorOptions):
        return method
    return _method_class(method)()


def resolve(
    method: str | IntegratorOptions, ts, options: dict
) -> tuple[IntegratorOptions, dict[str, object]]:
    """The typed options of a run, checked, and the options it records.

    Args:
        method: a method's name (its options in ``options``) or an options object (then
            ``options`` gives none: every value None).
        ts: (N,) output times [time].
        options: the run's integrator keywords (``rtol``, ``atol``, ``dt`` and the method's
            own); None values are left out (the default). The tolerances of a fixed-step
            method are ignored (every analysis has them).

    Returns:
        ``(options object, recorded options)``: the options recorded with the run
        (``stats["options"]``) are the tolerances of an adaptive method and the options
        given, for a method name; :meth:`IntegratorOptions.recorded` for an object.

    Raises:
        ModelError: an unknown method or option, a value out of range, a fixed-step method
            without ``dt`` or needing more than ``max_steps`` steps, or an options object
            together with integrator keywords.
    """
    if isinstance(method, IntegratorOptions):
        given = {k: v for k, v in options.items() if v is not None}
        if given:
            name = type(method).__name__
            raise ModelError(
                f"method is a {name} object, which holds the integrator's options: give "
                f"{', '.join(given)} in it ({name}({', '.join(f'{k}=...' for k in given)})), "
                "not as keywords of the run as well",
                ", ".join(given),
            )
        typed, recorded = method, method.recorded()
    else:
        cls = _method_class(method)
        defaults = cls.defaults()
        given = {}
        for name, value in options.items():
            if name in ("rtol", "atol"):
                if cls.fixed_step:
                    continue  # every analysis has them; a fixed step ignores them
                value = defaults[name] if value is None else value  # recorded with the run
            if value is not None:
                given[name] = value
        check(cls, given, np.asarray(ts, dtype=float))
        typed, recorded = cls(**given), given
    check_steps(typed, ts)
    return typed, recorded


__all__ = [
    "FIXED_STEP",
    "OPTIONS",
    "Baumgarte",
    "GeneralizedAlpha",
    "IntegratorOptions",
    "Partitioning",
    "Projection",
    "as_method",
    "check",
    "check_steps",
    "resolve",
]
