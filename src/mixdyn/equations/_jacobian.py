"""``Phi_q`` at one state as a linear operator, on the linear-solver path chosen once per
constraint set (:meth:`Constraints.jacobian`).

Every solve an analysis needs is built from ``Phi_q`` (m, n) and a diagonal metric ``W`` (n,):

* the Schur complement ``S = Phi_q W Phi_q^T`` (``W = M^-1``: the equations of motion and the
  mass-weighted projections; ``W = I``: least-norm kinematic steps);
* the least-``W^-1``-norm solution of ``Phi_q x = b``, ``x = W Phi_q^T S^-1 b``;
* the solution of ``Phi_q x = b`` itself (a square, regular ``Phi_q``; least squares with
  redundant rows).

Both operators keep one contract, in the manner of lineax's ``AbstractLinearSolver``
(``init`` factorizes once, ``compute`` solves, a result code): each method factorizes once and
returns a :class:`~mixdyn.linalg.Factor`, ``solve(b)`` for any number of right-hand sides and
the pivot ratio (near 0: the matrix lost rank; comparable between the two paths).

* :class:`DenseJacobian`: the dense matrix; LU, or a truncated SVD of known rank where rows are
  redundant.
* :class:`BandedJacobian`: values on the set's static sparsity pattern; ``S`` by the banded
  block Cholesky factorization (:mod:`mixdyn.linalg._sparse`), redundant rows by iterated
  regularization.

With ``guard=True`` a factorization whose pivot ratio falls below
:data:`~mixdyn.linalg._dense.SINGULAR_RATIO` (a singular position) is solved instead by the
damped SVD solve, on either path (:func:`~mixdyn.linalg._dense.guarded`): from the SVD of the
dense ``Phi_q W^(1/2)`` for the symmetric ``S``, of ``S`` itself for a mixed problem's; on the
sparse path above :data:`DENSE_GUARD_MAX_ENTRIES` by a damped solve on the banded factors.
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np

from ..linalg._choice import DenseSolver, LinearSolver
from ..linalg._dense import (
    SINGULAR_DAMPING,
    SINGULAR_RATIO,
    Factor,
    factor_ranked,
    gram_factor,
    guarded,
)

#: Redundant rows on the sparse path: relative shift of the Schur complement's diagonal, and
#: the steps of iterated regularization (see :meth:`BandedJacobian.schur`).
REGULARIZATION = 1e-8
REFINE_REDUNDANT = 4

#: The largest ``Phi_q`` (m x n entries) whose guard on the sparse path takes the damped SVD
#: solve of the dense matrix (32 MB of float64); a larger one's guard is the damped solve on
#: the banded factors (:meth:`BandedJacobian._banded_guard`). The dense branch is compiled
#: whether or not it is taken, and XLA's compile time grows with the matrix it forms: the
#: guard of a 4,000-link chain's start (m x n = 8000 x 12000) took 259 s to compile.
DENSE_GUARD_MAX_ENTRIES = 4_000_000


class JacobianOperator(eqx.Module):
    """``Phi_q`` (m, n) at one state. Subclasses: :class:`DenseJacobian`,
    :class:`BandedJacobian`; the shapes and the rank are static."""

    @property
    def shape(self) -> tuple[int, int]:
        raise NotImplementedError

    @property
    def rank(self) -> int | None:
        """The rank when rows are redundant (least-squares solves), else None."""
        raise NotImplementedError

    def mv(self, x) -> jax.Array:
        """``Phi_q x`` (m,) for ``x`` (n,)."""
        raise NotImplementedError

    def rmv(self, y) -> jax.Array:
        """``Phi_q^T y`` (n,) for ``y`` (m,)."""
        raise NotImplementedError

    def dense(self) -> jax.Array:
        """The matrix (m, n)."""
        raise NotImplementedError

    def values_on(self, rows, cols) -> jax.Array:
        """(nnz,) the entries at the constraint set's static pattern ``(rows, cols)``
        (``Constraints.coo()``)."""
        raise NotImplementedError

    def schur(self, W, shift=None, guard: bool = False) -> Factor:
        """Factor of ``S = Phi_q W Phi_q^T`` (plus ``shift I``: a Levenberg–Marquardt
        damping), ``W`` (n,) a positive diagonal (zeros keep coordinates out)."""
        raise NotImplementedError

    def schur_matrix(self, W) -> jax.Array:
        """``S = Phi_q W Phi_q^T`` formed densely (m, m)."""
        J = self.dense()
        return J @ (W[:, None] * J.T)

    def min_norm(self, W=None, shift=None, refine: int = 0, guard: bool = False) -> Factor:
        """Factor giving the least-``W^-1``-norm solution of ``Phi_q x = b``,
        ``x = W Phi_q^T (S + shift I)^-1 b``, with ``refine`` steps of iterative refinement on
        the residual ``b - Phi_q x`` (the Schur complement squares the condition number of
        ``Phi_q``; a step brings the error back to that of a direct solve). Its ratio is the
        square root of ``S``'s, comparable to the LU pivot ratio of ``Phi_q``."""
        W = jnp.ones(self.shape[1]) if W is None else W
        inner = self.schur(W, shift, guard)

        def once(b):
            return W * self.rmv(inner.solve(b))

        def solve(b):
            x = once(b)
            for _ in range(refine):
                x = x + once(b - self.mv(x))
            return x

        return Factor(solve, jnp.sqrt(inner.ratio))

    def solver(self, refine: int = 0) -> Factor:
        """Factor for ``Phi_q x = b`` on this path (see the subclasses)."""
        raise NotImplementedError

    def partition(self, D) -> Factor:
        """Factor for the dependent block of a coordinate partition: ``solve(b)`` is the
        ``x`` (n,), zero outside ``D`` (m,) (the dependent coordinates' indices), with
        ``Phi_qD x_D = b``; its ratio is comparable to ``Phi_qD``'s LU pivot ratio (how far
        the partition is from singular)."""
        W = jnp.zeros(self.shape[1]).at[D].set(1.0)
        return self.min_norm(W, refine=1)

    def kkt(self, W, B=None, collocated=()):
        """The constrained-dynamics matrix at one state, factorized once through its Schur
        complement ``S = C W G``:

            W^-1 x + G mu = r1,     C x = r2,     G = [Phi_q^T | -B]

        with ``C = Phi_q`` (this operator; its last ``p`` rows the prescribed motions of a
        mixed problem) and ``B`` (n, p) the directions of the unknown forces (None: ``p = 0``,
        ``G = C^T``). ``collocated``: for each unknown force, the prescribed motion along whose
        gradient it acts, or ``()`` (see :class:`~mixdyn.analysis._problem.Problem`).

        Returns:
            ``(solve, ratio)``: ``solve(r1 (n,), r2 (m,)) -> (x (n,), mu (m,))``, and the
            pivot ratio of ``S`` (below ``SINGULAR_RATIO`` the damped SVD solve of ``S``).
        """
        raise NotImplementedError


