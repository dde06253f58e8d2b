"""What a task asks of a linkage's form beyond its numbers' bounds: its Grashof type and
regions for its ground pivots.

**Grashof type** (``grashof=``). A four-bar whose shortest link ``s`` and longest ``l``
satisfy ``s + l <= p + q`` (the other two) is a Grashof linkage: its shortest link turns fully
relative to every other. The types a task may ask for:

* ``"crank_rocker"``: Grashof with the crank ``r2`` the shortest: the crank turns a full
  revolution, the rocker oscillates;
* ``"double_crank"`` (drag link): Grashof with the ground ``r1`` the shortest: crank and rocker
  both turn fully;
* ``"grashof"``: Grashof with any link the shortest, ``s + l <= p + q`` (the literature's
  plain Grashof condition): some link turns fully relative to the others;
* ``"any"`` (the default): no condition; the loop has only to close along the traversed
  motion (the search's closure check).

"Grashof with link ``i`` the shortest" is written as three linear conditions, ``r_i + r_j <=
r_k + r_l`` for each other link ``j`` (``k, l`` the remaining two): the sum of two of them
gives ``r_i <= r_j``, so together they are exactly Grashof's condition with ``r_i`` the
shortest (a tie, ``s + l = p + q`` or two links equally short, counts as met: a change-point
linkage). A slider-crank's crank turns fully where its rod reaches the slide from every crank
angle, ``r2 + |e| <= r3`` (``r2 + e <= r3`` and ``r2 - e <= r3``): that is what
``"crank_rocker"`` asks of it (the slider reciprocates as a rocker would); it has no double
crank. ``"grashof"`` is one gap, ``2 (s + l) - (r1 + r2 + r3 + r4)``; a slider-crank's is
``min(r2, r3) + |e| - max(r2, r3)`` (its crank, or its coupler, turns fully). Each condition
is a gap ``g <= 0`` [length] (:func:`grashof_gaps`).

**Ground-pivot regions** (``pivots=``): rectangles ``{"O2": ((x_lo, x_hi), (y_lo, y_hi)),
"O4": (...)}`` [length] in which a ground pivot must lie: ``O2 = (x0, y0)``, the crank's pivot
(every linkage), and a four-bar's rocker pivot ``O4 = O2 + r1 (cos theta0, sin theta0)``.
Each side is a gap ``g <= 0`` [length] (:func:`region_gaps`).

The search adds ``30 relu(g / s + 0.001)`` for every gap (:func:`penalty`; ``s`` the targets'
size): the weight is three times a bound's and the margin :data:`LIMIT_MARGIN` keeps a search
that leans on a condition (a crank-rocker through points no crank-rocker passes) inside it,
where the ranking's exact check keeps a candidate only if every gap is at most ``1e-9 s``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._fourbar import FourBar
from ._slidercrank import SliderCrank

#: The margin of the search's penalties on the gaps, in targets' sizes (a search that leans on
#: a condition ends this far inside it, so that the exact check keeps it).
LIMIT_MARGIN = 1e-3
#: The weight of the search's penalties on the gaps.
LIMIT_PENALTY = 30.0

#: The Grashof types a task may ask for.
GRASHOF = ("any", "grashof", "crank_rocker", "double_crank")

#: A four-bar's links by name, in the order of the shortest-link types below.
_LINKS = ("r1", "r2", "r3", "r4")

#: A Grashof four-bar's type by its shortest link (:func:`grashof_type`).
_BY_SHORTEST = {
    "r2": "crank_rocker",
    "r1": "double_crank",
    "r4": "rocker_crank",
    "r3": "double_rocker",
}


def _shortest_gaps(lengths, shortest: int) -> jax.Array:
    """(..., 3) ``r_i + r_j - r_k - r_l`` for ``i = shortest`` and each other link ``j``:
    all ``<= 0`` where the four-bar is Grashof with link ``i`` the shortest."""
    total = sum(lengths)
    others = [k for k in range(4) if k != shortest]
    return jnp.stack(
        [2.0 * (lengths[shortest] + lengths[j]) - total for j in others], axis=-1
    )  # r_i + r_j - (total - r_i - r_j)


def grashof_gaps(lk, grashof: str) -> jax.Array:
    """(..., K) the gaps [length] of ``lk``'s Grashof conditions (``<= 0`` where met; the
    module's documentation): K = 3 for a four-bar's ``"crank_rocker"`` or
    ``"double_crank"``, 2 for a slider-crank's ``"crank_rocker"``, 1 for ``"grashof"``, 0
    for ``"any"``."""
    if grashof == "any":
        return jnp.zeros((*jnp.shape(lk.x0), 0))
    if grashof == "grashof":
        if isinstance(lk, SliderCrank):
            gap = jnp.minimum(lk.r2, lk.r3) + jnp.abs(lk.e) - jnp.maximum(lk.r2, lk.r3)
        else:
            lengths = jnp.stack([getattr(lk, n) for n in _LINKS], axis=-1)
            total = jnp.sum(lengths, axis=-1)
            gap = 2.0 * (jnp.min(lengths, axis=-1) + jnp.max(lengths, axis=-1)) - total
        return gap[..., None]
    if isinstance(lk, SliderCrank):
        return jnp.stack([lk.r2 + lk.e - lk.r3, lk.r2 - lk.e - lk.r3], axis=-1)
    shortest = "r2" if grashof == "crank_rocker" else "r1"
    return _shortest_gaps([getattr(lk, n) for n in _LINKS], _LINKS.index(shortest))


def grashof_type(r1, r2, r3, r4, rtol: float = 1e-12) -> str:
    """A four-bar's Grashof type from its ground, crank, coupler and rocker lengths [length]:
    ``"crank_rocker"`` (Grashof, the crank shortest), ``"double_crank"`` (the ground
    shortest), ``"rocker_crank"`` (the rocker shortest: it turns fully, the crank oscillates),
    ``"double_rocker"`` (the coupler shortest: it turns fully, crank and rocker oscillate) or
    ``"triple_rocker"`` (not Grashof: no link turns fully). A tie within ``rtol`` of the
    links' sum counts as Grashof; two links equally short name the first in that order."""
    lengths = [float(x) for x in (r1, r2, r3, r4)]
    tol = rtol * sum(lengths)
    for name, kind in _BY_SHORTEST.items():
        if np.max(np.asarray(_shortest_gaps(lengths, _LINKS.index(name)))) <= tol:
            return kind
    return "triple_rocker"


