"""Resting rigid contacts: a contact point whose impacts accumulate is held on its contact.

A rigid contact point at rest on its pair (:mod:`._impacts`) keeps its gap at zero: its
penetration ``delta(q) = 0`` [length] is one more constraint row (a :class:`Hold`, built like
a driver with the law 0), placed after the joints and drivers (and before a mixed
problem's prescribed motions, whose multipliers are its unknown forces), so that the
constrained equations of motion of the projection method are integrated as they are::

    M qdd + Phi_q^T lambda + delta_q^T N = Q,     delta_q qdd = gamma_delta,

with ``delta_q = d delta / dq`` (1, nq) and its multiplier ``N`` the contact's normal force
[force]: the row's force on the bodies, ``-delta_q^T N``, pushes them apart along the
gap's gradient (as a compliant contact's ``-F grad(delta)``) while ``N >= 0``. The row's
velocity ``delta_q qd = 0`` makes its power zero: a resting contact does no work.

A contact with a friction coefficient ``mu`` adds Coulomb's friction at its held points
(:class:`RestFriction`, a reaction-dependent force as a joint's friction, Karnopp's stick
and slip): along each held point's sliding speed ``v_k = G_t,k qd`` (along ``z x n``), the
force ``-mu N_k sign(v_k)`` while it slides, and while it is still (``|v_k|`` inside the
stick band, the impacts' rest speed) the force that keeps it still, up to ``mu N_k``; its
load ``N_k`` is the held row's multiplier, solved with the accelerations
(:mod:`mixdyn.equations._reaction_dependent`). One problem per set of held points
(:func:`holding`), each compiled once.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp

from ..equations import Constraints
from ..linalg import DenseSolver
from ..model import Polynomial
from ..model._contact_friction import CoulombAtPoints
from ..model._drivers import Driver
from ..model._element import moving
from ._problem import Problem


class Hold(Driver):
    """The penetration of one contact point held at zero (a resting rigid contact).

    Attributes:
        contact: the rigid contact pair (a bound compliant-contact element).
        index: which of the pair's contact points (0 for a pair with one; not ``point``,
            a name the constraint set clears as naming a body point).
    """

    contact: eqx.Module
    index: int = eqx.field(static=True)
    bi: int = eqx.field(static=True, kw_only=True)
    bj: int = eqx.field(static=True, kw_only=True)
    #: A contact set's shapes' bodies (its ``bodies``); () for a pair (its ``bi``, ``bj``).
    bodies: tuple[int, ...] = eqx.field(static=True, default=(), kw_only=True)
    body_fields: ClassVar[tuple[str, ...]] = ("bi", "bj", "bodies")

    def measure(self, q):
        """The point's penetration ``delta(q)`` [length] (0 while it rests)."""
        contact = _on_bodies(self.contact, self.bi, self.bj, self.bodies)
        return jnp.atleast_1d(contact.penetration(q))[self.index]

    def body_indices(self):
        return moving(*self.bodies) if self.bodies else moving(self.bi, self.bj)


def _on_bodies(contact, bi: int, bj: int, bodies: tuple[int, ...] = ()):
    """``contact`` reading its bodies ``bi``, ``bj`` (a set's: ``bodies``) as the hold's
    (the model's, or a local vector's where the constraint set evaluates it per element),
    copied field by field (it is bound and checked already)."""
    changes = {"bi": bi, "bj": bj, **({"bodies": bodies} if bodies else {})}
    if all(getattr(contact, k) == v for k, v in changes.items()):
        return contact
    out = object.__new__(type(contact))
    for f in dataclasses.fields(contact):
        object.__setattr__(out, f.name, changes.get(f.name, getattr(contact, f.name)))
    return out


