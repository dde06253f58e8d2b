"""Contact pairs: the shapes of two bodies that touch, each a compliant contact
(:class:`~mixdyn.model._compliant._Compliant`) giving its penetrations, contact points and
Hertz's effective radius: a circle on a line (a half-plane's edge), a circle on a polyline
(segments end to end: a stop's outline, a notch, a slot's side), a box's rounded corners on a
line (a convex polygon's vertices), two circles, a journal in a bearing (a hole) and a slider
in a guide (a translational joint's gap).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._compliant import _Compliant, _safe_norm, _unit
from ._declare import direction, element, quantity, reference
from ._element import Resolver, body_name
from ._forces import _f64
from ._geometry import GROUND, angle, point, rot, vector
from ._polygon_sets import _points_field


def _apart(r: Resolver, name: str, first: str, second: str, both: str):
    """The bodies and local points ``((b, s), (b, s))`` of two point references, resolved in
    that order, which must lie on two different bodies; ``both`` (with ``{body}``, the one
    body) says what is wrong where they do not."""
    one, two = r.point(first, name), r.point(second, name)
    if one[0] == two[0]:
        raise ModelError(both.format(body=repr(body_name(first))), name)
    return one, two


@element("circle_line_contact", "forces")
class CircleLineContact(_Compliant):
    """A circle (a disk, a ball, a rounded tip) on body j touching a straight line of body i
    or the ground, the edge of a solid half-plane (a floor, a wall, a stop).

    The line passes through ``line_point`` along ``axis``; the solid lies on its right, so
    that the normal ``n = z x axis`` (left of the axis) points out of it: a floor along
    ``[1, 0]`` is solid below. Penetration ``delta = radius - (c - p) . n`` (``c`` the
    circle's centre, ``p`` the line's point). Hertz's effective radius is the circle's.
    Result columns: ``{name}.normal``, ``.penetration`` and, with ``mu``, ``.friction``.
    """

    center: str = reference("Centre of the circle, ``body.point`` (or ``body``).")
    radius: jax.Array = quantity("length", "Radius of the circle, > 0.", converter=_f64, above=0.0)
    line_point: str = reference(
        "A point of the line, ``ground.point`` or ``body.point`` (another body)."
    )
    axis: str | tuple[float, ...] = direction(
        "Direction of the line in its body's frame; the solid is on its right (``[1, 0]``: "
        "a floor). Default ``[1, 0]``.",
        (1.0, 0.0),
        on="line_point",
    )
    u: jax.Array | None = eqx.field(default=None, kw_only=True)

    def bind(self, r: Resolver):
        (bj, sj), (bi, si) = _apart(
            r,
            self.name,
            self.center,
            self.line_point,
            "the circle and the line are both on {body}: they must be on two different bodies",
        )
        u = r.vector(self.axis, bi, self.name)
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj, u=u)

    def _normal(self, q):
        u = vector(q, self.bi, self.u)
        return jnp.stack([-u[1], u[0]])

    def penetration(self, q):
        n = self._normal(q)
        return self.radius - jnp.dot(point(q, self.bj, self.sj) - point(q, self.bi, self.si), n)

    def frame(self, q):
        n = self._normal(q)
        c = point(q, self.bj, self.sj)
        return c - (self.radius - 0.5 * self.penetration(q)) * n, n

    def effective_radius(self):
        return self.radius

    def drawing(self):
        out = {"circles": [(self.bj, self.sj, self.radius)]}
        if self.bi == GROUND:
            out["guides"] = [(np.asarray(self.si), np.asarray(self.u))]
        return out


@element("circle_polyline_contact", "forces")
class CirclePolylineContact(_Compliant):
    """A circle (a pin, a roller, a ball) on body j touching a polyline of body i or the
    ground: segments end to end through the points ``polyline`` (two points: one segment), a
    stop's outline, a V notch, a slot's side. The polyline is a curve, not a solid: it has no
    inside, and the circle touches it from either side.

    Each segment ``k`` is a contact point: with ``p_k`` the point of the segment nearest the
    circle's centre ``c``, the penetration is ``delta_k = radius - |c - p_k|`` and the normal
    on the circle ``n_k = (c - p_k) / |c - p_k|``. A point where two segments meet belongs to
    the second: where the nearest point of segment ``k`` is its end (the centre beyond a
    convex corner), segment ``k`` is apart (``delta_k = -(radius + |c - p_k|)``) and the next
    segment, whose nearest point is that same corner, carries the contact once; in a concave
    corner (a notch) both sides touch, each with its own force. Hertz's effective radius is
    the circle's (the segments flat). Result columns: ``{name}.normal`` (the segments'
    normal forces added), ``.penetration`` (the deepest) and, with ``mu``, ``.friction``.
    """

    center: str = reference("Centre of the circle, ``body.point`` (or ``body``).")
    radius: jax.Array = quantity("length", "Radius of the circle, > 0.", converter=_f64, above=0.0)
    polyline: tuple = _points_field(
        "The polyline's points in order, ``body.point`` (``ground.point``: a fixed outline), "
        "two or more, all on one body other than the circle's, consecutive points apart."
    )
    #: The polyline's points in its body's frame (V, 2) [length], fixed when bound.
    local: jax.Array | None = eqx.field(default=None, kw_only=True)

    def bind(self, r: Resolver):
        bj, sj = r.point(self.center, self.name)
        if len(self.polyline) < 2:
            raise ModelError(
                f"a polyline needs two points or more (one segment), got {len(self.polyline)}",
                self.name,
                field="polyline",
            )
        located = [r.point(v, self.name) for v in self.polyline]
        on = {int(b) for b, _ in located}
        if len(on) > 1:
            raise ModelError(
                "the polyline's points are on several bodies: they must all be on one body "
                "(or the ground)",
                self.name,
                field="polyline",
            )
        bi = on.pop()
        if bi == bj:
            raise ModelError(
                f"the circle and the polyline are both on {body_name(self.center)!r}: they "
                "must be on two different bodies",
                self.name,
                field="polyline",
            )
        V = np.array([np.asarray(s, dtype=float) for _, s in located])
        short = np.flatnonzero(np.hypot(*np.diff(V, axis=0).T) <= 0.0)
        if short.size:
            k = int(short[0])
            raise ModelError(
                f"points {k + 1} and {k + 2} of the polyline coincide: consecutive points must "
                "be apart (a segment of zero length has no direction)",
                self.name,
                field="polyline",
            )
        return dataclasses.replace(self, bi=bi, bj=bj, sj=sj, local=jnp.asarray(V))

    def _nearest(self, q):
        """``(c, p, delta)``: the circle's centre (2,), each segment's point nearest to it
        (k, 2) [length] and the segments' penetrations (k,) [length] (apart where the
        segment's nearest point is its end, but for the last segment)."""
        c = point(q, self.bj, self.sj)
        P = jax.vmap(lambda s: point(q, self.bi, s))(self.local)
        a, e = P[:-1], P[1:] - P[:-1]
        s = jnp.clip(jnp.sum((c - a) * e, axis=1) / jnp.sum(e * e, axis=1), 0.0, 1.0)
        p = a + s[:, None] * e
        owned = (s < 1.0) | (jnp.arange(e.shape[0]) == e.shape[0] - 1)
        d = jax.vmap(_safe_norm)(c - p)
        return c, p, jnp.where(owned, self.radius - d, -(self.radius + d))

    def penetration(self, q):
        return self._nearest(q)[2]

    def frame(self, q):
        c, p, delta = self._nearest(q)
        n = jax.vmap(_unit)(c - p)
        return c - (self.radius - 0.5 * delta)[:, None] * n, n

    def effective_radius(self):
        return self.radius

    def drawing(self):
        out = {"circles": [(self.bj, self.sj, self.radius)]}
        if self.bi == GROUND:
            V = np.asarray(self.local, dtype=float)
            out["edges"] = list(itertools.pairwise(V))
        return out