def pivot_names(linkage: type) -> tuple[str, ...]:
    """The ground pivots of a linkage type that a region may hold: ``("O2", "O4")`` for a
    four-bar, ``("O2",)`` for any other (the crank's pivot)."""
    return ("O2", "O4") if issubclass(linkage, FourBar) else ("O2",)


def pivot_points(lk) -> dict[str, jax.Array]:
    """``name -> (..., 2)`` the ground pivots of ``lk`` [length] (:func:`pivot_names`)."""
    o2 = jnp.stack([lk.x0, lk.y0], axis=-1)
    out = {"O2": o2}
    if isinstance(lk, FourBar):
        out["O4"] = o2 + lk.r1[..., None] * jnp.stack(
            [jnp.cos(lk.theta0), jnp.sin(lk.theta0)], axis=-1
        )
    return out


def region_arrays(pivots: dict) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high)`` (R, 2) [length] of the regions of checked ``pivots``
    (:func:`check_pivots`), in their order: the corners ``(x_lo, y_lo)`` and ``(x_hi,
    y_hi)``."""
    boxes = np.array(list(pivots.values()), dtype=float).reshape(-1, 2, 2)
    return boxes[:, :, 0], boxes[:, :, 1]


def region_gaps(lk, names: tuple[str, ...], low, high) -> jax.Array:
    """(..., 4 R) the gaps [length] of ``lk``'s ground pivots ``names`` (R) against their
    regions ``low``, ``high`` (R, 2) (``<= 0`` inside): ``low - p`` and ``p - high`` for
    each pivot ``p``."""
    if not names:
        return jnp.zeros((*jnp.shape(lk.x0), 0))
    points = pivot_points(lk)
    p = jnp.stack([points[n] for n in names], axis=-2)  # (..., R, 2)
    gaps = jnp.concatenate([jnp.asarray(low) - p, p - jnp.asarray(high)], axis=-1)
    return gaps.reshape(*gaps.shape[:-2], -1)


def penalty(gaps) -> jax.Array:
    """The search's residuals of ``gaps`` (K,) in targets' sizes: ``30 relu(g + 0.001)``."""
    return LIMIT_PENALTY * jax.nn.relu(gaps + LIMIT_MARGIN)


def check_grashof(linkage: type, grashof: str) -> None:
    """Refuse a Grashof type that ``linkage`` cannot be asked for (a
    :class:`~mixdyn.errors.ModelError` at ``grashof``)."""
    if grashof not in GRASHOF:
        raise ModelError(f"grashof must be one of {', '.join(GRASHOF)}, got {grashof!r}", "grashof")
    if grashof == "any":
        return
    if issubclass(linkage, SliderCrank) and grashof == "double_crank":
        raise ModelError(
            "a slider-crank has no double crank: give grashof 'crank_rocker' (its crank turns "
            "fully: r2 + |e| <= r3), 'grashof' or 'any'",
            "grashof",
        )
    if not issubclass(linkage, FourBar | SliderCrank):
        raise ModelError(
            f"a Grashof type is a four-bar's or a slider-crank's, not a {linkage.TITLE}'s",
            "grashof",
        )


def check_pivots(linkage: type, pivots: dict) -> dict[str, tuple]:
    """``pivots`` checked for ``linkage``: ``name -> ((x_lo, x_hi), (y_lo, y_hi))`` [length]
    (floats); a :class:`~mixdyn.errors.ModelError` at the pivot's name for a pivot the
    linkage lacks or a region that is not two finite ``(low, high)`` with ``low < high``."""
    names = pivot_names(linkage)
    out = {}
    for name, region in pivots.items():
        if name not in names:
            raise ModelError(
                f"no ground pivot {name!r} of a {linkage.TITLE}: a region for one of "
                f"{', '.join(names)}",
                name,
            )
        try:
            box = np.array(region, dtype=float)
        except (TypeError, ValueError):
            box = np.zeros(0)
        if box.shape != (2, 2) or not np.all(np.isfinite(box)) or not np.all(box[:, 0] < box[:, 1]):
            raise ModelError(
                f"a pivot's region is ((x_lo, x_hi), (y_lo, y_hi)) with low < high, got {region!r}",
                name,
            )
        out[name] = tuple(tuple(float(v) for v in row) for row in box)
    return out


__all__ = [
    "GRASHOF",
    "LIMIT_MARGIN",
    "LIMIT_PENALTY",
    "check_grashof",
    "check_pivots",
    "grashof_gaps",
    "grashof_type",
    "penalty",
    "pivot_names",
    "pivot_points",
    "region_arrays",
    "region_gaps",
]
