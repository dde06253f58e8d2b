"""Joints: time-independent constraint equations ``Phi^K(q) = 0``.

Each joint connects body ``i`` and body ``j`` (either may be the ground) through points given by
reference, ``"body.point"``. Equations follow the planar textbooks (Nikravesh, *Computer-Aided
Analysis of Mechanical Systems*; Haug, *Computer-Aided Kinematics and Dynamics*).
Multipliers of these equations scale so that the constraint force on the bodies is
``-Phi_q^T lambda``; reactions are reported in physical terms by :mod:`mixdyn.analysis`.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from .._arrays import as_f64
from ..errors import ModelError
from . import _clearance
from . import _compliant as _c
from ._declare import direction, element, quantity, reference
from ._element import Element, Resolver, body_name, moving
from ._geometry import angle, cross, point, vector

_UNBOUND = -2


def _f64(x):
    return as_f64(x)


def _optional(x):
    return None if x is None else as_f64(x)


class Joint(Element):
    """Abstract joint between body ``i`` and body ``j``."""

    #: Number of scalar equations.
    n_equations: ClassVar[int]
    #: Labels of the equations, for messages (``"A.x"``).
    equation_labels: ClassVar[tuple[str, ...]]

    @abc.abstractmethod
    def residual(self, q: jax.Array) -> jax.Array:
        """The joint's equations ``Phi^K(q)``, shape (n_equations,)."""

    @abc.abstractmethod
    def reaction_point(self) -> tuple[int, jax.Array]:
        """``(body j, body-frame point)`` about which the reaction moment on body j is given."""

    @property
    def carries_moment(self) -> bool:
        """Whether the joint transmits a moment (about its reaction point)."""
        return False

    #: Whether the reaction on body j (``{name}.Fx``, ``.Fy``, ``.M``) is reported; contact
    #: joints (gears, rolling) report their contact forces instead (:meth:`contact`).
    generic_reaction: ClassVar[bool] = True
    #: The joint's own result columns ``{name}.{key}`` and their kinds of quantity.
    contact_kinds: ClassVar[dict[str, str]] = {}

    def contact(self, q, lam) -> dict:
        """The joint's own result columns (:attr:`contact_kinds`) from ``q`` and the
        multipliers of its equations ``lam`` (n_equations,)."""
        return {}

    def arrow(self, q, cols: dict):
        """A contact joint's force as an arrow: ``(at, F)``, the point (N, 2) [length] and
        the force (N, 2) [force] on its body j (or its wheel), from the coordinates ``q``
        (N, nq) and the result's columns; None for joints drawn by their reaction."""
        return None

    def drawing(self) -> dict:
        """What an animation draws of the joint: ``pins`` [(body, body point)], ``guides``
        [(ground point, direction)] (lines fixed on the ground), ``circles`` [(body, body
        point, radius)]."""
        return {}


class _TwoPoint(Joint):
    """A joint between point ``point_i`` of body i and ``point_j`` of body j (two different
    bodies)."""

    point_i: str = reference(
        "Point on body i: ``body.point``, ``body`` (centre of mass) or ``ground.point``."
    )
    point_j: str = reference("Point on body j (another body), coinciding with ``point_i``.")
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: jax.Array | None = eqx.field(default=None, kw_only=True)
    sj: jax.Array | None = eqx.field(default=None, kw_only=True)

    def _bind_points(self, r: Resolver) -> dict:
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError(
                f"both points are on {body_name(self.point_i)!r}: a joint must connect two "
                "different bodies",
                self.name,
            )
        return dict(bi=bi, bj=bj, si=si, sj=sj)

    def bind(self, r: Resolver):
        return dataclasses.replace(self, **self._bind_points(r))

    def body_indices(self):
        return moving(self.bi, self.bj)

    def reaction_point(self):
        return self.bj, self.sj

    def _d(self, q):
        """Vector from point i to point j, (2,) [length]."""
        return point(q, self.bj, self.sj) - point(q, self.bi, self.si)