@element("box_line_contact", "forces")
class BoxLineContact(_Compliant):
    """A box (a rectangle with rounded corners, on body j: a block, a slider, a cam's flat
    stop) touching a straight line of body i or the ground, the edge of a solid half-plane,
    at its corners: a convex polygon's vertices against a line.

    The box is ``width`` by ``height`` about ``center``, its sides along body j's axes; its
    four corners are rounded with radius ``corner_radius`` (Hertz's effective radius), each
    a circle that penetrates the half-plane (see :class:`CircleLineContact`: the solid right
    of ``axis``). Penetrations (4), one a corner. Result columns: ``{name}.normal`` (the sum
    of the corners' forces), ``.penetration`` (the deepest) and, with ``mu``, ``.friction``
    (the sum).
    """

    center: str = reference("Centre of the box, ``body.point`` (or ``body``).")
    width: jax.Array = quantity(
        "length", "The box's size along body j's x axis, > 0.", converter=_f64, above=0.0
    )
    height: jax.Array = quantity(
        "length", "The box's size along body j's y axis, > 0.", converter=_f64, above=0.0
    )
    corner_radius: jax.Array = quantity(
        "length",
        "Radius of the box's rounded corners, > 0 and at most half its smaller side.",
        converter=_f64,
        above=0.0,
    )
    line_point: str = reference(
        "A point of the line, ``ground.point`` or ``body.point`` (another body)."
    )
    axis: str | tuple[float, ...] = direction(
        "Direction of the line in its body's frame; the solid is on its right (``[1, 0]``: "
        "a floor). Default ``[1, 0]``.",
        (1.0, 0.0),
        on="line_point",
    )
    u: jax.Array | None = eqx.field(default=None, kw_only=True)

    def __check_init__(self):
        if not np.all(
            2 * np.asarray(self.corner_radius)
            <= np.minimum(np.asarray(self.width), np.asarray(self.height))
        ):
            raise ModelError(
                "the corners' radius must be at most half the box's smaller side",
                self.name,
                field="corner_radius",
            )

    def bind(self, r: Resolver):
        (bj, sj), (bi, si) = _apart(
            r,
            self.name,
            self.center,
            self.line_point,
            "the box and the line are both on {body}: they must be on two different bodies",
        )
        u = r.vector(self.axis, bi, self.name)
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj, u=u)

    def _corners(self, q):
        """The centres of the rounded corners (4, 2) and the line's normal ``n`` (2,)."""
        a = 0.5 * self.width - self.corner_radius
        b = 0.5 * self.height - self.corner_radius
        local = jnp.stack(
            [jnp.stack([a, b]), jnp.stack([-a, b]), jnp.stack([-a, -b]), jnp.stack([a, -b])]
        )
        centres = jax.vmap(lambda s: point(q, self.bj, self.sj + s))(local)
        u = vector(q, self.bi, self.u)
        return centres, jnp.stack([-u[1], u[0]])

    def penetration(self, q):
        centres, n = self._corners(q)
        return self.corner_radius - (centres - point(q, self.bi, self.si)) @ n

    def frame(self, q):
        centres, n = self._corners(q)
        reach = self.corner_radius - 0.5 * self.penetration(q)
        return centres - reach[:, None] * n, jnp.broadcast_to(n, (4, 2))

    def effective_radius(self):
        return self.corner_radius

    def drawing(self):
        """The box's rounded corners (their circles make its outline) and, where the line is
        the ground's, the line."""
        a = float(self.width) / 2 - float(self.corner_radius)
        b = float(self.height) / 2 - float(self.corner_radius)
        s = np.asarray(self.sj, dtype=float)
        corners = [(self.bj, s + np.array([x, y]), self.corner_radius)
                   for x, y in ((a, b), (-a, b), (-a, -b), (a, -b))]  # fmt: skip
        out = {"circles": corners}
        if self.bi == GROUND:
            out["guides"] = [(np.asarray(self.si), np.asarray(self.u))]
        return out


