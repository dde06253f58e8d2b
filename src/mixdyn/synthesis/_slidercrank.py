"""The offset slider-crank of synthesis: its numbers, its assembly and its transmission angle.

Notation (as :mod:`._fourbar`'s where the links agree): the crank ``r2`` turns about the
ground pivot ``O2 = (x0, y0)`` by the input angle ``theta2``, measured from the slide's
direction ``d = (cos theta0, sin theta0)`` (its absolute angle ``phi2 = theta0 + theta2``);
the slide is the line through ``P0 = O2 + e n``, ``n = (-sin theta0, cos theta0)`` (``e``
the signed offset: the slide's distance from ``O2``, positive on ``n``'s side); the
connecting rod ``r3`` from the crank pin ``A`` to the slider's pin ``B = P0 + s d``, ``s``
the slider's position along the slide from ``P0``; the coupler point ``C = A + R(phi3) (rcx,
rcy)`` in the rod's frame (x from ``A`` towards ``B``).

Assembly closes ``A + r3 e^{i phi3} = P0 + s d`` in closed form (a circle and a line):
with ``h = (A - P0) . n`` the crank pin's height above the slide,
``s = (A - P0) . d + branch sqrt(r3^2 - h^2)``; ``branch`` (+1 or -1) says whether ``B``
lies ahead of ``A`` along ``d`` or behind it, the same at every input angle. The derivatives
of ``phi3, s`` are the closure equations' (implicit differentiation, Cramer's rule on
``[r3 n3, -d] (dphi3, ds) = -(dA + dr3 e3 - dP0 - s dd)``, ``det = r3 cos(phi3 - theta0)``),
not the square root's; the solve is guarded where the rod stands perpendicular to the slide.

The transmission angle ``mu`` is the angle between the connecting rod and the slide's
normal ``n`` (the four-bar's, with the slider a rocker of infinite length normal to the
slide): 90 degrees with the rod along the slide, 0 with the rod across it (a dead point);
the angle between the rod and the slide itself is ``90 deg - mu``. ``cos mu = h / r3`` is
smooth in every number and beyond ±1 where the rod cannot reach the slide; there the closed
form returns the nearest configuration (``B`` at the foot of ``A`` on the slide), so that a
search adds a finite penalty instead of a NaN.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from ._linkage import TOGGLE_GUARD, Linkage, guarded

#: Names of the numbers of a slider-crank, in the order of :meth:`SliderCrank.vector`.
SLIDER_NAMES = ("r2", "r3", "e", "rcx", "rcy", "x0", "y0", "theta0")


class SliderCrank(Linkage):
    """An offset slider-crank's dimensions and placement [length, rad]; every field may carry
    a batch.

    Attributes:
        r2, r3: crank and connecting rod lengths [length].
        e: the slide's offset from the crank's pivot along ``n`` (signed) [length].
        rcx, rcy: the coupler point in the rod's frame (x along ``A -> B``) [length].
        x0, y0: the crank's ground pivot ``O2`` [length].
        theta0: the slide's direction angle [rad]; the input angle counts from it.
        branch: +1 or -1, the assembly branch (``B`` ahead of ``A`` along the slide's
            direction, or behind it).
    """

    NAMES: ClassVar[tuple[str, ...]] = SLIDER_NAMES
    LENGTHS: ClassVar[tuple[str, ...]] = ("r2", "r3")
    KIND: ClassVar[str] = "slider_crank"
    TITLE: ClassVar[str] = "slider-crank"
    OUTPUT: ClassVar[str | None] = "length"

    r2: jax.Array
    r3: jax.Array
    e: jax.Array
    rcx: jax.Array
    rcy: jax.Array
    x0: jax.Array
    y0: jax.Array
    theta0: jax.Array
    branch: jax.Array

    def slide(self) -> tuple[jax.Array, jax.Array]:
        """The slide's point ``P0`` nearest ``O2`` and its direction ``d``, each (2,)."""
        d = jnp.stack([jnp.cos(self.theta0), jnp.sin(self.theta0)])
        n = jnp.stack([-d[1], d[0]])
        return self.crank_pivot() + self.e * n, d

    def coupler_angle(self, theta2) -> jax.Array:
        """The rod's angle ``phi3`` [rad] at ``theta2`` (:func:`rod_and_slider`)."""
        return rod_and_slider(self, theta2)[0]

    def output(self, theta2) -> jax.Array:
        """The slider's position ``s`` [length] along the slide from ``P0`` at ``theta2``
        (:func:`rod_and_slider`)."""
        return rod_and_slider(self, theta2)[1]

    def transmission_cosine(self, theta2) -> jax.Array:
        """``cos mu = h / r3``: ``mu`` between the rod and the slide's normal, ``h`` the crank
        pin's height above the slide (module docstring); beyond ±1 where the rod cannot
        reach the slide."""
        p0, d = self.slide()
        w = self.crank_pin(theta2) - p0
        return (d[0] * w[1] - d[1] * w[0]) / self.r3


@jax.custom_jvp
def _slide_dyad(a, p0, theta0, r3, branch):
    """``(phi3, s)``: the angle of ``A -> B`` and ``B``'s position along the slide through
    ``p0`` at ``theta0``, ``|AB| = r3``, on ``branch`` (closed form; the nearest
    configuration where the rod cannot reach the slide)."""
    d = jnp.stack([jnp.cos(theta0), jnp.sin(theta0)])
    w = a - p0
    h = d[0] * w[1] - d[1] * w[0]
    reach = jnp.sqrt(jnp.maximum(r3**2 - h**2, 0.0))
    s = w[0] * d[0] + w[1] * d[1] + branch * reach
    b = p0 + s * d
    return jnp.arctan2(b[1] - a[1], b[0] - a[0]), s


@_slide_dyad.defjvp
def _slide_dyad_jvp(primals, tangents):
    a, p0, theta0, r3, branch = primals
    da, dp0, dtheta0, dr3, _ = tangents
    phi3, s = _slide_dyad(a, p0, theta0, r3, branch)
    d = jnp.stack([jnp.cos(theta0), jnp.sin(theta0)])
    n = jnp.stack([-d[1], d[0]])
    e3 = jnp.stack([jnp.cos(phi3), jnp.sin(phi3)])
    # Phi = a + r3 e3 - p0 - s d = 0;  Phi_(phi3, s) = [r3 n3, -d],  dd = n dtheta0.
    rhs = -(da + dr3 * e3 - dp0 - s * n * dtheta0)
    det = r3 * guarded(jnp.cos(phi3 - theta0), TOGGLE_GUARD)
    dphi3 = (rhs[0] * n[0] + rhs[1] * n[1]) / det
    ds = -r3 * (e3[0] * rhs[0] + e3[1] * rhs[1]) / det
    return (phi3, s), (dphi3, ds)


def rod_and_slider(sc: SliderCrank, theta2) -> tuple[jax.Array, jax.Array]:
    """The rod's absolute angle ``phi3`` [rad] and the slider's position ``s`` along the
    slide from ``P0`` [length] at ``theta2`` [rad] (scalars; ``jax.vmap`` for many), on the
    slider-crank's branch; differentiable implicitly."""
    p0, _ = sc.slide()
    return _slide_dyad(sc.crank_pin(theta2), p0, sc.theta0, sc.r3, sc.branch)


__all__ = ["SLIDER_NAMES", "SliderCrank", "rod_and_slider"]
