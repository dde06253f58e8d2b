"""Drivers: prescribed motions ``Phi^D(q, t) = g(q) - f(t) = 0``.

A driver measures one quantity ``g(q)`` of the mechanism (a coordinate, a point coordinate, a
relative angle, a distance) and prescribes it to follow a :class:`~mixdyn.model.Law`. The effort a
driver exerts, ``-lambda``, is the generalized force conjugate to ``g``: a force [force] for a
length measure, a torque [torque] for an angle measure.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from ..errors import ModelError
from . import _smoothness as smoothness
from ._declare import coordinate, element, option, quantity, reference
from ._element import Element, Resolver, body_name, moving
from ._geometry import GROUND, angle, point
from ._laws import Law, as_law

_UNBOUND = -2
_COORD = {"x": 0, "y": 1, "phi": 2}


class Driver(Element):
    """Abstract driver: a measure ``g(q)`` and its prescribed law ``f(t)``.

    Its law must be continuous with its slope over a run, and with its second derivative
    where the run reports accelerations (every run but statics), unless ``continuity`` is
    ``"C1"`` (:meth:`check_law`).
    """

    law: Law = eqx.field(converter=as_law, kw_only=True)
    continuity: str = option(
        smoothness.CONTINUITY_DOC, "C2", choices=tuple(smoothness.CONTINUITY), kw_only=True
    )
    #: ``"length"`` or ``"angle"``: the unit of the measure; the effort is a force or torque.
    measure_kind: ClassVar[str] = "length"

    @abc.abstractmethod
    def measure(self, q: jax.Array) -> jax.Array:
        """The driven quantity ``g(q)`` (scalar)."""

    def residual(self, q, t):
        """``g(q) - f(t)``, shape (1,)."""
        return (self.measure(q) - self.law(t))[None]

    def __check_init__(self):
        smoothness.check_continuity(self.continuity, self.name)

    def check_law(self, t0: float, t1: float, accelerations: bool = True) -> None:
        """Refuse a law that jumps in value or slope between the times ``t0`` and ``t1``
        [time] (a run's span): the driven quantity would move, or change its speed, in no
        time; and, for a run that reports ``accelerations``, one whose second derivative
        jumps (the accelerations and forces would jump in no time), unless the driver's
        ``continuity`` is ``"C1"``.

        Raises:
            ModelError: naming the law, the time and the jump (:mod:`._smoothness`).
        """
        smoothness.check(
            self.law,
            float(t0),
            float(t1),
            element=self.name,
            moved="the driven quantity",
            order=smoothness.CONTINUITY[self.continuity] if accelerations else 1,
        )

    @property
    def effort_kind(self) -> str:
        """``"force"`` or ``"torque"``."""
        return "torque" if self.measure_kind == "angle" else "force"


@element("coordinate", "drivers")
class CoordinateDriver(Driver):
    """Prescribes one absolute coordinate (``"x"``, ``"y"`` or ``"phi"``) of a body; a file
    names both, ``coordinate: crank.phi``."""

    body: str = eqx.field(static=True)
    coordinate: str = coordinate(
        "The driven body coordinate: ``body.x``, ``body.y`` [length] or ``body.phi`` [rad].",
        body="body",
    )
    law: Law = quantity(
        ("length", "angle"),
        "The coordinate as a law of time, e.g. ``2*pi*t`` or ``{expr: 360*t, unit: deg}``.",
        converter=as_law,
        law=True,
        kw_only=True,
    )
    b: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)

    @classmethod
    def field_kind(cls, field: str, values, element_class) -> str:
        """The law's kind: an angle for ``phi``, a length for ``x`` and ``y``."""
        return "angle" if values["coordinate"] == "phi" else "length"

    def bind(self, r: Resolver):
        if self.coordinate not in _COORD:
            raise ModelError(
                f"coordinate must be x, y or phi, got {self.coordinate!r}",
                self.name,
                field="coordinate",
            )
        b = r.body(self.body, self.name)
        if b == GROUND:
            raise ModelError("the ground cannot be driven", self.name, field="coordinate")
        return dataclasses.replace(self, b=b)

    @property
    def measure_kind(self):
        return "angle" if self.coordinate == "phi" else "length"

    @property
    def index(self) -> int:
        """Index of the driven coordinate in ``q``."""
        return 3 * self.b + _COORD[self.coordinate]

    def body_indices(self):
        return (self.b,)

    def measure(self, q):
        return q[self.index]


@element("point", "drivers")
class PointDriver(Driver):
    """Prescribes the global ``"x"`` or ``"y"`` coordinate of a body point."""

    point: str = reference("The driven point, ``body.point`` or ``body`` (not a ground point).")
    coordinate: str = option(
        "Which global coordinate of the point: ``x`` or ``y``.", choices=("x", "y")
    )
    law: Law = quantity(
        "length",
        'The coordinate as a law of time, e.g. ``"10*sin(pi*t)"``.',
        converter=as_law,
        law=True,
        kw_only=True,
    )
    b: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    s: jax.Array | None = eqx.field(default=None, kw_only=True)

    def bind(self, r: Resolver):
        if self.coordinate not in ("x", "y"):
            raise ModelError(
                f"coordinate must be x or y, got {self.coordinate!r}", self.name, field="coordinate"
            )
        b, s = r.point(self.point, self.name)
        if b == GROUND:
            raise ModelError("a ground point cannot be driven", self.name, field="point")
        return dataclasses.replace(self, b=b, s=s)

    def body_indices(self):
        return (self.b,)

    def measure(self, q):
        return point(q, self.b, self.s)[_COORD[self.coordinate]]


@element("relative_angle", "drivers")
class RelativeAngleDriver(Driver):
    """Prescribes ``phi_j - phi_i`` [rad], the angle of body j relative to body i."""

    body_i: str = reference("Body i (the reference body; may be ``ground``).", what="body")
    body_j: str = reference("Body j, whose angle relative to body i is driven.", what="body")
    law: Law = quantity(
        "angle",
        "The angle ``phi_j - phi_i`` as a law of time, e.g. ``{expr: 90*t, unit: deg}``.",
        converter=as_law,
        law=True,
        kw_only=True,
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    measure_kind: ClassVar[str] = "angle"

    def bind(self, r: Resolver):
        bi, bj = r.body(self.body_i, self.name), r.body(self.body_j, self.name)
        if bi == bj:
            raise ModelError(
                f"body_i and body_j are the same body ({self.body_i!r}): a relative angle needs "
                "two different bodies",
                self.name,
            )
        return dataclasses.replace(self, bi=bi, bj=bj)

    def body_indices(self):
        return moving(self.bi, self.bj)

    def measure(self, q):
        return angle(q, self.bj) - angle(q, self.bi)


@element("distance", "drivers")
class DistanceDriver(Driver):
    """Prescribes the distance ``|r_Pj - r_Pi|`` [length] between two points (an actuator)."""

    point_i: str = reference("First point: ``body.point``, ``body`` or ``ground.point``.")
    point_j: str = reference("Second point, on another body.")
    law: Law = quantity(
        "length",
        "The distance as a law of time, e.g. ``100 + 20*t``.",
        converter=as_law,
        law=True,
        kw_only=True,
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: jax.Array | None = eqx.field(default=None, kw_only=True)
    sj: jax.Array | None = eqx.field(default=None, kw_only=True)

    def bind(self, r: Resolver):
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError(
                f"both points are on {body_name(self.point_i)!r}: a distance driver needs "
                "points on two different bodies",
                self.name,
            )
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj)

    def body_indices(self):
        return moving(self.bi, self.bj)

    def measure(self, q):
        return jnp.linalg.norm(point(q, self.bj, self.sj) - point(q, self.bi, self.si))
