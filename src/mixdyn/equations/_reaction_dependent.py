"""Reaction-dependent forces in the equations of motion, solved with the accelerations
(:class:`~mixdyn.model._reaction_dependent.ReactionDependent`: the elements' contract).

For the reaction-dependent elements of a model, with ``nf`` their rows in all (an element
acts along one relative speed, or along ``w`` of them: a contact's friction, one a contact
point, :attr:`~mixdyn.model._reaction_dependent.ReactionDependent.width`), ``D`` (nq, nf) the
rows' relative speeds per unit of ``qd`` (``ds/dq`` for a relative coordinate ``s(q)``) and the
forces ``f`` (nf,) along them:

    M qdd + G mu = Q + D f,     C qdd = gamma

The KKT matrix does not depend on ``f``: factorized once, it gives ``qdd = qdd0 + A f`` and
``mu = mu0 + Mu_f f`` (``nf`` extra solves), the relative accelerations ``a = a0 + H f``
(``H = D^T A``), and each element's forces from its reaction rows of ``mu``. Per element:

- moving (``|v_k|`` at or above its stick band): its slip force ``f_k(v_k, R_k(mu))``;
- sticking (``|v_k|`` inside the band): ``f_k`` such that ``a_k = 0``, solved jointly for the
  sticking rows (:func:`held`: the least-norm forces where rows depend on each other, as the
  two corners of a block flat on the ground, whose split the rigid bodies leave open); one
  whose force would exceed its holding limit ``L_k(R_k(mu))`` pushes at the limit, in the
  direction of the force it needed, and the others take the rest; a row whose limit is 0 (a
  contact point that does not touch) never sticks. The integrators bring a sticking row's
  speed to exactly 0 after each step
  (:meth:`~mixdyn.analysis._problem.Problem.halt_sticking`), so that ``a_k = 0`` holds it
  where it stopped.

The forces depend on the reactions, which depend on ``f``: the fixed point ``f = F(f)``, the
rows' states found by a fixed-point iteration of :data:`ITERATIONS` steps (each a small
``nf x nf`` solve; the factorization is reused), then one step of Newton's method with those
states (``dF/df`` by ``jax.jacfwd``), exact for Coulomb's law, which is affine in the
reactions (the iteration alone converges only as fast as ``|dF/df|``: for a box sliding on
one corner, ``mu dN/df`` = 0.23, not to 1e-8 in 12 steps); where no element's load is a
reaction (a compliant contact's friction) there is no Newton step. Forces whose last step
changes them by more than :data:`SETTLED` of their scale (self-locking: a force that would
lock its joint whatever the load, no fixed point) are returned as NaN, which ends a run
with a named numerical error.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..errors import ModelError

#: Fixed-point steps for the forces' dependence on the reactions (then one Newton step).
ITERATIONS = 12
#: Relative change of the forces in their last step (``F(f) - f``) above which they have not
#: settled.
SETTLED = 1e-8
#: Sticking rows count as dependent along the directions in which their matrix, scaled to a
#: unit diagonal, has a singular value below this fraction of its largest (rows at an angle
#: of about 1e-3 rad or less in the metric of the mass: a block's corners on a line, its tilt
#: from the contact's compliance).
DEPENDENT = 1e-6


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


def spans(elements) -> list[slice]:
    """Per element, its rows among the ``nf`` (static): ``width`` rows each, in order."""
    out, start = [], 0
    for f in elements:
        out.append(slice(start, start + f.width))
        start += f.width
    return out


def _own(e, x, span: slice):
    """Element ``e``'s share of a row quantity ``x`` (nf,): a scalar for one row, else (w,)."""
    return x[span.start] if e.width == 1 else x[span]


def _rows(e, x) -> jax.Array:
    """An element's row quantity (a scalar or (w,)) as (w,)."""
    return jnp.broadcast_to(jnp.reshape(x, (-1,)), (e.width,))


def directions(model, elements, q) -> jax.Array:
    """``D`` (nq, nf): each row's relative speed per unit of ``qd``
    (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.relative_direction`; the
    gradient of the element's relative coordinate)."""
    nq = q.shape[0]
    return jnp.concatenate(
        [jnp.reshape(f.relative_direction(model, q), (nq, f.width)) for f in elements], axis=1
    )


def bands(elements) -> jax.Array:
    """The rows' stick bands (nf,) [velocity or angular velocity]."""
    return jnp.concatenate([_rows(f, f.stick_band()) for f in elements])


def limits(elements, positions, mu, state_loads=None) -> jax.Array:
    """The rows' holding limits (nf,) [force or torque] from the multipliers ``mu`` and the
    loads from the state."""
    R = reactions(positions, mu, state_loads)
    return jnp.concatenate([_rows(f, f.holding_limit(r)) for f, r in zip(elements, R, strict=True)])


def columns(elements, positions, f, v, mu, state_loads=None) -> dict:
    """The elements' result columns at one state, from the rows' forces ``f`` and speeds
    ``v`` (nf,): ``name`` (the element's force, its rows' summed), the element's own
    (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.reaction_outputs`),
    ``name.speed`` (:meth:`~mixdyn.model._reaction_dependent.ReactionDependent.speed_output`:
    its row's speed for one row) and ``name.power`` (``sum f_k v_k``)."""
    out = {}
    R = reactions(positions, mu, state_loads)
    for e, r, span in zip(elements, R, spans(elements), strict=True):
        out[e.name] = jnp.sum(f[span])
        out.update({f"{e.name}.{key}": x for key, x in e.reaction_outputs(r).items()})
        out[f"{e.name}.speed"] = e.speed_output(_own(e, v, span), r)
        out[f"{e.name}.power"] = jnp.sum(f[span] * v[span])
    return out


