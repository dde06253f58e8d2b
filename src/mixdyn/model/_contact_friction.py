"""Coulomb friction with stick and slip at a compliant contact.

A compliant contact's own ``mu`` gives a regularized friction, ``-mu N tanh(v_t / v_stick)``
(:mod:`~mixdyn.model._contact_law`): smooth, for the adaptive integrators and gradients, but
below ``v_stick`` it creeps instead of sticking. This element is the contact's friction as the
joint friction is a joint's (:class:`~mixdyn.JointFriction`, Karnopp's model): a
reaction-dependent force (:class:`~mixdyn.model._reaction_dependent.ReactionDependent`) along
the sliding speed ``v_t = D(q) . qd`` of body j on body i at the contact point (along
``z x n``, the contact's tangent), its load the contact's normal force ``N(q, qd)``:

- sliding (``|v_t| >= v_stick``): ``-mu N sign(v_t)``;
- inside the band: the force that keeps ``v_t`` from changing, as long as it stays within
  ``mu N``; the integrators then bring ``v_t`` to exactly 0 after each step
  (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so that a body that its friction
  holds stays where it stopped.

The sliding speed of a contact point integrates to no coordinate (a disk that rolls), so the
element gives the row ``D(q)`` itself
(:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.relative_direction`). It acts at
one contact point: a compliant pair that touches at one place (a circle on a line or on a
circle, a journal in its bearing), with no ``mu`` of its own.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._declare import element, quantity, reference
from ._element import Resolver
from ._forces import _f64
from ._geometry import GROUND
from ._reaction_dependent import ReactionDependent


@element("contact_friction", "forces")
class ContactFriction(ReactionDependent):
    """Coulomb friction, with stick and slip, at the compliant contact named ``contact``.

    Args:
        name: unique name.
        contact: the contact's name: a compliant contact that touches at one point, with no
            ``mu`` of its own.
        mu: the friction coefficient (>= 0) [1].
        v_stick: the stick band: a sliding speed below it sticks [velocity].
    """

    contact: str = reference(
        "The compliant contact with friction (one contact point, no mu of its own).",
        what="force",
    )
    mu: jax.Array = quantity(
        "dimensionless", "Coulomb friction coefficient, >= 0.", converter=_f64, at_least=0.0
    )
    v_stick: jax.Array = quantity(
        "velocity",
        "Stick band: below this sliding speed the contact sticks while the friction can hold "
        "it. Default 1e-6 in the model's units.",
        1e-6,
        converter=_f64,
        above=0.0,
    )
    kind_name: ClassVar[str] = "contact friction"
    #: What the element's name is used for, in a model file's description.
    name_doc: ClassVar[str] = (
        "Unique name of the friction element (its result columns: the friction force on the "
        "contact's body j along its tangent, ``.normal``, ``.limit``, ``.speed``, ``.power``)."
    )

    def bind(self, r: Resolver):
        return self

    def with_forces(self, forces, nq: int) -> ContactFriction:
        """The element checked against the model's bound ``forces``: its contact exists, is
        compliant, touches at one point and has no friction of its own."""
        from ._compliant import _Compliant

        for f in forces:
            if f.name != self.contact:
                continue
            if not isinstance(f, _Compliant) or f.rigid:
                raise ModelError(
                    f"{self.contact!r} is no compliant contact: contact friction acts at a "
                    "compliant contact (a rigid contact's friction is on its impulses: give it mu)",
                    self.name,
                    field="contact",
                )
            if f.mu is not None:
                raise ModelError(
                    f"contact {self.contact!r} has a friction of its own (mu): remove its mu "
                    "and v_stick, or this element",
                    self.name,
                    field="contact",
                )
            points = jax.eval_shape(f._delta, jax.ShapeDtypeStruct((nq,), jnp.float64)).shape
            if points != (1,):
                raise ModelError(
                    f"contact {self.contact!r} touches at {points[0]} points: contact friction "
                    "acts at one point (a circle on a line or a circle, a journal); give that "
                    "contact mu and v_stick (regularized friction at each point)",
                    self.name,
                    field="contact",
                )
            return self
        known = ", ".join(f.name for f in forces if f is not self) or "(none)"
        raise ModelError(
            f"no force element {self.contact!r}; forces: {known}", self.name, field="contact"
        )

    def body_indices(self):
        return ()

    def reaction_rows(self) -> tuple[str, ...]:
        """None: the load is the contact's normal force (:meth:`state_load`)."""
        return ()

    def relative_direction(self, model, q):
        """``D(q)`` (nq,): the sliding speed of body j on body i at the contact point along
        the tangent ``z x n``, per unit of ``qd`` (linear in ``qd``)."""
        c = model.element(self.contact)
        return jax.jacfwd(lambda qd: c.sliding(q, qd)[0])(jnp.zeros_like(q))

    def state_load(self, model, q, qd, t):
        """The contact's normal force ``N`` (1,) [force] at the state (0 apart)."""
        c = model.element(self.contact)
        return jnp.atleast_1d(c.outputs(q, qd, t)["normal"])

    def holding_limit(self, reactions):
        """``mu N``."""
        return self.mu * reactions[0]

    def slip_force(self, v, reactions):
        """The limit against the sliding, ``-mu N sign(v)``."""
        return -self.holding_limit(reactions) * jnp.sign(v)

    def stick_band(self):
        return self.v_stick

    def reaction_outputs(self, reactions):
        return {"normal": reactions[0], "limit": self.holding_limit(reactions)}

    no_arrow: ClassVar[None] = None

    def arrow(self, model, q):
        """The friction on body j at the contact point (its global positions (N, 2), on the
        ground's frame), along the contact's tangent."""
        c = model.element(self.contact)

        def one(q):
            P, n = (jnp.atleast_2d(x)[0] for x in c.frame(q))
            return P, jnp.stack([-n[1], n[0]])

        P, t = jax.vmap(one)(jnp.asarray(q))
        return GROUND, np.asarray(P), np.asarray(t)

    @property
    def magnitude_kind(self):
        return "force"

    @property
    def output_kinds(self):
        return {"": "force", "normal": "force", "limit": "force", "speed": "velocity"}


__all__ = ["ContactFriction"]
