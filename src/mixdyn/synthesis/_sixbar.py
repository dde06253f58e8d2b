"""What the six-bars of synthesis share: a four-bar ``O2 A B O4`` (crank, ternary coupler,
rocker) driven by its crank, and a dyad ``D E X`` closed by a second circle intersection,
the coupler point on the dyad's link ``D E``.

Notation (as :mod:`._fourbar`'s for the four-bar): the ground pivot ``O2 = (x0, y0)``, the
ground link ``r1`` at ``theta0`` (``O4 = O2 + r1 e^{i theta0}``), the crank ``r2`` turning by
``theta2`` from the ground link, the coupler ``r3`` from ``A`` to ``B``, the rocker ``r4``
from ``O4`` to ``B``, their angles ``phi3``, ``phi4`` from the four-bar's closed form; the
dyad's start ``D`` on the link :attr:`SixBar.DYAD_BODY` names: the coupler's point ``D = A +
R(phi3) (dx, dy)`` (the coupler's frame: x from ``A`` towards ``B``), the rocker's ``D =
O4 + R(phi4) (dx, dy)`` (:class:`~._watt.WattII`; x from ``O4`` towards ``B``) or the
crank's ``D = O2 + R(theta0 + theta2) (dx, dy)`` (:class:`~._stephenson.StephensonI`; x from
``O2`` towards ``A``). The dyad's
links: the tracer ``r5`` from ``D`` to ``E`` (angle ``phi5``) and the follower ``r6`` from
``X`` to ``E`` (angle ``phi6``), ``X`` on the link :attr:`SixBar.PIVOT_BODY` names: a ground
pivot (:class:`~._stephenson.StephensonIII`, :class:`~._watt.WattII`) or a point of the
rocker (:class:`~._watt.WattI`, :class:`~._stephenson.StephensonI`).
The coupler point (the path) rides on the tracer: ``C = D + R(phi5) (rcx, rcy)`` (x from
``D`` towards ``E``); :meth:`SixBar.coupler_angle` is the tracer's angle ``phi5``.

Both loops close by :mod:`._fourbar`'s circle intersection (``_dyad``), whose derivatives
are the closure equations' (implicit differentiation), so the second loop's are the chain
of the two implicit rules. Each loop has its branch (the side of ``A O4`` on which ``B``
lies, the side of ``D X`` on which ``E`` lies), kept at every input angle; the two are
carried in the one number ``branch = b4 + 2 b6`` (``b4``, ``b6`` each +1 or -1, so
``branch`` is one of 3, 1, -1, -3: ``b6`` its sign, ``b4 = branch - 2 b6``), which the
search treats as it treats a four-bar's branch (:attr:`BRANCHES`: a quarter of the starts
on each).

The transmission angles: the four-bar's ``mu1`` (between coupler and rocker at ``B``) and
the dyad's ``mu2`` (between tracer and follower at ``E``), each by the law of cosines;
:meth:`SixBar.transmission_cosine` is the one of the two farther from 0 (the worse angle),
so that a bound ``mu >= mu_min`` holds for both loops, and beyond ±1 where either loop
does not close.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import jax
import jax.numpy as jnp

from ._fourbar import _dyad
from ._linkage import Linkage


def _turned(phi, x, y):
    """``R(phi) (x, y)`` (2,)."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    return jnp.stack([c * x - s * y, s * x + c * y])


