"""Compliant contact: force elements for bodies that touch, collide and rattle.

Each contact pair is a shape on body i and a shape on body j (either may be the ground): a
line (the edge of a half-plane), a circle, or a hole (the inside of a circle, a bearing).
The pair's geometry gives the penetration ``delta(q)`` [length] (contact while ``delta > 0``,
negative: the gap), and the force of a compliant contact law
(:mod:`~mixdyn.model._contact_law`) acts along the normal with an optional regularized
Coulomb friction across it. In generalized coordinates::

    Q = -F grad_q(delta) + F_t grad_qd(v_t),

``F`` the normal force (from ``delta`` and ``delta_dot = grad_q(delta) . qd``), ``v_t`` the
sliding speed of j on i at the contact point (linear in ``qd``) and ``F_t`` the friction
force on j along the tangent: the normal force does work only through the penetration, so
that without damping (``restitution: 1``) and friction it derives from the potential
``K delta**2.5 / 2.5`` (:meth:`~_Compliant.potential`) and the energy is kept. Everything is
a pure JAX function of ``(q, qd)`` and the numbers of the element (derivatives by automatic
differentiation).

A revolute joint with a ``clearance`` is a :class:`JournalBearing` of the joint's name
(:func:`clearance_contacts`, called by the model): its two position equations are replaced
by the contact of a journal in a bearing, free flight, impacts and continuous contact.

The stiffness is Hertz's, from one material's Young's modulus and Poisson's ratio and the
pair's radii (:func:`~mixdyn.model._contact_law.hertz_stiffness`). Kinematic and inverse
analyses refuse a model with contacts (:func:`refuse_contacts`): the contact force follows
from a motion that no driver fixes.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._contact_law import (
    DAMPING_FACTORS,
    elastic_energy,
    friction_force,
    hertz_stiffness,
    normal_force,
)
from ._declare import direction, element, option, quantity, reference
from ._element import Resolver, body_name, moving
from ._forces import _UNBOUND, ForceElement, _f64
from ._geometry import GROUND, angle, point, pose, rot, vector


def _optional(x):
    return None if x is None else _f64(x)


def _safe_norm(d):
    """``|d|`` with a finite gradient (zero) where ``d = 0`` (a centred journal)."""
    dd = jnp.dot(d, d)
    positive = dd > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, dd, 1.0)), 0.0)


def _unit(d):
    """``d / |d|`` ([1, 0] where ``d = 0``)."""
    n = _safe_norm(d)
    safe = jnp.where(n > 0.0, n, 1.0)
    return jnp.where(n > 0.0, d / safe, jnp.array([1.0, 0.0]))


def _velocity(q, qd, b: int, P):
    """Velocity (2,) of the material point of body ``b`` at the global position ``P``."""
    if b == GROUND:
        return jnp.zeros(2, dtype=qd.dtype)
    r, _ = pose(q, b)
    w = qd[3 * b + 2]
    arm = P - r
    return qd[3 * b : 3 * b + 2] + w * jnp.stack([-arm[1], arm[0]])


# --------------------------------------------------------------------------- the contact law
def _young_modulus(optional: bool = False):
    return quantity(
        "pressure",
        "Young's modulus of both bodies' material, e.g. ``\"207 GPa\"`` (steel): with "
        "``poisson`` and the radii it gives Hertz's stiffness ``K = (4/3) E* sqrt(R*)``, "
        "``E* = E / (2 (1 - poisson**2))``.",
        *((None,) if optional else ()),
        converter=_optional if optional else _f64,
        above=0.0,
        kw_only=True,
    )


def _poisson(default):
    return quantity(
        "dimensionless",
        "Poisson's ratio of the material, in [0, 0.5). Default 0.3.",
        default,
        converter=_optional if default is None else _f64,
        at_least=0.0,
        kw_only=True,
    )


def _restitution(optional: bool = False):
    return quantity(
        "dimensionless",
        "Coefficient of restitution ``e`` in (0, 1] that the contact model reproduces for an "
        "impact at ``impact_speed`` (1: no damping, the energy is kept).",
        *((None,) if optional else ()),
        converter=_optional if optional else _f64,
        above=0.0,
        kw_only=True,
    )


def _impact_speed():
    return quantity(
        "velocity",
        "The impact speed ``v_ref`` for which the damping gives the restitution ``e`` "
        "(``delta_dot(-)`` of the papers, a constant here: the damping coefficient is "
        "``c(e) K / v_ref``). Required where ``restitution < 1``.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )


def _contact_model(default):
    return option(
        "The damping model: ``lankarani_nikravesh`` (1990, for ``e`` near 1, default), "
        "``flores`` (Flores et al. 2011, any ``e``, low restitution included) or "
        "``hunt_crossley`` (1975).",
        default,
        choices=tuple(DAMPING_FACTORS) if default is not None else (None, *DAMPING_FACTORS),
        kw_only=True,
    )


def _mu():
    return quantity(
        "dimensionless",
        "Coulomb friction coefficient at the contact (>= 0); default none (no friction, no "
        "friction column).",
        None,
        converter=_optional,
        at_least=0.0,
        kw_only=True,
    )


def _v_stick():
    return quantity(
        "velocity",
        "Friction's regularization speed: the friction is ``-mu F tanh(v_t / v_stick)``. "
        "Required with ``mu``.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )


def _check_law(e, name: str) -> None:
    """The checks of a contact law's numbers that their declared ranges do not make."""
    if e.poisson is not None and not np.all(np.asarray(e.poisson) < 0.5):
        raise ModelError("Poisson's ratio must be below 0.5", name, field="poisson")
    if e.restitution is None:
        return
    r = np.asarray(e.restitution)
    if not np.all(r <= 1.0):
        raise ModelError(
            f"the coefficient of restitution must be in (0, 1], got {r.tolist()}",
            name,
            field="restitution",
        )
    if e.impact_speed is None and not np.all(r == 1.0):
        raise ModelError(
            "a contact that loses energy (restitution < 1) needs the impact speed for which "
            "its damping gives that restitution: give impact_speed (e.g. the relative speed "
            "of a typical impact)",
            name,
            field="impact_speed",
        )
    if e.mu is not None and e.v_stick is None:
        raise ModelError(
            "friction needs its regularization speed v_stick (e.g. 1 mm/s)", name, field="v_stick"
        )


