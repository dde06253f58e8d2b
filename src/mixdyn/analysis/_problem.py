"""The constrained equations of motion of one analysis, as pure functions of ``(q, qd, t)``.

Forward, inverse and mixed dynamics differ only in which constraint rows exist and which
multipliers are forces of unknown magnitude:

    M qdd + G mu = Q(q, qd, t)          G = [Phi_q^T | -B]
    C qdd       = gamma                 C = [Phi_q ; Psi_q]

with ``Phi`` the joints and drivers (their multipliers ``lambda``), ``Psi`` the prescribed
motions of a mixed problem and ``B`` the directions of the unknown forces ``u`` (the last
``p`` entries of ``mu``). In forward dynamics ``p = 0`` and ``G = C^T``. Two solvers of the
acceleration problem exist: ``"augmented"`` (Schur complement, any ``B``) and
``"partition"`` (the paper's equations (28)–(29), unknown forces along coordinates).
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np

from ..equations import Constraints, applied_forces, force_directions, potential_energy
from ..linalg import lu_solve_checked, min_pivot, solve_kkt, solve_ranked
from ..linalg._dense import SINGULAR_DAMPING, SINGULAR_RATIO
from ..model import Model


def pivot_columns(A, k: int):
    """Indices (k,) of ``k`` well-conditioned columns of ``A`` (m, n), by partial-pivoting LU
    of ``A^T``; and the other columns (n - k,). Jittable."""
    n = A.shape[1]
    if k == 0:
        return jnp.zeros(0, dtype=int), jnp.arange(n)
    P, _, _ = jsl.lu(A.T)
    perm = jnp.argmax(P, axis=0)  # row of A^T (column of A) chosen at each pivot position
    dep = perm[:k]
    mask = jnp.ones(n, dtype=bool).at[dep].set(False)
    rest = jnp.argsort(~mask, stable=True)[: n - k]
    return dep, rest


class Problem(eqx.Module):
    """Equations of motion of one dynamic analysis.

    Attributes:
        model: the mechanism.
        c: constraint rows ``[Phi; Psi]`` (joints, drivers, then prescribed motions).
        unknown: names of the force elements of unknown magnitude (``p`` of them).
        solver: ``"augmented"`` or ``"partition"``.
        j_index: (p,) coordinates along which the unknown forces act (partition solver).
        i_index: user-chosen independent coordinates, or ``()`` for automatic choice.
        collocated: for each unknown force, the prescribed motion (0..p-1) along whose
            gradient it acts (``B[:, a] = s_a Psi_q[b]^T``), or ``()``: with it the augmented
            system is symmetric, ``G = C^T diag(1, -1/s)``, and can take the sparse path.
    """

    model: Model
    c: Constraints
    unknown: tuple[str, ...] = eqx.field(static=True)
    solver: str = eqx.field(static=True)
    j_index: tuple[int, ...] = eqx.field(static=True)
    i_index: tuple[int, ...] = eqx.field(static=True)
    collocated: tuple[int, ...] = eqx.field(static=True)

    def __init__(
        self, model, c, unknown=(), solver="augmented", j_index=(), i_index=(), collocated=()
    ):
        self.model = model
        self.c = c
        self.unknown = tuple(unknown)
        self.solver = solver
        self.j_index = tuple(int(i) for i in j_index)
        self.i_index = tuple(int(i) for i in i_index)
        self.collocated = tuple(int(i) for i in collocated)

    @property
    def p(self) -> int:
        return len(self.unknown)

    @property
    def Minv(self):
        return 1.0 / self.model.mass_diagonal

    @property
    def sparse(self) -> bool:
        """Whether the sparse linear-solver path is taken: the constraints ask for it and the
        augmented solver is used (the partition solver stays dense). Mixed problems whose
        unknown forces are not collocated are solved there by a rank-``p`` update of the
        symmetric system (:meth:`_woodbury_accelerations`)."""
        return self.c.linear_solver == "sparse" and self.solver == "augmented"

    # ------------------------------------------------------------------ forces
    def known_forces(self, q, qd, t):
        """Known generalized forces ``Q`` (nq,)."""
        return applied_forces(self.model, q, qd, t, exclude=self.unknown)

    def G(self, q, qd, t, C):
        """Force directions of the multipliers, (nq, m): ``[Phi_q^T | -B]``."""
        if self.p == 0:
            return C.T
        B = force_directions(self.model, self.unknown, q, qd, t)
        return jnp.concatenate([C[: C.shape[0] - self.p].T, -B], axis=1)

    # ------------------------------------------------------------------ accelerations
    def accelerations(self, q, qd, t, alpha=None, beta=None):
        """``(qdd (nq,), mu (m,), pivot_ratio)`` at one state.

        With ``alpha``, ``beta`` [1/time] the acceleration constraints are Baumgarte-stabilized:
        ``C qdd = gamma - 2 alpha (Phi_q qd + Phi_t) - beta**2 Phi``.
        """
        if self.sparse:
            return self._sparse_accelerations(q, qd, t, alpha, beta)
        C = self.c.phi_q(q, t)
        gam = self.c.gamma(q, qd, t)
        if alpha is not None:
            gam = gam - 2 * alpha * (C @ qd + self.c.phi_t(q, t)) - beta**2 * self.c(q, t)
        Q = self.known_forces(q, qd, t)
        if self.solver == "partition":
            return self._partition(q, qd, t, C, gam, Q)
        return solve_kkt(self.Minv, C, self.G(q, qd, t, C), Q, gam, self.c.rank)

    def _sparse_accelerations(self, q, qd, t, alpha, beta):
        """The Schur complement solve on the sparse path (see :mod:`mixdyn.linalg`)."""
        c, Minv = self.c, self.Minv
        v = c.jacobian_values(q, t)
        gam = c.gamma(q, qd, t)
        if alpha is not None:
            gam = gam - 2 * alpha * (c.matvec(v, qd) + c.phi_t(q, t)) - beta**2 * c(q, t)
        Q = self.known_forces(q, qd, t)
        rhs = c.matvec(v, Minv * Q) - gam
        if self.p and not self.collocated:
            return self._woodbury_accelerations(q, qd, t, v, Q, rhs)
        # the symmetric system M qdd + C^T y = Q, C qdd = gam
        mu, ratio = c.schur_solve(v, Minv, rhs)
        mu = jax.lax.cond(
            ~(ratio >= SINGULAR_RATIO),  # NaN: singular too
            lambda: self._dense_schur_solve(q, qd, t, rhs),
            lambda: mu,
        )
        qdd = Minv * (Q - c.rmatvec(v, mu))
        if self.p:
            # Collocated unknown forces: -B[:, a] u_a = Psi_q[b]^T y_b with B[:, a] = s_a
            # Psi_q[b]^T, so u_a = -y_b / s_a.
            mk = c.m - self.p
            rows = mk + np.asarray(self.collocated, dtype=int)
            B = force_directions(self.model, self.unknown, q, qd, t)
            PsiT = self._row_gradients(v, rows)
            scale = jnp.sum(B * PsiT, axis=0) / jnp.sum(PsiT**2, axis=0)
            mu = jnp.concatenate([mu[:mk], -mu[rows] / scale])
        return qdd, mu, ratio

    def _row_gradients(self, v, rows):
        """``Phi_q[rows]^T`` (nq, len(rows)) from the sparse values ``v``."""
        E = jnp.zeros((self.c.m, len(rows))).at[rows, np.arange(len(rows))].set(1.0)
        return jax.vmap(lambda e: self.c.rmatvec(v, e), in_axes=1, out_axes=1)(E)

    def _dense_schur_solve(self, q, qd, t, b, symmetric=True):
        """The sparse path's fallback at a singular position (the factorization loses rank
        for an instant), as on the dense path: a damped SVD solve of the Schur complement
        formed densely, ``C M^-1 C^T`` (or ``C M^-1 G`` with ``symmetric=False``)."""
        c = self.c
        C = c.phi_q(q, t)
        G = C.T if symmetric else self.G(q, qd, t, C)
        return solve_ranked(C @ (self.Minv[:, None] * G), b, c.rank, damping=SINGULAR_DAMPING)[0]

    def schur_solver(self, q, qd, t, v):
        """Sparse path: ``(solve, ratio, g_times)`` with ``solve(b)`` solving ``S mu = b`` for
        the Schur complement ``S = C M^-1 G`` (m, m), factorized once, and ``g_times(mu)`` the
        generalized force ``G mu`` (nq,), from the Jacobian values ``v`` at ``(q, t)``:
        ``G = C^T`` through the banded Cholesky factors (:meth:`Constraints.schur_solver`),
        mixed problems through :meth:`woodbury_solver`; below :data:`SINGULAR_RATIO` a dense
        damped SVD solve."""
        if self.p:
            return self.woodbury_solver(q, qd, t, v)
        c = self.c
        solve_sym, ratio = c.schur_solver(v, self.Minv)

        def solve(b):
            return jax.lax.cond(
                ~(ratio >= SINGULAR_RATIO),  # NaN: singular too
                lambda b: self._dense_schur_solve(q, qd, t, b),
                solve_sym,
                b,
            )

        return solve, ratio, lambda mu: c.rmatvec(v, mu)

    def _woodbury_accelerations(self, q, qd, t, v, Q, rhs):
        """Mixed dynamics on the sparse path with unknown forces of any direction
        (:meth:`woodbury_solver`)."""
        solve, ratio, g_times = self.woodbury_solver(q, qd, t, v)
        mu = solve(rhs)
        return self.Minv * (Q - g_times(mu)), mu, ratio

    def woodbury_solver(self, q, qd, t, v):
        """Sparse path, mixed problem: ``(solve, ratio, g_times)`` with ``solve(b)`` solving
        ``S mu = b`` for the Schur complement ``S = C M^-1 G`` (m, m) and ``g_times(mu)`` the
        generalized force ``G mu`` (nq,), from the Jacobian values ``v`` at ``(q, t)``.

        ``S`` differs from the symmetric ``S_sym = C M^-1 C^T`` in its last ``p`` columns only
        (``G = [Phi_q^T | -B]``, ``C^T = [Phi_q^T | Psi_q^T]``): ``S = S_sym + U E^T`` with
        ``U = -C M^-1 (B + Psi_q^T)`` (m, p) and ``E`` the last ``p`` columns of the identity.
        By the Sherman–Morrison–Woodbury formula ``S^-1 b = y - Z K^-1 E^T y``,
        ``y = S_sym^-1 b``, ``Z = S_sym^-1 U``, ``K = I + E^T Z`` (p, p): one banded Cholesky
        factorization, ``p`` solves once and one per right-hand side, and a ``p x p`` LU.
        ``K`` is singular exactly where ``S`` is (the mixed problem is not solvable there);
        the pivot ratio is the smaller of the two factorizations'. Below
        :data:`SINGULAR_RATIO` the solve is a dense damped SVD, as on the dense path.
        """
        c, Minv, p = self.c, self.Minv, self.p
        mk = c.m - p
        B = force_directions(self.model, self.unknown, q, qd, t)  # (nq, p)
        cols = functools.partial(jax.vmap, in_axes=1, out_axes=1)
        PsiT = self._row_gradients(v, mk + np.arange(p))  # (nq, p)
        U = cols(lambda f: c.matvec(v, Minv * f))(-(B + PsiT))  # (m, p)
        solve_sym, ratio = c.schur_solver(v, Minv)
        Z = cols(solve_sym)(U)
        K = jnp.eye(p) + Z[mk:]
        lu, piv = jsl.lu_factor(K)
        d = jnp.abs(jnp.diag(lu))
        ratio = jnp.minimum(ratio, jnp.min(d) / jnp.maximum(jnp.max(d), 1e-300))
        ratio = jnp.where(jnp.isfinite(ratio), ratio, 0.0)

        def woodbury(b):
            y = solve_sym(b)
            return y - Z @ jsl.lu_solve((lu, piv), y[mk:])

        def solve(b):  # dense below SINGULAR_RATIO: a singular position or unsolvable instant
            return jax.lax.cond(
                ~(ratio >= SINGULAR_RATIO),  # NaN: singular too
                lambda b: self._dense_schur_solve(q, qd, t, b, symmetric=False),
                woodbury,
                b,
            )

        def g_times(mu):
            lam = jnp.concatenate([mu[:mk], jnp.zeros(p, mu.dtype)])
            return c.rmatvec(v, lam) - B @ mu[mk:]

        return solve, ratio, g_times

    def _partition(self, q, qd, t, C, gam, Q):
        """The paper's method, eqs. (28)–(29), with ``j`` the prescribed coordinates."""
        n, p = self.model.nq, self.p
        mk = C.shape[0] - p  # constraint rows other than the prescribed motions
        Phi_q = C[:mk]
        j = jnp.asarray(self.j_index, dtype=int)
        Mdiag = self.model.mass_diagonal
        free = np.setdiff1d(np.arange(n), np.asarray(self.j_index, dtype=int))
        k_auto, rest = pivot_columns(Phi_q[:, free], mk)
        k_auto = jnp.asarray(free)[k_auto]
        i_auto = jnp.asarray(free)[rest]
        if self.i_index:
            i_user = jnp.asarray(self.i_index, dtype=int)
            mask = np.ones(n, dtype=bool)
            mask[list(self.i_index) + list(self.j_index)] = False
            k_user = jnp.asarray(np.where(mask)[0])
            # Fall back to the pivoted choice where the user's Phi_qk is ill-conditioned
            # (its smallest pivot far below the best choice's).
            use_user = min_pivot(Phi_q[:, k_user]) > 1e-3 * min_pivot(Phi_q[:, k_auto])
            k = jnp.where(use_user, k_user, k_auto)
            i = jnp.where(use_user, i_user, i_auto)
        else:
            k, i = k_auto, i_auto
        Pk, Pi = Phi_q[:, k], Phi_q[:, i]
        Mrows = jnp.diag(Mdiag)
        # X = (Phi_qk^T)^-1 [M_k. | Q_k]
        X, ratio = lu_solve_checked(Pk.T, jnp.concatenate([Mrows[k], Q[k][:, None]], axis=1))
        A_i = Mrows[i] - Pi.T @ X[:, :n]  # (29), left side
        b_i = Q[i] - Pi.T @ X[:, n]  # (29), right side (the source's sign repaired)
        A = jnp.concatenate([A_i, Phi_q, C[mk:]], axis=0)
        b = jnp.concatenate([b_i, gam[:mk], gam[mk:]])
        qdd, r2 = lu_solve_checked(A, b)
        lam = jnp.linalg.solve(Pk.T, Q[k] - Mdiag[k] * qdd[k])  # (28)
        B = force_directions(self.model, self.unknown, q, qd, t)
        # j rows: M_j qdd_j + Phi_qj^T lam = Q_j + B_j u
        Bj = B[j, :]
        u = jnp.linalg.solve(Bj, Mdiag[j] * qdd[j] + Phi_q[:, j].T @ lam - Q[j])
        return qdd, jnp.concatenate([lam, u]), jnp.minimum(ratio, r2)

    # ------------------------------------------------------------------ work
    def powers(self, q, qd, t, mu):
        """Power of each multiplier's force (m,): ``-(G[:, r] mu_r) . qd``, with
        ``G^T qd = [Phi_q qd; -B^T qd]`` (``Phi_q qd`` from the sparse values on the sparse
        path)."""
        c = self.c
        if c.linear_solver == "sparse":
            Cqd = c.matvec(c.jacobian_values(q, t), qd)
        else:
            Cqd = c.phi_q(q, t) @ qd
        Gqd = Cqd[: c.m - self.p]
        if self.p:
            B = force_directions(self.model, self.unknown, q, qd, t)
            Gqd = jnp.concatenate([Gqd, -(B.T @ qd)])
        return -Gqd * mu

    def work_rates(self, q, qd, t, qdd):
        """``[P_nonconservative_applied, P_constraints_and_unknowns]`` (2,) [power].

        By the equations of motion the constraint forces (joints, drivers, unknown forces) on
        the bodies are ``-G mu = M qdd - Q``, so their power needs no Jacobian:
        ``(M qdd - Q) . qd``.
        """
        Q = self.known_forces(q, qd, t)
        dV = jax.grad(lambda qq: potential_energy(self.model, qq))(q)
        p_nc = jnp.dot(Q + dV, qd)
        p_c = jnp.dot(self.model.mass_diagonal * qdd - Q, qd)
        return jnp.stack([p_nc, p_c])

    # ------------------------------------------------------------------ projections
    def project_positions(self, q, t, tol, iters: int = 4):
        """Mass-weighted least-norm projection of ``q`` onto ``Phi(q, t) = 0``: at most
        ``iters`` Newton steps, none once ``max |Phi| <= tol`` [length] (usually one after an
        integration step, so the loop stops early rather than solving ``iters`` times).

        Returns:
            ``(q (nq,), residual)``: the projected positions and ``max |Phi|`` there.
        """

        c, Minv = self.c, self.Minv

        def residual(q):
            r = c(q, t)
            return r, jnp.max(jnp.abs(r), initial=0.0) > tol

        def cond(state):
            k, _, _, far = state
            return (k < iters) & far

        def body(state):
            k, q, r, _ = state
            if c.linear_solver == "sparse":
                v = c.jacobian_values(q, t)
                y, _ = c.schur_solve(v, Minv, r)
                q = q - Minv * c.rmatvec(v, y)
            else:
                J = c.phi_q(q, t)
                MJ = Minv[:, None] * J.T
                q = q - MJ @ self._projection_solve(J @ MJ, r)
            return (k + 1, q, *residual(q))

        _, q, r, _ = jax.lax.while_loop(cond, body, (0, q, *residual(q)))
        return q, jnp.max(jnp.abs(r), initial=0.0)

    def project_velocities(self, q, qd, t):
        """Mass-weighted least-norm projection of ``qd`` onto ``Phi_q qd + Phi_t = 0``."""
        if self.c.linear_solver == "sparse":
            c, Minv = self.c, self.Minv
            v = c.jacobian_values(q, t)
            y, _ = c.schur_solve(v, Minv, c.matvec(v, qd) + c.phi_t(q, t))
            return qd - Minv * c.rmatvec(v, y)
        J = self.c.phi_q(q, t)
        r = J @ qd + self.c.phi_t(q, t)
        MJ = self.Minv[:, None] * J.T
        return qd - MJ @ self._projection_solve(J @ MJ, r)

    def _projection_solve(self, S, r):
        """``S^-1 r`` for a projection's ``S = Phi_q M^-1 Phi_q^T`` (dense path): near a
        singular position the damped SVD solve, as for the accelerations, so that the
        residual's part along the direction losing rank (rounding, drift) is not amplified
        like ``1/s`` into a jump of the positions or velocities."""
        y, ratio = self.c.solve(S, r)
        if self.c.rank is not None or S.shape[0] == 0:
            return y
        return jax.lax.cond(
            ~(ratio >= SINGULAR_RATIO),  # NaN: singular too
            lambda: solve_ranked(S, r, None, damping=SINGULAR_DAMPING)[0],
            lambda: y,
        )