class SixBar(Linkage):
    """A six-bar of synthesis: a four-bar and a dyad ``D E X`` (abstract; module docstring).

    Subclasses hold the fields of their ``NAMES`` (``r1``..``r6``, ``dx``, ``dy``, their
    ``X``'s two numbers, ``rcx``, ``rcy``, ``x0``, ``y0``, ``theta0``) and ``branch``, and
    say where ``X`` is (:meth:`dyad_pivot`).
    """

    #: The branch codes ``b4 + 2 b6`` the search spreads its starts over.
    BRANCHES: ClassVar[tuple[float, ...]] = (3.0, 1.0, -1.0, -3.0)
    #: The four-bar's link that carries the dyad's start ``D``: ``"coupler"``, ``"rocker"``
    #: or ``"crank"``.
    DYAD_BODY: ClassVar[str] = "coupler"
    #: The link that carries the follower's other end ``X``: ``"ground"`` or ``"rocker"``.
    PIVOT_BODY: ClassVar[str] = "ground"

    def loop_branches(self) -> tuple[jax.Array, jax.Array]:
        """``(b4, b6)``, each +1 or -1: the four-bar's and the dyad's branch."""
        b6 = jnp.where(self.branch > 0, 1.0, -1.0)
        return self.branch - 2.0 * b6, b6

    def pivots(self) -> tuple[jax.Array, jax.Array]:
        """The four-bar's ground pivots ``O2`` and ``O4``, each (2,) [length]."""
        o2 = self.crank_pivot()
        return o2, o2 + self.r1 * jnp.stack([jnp.cos(self.theta0), jnp.sin(self.theta0)])

    def dyad_start(self, theta2, a, o4, phi3, phi4) -> jax.Array:
        """``D`` (2,) [length] at the input angle ``theta2`` from the crank pin ``a``, the
        pivot ``o4`` and the coupler's and rocker's angles: on the link :attr:`DYAD_BODY`
        names, at ``(dx, dy)`` in its frame (the crank's: x from ``O2`` towards ``A``)."""
        if self.DYAD_BODY == "rocker":
            return o4 + _turned(phi4, self.dx, self.dy)
        if self.DYAD_BODY == "crank":
            return self.crank_pivot() + _turned(self.theta0 + theta2, self.dx, self.dy)
        return a + _turned(phi3, self.dx, self.dy)

    @abc.abstractmethod
    def dyad_pivot(self, phi4) -> jax.Array:
        """``X`` (2,) [length], the follower's other end, with the rocker at ``phi4``."""

    def joints(self, theta2) -> dict[str, jax.Array]:
        """The joints' points at ``theta2`` [rad]: ``O2``, ``A``, ``B``, ``O4``, ``D``,
        ``X``, ``E`` and the coupler point ``C``, each (2,) [length]; and the angles
        ``phi3``..``phi6`` [rad]."""
        _, o4 = self.pivots()
        b4, b6 = self.loop_branches()
        a = self.crank_pin(theta2)
        phi3, phi4 = _dyad(a, o4, self.r3, self.r4, b4)
        d = self.dyad_start(theta2, a, o4, phi3, phi4)
        x = self.dyad_pivot(phi4)
        phi5, phi6 = _dyad(d, x, self.r5, self.r6, b6)
        e = d + self.r5 * jnp.stack([jnp.cos(phi5), jnp.sin(phi5)])
        return {
            "O2": self.crank_pivot(),
            "A": a,
            "B": a + self.r3 * jnp.stack([jnp.cos(phi3), jnp.sin(phi3)]),
            "O4": o4,
            "D": d,
            "X": x,
            "E": e,
            "C": d + _turned(phi5, self.rcx, self.rcy),
            "phi3": phi3,
            "phi4": phi4,
            "phi5": phi5,
            "phi6": phi6,
        }

    def link_angles(self, theta2) -> jax.Array:
        """(4,) ``phi3, phi4, phi5, phi6`` [rad] at ``theta2``: coupler, rocker, tracer,
        follower, on the branches; differentiable implicitly."""
        j = self.joints(theta2)
        return jnp.stack([j["phi3"], j["phi4"], j["phi5"], j["phi6"]])

    def coupler_angle(self, theta2) -> jax.Array:
        """The tracer's angle ``phi5`` [rad] (the link that carries the coupler point)."""
        return self.joints(theta2)["phi5"]

    def coupler_point(self, theta2) -> jax.Array:
        """The coupler point ``C = D + R(phi5) (rcx, rcy)`` (2,) [length] on the tracer."""
        return self.joints(theta2)["C"]

    def transmission_cosines(self, theta2) -> jax.Array:
        """(2,) ``cos mu1`` (coupler against rocker at ``B``: ``(r3^2 + r4^2 - |A O4|^2) /
        (2 r3 r4)``) and ``cos mu2`` (tracer against follower at ``E``: ``(r5^2 + r6^2 -
        |D X|^2) / (2 r5 r6)``); beyond ±1 where that loop does not close."""
        j = self.joints(theta2)
        gap1 = jnp.sum((j["O4"] - j["A"]) ** 2)
        gap2 = jnp.sum((j["X"] - j["D"]) ** 2)
        return jnp.stack([
            (self.r3**2 + self.r4**2 - gap1) / (2.0 * self.r3 * self.r4),
            (self.r5**2 + self.r6**2 - gap2) / (2.0 * self.r5 * self.r6),
        ])  # fmt: skip

    def transmission_cosine(self, theta2) -> jax.Array:
        """The cosine of the worse of the two transmission angles (the one of
        :meth:`transmission_cosines` of the larger magnitude)."""
        c = self.transmission_cosines(theta2)
        return jnp.where(jnp.abs(c[0]) >= jnp.abs(c[1]), c[0], c[1])