class DenseJacobian(JacobianOperator):
    """``Phi_q`` as a dense matrix.

    Attributes:
        J: (m, n) the matrix.
        rank_: the rank when rows are redundant, else None (static).
        batched: whether the guard at singular positions decides once per batch (a sweep's
            one program; :func:`~mixdyn.linalg._dense.guarded`), static.
        path: the set's resolved linear solver, whose :meth:`~mixdyn.linalg.LinearSolver.factor`
            factorizes the square matrices (LAPACK's LU, or straight-line code for a few
            rows: :class:`~mixdyn.linalg.UnrolledSolver`), static.
    """

    J: jax.Array
    rank_: int | None = eqx.field(static=True, default=None)
    batched: bool = eqx.field(static=True, default=False)
    path: LinearSolver = eqx.field(static=True, default=DenseSolver())

    @property
    def shape(self):
        return self.J.shape

    @property
    def rank(self):
        return self.rank_

    def mv(self, x):
        return self.J @ x

    def rmv(self, y):
        return self.J.T @ y

    def dense(self):
        return self.J

    def values_on(self, rows, cols):
        return self.J[rows, cols]

    def _factor(self, A, symmetric: bool = False) -> Factor:
        """The square ``A`` (m, m) factorized on the set's path (:attr:`path`), or its
        truncated SVD of the known rank with redundant rows (and for a ``Phi_q`` that is not
        square)."""
        if self.rank is None and A.shape[0] == A.shape[1]:
            return self.path.factor(A, symmetric)
        return factor_ranked(A, self.rank)

    def schur(self, W, shift=None, guard=False):
        """LU (Cholesky on the straight-line path) of ``S``; a truncated SVD of the known
        rank with redundant rows."""
        S = self.schur_matrix(W)
        if shift is not None:
            S = S + shift * jnp.eye(S.shape[0])
        f = self._factor(S, symmetric=True)
        if guard and self.rank is None and S.shape[0]:
            F = functools.partial(gram_factor, self.J, W, shift)
            return guarded(f, F, batched=self.batched, gram=True)
        return f

    def min_norm(self, W=None, shift=None, refine=0, guard=False):
        """As :meth:`JacobianOperator.min_norm`, with ``W Phi_q^T`` formed once (no
        refinement is needed: ``refine`` is ignored on the dense path)."""
        W = jnp.ones(self.shape[1]) if W is None else W
        WJt = W[:, None] * self.J.T
        S = self.J @ WJt
        if shift is not None:
            S = S + shift * jnp.eye(S.shape[0])
        f = self._factor(S, symmetric=True)
        if guard and self.rank is None and S.shape[0]:
            F = functools.partial(gram_factor, self.J, W, shift)
            f = guarded(f, F, batched=self.batched, gram=True)
        return Factor(lambda b: WJt @ f.solve(b), jnp.sqrt(f.ratio))

    def solver(self, refine=0):
        """LU of ``Phi_q`` (square), or its truncated SVD of the known rank (least squares,
        minimum norm) with redundant rows; ``refine`` is ignored (a direct solve)."""
        return self._factor(self.J)

    def partition(self, D):
        """As :meth:`JacobianOperator.partition`: the LU of ``Phi_qD`` (m, m); the ratio is
        ``s_min / s_max`` of its singular values (an LU pivot ratio depends on the rows'
        scaling and would trigger needless new partitions; under ``jit`` the SVD is dropped
        where the ratio is not used)."""
        JD = self.J[:, D]
        f = self.path.factor(JD)
        s = jnp.linalg.svd(JD, compute_uv=False)
        ratio = s[-1] / s[0] if s.shape[0] else jnp.ones(())
        n = self.shape[1]
        return Factor(lambda b: jnp.zeros(n, self.J.dtype).at[D].set(f.solve(b)), ratio)

    def kkt(self, W, B=None, collocated=()):
        """LU of the dense ``S = C W G`` (any ``B``; a truncated SVD of the known rank with
        redundant rows). In forward dynamics ``G = C^T`` and ``mu = lambda``; in mixed
        dynamics ``G`` also holds ``-B``.

        Differentiated implicitly (:func:`_kkt_implicit`): the derivative of a solve is one
        more solve with the same factor, not the derivative of the factorization (measured:
        the paper model's reverse-mode gradient 5.7x the run against 6.3x)."""
        C = self.J
        m = C.shape[0]
        G = C.T if B is None else jnp.concatenate([C[: m - B.shape[1]].T, -B], axis=1)
        sym = B is None
        f, WG = _kkt_factor(C, G, W, self.rank, self.batched, sym, self.path)

        def solve(r1, r2):
            x, mu = jax.lax.stop_gradient(_kkt_apply(f, WG, C, W, r1, r2))
            return _kkt_implicit(C, G, W, r1, r2, x, mu, self.rank, self.batched, sym, self.path)

        return solve, f.ratio