class RestFriction(CoulombAtPoints):
    """Coulomb friction at the held points of one rigid contact with ``mu`` (the module's
    description), one row a held point.

    Attributes:
        contact: the rigid contact pair (a bound compliant-contact element).
        points: the held points among the pair's contact points (w,), static.
        holds: the held points' row labels (w,) (:func:`hold`'s names), static.
        mu: the contact's friction coefficient [1].
        v_stick: the stick band [velocity]: the run's rest speed.
    """

    contact: eqx.Module
    points: tuple[int, ...] = eqx.field(static=True)
    holds: tuple[str, ...] = eqx.field(static=True)
    mu: jax.Array
    v_stick: jax.Array
    kind_name: ClassVar[str] = "resting friction"

    @property
    def width(self) -> int:
        """One row a held point."""
        return len(self.points)

    def body_indices(self):
        return ()

    def reaction_rows(self) -> tuple[str, ...]:
        """The held points' rows: their multipliers are the normal forces ``N_k``."""
        return self.holds

    def relative_direction(self, model, q):
        """``D`` (nq, w): the held points' sliding speeds (body j on body i, along
        ``z x n``) per unit of ``qd``."""
        idx = jnp.asarray(self.points)
        return jax.jacfwd(lambda qd: self.contact.sliding(q, qd)[idx])(jnp.zeros_like(q)).T

    @property
    def magnitude_kind(self):
        return "force"


def friction_at(contact, points: tuple[int, ...], count: int, v_stick) -> RestFriction:
    """The :class:`RestFriction` of rigid ``contact`` (with ``mu``) at its held ``points``
    (of ``count``), named ``{contact}.friction``, sticking below ``v_stick`` [velocity]."""
    holds = tuple(hold(contact, k, count).name for k in points)
    return RestFriction(
        f"{contact.name}.friction",
        contact,
        tuple(int(k) for k in points),
        holds,
        jnp.asarray(contact.mu, jnp.float64),
        jnp.asarray(v_stick, jnp.float64),
    )


def hold(contact, point: int, count: int) -> Hold:
    """The :class:`Hold` of ``contact``'s contact point ``point`` (of ``count``), named
    ``{contact}.rest`` (``{contact}.rest{point}`` for a pair with several points)."""
    name = f"{contact.name}.rest" + (str(point) if count > 1 else "")
    bodies = getattr(contact, "bodies", ())
    return Hold(
        name, contact, int(point), law=Polynomial([0.0]), bi=contact.bi, bj=contact.bj,
        bodies=tuple(bodies) if isinstance(bodies, tuple) else (),
    )  # fmt: skip


def holding(problem: Problem, holds: tuple[Hold, ...], frictions=()) -> Problem:
    """``problem`` with the rows of ``holds`` inserted after its joints' and drivers' kept
    rows and before its ``p`` prescribed motions (a mixed problem's last rows, whose
    multipliers are its unknown forces): the ``len(holds)`` multipliers before the last
    ``p`` are the held points' normal forces [force]; solved densely. ``frictions``: the
    held points' :class:`RestFriction` elements, added to the model's forces."""
    if not holds:
        return problem
    c, p, k = problem.c, problem.p, len(holds)
    first = c.n_full - p  # the first prescribed motion's row (one row per driver)
    active = [a if a < first else a + k for a in c.active]
    held = Constraints(
        c.joints,
        (*c.drivers[: len(c.drivers) - p], *holds, *c.drivers[len(c.drivers) - p :]),
        c.nq,
        sorted((*active, *range(first, first + k))),
        None if c.rank is None else c.rank + k,
        linear_solver=DenseSolver(),
    )
    model = problem.model
    if frictions:
        model = eqx.tree_at(lambda m: m.forces, model, (*model.forces, *frictions))
    return Problem(
        model,
        held,
        problem.unknown,
        problem.solver,
        problem.j_index,
        problem.i_index,
        problem.collocated,
    )


def hold_positions(problem: Problem) -> range:
    """The positions of the held points' rows among ``problem``'s kept rows (and of their
    normal forces among its multipliers): the ``k`` before the last ``p``."""
    k, m, p = n_holds(problem), problem.c.m, problem.p
    return range(m - p - k, m - p)


def n_holds(problem: Problem) -> int:
    """How many held contact points ``problem`` has (static)."""
    return sum(isinstance(d, Hold) for d in problem.c.drivers)


def normal_forces(problem: Problem, q, qd, t) -> jax.Array:
    """The held points' normal forces (k,) [force] at ``(q, qd, t)``: the multipliers of
    the accelerations' solve at :func:`hold_positions` (positive: the contact pushes)."""
    rows = hold_positions(problem)
    if not len(rows):
        return jnp.zeros(0, dtype=q.dtype)
    mu = problem.accelerations(q, qd, t)[1]
    return mu[rows.start : rows.stop]


__all__ = [
    "Hold",
    "RestFriction",
    "friction_at",
    "hold",
    "hold_positions",
    "holding",
    "n_holds",
    "normal_forces",
]
