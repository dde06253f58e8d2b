"""What every linkage of synthesis shares: a crank turning about a ground pivot, a connecting
link (coupler) pinned to it that carries the coupler point, and a closure that fixes the
coupler's angle on a fixed assembly branch.

A :class:`Linkage` is an immutable PyTree of numbers (every field may carry a batch). Its
numbers (:attr:`Linkage.NAMES`) end with the crank's ground pivot ``O2 = (x0, y0)`` and the
angle ``theta0`` the input angle counts from; the numbers before them are lengths (the search
scales them by the targets' size). The crank ``r2`` turns about ``O2`` by the input angle
``theta2`` (its absolute angle ``phi2 = theta0 + theta2``); the coupler's angle ``phi3``
comes from the subclass's closed-form assembly (:meth:`Linkage.coupler_angle`), and the
coupler point is ``C = A + R(phi3) (rcx, rcy)`` in the coupler's frame (x from the crank pin
``A`` towards the coupler's other pin ``B``). A linkage with a grounded output of its own says
what it is (:meth:`Linkage.output`, :attr:`Linkage.OUTPUT`): the quantity a function
generation follows.

Final subclasses: :class:`~._fourbar.FourBar`, :class:`~._slidercrank.SliderCrank`, and the
six-bars of :mod:`._sixbar` (:class:`~._stephenson.StephensonIII`, :class:`~._watt.WattI`,
:class:`~._watt.WattII`), whose coupler is the link that carries the coupler point.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

#: The least ``|det|`` an implicit solve divides by (at a toggle position), as a fraction of
#: its scale.
TOGGLE_GUARD = 1e-9


def guarded(x, least):
    """``x`` moved away from zero to at least ``least`` in magnitude (its sign kept, + at 0):
    the denominator of an implicit solve at a toggle position."""
    return jnp.where(jnp.abs(x) < least, jnp.where(x < 0, -least, least), x)


class Linkage(eqx.Module):
    """A crank-driven linkage of synthesis (abstract).

    Class attributes:
        NAMES: its numbers, in the order of :meth:`vector`; the last three are ``x0``, ``y0``
            (the crank's ground pivot [length]) and ``theta0`` [rad]; the others lengths.
        LENGTHS: the numbers that are positive lengths (bounded by default).
        KIND: its name in tasks and model files (``"four_bar"``, ``"slider_crank"``).
        TITLE: its name in messages (``"four-bar"``, ``"slider-crank"``).
        BRANCHES: the values of ``branch`` the search spreads its starts over (one assembly
            branch each; a six-bar's code both loops', :mod:`._sixbar`).
        OUTPUT: what :meth:`output` gives, the quantity a function generation follows:
            ``"angle"`` [rad], ``"length"`` [length], or None where the linkage has no
            grounded output of its own (:meth:`output` then refuses).
    """

    NAMES: ClassVar[tuple[str, ...]]
    LENGTHS: ClassVar[tuple[str, ...]]
    KIND: ClassVar[str]
    TITLE: ClassVar[str]
    BRANCHES: ClassVar[tuple[float, ...]] = (1.0, -1.0)
    OUTPUT: ClassVar[str | None] = None

    @classmethod
    def from_vector(cls, v, branch):
        """A linkage from ``v`` (..., len(NAMES)) in the order of :attr:`NAMES` and
        ``branch`` (...)."""
        v = jnp.asarray(v, dtype=jnp.float64)
        return cls(*(v[..., k] for k in range(len(cls.NAMES))), jnp.asarray(branch, jnp.float64))

    def vector(self) -> jax.Array:
        """(..., len(NAMES)) the numbers in the order of :attr:`NAMES`."""
        return jnp.stack([getattr(self, n) for n in self.NAMES], axis=-1)

    def crank_pivot(self) -> jax.Array:
        """``O2`` (2,) [length]."""
        return jnp.stack([self.x0, self.y0])

    def crank_pin(self, theta2) -> jax.Array:
        """``A`` (2,) at the input angle ``theta2`` [rad] (from ``theta0``) [length]."""
        phi2 = self.theta0 + theta2
        return self.crank_pivot() + self.r2 * jnp.stack([jnp.cos(phi2), jnp.sin(phi2)])

    @abc.abstractmethod
    def coupler_angle(self, theta2) -> jax.Array:
        """The coupler's absolute angle ``phi3`` [rad] at ``theta2`` [rad] (scalar), on the
        linkage's branch, differentiable by the closure's implicit rule."""

    @abc.abstractmethod
    def transmission_cosine(self, theta2) -> jax.Array:
        """``cos mu`` of the transmission angle at ``theta2`` [rad]: within ±1 where the loop
        closes, beyond where it does not (smooth in every number)."""

    def output(self, theta2) -> jax.Array:
        """() the output at ``theta2`` [rad] (scalar), the quantity a function generation
        follows (:attr:`OUTPUT` says whether an angle [rad] or a length [length]): a link
        pivoted at the ground, its angle counted from the ground link, or a slider's position
        along its slide; differentiable implicitly.

        Raises:
            NotImplementedError: a linkage without a grounded output of its own
                (:attr:`OUTPUT` None).
        """
        raise NotImplementedError(f"a {self.TITLE} has no grounded output of its own")

    def coupler_point(self, theta2) -> jax.Array:
        """The coupler point ``C`` (2,) [length] at ``theta2`` [rad]."""
        a = self.crank_pin(theta2)
        phi3 = self.coupler_angle(theta2)
        c, s = jnp.cos(phi3), jnp.sin(phi3)
        return a + jnp.stack([c * self.rcx - s * self.rcy, s * self.rcx + c * self.rcy])


def coupler_point(lk: Linkage, theta2) -> jax.Array:
    """The coupler point ``C`` (2,) [length] of ``lk`` at the input angle ``theta2`` [rad]."""
    return lk.coupler_point(theta2)


def transmission_cosine(lk: Linkage, theta2) -> jax.Array:
    """``cos mu`` of ``lk``'s transmission angle ``mu`` at ``theta2`` [rad] (each linkage
    says its definition); the loop closes where ``|cos mu| <= 1``, and a bound
    ``mu >= mu_min`` is ``|cos mu| <= cos mu_min``.

    Returns:
        () the cosine (dimensionless; beyond ±1 where the loop does not close).
    """
    return lk.transmission_cosine(theta2)


@jax.jit
def coupler_curve(lk: Linkage, theta2) -> jax.Array:
    """``C`` at each input angle: (K, 2) [length] for ``theta2`` (K,) [rad] (compiled once
    per linkage type and shape)."""
    return jax.vmap(lk.coupler_point)(jnp.asarray(theta2, dtype=jnp.float64))


__all__ = [
    "TOGGLE_GUARD",
    "Linkage",
    "coupler_curve",
    "coupler_point",
    "guarded",
    "transmission_cosine",
]
