"""Coulomb friction in a revolute or translational joint.

The friction force depends on the joint's reaction: a reaction-dependent force
(:class:`~mixdyn.model._reaction_dependent.ReactionDependent`), which the analysis solves
together with the accelerations and the reactions.

- Revolute joint: a friction torque of at most ``mu * radius * |R|`` between the two bodies
  (``R`` the reaction force of the pin, ``radius`` the pin's radius [length]).
- Translational joint (and pin in slot): a friction force of at most ``mu * |N|`` along the
  axis (``N`` the normal reaction; the reaction moment's share, which depends on the slider's
  length, is not included).

Stick and slip (Karnopp's model): while the relative speed is below ``v_stick`` the joint
sticks: the friction force is the one that keeps the relative acceleration zero, as long as
it stays within the limit; past the limit, or above ``v_stick``, the joint slips with the
limit force opposing the motion. A joint that stops (its speed inside the band, or reversed
within a step) and that its static friction holds is brought to rest exactly after the step
(:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`: the impulse that zeroes its
relative speed, its kinetic energy counted as the friction's work), so that it stays where it
stopped. The one regularization left is the band for a joint that cannot stick: it turns
round inside it at the limit force the other way (a time shift of about ``v_stick`` over the
acceleration).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._declare import element, quantity, reference
from ._element import Resolver
from ._forces import _f64
from ._geometry import angle, vector
from ._reaction_dependent import ReactionDependent


@element("joint_friction", "forces")
class JointFriction(ReactionDependent):
    """Coulomb friction, with stick and slip, in the revolute, translational or pin-in-slot
    joint named ``joint``.

    Args:
        name: unique name.
        joint: the joint's name (a revolute, translational or pin-in-slot joint).
        mu: the friction coefficient (>= 0) [1].
        radius: the pin's radius, for a revolute joint [length].
        v_stick: the stick band: a relative speed below it sticks [velocity, or angular
            velocity for a revolute joint].
    """

    joint: str = reference(
        "The joint with friction: a revolute, translational or pin-in-slot joint.", what="joint"
    )
    mu: jax.Array = quantity(
        "dimensionless", "Coulomb friction coefficient, >= 0.", converter=_f64, at_least=0.0
    )
    radius: jax.Array = quantity(
        "length",
        "Pin radius, for a revolute joint: the friction torque is ``mu radius |R|``.",
        0.0,
        converter=_f64,
        at_least=0.0,
    )
    v_stick: jax.Array = quantity(
        ("velocity", "angular_velocity"),
        "Stick band (an angular velocity for a revolute joint): below this relative speed the "
        "joint sticks while the friction can hold it. Default 1e-6 in the model's units.",
        1e-6,
        converter=_f64,
        above=0.0,
    )
    #: Whether the joint is revolute (a friction torque), set when the model is built.
    rotary: bool = eqx.field(static=True, default=False, kw_only=True)
    kind_name: ClassVar[str] = "joint friction"
    #: What the element's name is used for, in a model file's description.
    name_doc: ClassVar[str] = (
        "Unique name of the friction element (its result columns: the friction force or "
        "torque, ``.normal``, ``.limit``, ``.speed``, ``.power``)."
    )

    @classmethod
    def field_kind(cls, field: str, values, element_class) -> str:
        """The stick band's kind: an angular velocity in a revolute joint, else a velocity
        (``element_class(name)``: the class of the model's element ``name``, or None)."""
        from ._joints import Revolute

        joint = element_class(values["joint"])
        rotary = values.get("rotary", False) or (
            isinstance(joint, type) and issubclass(joint, Revolute)
        )
        return "angular_velocity" if rotary else "velocity"

    def bind(self, r: Resolver):
        return self

    def with_joint(self, joints) -> JointFriction:
        """The element checked against the model's bound ``joints``: its joint exists and is
        revolute, translational or a pin in a slot."""
        from ._joints import Revolute, Translational

        for j in joints:
            if j.name == self.joint:
                if isinstance(j, Revolute):
                    if float(jnp.max(self.radius)) <= 0 and float(jnp.max(self.mu)) > 0:
                        raise ModelError(
                            f"friction in revolute joint {self.joint!r} needs the pin's radius "
                            "(radius > 0): the friction torque is mu * radius * |reaction|",
                            self.name,
                            field="radius",
                        )
                    return dataclasses.replace(self, rotary=True)
                if isinstance(j, Translational):
                    return dataclasses.replace(self, rotary=False)
                raise ModelError(
                    f"joint {self.joint!r} is a {type(j).__name__}: friction is modelled in "
                    "revolute, translational and pin-in-slot joints",
                    self.name,
                    field="joint",
                )
        known = ", ".join(j.name for j in joints) or "(none)"
        raise ModelError(f"no joint {self.joint!r}; joints: {known}", self.name, field="joint")

    def body_indices(self):
        return ()

    def reaction_rows(self) -> tuple[str, ...]:
        """The pin's reaction ``joint.x, joint.y``, or the slide's ``joint.normal``."""
        return tuple(f"{self.joint}.{lab}" for lab in (("x", "y") if self.rotary else ("normal",)))

    def relative_coordinate(self, model, q):
        """A pin's ``phi_j - phi_i`` [rad]; a slide's ``u_i . (r_Pj - r_Pi)`` [length]."""
        j = model.element(self.joint)  # checked to be such a joint when the model was built
        if self.rotary:
            return angle(q, j.bj) - angle(q, j.bi)
        return jnp.dot(vector(q, j.bi, j.u), j._d(q))

    def normal(self, reactions):
        """The normal reaction ``|R|`` or ``|N|`` [force] from the joint's multipliers (k,)."""
        return jnp.sqrt(jnp.maximum(sum(r**2 for r in reactions), 1e-300))

    def holding_limit(self, reactions):
        """``mu radius |R|`` (a pin) or ``mu |N|`` (a slide)."""
        return self.mu * (self.radius if self.rotary else 1.0) * self.normal(reactions)

    def slip_force(self, v, reactions):
        """The limit against the motion, ``-limit sign(v)``."""
        return -self.holding_limit(reactions) * jnp.sign(v)

    def stick_band(self):
        return self.v_stick

    def reaction_outputs(self, reactions):
        return {"normal": self.normal(reactions), "limit": self.holding_limit(reactions)}

    @property
    def no_arrow(self):
        return "is a pin's friction torque" if self.rotary else None

    def arrow(self, model, q):
        """A slide's friction on body j at the joint's point, along the axis turning with
        body i; a pin's friction torque has none."""
        if self.rotary:
            return None
        j = model.element(self.joint)
        u = np.asarray(j.u, dtype=float)
        if j.bi >= 0:
            phi = q[:, 3 * j.bi + 2]
            c, sn = np.cos(phi), np.sin(phi)
            u = np.stack([c * u[0] - sn * u[1], sn * u[0] + c * u[1]], axis=-1)
        return j.bj, j.sj, np.broadcast_to(u, (len(q), 2))

    @property
    def magnitude_kind(self):
        return "torque" if self.rotary else "force"

    @property
    def output_kinds(self):
        return {
            "": self.magnitude_kind,
            "normal": "force",
            "limit": self.magnitude_kind,
            "speed": "angular_velocity" if self.rotary else "velocity",
        }


__all__ = ["JointFriction"]
