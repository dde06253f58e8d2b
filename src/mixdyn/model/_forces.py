"""Force elements: contributions to the generalized applied forces ``Q^A(q, qd, t)``.

Each element gives, for the bodies it acts on, ``[Fx, Fy, Mz]`` per body (force [force] at the
body frame's origin, moment [torque] about it), assembled into a vector of shape (3 nb,).

An element with a *magnitude* (point force, torque, actuator of a spring–damper) splits as
``Q = passive(q, qd, t) + magnitude * direction(q, qd, t)``. A mixed-dynamics analysis may declare
that magnitude unknown; ``direction`` is then the column of the matrix ``B`` of the paper.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp

from ..errors import ModelError
from ._declare import direction, element, option, quantity, reference
from ._element import Element, Resolver, moving
from ._geometry import GROUND, angle, cross, point, rot, vector
from ._laws import Law, as_law

_UNBOUND = -2


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class StateFunction(eqx.Module):
    """A magnitude given as a JAX-traceable function of the state, ``fn(q, qd, t) -> scalar``.

    ``q`` and ``qd`` are the full coordinate and velocity vectors (3 nb,).
    """

    fn: Callable = eqx.field(static=True)

    def __call__(self, q, qd, t):
        return self.fn(q, qd, t)


def _magnitude(law, q, qd, t):
    if isinstance(law, StateFunction):
        return law(q, qd, t)
    return law(t)


def _as_magnitude(value):
    if value is None or isinstance(value, StateFunction):
        return value
    return as_law(value)


def wrench(nq: int, parts) -> jax.Array:
    """Assemble ``[(body, (3,) [Fx, Fy, Mz]), ...]`` into a generalized force (nq,)."""
    Q = jnp.zeros(nq)
    for b, w in parts:
        if b != GROUND:
            Q = Q.at[3 * b : 3 * b + 3].add(w)
    return Q


def point_wrench(q, b, s, F):
    """``[Fx, Fy, Mz]`` on body ``b`` of force ``F`` (2,) applied at body point ``s``."""
    arm = vector(q, b, s) if b != GROUND else s
    return jnp.concatenate([F, cross(arm, F)[None]])


class ForceElement(Element):
    """Abstract force element."""

    #: Whether the element has a scalar magnitude that may be declared unknown.
    has_magnitude = False
    #: Whether the element's force depends on the joint reactions (a
    #: :class:`~mixdyn.model._reaction_dependent.ReactionDependent`): the analysis evaluates
    #: it with the accelerations; ``generalized`` gives zero.
    needs_reactions = False

    def passive(self, q, qd, t, nq: int) -> jax.Array:
        """The part of ``Q`` that does not scale with the magnitude, (nq,)."""
        return jnp.zeros(nq)

    def direction(self, q, qd, t, nq: int) -> jax.Array:
        """``dQ/d(magnitude)``, (nq,): the generalized force per unit magnitude."""
        return jnp.zeros(nq)

    def magnitude(self, q, qd, t) -> jax.Array:
        """The magnitude's current value (0 for elements without one)."""
        return jnp.zeros(())

    def generalized(self, q, qd, t, nq: int) -> jax.Array:
        """The element's generalized force ``Q`` (nq,)."""
        return self.passive(q, qd, t, nq) + self.magnitude(q, qd, t) * self.direction(q, qd, t, nq)

    def potential(self, q) -> jax.Array:
        """Potential energy stored in the element [energy] (0 if it stores none)."""
        return jnp.zeros(())

    @property
    def magnitude_kind(self) -> str:
        """``"force"`` or ``"torque"``: the unit of the magnitude."""
        return "force"

    def outputs(self, q, qd, t) -> dict[str, jax.Array]:
        """The element's result columns by suffix (``""``: the column named as the element):
        its magnitude, and what else a reader wants of it (a spring's length and tension)."""
        return {"": self.magnitude(q, qd, t)} if self.has_magnitude else {}

    @property
    def output_kinds(self) -> dict[str, str]:
        """The kind of quantity of each of :meth:`outputs`' columns."""
        return {"": self.magnitude_kind} if self.has_magnitude else {}


