"""Joint reactions and driver efforts in physical terms, from the multipliers.

The constraint force on the bodies is ``-Phi_q^T lambda``. For a joint between bodies i and j,
its rows give on body j a force ``F`` [force] at the body origin and a moment about it; the
reported moment ``M`` is taken about the joint's point on body j. The force on body i is ``-F``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..model._geometry import GROUND, cross, vector


def reaction_kinds(c: Constraints) -> dict[str, str]:
    """The reaction columns of :func:`reaction_columns` and their kinds of quantity."""
    kinds = {}
    for j in c.joints:
        kinds[f"{j.name}.Fx"] = kinds[f"{j.name}.Fy"] = "force"
        if j.carries_moment:
            kinds[f"{j.name}.M"] = "torque"
    return kinds


def reaction_columns(c: Constraints, Phi_q, lam, q) -> dict:
    """Reaction columns for every joint, from one time's ``Phi_q`` (m, nq), ``lam`` (m,) and
    ``q`` (nq,). Vectorize over time with ``jax.vmap``.

    Returns values keyed ``{joint}.Fx``, ``{joint}.Fy`` (and ``{joint}.M``): the force and the
    moment (about the joint point) that body i exerts on body j (on the ground if j is it).
    """
    Qc = -(Phi_q * lam[:, None])  # (m, nq): generalized constraint force of each row
    owners = np.asarray([c.owners[i] for i in c.active])
    out = {}
    for k, j in enumerate(c.joints):
        rows = np.where(owners == k)[0]
        b, s = j.reaction_point()
        if b == GROUND:  # report on body i instead, with the sign flipped
            b, s, sign = j.bi, j.si, -1.0
        else:
            sign = 1.0
        if rows.size:
            w = sign * jnp.sum(Qc[rows, 3 * b : 3 * b + 3], axis=0)
        else:
            w = jnp.zeros(3)
        F = w[:2]
        M = w[2] - cross(vector(q, b, s), F)
        out[f"{j.name}.Fx"], out[f"{j.name}.Fy"] = F[0], F[1]
        if j.carries_moment:
            out[f"{j.name}.M"] = M
    return out


def driver_efforts(c: Constraints, lam, powers, n_drivers: int) -> dict:
    """The first ``n_drivers`` drivers' efforts ``-lambda`` (force or torque) keyed by name,
    and their powers keyed ``{name}.power``."""
    out = {}
    pos = {row: i for i, row in enumerate(c.active)}
    nk = c.n_joint_rows
    for k, d in enumerate(c.drivers[:n_drivers]):
        row = nk + k
        out[d.name] = -lam[pos[row]] if row in pos else jnp.zeros(())
        out[f"{d.name}.power"] = powers[pos[row]] if row in pos else jnp.zeros(())
    return out
