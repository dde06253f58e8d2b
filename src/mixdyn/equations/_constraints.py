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
from ..linalg import BandedSolver, DenseSolver, LinearSolver, UnrolledSolver, as_linear_solver
from ..linalg._dense import solve_ranked
from ..model import Driver, Joint, Model
from ..model._geometry import vectorized_elements
from ._jacobian import (  # noqa: F401  (REGULARIZATION, REFINE_REDUNDANT: re-exported)
    REFINE_REDUNDANT,
    REGULARIZATION,
    BandedJacobian,
    DenseJacobian,
    JacobianOperator,
)

# Static fields that only name things (resolved into indices and arrays at binding): cleared
# so that elements of one kind share one vectorized evaluation.
_NAME_FIELDS = ("name", "point_i", "point_j", "point", "body", "body_i", "body_j", "carrier",
                "center", "center_i", "center_j", "wheel", "line_point")  # fmt: skip


def _full(joints, drivers, q, t) -> jax.Array:
    """Every element's rows, one element after the other (the dense path's residual)."""
    parts = [j.residual(q) for j in joints] + [d.residual(q, t) for d in drivers]
    if not parts:
        return jnp.zeros(0)
    return jnp.concatenate(parts)


#: :func:`_full` inside a trace: traced once per structure and shapes and reused by every
#: program and derivative that evaluates it (``jax.jacfwd``, ``jax.jvp`` and ``vmap`` of a
#: jitted call transform its traced program, cached, instead of tracing the elements again).
#: XLA inlines the call: the compiled program and its numbers are the same.
_full_traced = eqx.filter_jit(_full)


