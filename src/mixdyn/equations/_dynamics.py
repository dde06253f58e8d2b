"""Mass matrix, applied forces and energies of a model.

``M = diag(m_i, m_i, J_i)`` is diagonal in absolute coordinates with the body frames at the
centres of mass; it is kept as its diagonal, shape (nq,).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..model import Model


def gravity_force(model: Model) -> jax.Array:
    """Generalized gravity force (nq,) [force]: ``[m g_x, m g_y, 0]`` per body."""
    m = jnp.stack([b.mass for b in model.bodies])
    return jnp.stack([m * model.gravity[0], m * model.gravity[1], jnp.zeros_like(m)], 1).ravel()


def applied_forces(model: Model, q, qd, t, exclude: tuple[str, ...] = ()) -> jax.Array:
    """``Q^A(q, qd, t)`` (nq,): gravity plus every force element not named in ``exclude``.

    For an excluded element only the magnitude part is left out: its passive part (spring and
    damper of an actuator declared unknown) still acts.
    """
    Q = gravity_force(model)
    for f in model.forces:
        if f.name in exclude:
            Q = Q + f.passive(q, qd, t, model.nq)
        else:
            Q = Q + f.generalized(q, qd, t, model.nq)
    return Q


def largest_load(model: Model, q, t, D) -> jax.Array:
    """The largest single load at rest: ``max |Q_e,i| D_i`` over gravity and each force
    element ``e`` taken alone at ``q`` and ``t`` (``qd = 0``), ``D`` (nq,) the coordinates'
    scales [force * length, or energy per rad] — unlike the sum ``Q^A``, which vanishes
    wherever the loads balance (a start at the equilibrium)."""
    zero = jnp.zeros_like(q)
    parts = [gravity_force(model)] + [f.generalized(q, zero, t, model.nq) for f in model.forces]
    return jnp.max(jnp.stack([jnp.max(jnp.abs(p) * D) for p in parts]))


def force_outputs(model: Model, q, qd, t, exclude: tuple[str, ...] = ()) -> dict:
    """The known force elements' result columns (those not in ``exclude``): each element's
    :meth:`~mixdyn.model.ForceElement.outputs` (``name``, ``name.length``...) and its power
    ``name.power = Q . qd`` [power]. Values () each."""
    out = {}
    for f in model.forces:
        if f.name in exclude or f.needs_reactions:  # reaction-dependent: the analysis' columns
            continue
        for suffix, v in f.outputs(q, qd, t).items():
            out[f"{f.name}.{suffix}" if suffix else f.name] = v
        out[f"{f.name}.power"] = jnp.dot(f.generalized(q, qd, t, model.nq), qd)
    return out


def force_output_kinds(model: Model, exclude: tuple[str, ...] = ()) -> dict[str, str]:
    """The kinds of quantity of :func:`force_outputs`' columns."""
    out = {}
    for f in model.forces:
        if f.name in exclude:
            continue
        for suffix, kind in f.output_kinds.items():
            out[f"{f.name}.{suffix}" if suffix else f.name] = kind
        out[f"{f.name}.power"] = "power"
    return out


def force_directions(model: Model, names: tuple[str, ...], q, qd, t) -> jax.Array:
    """Matrix ``B`` (nq, len(names)): generalized force per unit magnitude of each element."""
    cols = [model.element(n).direction(q, qd, t, model.nq) for n in names]
    if not cols:
        return jnp.zeros((model.nq, 0))
    return jnp.stack(cols, axis=1)


def potential_energy(model: Model, q) -> jax.Array:
    """Potential energy [energy]: gravity (``-m g . r``) plus the springs'."""
    V = -jnp.dot(gravity_force(model), q)
    for f in model.forces:
        V = V + f.potential(q)
    return V


def kinetic_energy(model: Model, qd) -> jax.Array:
    """Kinetic energy ``qd^T M qd / 2`` [energy]."""
    return 0.5 * jnp.sum(model.mass_diagonal * qd**2)


def nonconservative_power(model: Model, q, qd, t, exclude: tuple[str, ...] = ()) -> jax.Array:
    """Power of the applied forces that do not derive from the potential [power]."""
    dV = jax.grad(lambda qq: potential_energy(model, qq))(q)
    return jnp.dot(applied_forces(model, q, qd, t, exclude) + dV, qd)
