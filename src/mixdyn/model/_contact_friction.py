"""Coulomb friction with stick and slip at a compliant contact.

A compliant contact's own ``mu`` gives a regularized friction, ``-mu N tanh(v_t / v_stick)``
(:mod:`~mixdyn.model._contact_law`): smooth, for the adaptive integrators and gradients, but
below ``v_stick`` it creeps instead of sticking. This element is the contact's friction as the
joint friction is a joint's (:class:`~mixdyn.JointFriction`, Karnopp's model): a
reaction-dependent force (:class:`~mixdyn.model._reaction_dependent.ReactionDependent`) at
each of the contact's points ``k`` (a circle on a line: one; a box on a line: its four
corners; a slider in its guide: its ends on both surfaces; a contact set: its pairs), along
the sliding speed ``v_k = D_k(q) . qd`` of body j on body i there (along ``z x n_k``, the
point's tangent), its load the point's normal force ``N_k(q, qd)``:

- sliding (``|v_k| >= v_stick``): ``-mu N_k sign(v_k)``;
- inside the band: the force that keeps ``v_k`` from changing, as long as it stays within
  ``mu N_k``; the integrators then bring ``v_k`` to exactly 0 after each step
  (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so that a body that its friction
  holds stays where it stopped. A point that does not touch (``N_k = 0``) takes no force.
  Points whose rows are the same (a block flat on a line: its corners slide together) share
  the force that holds them (the least-norm split,
  :func:`~mixdyn.equations._reaction_dependent.held`; the rigid bodies leave the split open),
  a point past its limit pushing at it and the others taking the rest.

The sliding speed of a contact point integrates to no coordinate (a disk that rolls), so the
element gives the rows ``D_k(q)`` themselves
(:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.relative_direction`). The contact
is compliant, with no ``mu`` of its own; a rigid contact's friction is Coulomb's law on its
impulses (its own ``mu``).
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
from ._geometry import GROUND
from ._reaction_dependent import ReactionDependent


class CoulombAtPoints(ReactionDependent):
    """Coulomb's law with stick and slip at contact points, one row a point, its load the
    point's normal force ``N_k`` [force] (the element's ``mu`` and ``v_stick``): sliding,
    ``-mu N_k sign(v_k)``; inside the stick band, holding up to ``mu N_k`` (0 where ``N_k``
    pulls: the point leaves)."""

    def holding_limit(self, reactions):
        """``mu N_k`` (k,)."""
        return self.mu * jnp.maximum(reactions, 0.0)

    def slip_force(self, v, reactions):
        """The limits against the sliding, ``-mu N_k sign(v_k)`` (k,)."""
        return -self.holding_limit(reactions) * jnp.sign(v)

    def stick_band(self):
        return self.v_stick

    def speed_output(self, v, reactions):
        """The sliding speed at the point of the largest normal force."""
        return jnp.atleast_1d(v)[jnp.argmax(reactions)]


@element("contact_friction", "forces")
class ContactFriction(CoulombAtPoints):
    """Coulomb friction, with stick and slip, at the compliant contact named ``contact``, at
    each of its contact points.

    Args:
        name: unique name.
        contact: the contact's name: a compliant contact with no ``mu`` of its own.
        mu: the friction coefficient (>= 0) [1].
        v_stick: the stick band: a sliding speed below it sticks [velocity].
    """

    contact: str = reference(
        "The compliant contact with friction (no mu of its own): friction at each of its "
        "contact points.",
        what="force",
    )
    mu: jax.Array = quantity(
        "dimensionless", "Coulomb friction coefficient, >= 0.", converter=_f64, at_least=0.0
    )
    v_stick: jax.Array = quantity(
        "velocity",
        "Stick band: below this sliding speed a contact point sticks while the friction can "
        "hold it. Default 1e-6 in the model's units.",
        1e-6,
        converter=_f64,
        above=0.0,
    )
    #: The contact's number of contact points, set when the model is built.
    points: int = eqx.field(static=True, default=1, kw_only=True)
    kind_name: ClassVar[str] = "contact friction"
    #: What the element's name is used for, in a model file's description.
    name_doc: ClassVar[str] = (
        "Unique name of the friction element (its result columns: the friction force on the "
        "contact's body j along its tangent, summed over the contact points as the contact's "
        "own columns are; ``.normal``, ``.limit`` (summed), ``.speed`` (at the point of the "
        "largest normal force), ``.power``)."
    )

    def bind(self, r: Resolver):
        return self

    def with_forces(self, forces, nq: int) -> ContactFriction:
        """The element checked against the model's bound ``forces``: its contact exists, is
        compliant and has no friction of its own; with the contact's number of points."""
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
            (points,) = jax.eval_shape(f._delta, jax.ShapeDtypeStruct((nq,), jnp.float64)).shape
            return dataclasses.replace(self, points=points)
        known = ", ".join(f.name for f in forces if f is not self) or "(none)"
        raise ModelError(
            f"no force element {self.contact!r}; forces: {known}", self.name, field="contact"
        )

    @property
    def width(self) -> int:
        """One row a contact point."""
        return self.points

    def body_indices(self):
        return ()

    def reaction_rows(self) -> tuple[str, ...]:
        """None: the load is the contact's normal force (:meth:`state_load`)."""
        return ()

    def relative_direction(self, model, q):
        """``D`` (nq, k): the sliding speeds of body j on body i at the ``k`` contact points,
        each along its tangent ``z x n``, per unit of ``qd`` (linear in ``qd``)."""
        c = model.element(self.contact)
        return jax.jacfwd(lambda qd: c.sliding(q, qd))(jnp.zeros_like(q)).T

    def state_load(self, model, q, qd, t):
        """The contact points' normal forces ``N_k`` (k,) [force] at the state (0 apart)."""
        c = model.element(self.contact)
        return c._state(q, qd)[2]

    def reaction_outputs(self, reactions):
        """``normal``: the points' normal forces summed; ``limit``: ``mu`` times it."""
        return {"normal": jnp.sum(reactions), "limit": jnp.sum(self.holding_limit(reactions))}

    no_arrow: ClassVar[None] = None

    def arrow(self, model, q):
        """The friction on body j at the contact's deepest point (its global positions (N, 2),
        on the ground's frame), along that point's tangent (the column sums the points'
        forces, each along its own tangent: one direction where the points lie on one line,
        as a box's corners on it)."""
        c = model.element(self.contact)

        def one(q):
            P, n = (jnp.atleast_2d(x) for x in c.frame(q))
            k = jnp.argmax(c._delta(q))
            return P[k], jnp.stack([-n[k, 1], n[k, 0]])

        P, t = jax.vmap(one)(jnp.asarray(q))
        return GROUND, np.asarray(P), np.asarray(t)

    @property
    def magnitude_kind(self):
        return "force"

    @property
    def output_kinds(self):
        return {"": "force", "normal": "force", "limit": "force", "speed": "velocity"}


__all__ = ["ContactFriction", "CoulombAtPoints"]
