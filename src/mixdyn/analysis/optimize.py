"""Design optimization: numbers of a mechanism chosen to minimize a scalar of its run.

:func:`optimize` sets the run up once (:func:`~.gradients.differentiable`, reverse mode),
compiles the objective and its gradient together (``jax.value_and_grad``) and hands them to
scipy's L-BFGS-B within the bounds. Chosen by measurement (``examples/balance_fourbar.py``): 7 ms
and 17 iterations to the closed-form optimum of a four-bar's balancing, where optimistix'
Levenberg-Marquardt took 115 ms (it traces its solve again at each call), and L-BFGS-B takes
bounds.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from .. import paths
from ..errors import ConvergenceError, ModelError
from ..model import Model
from ._setup import Analysis

#: Reductions of a column over the output times, by name (JAX functions of (N,) arrays).
REDUCTIONS = ("max", "min", "absmax", "mean", "rms", "first", "last", "range")


def reduce(name: str, y):
    """``y`` (N,) reduced to a scalar by ``name`` (one of :data:`REDUCTIONS`), in JAX."""
    import jax.numpy as jnp

    return {
        "max": lambda: jnp.max(y),
        "min": lambda: jnp.min(y),
        "absmax": lambda: jnp.max(jnp.abs(y)),
        "mean": lambda: jnp.mean(y),
        "rms": lambda: jnp.sqrt(jnp.mean(y**2)),
        "first": lambda: y[0],
        "last": lambda: y[-1],
        "range": lambda: jnp.max(y) - jnp.min(y),
    }[name]()


@dataclasses.dataclass(frozen=True)
class Optimum:
    """The outcome of :func:`optimize`.

    Attributes:
        params: the varied paths, in order.
        values: (P,) the optimum [model units].
        start: (P,) where the search started.
        bounds: (P, 2) the bounds.
        objective: the objective at the optimum (its unit: that of the reduced quantity).
        objective_start: the objective at the start.
        gradient: (P,) its gradient at the optimum (0 where a bound is not active).
        history: the objective at each iteration, the start first.
        iterations: L-BFGS-B's iterations.
        evaluations: runs made (each with its gradient).
        seconds: wall time of the search [s].
        message: scipy's termination message.
    """

    params: tuple[str, ...]
    values: np.ndarray
    start: np.ndarray
    bounds: np.ndarray
    objective: float
    objective_start: float
    gradient: np.ndarray
    history: np.ndarray
    iterations: int
    evaluations: int
    seconds: float
    message: str

    def __getitem__(self, path: str) -> float:
        return float(self.values[self.params.index(path)])

    def table(self):
        """A pandas DataFrame: a row per number with its bounds, start, optimum, gradient."""
        import pandas as pd

        return pd.DataFrame(
            {
                "parameter": list(self.params),
                "low": self.bounds[:, 0],
                "high": self.bounds[:, 1],
                "start": self.start,
                "optimum": self.values,
                "gradient": self.gradient,
            }
        )


def optimize(
    model: Model,
    t,
    objective: Callable[[dict], object],
    params: Sequence[str],
    bounds: Mapping[str, tuple[float, float]],
    *,
    start: Sequence[float] | None = None,
    analysis: Analysis | str | None = None,
    gtol: float = 1e-10,
    max_iterations: int = 500,
    **kwargs,
) -> Optimum:
    """Minimize ``objective`` of a run of ``model`` over numbers within bounds.

    Args:
        model: the mechanism (its numbers at ``params`` are the default start).
        t: (N,) output times [time].
        objective: ``outputs -> scalar``, a JAX function of the run's outputs
            (:func:`~.gradients.differentiable`'s dict: ``"q"``, ``"qd"``, ``"w"``; for an
            inverse run also every reaction and effort column by name), e.g.
            ``lambda o: jnp.sqrt(jnp.mean(o["motor"] ** 2))``.
        params: paths of the numbers varied (``"spring.stiffness"``, ``"rod.mass"``).
        bounds: path -> ``(low, high)`` for every varied number.
        start: (P,) the first guess (default: the model's numbers, within the bounds).
        analysis: the analysis value (:mod:`mixdyn.analyses`): ``Forward(...)`` (default:
            ``Forward()``), ``Mixed(...)`` or ``Inverse(...)``, e.g.
            ``analysis=md.analyses.Inverse()``.
        gtol: L-BFGS-B's tolerance on the projected gradient.
        max_iterations: iterations at most.
        **kwargs: deprecated (a DeprecationWarning names the value to give instead): the
            analysis' keywords (``rtol``, ``method``, ``q0``, ``hold``...) with ``analysis``
            an analysis' name (``"forward"``, ``"mixed"``, ``"inverse"``).

    Returns:
        An :class:`Optimum`.

    Raises:
        ModelError: a bad path, bound or start, or a bound the number cannot take (a model
            built with it is refused: a negative mass), before any search.
        ConvergenceError: a run failed during the search (its objective not finite), or the
            search did not converge.
    """
    import jax
    import jax.numpy as jnp
    from scipy.optimize import minimize

    from ._keywords import study_analysis
    from .gradients import differentiable

    params = list(params)
    value, _ = study_analysis("md.optimize", analysis, t, kwargs)
    f, theta0 = differentiable(model, t, params, analysis=value)
    lo_hi = np.zeros((len(params), 2))
    for k, p in enumerate(params):
        if p not in bounds:
            raise ModelError("every varied number needs bounds (low, high)", f"bounds of {p!r}")
        lo, hi = (float(v) for v in bounds[p])
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ModelError(f"bounds (low, high) with low < high, got {bounds[p]!r}", p)
        lo_hi[k] = lo, hi
    extra = set(bounds) - set(params)
    if extra:
        raise ModelError(f"bounds of numbers not varied: {', '.join(sorted(extra))}", "bounds")
    for p, ends in zip(params, lo_hi, strict=True):  # values a model may take, or refused
        paths.check_bounds(model, p, ends)
    x0 = np.clip(theta0, lo_hi[:, 0], lo_hi[:, 1]) if start is None else np.asarray(start, float)
    if x0.shape != theta0.shape or not np.all((x0 >= lo_hi[:, 0]) & (x0 <= lo_hi[:, 1])):
        raise ModelError(f"start must be {len(params)} numbers within the bounds", "start")

    value_and_grad = jax.jit(jax.value_and_grad(lambda th: objective(f(th))))
    history, count, last = [], [0], {}

    def fun(x):
        v, g = value_and_grad(jnp.asarray(x))
        count[0] += 1
        v = float(v)
        last["x"], last["v"] = np.array(x, dtype=float), v
        if not np.isfinite(v):
            raise ConvergenceError(
                f"the objective is not finite at {dict(zip(params, x.tolist(), strict=True))} "
                "(the run failed there): narrow the bounds"
            )
        return v, np.asarray(g, dtype=float)

    started = time.perf_counter()
    v0, _ = fun(x0)
    history.append(v0)
    sol = minimize(
        fun,
        x0,
        jac=True,
        method="L-BFGS-B",
        bounds=[tuple(b) for b in lo_hi],
        callback=lambda x: history.append(last["v"] if np.array_equal(x, last["x"]) else fun(x)[0]),
        options={"gtol": gtol, "ftol": 1e-15, "maxiter": max_iterations},
    )
    seconds = time.perf_counter() - started
    if not sol.success:
        raise ConvergenceError(f"the optimization did not converge: {sol.message}")
    v, g = value_and_grad(jnp.asarray(sol.x))
    return Optimum(
        params=tuple(params),
        values=np.asarray(sol.x),
        start=x0,
        bounds=lo_hi,
        objective=float(v),
        objective_start=v0,
        gradient=np.asarray(g),
        history=np.asarray(history),
        iterations=int(sol.nit),
        evaluations=count[0],
        seconds=seconds,
        message=str(sol.message),
    )


__all__ = ["REDUCTIONS", "Optimum", "optimize", "reduce"]
