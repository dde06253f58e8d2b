"""Constraint equations and their derivatives, by automatic differentiation.

``Phi(q, t)`` stacks the joints' equations ``Phi^K(q)`` and the drivers' ``Phi^D(q, t)``.
From it, exactly (no finite differences):

* ``Phi_q = dPhi/dq`` (m, n) by ``jax.jacfwd`` of each element's equations with respect to
  its own bodies' coordinates (dense, or as values on a static sparsity pattern);
* ``Phi_t = dPhi/dt`` (m,), so velocities solve ``Phi_q qd = -Phi_t``;
* ``gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt`` (m,), the right-hand side of the
  acceleration equations ``Phi_q qdd = gamma``. It is minus the second derivative of
  ``s -> Phi(q + s qd, t + s)`` at ``s = 0``, computed by two nested ``jax.jvp``.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import ModelError
from ..model import Driver, Joint, Model

#: The linear-solver paths (see :mod:`mixdyn.linalg`).
LINEAR_SOLVERS = ("dense", "sparse", "auto")
#: Redundant rows on the sparse path: relative shift of the Schur complement's diagonal, and
#: the steps of iterated regularization (see :meth:`Constraints.schur_solver`).
REGULARIZATION = 1e-8
REFINE_REDUNDANT = 4

# Static fields that only name things (resolved into indices and arrays at binding): cleared
# so that elements of one kind share one vectorized evaluation.
_NAME_FIELDS = ("name", "point_i", "point_j", "point", "body", "body_i", "body_j")
_BODY_FIELDS = ("b", "bi", "bj")


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
    linear_solver: str = eqx.field(static=True)

    def __init__(self, joints, drivers, nq: int, active=None, rank=None, linear_solver="dense"):
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
        self.linear_solver = self._resolve_solver(linear_solver)

    def _resolve_solver(self, linear_solver: str) -> str:
        if linear_solver not in LINEAR_SOLVERS:
            raise ModelError(
                f"linear_solver must be one of {', '.join(LINEAR_SOLVERS)}, got {linear_solver!r}"
            )
        if linear_solver == "dense" or self.m == 0:  # no equation: nothing to solve
            return "dense"
        from ..linalg import AUTO_MIN_ROWS, choose_solver

        local = self._local_ok()
        if linear_solver == "auto":
            if not local or self.m < AUTO_MIN_ROWS:
                return "dense"
            return choose_solver(self.m, self.schur_structure())
        if not local:
            raise ModelError(
                "the sparse linear solver needs every joint and driver to refer to its bodies "
                "through the fields b, bi, bj; use linear_solver='dense'"
            )
        return "sparse"

    @classmethod
    def of(cls, model: Model, drivers=None) -> Constraints:
        """The model's joints with ``drivers`` (default: the model's own drivers)."""
        return cls(model.joints, model.drivers if drivers is None else drivers, model.nq)

    def with_active(self, active) -> Constraints:
        """The same set keeping only rows ``active`` (indices into the full set)."""
        return Constraints(
            self.joints, self.drivers, self.nq, active, linear_solver=self.linear_solver
        )

    def with_rank(self, rank: int) -> Constraints:
        """The full set, declared of rank ``rank``: if it has redundant rows, every solve with
        it becomes a least-squares (truncated SVD) solve, robust wherever the redundancy moves
        from row to row (a parallelogram passing through its singular positions)."""
        return Constraints(
            self.joints, self.drivers, self.nq, None, rank, linear_solver=self.linear_solver
        )

    def with_linear_solver(self, linear_solver: str) -> Constraints:
        """The same set solved by ``linear_solver`` (``"dense"``, ``"sparse"``, ``"auto"``)."""
        return Constraints(
            self.joints, self.drivers, self.nq, self.active, self.rank, linear_solver
        )

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
    # On the sparse path the equations and their derivatives are evaluated per element,
    # vectorized over the elements of one kind (:meth:`_local`): a small compiled program
    # whatever the number of elements. The dense path (the reference) evaluates the elements
    # one after the other and differentiates the whole vector, as it always has: its numbers
    # do not change with the sparse path (the double four-bar's passage through its singular
    # positions depends on them to the last bit, see tests/test_validation.py).
    def full(self, q, t) -> jax.Array:
        """All rows ``Phi(q, t)`` (n_full,) before dropping redundant ones."""
        if self.linear_solver == "sparse":
            return self._local(_residual, q, t, rows=range(self.n_full))
        parts = [j.residual(q) for j in self.joints] + [d.residual(q, t) for d in self.drivers]
        if not parts:
            return jnp.zeros(0)
        return jnp.concatenate(parts)

    def __call__(self, q, t) -> jax.Array:
        """``Phi(q, t)`` (m,), the rows kept."""
        if self.linear_solver == "sparse":
            return self._local(_residual, q, t)
        Phi = self.full(q, t)
        if len(self.active) == self.n_full:
            return Phi
        return Phi[np.asarray(self.active, dtype=int)]

    def phi_q(self, q, t) -> jax.Array:
        """Jacobian ``Phi_q`` (m, nq), dense: ``jax.jacfwd`` of :meth:`__call__`, or on the
        sparse path scattered from the per-element Jacobians of :meth:`jacobian_values` (the
        same numbers at O(nnz) work, with a small compiled program)."""
        if self.linear_solver == "sparse":
            rows, cols = self.coo()
            v = self.jacobian_values(q, t)
            return jnp.zeros((self.m, self.nq), v.dtype).at[rows, cols].add(v)
        return jax.jacfwd(self.__call__, argnums=0)(q, t)

    def phi_t(self, q, t) -> jax.Array:
        """Partial time derivative ``Phi_t`` (m,)."""
        t = jnp.asarray(t, dtype=jnp.float64)
        if self.linear_solver == "sparse":
            return self._local(_phi_t, q, t)
        return jax.jacfwd(self.__call__, argnums=1)(q, t)

    def gamma(self, q, qd, t) -> jax.Array:
        """Acceleration right-hand side ``gamma`` (m,)."""
        t = jnp.asarray(t, dtype=jnp.float64)
        if self.linear_solver == "sparse":
            return self._local(_gamma, q, t, qd)

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

    # ------------------------------------------------------------------ sparse form
    def _elements(self):
        return (*self.joints, *self.drivers)

    def _static(self) -> _Static:
        """The static layout of this element set (cached per set, see :class:`_Static`)."""
        return _static_of(self.joints, self.drivers)

    def _local_ok(self) -> bool:
        return self._static().groups is not None

    def _layout(self):
        """Static layout: per element its first full row, row count and coordinate columns."""
        return self._static().layout

    def _groups(self):
        """Elements grouped by kind (same tree structure once localized): a list of
        ``(indices of the elements, localized elements)``."""
        elems = self._elements()
        return [(idx, [_localize(elems[i]) for i in idx]) for idx in self._static().groups]

    def _local(self, fn, q, t, qd=None, rows=None):
        """``fn(element, q_local, t, qd_local)`` (rows, ...) over every element, vectorized per
        kind, stacked in row order; the rows ``rows`` of the full set (default: those kept)."""
        layout = self._layout()
        outs, order = [], []
        for idx, elems in self._groups():
            stacked = jax.tree.map(lambda *xs: jnp.stack(xs), *elems)
            cols = np.stack([layout[i][2] for i in idx])
            ql = q[cols]
            qdl = ql if qd is None else qd[cols]
            y = jax.vmap(fn, in_axes=(0, 0, None, 0))(stacked, ql, t, qdl)
            outs.append(y.reshape(-1, *y.shape[2:]))
            for i in idx:
                order.extend(range(layout[i][0], layout[i][0] + layout[i][1]))
        if not outs:
            return jnp.zeros((0,))
        allv = jnp.concatenate(outs)
        pos = np.empty(len(order), dtype=np.int64)
        pos[np.asarray(order, dtype=np.int64)] = np.arange(len(order))
        rows = self.active if rows is None else rows
        return allv[pos[np.asarray(rows, dtype=np.int64)]]

    def coo(self) -> tuple[np.ndarray, np.ndarray]:
        """Static pattern ``(rows, cols)`` of :meth:`jacobian_values` (rows of the kept set)."""
        cache = self._static().coo
        if self.active not in cache:
            cache[self.active] = self._coo()
        return cache[self.active]

    def _coo(self):
        layout = self._layout()
        where = {r: k for k, r in enumerate(self.active)}
        rows, cols = [], []
        for idx, _ in self._groups():
            for i in idx:
                r0, n, c = layout[i]
                for r in range(r0, r0 + n):
                    rows.append(np.full(c.size, where.get(r, -1)))
                    cols.append(c)
        rows = np.concatenate(rows) if rows else np.zeros(0, np.int64)
        cols = np.concatenate(cols) if cols else np.zeros(0, np.int64)
        keep = rows >= 0
        return rows[keep], cols[keep]

    def jacobian_values(self, q, t) -> jax.Array:
        """Values (nnz,) of ``Phi_q`` on the pattern :meth:`coo`: each element's Jacobian
        with respect to its own bodies' coordinates only (O(m) work)."""
        layout = self._layout()
        outs, keep, start = [], [], 0
        active = set(self.active)
        for idx, elems in self._groups():
            stacked = jax.tree.map(lambda *xs: jnp.stack(xs), *elems)
            cols = np.stack([layout[i][2] for i in idx])
            J = jax.vmap(_jac, in_axes=(0, 0, None))(stacked, q[cols], t)
            outs.append(J.reshape(-1))
            for i in idx:
                r0, n, c = layout[i]
                for r in range(r0, r0 + n):
                    if r in active:
                        keep.extend(range(start, start + c.size))
                    start += c.size
        if not outs:
            return jnp.zeros((0,))
        v = jnp.concatenate(outs)
        return v if len(keep) == v.shape[0] else v[np.asarray(keep, dtype=np.int64)]

    def schur_structure(self):
        """Symbolic analysis of ``Phi_q M^-1 Phi_q^T`` (cached per pattern)."""
        from ..linalg import schur_structure

        rows, cols = self.coo()
        return schur_structure(self.m, self.nq, rows, cols)

    def matvec(self, values, x) -> jax.Array:
        """``Phi_q x`` from the sparse values."""
        rows, cols = self.coo()
        return jax.ops.segment_sum(values * x[cols], jnp.asarray(rows), num_segments=self.m)

    def rmatvec(self, values, y) -> jax.Array:
        """``Phi_q^T y`` from the sparse values."""
        rows, cols = self.coo()
        return jax.ops.segment_sum(values * y[rows], jnp.asarray(cols), num_segments=self.nq)

    def schur_solve(self, values, Minv, b):
        """Solve ``(Phi_q M^-1 Phi_q^T) x = b`` on the sparse path; ``(x, pivot_ratio)``.

        With redundant rows (``rank`` given) ``S`` is singular: :meth:`schur_solver`'s
        regularized solve."""
        if self.rank is None:
            return self.schur_structure().solve(values, Minv, b)
        solve, ratio = self.schur_solver(values, Minv)
        return solve(b), ratio

    def schur_solver(self, values, W, shift=None):
        """``(solve, pivot_ratio)``: ``solve(b)`` solves ``(Phi_q W Phi_q^T + shift I) y = b``
        on the sparse path, with one factorization for every right-hand side.

        Without redundant rows: the banded block Cholesky factors. With redundant rows of
        consistent equations (``rank < m``), ``S`` is singular and its minimum-norm solution
        is sought by iterated Tikhonov regularization: ``S + eps I`` is factorized, with
        ``eps = REGULARIZATION * max diag S``, and each of :data:`REFINE_REDUNDANT` steps
        adds ``(S + eps I)^-1`` of the residual of the unregularized system. A component along
        an eigenvalue ``s`` of ``S`` converges by the factor ``eps / (s + eps)`` per step,
        one in the null space of ``S`` (the redundancy) is never excited beyond rounding
        (``~ 1e-16 / REGULARIZATION`` relative): the motion (which depends on ``Phi_q^T y``
        only) matches the dense truncated-SVD solve to rounding, the split of the multipliers
        among redundant rows its minimum-norm split to ``~1e-8`` relative. The pivot ratio
        leaves out the ``m - rank`` smallest pivots (:meth:`SchurStructure.factor`).
        """
        st = self.schur_structure()
        if self.rank is None:
            fac, ratio = st.factor(values, W, shift)
            return (lambda b: st.solve_factored(fac, b)), ratio
        rows, cols = self.coo()
        diag = jax.ops.segment_sum(values**2 * W[cols], jnp.asarray(rows), num_segments=self.m)
        eps = REGULARIZATION * jnp.max(diag, initial=0.0)
        extra = 0.0 if shift is None else shift
        fac, ratio = st.factor(values, W, eps + extra, rank=self.rank)

        def solve(b):
            y = st.solve_factored(fac, b)
            for _ in range(REFINE_REDUNDANT):
                r = b - self.matvec(values, W * self.rmatvec(values, y)) - extra * y
                y = y + st.solve_factored(fac, r)
            return y

        return solve, ratio

    def min_norm_solver(self, values, weights=None, shift=None, refine: int = 0):
        """On the sparse path, a function ``b -> x`` giving the solution of ``Phi_q x = b`` of
        least ``W^-1``-norm, ``x = W Phi_q^T (Phi_q W Phi_q^T + shift I)^-1 b`` (for a square,
        regular ``Phi_q``: the solution), with ``S = Phi_q W Phi_q^T`` factorized once.

        The Schur complement squares the condition number of ``Phi_q``: ``refine`` steps of
        iterative refinement on the residual ``b - Phi_q x`` (with the same factors) bring the
        error back to that of a direct solve of ``Phi_q`` (without a shift).

        Args:
            values: (nnz,) :meth:`jacobian_values`.
            weights: (nq,) diagonal ``W`` (default ones; zeros keep coordinates fixed).
            shift: Levenberg–Marquardt damping added to the diagonal of ``S``.
            refine: steps of iterative refinement.

        Returns:
            ``(solve, ratio)``: ``ratio`` is the square root of the pivot ratio of ``S``'s
            Cholesky factors, comparable to the LU pivot ratio of ``Phi_q`` on the dense path
            (0 when the factorization failed: ``Phi_q`` lost rank).
        """
        W = jnp.ones(self.nq) if weights is None else weights
        inner, ratio = self.schur_solver(values, W, shift)

        def once(b):
            return W * self.rmatvec(values, inner(b))

        def solve(b):
            x = once(b)
            for _ in range(refine):
                x = x + once(b - self.matvec(values, x))
            return x

        return solve, jnp.sqrt(ratio)

    def jacobian_solver(self, q, t, refine: int = 0):
        """A function ``b -> (x, pivot_ratio)`` solving ``Phi_q(q, t) x = b`` on this set's
        path: dense, LU of ``Phi_q`` (a truncated-SVD least-squares solve with redundant rows);
        sparse, the minimum-norm solution through the Schur complement
        (:meth:`min_norm_solver`, factorized once for every right-hand side, with ``refine``
        steps of iterative refinement). The pivot ratios are comparable (see there)."""
        if self.linear_solver == "sparse":
            solve, ratio = self.min_norm_solver(self.jacobian_values(q, t), refine=refine)
            return lambda b: (solve(b), ratio)
        J = self.phi_q(q, t)
        return lambda b: self.solve(J, b)


