"""Compliant contact: the base of the force elements for bodies that touch, collide and
rattle, and the declarations of their contact law.

Each contact pair (:mod:`~mixdyn.model._contact_pairs`) is a shape on body i and a shape on
body j (either may be the ground). The pair's geometry gives the penetration ``delta(q)``
[length] (contact while ``delta > 0``, negative: the gap), a scalar or one per contact
point, and the force of a compliant contact law (:mod:`~mixdyn.model._contact_law`) acts
along the normal with an optional regularized Coulomb friction across it. In generalized
coordinates::

    Q = -F grad_q(delta) + F_t grad_qd(v_t),

``F`` the normal force (from ``delta`` and ``delta_dot = grad_q(delta) . qd``), ``v_t`` the
sliding speed of j on i at the contact point (linear in ``qd``) and ``F_t`` the friction
force on j along the tangent: the normal force does work only through the penetration, so
that without damping (``restitution: 1``) and friction it derives from the potential
``K delta**2.5 / 2.5`` (:meth:`~_Compliant.potential`) and the energy is kept. Everything is
a pure JAX function of ``(q, qd)`` and the numbers of the element (derivatives by automatic
differentiation).

A pair whose ``contact_model`` is ``rigid`` exerts no force: its bodies collide with
Newton's restitution at the instants its penetration reaches zero (with ``mu``, Coulomb's
law on the impulses: :mod:`mixdyn.analysis._impact_friction`), and rest on each other once
the impacts accumulate, the penetration held at zero, without friction (forward and mixed
dynamics with impacts, :mod:`mixdyn.analysis._impacts`); it needs no material.

The stiffness of a compliant pair is Hertz's, from one material's Young's modulus and
Poisson's ratio and the pair's radii (:func:`~mixdyn.model._contact_law.hertz_stiffness`).
Joints with a ``clearance`` are such contacts (:mod:`~mixdyn.model._clearance`). Kinematic
and inverse analyses refuse a model with contacts (:func:`refuse_contacts`): the contact
force follows from a motion that no driver fixes.
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ._contact_law import (
    DAMPING_FACTORS,
    elastic_energy,
    friction_force,
    hertz_stiffness,
    normal_force,
)
from ._declare import option, quantity
from ._element import moving
from ._forces import _UNBOUND, ForceElement, _f64
from ._geometry import GROUND, pose


def _optional(x):
    return None if x is None else _f64(x)


def _safe_norm(d):
    """``|d|`` with a finite gradient (zero) where ``d = 0`` (a centred journal)."""
    dd = jnp.dot(d, d)
    positive = dd > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, dd, 1.0)), 0.0)


def _unit(d):
    """``d / |d|`` ([1, 0] where ``d = 0``)."""
    n = _safe_norm(d)
    safe = jnp.where(n > 0.0, n, 1.0)
    return jnp.where(n > 0.0, d / safe, jnp.array([1.0, 0.0]))


def _velocity(q, qd, b: int, P):
    """Velocity (2,) of the material point of body ``b`` at the global position ``P``."""
    if b == GROUND:
        return jnp.zeros(2, dtype=qd.dtype)
    r, _ = pose(q, b)
    w = qd[3 * b + 2]
    arm = P - r
    return qd[3 * b : 3 * b + 2] + w * jnp.stack([-arm[1], arm[0]])


# --------------------------------------------------------------------------- the contact law
def _young_modulus(optional: bool = False):
    return quantity(
        "pressure",
        "Young's modulus of both bodies' material, e.g. ``\"207 GPa\"`` (steel): with "
        "``poisson`` and the radii it gives Hertz's stiffness ``K = (4/3) E* sqrt(R*)``, "
        "``E* = E / (2 (1 - poisson**2))``.",
        *((None,) if optional else ()),
        converter=_optional if optional else _f64,
        above=0.0,
        kw_only=True,
    )


def _poisson(default):
    return quantity(
        "dimensionless",
        "Poisson's ratio of the material, in [0, 0.5). Default 0.3.",
        default,
        converter=_optional if default is None else _f64,
        at_least=0.0,
        kw_only=True,
    )


def _restitution(optional: bool = False):
    return quantity(
        "dimensionless",
        "Coefficient of restitution ``e``: a compliant contact's in (0, 1], which its damping "
        "reproduces for an impact at ``impact_speed`` (1: no damping, the energy is kept); a "
        "rigid contact's in [0, 1], Newton's (0: a perfectly plastic impact).",
        *((None,) if optional else ()),
        converter=_optional if optional else _f64,
        at_least=0.0,
        kw_only=True,
    )


def _impact_speed():
    return quantity(
        "velocity",
        "The impact speed ``v_ref`` for which the damping gives the restitution ``e`` "
        "(``delta_dot(-)`` of the papers, a constant here: the damping coefficient is "
        "``c(e) K / v_ref``). Required where ``restitution < 1``.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )


#: The contact models by file name: the compliant ones (by their damping) and the rigid one.
RIGID = "rigid"
CONTACT_MODELS = (*DAMPING_FACTORS, RIGID)


def _contact_model(default):
    return option(
        "The contact model: compliant, damped as ``lankarani_nikravesh`` (1990, ``e`` near 1, "
        "default), ``flores`` (2011, any ``e``) or ``hunt_crossley`` (1975); or ``rigid`` "
        "(contact pairs): impacts with Newton's restitution ``e`` (forward and mixed dynamics).",
        default,
        choices=CONTACT_MODELS if default is not None else (None, *DAMPING_FACTORS),
        kw_only=True,
    )


def _mu():
    return quantity(
        "dimensionless",
        "Coulomb friction coefficient at the contact (>= 0); default none (no friction, no "
        "friction column). A rigid contact: Coulomb's law on its impacts' impulses (stick or "
        "slip; its resting points slide without friction).",
        None,
        converter=_optional,
        at_least=0.0,
        kw_only=True,
    )


def _v_stick():
    return quantity(
        "velocity",
        "Friction's regularization speed: the friction is ``-mu F tanh(v_t / v_stick)``. "
        "Required with ``mu`` on a compliant contact; a rigid contact takes none.",
        None,
        converter=_optional,
        above=0.0,
        kw_only=True,
    )


def _check_law(e, name: str) -> None:
    """The checks of a contact law's numbers that their declared ranges do not make."""
    if getattr(e, "contact_model", None) == RIGID:
        if e.v_stick is not None:
            raise ModelError(
                "a rigid contact's friction acts in its impacts, which stick or slip exactly "
                "(Coulomb's law on the impulses): remove v_stick (the regularization of a "
                "compliant contact's friction)",
                name,
                field="v_stick",
            )
        if not np.all(np.asarray(e.restitution) <= 1.0):
            raise ModelError(
                "the coefficient of restitution must be in [0, 1], got "
                f"{np.asarray(e.restitution).tolist()}",
                name,
                field="restitution",
            )
        return
    if getattr(e, "contact_model", None) is not None and e.young_modulus is None:
        raise ModelError(
            "a compliant contact needs its material's Young's modulus (e.g. 207 GPa for "
            "steel), or contact_model: rigid",
            name,
            field="young_modulus",
        )
    if e.poisson is not None and not np.all(np.asarray(e.poisson) < 0.5):
        raise ModelError("Poisson's ratio must be below 0.5", name, field="poisson")
    if e.restitution is None:
        return
    r = np.asarray(e.restitution)
    if not np.all(r > 0.0):
        raise ModelError(
            "a compliant contact's damping grows without bound as its restitution falls to "
            f"0 (got {r.tolist()}): give restitution > 0 (e.g. 0.05 with contact_model: "
            "flores), or contact_model: rigid for a perfectly plastic impact",
            name,
            field="restitution",
        )
    if not np.all(r <= 1.0):
        raise ModelError(
            f"a compliant contact's restitution must be in (0, 1], got {r.tolist()}",
            name,
            field="restitution",
        )
    if e.impact_speed is None and not np.all(r == 1.0):
        raise ModelError(
            "a contact that loses energy (restitution < 1) needs the impact speed for which "
            "its damping gives that restitution: give impact_speed (e.g. the relative speed "
            "of a typical impact)",
            name,
            field="impact_speed",
        )
    if e.mu is not None and e.v_stick is None:
        raise ModelError(
            "friction needs its regularization speed v_stick (e.g. 1 mm/s)", name, field="v_stick"
        )


