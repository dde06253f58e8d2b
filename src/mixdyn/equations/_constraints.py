"""Constraint equations and their derivatives, by automatic differentiation.

``Phi(q, t)`` stacks the joints' equations ``Phi^K(q)`` and the drivers' ``Phi^D(q, t)``.
From it, exactly (no finite differences):

* ``Phi_q = dPhi/dq`` (m, n) by ``jax.jacfwd``;
* ``Phi_t = dPhi/dt`` (m,), so velocities solve ``Phi_q qd = -Phi_t``;
* ``gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt`` (m,), the right-hand side of the
  acceleration equations ``Phi_q qdd = gamma``. It is minus the second derivative of
  ``s -> Phi(q + s qd, t + s)`` at ``s = 0``, computed by two nested ``jax.jvp``.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..model import Driver, Joint, Model


class Constraints(eqx.Module):
    """The constraint set of one analysis: joints, then drivers (prescribed motions).

    Attributes:
        joints: the joints (time independent).
        drivers: drivers and other prescribed motions (may depend on time).
        active: indices of the rows kept (redundant rows dropped), static.
        labels: a label per row of the full set (``"A.x"``, ``"crank_angle"``), static.
        nq: number of coordinates.
    """

    joints: tuple[Joint, ...]
    drivers: tuple[Driver, ...]
    active: tuple[int, ...] = eqx.field(static=True)
    labels: tuple[str, ...] = eqx.field(static=True)
    owners: tuple[int, ...] = eqx.field(static=True)
    nq: int = eqx.field(static=True)
    rank: int | None = eqx.field(static=True)

    def __init__(self, joints, drivers, nq: int, active=None, rank=None):
        self.joints = tuple(joints)
        self.drivers = tuple(drivers)
        labels, owners = [], []
        for k, j in enumerate(self.joints):
            labels += [f"{j.name}.{lab}" for lab in j.equation_labels]
            owners += [k] * j.n_equations
        for k, d in enumerate(self.drivers):
            labels.append(d.name)
            owners.append(len(self.joints) + k)
        self.labels = tuple(labels)
        self.owners = tuple(owners)
        self.nq = nq
        self.active = tuple(range(len(labels))) if active is None else tuple(int(i) for i in active)
        self.rank = None if rank is None or rank == len(self.active) else int(rank)

    @classmethod
    def of(cls, model: Model, drivers=None) -> Constraints:
        """The model's joints with ``drivers`` (default: the model's own drivers)."""
        return cls(model.joints, model.drivers if drivers is None else drivers, model.nq)

    def with_active(self, active) -> Constraints:
        """The same set keeping only rows ``active`` (indices into the full set)."""
        return Constraints(self.joints, self.drivers, self.nq, active)

    def with_rank(self, rank: int) -> Constraints:
        """The full set, declared of rank ``rank``: if it has redundant rows, every solve with
        it becomes a least-squares (truncated SVD) solve, robust wherever the redundancy moves
        from row to row (a parallelogram passing through its singular positions)."""
        return Constraints(self.joints, self.drivers, self.nq, None, rank)

    def solve(self, A, b, extra_rank: int = 0):
        """Solve with a matrix built from ``Phi_q`` whose rank is ``self.rank + extra_rank``
        (LU when no row is redundant); returns ``(x, ratio)``."""
        from ..linalg import solve_ranked

        return solve_ranked(A, b, None if self.rank is None else self.rank + extra_rank)

    # ------------------------------------------------------------------ sizes
    @property
    def n_full(self) -> int:
        """Rows of the full set, redundant ones included."""
        return len(self.labels)

    @property
    def m(self) -> int:
        """Rows kept."""
        return len(self.active)

    @property
    def n_joint_rows(self) -> int:
        return sum(j.n_equations for j in self.joints)

    @property
    def active_labels(self) -> tuple[str, ...]:
        return tuple(self.labels[i] for i in self.active)

    @property
    def element_names(self) -> tuple[str, ...]:
        return tuple(e.name for e in (*self.joints, *self.drivers))

    # ------------------------------------------------------------------ equations
    def full(self, q, t) -> jax.Array:
        """All rows ``Phi(q, t)`` (n_full,) before dropping redundant ones."""
        parts = [j.residual(q) for j in self.joints] + [d.residual(q, t) for d in self.drivers]
        if not parts:
            return jnp.zeros(0)
        return jnp.concatenate(parts)

    def __call__(self, q, t) -> jax.Array:
        """``Phi(q, t)`` (m,), the rows kept."""
        Phi = self.full(q, t)
        if len(self.active) == self.n_full:
            return Phi
        return Phi[np.asarray(self.active, dtype=int)]

    def phi_q(self, q, t) -> jax.Array:
        """Jacobian ``Phi_q`` (m, nq)."""
        return jax.jacfwd(self.__call__, argnums=0)(q, t)

    def phi_t(self, q, t) -> jax.Array:
        """Partial time derivative ``Phi_t`` (m,)."""
        return jax.jacfwd(self.__call__, argnums=1)(q, jnp.asarray(t, dtype=jnp.float64))

    def gamma(self, q, qd, t) -> jax.Array:
        """Acceleration right-hand side ``gamma`` (m,)."""
        t = jnp.asarray(t, dtype=jnp.float64)

        def path(s):
            return self(q + s * qd, t + s)

        def rate(s):
            return jax.jvp(path, (s,), (jnp.ones_like(s),))[1]

        _, acc = jax.jvp(rate, (jnp.zeros(()),), (jnp.ones(()),))
        return -acc

    # ------------------------------------------------------------------ structure
    def pattern(self) -> np.ndarray:
        """Boolean sparsity pattern of ``Phi_q`` (m, nq), from which bodies each row touches."""
        P = np.zeros((self.n_full, self.nq), dtype=bool)
        row = 0
        for e in (*self.joints, *self.drivers):
            n = e.n_equations if isinstance(e, Joint) else 1
            for b in e.body_indices():
                P[row : row + n, 3 * b : 3 * b + 3] = True
            row += n
        return P[np.asarray(self.active, dtype=int)]