class _Static:
    """What is static about a set of joints and drivers, computed once per set (not per
    analysis, constraint-set copy or call: at 256 bodies this took 0.3 s each time).

    Attributes:
        layout: per element its first full row, row count and coordinate columns (nq,).
        groups: the elements' indices grouped by kind (same tree structure and leaf shapes
            once localized, one vectorized evaluation per group); None when an element
            cannot be localized (no sparse path).
        coo: the sparsity patterns already built, per tuple of kept rows.
    """

    def __init__(self, elements):
        self.layout, row = [], 0
        for e in elements:
            n = e.n_equations if isinstance(e, Joint) else 1
            cols = [3 * b + k for b in e.body_indices() for k in range(3)]
            self.layout.append((row, n, np.asarray(cols, dtype=np.int64)))
            row += n
        groups: dict = {}
        try:
            for i, e in enumerate(elements):
                loc = _localize(e)
                # the leaves' shapes too: two polynomial laws of different degrees do not stack
                shapes = tuple(np.shape(x) for x in jax.tree.leaves(loc))
                key = (jax.tree_util.tree_structure(loc), shapes, len(e.body_indices()))
                groups.setdefault(key, []).append(i)
            self.groups = list(groups.values())
        except ValueError:
            self.groups = None
        self.coo: dict = {}


