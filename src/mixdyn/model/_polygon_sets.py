"""Polygon sets: rounded convex polygons and segments on several bodies declared once, every
pair on two different bodies a contact (blocks stacked or colliding, a box on a ramp, a
crate between walls), the counterpart of the circle set
(:class:`~mixdyn.model._contact_sets.CircleSetContact`).

Each shape is a convex core polygon ``C`` (its vertices fixed in its body's frame, counter-
clockwise; two vertices: a segment) swept by a circle of the set's radius ``r``: the points
within ``r`` of ``C``, a box with rounded corners, a capsule. Two such shapes touch where
their cores come within ``2 r``; the nearest points of two convex polygons include a vertex
of one of them, so that a pair ``(A, B)`` is tested at each core vertex ``p`` of ``A``
against ``B``'s core and each core vertex of ``B`` against ``A``'s: ``n_A + n_B`` contact
points, a number fixed by the shapes. At each, with ``d(p, C)`` the signed distance of ``p``
to the core ``C`` (outside: the distance to the nearest point of ``C``; inside: minus the
distance to the nearest side; a segment has no inside)::

    delta = 2 r - d(p, C),     n = grad_p d(p, C),

the penetration [length] and the unit normal on the vertex's body (from ``C`` towards
``p``), the contact point half-way between ``p`` and its nearest point on ``C``'s boundary.
Hertz's effective radius is ``r / 2``, two rounded corners', for every point of the set (a
corner on a flat side included: one stiffness for the set).

The pairs are enumerated once, at binding, as the circle set's; each evaluation tests every
pair's bounding circles first (the broad phase: one centre distance a pair) and computes the
contact points' distances and forces only while some pair's bounding circles overlap (the
narrow phase, :meth:`PolygonSetContact.passive`), all points at once over static shapes, as
MuJoCo MJX's collision driver does.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._compliant import _Compliant, _safe_norm, _unit
from ._contact_law import friction_force, normal_force
from ._contact_sets import pairs_on_bodies
from ._declare import KEY, Reference, element, option, quantity
from ._element import Resolver, body_name
from ._forces import _f64
from ._geometry import GROUND, pose

#: Turning at a vertex below which a core polygon is taken as not convex [rad] (a vertex on
#: a straight side, turning 0, is allowed: one more contact point along that side).
_TURN_TOL = 1e-9


def _deep_tuple(value):
    """``value`` with every list turned into a tuple and every NumPy number into Python's (a
    static field is hashed)."""
    if isinstance(value, str):
        return value
    if isinstance(value, list | tuple | np.ndarray):
        return tuple(_deep_tuple(v) for v in value)
    return value.item() if isinstance(value, np.generic) else value


def _points_field(doc: str):
    """A static list of point references as :func:`~mixdyn.model._declare.references`
    declares it, whose coordinate points (``("body", (x, y))``) are held as tuples."""
    return eqx.field(
        static=True, converter=_deep_tuple, metadata={KEY: Reference(doc, "point", True)}
    )


def _counts(value):
    """The counts of vertices as a tuple (one number: one shape's)."""
    return tuple(value) if isinstance(value, list | tuple | np.ndarray) else (value,)


def _runs(vertices) -> tuple[int, ...]:
    """The lengths of the runs of consecutive ``vertices`` on one body."""
    names = [body_name(v) for v in vertices]
    return tuple(len(list(g)) for _, g in itertools.groupby(names))


def _shape_words(refs) -> str:
    """A shape's vertices for messages: ``(box.c1, box.c2, ...)``."""
    return "(" + ", ".join(r if isinstance(r, str) else repr(r) for r in refs) + ")"


def _check_core(V: np.ndarray) -> str | None:
    """What is wrong with the core polygon of vertices ``V`` (m, 2) [length], or None: a
    segment's two ends must differ; a polygon's sides must have a length, its vertices must
    not all lie on one line, and they must turn left at every vertex by one turn in all
    (convex, counter-clockwise)."""
    m = len(V)
    size = float(np.max(np.ptp(V, axis=0)))
    if m == 2:
        return None if size > 0.0 else "its two vertices coincide: a segment needs a length"
    E = np.roll(V, -1, axis=0) - V
    if np.any(np.hypot(E[:, 0], E[:, 1]) <= 1e-12 * size) or size == 0.0:
        return "two consecutive vertices coincide: every side needs a length"
    area = 0.5 * float(np.sum(V[:, 0] * np.roll(V[:, 1], -1) - np.roll(V[:, 0], -1) * V[:, 1]))
    if abs(area) <= 1e-12 * size**2:
        return (
            "its vertices lie on one line (no area): give a segment as its two ends, or "
            "vertices around an area"
        )
    before = np.roll(E, 1, axis=0)
    turn = np.arctan2(before[:, 0] * E[:, 1] - before[:, 1] * E[:, 0], np.sum(before * E, axis=1))
    if area < 0.0 and np.all(turn <= _TURN_TOL):
        return "its vertices run clockwise: list them counter-clockwise"
    if np.any(turn < -_TURN_TOL) or abs(float(np.sum(turn)) - 2.0 * math.pi) > 1e-6:
        return (
            "it is not convex (it turns right at a vertex, or winds more than once): split it "
            "into convex shapes on the same body"
        )
    return None


def _edges(V: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sides of the core polygon of vertices ``V`` (m, 2), as ``count`` rows (the first
    side repeated past the polygon's own, which leaves a nearest side as it is): their starts,
    their vectors and their outward unit normals (count, 2) each (a segment: its one side,
    the normal on its right)."""
    m = len(V)
    starts = V if m > 2 else V[:1]
    sides = (np.roll(V, -1, axis=0) - V) if m > 2 else V[1:] - V[:1]
    normals = np.stack([sides[:, 1], -sides[:, 0]], axis=1)
    normals /= np.hypot(normals[:, 0], normals[:, 1])[:, None]
    pad = np.zeros(count - len(starts), dtype=int)
    take = np.concatenate([np.arange(len(starts)), pad])
    return starts[take], sides[take], normals[take]


def _perp(a):
    """``z x a`` for rows ``a`` (..., 2)."""
    return jnp.stack([-a[..., 1], a[..., 0]], axis=-1)


@element("polygon_set_contact", "forces")
class PolygonSetContact(_Compliant):
    """Rounded convex polygons and segments (capsules) on several bodies (blocks, crates,
    walls, ramps), each pair on two different bodies a contact: a shape on the ground is a
    fixed one.

    A shape is a convex core polygon, its vertices points of one body listed counter-
    clockwise (two vertices: a segment), swept by a circle of ``radius``: a polygon with
    rounded corners, or a capsule. ``vertices`` lists the shapes' vertices one shape after
    the other; ``counts`` says how many each shape has (by default each run of consecutive
    vertices on one body is one shape).

    The pairs are every two shapes on different bodies, in the order of the shapes
    (:attr:`pairs`). A pair ``(A, B)`` touches at ``n_A + n_B`` points: each core vertex
    ``p`` of ``A`` against ``B``'s core ``C``, then each core vertex of ``B`` against
    ``A``'s. The penetration is ``2 radius - d(p, C)`` (``d`` the signed distance: the
    distance to ``C``, negative inside it), the normal on ``p``'s body points from ``C``
    towards ``p`` (the gradient of ``d``), and Hertz's effective radius is ``radius / 2``
    (two rounded corners). Result columns (summed over the points, as a contact of several
    points): ``{name}.normal`` (the points' normal forces added), ``.penetration`` (the
    deepest) and, with ``mu``, ``.friction``.
    """

    vertices: tuple = _points_field(
        "The shapes' core vertices, ``body.point`` (``ground.point``: a fixed shape), each "
        "shape's counter-clockwise in its body's frame and convex, two or more a shape (two: "
        "a segment), one shape after the other, on at least two bodies."
    )
    radius: jax.Array = quantity(
        "length",
        "Radius of the rounding of every shape, > 0: a shape is the points within it of its "
        "core polygon.",
        converter=_f64,
        above=0.0,
    )
    counts: tuple = option(
        "How many vertices each shape has, in the order of ``vertices`` (e.g. ``[4, 2]``: a "
        "box, then a segment). Default: each run of consecutive vertices on one body is one "
        "shape.",
        (),
        converter=_counts,
        kw_only=True,
    )
    #: The shapes' bodies (S,), fixed when the model is built.
    bodies: tuple[int, ...] = eqx.field(static=True, default=(), kw_only=True)
    #: The shape of each vertex (V,), an index into the shapes.
    shape_of: tuple[int, ...] = eqx.field(static=True, default=(), kw_only=True)
    #: Whether each shape's core has an inside (S,) (a segment has none).
    closed: tuple[bool, ...] = eqx.field(static=True, default=(), kw_only=True)
    #: The pairs that can touch, as indices into the shapes (K pairs of two).
    pairs: tuple[tuple[int, int], ...] = eqx.field(static=True, default=(), kw_only=True)
    #: The contact points ``(vertex, shape)`` (k,): a vertex against another shape's core.
    points: tuple[tuple[int, int], ...] = eqx.field(static=True, default=(), kw_only=True)
    #: The vertices in their bodies' frames (V, 2) [length].
    local: jax.Array | None = eqx.field(default=None, kw_only=True)
    #: Each shape's sides (S, E, 2): their starts, vectors and outward unit normals, in its
    #: body's frame (a shape with fewer sides than E repeats its first).
    starts: jax.Array | None = eqx.field(default=None, kw_only=True)
    sides: jax.Array | None = eqx.field(default=None, kw_only=True)
    normals: jax.Array | None = eqx.field(default=None, kw_only=True)
    #: Each shape's bounding circle about its core: centre (S, 2) in its body's frame and
    #: radius (S,) [length].
    centres: jax.Array | None = eqx.field(default=None, kw_only=True)
    reach: jax.Array | None = eqx.field(default=None, kw_only=True)

    def __check_init__(self):
        counts = self.counts
        if counts and not all(
            isinstance(c, int | np.integer) and not isinstance(c, bool) and c > 0 for c in counts
        ):
            raise ModelError(
                f"the counts of vertices must be whole numbers, got {list(counts)}",
                self.name,
                field="counts",
            )
        if counts and sum(int(c) for c in counts) != len(self.vertices):
            raise ModelError(
                f"the counts add up to {sum(int(c) for c in counts)} vertices, but "
                f"{len(self.vertices)} are given",
                self.name,
                field="counts",
            )

    def _groups(self) -> list[tuple]:
        """The vertex references of each shape."""
        counts = [int(c) for c in self.counts] or list(_runs(self.vertices))
        ends = np.cumsum([0, *counts])
        return [self.vertices[a:b] for a, b in itertools.pairwise(ends)]

    def bind(self, r: Resolver):
        groups = self._groups()
        field = "counts" if self.counts else "vertices"
        bodies, cores = [], []
        for k, refs in enumerate(groups):
            words = f"shape {k + 1} {_shape_words(refs)}"
            if len(refs) < 2:
                raise ModelError(
                    f"{words} has one vertex: a shape needs two (a segment) or more",
                    self.name,
                    field=field,
                )
            located = [r.point(v, self.name) for v in refs]
            on = {int(b) for b, _ in located}
            if len(on) > 1:
                raise ModelError(
                    f"{words} has vertices on several bodies: a shape's are on one body",
                    self.name,
                    field=field,
                )
            V = np.array([np.asarray(s, dtype=float) for _, s in located])
            fault = _check_core(V)
            if fault is not None:
                raise ModelError(f"{words}: {fault}", self.name, field="vertices")
            bodies.append(on.pop())
            cores.append(V)
        if len(groups) < 2:
            raise ModelError("a contact set needs two shapes or more", self.name, field="vertices")
        pairs = pairs_on_bodies(bodies, "shape", self.name, "vertices")
        first = np.cumsum([0, *[len(V) for V in cores]])
        shape_of = tuple(s for s, V in enumerate(cores) for _ in V)
        points = tuple(
            (int(v), s) for a, b in pairs for own, s in ((a, b), (b, a))
            for v in range(first[own], first[own + 1])
        )  # fmt: skip
        count = max(len(V) if len(V) > 2 else 1 for V in cores)
        edges = [_edges(V, count) for V in cores]
        centres = np.array([0.5 * (V.min(axis=0) + V.max(axis=0)) for V in cores])
        reach = np.array(
            [np.max(np.hypot(*(V - c).T)) for V, c in zip(cores, centres, strict=True)]
        )

        def f64(x):
            return jnp.asarray(np.asarray(x, dtype=float))

        return dataclasses.replace(
            self,
            bodies=tuple(bodies),
            shape_of=shape_of,
            closed=tuple(len(V) > 2 for V in cores),
            pairs=pairs,
            points=points,
            local=f64(np.concatenate(cores)),
            starts=f64([e[0] for e in edges]),
            sides=f64([e[1] for e in edges]),
            normals=f64([e[2] for e in edges]),
            centres=f64(centres),
            reach=f64(reach),
        )

    def body_indices(self):
        return tuple(sorted({b for b in self.bodies if b != GROUND}))

    # ------------------------------------------------------------------ geometry
    def _poses(self, q):
        """The shapes' bodies' origins (S, 2) [length] and rotations (S, 2, 2)."""
        r, phi = zip(*(pose(q, b) for b in self.bodies), strict=True)
        phi = jnp.stack(phi)
        c, s = jnp.cos(phi), jnp.sin(phi)
        return jnp.stack(r), jnp.stack([jnp.stack([c, -s], -1), jnp.stack([s, c], -1)], -2)

    def _near(self, q):
        """Whether each pair's bounding circles (widened by the rounding) overlap (K,): the
        broad phase."""
        r, A = self._poses(q)
        c = r + jnp.einsum("sij,sj->si", A, self.centres)
        a, b = (np.array(x, dtype=int) for x in zip(*self.pairs, strict=True))
        d = c[b] - c[a]
        reach = self.reach[a] + self.reach[b] + 2.0 * self.radius
        return jnp.sum(d * d, axis=1) < reach**2

    def _distances(self, q):
        """``(p, d, n)``: each contact point's vertex (k, 2) [length], its signed distance
        to the other shape's core (k,) [length] and the unit normal (k, 2) (the gradient of
        the distance, from the core towards the vertex); one compiled program (an eager call
        costs one dispatch, a trace inlines it)."""
        return _nearest_jit(self, q)

    def penetration(self, q):
        """``2 radius - d`` (k,) [length] of every contact point, pair after pair (each
        pair's first shape's vertices, then its second's)."""
        _, d, _ = self._distances(q)
        return 2.0 * self.radius - d

    def frame(self, q):
        """The contact points (k, 2) [length], half-way between each vertex and its nearest
        point on the other core, and the normals on the vertices' bodies (k, 2)."""
        p, d, n = self._distances(q)
        return p - 0.5 * d[:, None] * n, n

    def effective_radius(self):
        return 0.5 * self.radius

    def _rows(self, q, P, u):
        """``(k, nq)``: per contact point, its vertex's body's velocity along ``u`` (k, 2) at
        the point ``P`` (k, 2) [length] less the other shape's body's, per unit of ``qd``
        (``[u, (P - r) x u]`` in the first body's columns, the opposite in the second's)."""
        vertex, other = (np.array(x, dtype=int) for x in zip(*self.points, strict=True))
        k = np.arange(len(vertex))
        out = jnp.zeros((len(k), q.shape[0]), dtype=jnp.result_type(q, P))
        for shape, sign in ((np.asarray(self.shape_of, dtype=int)[vertex], 1.0), (other, -1.0)):
            b = np.asarray(self.bodies, dtype=int)[shape]
            on = b != GROUND
            if not on.any():
                continue
            rows, b = k[on], b[on]
            arm = P[rows] - jnp.stack([q[3 * b], q[3 * b + 1]], axis=1)
            moment = arm[:, 0] * u[rows, 1] - arm[:, 1] * u[rows, 0]
            vals = sign * jnp.concatenate([u[rows], moment[:, None]], axis=1)
            out = out.at[rows[:, None], 3 * b[:, None] + np.arange(3)].add(vals)
        return out

    def sliding(self, q, qd):
        """The sliding speeds (k,) [velocity] of each vertex's body on the other shape's
        body at the contact points, along ``z x n``."""
        P, n = self.frame(q)
        return self._rows(q, P, _perp(n)) @ qd

    # ------------------------------------------------------------------ the force
    def _forces(self, q, qd):
        """``(delta (k,), d delta / dq (k, nq), d v_t / d qd (k, nq) or None, F (k,), F_t
        (k,) or None)``: :meth:`_Compliant._state`'s, and the sliding speeds' rows, each row
        from its point's normal and lever arms (a rigid body's motion moves a point and the
        other core together: ``d delta / dq`` is the velocity along ``-n``), without one
        derivative pass a coordinate."""
        p, d, n = self._distances(q)
        P = p - 0.5 * d[:, None] * n
        delta = 2.0 * self.radius - d
        J = -self._rows(q, P, n)
        speed = 1.0 if self.impact_speed is None else self.impact_speed
        F = normal_force(delta, J @ qd, self.stiffness, self.restitution, speed, self.contact_model)
        if self.mu is None:
            return delta, J, None, F, None
        G = self._rows(q, P, _perp(n))
        return delta, J, G, F, friction_force(F, G @ qd, self.mu, self.v_stick)

    def _state(self, q, qd):
        delta, J, _, F, Ft = self._forces(q, qd)
        return delta, J, F, Ft

    def passive(self, q, qd, t, nq):
        """The contact's generalized force (nq,): the contact points' forces where some
        pair's bounding circles overlap (:meth:`_near`), zero elsewhere without computing a
        contact point (one centre distance a pair); zero for a rigid contact."""
        if self.rigid:
            return jnp.zeros(nq, dtype=jnp.result_type(q, qd))

        def touching(q, qd):
            _, J, G, F, Ft = self._forces(q, qd)
            return -F @ J if Ft is None else Ft @ G - F @ J

        def apart(q, qd):
            return jnp.zeros(nq, dtype=jnp.result_type(q, qd))

        return jax.lax.cond(jnp.any(self._near(q)), touching, apart, q, qd)

    # ------------------------------------------------------------------ drawing
    def drawing(self):
        """Every core vertex's circle of ``radius`` (on a body, the rims that its outline
        wraps: the rounded polygon) and, for a shape on the ground, its rounded outline's
        straight sides as ``edges`` [(ground point, ground point)]."""
        local = np.asarray(self.local, dtype=float)
        out = {"circles": [(self.bodies[s], local[k], self.radius)
                           for k, s in enumerate(self.shape_of)]}  # fmt: skip
        edges = []
        rad = float(self.radius)
        for s, b in enumerate(self.bodies):
            if b != GROUND:
                continue
            V = local[np.asarray(self.shape_of) == s]
            starts, sides, normals = _edges(V, len(V) if len(V) > 2 else 1)
            for p, e, n in zip(starts, sides, normals, strict=True):
                edges.append((p + rad * n, p + e + rad * n))
                if len(V) == 2:  # a capsule: both sides
                    edges.append((p - rad * n, p + e - rad * n))
        if edges:
            out["edges"] = edges
        return out


def _nearest(contact: PolygonSetContact, q):
    """:meth:`PolygonSetContact._distances` (traced once per set of shapes)."""
    r, A = contact._poses(q)
    vertex, shape = (np.array(x, dtype=int) for x in zip(*contact.points, strict=True))
    own = np.asarray(contact.shape_of, dtype=int)[vertex]
    p = r[own] + jnp.einsum("kij,kj->ki", A[own], contact.local[vertex])
    starts = r[:, None, :] + jnp.einsum("sij,sej->sei", A, contact.starts)
    sides = jnp.einsum("sij,sej->sei", A, contact.sides)
    normals = jnp.einsum("sij,sej->sei", A, contact.normals)
    closed = jnp.asarray(np.asarray(contact.closed, dtype=bool)[shape])

    def one(p, starts, sides, normals, closed):
        w = p - starts  # (E, 2) from each side's start
        along = jnp.clip(jnp.sum(w * sides, 1) / jnp.sum(sides * sides, 1), 0.0, 1.0)
        off = w - along[:, None] * sides  # from each side's nearest point
        dist = jax.vmap(_safe_norm)(off)
        height = jnp.sum(w * normals, 1)  # > 0 outside that side
        outside = ~closed | (jnp.max(height) > 0.0)
        d = jnp.where(outside, jnp.min(dist), jnp.max(height))
        n = jnp.where(outside, _unit(off[jnp.argmin(dist)]), normals[jnp.argmax(height)])
        return d, n

    d, n = jax.vmap(one)(p, starts[shape], sides[shape], normals[shape], closed)
    return p, d, n


_nearest_jit = eqx.filter_jit(_nearest)


__all__ = ["PolygonSetContact"]
