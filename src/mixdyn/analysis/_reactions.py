"""Joint reactions and driver efforts in physical terms, from the multipliers.

The constraint force on the bodies is ``-Phi_q^T lambda``. For a joint between bodies i and j,
its rows give on body j a force ``F`` [force] at the body origin and a moment about it; the
reported moment ``M`` is taken about the joint's point on body j. The force on body i is ``-F``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..model._forces import point_wrench  # noqa: F401  (documentation of the convention)
from ..model._geometry import GROUND, cross, vector


def reaction_columns(c: Constraints, Phi_q, lam, q) -> tuple[dict, dict]:
    """Reaction columns for every joint, from one time's ``Phi_q`` (m, nq), ``lam`` (m,) and
    ``q`` (nq,). Vectorize over time with ``jax.vmap``.

    Returns ``(values, kinds)`` keyed ``{joint}.Fx``, ``{joint}.Fy`` (and ``{joint}.M``).
    """
    Qc = -(Phi_q * lam[:, None])  # (m, nq): generalized constraint force of each row
    owners = np.asarray([c.owners[i] for i in c.active])
    out, kinds = {}, {}
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
        kinds[f"{j.name}.Fx"] = kinds[f"{j.name}.Fy"] = "force"
        if j.carries_moment:
            out[f"{j.name}.M"] = M
            kinds[f"{j.name}.M"] = "torque"
    return out, kinds


def driver_efforts(c: Constraints, lam) -> tuple[dict, dict]:
    """Each driver's effort ``-lambda`` (force or torque), keyed by the driver's name."""
    out, kinds = {}, {}
    pos = {row: i for i, row in enumerate(c.active)}
    nk = c.n_joint_rows
    for k, d in enumerate(c.drivers):
        row = nk + k
        out[d.name] = -lam[pos[row]] if row in pos else jnp.zeros(())
        kinds[d.name] = d.effort_kind
    return out, kinds