def _kkt_factor(C, G, W, rank, batched, sym, path):
    """The factor of ``S = C W G`` (guarded at singular positions) and ``W G``: C (m, n),
    G (n, m), W (n,). With ``sym`` (static) ``G = C^T`` and the damped solve takes the SVD of
    ``C W^(1/2)``, else (a mixed problem's unknown forces) that of ``S``. ``path``: the set's
    linear solver (:meth:`~mixdyn.linalg.LinearSolver.factor`)."""
    WG = W[:, None] * G
    S = C @ WG
    f = path.factor(S, sym) if rank is None else factor_ranked(S, rank)
    if rank is None and C.shape[0]:
        if sym:
            f = guarded(f, lambda: gram_factor(C, W), batched=batched, gram=True)
        else:
            f = guarded(f, lambda: S, batched=batched)
    return f, WG


def _kkt_apply(f, WG, C, W, r1, r2):
    """``(x (n,), mu (m,))`` of :meth:`DenseJacobian.kkt` with the factor ``f``."""
    mu = f.solve(C @ (W * r1) - r2)
    return W * r1 - WG @ mu, mu


@functools.partial(jax.custom_jvp, nondiff_argnums=(7, 8, 9, 10))
def _kkt_implicit(C, G, W, r1, r2, x, mu, rank, batched, sym, path):
    """``(x, mu)``, the solution of ``W^-1 x + G mu = r1``, ``C x = r2`` (solved with the
    factor made once, its own derivative stopped), differentiated implicitly: the tangent
    is one more solve, not the derivative of the factorization."""
    return x, mu


