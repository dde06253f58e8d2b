"""Degrees of freedom, redundant equations and the balance of drivers."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from .._hints import count, listed
from ..equations import Constraints
from ..equations._constraints import Packed
from ..errors import DegreesOfFreedomError, ModelError, RedundantConstraintError
from ..linalg import AutoSolver, independent_rows
from ..model import Model
from ..runtime._programs import cached_jit
from ._assembly import start_q

if TYPE_CHECKING:  # SciPy is imported where a sparse matrix is made: a small model needs none
    import scipy.sparse as sp


@dataclasses.dataclass(frozen=True)
class DofReport:
    """Mobility analysis of a model at one configuration.

    Attributes:
        n_coordinates: ``nc = 3 nb``.
        n_equations: joint equations ``nh`` (redundant ones included).
        rank: rank of the joints' ``Phi_q``.
        dof: degrees of freedom, ``nc - rank``.
        redundant: labels of joint equations that repeat others (dropped by the solvers).
        n_drivers: number of drivers considered.
        redundant_drivers: drivers that prescribe a motion the joints already fix, or that
            repeat another driver.
    """

    n_coordinates: int
    n_equations: int
    rank: int
    dof: int
    redundant: tuple[str, ...]
    n_drivers: int
    redundant_drivers: tuple[str, ...]

    @property
    def balanced(self) -> bool:
        """Whether the drivers fix every degree of freedom exactly once."""
        return self.n_drivers == self.dof and not self.redundant_drivers

    def __str__(self) -> str:
        lines = [
            f"coordinates: {self.n_coordinates}",
            f"joint equations: {self.n_equations} (rank {self.rank})",
            f"degrees of freedom: {self.dof}",
            f"redundant joint equations: {', '.join(self.redundant) or 'none'}",
            f"drivers: {self.n_drivers}"
            + ("" if self.n_drivers == self.dof else f" (expected {self.dof})"),
        ]
        if self.redundant_drivers:
            lines.append(f"redundant drivers: {', '.join(self.redundant_drivers)}")
        return "\n".join(lines)


@cached_jit(optimize=False)  # runs a few times per analysis
def _jac(c: Constraints, q, t):
    return c.phi_q(q, t)


@cached_jit(optimize=False)  # runs a few times per analysis
def _values(p: Packed, q, t):
    return p.jacobian_values(q, t)


#: :func:`_full_row_rank` certifies full row rank above this ratio (the rank decision's own
#: tolerance is ``rtol = 1e-9``; the margin covers the unpivoted factorization).
FULL_RANK_RATIO = 1e-6
#: A dense Jacobian of at most this many rows has its full row rank checked by NumPy
#: (:func:`_full_row_rank_dense`, no SciPy imported); larger ones by SciPy's sparse LU, on one
#: thread: NumPy's BLAS runs its threads for a 128-row Gram matrix (a 64-link chain: 23 ms of
#: wall and 90 ms of CPU more per analysis).
DENSE_RANK_ROWS = 32
#: A model whose Jacobian has at most this many entries (rows x coordinates, about 130
#: bodies on revolute joints) is analysed densely: rank-revealing QR of the whole Jacobian
#: (the reference). Larger ones by :func:`independent_rows_sparse`, in time and memory linear
#: in the size.
DENSE_MAX_ENTRIES = 100_000
#: The sparse analysis hands the rows around a redundancy to the dense QR; it refuses (an
#: input error) when they would form a dense block of more than this many entries
#: (rows x columns, 8 bytes each: 400 MB).
LOCAL_MAX_ENTRIES = 50_000_000
#: Sparse analysis: diagonal shift of the Gram matrix ``A_n A_n^T`` (rows at unit norm) in the
#: inverse iteration, pivots below :data:`SUSPECT_PIVOT` counted as possible dependencies,
#: Ritz values below :data:`NULL_RITZ` (a singular value below 1e-4, far above the QR's
#: ``rtol``) taken as dependencies, rows with a component above :data:`SUPPORT_TOL` (relative)
#: in one as taking part, and :data:`LAYERS` layers of neighbouring rows added around them.
GRAM_SHIFT = 1e-10
SUSPECT_PIVOT = 1e-6
NULL_RITZ = 1e-8
SUPPORT_TOL = 1e-6
LAYERS = 2


#: The largest model the mobility analysis (and ``mixdyn check``) accepts [bodies]: its time
#: and memory grow linearly, about 2 s and 50 MB per 1,000 bodies (``mixdyn check`` of a
#: pendulum chain, ``benchmarks/check_scaling.py``: 17 s and 0.6 GB at 10,000 bodies, 97 s
#: and 2.4 GB at 50,000), most of it reading the file and building the model.
MAX_BODIES = 50_000


def require_checkable(n_bodies: int, where: str = "the model") -> None:
    """Refuse (an input error) a model too large to be checked in bounded time and memory.

    Args:
        n_bodies: number of moving bodies.
        where: what to name in the message (a file name).

    Raises:
        ModelError: more than :data:`MAX_BODIES` bodies.
    """
    if n_bodies > MAX_BODIES:
        raise ModelError(
            f"{where} has {n_bodies:,} bodies; a model is checked and analysed with at most "
            f"{MAX_BODIES:,} bodies (about 2 s and 50 MB per 1,000 bodies); split the "
            "mechanism into smaller models"
        )


def _unit_rows(A: sp.csr_matrix) -> sp.csr_matrix:
    """``A`` (m, n) with its rows scaled to unit norm (zero rows left zero)."""
    import scipy.sparse as sp

    norms = np.sqrt(np.asarray(A.multiply(A).sum(axis=1)).ravel())
    return sp.diags(1.0 / np.where(norms == 0, 1.0, norms)) @ A


def _gram_lu(An: sp.csr_matrix, shift: float):
    """``(lu, perm)``: sparse LU without pivoting (a Cholesky in effect) of ``An An^T + shift
    I`` (m, m) in reverse Cuthill–McKee order ``perm``; ``lu`` None if exactly singular."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import reverse_cuthill_mckee
    from scipy.sparse.linalg import splu

    m = An.shape[0]
    S = (An @ An.T).tocsr()
    if shift:
        S = S + shift * sp.eye(m, format="csr")
    perm = reverse_cuthill_mckee(S, symmetric_mode=True)
    S = S[perm][:, perm].tocsc()
    try:
        lu = splu(S, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return None, perm
    return lu, perm


def _full_row_rank_dense(A: np.ndarray) -> bool:
    """:func:`_full_row_rank` of a dense ``A`` (m, n), by NumPy: the pivots of the Cholesky
    factorization of ``A_n A_n^T`` (rows at unit norm, their own order), their ratio
    ``sqrt(min / max)`` above :data:`FULL_RANK_RATIO`; False means "not certain"."""
    m = A.shape[0]
    if m == 0:
        return True
    norms = np.linalg.norm(A, axis=1)
    if not np.all(np.isfinite(norms)) or np.any(norms == 0):
        return False
    An = A / norms[:, None]
    try:
        d = np.diag(np.linalg.cholesky(An @ An.T)) ** 2
    except np.linalg.LinAlgError:  # not positive definite: dependent rows
        return False
    if not (np.all(np.isfinite(d)) and np.all(d > 0)):
        return False
    return bool(np.sqrt(d.min() / d.max()) > FULL_RANK_RATIO)


def _full_row_rank(A) -> bool:
    """Whether the rows of ``A`` (m, n), dense or sparse, are clearly independent, in O(m)
    work for a sparse, banded ``A``: the pivots of the Cholesky factorization of ``A_n A_n^T``
    (rows scaled to unit norm, bandwidth-reducing order, sparse LU without pivoting), their
    ratio ``sqrt(min / max)`` above :data:`FULL_RANK_RATIO`. False means "not certain": the
    caller then takes the rank-revealing QR. A dense ``A`` (a NumPy array) of at most
    :data:`DENSE_RANK_ROWS` rows: :func:`_full_row_rank_dense`."""
    if isinstance(A, np.ndarray) and A.shape[0] <= DENSE_RANK_ROWS:
        return _full_row_rank_dense(A)
    import scipy.sparse as sp

    A = sp.csr_matrix(A)
    m = A.shape[0]
    if m == 0:
        return True
    An = _unit_rows(A)
    if np.any(np.diff(An.indptr) == 0) or np.any(An.multiply(An).sum(axis=1) == 0):
        return False
    lu, _ = _gram_lu(An, 0.0)
    if lu is None:
        return False
    d = lu.U.diagonal()
    if not (np.all(np.isfinite(d)) and np.all(d > 0)):
        return False
    return bool(np.sqrt(d.min() / d.max()) > FULL_RANK_RATIO)


def _neighbours(P: sp.csr_matrix, rows: np.ndarray, layers: int) -> np.ndarray:
    """``rows`` and the rows sharing a column with them, ``layers`` times over (pattern
    ``P`` (m, n)); sorted."""

    sel = np.zeros(P.shape[0], dtype=bool)
    sel[rows] = True
    PT = P.T.tocsr()
    for _ in range(layers):
        cols = (PT @ sel.astype(float)) > 0
        sel |= (P @ cols.astype(float)) > 0
    return np.flatnonzero(sel)


def dependent_neighbourhood(A) -> np.ndarray | None:
    """Where the rows of the sparse ``A`` (m, n) may depend on one another, in time and memory
    linear in ``m`` for a banded ``A`` (a mechanism of bounded bandwidth).

    The (near) dependencies are the null space of ``A_n^T`` (rows at unit norm): found by
    inverse subspace iteration with the Cholesky factors of ``A_n A_n^T + GRAM_SHIFT I``, its
    block as wide as the factors' small pivots are many (plus 4), widened until it holds more
    than the dependencies. The rows with a component in one of them, and :data:`LAYERS`
    layers of rows around, are returned.

    Every combination of rows that vanishes involves these rows only, so a maximal
    independent subset of them, with every other row, is a maximal independent set of rows.

    Args:
        A: (m, n) sparse matrix.

    Returns:
        The sorted row indices of the neighbourhood, or None when the rows are certainly
        independent (:func:`_full_row_rank`).
    """
    import scipy.sparse as sp

    A = sp.csr_matrix(A)
    m = A.shape[0]
    if _full_row_rank(A):
        return None
    An = _unit_rows(A)
    lu, perm = _gram_lu(An, GRAM_SHIFT)
    d = lu.U.diagonal()
    inv = np.empty(m, dtype=np.int64)
    inv[perm] = np.arange(m)
    S = (An @ An.T).tocsr()[perm][:, perm]
    k = int(np.sum(~(d > SUSPECT_PIVOT)))
    rng = np.random.default_rng(0)
    while True:
        b = min(max(k, 1) + 4, m)
        X = rng.standard_normal((m, b))
        for _ in range(4):
            X = lu.solve(X)
            X, _ = np.linalg.qr(X)
        mu, V = np.linalg.eigh(X.T @ (S @ X))
        null = mu < NULL_RITZ
        if not null.all() or b == m:
            break
        k = 2 * b
    if not null.any():
        return None
    Y = (X @ V[:, null])[inv]  # back to the original row order
    big = np.abs(Y) > SUPPORT_TOL * np.max(np.abs(Y), axis=0)
    rows = np.flatnonzero(big.any(axis=1))
    P = A.copy()
    P.data = np.ones_like(P.data)
    return _neighbours(P, rows, LAYERS)


def _dense_block(A: sp.csr_matrix, rows: np.ndarray) -> np.ndarray:
    """``A[rows]`` (k, c) dense, on the columns where it has entries; refused (an input error)
    beyond :data:`LOCAL_MAX_ENTRIES` entries."""

    sub = A[rows]
    cols = np.unique(sub.indices)
    if rows.size * max(cols.size, 1) > LOCAL_MAX_ENTRIES:
        raise ModelError(
            f"the redundant joint equations or drivers involve {rows.size} equations over "
            f"{cols.size} coordinates, more than the mobility analysis handles "
            f"({LOCAL_MAX_ENTRIES:,} entries); remove the redundant joints"
        )
    return sub[:, cols].toarray()


def independent_rows_sparse(A, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`mixdyn.linalg.independent_rows` for a sparse ``A`` (m, n), in time and memory
    linear in ``m`` for a mechanism of bounded bandwidth: the rank-revealing QR runs on the
    rows of :func:`dependent_neighbourhood` only, every other row being independent.

    Returns:
        ``(independent, redundant, rank)`` as :func:`~mixdyn.linalg.independent_rows`.
    """
    import scipy.sparse as sp

    A = sp.csr_matrix(A)
    m = A.shape[0]
    local = dependent_neighbourhood(A)
    if local is None:
        return np.arange(m), np.zeros(0, int), m
    _, red, _ = independent_rows(_dense_block(A, local), rtol)
    redundant = np.sort(local[red])
    keep = np.setdiff1d(np.arange(m), redundant)
    return keep, redundant, int(keep.size)


def _driver_rows(J, n_keep: int, rtol: float, rank: int | None = None) -> list[int]:
    """Which of the rows ``J[n_keep:]`` (drivers, in order) to keep after the independent
    rows ``J[:n_keep]``: all if together they raise the rank by their number (one
    factorization), else one by one, a driver that does not raise the rank being redundant.

    Args:
        J: (k, n) dense rows: ``n_keep`` independent rows, then the drivers' rows.
        n_keep: number of independent rows first.
        rtol: tolerance of the rank decision.
        rank: the rank of ``J[:n_keep]`` if known (else computed).

    Returns:
        The positions (``>= n_keep``) of the drivers kept.
    """
    keep = list(range(n_keep))
    drivers = list(range(n_keep, J.shape[0]))
    if not drivers:
        return []
    if rank is None:
        rank = independent_rows(J[keep], rtol)[2] if keep else 0
    if drivers and independent_rows(J[[*keep, *drivers]], rtol)[2] == rank + len(drivers):
        return drivers
    out = []
    for k in drivers:
        _, _, r = independent_rows(J[[*keep, k]], rtol)
        if r > rank:
            keep.append(k)
            out.append(k)
            rank = r
    return out


def _dense_jacobian(c: Constraints, q, t) -> np.ndarray:
    """``Phi_q`` (n_full, nq) of every row of ``c`` as a NumPy array, from the per-element
    Jacobians (the entries of :func:`_sparse_jacobian`, placed densely)."""
    if c.m != c.n_full:
        c = c.with_active(range(c.n_full))
    v = np.asarray(_values(c.packed(), q, t))
    rows, cols = c.coo()
    J = np.zeros((c.n_full, c.nq))
    np.add.at(J, (np.asarray(rows), np.asarray(cols)), v)
    return J


def _sparse_jacobian(c: Constraints, q, t) -> sp.csr_matrix:
    """``Phi_q`` (n_full, nq) of every row of ``c`` as a SciPy sparse matrix, from the
    per-element Jacobians (one compiled program per structure; no dense matrix)."""
    import scipy.sparse as sp

    if c.m != c.n_full:
        c = c.with_active(range(c.n_full))
    v = np.asarray(_values(c.packed(), q, t))
    rows, cols = c.coo()
    return sp.csr_matrix((v, (rows, cols)), shape=(c.n_full, c.nq))


def analyse(
    model: Model,
    q=None,
    t: float = 0.0,
    drivers=None,
    rtol: float = 1e-9,
    method: str = "auto",
) -> tuple[DofReport, tuple[int, ...]]:
    """Mobility analysis; returns the report and the rows to keep in ``Constraints.of(model,
    drivers)`` (joint rows independent among themselves, then the drivers).

    Args:
        model: the mechanism.
        q: (nq,) configuration (default: the bodies' ``q0``).
        t: time [time] at which drivers are evaluated.
        drivers: drivers (default: the model's).
        rtol: relative tolerance of the rank decision (see
            :func:`~mixdyn.linalg.independent_rows`).
        method: ``"dense"`` (QR of the dense Jacobian), ``"sparse"`` (sparse Jacobian, QR
            of the rows around a redundancy only: :func:`independent_rows_sparse`) or
            ``"auto"`` (dense up to :data:`DENSE_MAX_ENTRIES` Jacobian entries).
    """
    c = Constraints.of(model, drivers)
    q = np.asarray(start_q(model) if q is None else q, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if method not in ("dense", "sparse", "auto"):
        raise ModelError(f"method must be 'dense', 'sparse' or 'auto', got {method!r}")
    if method == "auto":
        small = c.n_full * model.nq <= DENSE_MAX_ENTRIES or not c._local_ok()
        method = "dense" if small else "sparse"
    if method == "sparse":
        return _analyse_sparse(model, c, _sparse_jacobian(c, q, t), rtol)
    # the per-element Jacobians (a small program, compiled once per structure) when every
    # element has that form, else ``jax.jacfwd`` of the whole set
    if c._local_ok():
        J = _dense_jacobian(c, q, t)
    else:
        J = np.asarray(_jac(c.with_linear_solver(AutoSolver()), q, t))
    nk = c.n_joint_rows
    if _full_row_rank(J):  # the usual case, in O(m): every row independent
        keep = tuple(range(c.n_full))
        report = DofReport(model.nq, nk, nk, model.nq - nk, (), c.n_full - nk, ())
        return report, keep
    keep_k, red_k, rank_k = independent_rows(J[:nk], rtol)
    drivers_rows = list(range(nk, c.n_full))
    kept = _driver_rows(J[[*keep_k, *drivers_rows]], len(keep_k), rtol, rank_k)
    kept_drivers = [drivers_rows[k - len(keep_k)] for k in kept]
    return _report(model, c, red_k, rank_k, [*keep_k, *kept_drivers])


def _report(model, c: Constraints, red_k, rank_k: int, keep) -> tuple[DofReport, tuple]:
    nk = c.n_joint_rows
    kept = set(int(i) for i in keep)
    report = DofReport(
        n_coordinates=model.nq,
        n_equations=nk,
        rank=int(rank_k),
        dof=model.nq - int(rank_k),
        redundant=tuple(c.labels[i] for i in red_k),
        n_drivers=c.n_full - nk,
        redundant_drivers=tuple(c.labels[k] for k in range(nk, c.n_full) if k not in kept),
    )
    return report, tuple(int(i) for i in keep)


def _analyse_sparse(model, c: Constraints, J: sp.csr_matrix, rtol: float):
    """:func:`analyse` on the sparse Jacobian ``J`` (n_full, nq)."""

    nk = c.n_joint_rows
    keep_k, red_k, rank_k = independent_rows_sparse(J[:nk], rtol)
    drivers_rows = np.arange(nk, c.n_full)
    if drivers_rows.size == 0:
        return _report(model, c, red_k, rank_k, keep_k)
    B = J[np.concatenate([keep_k, drivers_rows])]
    local = dependent_neighbourhood(B)
    if local is None:
        return _report(model, c, red_k, rank_k, [*keep_k, *drivers_rows])
    nkeep = keep_k.size
    block = _dense_block(B, local)
    n_local_keep = int(np.sum(local < nkeep))  # local is sorted: joint rows first
    kept_local = _driver_rows(block, n_local_keep, rtol)
    dropped = set(int(local[k]) - nkeep for k in range(n_local_keep, local.size)) - set(
        int(local[k]) - nkeep for k in kept_local
    )
    kept_drivers = [int(drivers_rows[i]) for i in range(drivers_rows.size) if i not in dropped]
    return _report(model, c, red_k, rank_k, [*keep_k, *kept_drivers])


def degrees_of_freedom(model: Model, q=None, t: float = 0.0, drivers=None) -> DofReport:
    """Degrees of freedom and redundant equations of ``model`` at configuration ``q``.

    Args:
        model: the mechanism.
        q: (nq,) configuration (default: the bodies' ``q0``; assemble first for a reliable
            count, since a rough pose may hide or create singularities).
        t: time at which drivers are evaluated [time].
        drivers: drivers to check against the degrees of freedom (default: the model's).
    """
    return analyse(model, q, t, drivers)[0]


#: "degree of freedom" in its two numbers, for :func:`mixdyn._hints.count`.
_DOF = ("degree of freedom", "degrees of freedom")


def require_balanced(report: DofReport, what: str = "kinematic analysis") -> None:
    """Raise a clear error unless the drivers fix every degree of freedom once."""
    if report.n_drivers > report.dof:
        raise DegreesOfFreedomError(
            f"{what}: the mechanism has {count(report.dof, *_DOF)} but "
            f"{count(report.n_drivers, 'driver')}; remove "
            f"{count(report.n_drivers - report.dof, 'driver')}"
            + (
                f" (redundant: {', '.join(report.redundant_drivers)})"
                if report.redundant_drivers
                else ""
            )
        )
    if report.redundant_drivers:
        raise RedundantConstraintError(
            f"{what}: {listed(report.redundant_drivers, 'driver')} prescribe"
            f"{'s' if len(report.redundant_drivers) == 1 else ''} a motion that the joints or "
            "other drivers already fix; remove them or drive another coordinate"
        )
    if report.n_drivers != report.dof:
        more = "remove" if report.n_drivers > report.dof else "add"
        raise DegreesOfFreedomError(
            f"{what}: the mechanism has {count(report.dof, *_DOF)} but "
            f"{count(report.n_drivers, 'driver')}; {more} "
            f"{count(abs(report.n_drivers - report.dof), 'driver')}"
        )
