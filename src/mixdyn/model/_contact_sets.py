"""Contact sets: many shapes declared once, every pair that can touch found when the model is
built (a ball pit, a row of rollers, Newton's cradle).

A set's pairs are enumerated once, at binding: every two of its circles on two different
bodies (two circles of one body never touch each other). Each evaluation then computes one
centre distance per pair, all at once (the broad phase: a pair apart costs that distance),
and the contact forces only while some pair touches (the compliant law's narrow phase,
:meth:`~mixdyn.model._compliant._Compliant.passive`), as MuJoCo MJX's collision driver
fixes its geometry pairs from the model, so that each collision function runs on static
shapes over all its pairs at once.
"""

from __future__ import annotations

import dataclasses
import itertools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._compliant import _Compliant, _safe_norm, _unit, _velocity
from ._declare import element, quantity, references
from ._element import Resolver
from ._forces import _f64
from ._geometry import GROUND, point


def pairs_on_bodies(bodies, shape: str, name: str, field: str) -> tuple[tuple[int, int], ...]:
    """The pairs of a set's shapes on two different ``bodies`` (one a shape), every two in
    order (``(0, 1), (0, 2), ..., (1, 2), ...``); a set with none (every ``shape`` on one
    body) is refused at ``field`` of element ``name``."""
    pairs = tuple(
        (a, b) for a, b in itertools.combinations(range(len(bodies)), 2)
        if bodies[a] != bodies[b]
    )  # fmt: skip
    if not pairs:
        raise ModelError(
            f"every {shape} of the set is on one body: no two can touch; put them on two "
            "bodies or more",
            name,
            field=field,
        )
    return pairs


@element("circle_set_contact", "forces")
class CircleSetContact(_Compliant):
    """Circles of one radius on several bodies (balls, rollers, the balls of Newton's cradle),
    each pair on two different bodies a contact as :class:`~mixdyn.CircleContact`'s: a
    circle on the ground is a fixed ball.

    The pairs are every two circles on different bodies, in the order of ``centers``
    (``(0, 1), (0, 2), ..., (1, 2), ...``; :attr:`pairs`). For each, the penetration is
    ``2 radius - |c_b - c_a|``, the normal on the second circle points from the first's
    centre to its own, and Hertz's effective radius is ``radius / 2``. Result columns
    (summed over the pairs, as a contact of several points): ``{name}.normal`` (the pairs'
    normal forces added), ``.penetration`` (the deepest) and, with ``mu``, ``.friction``.
    """

    centers: tuple[str, ...] = references(
        "Centres of the circles, ``body.point`` or ``body`` (``ground.point``: a fixed one), "
        "on at least two bodies."
    )
    radius: jax.Array = quantity(
        "length", "Radius of every circle, > 0.", converter=_f64, above=0.0
    )
    #: The circles' bodies (M,), fixed when the model is built.
    bodies: tuple[int, ...] = eqx.field(static=True, default=(), kw_only=True)
    #: The circles' centres in their bodies' frames (M, 2).
    local: jax.Array | None = eqx.field(default=None, kw_only=True)
    #: The pairs that can touch, as indices into ``centers`` (K pairs of two).
    pairs: tuple[tuple[int, int], ...] = eqx.field(static=True, default=(), kw_only=True)

    def bind(self, r: Resolver):
        if len(self.centers) < 2:
            raise ModelError("a contact set needs two circles or more", self.name, field="centers")
        located = [r.point(c, self.name) for c in self.centers]
        bodies = tuple(int(b) for b, _ in located)
        pairs = pairs_on_bodies(bodies, "circle", self.name, "centers")
        local = jnp.stack([jnp.asarray(s, dtype=jnp.float64) for _, s in located])
        return dataclasses.replace(self, bodies=bodies, local=local, pairs=pairs)

    def body_indices(self):
        return tuple(sorted({b for b in self.bodies if b != GROUND}))

    def _centres(self, q) -> jax.Array:
        """The circles' centres (M, 2) [length]."""
        return jnp.stack([point(q, b, self.local[k]) for k, b in enumerate(self.bodies)])

    def _index(self):
        a, b = (np.array(x, dtype=int) for x in zip(*self.pairs, strict=True))
        return a, b

    def _offsets(self, q):
        """``(first centres (K, 2), second minus first (K, 2))`` of the pairs [length]."""
        a, b = self._index()
        c = self._centres(q)
        return c[a], c[b] - c[a]

    def penetration(self, q):
        _, d = self._offsets(q)
        return 2.0 * self.radius - jax.vmap(_safe_norm)(d)

    def frame(self, q):
        first, d = self._offsets(q)
        n = jax.vmap(_unit)(d)
        delta = 2.0 * self.radius - jax.vmap(_safe_norm)(d)
        return first + (self.radius - 0.5 * delta)[:, None] * n, n

    def effective_radius(self):
        return 0.5 * self.radius

    def sliding(self, q, qd):
        """The sliding speeds (K,) [velocity] of each pair's second circle on its first at
        the contact points, along ``z x n``."""
        P, n = self.frame(q)
        t = jnp.stack([-n[:, 1], n[:, 0]], axis=1)
        return jnp.stack([
            jnp.dot(_velocity(q, qd, self.bodies[j], P[k]) - _velocity(q, qd, self.bodies[i], P[k]),
                    t[k])
            for k, (i, j) in enumerate(self.pairs)
        ])  # fmt: skip

    def drawing(self):
        return {"circles": [(b, self.local[k], self.radius) for k, b in enumerate(self.bodies)]}


__all__ = ["CircleSetContact"]
