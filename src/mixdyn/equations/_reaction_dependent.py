"""Reaction-dependent forces in the equations of motion, solved with the accelerations
(:class:`~mixdyn.model._reaction_dependent.ReactionDependent`: the elements' contract).

For the ``nf`` reaction-dependent elements of a model, with ``s_k(q)`` the relative
coordinate of element ``k``, ``D = ds/dq`` (nq, nf) and the forces ``f`` (nf,) along them:

    M qdd + G mu = Q + D f,     C qdd = gamma

The KKT matrix does not depend on ``f``: factorized once, it gives ``qdd = qdd0 + A f`` and
``mu = mu0 + Mu_f f`` (``nf`` extra solves), the relative accelerations ``a = a0 + H f``
(``H = D^T A``), and each element's forces from its reaction rows of ``mu``. Per element:

- moving (``|v_k|`` at or above its stick band): its slip force ``f_k(v_k, R_k(mu))``;
- sticking (``|v_k|`` inside the band): ``f_k`` such that ``a_k = 0``, solved jointly for the
  sticking elements; one whose force would exceed its holding limit ``L_k(R_k(mu))`` pushes
  at the limit, in the direction of the force it needed. The integrators bring a sticking
  element's speed to exactly 0 after each step
  (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so that ``a_k = 0`` holds it
  where it stopped.

The forces depend on the reactions, which depend on ``f``: a fixed-point iteration of
:data:`ITERATIONS` steps (each a small ``nf x nf`` solve; the factorization is reused). Forces
that do not settle there (self-locking: a force that would lock its joint whatever the
load) are returned as NaN, which ends a run with a named numerical error.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..errors import ModelError

#: Fixed-point steps for the forces' dependence on the reactions.
ITERATIONS = 12
#: Relative change of the forces in the last step above which they have not settled.
SETTLED = 1e-8


def elements(model) -> tuple:
    """The model's reaction-dependent elements (static)."""
    return tuple(f for f in model.forces if f.needs_reactions)


def rows(model, c, elements) -> list[tuple[int, ...]]:
    """Per element, the positions in the multipliers ``mu`` of the constraint set ``c`` of
    its reaction rows (``reaction_rows``)."""
    out = []
    for f in elements:
        pos = []
        for label in f.reaction_rows():
            full = c.labels.index(label)
            if full not in c.active:
                raise ModelError(
                    f"the reaction row {label!r} that this {f.kind_name} depends on is "
                    "redundant (its force is not determined); remove the redundancy or the "
                    "element",
                    f.name,
                )
            pos.append(c.active.index(full))
        out.append(tuple(pos))
    return out


def loads(model, elements, q, qd, t) -> list[jax.Array]:
    """Per element, its load that is no reaction (j,) at the state
    (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.state_load`)."""
    return [f.state_load(model, q, qd, t) for f in elements]


def reactions(positions, mu, state_loads=None) -> list[jax.Array]:
    """Per element, its reaction multipliers (k,) from ``mu`` (m,), followed by its load
    from the state (``state_loads``, :func:`loads`; none where not given)."""
    out = []
    for k, pos in enumerate(positions):
        r = jnp.stack([mu[i] for i in pos]) if pos else jnp.zeros((0,), mu.dtype)
        if state_loads is not None:
            r = jnp.concatenate([r, state_loads[k]])
        out.append(r)
    return out


def directions(model, elements, q) -> jax.Array:
    """``D`` (nq, nf): each element's relative speed per unit of ``qd``
    (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.relative_direction`; the
    gradient of its relative coordinate)."""
    return jnp.stack([f.relative_direction(model, q) for f in elements], axis=1)


def limits(elements, positions, mu, state_loads=None) -> jax.Array:
    """The holding limits (nf,) [force or torque] from the multipliers ``mu`` and the loads
    from the state."""
    R = reactions(positions, mu, state_loads)
    return jnp.stack([f.holding_limit(r) for f, r in zip(elements, R, strict=True)])


def columns(elements, positions, f, v, mu, state_loads=None) -> dict:
    """The elements' result columns at one state: ``name`` (the force ``f``), the element's
    own (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.reaction_outputs`),
    ``name.speed`` (``v``) and ``name.power`` (``f v``)."""
    out = {}
    R = reactions(positions, mu, state_loads)
    for k, (e, r) in enumerate(zip(elements, R, strict=True)):
        out[e.name] = f[k]
        out.update({f"{e.name}.{key}": x for key, x in e.reaction_outputs(r).items()})
        out[f"{e.name}.speed"] = v[k]
        out[f"{e.name}.power"] = f[k] * v[k]
    return out


def solve(elements, positions, v, a0, H, mu0, Mu_f, h_free, state_loads=None):
    """The forces ``f`` (nf,) and whether each element sticks, from the relative speeds
    ``v`` (nf,), the relative accelerations without the forces ``a0`` (nf,), ``H`` (nf, nf),
    the multipliers ``mu0 + Mu_f f`` and the loads from the state (:func:`loads`).
    ``h_free`` (nf,): ``d_k^T M^-1 d_k``, the scale of ``H_kk`` for an element free to move:
    one whose ``H_kk`` is below 1e-10 of it cannot be held (its motion is prescribed by the
    other constraints, as in an inverse analysis): at rest it pushes at its limit against its
    relative acceleration ``a0``."""
    nf = v.shape[0]
    band = jnp.abs(v) < jnp.stack([f.stick_band() for f in elements])
    free = jnp.diag(H) > 1e-10 * h_free
    eye = jnp.eye(nf)

    def step(f, stick):
        mu = mu0 + Mu_f @ f
        lim = limits(elements, positions, mu, state_loads)
        R = reactions(positions, mu, state_loads)
        slip = jnp.stack(
            [e.slip_force(v[k], r) for k, (e, r) in enumerate(zip(elements, R, strict=True))]
        )
        # elements not sticking: their slip force (outside the band), or at the limit in the
        # direction of the force they needed to stick (released inside the band)
        fixed = jnp.where(band, jnp.where(free, lim * jnp.sign(f), -lim * jnp.sign(a0)), slip)
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
    lim = limits(elements, positions, mu0 + Mu_f @ f, state_loads)
    scale = jnp.maximum(jnp.max(jnp.abs(f), initial=0.0), jnp.max(lim, initial=0.0))
    settled = jnp.max(jnp.abs(f - prev), initial=0.0) <= SETTLED * jnp.maximum(scale, 1e-300)
    return jnp.where(settled, f, jnp.nan), stick


def check_supported(model, analysis: str, hint: str = "remove it for this analysis") -> None:
    """Refuse reaction-dependent elements where they are not modelled (named input error)."""
    found = elements(model)
    if found:
        kinds = ", ".join(dict.fromkeys(f.kind_name for f in found))
        raise ModelError(
            f"{kinds} ({', '.join(f.name for f in found)}) is modelled in forward, mixed "
            f"and inverse dynamics with the explicit integrators, not in {analysis}; {hint}",
            found[0].name,
        )


__all__ = [
    "check_supported",
    "columns",
    "directions",
    "elements",
    "limits",
    "loads",
    "reactions",
    "rows",
    "solve",
]