@element("circle_contact", "forces")
class CircleContact(_Compliant):
    """Two circles touching from outside (disks, balls, a pin and a round stop): circle i on
    body i (or the ground) and circle j on body j.

    Penetration ``delta = radius_i + radius_j - |c_j - c_i|``; the normal on j points from
    ``c_i`` to ``c_j``. Hertz's effective radius ``R_i R_j / (R_i + R_j)``. Result columns:
    ``{name}.normal``, ``.penetration`` and, with ``mu``, ``.friction``.
    """

    point_i: str = reference("Centre of circle i, ``body.point``, ``body`` or ``ground.point``.")
    radius_i: jax.Array = quantity("length", "Radius of circle i, > 0.", converter=_f64, above=0.0)
    point_j: str = reference("Centre of circle j, on another body.")
    radius_j: jax.Array = quantity("length", "Radius of circle j, > 0.", converter=_f64, above=0.0)

    def bind(self, r: Resolver):
        (bi, si), (bj, sj) = _apart(
            r,
            self.name,
            self.point_i,
            self.point_j,
            "both circles are on {body}: they must be on two different bodies",
        )
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj)

    def _d(self, q):
        return point(q, self.bj, self.sj) - point(q, self.bi, self.si)

    def penetration(self, q):
        return self.radius_i + self.radius_j - _safe_norm(self._d(q))

    def frame(self, q):
        n = _unit(self._d(q))
        P = point(q, self.bi, self.si) + (self.radius_i - 0.5 * self.penetration(q)) * n
        return P, n

    def effective_radius(self):
        return self.radius_i * self.radius_j / (self.radius_i + self.radius_j)

    def drawing(self):
        return {"circles": [(self.bi, self.si, self.radius_i), (self.bj, self.sj, self.radius_j)]}


