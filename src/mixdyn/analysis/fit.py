"""Identification: numbers of a mechanism fitted to a measured motion (weighted least squares).

:func:`fit` sets the run of an analysis value up once
(:func:`~.gradients.differentiable`, forward-mode derivatives), then minimizes
``sum_k ((y_k(theta) - measured_k) / sigma_k)**2`` over the measured columns (body
coordinates ``slider.x``, ``crank.phi``, or velocities ``slider.vx``, ``crank.omega``) at the
output times, with scipy's trust-region least squares and the
Jacobian ``d y / d theta`` from ``jax.jacfwd`` through the integrator. The covariance of the
estimate is ``(J^T J)^-1`` of the weighted residuals at the optimum, its square-root diagonal
the standard deviations; with the right noise the reduced chi-square is near 1.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence

import numpy as np

from .. import paths
from ..errors import ConvergenceError, ModelError
from ..model import Model
from ._setup import Analysis

#: Velocity column suffixes and the coordinate each is the rate of.
_RATES = {"vx": "x", "vy": "y", "omega": "phi"}


@dataclasses.dataclass(frozen=True)
class Fit:
    """The outcome of :func:`fit`.

    Attributes:
        params: the fitted paths, in order.
        values: (P,) the estimates [model units].
        deviations: (P,) their standard deviations (noise-implied) [model units].
        covariance: (P, P) the estimate's covariance.
        start: (P,) where the fit started.
        chi2: the reduced chi-square ``2 cost / (n - P)`` (about 1 when the model explains the
            measurements to within the given noise).
        residuals: (n,) the weighted residuals at the optimum (dimensionless).
        evaluations: runs made (with their Jacobians).
        seconds: wall time of the fit [s].
        message: scipy's termination message.
    """

    params: tuple[str, ...]
    values: np.ndarray
    deviations: np.ndarray
    covariance: np.ndarray
    start: np.ndarray
    chi2: float
    residuals: np.ndarray
    evaluations: int
    seconds: float
    message: str

    def __getitem__(self, path: str) -> float:
        """The estimate of ``path``."""
        return float(self.values[self.params.index(path)])

    def table(self):
        """A pandas DataFrame: a row per number with its start, estimate and deviation."""
        import pandas as pd

        return pd.DataFrame(
            {
                "parameter": list(self.params),
                "start": self.start,
                "estimate": self.values,
                "std_dev": self.deviations,
            }
        )


def _selectors(model: Model, measured: Mapping[str, Sequence[float]], n: int):
    """``[(column, "q" or "qd", index, (N,) values)]`` of the measured columns."""
    out = []
    for col, vals in measured.items():
        body, _, suffix = col.rpartition(".")
        which, coord = ("qd", _RATES[suffix]) if suffix in _RATES else ("q", suffix)
        try:
            k = model.coordinate_index(f"{body}.{coord}")
        except ModelError as e:
            raise ModelError(
                f"{e.message}; a measured column is a body coordinate (slider.x, crank.phi) "
                "or velocity (slider.vx, crank.omega)",
                f"measured {col!r}",
            ) from None
        v = np.asarray(vals, dtype=float)
        if v.shape != (n,):
            raise ModelError(f"{v.shape} values, one per output time ({n}) expected", col)
        if not np.all(np.isfinite(v)):
            raise ModelError("a measured value is not finite", col)
        out.append((col, which, k, v))
    return out


#: The smallest noise of a measured column relative to its largest value: float64's
#: resolution (2.2e-16). Below it the noise is finer than the rounding of the values
#: themselves, and the weighted residuals' squares may overflow.
RESOLUTION = float(np.finfo(np.float64).eps)


def check_noise(column: str, values, sigma: float, row=lambda k: f"row {k}") -> None:
    """Refuse a noise that float64 cannot tell from the rounding of the measured values.

    Args:
        column: the measured column, for the message.
        values: (N,) its finite measured values [model units].
        sigma: its noise (standard deviation) [model units], > 0.
        row: the name of a row from its index, for the message.

    Raises:
        ModelError: ``sigma`` below :data:`RESOLUTION` times the largest ``|value|``, naming
            that value's row.
    """
    v = np.abs(np.asarray(values, dtype=float))
    k = int(np.argmax(v)) if v.size else 0
    top = float(v[k]) if v.size else 0.0
    if top * RESOLUTION > sigma:
        raise ModelError(
            f"the noise {sigma:.3g} is finer than float64 resolves the value {top:.3g} in "
            f"{row(k)} (to {top * RESOLUTION:.3g}): the noise cannot be told from rounding; "
            "check the noise's unit and that value",
            f"noise of {column!r}",
        )


def fit(
    model: Model,
    t,
    measured: Mapping[str, Sequence[float]],
    params: Sequence[str],
    *,
    noise: Mapping[str, float] | float = 1.0,
    start: Sequence[float] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    analysis: Analysis | str | None = None,
    xtol: float = 1e-10,
    max_evaluations: int = 200,
    **kwargs,
) -> Fit:
    """Fit numbers of ``model`` so that its run reproduces a measured motion.

    Args:
        model: the mechanism (its numbers at ``params`` are the default start).
        t: (N,) the measurement times [time]: the run's output times.
        measured: column -> (N,) measured values [model units]: body coordinates
            (``"slider.x"``, ``"crank.phi"``) or velocities (``"slider.vx"``, ``"crank.omega"``).
        params: paths of the numbers to fit (``"slider.mass"``, ``"damper.damping"``: numbers
            of bodies and force elements, as :func:`~.gradients.differentiable` takes).
        noise: the standard deviation of each measured column [model units] (one number for
            all), the weights of the residuals and the scale of the deviations.
        start: (P,) the first guess (default: the model's numbers).
        bounds: path -> ``(low, high)``: the fit stays within (default: above the least
            value the number may take, :func:`mixdyn.paths.lower_limit`, e.g. a mass >= 0;
            else unbounded).
        analysis: the analysis value (:mod:`mixdyn.analyses`): ``Forward(...)`` (default:
            ``Forward()``) or ``Mixed(...)``, e.g.
            ``analysis=md.analyses.Forward(method=md.Projection(rtol=1e-10))``.
        xtol: relative change of the numbers at which the fit stops.
        max_evaluations: runs at most.
        **kwargs: deprecated (a DeprecationWarning names the value to give instead): the
            analysis' keywords (``rtol``, ``atol``, ``method``, ``q0``, ``hold``...) with
            ``analysis`` an analysis' name (``"forward"``, ``"mixed"``).

    Returns:
        A :class:`Fit`.

    Raises:
        ModelError: a bad column, path, bound or start, a bound or start the number cannot
            take (a model built with it is refused: a negative mass), or a noise finer than
            float64 resolves the measured values (:func:`check_noise`), before any search.
        ConvergenceError: the fit did not converge, or its Jacobian is rank-deficient (the
            measurements do not determine the numbers: name fewer, or measure more).
    """
    import jax
    import jax.numpy as jnp
    from scipy.optimize import least_squares

    from ._keywords import study_analysis
    from .gradients import differentiable

    ts = np.asarray(t, dtype=float)
    params = list(params)
    if not measured:
        raise ModelError("nothing measured: give measured={'slider.x': [...], ...}", "measured")
    sel = _selectors(model, measured, len(ts))
    measured_values = {col: v for col, _, _, v in sel}
    sigma = {}
    for col, *_ in sel:
        s = noise.get(col, None) if isinstance(noise, Mapping) else noise
        if s is None or not np.isfinite(float(s)) or float(s) <= 0:
            raise ModelError(f"the noise must be a number > 0, got {s!r}", f"noise of {col!r}")
        check_noise(col, measured_values[col], float(s))
        sigma[col] = float(s)
    value, _ = study_analysis("md.fit", analysis, ts, kwargs)
    f, theta0 = differentiable(model, ts, params, analysis=value, derivatives="forward")
    x0 = theta0 if start is None else np.asarray(start, dtype=float)
    if x0.shape != theta0.shape or not np.all(np.isfinite(x0)):
        raise ModelError(f"start must be {len(params)} finite numbers, got {start!r}", "start")
    lo = np.full(len(params), -np.inf)
    hi = np.full(len(params), np.inf)
    for path, (a, b) in (bounds or {}).items():
        if path not in params:
            raise ModelError(f"{path!r} is not fitted; fitted: {', '.join(params)}", "bounds")
        k = params.index(path)
        lo[k], hi[k] = float(a), float(b)
        if not lo[k] < hi[k]:
            raise ModelError(f"a bound (low, high) with low < high, got {(a, b)!r}", path)
        if not lo[k] <= x0[k] <= hi[k]:
            raise ModelError(f"the start {x0[k]:g} is outside its bounds {(a, b)!r}", path)
        paths.check_bounds(model, path, (lo[k], hi[k]))  # values a model may take
    if start is not None and len(x0) == len(params):  # a start a model may take
        paths.check(model, {p: x0[k : k + 1] for k, p in enumerate(params)}, lambda i: "the start")
    for k, p in enumerate(params):  # a number without bounds searched within its range
        if p not in (bounds or {}):
            lo[k] = paths.lower_limit(model, p)

    def residuals(theta):
        out = f(theta)
        return jnp.concatenate([(out[which][:, k] - v) / sigma[col] for col, which, k, v in sel])

    res, jac = jax.jit(residuals), jax.jit(jax.jacfwd(residuals))
    started = time.perf_counter()
    try:
        sol = least_squares(
            lambda th: np.asarray(res(th)),
            x0,
            jac=lambda th: np.asarray(jac(th)),
            bounds=(lo, hi),
            x_scale="jac",
            xtol=xtol,
            max_nfev=max_evaluations,
        )
    except ValueError as e:  # scipy refuses residuals or a Jacobian that are not finite
        raise ConvergenceError(
            f"the fit's weighted residuals or their derivatives are not finite ({e}): a run "
            "failed on the way, or a noise is too small for the motion; give a closer start, "
            "bounds or larger noises"
        ) from None
    seconds = time.perf_counter() - started
    if not sol.success or not np.all(np.isfinite(sol.x)) or not np.all(np.isfinite(sol.fun)):
        raise ConvergenceError(
            f"the fit did not converge ({sol.message}); a run failed on the way, or the start "
            "is too far: give a closer start or bounds"
        )
    J = np.asarray(jac(sol.x))
    n, p = J.shape
    scale = np.linalg.norm(J, axis=0)
    scale[scale == 0] = 1.0
    _, s, vt = np.linalg.svd(J / scale)  # columns scaled: the numbers' units do not matter
    if s[-1] <= 1e-8 * s[0]:
        null = np.abs(vt[-1])
        loose = [p for p, v in zip(params, null, strict=True) if v >= 0.1 * null.max()]
        raise ConvergenceError(
            f"the measurements do not determine {', '.join(loose)} (the scaled Jacobian's "
            f"condition is {s[0] / max(s[-1], 1e-300):.1e}): fit fewer numbers or measure "
            "more columns"
        )
    cov = np.linalg.inv(J.T @ J)
    return Fit(
        params=tuple(params),
        values=np.asarray(sol.x),
        deviations=np.sqrt(np.diag(cov)),
        covariance=cov,
        start=x0,
        chi2=float(np.sum(sol.fun**2) / max(n - p, 1)),
        residuals=np.asarray(sol.fun),
        evaluations=int(sol.nfev),
        seconds=seconds,
        message=str(sol.message),
    )


__all__ = ["Fit", "fit"]
