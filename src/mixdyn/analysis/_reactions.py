"""Joint reactions and driver efforts in physical terms, from the multipliers.

The constraint force on the bodies is ``-Phi_q^T lambda``. For a joint between bodies i and j,
its rows give on body j a force ``F`` [force] at the body origin and a moment about it; the
reported moment ``M`` is taken about the joint's point on body j. The force on body i is ``-F``.

Only the entries of ``Phi_q`` in the joint's rows and body j's columns take part: they are taken
at the constraint set's static sparsity pattern from the operator (``values_on``, either path)
and summed by one segment sum.

Teeth (a gear pair, a rack and pinion) also push their pitch curves apart with the radial
force ``Fr = |Ft| tan(alpha)`` (:mod:`mixdyn.model._contacts`), a force pair along the line
of centres whose generalized force is ``Fr grad(s)`` (``s``: the joint's ``separation``).
The joints that hold the centres carry it: the multipliers ``w`` with ``Phi_q^T w = sum Fr
grad(s)`` (least squares through ``Phi_q Phi_q^T``, refined once) are added to the
multipliers before the reactions are taken. Where the other joints do not hold the
separation (``Phi_q^T w`` misses it by more than :data:`HELD`, relative), the radial force
would move the mechanism, which the equations of motion do not model: the reactions are NaN.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..errors import ModelError
from ..linalg import AutoSolver
from ..model._geometry import GROUND

#: Largest relative miss of the radial tooth forces by the joints that hold the centres.
HELD = 1e-7


def reaction_kinds(c: Constraints) -> dict[str, str]:
    """The reaction columns of :func:`reaction_columns` and their kinds of quantity."""
    kinds = {}
    for j in c.joints:
        if j.generic_reaction:
            kinds[f"{j.name}.Fx"] = kinds[f"{j.name}.Fy"] = "force"
            if j.carries_moment:
                kinds[f"{j.name}.M"] = "torque"
        kinds.update({f"{j.name}.{k}": v for k, v in j.contact_kinds.items()})
    return kinds


def contact_columns(c: Constraints, q, lam) -> dict:
    """The joints' own columns (a gear pair's tooth force, a rolling contact's normal and
    friction forces: ``Joint.contact``) at one state, from the multipliers ``lam`` (m,) of
    the kept rows (a dropped, redundant row counts 0)."""
    wanted = {k for k, j in enumerate(c.joints) if j.contact_kinds}
    out = {}
    for k, lj in _joint_multipliers(c, lam, wanted).items():
        j = c.joints[k]
        out.update({f"{j.name}.{key}": v for key, v in j.contact(q, lj).items()})
    return out


def _joint_multipliers(c: Constraints, lam, wanted) -> dict:
    """The multipliers (n_equations,) of the joints with the indices ``wanted``, keyed by
    index, from ``lam`` (m,) of the kept rows (a dropped, redundant row counts 0)."""
    where = {row: k for k, row in enumerate(c.active)}
    out, start = {}, 0
    for k, j in enumerate(c.joints):
        rows = range(start, start + j.n_equations)
        start += j.n_equations
        if k in wanted:
            zero = jnp.zeros((), lam.dtype)
            out[k] = jnp.stack([lam[where[r]] if r in where else zero for r in rows])
    return out


def with_tooth_forces(c: Constraints, q, lam, J):
    """The multipliers ``lam`` (m,) with the radial tooth forces of the meshes (joints with a
    ``separation``) carried by the joints that hold their centres (module docstring); ``lam``
    itself without meshes. ``J``: the operator ``Phi_q`` at ``q``."""
    meshes = [k for k, j in enumerate(c.joints) if hasattr(j, "separation")]
    if not meshes:
        return lam
    lam_j = _joint_multipliers(c, lam, set(meshes))
    Qr = jnp.zeros_like(q)
    for k in meshes:
        j = c.joints[k]
        Fr = j.contact(q, lam_j[k])["Fr"]
        Qr = Qr + Fr * jax.grad(j.separation)(q)
    inner = J.schur(jnp.ones_like(q))
    w = inner.solve(J.mv(Qr))
    w = w + inner.solve(J.mv(Qr - J.rmv(w)))
    miss = jnp.max(jnp.abs(J.rmv(w) - Qr))
    held = miss <= HELD * jnp.maximum(jnp.max(jnp.abs(Qr)), 1e-300)
    return jnp.where(held | (miss == 0.0), lam + w, jnp.nan)


def require_held_meshes(model, q, t0: float = 0.0, drivers=None) -> None:
    """Every mesh's separation held by the joints (module docstring), at the start ``q``
    (nq,): a gear whose centre no joint holds (a free body, a slot along the line of centres)
    would be pushed away by its radial tooth force, which the equations of motion do not
    model. The joints' Jacobian is the one the mobility analysis has just computed at
    ``(q, t0)`` with ``drivers`` (the same compiled program); each mesh's unit separating
    pair (:meth:`~mixdyn.model.GearPair.separating_pair`) is NumPy.

    Raises:
        ModelError: naming the first mesh whose separation the joints leave free.
    """
    meshes = [j for j in model.joints if hasattr(j, "separation")]
    if not meshes:
        return
    import scipy.sparse as sp
    from scipy.sparse.linalg import lsqr

    from ._structure import _jac, _sparse_jacobian

    c = Constraints.of(model, drivers)
    qn, tn = np.asarray(q, dtype=np.float64), np.asarray(t0, dtype=np.float64)
    if c._local_ok():
        J = _sparse_jacobian(c, qn, tn)[: c.n_joint_rows]
    else:
        J = sp.csr_matrix(
            np.asarray(_jac(c.with_linear_solver(AutoSolver()), qn, tn))[: c.n_joint_rows]
        )
    dense = J.shape[0] * J.shape[1] <= 250_000
    for j in meshes:
        g = np.zeros(model.nq)
        for b, at, force in j.separating_pair(qn):
            if b >= 0:  # not the ground
                r = at - qn[3 * b : 3 * b + 2]
                g[3 * b : 3 * b + 3] += (force[0], force[1], r[0] * force[1] - r[1] * force[0])
        if dense:
            w = np.linalg.lstsq(J.T.toarray(), g, rcond=None)[0] if J.shape[0] else np.zeros(0)
        else:
            w = lsqr(J.T.tocsr(), g, atol=1e-14, btol=1e-14, iter_lim=10 * J.shape[0])[0]
        if np.max(np.abs(J.T @ w - g)) > 10 * HELD * np.max(np.abs(g)):
            raise ModelError(
                f"{j.along_centres}, and no joint holds them apart: hold each wheel's centre "
                "with a revolute joint (on the ground or on a carrier) or the rack with a guide",
                j.name,
            )


def _reaction_bodies(c: Constraints):
    """Per joint: the body the reaction is reported on, the point (body frame) the moment is
    taken about, and the sign (-1 where body j is the ground and body i reports instead)."""
    out = []
    for j in c.joints:
        b, s = j.reaction_point()
        if b == GROUND:  # report on body i instead, with the sign flipped
            out.append((j.bi, j.si, -1.0))
        else:
            out.append((b, s, 1.0))
    return out


def _sparse_map(c: Constraints, bodies):
    """Static map of the nonzeros of ``Phi_q`` onto the reactions: the nonzeros taken (in a
    joint's rows and its reporting body's columns), their slot ``3 k + (x, y, phi)`` in the
    (n_joints, 3) reactions, and their sign."""
    rows, cols = c.coo()
    owners = np.asarray([c.owners[i] for i in c.active], dtype=np.int64)
    own = owners[rows]
    nj = len(c.joints)
    joint = own < nj
    body = np.full(rows.size, -2, dtype=np.int64)
    sign = np.zeros(rows.size)
    rb = np.asarray([b for b, _, _ in bodies], dtype=np.int64)
    rs = np.asarray([sg for _, _, sg in bodies])
    body[joint] = rb[own[joint]]
    sign[joint] = rs[own[joint]]
    take = np.flatnonzero(joint & (cols // 3 == body))
    return take, 3 * own[take] + cols[take] % 3, sign[take]


def joint_reactions(c: Constraints, q, t, lam, J=None) -> jax.Array:
    """Reactions (n_joints, 3) ``[Fx, Fy, M]`` of every joint at one time: the force and the
    moment (about the joint point) that body i exerts on body j (on body i, sign flipped, if j
    is the ground), from ``q`` (nq,), ``t`` and the multipliers ``lam`` (m,), the meshes'
    radial tooth forces included (module docstring); ``J``: the operator ``c.jacobian(q, t)``
    if already built. Vectorize over time with ``jax.vmap`` or ``jax.lax.map``."""
    nj = len(c.joints)
    if nj == 0:
        return jnp.zeros((0, 3))
    bodies = _reaction_bodies(c)
    rows, cols = c.coo()
    take, slot, sign = _sparse_map(c, bodies)
    J = c.jacobian(q, t) if J is None else J
    lam = with_tooth_forces(c, q, lam, J)
    v = J.values_on(rows, cols)
    contrib = -(v[take] * lam[rows[take]]) * sign
    w = jax.ops.segment_sum(contrib, jnp.asarray(slot), num_segments=3 * nj).reshape(nj, 3)
    b = np.asarray([b for b, _, _ in bodies], dtype=np.int64)
    s = jnp.stack([jnp.asarray(s, dtype=q.dtype) for _, s, _ in bodies])
    phi = q[3 * b + 2]
    cos, sin = jnp.cos(phi), jnp.sin(phi)
    rx = cos * s[:, 0] - sin * s[:, 1]  # the point's vector from the body origin, global
    ry = sin * s[:, 0] + cos * s[:, 1]
    F = w[:, :2]
    M = w[:, 2] - (rx * F[:, 1] - ry * F[:, 0])
    return jnp.concatenate([F, M[:, None]], axis=1)


def check_contacts(c: Constraints, ts, cols: dict, units: dict | None = None) -> None:
    """A one-sided contact (a joint with a ``unilateral`` column: a cam's ``F``, a rolling
    contact's ``N``) must push at every output time; where it pulls, the bodies separate.

    Raises:
        ContactLostError: at the first time (interpolated between outputs) the contact force
            crosses zero, with the joint's name and the force there.
    """
    from ..errors import ContactLostError

    for j in c.joints:
        key = getattr(j, "unilateral", None)
        if key is None:
            continue
        name = f"{j.name}.{key}"
        f = np.asarray(cols[name])
        tol = 1e-9 * float(np.max(np.abs(f), initial=0.0))
        bad = np.flatnonzero(f < -tol)
        if not bad.size:
            continue
        k = int(bad[0])
        t = float(ts[k])
        if k > 0 and f[k - 1] > 0:
            t = float(ts[k - 1] + (ts[k] - ts[k - 1]) * f[k - 1] / (f[k - 1] - f[k]))
        unit = f" {units[name]}" if units and name in units else ""
        raise ContactLostError(
            f"contact {j.name!r} is lost: its force {name} falls to zero and would turn "
            f"negative ({f[k]:.4g}{unit} at the next output); the bodies separate there "
            "(a stronger spring or preload, or a lower speed, keeps them together)",
            t,
            (j.name,),
        )


def reaction_columns(c: Constraints, R) -> dict:
    """The reaction columns ``{joint}.Fx``, ``{joint}.Fy`` (and ``{joint}.M`` where the joint
    carries a moment) from :func:`joint_reactions`' values ``R`` (..., n_joints, 3)."""
    out = {}
    for k, j in enumerate(c.joints):
        if not j.generic_reaction:
            continue
        out[f"{j.name}.Fx"], out[f"{j.name}.Fy"] = R[..., k, 0], R[..., k, 1]
        if j.carries_moment:
            out[f"{j.name}.M"] = R[..., k, 2]
    return out


def driver_efforts(c: Constraints, lam, powers, n_drivers: int) -> dict:
    """The first ``n_drivers`` drivers' efforts ``-lambda`` (force or torque) keyed by name,
    and their powers keyed ``{name}.power``, from ``lam`` and ``powers`` (..., m)."""
    out = {}
    pos = {row: i for i, row in enumerate(c.active)}
    nk = c.n_joint_rows
    zero = np.zeros(lam.shape[:-1])
    for k, d in enumerate(c.drivers[:n_drivers]):
        row = nk + k
        out[d.name] = -lam[..., pos[row]] if row in pos else zero
        out[f"{d.name}.power"] = powers[..., pos[row]] if row in pos else zero
    return out