class _Compliant(ForceElement):
    """A compliant contact between body i and body j: a subclass gives the penetration
    ``delta(q)`` [length], the contact point and the tangent (:meth:`frame`) and the
    effective radius ``R*`` of Hertz's stiffness (:meth:`effective_radius`)."""

    young_modulus: jax.Array | None = _young_modulus(optional=True)
    poisson: jax.Array = _poisson(0.3)
    restitution: jax.Array = _restitution()
    impact_speed: jax.Array | None = _impact_speed()
    contact_model: str = _contact_model("lankarani_nikravesh")
    mu: jax.Array | None = _mu()
    v_stick: jax.Array | None = _v_stick()
    bi: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    bj: int = eqx.field(static=True, default=_UNBOUND, kw_only=True)
    si: jax.Array | None = eqx.field(default=None, kw_only=True)
    sj: jax.Array | None = eqx.field(default=None, kw_only=True)
    #: What the contact is, in messages; and whether a joint's ``clearance`` makes it.
    described: ClassVar[str] = "a compliant contact"
    of_a_joint: ClassVar[bool] = False

    def __check_init__(self):
        _check_law(self, self.name)

    def body_indices(self):
        return moving(self.bi, self.bj)

    # what a shape pair gives
    def penetration(self, q) -> jax.Array:
        """``delta(q)`` [length]: positive in contact, negative the gap; a scalar, or (k,)
        for a pair that touches at k places (a slider's corners)."""
        raise NotImplementedError

    def frame(self, q) -> tuple[jax.Array, jax.Array]:
        """``(P, n)``: the contact point (2,) [length] and the unit normal (2,) along which
        the contact pushes body j; (k, 2) each for k places."""
        raise NotImplementedError

    def effective_radius(self) -> jax.Array:
        """Hertz's effective radius ``R*`` of the pair [length]."""
        raise NotImplementedError

    # the law
    @property
    def rigid(self) -> bool:
        """Whether the pair collides by impacts (``contact_model: rigid``) and exerts no
        force."""
        return self.contact_model == RIGID

    @property
    def stiffness(self) -> jax.Array:
        """Hertz's stiffness ``K`` [force / length**1.5]."""
        return hertz_stiffness(self.young_modulus, self.poisson, self.effective_radius())

    def sliding(self, q, qd):
        """The sliding speeds of j on i at the contact points, along ``z x n`` (k,)
        [velocity]."""
        P, n = (jnp.atleast_2d(x) for x in self.frame(q))
        t = jnp.stack([-n[:, 1], n[:, 0]], axis=1)

        def one(P, t):
            return jnp.dot(_velocity(q, qd, self.bj, P) - _velocity(q, qd, self.bi, P), t)

        return jax.vmap(one)(P, t)

    def _delta(self, q):
        return jnp.atleast_1d(self.penetration(q))

    def _state(self, q, qd):
        """``(delta (k,), d delta / dq (k, nq), F (k,), F_t (k,) or None)`` at the state."""
        delta = self._delta(q)
        J = jax.jacfwd(self._delta)(q)
        speed = 1.0 if self.impact_speed is None else self.impact_speed
        F = normal_force(delta, J @ qd, self.stiffness, self.restitution, speed, self.contact_model)
        if self.mu is None:
            return delta, J, F, None
        return delta, J, F, friction_force(F, self.sliding(q, qd), self.mu, self.v_stick)

    def passive(self, q, qd, t, nq):
        """The contact's generalized force (nq,): evaluated where a penetration is positive,
        zero without computing it elsewhere (a narrow phase that costs one penetration while
        the pair is apart); zero for a rigid contact (its impacts are impulses)."""
        if self.rigid:
            return jnp.zeros(nq, dtype=jnp.result_type(q, qd))

        def touching(q, qd):
            _, J, F, Ft = self._state(q, qd)
            Q = -F @ J
            if Ft is not None:
                Q = Q + Ft @ jax.jacfwd(self.sliding, argnums=1)(q, qd)
            return Q

        def apart(q, qd):
            return jnp.zeros(nq, dtype=jnp.result_type(q, qd))

        return jax.lax.cond(jnp.any(self._delta(q) > 0.0), touching, apart, q, qd)

    def potential(self, q):
        """The elastic energy ``K delta**2.5 / 2.5`` [energy], summed over the contact
        points (the damping and the friction count as non-conservative work); 0 for a rigid
        contact."""
        if self.rigid:
            return jnp.zeros((), dtype=q.dtype)
        return jnp.sum(elastic_energy(self._delta(q), self.stiffness))

    def outputs(self, q, qd, t):
        """``normal``: the normal force [force] (>= 0); ``penetration`` [length] (negative:
        the gap); ``friction``: the friction force on body j along ``z x n`` [force], where
        ``mu`` is given. For several contact points: the sum of the forces and the deepest
        penetration. A rigid contact: ``penetration``, and ``normal`` 0 here (its impulses
        are the run's ``{name}.impulse`` events; the run fills in the normal force while it
        rests, :mod:`mixdyn.analysis._impacts`)."""
        if self.rigid:
            delta = self._delta(q)
            return {"normal": jnp.zeros((), delta.dtype), "penetration": jnp.max(delta)}
        delta, _, F, Ft = self._state(q, qd)
        out = {"normal": jnp.sum(F), "penetration": jnp.max(delta)}
        if Ft is not None:
            out["friction"] = jnp.sum(Ft)
        return out

    def drawing(self) -> dict:
        """What an animation draws of the contact's shapes (as a joint's
        :meth:`~mixdyn.Joint.drawing`): ``circles`` [(body, body point, radius)], ``guides``
        [(ground point, direction)] (lines on the ground)."""
        return {}

    def arrow(self, q, qd, normal=None, friction=None) -> tuple[np.ndarray, np.ndarray]:
        """The contact's force on body j as an arrow: ``(at, F)``, the contact point (N, 2)
        [length] (of the largest force, where the pair touches at several) and the force
        (N, 2) [force] (normal and friction, summed over the contact points), from the
        coordinates ``q`` and velocities ``qd`` (N, nq). A rigid contact: its normal force
        ``normal`` (N,) [force] (the run's ``{name}.normal``, nonzero while it rests) along
        the normal at its deepest point, and its resting friction ``friction`` (N,) [force]
        (the run's ``{name}.friction``) along the tangent ``z x n`` there; zero where not
        given."""
        none = np.zeros(np.shape(q)[0])
        normal = none if normal is None else np.asarray(normal, float)
        friction = none if friction is None else np.asarray(friction, float)

        def one(q, qd, N, T):
            if self.rigid:
                P, n = (jnp.atleast_2d(x) for x in self.frame(q))
                k = jnp.argmax(self._delta(q))
                return P[k], N * n[k] + T * jnp.stack([-n[k, 1], n[k, 0]])
            _, _, F, Ft = self._state(q, qd)
            P, n = (jnp.atleast_2d(x) for x in self.frame(q))
            force = F[:, None] * n
            if Ft is not None:
                force = force + Ft[:, None] * jnp.stack([-n[:, 1], n[:, 0]], axis=1)
            return P[jnp.argmax(F)], jnp.sum(force, axis=0)

        at, F = jax.vmap(one)(
            jnp.asarray(q), jnp.asarray(qd), jnp.asarray(normal), jnp.asarray(friction)
        )
        return np.asarray(at), np.asarray(F)

    @property
    def output_kinds(self):
        if self.rigid:
            return {"normal": "force", "penetration": "length"}
        kinds = {"normal": "force", "penetration": "length"}
        if self.mu is not None:
            kinds["friction"] = "force"
        return kinds


