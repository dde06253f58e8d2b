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

from ._sixbar import GroundPivotSixBar

#: Names of the numbers of a Stephenson III six-bar, in the order of its ``vector``.
STEPHENSON_NAMES = GroundPivotSixBar.NAMES


class StephensonIII(GroundPivotSixBar):
    """A Stephenson III six-bar's dimensions and placement [length, rad]
    (:class:`~._sixbar.GroundPivotSixBar`'s fields, ``D`` in the coupler's frame: x along
    ``A -> B``); every field may carry a batch."""

    KIND: ClassVar[str] = "stephenson3"
    TITLE: ClassVar[str] = "Stephenson III six-bar"


__all__ = ["STEPHENSON_NAMES", "StephensonIII"]