class _Compliant(ForceElement):
    """A compliant contact between body i and body j: a subclass gives the penetration
    ``delta(q)`` [length], the contact point and the tangent (:meth:`frame`) and the
    effective radius ``R*`` of Hertz's stiffness (:meth:`effective_radius`)."""

    young_modulus: jax.Array = _young_modulus()
    poisson: jax.Array = _poisson(0.3)
    restitution: jax.Array = _restitution()
    impact_speed: jax.Array | None = _impact_speed()
    contact_model: str = _contact_model("lankarani_nikravesh")
    mu: jax.Array | None = _mu()
    v_stick: jax.Array | None = _v_stick()
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: jax.Array | None = eqx.field(default=None, kw_only=True)
    sj: jax.Array | None = eqx.field(default=None, kw_only=True)

    def __check_init__(self):
        _check_law(self, self.name)

    def body_indices(self):
        return moving(self.bi, self.bj)

    # what a shape pair gives
    def penetration(self, q) -> jax.Array:
        """``delta(q)`` [length]: positive in contact, negative the gap; a scalar, or (k,)
        for a pair that touches at k places (a slider's corners)."""
        raise NotImplementedError

    def frame(self, q) -> tuple[jax.Array, jax.Array]:
        """``(P, n)``: the contact point (2,) [length] and the unit normal (2,) along which
        the contact pushes body j; (k, 2) each for k places."""
        raise NotImplementedError

    def effective_radius(self) -> jax.Array:
        """Hertz's effective radius ``R*`` of the pair [length]."""
        raise NotImplementedError

    # the law
    @property
    def stiffness(self) -> jax.Array:
        """Hertz's stiffness ``K`` [force / length**1.5]."""
        return hertz_stiffness(self.young_modulus, self.poisson, self.effective_radius())

    def _sliding(self, q, qd):
        """The sliding speeds of j on i at the contact points, along ``z x n`` (k,)
        [velocity]."""
        P, n = (jnp.atleast_2d(x) for x in self.frame(q))
        t = jnp.stack([-n[:, 1], n[:, 0]], axis=1)

        def one(P, t):
            return jnp.dot(_velocity(q, qd, self.bj, P) - _velocity(q, qd, self.bi, P), t)

        return jax.vmap(one)(P, t)

    def _delta(self, q):
        return jnp.atleast_1d(self.penetration(q))

    def _state(self, q, qd):
        """``(delta (k,), d delta / dq (k, nq), F (k,), F_t (k,) or None)`` at the state."""
        delta = self._delta(q)
        J = jax.jacfwd(self._delta)(q)
        speed = 1.0 if self.impact_speed is None else self.impact_speed
        F = normal_force(delta, J @ qd, self.stiffness, self.restitution, speed, self.contact_model)
        if self.mu is None:
            return delta, J, F, None
        return delta, J, F, friction_force(F, self._sliding(q, qd), self.mu, self.v_stick)

    def passive(self, q, qd, t, nq):
        """The contact's generalized force (nq,): evaluated where a penetration is positive,
        zero without computing it elsewhere (a narrow phase that costs one penetration while
        the pair is apart)."""

        def touching(q, qd):
            _, J, F, Ft = self._state(q, qd)
            Q = -F @ J
            if Ft is not None:
                Q = Q + Ft @ jax.jacfwd(self._sliding, argnums=1)(q, qd)
            return Q

        def apart(q, qd):
            return jnp.zeros(nq, dtype=jnp.result_type(q, qd))

        return jax.lax.cond(jnp.any(self._delta(q) > 0.0), touching, apart, q, qd)

    def potential(self, q):
        """The elastic energy ``K delta**2.5 / 2.5`` [energy], summed over the contact
        points (the damping and the friction count as non-conservative work)."""
        return jnp.sum(elastic_energy(self._delta(q), self.stiffness))

    def outputs(self, q, qd, t):
        """``normal``: the normal force [force] (>= 0); ``penetration`` [length] (negative:
        the gap); ``friction``: the friction force on body j along ``z x n`` [force], where
        ``mu`` is given. For several contact points: the sum of the forces and the deepest
        penetration."""
        delta, _, F, Ft = self._state(q, qd)
        out = {"normal": jnp.sum(F), "penetration": jnp.max(delta)}
        if Ft is not None:
            out["friction"] = jnp.sum(Ft)
        return out

    def drawing(self) -> dict:
        """What an animation draws of the contact's shapes (as a joint's
        :meth:`~mixdyn.Joint.drawing`): ``circles`` [(body, body point, radius)], ``guides``
        [(ground point, direction)] (lines on the ground)."""
        return {}

    def arrow(self, q, qd) -> tuple[np.ndarray, np.ndarray]:
        """The contact's force on body j as an arrow: ``(at, F)``, the contact point (N, 2)
        [length] (of the largest force, where the pair touches at several) and the force
        (N, 2) [force] (normal and friction, summed over the contact points), from the
        coordinates ``q`` and velocities ``qd`` (N, nq)."""

        def one(q, qd):
            _, _, F, Ft = self._state(q, qd)
            P, n = (jnp.atleast_2d(x) for x in self.frame(q))
            force = F[:, None] * n
            if Ft is not None:
                force = force + Ft[:, None] * jnp.stack([-n[:, 1], n[:, 0]], axis=1)
            return P[jnp.argmax(F)], jnp.sum(force, axis=0)

        at, F = jax.vmap(one)(jnp.asarray(q), jnp.asarray(qd))
        return np.asarray(at), np.asarray(F)

    @property
    def output_kinds(self):
        kinds = {"normal": "force", "penetration": "length"}
        if self.mu is not None:
            kinds["friction"] = "force"
        return kinds


