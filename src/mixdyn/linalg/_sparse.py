"""Sparse linear algebra: the Schur complement ``S = C M^-1 C^T`` of a constraint Jacobian
``C`` given by values on a static sparsity pattern (COO), factorized by a banded block
Cholesky.

The symbolic work is done once per pattern, outside ``jit`` (NumPy/SciPy), and cached:

* the pattern of ``S`` (rows sharing a column of ``C``);
* a fill-reducing, bandwidth-reducing ordering (reverse Cuthill–McKee);
* the block size ``B`` (at least the bandwidth of the reordered ``S``), so that the
  reordered ``S`` is block tridiagonal with ``B x B`` blocks;
* for every product ``C[r, c] C[s, c]`` the slot of ``S``'s block storage it adds to.

Inside ``jit`` only the numeric work remains: ``S``'s blocks by one segment sum, then a
``lax.scan`` of block Cholesky steps and two block triangular sweeps. The cost is
``O(m B^2)``: linear in the number of rows for a mechanism of bounded bandwidth (chains,
ladders, a chain of loops). A mechanism whose constraint graph has a wide bandwidth after
reordering (a hub body tied to every other body) gets ``B ~ m`` and the cost of a dense
solve: :func:`choose_solver` picks the dense path for it. Everything is ``jax.numpy`` and
``lax`` primitives, so ``jit``, ``vmap`` and gradients go through the solve.

The pivot ratio reported is ``min L_ii^2 / max L_ii^2``, the ratio of the pivots an LU
without pivoting would meet (0 when ``S`` is singular: redundant constraints or a singular
position).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np

#: Smallest block size: fewer, larger blocks amortize the scan's per-step overhead.
MIN_BLOCK = 16
UNROLL = 1

#: :class:`~mixdyn.linalg.AutoSolver` takes the sparse path from this many constraint rows
#: on, when the reordered bandwidth is at most :data:`MAX_AUTO_BLOCK`. Measured
#: (``benchmarks/RESULTS.md``, the sparse path): in ``md.forward`` at 32 rows (a 16-link
#: chain) generalized-alpha runs 4-13 % faster on it; the explicit methods 10-30 % slower on
#: one core, but on two cores the dense path takes 1.6-2.4x their CPU time; from 48 rows every
#: method runs faster on it; below 32 the small published benchmarks stay on the dense
#: reference path.
AUTO_MIN_ROWS = 32
MAX_AUTO_BLOCK = 64


class SchurStructure:
    """Symbolic analysis of ``S = C M^-1 C^T`` for one COO pattern of ``C`` (m, n).

    Attributes:
        m, n: shape of ``C``.
        perm: (m,) new order of the rows (``S[perm][:, perm]`` is banded).
        bandwidth: half bandwidth of the reordered ``S``.
        block: block size ``B``; ``nblk`` blocks, ``m`` padded to ``nblk * B``.
        k1, k2, col, slot: the products ``C[k1] C[k2] / M[col]`` and their slots in the flat
            storage ``[D (nblk, B, B), E (nblk - 1, B, B)]`` (``E[i]`` = block ``(i + 1, i)``).
    """

    def __init__(self, m: int, n: int, rows: np.ndarray, cols: np.ndarray, min_block: int):
        self.m, self.n = m, n
        if m == 0:  # nothing to factorize: solve and factor return at once
            self.bandwidth, self.block, self.nblk = 0, 1, 0
            return
        import scipy.sparse as sp  # here, not at import: a small model never needs SciPy
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        rows = np.asarray(rows, dtype=np.int64)
        cols = np.asarray(cols, dtype=np.int64)
        C = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(m, n)).tocsc()
        Sp = (C @ C.T).tocsr()
        Sp = Sp + sp.eye(m, format="csr")
        perm = np.asarray(reverse_cuthill_mckee(Sp, symmetric_mode=True), dtype=np.int64)
        inv = np.empty(m, dtype=np.int64)
        inv[perm] = np.arange(m)
        Sc = Sp.tocoo()
        bw = int(np.max(np.abs(inv[Sc.row] - inv[Sc.col]))) if Sc.nnz else 0
        B = max(bw, min(min_block, m), 1)
        nblk = -(-m // B)
        self.perm, self.inv, self.bandwidth, self.block, self.nblk = perm, inv, bw, B, nblk
        # every pair of entries of C in the same column
        order = np.argsort(cols, kind="stable")
        cs = cols[order]
        starts = np.searchsorted(cs, np.arange(n))
        ends = np.searchsorted(cs, np.arange(n), side="right")
        k1, k2, cc = [], [], []
        for c in range(n):
            ks = order[starts[c] : ends[c]]
            if ks.size:
                a, b = np.meshgrid(ks, ks, indexing="ij")
                k1.append(a.ravel())
                k2.append(b.ravel())
                cc.append(np.full(a.size, c))
        k1 = np.concatenate(k1) if k1 else np.zeros(0, np.int64)
        k2 = np.concatenate(k2) if k2 else np.zeros(0, np.int64)
        cc = np.concatenate(cc) if cc else np.zeros(0, np.int64)
        self.k1_all, self.k2_all, self.col_all = k1, k2, cc  # every product (klujax, tests)
        p1, p2 = inv[rows[k1]], inv[rows[k2]]
        b1, b2 = p1 // B, p2 // B
        keep = b1 >= b2  # diagonal blocks in full, the sub-diagonal blocks (i + 1, i)
        k1, k2, cc, p1, p2, b1, b2 = (a[keep] for a in (k1, k2, cc, p1, p2, b1, b2))
        diag = b1 == b2
        slot = np.where(
            diag,
            (b1 * B + p1 % B) * B + p2 % B,
            nblk * B * B + (b2 * B + p1 % B) * B + p2 % B,
        )
        self.k1, self.k2, self.col, self.slot = k1, k2, cc, slot
        self.size = (2 * nblk - 1) * B * B
        pad = np.arange(m, nblk * B)
        self.pad_slot = (pad // B * B + pad % B) * B + pad % B
        real = np.arange(m)  # the diagonal of S (order irrelevant: a shift adds to all)
        self.diag_slot = (real // B * B + real % B) * B + real % B

    # ------------------------------------------------------------------ numeric
    def blocks(self, values, Minv, shift=None):
        """``(D (nblk, B, B), E (nblk - 1, B, B))`` of the reordered ``S`` from ``C``'s values
        (plus ``shift`` on the diagonal: ``S + shift I``, a Levenberg–Marquardt damping)."""
        B, nblk = self.block, self.nblk
        contrib = values[self.k1] * values[self.k2] * Minv[self.col]
        flat = jax.ops.segment_sum(contrib, jnp.asarray(self.slot), num_segments=self.size)
        if shift is not None:
            flat = flat.at[self.diag_slot].add(shift)
        if self.pad_slot.size:
            flat = flat.at[self.pad_slot].set(1.0)
        D = flat[: nblk * B * B].reshape(nblk, B, B)
        E = flat[nblk * B * B :].reshape(nblk - 1, B, B)
        return D, E

    def solve(self, values, Minv, b):
        """Solve ``S x = b`` (b (m,) or (m, k)); returns ``(x, pivot_ratio)``."""
        if self.m == 0:
            return b, jnp.ones(())
        D, E = self.blocks(values, Minv)
        vec = b.ndim == 1
        bb = b[:, None] if vec else b
        B, nblk = self.block, self.nblk
        rhs = bb[self.perm]
        rhs = jnp.concatenate([rhs, jnp.zeros((nblk * B - self.m, rhs.shape[1]), rhs.dtype)])
        rhs = rhs.reshape(nblk, B, -1)
        L, W, y = _block_cholesky_forward(D, E, rhs)
        x = _block_backward(L, W, y)
        d = jnp.diagonal(L, axis1=1, axis2=2).reshape(-1)[: self.m] ** 2
        x = x.reshape(nblk * B, -1)[: self.m][self.inv]
        return (x[:, 0] if vec else x), _ratio(d)

    def factor(self, values, Minv, shift=None, rank=None):
        """Block Cholesky factors of ``S`` (or ``S + shift I``) for several solves with
        :meth:`solve_factored`; returns ``(factor, pivot_ratio)``.

        With ``rank`` (``S`` has ``m - rank`` redundant rows, factorized with a ``shift``) the
        pivot ratio leaves out the ``m - rank`` smallest pivots, those of the redundancy:
        ``d_(rank) / d_(1)`` of the squared pivots sorted in decreasing order."""
        if self.m == 0:
            return (jnp.zeros((0, 1, 1)), jnp.zeros((0, 1, 1))), jnp.ones(())
        D, E = self.blocks(values, Minv, shift)
        L, W = _block_cholesky(D, E)
        d = jnp.diagonal(L, axis1=1, axis2=2).reshape(-1)[: self.m] ** 2
        if rank is not None and rank < self.m:
            return (L, W), _ranked_ratio(d, rank)
        return (L, W), _ratio(d)

    def solve_factored(self, factor, b):
        """Solve ``S x = b`` (b (m,) or (m, k)) with the factors of :meth:`factor`."""
        if self.m == 0:
            return b
        L, W = factor
        vec = b.ndim == 1
        bb = b[:, None] if vec else b
        B, nblk = self.block, self.nblk
        rhs = bb[self.perm]
        rhs = jnp.concatenate([rhs, jnp.zeros((nblk * B - self.m, rhs.shape[1]), rhs.dtype)])
        y = _block_forward(L, W, rhs.reshape(nblk, B, -1))
        x = _block_backward(L, W, y).reshape(nblk * B, -1)[: self.m][self.inv]
        return x[:, 0] if vec else x


def _ratio(d):
    """``min d / max d`` of the squared pivots, 0 where not finite (a failed factorization)."""
    ratio = jnp.min(d) / jnp.maximum(jnp.max(d), jnp.finfo(d.dtype).tiny)
    return jnp.where(jnp.isfinite(ratio), ratio, 0.0)


def _ranked_ratio(d, rank: int):
    """``d_(rank) / d_(1)``: the pivot ratio of the ``rank`` largest squared pivots ``d``."""
    if rank <= 0:
        return jnp.ones(())
    ds = jnp.sort(d)[::-1]
    ratio = ds[rank - 1] / jnp.maximum(ds[0], jnp.finfo(d.dtype).tiny)
    return jnp.where(jnp.all(jnp.isfinite(d)), ratio, 0.0)


def _block_cholesky_forward(D, E, rhs):
    """Block Cholesky ``S = L L^T`` of a block-tridiagonal SPD matrix (diagonal blocks ``D``,
    sub-diagonal ``E``), fused with the forward sweep ``L y = rhs``.

    Returns ``L`` (nblk, B, B) diagonal factors, ``W`` (nblk, B, B) with ``W[i]`` the
    sub-diagonal factor of block row ``i`` (``W[0] = 0``), and ``y``.
    """
    B = D.shape[1]
    Epad = jnp.concatenate([jnp.zeros((1, B, B), D.dtype), E])

    def step(carry, xs):
        Lp, yp = carry
        Di, Ei, ri = xs
        # W_i = E_i L_{i-1}^-T
        Wi = jsl.solve_triangular(Lp, Ei.T, lower=True).T
        Li = jnp.linalg.cholesky(Di - Wi @ Wi.T)
        yi = jsl.solve_triangular(Li, ri - Wi @ yp, lower=True)
        return (Li, yi), (Li, Wi, yi)

    init = (jnp.eye(B, dtype=D.dtype), jnp.zeros_like(rhs[0]))
    _, (L, W, y) = jax.lax.scan(step, init, (D, Epad, rhs), unroll=UNROLL)
    return L, W, y


def _block_cholesky(D, E):
    """The factors ``(L, W)`` of :func:`_block_cholesky_forward`, without a right-hand side."""
    B = D.shape[1]
    Epad = jnp.concatenate([jnp.zeros((1, B, B), D.dtype), E])

    def step(Lp, xs):
        Di, Ei = xs
        Wi = jsl.solve_triangular(Lp, Ei.T, lower=True).T
        Li = jnp.linalg.cholesky(Di - Wi @ Wi.T)
        return Li, (Li, Wi)

    _, (L, W) = jax.lax.scan(step, jnp.eye(B, dtype=D.dtype), (D, Epad), unroll=UNROLL)
    return L, W


def _block_forward(L, W, rhs):
    """Forward sweep ``L y = rhs`` for the factors of :func:`_block_cholesky`."""

    def step(yp, xs):
        Li, Wi, ri = xs
        yi = jsl.solve_triangular(Li, ri - Wi @ yp, lower=True)
        return yi, yi

    _, y = jax.lax.scan(step, jnp.zeros_like(rhs[0]), (L, W, rhs), unroll=UNROLL)
    return y


def _block_backward(L, W, y):
    """Backward sweep ``L^T x = y`` for the factors of :func:`_block_cholesky_forward`."""
    Wnext = jnp.concatenate([W[1:], jnp.zeros_like(W[:1])])

    def step(xn, xs):
        Li, Wn, yi = xs
        xi = jsl.solve_triangular(Li, yi - Wn.T @ xn, lower=True, trans="T")
        return xi, xi

    _, x = jax.lax.scan(step, jnp.zeros_like(y[0]), (L, Wnext, y), reverse=True, unroll=UNROLL)
    return x


@functools.lru_cache(maxsize=64)
def _structure_cached(m, n, rows_bytes, cols_bytes, min_block):
    rows = np.frombuffer(rows_bytes, dtype=np.int64)
    cols = np.frombuffer(cols_bytes, dtype=np.int64)
    return SchurStructure(m, n, rows, cols, min_block)


def schur_structure(m: int, n: int, rows, cols, min_block: int = MIN_BLOCK) -> SchurStructure:
    """The (cached) symbolic analysis of ``C M^-1 C^T`` for the pattern ``(rows, cols)``."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    cols = np.ascontiguousarray(cols, dtype=np.int64)
    return _structure_cached(int(m), int(n), rows.tobytes(), cols.tobytes(), int(min_block))


__all__ = ["AUTO_MIN_ROWS", "MAX_AUTO_BLOCK", "SchurStructure", "schur_structure"]