@element("journal_bearing", "forces")
class JournalBearing(_Compliant):
    """A journal (a pin of radius ``journal_radius``, centre ``point_j`` on body j) inside a
    bearing (a hole of radius ``journal_radius + clearance``, centre ``point_i`` on body i
    or the ground): a revolute joint with radial clearance, whose journal flies freely,
    impacts and stays in contact (Flores, Ambrosio, Claro and Lankarani, Proc. IMechE K 220
    (2006) 21-34). A revolute joint with ``clearance`` is this element.

    Penetration ``delta = |c_j - c_i| - clearance`` (the eccentricity less the clearance);
    the normal on the journal points back to the bearing's centre. Hertz's effective radius
    ``R_j (R_j + c) / c`` (a concave bearing). Result columns: ``{name}.normal``,
    ``.penetration``, the journal's orbit ``.ex``, ``.ey`` (its centre from the bearing's, in
    body i's frame) and, with ``mu``, ``.friction``.
    """

    point_i: str = reference(
        "Centre of the bearing (the hole), ``body.point``, ``body`` or ``ground.point``."
    )
    point_j: str = reference("Centre of the journal (the pin), on another body.")
    clearance: jax.Array = quantity(
        "length",
        'Radial clearance ``c`` (bearing radius less journal radius), > 0, e.g. ``"0.5 mm"``.',
        converter=_f64,
        above=0.0,
    )
    journal_radius: jax.Array = quantity(
        "length", "Radius of the journal, > 0.", converter=_f64, above=0.0
    )
    described: ClassVar[str] = "a journal in a bearing (a revolute joint's clearance)"
    of_a_joint: ClassVar[bool] = True

    def bind(self, r: Resolver):
        (bi, si), (bj, sj) = _apart(
            r,
            self.name,
            self.point_i,
            self.point_j,
            "the journal and the bearing are both on {body}: they must be on two different bodies",
        )
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj)

    def _d(self, q):
        return point(q, self.bj, self.sj) - point(q, self.bi, self.si)

    def penetration(self, q):
        return _safe_norm(self._d(q)) - self.clearance

    def frame(self, q):
        d = self._d(q)
        n = _unit(d)
        reach = 0.5 * (_safe_norm(d) + 2.0 * self.journal_radius + self.clearance)
        return point(q, self.bi, self.si) + reach * n, -n

    def effective_radius(self):
        R = self.journal_radius
        return R * (R + self.clearance) / self.clearance

    def drawing(self):
        R = self.journal_radius
        return {"circles": [(self.bi, self.si, R + self.clearance), (self.bj, self.sj, R)]}

    def outputs(self, q, qd, t):
        """As every contact's, and the journal's orbit: ``ex``, ``ey``, the journal centre's
        position relative to the bearing's centre in body i's frame [length] (within the
        clearance in free flight)."""
        e = rot(angle(q, self.bi)).T @ self._d(q)
        return {**super().outputs(q, qd, t), "ex": e[0], "ey": e[1]}

    @property
    def output_kinds(self):
        return {**super().output_kinds, "ex": "length", "ey": "length"}