# --------------------------------------------------------------------------- shape pairs
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
        bj, sj = r.point(self.center, self.name)
        bi, si = r.point(self.line_point, self.name)
        if bi == bj:
            raise ModelError(
                f"the circle and the line are both on {body_name(self.center)!r}: they must "
                "be on two different bodies",
                self.name,
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
        bj, sj = r.point(self.center, self.name)
        bi, si = r.point(self.line_point, self.name)
        if bi == bj:
            raise ModelError(
                f"the box and the line are both on {body_name(self.center)!r}: they must be "
                "on two different bodies",
                self.name,
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
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError(
                f"both circles are on {body_name(self.point_i)!r}: they must be on two "
                "different bodies",
                self.name,
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

    def bind(self, r: Resolver):
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError(
                f"the journal and the bearing are both on {body_name(self.point_i)!r}: they "
                "must be on two different bodies",
                self.name,
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
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError(
                f"the slider and the guide are both on {body_name(self.point_i)!r}: they must "
                "be on two different bodies",
                self.name,
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


# --------------------------------------------------------------------------- the model's use
#: The contact numbers of a joint with clearance, as its contact element names them.
LAW_FIELDS = (
    "young_modulus",
    "poisson",
    "restitution",
    "impact_speed",
    "contact_model",
    "mu",
    "v_stick",
)

#: The joint classes' names that take a ``clearance``: the contact element that replaces
#: such a joint, and the fields of its geometry besides the clearance.
CLEARANCE_JOINTS = {
    "Revolute": ("JournalBearing", ("journal_radius",)),
    "Translational": ("SliderInGuide", ("slider_length", "corner_radius")),
}


def clearance_contacts(joints) -> tuple[tuple, tuple]:
    """``(joints, contacts)``: the joints without those that have a ``clearance``, and the
    contact element of each one's name, points and numbers (a revolute joint's
    :class:`JournalBearing`, a translational joint's :class:`SliderInGuide`; called by the
    model)."""
    kept, made = [], []
    for j in joints:
        entry = CLEARANCE_JOINTS.get(type(j).__name__)
        if entry is None or j.clearance is None:
            kept.append(j)
            continue
        cls, geometry = entry
        fields = ("clearance", *geometry, *LAW_FIELDS)
        given = {f: getattr(j, f) for f in fields if getattr(j, f) is not None}
        if cls == "SliderInGuide":
            given |= {"axis": j.axis, "angle": j.angle}
        made.append(globals()[cls](j.name, j.point_i, j.point_j, **given))
    return tuple(kept), tuple(made)


def check_clearance(joint, geometry: tuple[str, ...]) -> None:
    """The checks of a joint's clearance fields (its ``__check_init__``): a clearance needs
    the numbers of its ``geometry`` (a journal's radius), the material and the restitution;
    contact numbers need a clearance."""
    given = [f for f in (*geometry, *LAW_FIELDS) if getattr(joint, f) is not None]
    if joint.clearance is None:
        if given:
            raise ModelError(
                f"{', '.join(given)} describe a clearance's contact: give the joint a "
                "clearance (e.g. clearance: 0.5 mm) or leave them out",
                joint.name,
                field=given[0],
            )
        return
    for f in (*geometry, "young_modulus", "restitution"):
        if getattr(joint, f) is None:
            raise ModelError(
                f"a joint with clearance is a contact: give its {f} ("
                + ", ".join((*geometry, "young_modulus", "restitution"))
                + "; impact_speed where restitution < 1)",
                joint.name,
                field=f,
            )
    _check_law(joint, joint.name)


def contacts(model) -> tuple[_Compliant, ...]:
    """The model's compliant contacts (its clearance joints included)."""
    return tuple(f for f in model.forces if isinstance(f, _Compliant))


def refuse_contacts(model, analysis: str) -> None:
    """Raise a :class:`~mixdyn.errors.ModelError` naming the first contact of ``model``: a
    ``analysis`` (kinematic or inverse) run prescribes the whole motion, and a contact's
    force follows from a motion that no driver fixes."""
    found = contacts(model)
    if not found:
        return
    c = found[0]
    what = (
        "a revolute joint with clearance (a journal in a bearing)"
        if isinstance(c, JournalBearing)
        else f"a compliant contact ({type(c).__name__})"
    )
    article = "an" if analysis[0] in "aeiou" else "a"
    raise ModelError(
        f"is {what}: {article} {analysis} analysis prescribes the whole motion, while a "
        "contact's force decides how the bodies move; run a forward or mixed analysis "
        "(prescribe the driven motions, seek their efforts)"
        + (", or give the joint no clearance" if isinstance(c, JournalBearing) else ""),
        c.name,
    )


__all__ = [
    "CLEARANCE_JOINTS",
    "LAW_FIELDS",
    "BoxLineContact",
    "CircleContact",
    "CircleLineContact",
    "JournalBearing",
    "SliderInGuide",
    "check_clearance",
    "clearance_contacts",
    "contacts",
    "refuse_contacts",
]