@_kkt_implicit.defjvp
def _kkt_implicit_jvp(rank, batched, sym, path, primals, tangents):
    C, G, W, _, _, x, mu = primals
    dC, dG, dW, dr1, dr2, _, _ = tangents
    f, WG = _kkt_factor(C, G, W, rank, batched, sym, path)
    # d(W^-1 x + G mu - r1) = 0, d(C x - r2) = 0
    a = dr1 + dW / (W * W) * x - dG @ mu
    b = dr2 - dC @ x
    return (x, mu), _kkt_apply(f, WG, C, W, a, b)


class BandedJacobian(JacobianOperator):
    """``Phi_q`` as values on the constraint set's static sparsity pattern.

    Attributes:
        c: the constraint set (its static pattern and rank; its numbers are not read).
        values: (nnz,) the Jacobian's values on ``c.coo()``.
    """

    c: object
    values: jax.Array

    @property
    def shape(self):
        return (self.c.m, self.c.nq)

    @property
    def rank(self):
        return self.c.rank

    def mv(self, x):
        rows, cols = self.c.coo()
        return jax.ops.segment_sum(self.values * x[cols], jnp.asarray(rows), num_segments=self.c.m)

    def rmv(self, y):
        rows, cols = self.c.coo()
        return jax.ops.segment_sum(self.values * y[rows], jnp.asarray(cols), num_segments=self.c.nq)

    def dense(self):
        rows, cols = self.c.coo()
        return jnp.zeros(self.shape, self.values.dtype).at[rows, cols].add(self.values)

    def values_on(self, rows, cols):
        return self.values  # the same pattern: the set's own

    def schur_solve(self, W, b):
        """One solve ``S x = b`` (fused factorization and forward sweep); ``(x, ratio)``.
        With redundant rows, :meth:`schur`'s regularized solve."""
        if self.rank is None:
            return self.c.schur_structure().solve(self.values, W, b)
        f = self.schur(W)
        return f.solve(b), f.ratio

    def schur(self, W, shift=None, guard=False):
        """The banded block Cholesky factors of ``S`` (+ ``shift I``).

        With redundant rows of consistent equations (``rank < m``), ``S`` is singular and its
        minimum-norm solution is sought by iterated Tikhonov regularization: ``S + eps I`` is
        factorized, with ``eps = REGULARIZATION * max diag S``, and each of
        :data:`REFINE_REDUNDANT` steps adds ``(S + eps I)^-1`` of the residual of the
        unregularized system. A component along an eigenvalue ``s`` of ``S`` converges by the
        factor ``eps / (s + eps)`` per step, one in the null space of ``S`` (the redundancy)
        is never excited beyond rounding (``~ 1e-16 / REGULARIZATION`` relative): the motion
        (which depends on ``Phi_q^T y`` only) matches the dense truncated-SVD solve to
        rounding, the split of the multipliers among redundant rows its minimum-norm split to
        ``~1e-8`` relative. The pivot ratio leaves out the ``m - rank`` smallest pivots.
        """
        c, v = self.c, self.values
        st = c.schur_structure()
        if self.rank is None:
            fac, ratio = st.factor(v, W, shift)
            f = Factor(lambda b: st.solve_factored(fac, b), ratio)
        else:
            rows, cols = c.coo()
            diag = jax.ops.segment_sum(v**2 * W[cols], jnp.asarray(rows), num_segments=c.m)
            eps = REGULARIZATION * jnp.max(diag, initial=0.0)
            extra = 0.0 if shift is None else shift
            fac, ratio = st.factor(v, W, eps + extra, rank=self.rank)

            def solve(b):
                y = st.solve_factored(fac, b)
                for _ in range(REFINE_REDUNDANT):
                    r = b - self.mv(W * self.rmv(y)) - extra * y
                    y = y + st.solve_factored(fac, r)
                return y

            f = Factor(solve, ratio)
        if guard and c.m and c.m * c.nq > DENSE_GUARD_MAX_ENTRIES:
            return self._banded_guard(f, W, shift)
        if guard and c.m:

            def F():  # formed only where the guard takes the damped solve
                return gram_factor(self.dense(), W, shift)

            return guarded(f, F, self.rank, c.batched, gram=True)
        return f

    def _banded_guard(self, f: Factor, W, shift=None) -> Factor:
        """``f`` with, below :data:`~mixdyn.linalg._dense.SINGULAR_RATIO`, a damped solve on
        the banded factors instead of the dense SVD (``Phi_q`` over
        :data:`DENSE_GUARD_MAX_ENTRIES`): ``y = (S + mu I)^-1 S (S + mu I)^-1 b`` with
        ``mu = SINGULAR_DAMPING * max diag S``, which inverts an eigenvalue ``s`` of ``S`` as
        ``s / (s + mu)^2``: ``1/s`` for ``s >> mu``, smoothly to zero below, as the SVD
        solve's ``s / (s^2 + mu^2)`` does (both at most ``1 / (2 mu)``)."""
        c, v = self.c, self.values
        st = c.schur_structure()
        rows, cols = c.coo()
        extra = 0.0 if shift is None else shift
        diag = jax.ops.segment_sum(v**2 * W[cols], jnp.asarray(rows), num_segments=c.m)
        mu = SINGULAR_DAMPING * (jnp.max(diag, initial=0.0) + extra)
        fac, _ = st.factor(v, W, mu + extra, rank=self.rank)

        def damped(b):
            if b.ndim == 2:
                return jax.vmap(damped, in_axes=1, out_axes=1)(b)
            y = st.solve_factored(fac, b)
            return st.solve_factored(fac, self.mv(W * self.rmv(y)) + extra * y)

        def solve(b):
            return jax.lax.cond(~(f.ratio >= SINGULAR_RATIO), damped, f.solve, b)

        return Factor(solve, f.ratio)

    def solver(self, refine=0):
        """The minimum-norm solution through the Schur complement (:meth:`min_norm` with
        ``W = I``; for a square, regular ``Phi_q``: the solution)."""
        return self.min_norm(refine=refine)

    def _row_gradients(self, rows):
        """``Phi_q[rows]^T`` (n, len(rows))."""
        E = jnp.zeros((self.c.m, len(rows))).at[rows, np.arange(len(rows))].set(1.0)
        return jax.vmap(self.rmv, in_axes=1, out_axes=1)(E)

    def kkt(self, W, B=None, collocated=()):
        """The banded block Cholesky factors of the symmetric ``C W C^T``: directly for
        ``p = 0`` and for collocated unknown forces (``B[:, a] = s_a Psi_q[b]^T``, so that
        ``G = C^T diag(1, -1/s)``), by a rank-``p`` Woodbury update for unknown forces of any
        direction (:meth:`_woodbury`). Below ``SINGULAR_RATIO`` the damped SVD solve of
        ``C W C^T``, from the SVD of the dense ``C W^(1/2)``."""
        m = self.c.m
        if B is not None and not collocated:
            return self._woodbury(W, B)
        f = self.schur(W, guard=True)
        p = 0 if B is None else B.shape[1]
        if p:
            # Collocated unknown forces: -B[:, a] u_a = Psi_q[b]^T y_b with B[:, a] = s_a
            # Psi_q[b]^T, so u_a = -y_b / s_a.
            rows = m - p + np.asarray(collocated, dtype=int)
            PsiT = self._row_gradients(rows)
            scale = jnp.sum(B * PsiT, axis=0) / jnp.sum(PsiT**2, axis=0)

        def solve(r1, r2):
            y = f.solve(self.mv(W * r1) - r2)
            x = W * (r1 - self.rmv(y))
            if p:
                y = jnp.concatenate([y[: m - p], -y[rows] / scale])
            return x, y

        return solve, f.ratio

    def _woodbury(self, W, B):
        """Unknown forces of any direction: ``S = C W G`` differs from the symmetric
        ``S_sym = C W C^T`` in its last ``p`` columns only (``G = [Phi_q^T | -B]``,
        ``C^T = [Phi_q^T | Psi_q^T]``): ``S = S_sym + U E^T`` with ``U = -C W (B + Psi_q^T)``
        (m, p) and ``E`` the last ``p`` columns of the identity. By the Sherman–Morrison–
        Woodbury formula ``S^-1 b = y - Z K^-1 E^T y``, ``y = S_sym^-1 b``, ``Z = S_sym^-1 U``,
        ``K = I + E^T Z`` (p, p): one banded Cholesky factorization, ``p`` solves once and one
        per right-hand side, and a ``p x p`` LU. ``K`` is singular exactly where ``S`` is (the
        mixed problem is not solvable there); the pivot ratio is the smaller of the two
        factorizations'. Below ``SINGULAR_RATIO`` the solve is the damped SVD of the dense
        ``S``, as on the dense path."""
        m, p = self.c.m, B.shape[1]
        mk = m - p
        cols = functools.partial(jax.vmap, in_axes=1, out_axes=1)
        PsiT = self._row_gradients(mk + np.arange(p))  # (n, p)
        U = cols(lambda f: self.mv(W * f))(-(B + PsiT))  # (m, p)
        sym = self.schur(W)
        Z = cols(sym.solve)(U)
        K = jnp.eye(p) + Z[mk:]
        lu, piv = jsl.lu_factor(K)
        d = jnp.abs(jnp.diag(lu))
        ratio = jnp.minimum(sym.ratio, jnp.min(d) / jnp.maximum(jnp.max(d), 1e-300))
        ratio = jnp.where(jnp.isfinite(ratio), ratio, 0.0)

        def woodbury(b):
            y = sym.solve(b)
            return y - Z @ jsl.lu_solve((lu, piv), y[mk:])

        def dense_S():
            C = self.dense()
            G = jnp.concatenate([C[:mk].T, -B], axis=1)
            return C @ (W[:, None] * G)

        f = guarded(Factor(woodbury, ratio), dense_S, self.rank, self.c.batched)

        def g_times(mu):
            lam = jnp.concatenate([mu[:mk], jnp.zeros(p, mu.dtype)])
            return self.rmv(lam) - B @ mu[mk:]

        def solve(r1, r2):
            mu = f.solve(self.mv(W * r1) - r2)
            return W * (r1 - g_times(mu)), mu

        return solve, ratio


__all__ = ["BandedJacobian", "DenseJacobian", "JacobianOperator"]
