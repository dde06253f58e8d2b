"""The Stephenson III six-bar of synthesis: a four-bar whose coupler drives a dyad to a third
ground pivot, the coupler point on the dyad's floating link.

Topology: Stephenson's chain (its two ternary links not joined to each other) with a
ternary link as the ground: the ground ``O2 O4 O6`` and the coupler ``A B D`` are the
ternaries; the crank ``O2 A``, the rocker ``O4 B``, the tracer ``D E`` and the follower
``O6 E`` the binaries. The name and topology are those of the Stephenson III mechanism of
the PMKS+ verification set (PMKS-Web/PMKS_Verification, as its fixtures list it: ground
pivots ``A``, ``D``, ``G``; links ``AB``, ``BCE``, ``CD``, ``EF``, ``FG``; read through
the code search of public repositories): the inversion of Stephenson's chain that grounds a
ternary link.

Numbers (module :mod:`._sixbar`'s notation): ``r1``..``r4`` the four-bar, ``r5 = |D E|``,
``r6 = |O6 E|``, ``(dx, dy)`` the point ``D`` in the coupler's frame, ``(gx, gy)`` the pivot
``O6 = O2 + R(theta0) (gx, gy)`` in the ground link's frame (x from ``O2`` towards ``O4``),
``(rcx, rcy)`` the coupler point on the tracer, ``x0``, ``y0``, ``theta0``.
"""

from __future__ import annotations

from typing import ClassVar

import jax

from ._sixbar import SixBar, _turned

#: Names of the numbers of a Stephenson III six-bar, in the order of its ``vector``.
STEPHENSON_NAMES = (
    "r1", "r2", "r3", "r4", "r5", "r6", "dx", "dy", "gx", "gy", "rcx", "rcy", "x0", "y0",
    "theta0",
)  # fmt: skip


class StephensonIII(SixBar):
    """A Stephenson III six-bar's dimensions and placement [length, rad]; every field may
    carry a batch.

    Attributes:
        r1, r2, r3, r4: ground, crank, coupler and rocker lengths [length].
        r5, r6: the tracer ``D E`` and the follower ``O6 E`` [length].
        dx, dy: ``D`` in the coupler's frame (x along ``A -> B``) [length].
        gx, gy: ``O6`` from ``O2`` in the ground link's frame (x along ``O2 -> O4``) [length].
        rcx, rcy: the coupler point in the tracer's frame (x along ``D -> E``) [length].
        x0, y0: the crank's ground pivot ``O2`` [length].
        theta0: the ground link's angle ``O2 -> O4`` [rad].
        branch: ``b4 + 2 b6`` (3, 1, -1 or -3): the two loops' branches (:mod:`._sixbar`).
    """

    NAMES: ClassVar[tuple[str, ...]] = STEPHENSON_NAMES
    LENGTHS: ClassVar[tuple[str, ...]] = ("r1", "r2", "r3", "r4", "r5", "r6")
    KIND: ClassVar[str] = "stephenson3"
    TITLE: ClassVar[str] = "Stephenson III six-bar"

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


__all__ = ["STEPHENSON_NAMES", "StephensonIII"]
