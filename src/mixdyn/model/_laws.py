"""Laws of time: ``f(t)`` with exact derivatives (by automatic differentiation).

A law is a scalar function of time [model time unit] whose value is in the unit of whatever it
drives (a length, an angle, a force...). Every law is a JAX-traceable ``eqx.Module``; its first
and second derivatives come from ``jax.jvp`` and are exact up to rounding.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._arrays import as_f64
from ..errors import ModelError
from ._validate import finite


def _f64(x) -> jax.Array:
    return as_f64(x)


class Law(eqx.Module):
    """Abstract scalar function of time."""

    #: Smooth by construction (value and every derivative continuous): not sampled for
    #: jumps (:mod:`mixdyn.model._smoothness`) over an interval.
    smooth: ClassVar[bool] = False

    def smooth_to(self, order: int) -> bool:
        """Whether the law and its derivatives up to ``order`` (1: the slope, 2: the second
        derivative) are continuous everywhere by its form, so that they need not be sampled
        for jumps; by default :attr:`smooth`."""
        return bool(self.smooth)

    @abc.abstractmethod
    def __call__(self, t: jax.Array) -> jax.Array:
        """Value at time ``t`` (scalar)."""

    def derivatives(self, t) -> tuple[jax.Array, jax.Array, jax.Array]:
        """``(f, f', f'')`` at time ``t``, exact (forward-mode AD)."""
        t = _f64(t)

        def first(s):
            return jax.jvp(self, (s,), (jnp.ones_like(s),))

        (f, fd), (_, fdd) = jax.jvp(first, (t,), (jnp.ones_like(t),))
        return f, fd, fdd


class Constant(Law):
    """``f(t) = value``."""

    smooth: ClassVar[bool] = True

    value: jax.Array

    def __init__(self, value):
        finite(value, "the value of a Constant law")
        self.value = _f64(value)

    def __call__(self, t):
        return self.value + 0.0 * t


class Polynomial(Law):
    """``f(t) = sum_k coeffs[k] * t**k`` (coefficients in ascending powers)."""

    smooth: ClassVar[bool] = True

    coeffs: jax.Array

    def __init__(self, coeffs):
        finite(coeffs, "the coefficients of a Polynomial law")
        self.coeffs = _f64(np.atleast_1d(coeffs))

    def __call__(self, t):
        return jnp.polyval(self.coeffs[::-1], t)


def Ramp(start=0.0, rate=1.0) -> Polynomial:
    """``f(t) = start + rate * t``: a constant-rate motion (a ramp)."""
    return Polynomial([start, rate])


class Harmonic(Law):
    """``f(t) = offset + amplitude * sin(omega * t + phase)``, ``omega`` in rad per time unit."""

    smooth: ClassVar[bool] = True

    amplitude: jax.Array
    omega: jax.Array
    phase: jax.Array
    offset: jax.Array

    def __init__(self, amplitude, omega, phase=0.0, offset=0.0):
        values = {"amplitude": amplitude, "omega": omega, "phase": phase, "offset": offset}
        for name, value in values.items():  # one by one: a sweep's check stacks one of them
            finite(value, f"the {name} of a Harmonic")
        self.amplitude = _f64(amplitude)
        self.omega = _f64(omega)
        self.phase = _f64(phase)
        self.offset = _f64(offset)

    def __call__(self, t):
        return self.offset + self.amplitude * jnp.sin(self.omega * t + self.phase)


class PiecewisePolynomial(Law):
    """Piecewise polynomial ``f(t) = sum_k c[k, i] (t - breaks[i])**(K-k)`` on interval ``i``.

    Outside ``[breaks[0], breaks[-1]]`` the first or last piece is extended.

    Attributes:
        breaks: (n+1,) increasing break points [time].
        coeffs: (K+1, n) coefficients, highest power first (scipy ``PPoly`` layout).
    """

    breaks: jax.Array
    coeffs: jax.Array

    def __init__(self, breaks, coeffs):
        finite(breaks, "the breaks of a PiecewisePolynomial")
        finite(coeffs, "the coefficients of a PiecewisePolynomial")
        self.breaks = _f64(breaks)
        self.coeffs = _f64(coeffs)

    def __call__(self, t):
        n = self.coeffs.shape[1]
        i = jnp.clip(jnp.searchsorted(self.breaks, t, side="right") - 1, 0, n - 1)
        dt = t - self.breaks[i]
        return jnp.polyval(self.coeffs[:, i], dt)


def Spline(t, y, kind: str = "cubic", bc_type="not-a-knot") -> PiecewisePolynomial:
    """Interpolating spline through samples ``(t, y)``.

    Args:
        t: (n,) strictly increasing sample times [time].
        y: (n,) sample values.
        kind: ``"cubic"`` (C2) or ``"quintic"`` (C4).
        bc_type: end conditions of the cubic spline (scipy's ``CubicSpline``), e.g.
            ``"not-a-knot"``, ``"natural"``, ``"clamped"``.
    """
    from scipy.interpolate import CubicSpline, PPoly, make_interp_spline

    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size < 2:
        raise ModelError("spline samples: t and y must be 1-D arrays of equal length >= 2")
    if np.any(np.diff(t) <= 0):
        raise ModelError("spline samples: times must be strictly increasing")
    if kind == "cubic":
        pp = CubicSpline(t, y, bc_type=bc_type if t.size > 3 else "natural")
        return PiecewisePolynomial(pp.x, pp.c)
    if kind == "quintic":
        if t.size < 6:
            raise ModelError("a quintic spline needs at least 6 samples")
        pp = PPoly.from_spline(make_interp_spline(t, y, k=5))
        # Drop the zero-length pieces at the ends that from_spline adds.
        keep = np.diff(pp.x) > 0
        return PiecewisePolynomial(np.concatenate([pp.x[:-1][keep], [pp.x[-1]]]), pp.c[:, keep])
    raise ModelError(f"unknown spline kind {kind!r}; use 'cubic' or 'quintic'")


def QuinticHermite(t, y, yd, ydd) -> PiecewisePolynomial:
    """Quintic Hermite interpolation of values, first and second derivatives at samples.

    Reproduces ``y``, ``y'`` and ``y''`` at every sample; C2 everywhere. Used to prescribe a
    motion taken from an earlier result (positions, velocities and accelerations).

    Args:
        t: (n,) strictly increasing sample times [time].
        y, yd, ydd: (n,) values, first and second time derivatives at the samples.
    """
    t, y, yd, ydd = (np.asarray(a, dtype=float) for a in (t, y, yd, ydd))
    if np.any(np.diff(t) <= 0):
        raise ModelError("Hermite samples: times must be strictly increasing")
    h = np.diff(t)
    y0, y1, v0, v1, a0, a1 = y[:-1], y[1:], yd[:-1], yd[1:], ydd[:-1], ydd[1:]
    # p(s) = c0 + c1 s + c2 s^2 + c3 s^3 + c4 s^4 + c5 s^5, s = tau - t_i in [0, h]
    c0, c1, c2 = y0, v0, a0 / 2
    d = y1 - (c0 + c1 * h + c2 * h**2)
    dv = v1 - (c1 + 2 * c2 * h)
    da = a1 - 2 * c2
    c3 = (10 * d - 4 * dv * h + 0.5 * da * h**2) / h**3
    c4 = (-15 * d + 7 * dv * h - da * h**2) / h**4
    c5 = (6 * d - 3 * dv * h + 0.5 * da * h**2) / h**5
    return PiecewisePolynomial(t, np.stack([c5, c4, c3, c2, c1, c0]))


class FunctionLaw(Law):
    """A law given by a JAX-traceable Python callable ``fn(t) -> scalar``."""

    fn: Callable = eqx.field(static=True)

    def __call__(self, t):
        return self.fn(t)


def as_law(value) -> Law:
    """Coerce a number, a callable of ``t`` or a law into a :class:`Law`."""
    if isinstance(value, Law):
        return value
    if callable(value):
        return FunctionLaw(value)
    return Constant(value)
