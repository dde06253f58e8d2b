"""The Watt six-bars of synthesis. Watt I: a four-bar whose coupler and rocker are joined by a
dyad, the coupler point on the dyad's link from the coupler. Watt II: two four-bars in
series, the first one's rocker the second one's crank, the coupler point on the second one's
coupler.

Topology: Watt's chain (its two ternary links joined to each other) with a binary link as
the ground: the coupler ``A B D`` and the rocker ``O4 B F`` are the ternaries, joined at
``B``; the ground ``O2 O4``, the crank ``O2 A``, the tracer ``D E`` and the follower
``F E`` the binaries. The name and topology are those of the Watt I mechanism of the PMKS+
verification set (PMKS-Web/PMKS_Verification, as its fixtures list it: ground pivots ``A``,
``G``; links ``AB``, ``BCD``, ``DE``, ``EF``, ``CFG``; read through the code search of
public repositories): the inversion of Watt's chain that grounds a binary link (grounding a
ternary one gives Watt II, two four-bars in series).

Numbers (module :mod:`._sixbar`'s notation): ``r1``..``r4`` the four-bar, ``r5 = |D E|``,
``r6 = |F E|``, ``(dx, dy)`` the point ``D`` in the coupler's frame, ``(fx, fy)`` the point
``F = O4 + R(phi4) (fx, fy)`` in the rocker's frame (x from ``O4`` towards ``B``),
``(rcx, rcy)`` the coupler point on the tracer, ``x0``, ``y0``, ``theta0``.

Watt II (:class:`WattII`): Watt's chain with a ternary link as the ground: the ground ``O2 O4
O6`` and the rocker ``O4 B D`` are the ternaries, joined at ``O4``; the crank ``O2 A``, the
coupler ``A B``, the tracer ``D E`` and the follower ``O6 E`` the binaries. The four-bar
``O2 A B O4`` turns the rocker, which drives the second four-bar ``O4 D E O6`` (the same
ground). Numbers: ``r1``..``r6`` as above, ``(dx, dy)`` the point ``D`` in the rocker's
frame (x from ``O4`` towards ``B``), ``(gx, gy)`` the pivot ``O6 = O2 + R(theta0) (gx,
gy)`` in the ground link's frame, ``(rcx, rcy)``, ``x0``, ``y0``, ``theta0``.
"""

from __future__ import annotations

from typing import ClassVar

from ._sixbar import GroundPivotSixBar, RockerPivotSixBar

#: Names of the numbers of a Watt I six-bar, in the order of its ``vector``.
WATT_NAMES = RockerPivotSixBar.NAMES


class WattI(RockerPivotSixBar):
    """A Watt I six-bar's dimensions and placement [length, rad]
    (:class:`~._sixbar.RockerPivotSixBar`'s fields, ``D`` in the coupler's frame: x along
    ``A -> B``); every field may carry a batch."""

    KIND: ClassVar[str] = "watt1"
    TITLE: ClassVar[str] = "Watt I six-bar"


#: Names of the numbers of a Watt II six-bar, in the order of its ``vector``.
WATT2_NAMES = GroundPivotSixBar.NAMES


class WattII(GroundPivotSixBar):
    """A Watt II six-bar's dimensions and placement [length, rad] (the module's
    description; :class:`~._sixbar.GroundPivotSixBar`'s fields, ``D`` in the rocker's frame:
    x along ``O4 -> B``); every field may carry a batch."""

    KIND: ClassVar[str] = "watt2"
    TITLE: ClassVar[str] = "Watt II six-bar"
    DYAD_BODY: ClassVar[str] = "rocker"


__all__ = ["WATT2_NAMES", "WATT_NAMES", "WattI", "WattII"]