class GroundPivotSixBar(SixBar):
    """A six-bar whose follower ends at a third ground pivot ``O6 = O2 + R(theta0) (gx, gy)``
    (abstract: :class:`~._stephenson.StephensonIII`, ``D`` on the coupler, and
    :class:`~._watt.WattII`, ``D`` on the rocker): its fields, in the order of both types'
    ``NAMES``.

    Attributes:
        r1, r2, r3, r4: ground, crank, coupler and rocker lengths [length].
        r5, r6: the tracer ``D E`` and the follower ``O6 E`` [length].
        dx, dy: ``D`` in the frame of the link that carries it (:attr:`SixBar.DYAD_BODY`; x
            along ``A -> B`` on the coupler, ``O4 -> B`` on the rocker) [length].
        gx, gy: ``O6`` from ``O2`` in the ground link's frame (x along ``O2 -> O4``) [length].
        rcx, rcy: the coupler point in the tracer's frame (x along ``D -> E``) [length].
        x0, y0: the crank's ground pivot ``O2`` [length].
        theta0: the ground link's angle ``O2 -> O4`` [rad].
        branch: ``b4 + 2 b6`` (3, 1, -1 or -3): the two loops' branches.
    """

    NAMES: ClassVar[tuple[str, ...]] = (
        "r1", "r2", "r3", "r4", "r5", "r6", "dx", "dy", "gx", "gy", "rcx", "rcy", "x0", "y0",
        "theta0",
    )  # fmt: skip
    LENGTHS: ClassVar[tuple[str, ...]] = ("r1", "r2", "r3", "r4", "r5", "r6")
    OUTPUT: ClassVar[str | None] = "angle"

    r1: jax.Array
    r2: jax.Array
    r3: jax.Array
    r4: jax.Array
    r5: jax.Array
    r6: jax.Array
    dx: jax.Array
    dy: jax.Array
    gx: jax.Array
    gy: jax.Array
    rcx: jax.Array
    rcy: jax.Array
    x0: jax.Array
    y0: jax.Array
    theta0: jax.Array
    branch: jax.Array

    def dyad_pivot(self, phi4) -> jax.Array:
        """The ground pivot ``O6`` (2,) [length] (fixed: ``phi4`` unused)."""
        return self.crank_pivot() + _turned(self.theta0, self.gx, self.gy)

    def output(self, theta2) -> jax.Array:
        """The follower's angle ``phi6 - theta0`` [rad] (the link ``O6 -> E``, pivoted at the
        third ground pivot) from the ground link at ``theta2``."""
        return self.joints(theta2)["phi6"] - self.theta0


class RockerPivotSixBar(SixBar):
    """A six-bar whose follower ends at a point ``F = O4 + R(phi4) (fx, fy)`` of the rocker
    (abstract: :class:`~._watt.WattI`, ``D`` on the coupler, and
    :class:`~._stephenson.StephensonI`, ``D`` on the crank): its fields, in the order of
    both types' ``NAMES``.

    Attributes:
        r1, r2, r3, r4: ground, crank, coupler and rocker lengths [length].
        r5, r6: the tracer ``D E`` and the follower ``F E`` [length].
        dx, dy: ``D`` in the frame of the link that carries it (:attr:`SixBar.DYAD_BODY`)
            [length].
        fx, fy: ``F`` in the rocker's frame (x along ``O4 -> B``) [length].
        rcx, rcy: the coupler point in the tracer's frame (x along ``D -> E``) [length].
        x0, y0: the crank's ground pivot ``O2`` [length].
        theta0: the ground link's angle ``O2 -> O4`` [rad].
        branch: ``b4 + 2 b6`` (3, 1, -1 or -3): the two loops' branches.
    """

    NAMES: ClassVar[tuple[str, ...]] = (
        "r1", "r2", "r3", "r4", "r5", "r6", "dx", "dy", "fx", "fy", "rcx", "rcy", "x0", "y0",
        "theta0",
    )  # fmt: skip
    LENGTHS: ClassVar[tuple[str, ...]] = ("r1", "r2", "r3", "r4", "r5", "r6")
    PIVOT_BODY: ClassVar[str] = "rocker"

    r1: jax.Array
    r2: jax.Array
    r3: jax.Array
    r4: jax.Array
    r5: jax.Array
    r6: jax.Array
    dx: jax.Array
    dy: jax.Array
    fx: jax.Array
    fy: jax.Array
    rcx: jax.Array
    rcy: jax.Array
    x0: jax.Array
    y0: jax.Array
    theta0: jax.Array
    branch: jax.Array

    def dyad_pivot(self, phi4) -> jax.Array:
        """The rocker's point ``F`` (2,) [length] with the rocker at ``phi4``."""
        _, o4 = self.pivots()
        return o4 + _turned(phi4, self.fx, self.fy)


__all__ = ["GroundPivotSixBar", "RockerPivotSixBar", "SixBar"]