def contacts(model) -> tuple[_Compliant, ...]:
    """The model's compliant contacts (its clearance joints included)."""
    return tuple(f for f in model.forces if isinstance(f, _Compliant))


def refuse_contacts(model, analysis: str) -> None:
    """Raise a :class:`~mixdyn.errors.ModelError` naming the first contact of ``model``: a
    ``analysis`` (kinematic or inverse) run prescribes the whole motion, and a contact's
    force follows from a motion that no driver fixes."""
    found = contacts(model)
    if not found:
        return
    c = found[0]
    article = "an" if analysis[0] in "aeiou" else "a"
    raise ModelError(
        f"is {c.described}: {article} {analysis} analysis prescribes the whole motion, while "
        "a contact's force decides how the bodies move; run a forward or mixed analysis "
        "(prescribe the driven motions, seek their efforts)"
        + (", or give the joint no clearance" if c.of_a_joint else ""),
        c.name,
    )


def rigid_contacts(model) -> tuple[_Compliant, ...]:
    """The model's rigid contacts (``contact_model: rigid``)."""
    return tuple(c for c in contacts(model) if c.rigid)


def refuse_rigid(model, analysis: str) -> None:
    """Raise a :class:`~mixdyn.errors.ModelError` naming the first rigid contact of
    ``model``: its impacts are solved by forward and mixed dynamics only (``analysis``: what refuses
    them, e.g. ``"a mixed analysis"``)."""
    found = rigid_contacts(model)
    if found:
        raise ModelError(
            f"is a rigid contact (contact_model: rigid): {analysis} does not take impacts; run "
            "a forward or mixed analysis, or give the contact a compliant contact_model (e.g. "
            "lankarani_nikravesh with young_modulus and impact_speed)",
            found[0].name,
            field="contact_model",
        )


__all__ = ["contacts", "refuse_contacts", "refuse_rigid", "rigid_contacts"]