class Constraints(eqx.Module):
    """The constraint set of one analysis: joints, then drivers (prescribed motions).

    Attributes:
        joints: the joints (time independent).
        drivers: drivers and other prescribed motions (may depend on time).
        active: indices of the rows kept (redundant rows dropped), static.
        labels: a label per row of the full set (``"A.x"``, ``"crank_angle"``), static.
        nq: number of coordinates.
        linear_solver: the path of this set's solves (a
            :class:`~mixdyn.linalg.DenseSolver`, :class:`~mixdyn.linalg.UnrolledSolver` or
            :class:`~mixdyn.linalg.BandedSolver`), resolved once from the analysis' choice,
            static.
        batched: whether this set is solved in a sweep's one vectorized program: the guard at
            singular positions then decides once per batch
            (:func:`~mixdyn.linalg._dense.guarded`), static.
    """

    joints: tuple[Joint, ...]
    drivers: tuple[Driver, ...]
    active: tuple[int, ...] = eqx.field(static=True)
    labels: tuple[str, ...] = eqx.field(static=True)
    owners: tuple[int, ...] = eqx.field(static=True)
    nq: int = eqx.field(static=True)
    rank: int | None = eqx.field(static=True)
    linear_solver: DenseSolver | UnrolledSolver | BandedSolver = eqx.field(static=True)
    batched: bool = eqx.field(static=True)

    def __init__(
        self,
        joints,
        drivers,
        nq: int,
        active=None,
        rank=None,
        linear_solver: str | LinearSolver = DenseSolver(),
        batched: bool = False,
    ):
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
        self.batched = bool(batched)

    def _resolve_solver(
        self, choice: str | LinearSolver
    ) -> DenseSolver | UnrolledSolver | BandedSolver:
        solver = as_linear_solver(choice)
        if isinstance(solver, DenseSolver):
            return solver
        return solver.resolve(self.m, self._local_ok(), self.schur_structure)

    @property
    def banded(self) -> bool:
        """Whether this set's solves take the banded path (:attr:`linear_solver`)."""
        return self.linear_solver.banded

    @classmethod
    def of(cls, model: Model, drivers=None) -> Constraints:
        """The model's joints with ``drivers`` (default: the model's own drivers)."""
        return cls(model.joints, model.drivers if drivers is None else drivers, model.nq)

    def with_active(self, active) -> Constraints:
        """The same set keeping only rows ``active`` (indices into the full set)."""
        return Constraints(
            self.joints,
            self.drivers,
            self.nq,
            active,
            linear_solver=self.linear_solver,
            batched=self.batched,
        )

    def with_rank(self, rank: int) -> Constraints:
        """The full set, declared of rank ``rank``: if it has redundant rows, every solve with
        it becomes a least-squares (truncated SVD) solve, robust wherever the redundancy moves
        from row to row (a parallelogram passing through its singular positions)."""
        return Constraints(
            self.joints,
            self.drivers,
            self.nq,
            None,
            rank,
            linear_solver=self.linear_solver,
            batched=self.batched,
        )

    def with_linear_solver(self, linear_solver: str | LinearSolver) -> Constraints:
        """The same set solved by ``linear_solver`` (a :class:`~mixdyn.linalg.LinearSolver`
        or its name)."""
        return Constraints(
            self.joints, self.drivers, self.nq, self.active, self.rank, linear_solver, self.batched
        )

    def for_batch(self) -> Constraints:
        """The same set, solved in a sweep's one vectorized program (:attr:`batched`), by
        the path its solver takes there (:meth:`~mixdyn.linalg.LinearSolver.vectorized`)."""
        return Constraints(
            self.joints,
            self.drivers,
            self.nq,
            self.active,
            self.rank,
            self.linear_solver.vectorized(),
            True,
        )

    def solve(self, A, b, extra_rank: int = 0):
        """Solve with a matrix built from ``Phi_q`` whose rank is ``self.rank + extra_rank``
        (LU when no row is redundant); returns ``(x, ratio)``."""
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
        if self.banded:
            return self._local(_residual, q, t, rows=range(self.n_full))
        if isinstance(q, jax.core.Tracer) or isinstance(t, jax.core.Tracer):
            return _full_traced(self.joints, self.drivers, q, t)
        return _full(self.joints, self.drivers, q, t)

    def __call__(self, q, t) -> jax.Array:
        """``Phi(q, t)`` (m,), the rows kept."""
        if self.banded:
            return self._local(_residual, q, t)
        Phi = self.full(q, t)
        if len(self.active) == self.n_full:
            return Phi
        return Phi[np.asarray(self.active, dtype=int)]

    def phi_q(self, q, t) -> jax.Array:
        """Jacobian ``Phi_q`` (m, nq), dense: ``jax.jacfwd`` of :meth:`__call__`, or on the
        sparse path scattered from the per-element Jacobians of :meth:`jacobian_values` (the
        same numbers at O(nnz) work, with a small compiled program)."""
        if self.banded:
            rows, cols = self.coo()
            v = self.jacobian_values(q, t)
            return jnp.zeros((self.m, self.nq), v.dtype).at[rows, cols].add(v)
        return jax.jacfwd(self.__call__, argnums=0)(q, t)

    def phi_t(self, q, t) -> jax.Array:
        """Partial time derivative ``Phi_t`` (m,)."""
        t = jnp.asarray(t, dtype=jnp.float64)
        if self.banded:
            return self._local(_phi_t, q, t)
        return jax.jacfwd(self.__call__, argnums=1)(q, t)

    def gamma(self, q, qd, t) -> jax.Array:
        """Acceleration right-hand side ``gamma`` (m,)."""
        t = jnp.asarray(t, dtype=jnp.float64)
        if self.banded:
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

    def _stacked(self) -> tuple:
        """The elements of each kind (:attr:`_Static.groups`) localized and stacked: one
        PyTree per group whose leaves have a leading axis over the group's elements."""
        return _stack_groups(self._static(), self.joints, self.drivers)

    def _local(self, fn, q, t, qd=None, rows=None):
        """``fn(element, q_local, t, qd_local)`` (rows, ...) over every element, vectorized per
        kind, stacked in row order; the rows ``rows`` of the full set (default: those kept)."""
        return _local_eval(
            self._static(), self._stacked(), fn, q, t, qd, self.active if rows is None else rows
        )

    def coo(self) -> tuple[np.ndarray, np.ndarray]:
        """Static pattern ``(rows, cols)`` of :meth:`jacobian_values` (rows of the kept set)."""
        cache = self._static().coo
        if self.active not in cache:
            cache[self.active] = self._coo()
        return cache[self.active]

    def _coo(self):
        st = self._static()
        where = np.full(self.n_full, -1, dtype=np.int64)
        where[np.asarray(self.active, dtype=np.int64)] = np.arange(self.m)
        rows, cols = where[st.nz_rows], st.nz_cols
        keep = rows >= 0
        return rows[keep], cols[keep]

    def jacobian_values(self, q, t) -> jax.Array:
        """Values (nnz,) of ``Phi_q`` on the pattern :meth:`coo`: each element's Jacobian
        with respect to its own bodies' coordinates only (O(m) work)."""
        return _jacobian_eval(self._static(), self._stacked(), q, t, self.active)

    def packed(self) -> Packed:
        """This set with its elements stacked per kind (see :class:`Packed`): a few array
        leaves whatever the number of elements, for compiled programs that do not grow with
        it. Needs the per-element form (every element refers to its bodies through ``b``,
        ``bi``, ``bj``)."""
        if not self._local_ok():
            raise ModelError("packed constraints need every element in the per-element form")
        return Packed(self._stacked(), _Key(self))

    def schur_structure(self):
        """Symbolic analysis of ``Phi_q M^-1 Phi_q^T`` (cached per pattern)."""
        from ..linalg import schur_structure

        rows, cols = self.coo()
        return schur_structure(self.m, self.nq, rows, cols)

    # ------------------------------------------------------------------ the operator
    def jacobian(self, q, t) -> JacobianOperator:
        """``Phi_q(q, t)`` as the linear operator of this set's path, the one place the path
        is read: :class:`~mixdyn.equations._jacobian.DenseJacobian` (the matrix of
        :meth:`phi_q`) or :class:`~mixdyn.equations._jacobian.BandedJacobian` (the values of
        :meth:`jacobian_values`). Every solve with ``Phi_q`` goes through its methods."""
        if self.banded:
            return BandedJacobian(self, self.jacobian_values(q, t))
        return DenseJacobian(self.phi_q(q, t), self.rank, self.batched, self.linear_solver)

    def matvec(self, values, x) -> jax.Array:
        """``Phi_q x`` from the sparse values."""
        return BandedJacobian(self, values).mv(x)

    def rmatvec(self, values, y) -> jax.Array:
        """``Phi_q^T y`` from the sparse values."""
        return BandedJacobian(self, values).rmv(y)

    def schur_solve(self, values, Minv, b):
        """Solve ``(Phi_q M^-1 Phi_q^T) x = b`` on the sparse path; ``(x, pivot_ratio)``
        (:meth:`BandedJacobian.schur_solve`)."""
        return BandedJacobian(self, values).schur_solve(Minv, b)

    def schur_solver(self, values, W, shift=None):
        """``(solve, pivot_ratio)`` of ``Phi_q W Phi_q^T + shift I`` on the sparse path
        (:meth:`BandedJacobian.schur`)."""
        return tuple(BandedJacobian(self, values).schur(W, shift))

    def min_norm_solver(self, values, weights=None, shift=None, refine: int = 0):
        """``(solve, ratio)``: on the sparse path the least-``W^-1``-norm solution of
        ``Phi_q x = b`` (:meth:`JacobianOperator.min_norm`)."""
        return tuple(BandedJacobian(self, values).min_norm(weights, shift, refine))

    def jacobian_solver(self, q, t, refine: int = 0):
        """A function ``b -> (x, pivot_ratio)`` solving ``Phi_q(q, t) x = b`` on this set's
        path, factorized once (:meth:`JacobianOperator.solver`: LU of ``Phi_q``, a
        truncated-SVD least-squares solve with redundant rows; on the sparse path the
        minimum-norm solution through the Schur complement with ``refine`` steps of
        iterative refinement). The pivot ratios are comparable."""
        f = self.jacobian(q, t).solver(refine)
        return lambda b: (f.solve(b), f.ratio)