@element("revolute", "joints")
class Revolute(_TwoPoint):
    """Revolute (pin) joint: point ``point_i`` of body i coincides with ``point_j`` of body j.

    Equations (2): ``r_j + A_j s_j - r_i - A_i s_i = 0``.

    With a ``clearance`` the joint is a journal (the pin, centre ``point_j``) in a bearing
    (centre ``point_i``): the model replaces its two equations by the compliant contact of
    a :class:`~mixdyn.JournalBearing` of the same name, numbers and result columns (the
    journal's free flight, impacts and continuous contact).
    """

    clearance: jax.Array | None = quantity(
        "length",
        'Radial clearance (bearing radius less journal radius), e.g. ``"0.5 mm"``: the joint '
        "becomes a journal in a bearing (a ``journal_bearing`` contact). Default none (an "
        "ideal pin).",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )
    journal_radius: jax.Array | None = quantity(
        "length",
        "With a clearance: the journal's (pin's) radius, > 0.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )
    young_modulus: jax.Array | None = _c._young_modulus(optional=True)
    poisson: jax.Array | None = _c._poisson(None)
    restitution: jax.Array | None = _c._restitution(optional=True)
    impact_speed: jax.Array | None = _c._impact_speed()
    contact_model: str | None = _c._contact_model(None)
    mu: jax.Array | None = _c._mu()
    v_stick: jax.Array | None = _c._v_stick()
    n_equations: ClassVar[int] = 2
    equation_labels: ClassVar[tuple[str, ...]] = ("x", "y")

    def __check_init__(self):
        _clearance.check_clearance(self, ("journal_radius",))

    def residual(self, q):
        return self._d(q)

    def drawing(self):
        return {"pins": [(self.bj, self.sj)]}


@element("weld", "joints")
class Weld(_TwoPoint):
    """Rigid (weld) joint: points coincide and the relative angle is fixed.

    Equations (3): the revolute's two, and ``phi_j - phi_i - angle = 0``.
    """

    angle: jax.Array = quantity(
        "angle",
        'Fixed relative angle ``phi_j - phi_i`` (or with a unit, ``"30 deg"``). Default 0.',
        0.0,
        converter=_f64,
    )
    n_equations: ClassVar[int] = 3
    equation_labels: ClassVar[tuple[str, ...]] = ("x", "y", "angle")

    def residual(self, q):
        rel = angle(q, self.bj) - angle(q, self.bi) - self.angle
        return jnp.concatenate([self._d(q), rel[None]])

    @property
    def carries_moment(self):
        return True


@element("translational", "joints")
class Translational(_TwoPoint):
    """Translational (prismatic, sliding) joint along ``axis`` fixed in body i.

    Point ``point_j`` of body j moves on the line through ``point_i`` of body i with direction
    ``axis`` (body-i frame), and the relative angle stays ``angle``.

    Equations (2): ``u_i x (r_Pj - r_Pi) = 0`` (u_i the global unit axis) and
    ``phi_j - phi_i - angle = 0``.

    With a ``clearance`` the slider moves in a guide with a gap on each side: the model
    replaces the two equations by the contact of a :class:`~mixdyn.SliderInGuide` of the
    same name, points, axis and numbers.
    """

    point_i: str = reference(
        "Point of body i on the sliding line: ``body.point``, ``body`` or ``ground.point``."
    )
    point_j: str = reference("Point of body j (another body) that moves on the line.")
    axis: str | tuple[float, ...] = direction(
        "Direction of the line in body i's frame: ``[x, y]`` or the name of one of body i's "
        "``vectors``. Default ``[1, 0]``.",
        (1.0, 0.0),
        on="point_i",
    )
    angle: jax.Array = quantity(
        "angle",
        "Fixed relative angle ``phi_j - phi_i`` (or with a unit). Default 0.",
        0.0,
        converter=_f64,
    )
    clearance: jax.Array | None = quantity(
        "length",
        'The gap on each side of the centred slider, e.g. ``"0.5 mm"``: the joint becomes a '
        "slider in a guide (a ``slider_in_guide`` contact). Default none (an ideal slide).",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )
    slider_length: jax.Array | None = quantity(
        "length",
        "With a clearance: the distance between the slider's two ends, > 0.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )
    corner_radius: jax.Array | None = quantity(
        "length",
        "With a clearance: the radius of the slider's rounded corners, > 0.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )
    young_modulus: jax.Array | None = _c._young_modulus(optional=True)
    poisson: jax.Array | None = _c._poisson(None)
    restitution: jax.Array | None = _c._restitution(optional=True)
    impact_speed: jax.Array | None = _c._impact_speed()
    contact_model: str | None = _c._contact_model(None)
    mu: jax.Array | None = _c._mu()
    v_stick: jax.Array | None = _c._v_stick()
    u: jax.Array | None = eqx.field(default=None, kw_only=True)
    n_equations: ClassVar[int] = 2
    equation_labels: ClassVar[tuple[str, ...]] = ("normal", "angle")

    def __check_init__(self):
        _clearance.check_clearance(self, ("slider_length", "corner_radius"))

    def bind(self, r: Resolver):
        kw = self._bind_points(r)
        return dataclasses.replace(self, u=r.vector(self.axis, kw["bi"], self.name), **kw)

    def residual(self, q):
        n = cross(vector(q, self.bi, self.u), self._d(q))
        return jnp.stack([n, angle(q, self.bj) - angle(q, self.bi) - self.angle])

    @property
    def carries_moment(self):
        return True

    def drawing(self):
        if self.bi < 0 and self.u is not None:
            return {"guides": [(self.si, self.u)]}
        return {}


@element("pin_in_slot", "joints")
class PinInSlot(Translational):
    """Revolute–translational joint: point ``point_j`` of body j moves in a slot of body i.

    The slot is the line through ``point_i`` with direction ``axis`` (body-i frame); body j
    may rotate freely. Equation (1): ``u_i x (r_Pj - r_Pi) = 0``.
    """

    point_i: str = reference(
        "Point of body i on the slot's line: ``body.point``, ``body`` or ``ground.point``."
    )
    point_j: str = reference("Point (pin) of body j (another body) that moves in the slot.")
    axis: str | tuple[float, ...] = direction(
        "Direction of the slot in body i's frame: ``[x, y]`` or the name of one of body i's "
        "``vectors``. Default ``[1, 0]``.",
        (1.0, 0.0),
        on="point_i",
    )
    #: Not a field of a file: the pin turns freely, no relative angle is held.
    angle: jax.Array = eqx.field(default=0.0, converter=_f64)
    #: Not fields of a file: a pin in a slot has no clearance here.
    clearance: None = eqx.field(default=None, kw_only=True)
    slider_length: None = eqx.field(default=None, kw_only=True)
    corner_radius: None = eqx.field(default=None, kw_only=True)
    young_modulus: None = eqx.field(default=None, kw_only=True)
    poisson: None = eqx.field(default=None, kw_only=True)
    restitution: None = eqx.field(default=None, kw_only=True)
    impact_speed: None = eqx.field(default=None, kw_only=True)
    contact_model: None = eqx.field(default=None, kw_only=True)
    mu: None = eqx.field(default=None, kw_only=True)
    v_stick: None = eqx.field(default=None, kw_only=True)
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("normal",)

    def residual(self, q):
        return cross(vector(q, self.bi, self.u), self._d(q))[None]

    @property
    def carries_moment(self):
        return False

    def drawing(self):
        return {"pins": [(self.bj, self.sj)], **super().drawing()}


@element("distance", "joints")
class Distance(_TwoPoint):
    """Distance constraint (a massless rod): ``|r_Pj - r_Pi| - length = 0`` (1 equation).

    Its multiplier is the rod's compression force [force].
    """

    point_i: str = reference("First point: ``body.point``, ``body`` or ``ground.point``.")
    point_j: str = reference("Second point, on another body.")
    length: jax.Array = quantity(
        "length",
        'Distance between the points, > 0, e.g. ``"120 mm"``.',
        converter=_f64,
        above=0.0,
    )
    n_equations: ClassVar[int] = 1
    equation_labels: ClassVar[tuple[str, ...]] = ("length",)

    def residual(self, q):
        return (jnp.linalg.norm(self._d(q)) - self.length)[None]
