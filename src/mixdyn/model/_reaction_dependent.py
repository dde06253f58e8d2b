"""Reaction-dependent forces: force elements whose force depends on the joint reactions.

Such an element acts along one relative coordinate ``s(q)`` of the mechanism (the angle
between two bodies, a displacement along a slide): its generalized force is ``f D``,
``D = ds/dq`` (nq,), and its force ``f`` [force or torque] depends on the relative speed
``v = D . qd`` and on the multipliers of the constraint rows it names (a joint's reaction).
The reactions depend on ``f`` in turn, so the analyses solve every such element of a model
together with the accelerations and the multipliers, in one place
(:mod:`mixdyn.equations._reaction_dependent`). The element says:

- which reaction rows it reads (:meth:`ReactionDependent.reaction_rows`) and its relative
  coordinate (:meth:`~ReactionDependent.relative_coordinate`), or, where its relative speed
  integrates to no coordinate (sliding at a contact point), the row ``D(q)`` of that speed
  ``v = D . qd`` itself (:meth:`~ReactionDependent.relative_direction`);
- what else loads it, from the state (:meth:`~ReactionDependent.state_load`: a compliant
  contact's normal force), read after its reactions;
- its force while it moves (:meth:`~ReactionDependent.slip_force`), from its relative speed
  and its reactions;
- whether it holds the joint at rest (Karnopp's stick and slip): inside its stick band
  (:meth:`~ReactionDependent.stick_band`, 0 for an element that never sticks) it takes the
  force that keeps the relative acceleration zero, as long as that force stays within its
  holding limit (:meth:`~ReactionDependent.holding_limit`); past the limit it pushes at the
  limit, in the direction of the force it needed. After each step the integrators bring a
  sticking element's relative speed to exactly 0
  (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`: a stop is its speed inside the
  band, or reversed within the step);
- its result columns from its reactions (:meth:`~ReactionDependent.reaction_outputs`; the
  analysis adds the force itself, ``.speed`` and ``.power``) and, in an animation, its arrow
  (:meth:`~ReactionDependent.arrow`, or why it has none: :attr:`~ReactionDependent.no_arrow`).

An element may act along several relative speeds at once, its :attr:`~ReactionDependent.width`
``w`` rows (a contact's friction at each of its contact points): its direction is then
(nq, w), its slip force, holding limit and stick band (w,) (or one for all), each row
sticking or slipping on its own, and its force column the sum of its rows' forces.
"""

from __future__ import annotations

from typing import ClassVar

import jax
import jax.numpy as jnp

from ._forces import ForceElement


class ReactionDependent(ForceElement):
    """Abstract force element along one relative coordinate whose force depends on the joint
    reactions (the module's description gives the contract)."""

    #: The element is evaluated by the analysis, with the reactions.
    needs_reactions: ClassVar[bool] = True
    #: What the element is, in messages (``"pin drag"``).
    kind_name: ClassVar[str] = "reaction-dependent force"

    @property
    def width(self) -> int:
        """The number of relative speeds (rows) the element acts along, each with its own
        force, stick and limit (static); 1 by default. With ``w > 1`` the methods below take
        and give (w,) where they take and give a scalar for one row."""
        return 1

    def reaction_rows(self) -> tuple[str, ...]:
        """The labels of the constraint rows whose multipliers the element reads
        (``("pin.x", "pin.y")``; a joint's rows are named ``joint.label``)."""
        raise NotImplementedError

    def relative_coordinate(self, model, q) -> jax.Array:
        """``s(q)`` [rad or length], a scalar: the coordinate the force acts along (its
        generalized force is ``f ds/dq``), of the bound ``model`` at positions ``q`` (nq,)."""
        raise NotImplementedError

    def relative_direction(self, model, q) -> jax.Array:
        """``D(q)`` (nq,), or (nq, w) for ``w`` rows: the relative speed ``v = D^T qd``
        [velocity or angular velocity] along which the force acts (its generalized force is
        ``D f``); by default the gradient of :meth:`relative_coordinate`."""
        return jax.grad(lambda q: self.relative_coordinate(model, q))(q)

    def state_load(self, model, q, qd, t) -> jax.Array:
        """The element's load that is no reaction (j,) at ``(q, qd, t)`` (a compliant
        contact's normal force [force]), appended to its reactions in the methods below; by
        default none."""
        return jnp.zeros((0,), dtype=jnp.result_type(q, qd))

    def slip_force(self, v, reactions) -> jax.Array:
        """The force ``f`` [force or torque] at the relative speed ``v`` outside the stick band
        (positive along ``s``; (w,) at ``v`` (w,) for ``w`` rows), from ``reactions`` (k,),
        the multipliers of :meth:`reaction_rows` in their order."""
        raise NotImplementedError

    def stick_band(self) -> jax.Array:
        """The relative speed below which the element sticks [velocity or angular velocity];
        0: it never sticks."""
        return jnp.zeros(())

    def holding_limit(self, reactions) -> jax.Array:
        """The largest force magnitude with which the element holds its joint at rest
        [force or torque] ((w,) for ``w`` rows), from ``reactions`` (k,); 0 for an element
        that never sticks (a row with limit 0 never sticks)."""
        return jnp.zeros(())

    def speed_output(self, v, reactions) -> jax.Array:
        """The element's ``.speed`` column from its rows' relative speeds ``v`` (a scalar, or
        (w,)) and ``reactions``; by default ``v`` (one row)."""
        return v

    def reaction_outputs(self, reactions) -> dict[str, jax.Array]:
        """The element's own result columns by suffix from ``reactions`` (k,) (the analysis
        adds the force, column ``name``, the relative speed ``.speed`` and ``.power``)."""
        return {}

    def generalized(self, q, qd, t, nq):
        """Zero: the force is the analysis' (it needs the reactions)."""
        return jnp.zeros(nq)

    @property
    def no_arrow(self) -> str | None:
        """Why the element has no arrow in an animation, completing ``"'name' ...: it has no
        arrow"`` (``"is a torque"``), or None where :meth:`arrow` draws one."""
        return f"is a {self.kind_name} without a line of action"

    def arrow(self, model, q):
        """Where the force is drawn, over a motion ``q`` (N, nq) (NumPy): ``(body, point (2,)
        in its frame, direction (N, 2) [1])`` (a point that moves on its body: body -1, the
        ground, and its positions (N, 2)), the force being its column times the direction;
        None where it has no arrow (:attr:`no_arrow`)."""
        return None


__all__ = ["ReactionDependent"]