class _Static:
    """What is static about a set of joints and drivers, computed once per structure (not per
    analysis, constraint-set copy, trace or call: at 2,000 bodies rebuilding it took seconds).

    Shared by every set of the same structure (the same elements, bodies and leaf shapes, any
    numbers): see :func:`_static_of`.

    Attributes:
        layout: per element its first full row, row count and coordinate columns (nq,).
        groups: the elements' indices grouped by kind (same tree structure and leaf shapes
            once localized, one vectorized evaluation per group); None when an element
            cannot be localized (no sparse path).
        loc_defs: per group, the tree structure of its localized elements.
        direct: per group, whether a localized element has exactly its element's leaves (then
            the group is stacked from the elements' leaves, without localizing them).
        cols: per group, (k, nc) the coordinate columns of its k elements.
        pos: (n_full,) where each full row lies in the group-ordered output of
            :func:`_local_eval`.
        nz_rows, nz_cols: (nnz,) the full rows and columns of the per-element Jacobian
            values, in the order :func:`_jacobian_eval` computes them.
        coo: the sparsity patterns already built, per tuple of kept rows.
        keep: per tuple of kept rows, the indices of their values among all values.
    """

    def __init__(self, elements):
        self.layout, row = [], 0
        for e in elements:
            n = type(e).n_equations if isinstance(e, Joint) else 1
            # through the class: an equinox module wraps every method it hands out (slow)
            cols = [3 * b + k for b in type(e).body_indices(e) for k in range(3)]
            self.layout.append((row, n, np.asarray(cols, dtype=np.int64)))
            row += n
        self.n_full = row
        groups: dict = {}
        defs: dict = {}
        direct: dict = {}
        try:
            for i, e in enumerate(elements):
                loc = _localize(e)
                loc_leaves, loc_def = jax.tree_util.tree_flatten(loc)
                # the leaves' shapes too: two polynomial laws of different degrees do not stack
                shapes = tuple(np.shape(x) for x in loc_leaves)
                key = (loc_def, shapes, len(self.layout[i][2]) // 3)
                groups.setdefault(key, []).append(i)
                defs.setdefault(key, loc_def)
                own = jax.tree_util.tree_leaves(e)
                same = len(own) == len(loc_leaves) and all(
                    a is b for a, b in zip(own, loc_leaves, strict=True)
                )
                direct[key] = direct.get(key, True) and same
            self.groups = list(groups.values())
            self.loc_defs = list(defs.values())
            self.direct = list(direct.values())
        except ValueError:
            self.groups = None
        self.coo: dict = {}
        self.keep: dict = {}
        if self.groups is None:
            return
        self.cols = [np.stack([self.layout[i][2] for i in idx]) for idx in self.groups]
        order, nz_rows, nz_cols = [], [], []
        for idx in self.groups:
            for i in idx:
                r0, n, c = self.layout[i]
                order.append(np.arange(r0, r0 + n))
                nz_rows.append(np.repeat(np.arange(r0, r0 + n), c.size))
                nz_cols.append(np.tile(c, n))
        order = np.concatenate(order) if order else np.zeros(0, np.int64)
        self.pos = np.empty(order.size, dtype=np.int64)
        self.pos[order] = np.arange(order.size)
        self.nz_rows = np.concatenate(nz_rows) if nz_rows else np.zeros(0, np.int64)
        self.nz_cols = np.concatenate(nz_cols) if nz_cols else np.zeros(0, np.int64)

    def kept_values(self, active: tuple) -> np.ndarray | None:
        """Indices of the values of the rows ``active`` among all values (None: all kept)."""
        if active not in self.keep:
            if len(active) == self.n_full:
                self.keep[active] = None
            else:
                mask = np.zeros(self.n_full, dtype=bool)
                mask[np.asarray(active, dtype=np.int64)] = True
                self.keep[active] = np.flatnonzero(mask[self.nz_rows])
        return self.keep[active]


#: Identity cache of :class:`_Static`: ``(id(joints), id(drivers)) -> (joints, drivers,
#: info, stacked)``. The tuples are held, so their ids stay theirs while cached; a set being
#: traced (tracer leaves: a fresh tuple on every trace) is not stored, but finds its
#: :class:`_Static` in :data:`_STRUCT_CACHE` by its structure.
_STATIC_CACHE: dict = {}
_STATIC_CACHE_SIZE = 32
#: Structural cache of :class:`_Static`: ``(tree structure, leaf shapes) -> info``.
_STRUCT_CACHE: dict = {}
_STRUCT_CACHE_SIZE = 16


def _is_traced(leaves) -> bool:
    return any(isinstance(x, jax.core.Tracer) for x in leaves)


def _static_of(joints: tuple, drivers: tuple) -> _Static:
    key = (id(joints), id(drivers))
    hit = _STATIC_CACHE.get(key)
    if hit is not None and hit[0] is joints and hit[1] is drivers:
        return hit[2]
    leaves, treedef = jax.tree_util.tree_flatten((joints, drivers))
    skey = (treedef, tuple(np.shape(x) for x in leaves))
    info = _STRUCT_CACHE.get(skey)
    if info is None:
        info = _Static((*joints, *drivers))
        if len(_STRUCT_CACHE) >= _STRUCT_CACHE_SIZE:
            _STRUCT_CACHE.pop(next(iter(_STRUCT_CACHE)))
        _STRUCT_CACHE[skey] = info
    if not _is_traced(leaves):
        if len(_STATIC_CACHE) >= _STATIC_CACHE_SIZE:
            _STATIC_CACHE.pop(next(iter(_STATIC_CACHE)))
        _STATIC_CACHE[key] = [joints, drivers, info, None]
    return info


def _stack_groups(st: _Static, joints: tuple, drivers: tuple) -> tuple:
    """Per group of ``st``, its elements localized and stacked (leading axis: the element).

    Concrete elements are stacked with NumPy (once per set: cached with its
    :class:`_Static`), traced ones with ``jnp.stack``."""
    hit = _STATIC_CACHE.get((id(joints), id(drivers)))
    cached = hit is not None and hit[0] is joints and hit[1] is drivers
    if cached and hit[3] is not None:
        return hit[3]
    elems = (*joints, *drivers)
    out = []
    for idx, loc_def, direct in zip(st.groups, st.loc_defs, st.direct, strict=True):
        if direct:
            per = [jax.tree_util.tree_leaves(elems[i]) for i in idx]
        else:
            per = [jax.tree_util.tree_leaves(_localize(elems[i])) for i in idx]
        leaves = []
        for k in range(loc_def.num_leaves):
            xs = [p[k] for p in per]
            if _is_traced(xs):
                leaves.append(jnp.stack(xs))
            else:
                leaves.append(jax.device_put(np.stack([np.asarray(x) for x in xs])))
        out.append(jax.tree_util.tree_unflatten(loc_def, leaves))
    out = tuple(out)
    if cached:
        hit[3] = out
    return out


def _local_eval(st: _Static, stacked: tuple, fn, q, t, qd, rows) -> jax.Array:
    """``fn(element, q_local, t, qd_local)`` (rows, ...) over the stacked groups, vectorized
    per group, the full rows ``rows`` in their order."""
    outs = []
    for group, cols in zip(stacked, st.cols, strict=True):
        ql = q[cols]
        qdl = ql if qd is None else qd[cols]
        with vectorized_elements():
            y = jax.vmap(fn, in_axes=(0, 0, None, 0))(group, ql, t, qdl)
        outs.append(y.reshape(-1, *y.shape[2:]))
    if not outs:
        return jnp.zeros((0,))
    allv = jnp.concatenate(outs)
    return allv[st.pos[np.asarray(rows, dtype=np.int64)]]


def _jacobian_eval(st: _Static, stacked: tuple, q, t, active: tuple) -> jax.Array:
    """The per-element Jacobian values (nnz,) of the rows ``active``, in :meth:`coo` order."""
    outs = []
    for group, cols in zip(stacked, st.cols, strict=True):
        with vectorized_elements():
            J = jax.vmap(_jac, in_axes=(0, 0, None))(group, q[cols], t)
        outs.append(J.reshape(-1))
    if not outs:
        return jnp.zeros((0,))
    v = jnp.concatenate(outs)
    keep = st.kept_values(tuple(active))
    return v if keep is None else v[keep]


class _Key:
    """Static part of a :class:`Packed` set: equal (one compiled program) for every set of the
    same structure, kept rows, rank and solver path, whatever its numbers."""

    def __init__(self, c: Constraints):
        self.c = c
        self.static = c._static()
        self.id = (id(self.static), c.active, c.rank, c.nq, c.linear_solver, c.batched)

    def __hash__(self):
        return hash(self.id)

    def __eq__(self, other):
        return isinstance(other, _Key) and self.static is other.static and self.id == other.id


class Packed(eqx.Module):
    """A constraint set with its elements stacked per kind (:meth:`Constraints.packed`).

    Its leaves are a few stacked arrays, whatever the number of joints and drivers, so a
    compiled function of it has a program (and a compile time) independent of that number;
    the numbers are those of the per-element (sparse) path of :class:`Constraints`.

    Attributes:
        groups: per kind of element, the localized elements stacked (leading axis: element).
        key: the static part; ``key.c`` is the set, for its static methods (:meth:`coo`,
            solvers): those do not read the elements' numbers.
    """

    groups: tuple
    key: _Key = eqx.field(static=True)

    @property
    def c(self) -> Constraints:
        """The constraint set (use only its static structure inside a compiled function)."""
        return self.key.c

    def full(self, q, t) -> jax.Array:
        """All rows ``Phi(q, t)`` (n_full,) before dropping redundant ones."""
        rows = range(self.c.n_full)
        return _local_eval(self.key.static, self.groups, _residual, q, t, None, rows)

    def __call__(self, q, t) -> jax.Array:
        """``Phi(q, t)`` (m,), the rows kept."""
        return _local_eval(self.key.static, self.groups, _residual, q, t, None, self.c.active)

    def jacobian_values(self, q, t) -> jax.Array:
        """Values (nnz,) of ``Phi_q`` on the pattern ``c.coo()``."""
        return _jacobian_eval(self.key.static, self.groups, q, t, self.c.active)

    def jacobian(self, q, t) -> BandedJacobian:
        """``Phi_q(q, t)`` as the set's banded operator (:meth:`Constraints.jacobian`)."""
        return BandedJacobian(self.c, self.jacobian_values(q, t))

    def phi_t(self, q, t) -> jax.Array:
        """Partial time derivative ``Phi_t`` (m,), the rows kept."""
        t = jnp.asarray(t, dtype=jnp.float64)
        return _local_eval(self.key.static, self.groups, _phi_t, q, t, None, self.c.active)


def _relabel(body, where):
    """A body field's value read through ``where`` (global index -> local): one index, or a
    tuple of them (a contact set's bodies); indices not in ``where`` (the ground) as they
    are."""
    if isinstance(body, tuple):
        return tuple(where.get(b, b) for b in body)
    return where.get(body, body)


def _localize(e):
    """A copy of element ``e`` reading its bodies from a local vector ``[q_b0, q_b1, ...]``
    (its ``body_indices()`` in order), with its naming fields cleared."""
    bodies = type(e).body_indices(e)  # through the class: equinox wraps bound methods (slow)
    where = {b: k for k, b in enumerate(bodies)}
    names = {f.name for f in dataclasses.fields(e)}
    fields = [f for f in type(e).body_fields if f in names]
    if not fields and bodies:
        raise ValueError(f"{type(e).__name__} names no body_fields")
    repl = {f: _relabel(getattr(e, f), where) for f in fields}
    repl.update({f: "" for f in _NAME_FIELDS if f in names})
    # A field-by-field copy: the element is already bound and checked, and
    # ``dataclasses.replace`` (through ``__init__``) costs several times more, per element and
    # per call (this runs for every element whenever a constraint set is built or traced).
    loc = object.__new__(type(e))
    for f in dataclasses.fields(e):
        object.__setattr__(loc, f.name, repl[f.name] if f.name in repl else getattr(e, f.name))
    if type(loc).body_indices(loc) != tuple(range(len(bodies))):
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
