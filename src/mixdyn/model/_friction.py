"""Coulomb friction in a revolute or translational joint.

The friction force depends on the joint's reaction, which the analysis computes together with
the accelerations: the element holds the coefficients, the analysis evaluates it
(:mod:`mixdyn.equations._friction`).

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

from ..errors import ModelError
from ._declare import element, quantity, reference
from ._element import Resolver
from ._forces import ForceElement, _f64


@element("joint_friction", "forces")
class JointFriction(ForceElement):
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
    #: The element is evaluated by the analysis, with the reactions.
    needs_reactions: ClassVar[bool] = True
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

    def generalized(self, q, qd, t, nq):
        """Zero: the friction force is the analysis' (it needs the reactions)."""
        return jnp.zeros(nq)

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