@element("point_force", "forces")
class PointForce(ForceElement):
    """A force at a body point along a fixed direction, of magnitude ``law`` [force].

    Args:
        name: unique name.
        point: ``"body.point"`` (or ``"body"`` for the centre of mass).
        along: (2,) direction, in the ground frame (``frame="ground"``) or the body frame.
        law: the magnitude: a law of time, a :class:`StateFunction`, or a number.
        frame: ``"ground"`` or ``"body"``.
    """

    point: str = reference("The loaded point, ``body.point`` or ``body`` (centre of mass).")
    along: tuple[float, ...] = direction(
        "Direction of the force ``[x, y]``, in the ground or body frame (``frame``). Default "
        "``[1, 0]``.",
        (1.0, 0.0),
    )
    law: Law | StateFunction | None = quantity(
        "force",
        "Magnitude along ``along``: a law of time, which may also use body states "
        "(``-c*slider.vx``). Default 0.",
        0.0,
        converter=_as_magnitude,
        law=True,
        state=True,
    )
    frame: str = option(
        "Frame of ``along``: ``ground`` (fixed direction, default) or ``body`` (turns with the "
        "body).",
        "ground",
        choices=("ground", "body"),
    )
    b: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    s: jax.Array | None = eqx.field(default=None, kw_only=True)
    u: jax.Array | None = eqx.field(default=None, kw_only=True)
    has_magnitude = True

    def bind(self, r: Resolver):
        if self.frame not in ("ground", "body"):
            raise ModelError(
                f"frame must be 'ground' or 'body', got {self.frame!r}", self.name, field="frame"
            )
        b, s = r.point(self.point, self.name)
        if b == GROUND:
            raise ModelError(
                "a force on the ground has no effect; apply it to a body", self.name, field="point"
            )
        u = r.vector(self.along, GROUND, self.name)
        return dataclasses.replace(self, b=b, s=s, u=u)

    def body_indices(self):
        return (self.b,)

    def direction(self, q, qd, t, nq):
        u = self.u if self.frame == "ground" else rot(angle(q, self.b)) @ self.u
        return wrench(nq, [(self.b, point_wrench(q, self.b, self.s, u))])

    def magnitude(self, q, qd, t):
        return _magnitude(self.law, q, qd, t)


@element("torque", "forces")
class Torque(ForceElement):
    """A torque ``law`` [torque] (counter-clockwise positive) on ``body``.

    If ``reaction`` names a second body, the opposite torque acts on it.
    """

    body: str = reference("The body the torque acts on.", what="body")
    law: Law | StateFunction | None = quantity(
        "torque",
        "Magnitude, counter-clockwise positive: a law of time, which may also use body states "
        "(``-c*crank.omega``). Default 0.",
        0.0,
        converter=_as_magnitude,
        law=True,
        state=True,
    )
    reaction: str | None = reference(
        "A body that receives the opposite torque (e.g. a motor housing); default none "
        "(``ground``).",
        what="body",
        default=None,
    )
    b: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    br: int = eqx.field(static=True, default=GROUND, kw_only=True)
    has_magnitude = True

    def bind(self, r: Resolver):
        b = r.body(self.body, self.name)
        if b == GROUND:
            raise ModelError(
                "a torque on the ground has no effect; apply it to a body", self.name, field="body"
            )
        br = r.body(self.reaction, self.name) if self.reaction else GROUND
        if br == b:
            raise ModelError(
                "the reaction acts on the same body: name another body (or none)",
                self.name,
                field="reaction",
            )
        return dataclasses.replace(self, b=b, br=br)

    def body_indices(self):
        return moving(self.b, self.br)

    def direction(self, q, qd, t, nq):
        e = jnp.array([0.0, 0.0, 1.0])
        return wrench(nq, [(self.b, e), (self.br, -e)])

    def magnitude(self, q, qd, t):
        return _magnitude(self.law, q, qd, t)

    @property
    def magnitude_kind(self):
        return "torque"