#: Identity cache of :class:`_Static`: ``(id(joints), id(drivers)) -> (joints, drivers,
#: info)``. The tuples are held, so their ids stay theirs while cached; a set being traced
#: (tracer leaves: a fresh tuple on every trace) is not stored.
_STATIC_CACHE: dict = {}
_STATIC_CACHE_SIZE = 32


def _static_of(joints: tuple, drivers: tuple) -> _Static:
    key = (id(joints), id(drivers))
    hit = _STATIC_CACHE.get(key)
    if hit is not None and hit[0] is joints and hit[1] is drivers:
        return hit[2]
    info = _Static((*joints, *drivers))
    leaves = jax.tree.leaves((joints, drivers))
    if not any(isinstance(x, jax.core.Tracer) for x in leaves):
        if len(_STATIC_CACHE) >= _STATIC_CACHE_SIZE:
            _STATIC_CACHE.pop(next(iter(_STATIC_CACHE)))
        _STATIC_CACHE[key] = (joints, drivers, info)
    return info


def _localize(e):
    """A copy of element ``e`` reading its bodies from a local vector ``[q_b0, q_b1, ...]``
    (its ``body_indices()`` in order), with its naming fields cleared."""
    bodies = e.body_indices()
    where = {b: k for k, b in enumerate(bodies)}
    names = {f.name for f in dataclasses.fields(e)}
    if not names & set(_BODY_FIELDS) and bodies:
        raise ValueError(type(e).__name__)
    repl = {f: where.get(getattr(e, f), getattr(e, f)) for f in _BODY_FIELDS if f in names}
    repl.update({f: "" for f in _NAME_FIELDS if f in names})
    # A field-by-field copy: the element is already bound and checked, and
    # ``dataclasses.replace`` (through ``__init__``) costs several times more, per element and
    # per call (this runs for every element whenever a constraint set is built or traced).
    loc = object.__new__(type(e))
    for f in dataclasses.fields(e):
        object.__setattr__(loc, f.name, repl[f.name] if f.name in repl else getattr(e, f.name))
    if loc.body_indices() != tuple(range(len(bodies))):
        raise ValueError(type(e).__name__)
    return loc


def _residual(e, ql, t, qdl=None):
    return e.residual(ql) if isinstance(e, Joint) else e.residual(ql, t)


def _jac(e, ql, t):
    return jax.jacfwd(_residual, argnums=1)(e, ql, t)


def _phi_t(e, ql, t, qdl=None):
    return jax.jacfwd(_residual, argnums=2)(e, ql, t)


def _gamma(e, ql, t, qdl):
    def path(s):
        return _residual(e, ql + s * qdl, t + s)

    def rate(s):
        return jax.jvp(path, (s,), (jnp.ones_like(s),))[1]

    _, acc = jax.jvp(rate, (jnp.zeros(()),), (jnp.ones(()),))
    return -acc
