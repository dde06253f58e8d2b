"""Joint friction in the equations of motion: Coulomb's law with stick and slip, solved with
the accelerations (:class:`~mixdyn.model.JointFriction`).

For the ``nf`` friction elements of a model, with ``s_k(q)`` the relative coordinate of
joint ``k`` (revolute: ``phi_j - phi_i``; translational: the displacement along the axis,
``u_i . (r_Pj - r_Pi)``), ``D = ds/dq`` (nq, nf) and the friction forces ``f`` (nf,) along them:

    M qdd + G mu = Q + D f,     C qdd = gamma

The KKT matrix does not depend on ``f``: factorized once, it gives ``qdd = qdd0 + A f`` and
``mu = mu0 + Mu_f f`` (``nf`` extra solves), the relative accelerations ``a = a0 + H f``
(``H = D^T A``) and the limits ``mu_k N_k(mu)`` from the reactions. Per joint:

- slip (``|v_k| >= v_stick``): ``f_k = -limit_k sign(v_k)``;
- stick (``|v_k| < v_stick``): ``f_k`` such that ``a_k = 0``, solved jointly for the
  sticking joints; one whose force would exceed its limit slips at the limit, in the
  direction of the force it needed. The integrators bring a sticking joint's speed to
  exactly 0 after each step (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so
  that ``a_k = 0`` holds it where it stopped.

The limits depend on the reactions, which depend on ``f``: a fixed-point iteration of
:data:`ITERATIONS` steps (each a small ``nf x nf`` solve; the factorization is reused). A
friction force that does not settle there (self-locking: the friction would lock the joint
whatever the load) is returned as NaN, which ends a run with a named numerical error.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..errors import ModelError
from ..model._geometry import angle, vector

#: Fixed-point steps for the limits' dependence on the reactions.
ITERATIONS = 12
#: Relative change of the friction forces in the last step above which they have not settled.
SETTLED = 1e-8


def friction_elements(model) -> tuple:
    """The model's friction elements (static)."""
    return tuple(f for f in model.forces if f.needs_reactions)


def rows(model, c, elements) -> list[tuple[int, ...]]:
    """Per element, the positions in the multipliers of its joint's reaction rows
    (revolute: ``x, y``; translational: ``normal``)."""
    out = []
    for f in elements:
        wanted = ("x", "y") if f.rotary else ("normal",)
        pos = []
        for lab in wanted:
            label = f"{f.joint}.{lab}"
            full = c.labels.index(label)
            if full not in c.active:
                raise ModelError(
                    f"the reaction row {label!r} of the joint with friction is redundant (its "
                    "force is not determined); remove the redundancy or the friction",
                    f.name,
                )
            pos.append(c.active.index(full))
        out.append(tuple(pos))
    return out


def relative_coordinates(model, elements, q) -> jax.Array:
    """``s(q)`` (nf,): each friction joint's relative coordinate [rad or length]."""
    out = []
    for f in elements:
        j = model.element(f.joint)  # checked to be a joint when the model was built
        if f.rotary:
            out.append(angle(q, j.bj) - angle(q, j.bi))
        else:
            out.append(jnp.dot(vector(q, j.bi, j.u), j._d(q)))
    return jnp.stack(out)


def directions(model, elements, q) -> jax.Array:
    """``D = ds/dq`` (nq, nf)."""
    return jax.jacfwd(lambda q: relative_coordinates(model, elements, q))(q).T


def limits(elements, positions, mu) -> tuple[jax.Array, jax.Array]:
    """``(limit (nf,), normal (nf,))``: the largest friction force [force or torque] and the
    normal reaction [force] from the multipliers ``mu``."""
    normal = []
    for pos in positions:
        normal.append(jnp.sqrt(jnp.maximum(sum(mu[i] ** 2 for i in pos), 1e-300)))
    normal = jnp.stack(normal)
    coef = jnp.stack([f.mu * (f.radius if f.rotary else 1.0) for f in elements])
    return coef * normal, normal


def solve_friction(elements, positions, v, a0, H, mu0, Mu_f, h_free):
    """The friction forces ``f`` (nf,) and whether each joint sticks, from the relative speeds
    ``v`` (nf,), the relative accelerations without friction ``a0`` (nf,), ``H`` (nf, nf),
    and the multipliers ``mu0 + Mu_f f``. ``h_free`` (nf,): ``d_k^T M^-1 d_k``, the scale of
    ``H_kk`` for a joint free to move: a joint whose ``H_kk`` is below 1e-10 of it cannot be
    held by its friction (its motion is prescribed by the other constraints, as in an inverse
    analysis): at rest it slips at the limit against its relative acceleration ``a0``."""
    nf = v.shape[0]
    band = jnp.abs(v) < jnp.stack([f.v_stick for f in elements])
    free = jnp.diag(H) > 1e-10 * h_free
    eye = jnp.eye(nf)

    def step(f, stick):
        lim, _ = limits(elements, positions, mu0 + Mu_f @ f)
        # joints not sticking: at the limit, against the motion (outside the band) or in the
        # direction of the force they needed to stick (released inside the band)
        fixed = jnp.where(
            band, jnp.where(free, lim * jnp.sign(f), -lim * jnp.sign(a0)), -lim * jnp.sign(v)
        )
        fixed = jnp.where(stick, 0.0, fixed)
        A = jnp.where(stick[:, None] & stick[None, :], H, 0.0) + jnp.where(stick, 0.0, 1.0) * eye
        rhs = jnp.where(stick, -(a0 + H @ fixed), fixed)
        need = jnp.linalg.solve(A, rhs)
        over = stick & (jnp.abs(need) > lim)
        return jnp.where(over, lim * jnp.sign(need), need), stick & ~over

    f, stick = jnp.zeros(nf), band & free
    prev = f
    for _ in range(ITERATIONS):
        prev = f
        f, stick = step(f, stick)
    lim, _ = limits(elements, positions, mu0 + Mu_f @ f)
    scale = jnp.maximum(jnp.max(jnp.abs(f), initial=0.0), jnp.max(lim, initial=0.0))
    settled = jnp.max(jnp.abs(f - prev), initial=0.0) <= SETTLED * jnp.maximum(scale, 1e-300)
    return jnp.where(settled, f, jnp.nan), stick


def check_supported(model, analysis: str, hint: str = "remove it for this analysis") -> None:
    """Refuse joint friction where it is not modelled (named input error)."""
    fr = friction_elements(model)
    if fr:
        raise ModelError(
            f"joint friction ({', '.join(f.name for f in fr)}) is modelled in forward, mixed "
            f"and inverse dynamics with the explicit integrators, not in {analysis}; {hint}",
            fr[0].name,
        )


__all__ = [
    "check_supported",
    "directions",
    "friction_elements",
    "limits",
    "relative_coordinates",
    "rows",
    "solve_friction",
]
