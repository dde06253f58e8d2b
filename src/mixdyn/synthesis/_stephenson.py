"""The Stephenson six-bars of synthesis. Stephenson III: a four-bar whose coupler drives a dyad
to a third ground pivot, the coupler point on the dyad's floating link. Stephenson I: a
four-bar whose crank and rocker are joined by a dyad, the coupler point on the dyad's link
from the crank.

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

Stephenson I (:class:`StephensonI`): Stephenson's chain with the binary link that joins its
two ternary links directly as the ground: the crank ``O2 A D`` and the rocker ``O4 B F`` are
the ternaries, the ground ``O2 O4`` joins them, the coupler ``A B``, the tracer ``D E`` and
the follower ``F E`` the binaries (the two ternaries are joined through the ground and the
coupler, and through the dyad: not to each other). Grounding the other kind of binary link,
one of the two that join a ternary to the dyad, gives Stephenson II, whose crank does not
close its loops one dyad at a time. Numbers: ``r1``..``r6``, ``(dx, dy)`` the point ``D`` in
the crank's frame (x from ``O2`` towards ``A``), ``(fx, fy)`` the point ``F`` in the rocker's
(x from ``O4`` towards ``B``), ``(rcx, rcy)`` the coupler point on the tracer, ``x0``,
``y0``, ``theta0``.
"""

from __future__ import annotations

from typing import ClassVar

from ._sixbar import GroundPivotSixBar, RockerPivotSixBar

#: Names of the numbers of a Stephenson III six-bar, in the order of its ``vector``.
STEPHENSON_NAMES = GroundPivotSixBar.NAMES


class StephensonIII(GroundPivotSixBar):
    """A Stephenson III six-bar's dimensions and placement [length, rad]
    (:class:`~._sixbar.GroundPivotSixBar`'s fields, ``D`` in the coupler's frame: x along
    ``A -> B``); every field may carry a batch."""

    KIND: ClassVar[str] = "stephenson3"
    TITLE: ClassVar[str] = "Stephenson III six-bar"


#: Names of the numbers of a Stephenson I six-bar, in the order of its ``vector``.
STEPHENSON1_NAMES = RockerPivotSixBar.NAMES


class StephensonI(RockerPivotSixBar):
    """A Stephenson I six-bar's dimensions and placement [length, rad] (the module's
    description; :class:`~._sixbar.RockerPivotSixBar`'s fields, ``D`` in the crank's frame:
    x along ``O2 -> A``); every field may carry a batch."""

    KIND: ClassVar[str] = "stephenson1"
    TITLE: ClassVar[str] = "Stephenson I six-bar"
    DYAD_BODY: ClassVar[str] = "crank"


__all__ = ["STEPHENSON1_NAMES", "STEPHENSON_NAMES", "StephensonI", "StephensonIII"]
