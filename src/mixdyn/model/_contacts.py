"""Joints of bodies that touch along pitch curves: gear pairs, rack and pinion, a disk rolling
on a line, two disks rolling on each other (all without slipping).

No slip is written at the position level on the angle ``theta`` of the line of centres, so
that the constraint force is the physical contact force: for two wheels of pitch radii
``R_i``, ``R_j`` whose centres are ``d = c_j - c_i`` apart (``e = d / |d|``,
``t = z x e``), the pitch points' tangential velocities match when
``R_i (phi_i - theta) + s R_j (phi_j - theta) = const`` (``s = +1`` external, ``-1``
internal with body i the ring), whose Jacobian gives body j a force ``lambda t`` at the pitch
point (Willis: ``(w_j - w_c) / (w_i - w_c) = -s R_i / R_j`` for centres fixed on a carrier
``c``). ``theta`` is measured from the line of centres at the bodies' rough start ``q0`` in
the carrier's frame, so it is continuous while the line of centres turns less than half a turn
relative to the carrier from there (always, for centres fixed on it). The constants of the
equations come from the bodies' ``q0``: give the bodies the angles at which their teeth (or
marks) mesh. Lines (rack, rolling track) are straight, fixed in a body (or the ground).

Teeth (gear pair, rack and pinion) push along their line of action, at the pressure angle
``alpha`` to the pitch line: besides the tangential force ``Ft`` that the no-slip equation
transmits, a separating force ``Fr = |Ft| tan(alpha)`` pushes the pitch curves apart, along
the line of centres (the normal of the rack), whichever way the torque goes. The centres are
held apart by other joints (pins on the ground or a carrier, a rack's guide), so this force
does no work and leaves the motion as it is: it loads those joints. Their reactions carry it
(:func:`~mixdyn.analysis._reactions.joint_reactions`), so that a gear on a pin loads the pin
with the whole tooth force ``|Fn| = |Ft| / cos(alpha)``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._declare import direction, element, option, quantity, reference
from ._element import Resolver, body_name, moving
from ._geometry import GROUND, angle, cross, point, rot, vector
from ._joints import _UNBOUND, Joint, _f64


def _start(r: Resolver, b: int, s) -> tuple[np.ndarray, float]:
    """Global position of body point ``s`` and the body's angle at the rough start ``q0``."""
    s = np.asarray(s, dtype=float)
    if b == GROUND:
        return s, 0.0
    x, y, phi = (float(v) for v in np.asarray(r._body_objs[b].q0))
    c, sn = math.cos(phi), math.sin(phi)
    return np.array([x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]]), phi


def _np_point(q, b: int, s) -> np.ndarray:
    """Global position (2,) of body point ``s`` at NumPy positions ``q`` (nq,)."""
    s = np.asarray(s, dtype=float)
    if b == GROUND:
        return s
    x, y, phi = (float(v) for v in q[3 * b : 3 * b + 3])
    c, sn = math.cos(phi), math.sin(phi)
    return np.array([x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]])


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


#: The tooth-force columns of a mesh (gears, rack) and their kinds.
TOOTH_KINDS = {"Ft": "force", "Fn": "force", "Fr": "force"}


def _pressure_angle():
    """The declaration of a mesh's pressure angle."""
    return quantity(
        "angle",
        'Pressure angle (or ``"20 deg"``), below 90 degrees. Default 20 degrees.',
        math.radians(20.0),
        converter=_f64,
        at_least=0.0,
        file_default="20 deg",
    )


def _check_pressure_angle(joint) -> None:
    if not np.all(np.asarray(joint.pressure_angle) < math.pi / 2):
        raise ModelError(
            "the pressure angle must be in [0, 90) degrees", joint.name, field="pressure_angle"
        )


def _tooth(Ft, pressure_angle) -> dict:
    """A mesh's columns from its tangential tooth force ``Ft``: the force along the line of
    action ``Fn`` and the radial (separating) force ``Fr``."""
    return {
        "Ft": Ft,
        "Fn": Ft / jnp.cos(pressure_angle),
        "Fr": jnp.abs(Ft) * jnp.tan(pressure_angle),
    }