def may_depend(elements) -> bool:
    """Whether the rows of ``elements`` may depend on each other (static): where an element
    acts along several rows (a contact's friction at its points). One row an element (joint
    frictions) keeps the plain solve."""
    return any(e.width > 1 for e in elements)


def held(H, stick, rhs, dependent: bool = True) -> jax.Array:
    """``x`` (nf,) with ``H_ss x_s = rhs_s`` over the sticking rows ``s`` (``stick`` (nf,),
    bool) and ``x = rhs`` elsewhere, from ``H`` (nf, nf): the stick forces (or, after a step,
    the impulses that halt the sticking rows).

    Rows that depend on each other (``dependent``, static: :func:`may_depend`; a block's two
    corners on a line, their sliding speeds the same) leave ``x_s`` open along their null
    space: the solve takes the least-norm ``x_s`` of ``H_ss`` scaled to a unit diagonal (its
    pseudo-inverse, singular values below :data:`DEPENDENT` of the largest taken as 0),
    finite and shared among the rows; for independent rows it is the solution, which
    ``dependent=False`` finds by a plain solve. The sticking rows' ``H_kk`` are positive
    (the rows are free to move, :func:`solve`)."""
    n = H.shape[0]
    both = stick[:, None] & stick[None, :]
    if not dependent:
        return jnp.linalg.solve(jnp.where(both, H, jnp.eye(n)), rhs)
    scale = 1.0 / jnp.sqrt(jnp.where(stick, jnp.diag(H), 1.0))
    B = jnp.where(both, scale[:, None] * H * scale[None, :], jnp.eye(n))
    x = scale * (jnp.linalg.pinv(B, rtol=DEPENDENT) @ (scale * rhs))
    return jnp.where(stick, x, rhs)


def solve(elements, positions, v, a0, H, mu0, Mu_f, h_free, state_loads=None):
    """The rows' forces ``f`` (nf,) and whether each row sticks, from the relative speeds
    ``v`` (nf,), the relative accelerations without the forces ``a0`` (nf,), ``H`` (nf, nf),
    the multipliers ``mu0 + Mu_f f`` and the loads from the state (:func:`loads`).
    ``h_free`` (nf,): ``d_k^T M^-1 d_k``, the scale of ``H_kk`` for a row free to move: one
    whose ``H_kk`` is below 1e-10 of it cannot be held (its motion is prescribed by the other
    constraints, as in an inverse analysis): at rest it pushes at its limit against its
    relative acceleration ``a0``."""
    band = jnp.abs(v) < bands(elements)
    free = jnp.diag(H) > 1e-10 * h_free
    where = spans(elements)
    dependent = may_depend(elements)

    def step(f, stick):
        mu = mu0 + Mu_f @ f
        lim = limits(elements, positions, mu, state_loads)
        R = reactions(positions, mu, state_loads)
        slip = jnp.concatenate(
            [
                _rows(e, e.slip_force(_own(e, v, span), r))
                for e, r, span in zip(elements, R, where, strict=True)
            ]
        )
        # rows not sticking: their slip force (outside the band), or at the limit in the
        # direction of the force they needed to stick (released inside the band)
        fixed = jnp.where(band, jnp.where(free, lim * jnp.sign(f), -lim * jnp.sign(a0)), slip)
        fixed = jnp.where(stick, 0.0, fixed)
        need = held(H, stick, jnp.where(stick, -(a0 + H @ fixed), fixed), dependent)
        over = stick & ((jnp.abs(need) > lim) | (lim <= 0.0))
        return jnp.where(over, lim * jnp.sign(need), need), stick & ~over

    # a row that holds with nothing (a contact point apart) takes no part in the stick solve
    holds = limits(elements, positions, mu0, state_loads) > 0.0
    f, stick = jnp.zeros(v.shape[0]), band & free & holds
    prev = f
    for _ in range(ITERATIONS):
        prev = f
        f, stick = step(f, stick)
    if any(positions):
        # Newton's step on f = F(f) with the rows' states found (exact for Coulomb's law,
        # affine in the reactions; a pin's is smooth): the iteration above converges only as
        # fast as |dF/df| (a box sliding on one corner: 0.23, 2e-8 after 12 steps). Forces
        # of loads from the state alone (a compliant contact's) settle in the iteration.
        def stepped(x):
            g, after = step(x, stick)
            return g, (g, after)

        dF, (g, after) = jax.jacfwd(stepped, has_aux=True)(f)
        polished = f + jnp.linalg.solve(jnp.eye(f.shape[0]) - dF, g - f)
        keep = jnp.all(after == stick) & jnp.all(jnp.isfinite(polished))
        prev = jnp.where(keep, polished, g)
        f, stick = step(prev, stick)  # settled where f = F(f)
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
    "bands",
    "check_supported",
    "columns",
    "directions",
    "elements",
    "held",
    "limits",
    "loads",
    "may_depend",
    "reactions",
    "rows",
    "solve",
    "spans",
]