@element("slider_in_guide", "forces")
class SliderInGuide(_Compliant):
    """A slider (body j) in a guide (body i or the ground) with a gap: a translational joint
    with clearance (Flores, Ambrosio, Claro and Lankarani, "Translational joints with
    clearance in rigid multibody systems", J. Comput. Nonlinear Dyn. 3 (2008) 011007). A
    translational joint with ``clearance`` is this element.

    The guide's surfaces run along ``axis`` through ``point_i`` at ``+-clearance`` from the
    line that the slider's centre ``point_j`` follows in the ideal joint; the slider's two
    ends, ``slider_length`` apart along its axis (the guide's axis turned by the relative
    angle less ``angle``), touch them with rounded corners of radius ``corner_radius``
    (Hertz's effective radius; the slider's height is taken into the clearance, exact to
    first order in its tilt). Penetrations (4): each end beyond each surface. Result columns:
    ``{name}.normal`` (the sum of the corners' forces), ``.penetration`` (the deepest) and,
    with ``mu``, ``.friction`` (the sum).
    """

    point_i: str = reference(
        "A point of the guide's centre line, ``ground.point`` or ``body.point``."
    )
    point_j: str = reference("The slider's centre, on another body.")
    clearance: jax.Array = quantity(
        "length",
        'The gap on each side of the centred slider, > 0, e.g. ``"0.5 mm"``.',
        converter=_f64,
        above=0.0,
    )
    slider_length: jax.Array = quantity(
        "length", "Distance between the slider's two ends, > 0.", converter=_f64, above=0.0
    )
    corner_radius: jax.Array = quantity(
        "length", "Radius of the slider's rounded corners, > 0.", converter=_f64, above=0.0
    )
    described: ClassVar[str] = "a slider in a guide (a translational joint's clearance)"
    of_a_joint: ClassVar[bool] = True
    axis: str | tuple[float, ...] = direction(
        "Direction of the guide in body i's frame: ``[x, y]`` or a vector's name. Default "
        "``[1, 0]``.",
        (1.0, 0.0),
        on="point_i",
    )
    angle: jax.Array = quantity(
        "angle",
        "The relative angle ``phi_j - phi_i`` at which the slider lies along the guide. Default 0.",
        0.0,
        converter=_f64,
    )
    u: jax.Array | None = eqx.field(default=None, kw_only=True)

    def bind(self, r: Resolver):
        (bi, si), (bj, sj) = _apart(
            r,
            self.name,
            self.point_i,
            self.point_j,
            "the slider and the guide are both on {body}: they must be on two different bodies",
        )
        u = r.vector(self.axis, bi, self.name)
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj, u=u)

    def _ends(self, q):
        """The slider's two ends (2, 2) [length] and the guide's normal ``n`` (2,)."""
        u = vector(q, self.bi, self.u)
        tilt = angle(q, self.bj) - angle(q, self.bi) - self.angle
        c, sn = jnp.cos(tilt), jnp.sin(tilt)
        w = jnp.stack([c * u[0] - sn * u[1], sn * u[0] + c * u[1]])
        centre = point(q, self.bj, self.sj)
        half = 0.5 * self.slider_length * w
        return jnp.stack([centre + half, centre - half]), jnp.stack([-u[1], u[0]])

    def penetration(self, q):
        ends, n = self._ends(q)
        y = (ends - point(q, self.bi, self.si)) @ n
        return jnp.stack([y[0], -y[0], y[1], -y[1]]) - self.clearance

    def frame(self, q):
        ends, n = self._ends(q)
        P = jnp.stack([ends[0], ends[0], ends[1], ends[1]])
        return P, jnp.stack([-n, n, -n, n])

    def effective_radius(self):
        return self.corner_radius

    def drawing(self):
        """The guide's two surfaces, where the guide is the ground."""
        if self.bi != GROUND:
            return {}
        u = np.asarray(self.u, dtype=float)
        n, p = np.array([-u[1], u[0]]), np.asarray(self.si, dtype=float)
        c = float(np.max(np.asarray(self.clearance)))
        return {"guides": [(p + c * n, u), (p - c * n, u)]}


__all__ = [
    "BoxLineContact",
    "CircleContact",
    "CircleLineContact",
    "JournalBearing",
    "SliderInGuide",
]
