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
from ._geometry import GROUND, point, pose, vector


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
        """``delta(q)`` [length]: positive in contact, negative the gap."""
        raise NotImplementedError

    def frame(self, q) -> tuple[jax.Array, jax.Array]:
        """``(P, n)``: the contact point (2,) [length] and the unit normal (2,) along which
        the contact pushes body j."""
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
        """The sliding speed of j on i at the contact point, along ``z x n`` [velocity]."""
        P, n = self.frame(q)
        t = jnp.stack([-n[1], n[0]])
        return jnp.dot(_velocity(q, qd, self.bj, P) - _velocity(q, qd, self.bi, P), t)

    def _state(self, q, qd):
        """``(delta, grad delta (nq,), F, F_t)`` at the state."""
        delta, g = jax.value_and_grad(self.penetration)(q)
        speed = 1.0 if self.impact_speed is None else self.impact_speed
        F = normal_force(
            delta, jnp.dot(g, qd), self.stiffness, self.restitution, speed, self.contact_model
        )
        if self.mu is None:
            return delta, g, F, None
        return delta, g, F, friction_force(F, self._sliding(q, qd), self.mu, self.v_stick)

    def passive(self, q, qd, t, nq):
        _, g, F, Ft = self._state(q, qd)
        Q = -F * g
        if Ft is not None:
            Q = Q + Ft * jax.grad(self._sliding, argnums=1)(q, qd)
        return Q

    def potential(self, q):
        """The elastic energy ``K delta**2.5 / 2.5`` [energy] (the damping and the friction
        count as non-conservative work)."""
        return elastic_energy(self.penetration(q), self.stiffness)

    def outputs(self, q, qd, t):
        """``normal``: the normal force [force] (>= 0); ``penetration`` [length] (negative:
        the gap); ``friction``: the friction force on body j along ``z x n`` [force], where
        ``mu`` is given."""
        delta, _, F, Ft = self._state(q, qd)
        out = {"normal": F, "penetration": delta}
        if Ft is not None:
            out["friction"] = Ft
        return out

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
    ``.penetration`` and, with ``mu``, ``.friction``.
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


# --------------------------------------------------------------------------- the model's use
#: The revolute joint's fields that describe its clearance, as the journal bearing names them.
CLEARANCE_FIELDS = (
    "clearance",
    "journal_radius",
    "young_modulus",
    "poisson",
    "restitution",
    "impact_speed",
    "contact_model",
    "mu",
    "v_stick",
)


def clearance_contacts(joints) -> tuple[tuple, tuple]:
    """``(joints, bearings)``: the joints without the revolute joints that have a
    ``clearance``, and a :class:`JournalBearing` of each one's name, points and contact
    numbers (called by the model)."""
    from ._joints import Revolute

    kept, bearings = [], []
    for j in joints:
        if isinstance(j, Revolute) and j.clearance is not None:
            given = {f: getattr(j, f) for f in CLEARANCE_FIELDS if getattr(j, f) is not None}
            bearings.append(JournalBearing(j.name, j.point_i, j.point_j, **given))
        else:
            kept.append(j)
    return tuple(kept), tuple(bearings)


def check_clearance(joint) -> None:
    """The checks of a revolute joint's clearance fields (its ``__check_init__``): a
    clearance needs its journal's radius, the material and the restitution; contact numbers
    need a clearance."""
    given = [f for f in CLEARANCE_FIELDS[1:] if getattr(joint, f) is not None]
    if joint.clearance is None:
        if given:
            raise ModelError(
                f"{', '.join(given)} describe a clearance's contact: give the joint a "
                "clearance (e.g. clearance: 0.5 mm) or leave them out",
                joint.name,
                field=given[0],
            )
        return
    for f in ("journal_radius", "young_modulus", "restitution"):
        if getattr(joint, f) is None:
            raise ModelError(
                f"a revolute joint with clearance is a journal in a bearing: give its {f} "
                "(journal_radius, young_modulus and restitution; impact_speed where "
                "restitution < 1)",
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
    "CLEARANCE_FIELDS",
    "CircleContact",
    "CircleLineContact",
    "JournalBearing",
    "check_clearance",
    "clearance_contacts",
    "contacts",
    "refuse_contacts",
]