class _Wheels(Joint):
    """Two wheels (pitch circles of radii ``radius_i``, ``radius_j`` about body points
    ``center_i``, ``center_j``) meshing or rolling, on a carrier body (default the ground)."""

    body_i: str = reference("Body i (the ring, if ``internal``).", what="body")
    body_j: str = reference("Body j (another body).", what="body")
    radius_i: object = quantity(
        "length",
        'Pitch (or rolling) radius of body i, > 0, e.g. ``"40 mm"``.',
        converter=_f64,
        above=0.0,
    )
    radius_j: object = quantity(
        "length", "Pitch (or rolling) radius of body j, > 0.", converter=_f64, above=0.0
    )
    internal: bool = option(
        "True for body j inside the ring of body i (``radius_i > radius_j``). Default false.",
        False,
    )
    carrier: str = reference(
        "The body holding both centres (a planet carrier); default the ground.",
        what="body",
        default="ground",
    )
    center_i: str | None = reference(
        "Centre of body i's wheel, ``body_i.point`` (default: its origin).", default=None
    )
    center_j: str | None = reference(
        "Centre of body j's wheel, ``body_j.point`` (default: its origin).", default=None
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bc: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: object = eqx.field(default=None, kw_only=True)
    sj: object = eqx.field(default=None, kw_only=True)
    e0: object = eqx.field(default=None, kw_only=True)  # line of centres at q0, carrier frame
    # The wheels' angles from the line of centres at q0 (2,) [rad]: the no-slip constant
    # (c0) is made from them and the radii where it is used, so that a radius varied by a
    # study (a sweep, a fit) gives the constant of a model built with it.
    a0: object = eqx.field(default=None, kw_only=True)
    body_fields: ClassVar[tuple[str, ...]] = ("bi", "bj", "bc")
    generic_reaction: ClassVar[bool] = False

    def __check_init__(self):
        if self.internal and not np.all(np.asarray(self.radius_i) > np.asarray(self.radius_j)):
            raise ModelError(
                f"an internal pair needs body i as the ring, radius_i > radius_j (got "
                f"{np.asarray(self.radius_i).tolist()} and {np.asarray(self.radius_j).tolist()})",
                self.name,
                field="radius_i",
            )

    @property
    def _s(self) -> float:
        return -1.0 if self.internal else 1.0

    def bind(self, r: Resolver):
        bi, si = r.point(self.center_i or self.body_i, self.name)
        bj, sj = r.point(self.center_j or self.body_j, self.name)
        bc = r.body(self.carrier, self.name)
        if bi == bj:
            raise ModelError(
                f"both wheels are on {body_name(self.center_i or self.body_i)!r}: a wheel pair "
                "needs two different bodies",
                self.name,
            )
        ci, phi_i = _start(r, bi, si)
        cj, phi_j = _start(r, bj, sj)
        _, phi_c = _start(r, bc, np.zeros(2))
        d = cj - ci
        if not np.linalg.norm(d) > 0:
            raise ModelError(
                "the wheels' centres coincide at the start q0; place them apart "
                "by the sum (external) or difference (internal) of the radii",
                self.name,
            )
        theta = math.atan2(d[1], d[0])
        c, s = math.cos(phi_c), math.sin(phi_c)
        e0 = np.array([[c, s], [-s, c]]) @ (d / np.linalg.norm(d))
        a0 = np.array([phi_i - theta, phi_j - theta])
        return dataclasses.replace(
            self, bi=bi, bj=bj, bc=bc, si=si, sj=sj, e0=_f64(e0), a0=_f64(a0)
        )

    @property
    def c0(self):
        """The no-slip constant ``R_i (phi_i - theta) + s R_j (phi_j - theta)`` at the rough
        start [length * rad], from the radii as they are (numbers or traced)."""
        return self.radius_i * self.a0[0] + self._s * self.radius_j * self.a0[1]

    def body_indices(self):
        return moving(self.bi, self.bj, self.bc)

    def reaction_point(self):
        return self.bj, self.sj

    def _d(self, q):
        return point(q, self.bj, self.sj) - point(q, self.bi, self.si)

    def theta(self, q):
        """Angle of the line of centres [rad], continuous from its start (see the module)."""
        dc = rot(angle(q, self.bc)).T @ self._d(q)
        e0 = self.e0
        rel = jnp.arctan2(cross(e0, dc), jnp.dot(e0, dc))
        return angle(q, self.bc) + jnp.arctan2(e0[1], e0[0]) + rel

    def _no_slip(self, q):
        th = self.theta(q)
        return (
            self.radius_i * (angle(q, self.bi) - th)
            + self._s * self.radius_j * (angle(q, self.bj) - th)
            - self.c0
        )

    def drawing(self):
        return {"circles": [(self.bi, self.si, self.radius_i), (self.bj, self.sj, self.radius_j)]}

    def _frame(self, q):
        """The pitch point (2,) and the unit vectors ``e`` (i's centre to j's) and ``t``."""
        d = self._d(q)
        e = d / jnp.linalg.norm(d)
        return point(q, self.bi, self.si) + self.radius_i * e, e, jnp.stack([-e[1], e[0]])

    def arrow(self, q, cols):
        P, e, t = jax.vmap(self._frame)(jnp.asarray(q))
        if "Ft" in self.contact_kinds:  # the tooth force on gear j, along the line of action
            Ft = np.asarray(cols[f"{self.name}.Ft"])[:, None]
            Fr = np.asarray(cols[f"{self.name}.Fr"])[:, None]
            F = Ft * np.asarray(t) + self._s * Fr * np.asarray(e)
        else:
            N = np.asarray(cols[f"{self.name}.N"])[:, None]
            T = np.asarray(cols[f"{self.name}.T"])[:, None]
            F = N * self._s * np.asarray(e) + T * np.asarray(t)
        return np.asarray(P), F


@element("gear_pair", "joints")
class GearPair(_Wheels):
    """A pair of spur gears (external, or internal with body i the ring gear), pitch radii
    ``radius_i``, ``radius_j`` [length] about ``center_i``, ``center_j`` (default: the bodies'
    origins), the centres held by other joints (pins on the ground or on a carrier).

    Equation (1): no slip at the pitch point (see the module), so
    ``(w_j - w_c) / (w_i - w_c) = -R_i / R_j`` (external) or ``+R_i / R_j`` (internal).
    Result columns: ``{name}.Ft`` the tangential tooth force on gear j [force], along
    ``t = z x e`` (``e``: from i's centre to j's); ``.Fn = Ft / cos(pressure_angle)``, the
    tooth force along the line of action; ``.Fr = |Ft| tan(pressure_angle)``, its radial
    part, pushing gear j away from gear i's teeth (along ``e`` external, ``-e`` internal) and
    gear i the other way. The tooth force on gear j is ``Ft t +- Fr e``, of magnitude ``|Fn|``:
    the joints that hold the centres (their pins) carry all of it, the radial part included
    (see the module).
    """

    pressure_angle: object = _pressure_angle()
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("mesh",)
    contact_kinds: ClassVar[dict[str, str]] = TOOTH_KINDS
    #: What pushes along the line of centres (a mesh's separation, see the module).
    along_centres: ClassVar[str] = (
        "the teeth push the pitch curves apart with the radial force |Ft| tan(pressure angle)"
    )

    def __check_init__(self):
        _check_pressure_angle(self)

    def residual(self, q):
        return self._no_slip(q)[None]

    def contact(self, q, lam):
        L = (self.radius_i + self._s * self.radius_j) / jnp.linalg.norm(self._d(q))
        return _tooth(lam[0] * L, self.pressure_angle)

    def separation(self, q):
        """The distance that the radial tooth force ``Fr`` pushes to grow: the centres'
        distance, negated for an internal pair (the pinion pushed towards the ring's centre)
        [length]; ``Fr`` times its gradient is the radial force pair's generalized force."""
        return self._s * jnp.linalg.norm(self._d(q))

    def separating_pair(self, q) -> tuple:
        """The unit separating force pair at NumPy positions ``q`` (nq,): ``(body, point (2,),
        force (2,))`` per body, the forces (unit and opposite) at the centres, along the line
        of centres; its generalized force is the gradient of :meth:`separation`."""
        ci, cj = _np_point(q, self.bi, self.si), _np_point(q, self.bj, self.sj)
        e = (cj - ci) / np.linalg.norm(cj - ci)
        return ((self.bj, cj, self._s * e), (self.bi, ci, -self._s * e))


@element("rolling_disks", "joints")
class RollingDisks(_Wheels):
    """Two disks rolling on each other without slipping: external, or disk j inside the ring
    of body i (``internal``). Equations (2): the centres ``R_i + R_j`` (or ``R_i - R_j``)
    apart, and no slip. Result columns: ``{name}.N`` the normal force on disk j pushing it off
    body i (positive while they press together) and ``{name}.T`` the tangential (friction)
    force on j along ``t = z x e`` [force].
    """

    n_equations: ClassVar[int] = 2
    equation_labels: ClassVar[tuple[str, ...]] = ("contact", "no_slip")
    contact_kinds: ClassVar[dict[str, str]] = {"N": "force", "T": "force"}
    #: The contact column that must stay positive (the bodies only press).
    unilateral: ClassVar[str] = "N"

    def residual(self, q):
        gap = jnp.linalg.norm(self._d(q)) - (self.radius_i + self._s * self.radius_j)
        return jnp.stack([gap, self._no_slip(q)])

    def contact(self, q, lam):
        L = (self.radius_i + self._s * self.radius_j) / jnp.linalg.norm(self._d(q))
        return {"N": -self._s * lam[0], "T": lam[1] * L}


@element("belt_drive", "joints")
class BeltDrive(_Wheels):
    """A belt (or chain) drive: an endless belt around two pulleys, open or crossed, the
    pulleys' centres held by other joints (pins on the ground or on a carrier).

    Equation (1): the belt does not slip on either pulley: the no-slip equation of two wheels
    (see the module) with ``s = -1`` (open: the pulleys turn the same way,
    ``w_j / w_i = R_i / R_j`` relative to the carrier) or ``s = +1`` (crossed: opposite ways).
    Its multiplier is the tension difference ``F = T_tight - T_slack`` [force] (up to its
    sign), whose torques ``R F`` drive the pulleys.

    Result columns [force]: ``{name}.F`` the tension difference (signed: positive when the
    torque it exerts on pulley j turns j like ``-s`` times its positive angle);
    ``.T_tight`` and ``.T_slack`` the spans' tensions; ``.Fr`` the spans' pull on pulley j
    along the line of centres, away from pulley i (negative: the belt pulls the pulleys
    together), the opposite on pulley i. The spans' tensions follow from ``initial_tension``
    ``T0``: a belt whose length does not change keeps ``T_tight + T_slack = 2 T0``, so
    ``T_tight = T0 + |F| / 2`` and ``T_slack = T0 - |F| / 2``; with ``T0 = 0`` (a chain, or a
    belt taken at the least tension that drives) the slack span carries nothing,
    ``T_tight = |F|``. Both spans leave the pulleys at the angle ``beta`` to the line of
    centres (``sin beta = (R_i + s R_j) / d``, ``d`` the centres' distance), so they pull the
    centres together with ``(T_tight + T_slack) cos beta`` (carried by the pins, as a gear's
    radial tooth force: see the module) and across it with ``F sin beta`` (the no-slip
    equation's own force). A slack span whose tension would fall below zero (``|F| > 2 T0``)
    means the belt slips: the run stops there (:class:`~mixdyn.errors.ContactLostError`).
    """

    body_i: str = reference(
        "Pulley i: a body, its centre at the body's origin, held by a revolute joint.",
        what="body",
    )
    body_j: str = reference("Pulley j: another body, held the same way.", what="body")
    radius_i: object = quantity("length", "Pitch radius of pulley i.", converter=_f64, above=0.0)
    radius_j: object = quantity("length", "Pitch radius of pulley j.", converter=_f64, above=0.0)
    crossed: bool = option(
        "A crossed belt: the pulleys turn opposite ways (default: open, the same way).", False
    )
    initial_tension: object = quantity(
        "force",
        "The belt's tension at rest ``T0`` (each span); 0 (the default): a chain, whose "
        "slack span carries nothing.",
        0.0,
        converter=_f64,
        at_least=0.0,
    )
    # Not fields of a file: a belt's pulleys turn about their bodies' origins, on the ground
    # or a carrier given in Python; an open or crossed belt, not an internal pair.
    internal: bool = eqx.field(static=True, default=False)
    carrier: str = eqx.field(static=True, default="ground")
    center_i: str | None = eqx.field(static=True, default=None)
    center_j: str | None = eqx.field(static=True, default=None)
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("belt",)
    contact_kinds: ClassVar[dict[str, str]] = {
        "F": "force",
        "T_tight": "force",
        "T_slack": "force",
        "Fr": "force",
    }
    #: The column that must stay at or above zero (a slack span cannot push).
    unilateral: ClassVar[str] = "T_slack"
    #: What pulls along the line of centres (see :class:`GearPair`).
    along_centres: ClassVar[str] = "the belt's spans pull the pulleys together"

    @property
    def _s(self) -> float:
        return 1.0 if self.crossed else -1.0

    def residual(self, q):
        return self._no_slip(q)[None]

    def contact(self, q, lam):
        F = lam[0]
        T0 = self.initial_tension
        preloaded = T0 > 0.0
        tight = jnp.where(preloaded, T0 + 0.5 * jnp.abs(F), jnp.abs(F))
        slack = jnp.where(preloaded, T0 - 0.5 * jnp.abs(F), 0.0)
        sin_beta = (self.radius_i + self._s * self.radius_j) / jnp.linalg.norm(self._d(q))
        cos_beta = jnp.sqrt(jnp.maximum(1.0 - sin_beta**2, 0.0))
        return {"F": F, "T_tight": tight, "T_slack": slack, "Fr": -(tight + slack) * cos_beta}

    def separation(self, q):
        """The centres' distance [length]: the spans' pull ``Fr`` (negative) times its
        gradient is the pull's generalized force (see :class:`GearPair`)."""
        return jnp.linalg.norm(self._d(q))

    def separating_pair(self, q) -> tuple:
        """The unit pair along the line of centres at NumPy positions ``q`` (nq,): ``(body,
        point (2,), force (2,))`` per pulley, pushing the centres apart."""
        ci, cj = _np_point(q, self.bi, self.si), _np_point(q, self.bj, self.sj)
        e = (cj - ci) / np.linalg.norm(cj - ci)
        return ((self.bj, cj, e), (self.bi, ci, -e))

    def arrow(self, q, cols):
        """The belt's force on pulley j at its centre: the pull along the line of centres
        and the tension difference's part across it."""
        q = jnp.asarray(q)
        cj = jax.vmap(lambda x: point(x, self.bj, self.sj))(q)
        _, e, t = jax.vmap(self._frame)(q)
        d = np.linalg.norm(np.asarray(jax.vmap(self._d)(q)), axis=1)
        sin_beta = (float(self.radius_i) + self._s * float(self.radius_j)) / d
        F = np.asarray(cols[f"{self.name}.F"]) * sin_beta
        Fr = np.asarray(cols[f"{self.name}.Fr"])
        return np.asarray(cj), Fr[:, None] * np.asarray(e) + F[:, None] * np.asarray(t)


class _OnLine(Joint):
    """A wheel (body i, pitch radius ``radius`` about ``center``) on a straight line of body j
    through ``line_point`` with direction ``axis`` (body j's frame); the wheel on the side of
    the line it starts on (at ``q0``)."""

    wheel: str = reference("The body of the wheel (pinion, disk).", what="body")
    line_point: str = reference(
        "A point of the line (rack's pitch line, track), ``body.point`` or ``ground.point``."
    )
    radius: object = quantity(
        "length", "Pitch (rolling) radius of the wheel, > 0.", converter=_f64, above=0.0
    )
    axis: str | tuple[float, ...] = direction(
        "Direction of the line in its body's frame: ``[x, y]`` or a vector's name. Default "
        "``[1, 0]``.",
        (1.0, 0.0),
        on="line_point",
    )
    center: str | None = reference(
        "Centre of the wheel, ``wheel.point`` (default: the wheel body's origin).", default=None
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: object = eqx.field(default=None, kw_only=True)
    sj: object = eqx.field(default=None, kw_only=True)
    u: object = eqx.field(default=None, kw_only=True)
    side: float = eqx.field(static=True, default=1.0, kw_only=True)
    # The centre's position along the line [length] and the angle of the wheel relative to
    # the line's body [rad] at q0 (2,): the no-slip constant (c0) is made from them and the
    # radius where it is used (a varied radius gives the constant of a model built with it).
    a0: object = eqx.field(default=None, kw_only=True)
    body_fields: ClassVar[tuple[str, ...]] = ("bi", "bj")
    generic_reaction: ClassVar[bool] = False

    def bind(self, r: Resolver):
        bi, si = r.point(self.center or self.wheel, self.name)
        if bi == GROUND:
            field = "center" if self.center else "wheel"
            raise ModelError("the wheel cannot be on the ground", self.name, field=field)
        bj, sj = r.point(self.line_point, self.name)
        if bi == bj:
            raise ModelError(
                "the wheel and its line are on the same body: they must be on two different bodies",
                self.name,
            )
        u = r.vector(self.axis, bj, self.name)
        ci, phi_i = _start(r, bi, si)
        pj, phi_j = _start(r, bj, sj)
        c, s = math.cos(phi_j), math.sin(phi_j)
        ug = np.array([[c, -s], [s, c]]) @ np.asarray(u)
        n = np.array([-ug[1], ug[0]])
        h = float(np.dot(ci - pj, n))
        if abs(h) < 1e-12 * max(1.0, float(np.abs(ci).max())):
            raise ModelError(
                "the wheel's centre starts on the line; place it on one side, a radius away",
                self.name,
            )
        side = 1.0 if h > 0 else -1.0
        a0 = np.array([float(np.dot(ci - pj, ug)), phi_i - phi_j])
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj, u=u, side=side, a0=_f64(a0))

    @property
    def c0(self):
        """The no-slip constant ``x + side R (phi_i - phi_j)`` at the rough start [length],
        from the radius as it is (a number or traced)."""
        return self.a0[0] + self.side * self.radius * self.a0[1]

    def body_indices(self):
        return moving(self.bi, self.bj)

    def reaction_point(self):
        return self.bi, self.si

    def _rel(self, q):
        return point(q, self.bi, self.si) - point(q, self.bj, self.sj)

    def _along(self, q):
        """Position of the centre along the line and the no-slip residual."""
        u = vector(q, self.bj, self.u)
        x = jnp.dot(self._rel(q), u)
        return x + self.side * self.radius * (angle(q, self.bi) - angle(q, self.bj)) - self.c0

    def _normal(self, q):
        u = vector(q, self.bj, self.u)
        n = jnp.stack([-u[1], u[0]])
        return jnp.dot(self._rel(q), n) - self.side * self.radius

    def _contact_point(self, q):
        u = vector(q, self.bj, self.u)
        n = jnp.stack([-u[1], u[0]])
        return point(q, self.bi, self.si) - self.side * self.radius * n, u, n

    def arrow(self, q, cols):
        """The force on the wheel at its contact point."""
        P, u, n = (np.asarray(a) for a in jax.vmap(self._contact_point)(jnp.asarray(q)))
        if "Ft" in self.contact_kinds:  # the rack's tooth force on the pinion: -Ft u, and Fr
            Ft = np.asarray(cols[f"{self.name}.Ft"])[:, None]  # away from the pitch line
            Fr = np.asarray(cols[f"{self.name}.Fr"])[:, None]
            F = -Ft * u + self.side * Fr * n
        else:
            N = np.asarray(cols[f"{self.name}.N"])[:, None]
            F = N * self.side * n + np.asarray(cols[f"{self.name}.T"])[:, None] * u
        return P, F

    def drawing(self):
        out = {"circles": [(self.bi, self.si, self.radius)]}
        if self.bj == GROUND:
            out["guides"] = [(np.asarray(self.sj), np.asarray(self.u))]
        return out


@element("rack_pinion", "joints")
class RackPinion(_OnLine):
    """A rack (body j, its pitch line through ``line_point`` along ``axis``) and a pinion
    (body i, pitch radius ``radius``), the pinion's centre held by other joints.

    Equation (1): no slip, ``x + side R (phi_i - phi_j) = const`` with ``x`` the pinion
    centre's position along the rack; the rack moves ``R`` per radian of the pinion.
    Result columns: ``{name}.Ft`` the tooth force on the rack along ``axis`` [force],
    ``.Fn = Ft / cos(pressure_angle)`` (along the line of action),
    ``.Fr = |Ft| tan(pressure_angle)``, the radial part, pushing the pinion's centre away from
    the pitch line and the rack the other way: the pinion's pin and the rack's guide carry it
    (see the module).
    """

    pressure_angle: object = _pressure_angle()
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("mesh",)
    contact_kinds: ClassVar[dict[str, str]] = TOOTH_KINDS
    #: What pushes along the line of centres (a mesh's separation, see the module).
    along_centres: ClassVar[str] = (
        "the teeth push the pitch curves apart with the radial force |Ft| tan(pressure angle)"
    )

    def __check_init__(self):
        _check_pressure_angle(self)

    def residual(self, q):
        return self._along(q)[None]

    def contact(self, q, lam):
        return _tooth(lam[0], self.pressure_angle)

    def separation(self, q):
        """The pinion centre's distance from the rack's pitch line [length], which the
        radial tooth force ``Fr`` pushes to grow (see :meth:`GearPair.separation`)."""
        return self.side * self._normal(q) + self.radius

    def separating_pair(self, q) -> tuple:
        """As :meth:`GearPair.separating_pair`: at the pinion's centre, along the rack's
        normal, the pinion pushed away from the pitch line and the rack the other way."""
        ci = _np_point(q, self.bi, self.si)
        phi = 0.0 if self.bj == GROUND else float(q[3 * self.bj + 2])
        c, s = math.cos(phi), math.sin(phi)
        u = np.array([[c, -s], [s, c]]) @ np.asarray(self.u, dtype=float)
        n = self.side * np.array([-u[1], u[0]])
        return ((self.bi, ci, n), (self.bj, ci, -n))


@element("rolling_on_line", "joints")
class RollingOnLine(_OnLine):
    """A disk (body i, radius ``radius``) rolling without slipping on a straight line of body
    j (a track, an incline: ``line_point``, ``axis``).

    Equations (2): the centre a radius from the line, and no slip. Result columns:
    ``{name}.N`` the normal force on the disk, away from the line (positive while it presses
    on it), and ``{name}.T`` the friction force on the disk along ``axis`` [force]: rolling
    needs a friction coefficient of at least ``|T| / N``.
    """

    n_equations: ClassVar[int] = 2
    equation_labels: ClassVar[tuple[str, ...]] = ("contact", "no_slip")
    contact_kinds: ClassVar[dict[str, str]] = {"N": "force", "T": "force"}
    #: The contact column that must stay positive (the bodies only press).
    unilateral: ClassVar[str] = "N"

    def residual(self, q):
        return jnp.stack([self._normal(q), self._along(q)])

    def contact(self, q, lam):
        return {"N": -self.side * lam[0], "T": -lam[1]}