@element("spring_damper", "forces")
class SpringDamper(ForceElement):
    """Translational spring–damper–actuator between two points.

    The tension ``T = stiffness (L - free_length) + damping dL/dt - actuator`` pulls the points
    together; the actuator force [force] pushes them apart. ``L`` is the current distance.
    """

    point_i: str = reference(
        "First attachment point: ``body.point``, ``body`` or ``ground.point``."
    )
    point_j: str = reference("Second attachment point, on another body.")
    stiffness: jax.Array = quantity(
        "stiffness",
        'Spring stiffness, e.g. ``"2 N/mm"``. Tension ``stiffness (L - free_length) + '
        "damping dL/dt - actuator``. Default 0.",
        0.0,
        converter=_f64,
    )
    damping: jax.Array = quantity(
        "damping", 'Damping coefficient, e.g. ``"5 N*s/m"``. Default 0.', 0.0, converter=_f64
    )
    free_length: jax.Array = quantity(
        "length", "Unstretched length of the spring. Default 0.", 0.0, converter=_f64, at_least=0.0
    )
    actuator: Law | StateFunction | None = quantity(
        "force",
        "Actuator force pushing the points apart: a law of time, which may also use body "
        "states. Default 0.",
        0.0,
        converter=_as_magnitude,
        law=True,
        state=True,
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: jax.Array | None = eqx.field(default=None, kw_only=True)
    sj: jax.Array | None = eqx.field(default=None, kw_only=True)
    has_magnitude = True

    def bind(self, r: Resolver):
        bi, si = r.point(self.point_i, self.name)
        bj, sj = r.point(self.point_j, self.name)
        if bi == bj:
            raise ModelError("a spring needs points on two different bodies", self.name)
        return dataclasses.replace(self, bi=bi, bj=bj, si=si, sj=sj)

    def body_indices(self):
        return moving(self.bi, self.bj)

    def _geometry(self, q, qd):
        d = point(q, self.bj, self.sj) - point(q, self.bi, self.si)
        L = jnp.linalg.norm(d)
        u = d / L
        Ld = jax.jvp(
            lambda qq: jnp.linalg.norm(point(qq, self.bj, self.sj) - point(qq, self.bi, self.si)),
            (q,),
            (qd,),
        )[1]
        return L, Ld, u

    def _pair(self, q, F_on_j, nq):
        return wrench(
            nq,
            [
                (self.bj, point_wrench(q, self.bj, self.sj, F_on_j)),
                (self.bi, point_wrench(q, self.bi, self.si, -F_on_j)),
            ],
        )

    def passive(self, q, qd, t, nq):
        L, Ld, u = self._geometry(q, qd)
        T = self.stiffness * (L - self.free_length) + self.damping * Ld
        return self._pair(q, -T * u, nq)

    def direction(self, q, qd, t, nq):
        _, _, u = self._geometry(q, qd)
        return self._pair(q, u, nq)

    def magnitude(self, q, qd, t):
        return _magnitude(self.actuator, q, qd, t)

    def potential(self, q):
        d = point(q, self.bj, self.sj) - point(q, self.bi, self.si)
        return 0.5 * self.stiffness * (jnp.linalg.norm(d) - self.free_length) ** 2

    def outputs(self, q, qd, t):
        """The actuator force (``""``), the length ``L`` and the tension ``T`` (pulling the
        points together: spring and damper less the actuator)."""
        L, Ld, _ = self._geometry(q, qd)
        a = self.magnitude(q, qd, t)
        T = self.stiffness * (L - self.free_length) + self.damping * Ld - a
        return {"": a, "length": L, "tension": T}

    @property
    def output_kinds(self):
        return {"": "force", "length": "length", "tension": "force"}


@element("rotary_spring_damper", "forces")
class RotarySpringDamper(ForceElement):
    """Rotational spring–damper–actuator between body i and body j (either may be the ground).

    Torque on body j: ``-stiffness (theta - free_angle) - damping dtheta/dt + actuator`` with
    ``theta = phi_j - phi_i``; the opposite torque acts on body i.
    """

    body_i: str = reference("Body i (may be ``ground``).", what="body")
    body_j: str = reference(
        "Body j (another body). The torque on j is ``-stiffness (theta - free_angle) - damping "
        "dtheta/dt + actuator`` with ``theta = phi_j - phi_i``; the opposite acts on i.",
        what="body",
    )
    stiffness: jax.Array = quantity(
        "rotational_stiffness",
        'Rotational stiffness, e.g. ``"500 N*mm/rad"``. Default 0.',
        0.0,
        converter=_f64,
    )
    damping: jax.Array = quantity(
        "rotational_damping", "Rotational damping. Default 0.", 0.0, converter=_f64
    )
    free_angle: jax.Array = quantity(
        "angle",
        "Relative angle ``phi_j - phi_i`` at which the spring is relaxed. Default 0.",
        0.0,
        converter=_f64,
    )
    actuator: Law | StateFunction | None = quantity(
        "torque",
        "Actuator torque on body j (opposite on body i): a law of time, which may also use "
        "body states. Default 0.",
        0.0,
        converter=_as_magnitude,
        law=True,
        state=True,
    )
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    has_magnitude = True

    def bind(self, r: Resolver):
        bi, bj = r.body(self.body_i, self.name), r.body(self.body_j, self.name)
        if bi == bj:
            raise ModelError("a rotary spring needs two different bodies", self.name)
        return dataclasses.replace(self, bi=bi, bj=bj)

    def body_indices(self):
        return moving(self.bi, self.bj)

    def _theta(self, q):
        return angle(q, self.bj) - angle(q, self.bi)

    def direction(self, q, qd, t, nq):
        e = jnp.array([0.0, 0.0, 1.0])
        return wrench(nq, [(self.bj, e), (self.bi, -e)])

    def passive(self, q, qd, t, nq):
        th, thd = jax.jvp(self._theta, (q,), (qd,))
        tau = -self.stiffness * (th - self.free_angle) - self.damping * thd
        return tau * self.direction(q, qd, t, nq)

    def magnitude(self, q, qd, t):
        return _magnitude(self.actuator, q, qd, t)

    def potential(self, q):
        return 0.5 * self.stiffness * (self._theta(q) - self.free_angle) ** 2

    def outputs(self, q, qd, t):
        """The actuator torque (``""``), the relative angle ``theta`` and the whole torque
        on body j (spring, damper and actuator)."""
        th, thd = jax.jvp(self._theta, (q,), (qd,))
        a = self.magnitude(q, qd, t)
        tau = -self.stiffness * (th - self.free_angle) - self.damping * thd + a
        return {"": a, "angle": th, "torque": tau}

    @property
    def output_kinds(self):
        return {"": "torque", "angle": "angle", "torque": "torque"}

    @property
    def magnitude_kind(self):
        return "torque"


class GeneralizedForce(ForceElement):
    """A user generalized force: a JAX-traceable ``fn(q, qd, t) -> Q`` of shape (3 nb,).

    ``bodies`` names the bodies it acts on (for the sparsity structure; all if empty).
    """

    fn: Callable = eqx.field(static=True)
    bodies: tuple = eqx.field(static=True, default=())
    idx: tuple = eqx.field(static=True, default=(), kw_only=True)

    def bind(self, r: Resolver):
        idx = (
            tuple(r.body(b, self.name) for b in self.bodies)
            if self.bodies
            else tuple(range(len(r.bodies)))
        )
        return dataclasses.replace(self, idx=idx)

    def body_indices(self):
        return moving(*self.idx)

    def passive(self, q, qd, t, nq):
        Q = jnp.asarray(self.fn(q, qd, t), dtype=jnp.float64)
        if Q.shape != (nq,):
            raise ModelError(f"the function must return shape ({nq},), got {Q.shape}", self.name)
        return Q
