"""The planar four-bar of synthesis: its numbers, its assembly and its coupler curve.

Notation (Cabrera, Simon and Prado, 2002, and most of the synthesis literature): the ground
pivot ``O2 = (x0, y0)``, the ground link of length ``r1`` at the angle ``theta0``, so that
``O4 = O2 + r1 e^{i theta0}``; the crank ``r2`` turns about ``O2`` by the input angle
``theta2``, measured from the ground link (its absolute angle ``phi2 = theta0 + theta2``);
the coupler ``r3`` from ``A`` to ``B``, the rocker ``r4`` from ``O4`` to ``B``; the coupler
point ``C = A + R(phi3) (rcx, rcy)`` in the coupler's frame (x from ``A`` towards ``B``).

Assembly closes the loop ``A + r3 e^{i phi3} = O4 + r4 e^{i phi4}`` in closed form (two
circles' intersection); ``branch`` (+1 or -1) picks the side of the line ``A O4`` on which
``B`` lies, the same at every input angle, so that a candidate never jumps between the two
assembly branches. The derivatives of ``phi3, phi4`` are those of the closure equations
(implicit differentiation: ``Phi_phi dphi = -Phi_p dp``), not those of the closed form's
square root, so they are exact wherever the loop closes with a nonzero transmission angle
and finite everywhere (the solve is guarded at the toggle positions).

Where the loop does not close (the two circles do not meet) the closed form returns the
nearest configuration (``B`` on the line ``A O4``); :func:`transmission_cosine` says by how
much it failed (``|cos mu| > 1``), so that a search adds a finite penalty instead of a NaN.

What four-bars share with the other linkages (the crank, the coupler point, the curve) is
:class:`~._linkage.Linkage`'s.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from ._linkage import (
    TOGGLE_GUARD,
    Linkage,
    coupler_curve,
    coupler_point,
    guarded,
    transmission_cosine,
)

#: Names of the numbers of a four-bar, in the order of :meth:`FourBar.vector`.
NAMES = ("r1", "r2", "r3", "r4", "rcx", "rcy", "x0", "y0", "theta0")


class FourBar(Linkage):
    """A four-bar's dimensions and placement [length, rad]; every field may carry a batch.

    Attributes:
        r1, r2, r3, r4: ground, crank, coupler and rocker lengths [length].
        rcx, rcy: the coupler point in the coupler's frame (x along ``A -> B``) [length].
        x0, y0: the crank's ground pivot ``O2`` [length].
        theta0: the ground link's angle ``O2 -> O4`` [rad].
        branch: +1 or -1, the assembly branch (the side of ``A O4`` where ``B`` lies).
    """

    NAMES: ClassVar[tuple[str, ...]] = NAMES
    LENGTHS: ClassVar[tuple[str, ...]] = ("r1", "r2", "r3", "r4")
    KIND: ClassVar[str] = "four_bar"
    TITLE: ClassVar[str] = "four-bar"
    OUTPUT: ClassVar[str | None] = "angle"

    r1: jax.Array
    r2: jax.Array
    r3: jax.Array
    r4: jax.Array
    rcx: jax.Array
    rcy: jax.Array
    x0: jax.Array
    y0: jax.Array
    theta0: jax.Array
    branch: jax.Array

    def pivots(self) -> tuple[jax.Array, jax.Array]:
        """The ground pivots ``O2`` and ``O4``, each (2,) [length]."""
        o2 = self.crank_pivot()
        o4 = o2 + self.r1 * jnp.stack([jnp.cos(self.theta0), jnp.sin(self.theta0)])
        return o2, o4

    def coupler_angle(self, theta2) -> jax.Array:
        """The coupler's angle ``phi3`` [rad] at ``theta2`` (:func:`link_angles`)."""
        return link_angles(self, theta2)[0]

    def output(self, theta2) -> jax.Array:
        """The rocker's angle ``phi4 - theta0`` [rad] from the ground link at ``theta2``
        (:func:`link_angles`)."""
        return link_angles(self, theta2)[1] - self.theta0

    def transmission_cosine(self, theta2) -> jax.Array:
        """``cos mu`` of the transmission angle ``mu`` (between coupler and rocker) at
        ``theta2`` [rad]: the law of cosines in the triangle ``A B O4``, ``(r3^2 + r4^2 -
        |A O4|^2) / (2 r3 r4)`` (beyond ±1 where the loop does not close)."""
        _, o4 = self.pivots()
        d = o4 - self.crank_pin(theta2)
        return (self.r3**2 + self.r4**2 - jnp.sum(d**2)) / (2.0 * self.r3 * self.r4)


@jax.custom_jvp
def _dyad(a, o4, r3, r4, branch):
    """``(phi3, phi4)``: the angles of ``A -> B`` and ``O4 -> B`` with ``|AB| = r3``,
    ``|O4 B| = r4``, ``B`` on the side ``branch`` of ``A -> O4`` (closed form; the nearest
    configuration where the circles do not meet)."""
    d = o4 - a
    l2 = jnp.maximum(jnp.sum(d**2), 1e-300)
    ll = jnp.sqrt(l2)
    u = d / ll
    along = (r3**2 - r4**2 + l2) / (2.0 * ll)
    along = jnp.clip(along, -r3, r3)
    h = jnp.sqrt(jnp.maximum(r3**2 - along**2, 0.0))
    perp = jnp.stack([-u[1], u[0]])
    b = a + along * u + branch * h * perp
    phi3 = jnp.arctan2(b[1] - a[1], b[0] - a[0])
    phi4 = jnp.arctan2(b[1] - o4[1], b[0] - o4[0])
    return phi3, phi4


@_dyad.defjvp
def _dyad_jvp(primals, tangents):
    a, o4, r3, r4, branch = primals
    da, do4, dr3, dr4, _ = tangents
    phi3, phi4 = _dyad(a, o4, r3, r4, branch)
    e3 = jnp.stack([jnp.cos(phi3), jnp.sin(phi3)])
    e4 = jnp.stack([jnp.cos(phi4), jnp.sin(phi4)])
    # Phi = a + r3 e3 - o4 - r4 e4 = 0;  Phi_phi = [r3 e3', -r4 e4'],  e' = (-sin, cos).
    rhs = -(da - do4 + dr3 * e3 - dr4 * e4)
    s = guarded(jnp.sin(phi3 - phi4), TOGGLE_GUARD)
    # Cramer's rule for [[-r3 sin3, r4 sin4], [r3 cos3, -r4 cos4]] (dphi3, dphi4) = rhs.
    det = r3 * r4 * s
    dphi3 = -r4 * (e4[0] * rhs[0] + e4[1] * rhs[1]) / det
    dphi4 = -r3 * (e3[0] * rhs[0] + e3[1] * rhs[1]) / det
    return (phi3, phi4), (dphi3, dphi4)


def link_angles(fb: FourBar, theta2) -> tuple[jax.Array, jax.Array]:
    """The coupler's and rocker's absolute angles ``(phi3, phi4)`` [rad] at ``theta2`` [rad]
    (scalars; ``jax.vmap`` for many), on the four-bar's branch; differentiable implicitly."""
    _, o4 = fb.pivots()
    return _dyad(fb.crank_pin(theta2), o4, fb.r3, fb.r4, fb.branch)


__all__ = [
    "NAMES",
    "FourBar",
    "coupler_curve",
    "coupler_point",
    "link_angles",
    "transmission_cosine",
]
