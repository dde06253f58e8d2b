"""The linear solver of an analysis, as a value.

Every analysis takes ``linear_solver=``: a :class:`LinearSolver` (:class:`DenseSolver`,
:class:`UnrolledSolver`, :class:`BandedSolver`, :class:`AutoSolver`) or its name
(``"dense"``, ``"unrolled"``, ``"sparse"``, ``"auto"``), turned into the object once
(:func:`as_linear_solver`). A constraint set resolves it once (:meth:`LinearSolver.resolve`)
into the path its solves take, a :class:`DenseSolver`, an :class:`UnrolledSolver` or a
:class:`BandedSolver`, and carries that object: every later stage reads the decision from it
(:attr:`LinearSolver.banded`, :meth:`LinearSolver.factor`), none from a string.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx

from ..errors import ModelError
from ._dense import Factor, lu_factor_checked
from ._sparse import AUTO_MIN_ROWS, MAX_AUTO_BLOCK, SchurStructure
from ._unrolled import (
    UNROLLED_MAX_ROWS,
    UNROLLED_MAX_ROWS_VECTORIZED,
    cholesky_unrolled,
    lu_factor_unrolled,
)


class LinearSolver(eqx.Module):
    """How the solves with ``Phi_q`` are done (abstract).

    Attributes:
        name: the name a model file and ``result.stats["linear_solver"]`` use.
        banded: whether the solves go through the banded block Cholesky factorization of
            ``Phi_q W Phi_q^T`` on the per-element Jacobian's pattern (else dense matrices).
    """

    name: ClassVar[str]
    banded: ClassVar[bool] = False

    def factor(self, A, symmetric: bool = False) -> Factor:
        """The factorization of a square matrix ``A`` (m, m) built from ``Phi_q`` on the
        dense paths (a Schur complement; ``Phi_q`` itself where it is square), done once:
        partial-pivoting LU through LAPACK. ``symmetric``: ``A`` is symmetric positive
        definite away from singular positions (``Phi_q W Phi_q^T``)."""
        return lu_factor_checked(A)

    def vectorized(self) -> LinearSolver:
        """The path of the same solves in a sweep's one vectorized program (``vmap`` over
        members), where batched LAPACK calls cost more than straight-line code of more rows:
        this one unless the choice said otherwise at :meth:`resolve`."""
        return self

    @abc.abstractmethod
    def resolve(
        self, rows: int, per_element: bool, structure: Callable[[], SchurStructure]
    ) -> DenseSolver | UnrolledSolver | BandedSolver:
        """The path a constraint set of ``rows`` kept rows takes.

        Args:
            rows: the set's kept rows ``m``.
            per_element: whether every element refers to its bodies through ``b``, ``bi``,
                ``bj`` (the banded path evaluates each element on its own bodies).
            structure: the symbolic analysis of ``Phi_q M^-1 Phi_q^T`` (called only where
                the choice needs its bandwidth).
        """


class DenseSolver(LinearSolver):
    """LU of dense matrices built from ``Phi_q``; a truncated SVD where equations are
    redundant, a damped SVD at singular positions (:mod:`mixdyn.linalg._dense`). The
    reference path, for any mechanism.

    Attributes:
        in_batch: the path in a sweep's one vectorized program (:meth:`vectorized`; None:
            this one). Set by :class:`AutoSolver` only.
    """

    name: ClassVar[str] = "dense"
    in_batch: LinearSolver | None = eqx.field(default=None, static=True)

    def vectorized(self) -> LinearSolver:
        return self if self.in_batch is None else self.in_batch

    def resolve(self, rows, per_element, structure) -> DenseSolver:
        return self


class UnrolledSolver(LinearSolver):
    """The dense path with its factorizations written out as straight-line array code at
    trace time (:mod:`mixdyn.linalg._unrolled`): Cholesky of the symmetric Schur complement,
    LU with LAPACK's pivots otherwise; no LAPACK call in an integrator's step. Solves equal
    the dense path's to rounding; for a few rows (the program grows like ``m^3``).

    Attributes:
        max_rows: most kept rows; a larger set takes the dense path (:class:`DenseSolver`).
    """

    name: ClassVar[str] = "unrolled"
    max_rows: int = eqx.field(default=UNROLLED_MAX_ROWS, static=True)

    def factor(self, A, symmetric: bool = False) -> Factor:
        return cholesky_unrolled(A) if symmetric else lu_factor_unrolled(A)

    def resolve(self, rows, per_element, structure) -> DenseSolver | UnrolledSolver:
        return self if rows <= self.max_rows else DenseSolver()


class BandedSolver(LinearSolver):
    """``Phi_q`` as values on a static pattern, every solve through the banded block Cholesky
    factorization of ``Phi_q W Phi_q^T`` (:mod:`mixdyn.linalg._sparse`): cost linear in the
    bodies of a chain-like mechanism. Needs every element in the per-element form."""

    name: ClassVar[str] = "sparse"
    banded: ClassVar[bool] = True

    def resolve(self, rows, per_element, structure) -> DenseSolver | BandedSolver:
        if rows == 0:  # no equation: nothing to solve
            return DenseSolver()
        if not per_element:
            raise ModelError(
                "the sparse linear solver needs every joint and driver to refer to its bodies "
                "through the fields b, bi, bj; use linear_solver='dense'"
            )
        return self


class AutoSolver(LinearSolver):
    """The straight-line path for a few rows, the banded path for large mechanisms of small
    bandwidth, else the dense one; in a sweep's one vectorized program, the straight-line
    path up to more rows.

    Attributes:
        max_unrolled: most kept rows for the straight-line path (:class:`UnrolledSolver`;
            measured: :data:`~mixdyn.linalg._unrolled.UNROLLED_MAX_ROWS`).
        max_unrolled_vectorized: most kept rows for it in a vectorized program (measured:
            :data:`~mixdyn.linalg._unrolled.UNROLLED_MAX_ROWS_VECTORIZED`).
        min_rows: fewest kept rows for the banded path (measured: at 32 rows, a 16-link
            chain, it runs generalized-alpha 4-13% faster; the explicit methods 10-30%
            slower on one core, but on two the dense path takes 1.6-2.4x their CPU time).
        max_block: largest reordered bandwidth of ``Phi_q M^-1 Phi_q^T`` for it.
    """

    name: ClassVar[str] = "auto"
    max_unrolled: int = eqx.field(default=UNROLLED_MAX_ROWS, static=True)
    max_unrolled_vectorized: int = eqx.field(default=UNROLLED_MAX_ROWS_VECTORIZED, static=True)
    min_rows: int = eqx.field(default=AUTO_MIN_ROWS, static=True)
    max_block: int = eqx.field(default=MAX_AUTO_BLOCK, static=True)

    def resolve(self, rows, per_element, structure) -> DenseSolver | UnrolledSolver | BandedSolver:
        if 0 < rows <= self.max_unrolled:
            return UnrolledSolver(self.max_unrolled)
        in_batch = None
        if 0 < rows <= self.max_unrolled_vectorized:
            in_batch = UnrolledSolver(self.max_unrolled_vectorized)
        if rows == 0 or not per_element or rows < self.min_rows:
            return DenseSolver(in_batch)
        if structure().bandwidth <= self.max_block:
            return BandedSolver()
        return DenseSolver(in_batch)


#: The names a file or a keyword may give, and their objects.
NAMES: dict[str, type[LinearSolver]] = {
    "dense": DenseSolver,
    "unrolled": UnrolledSolver,
    "sparse": BandedSolver,
    "banded": BandedSolver,
    "auto": AutoSolver,
}


def as_linear_solver(choice: str | LinearSolver) -> LinearSolver:
    """``choice`` as a :class:`LinearSolver` (a name of :data:`NAMES`, or the object itself).

    Raises:
        ModelError: anything else.
    """
    if isinstance(choice, LinearSolver):
        return choice
    if isinstance(choice, str) and choice in NAMES:
        return NAMES[choice]()
    raise ModelError(
        "linear_solver must be one of 'auto', 'dense', 'unrolled', 'sparse' or a "
        "mixdyn.LinearSolver (AutoSolver(), DenseSolver(), UnrolledSolver(), BandedSolver()), "
        f"got {choice!r}"
    )


__all__ = [
    "NAMES",
    "AutoSolver",
    "BandedSolver",
    "DenseSolver",
    "LinearSolver",
    "UnrolledSolver",
    "as_linear_solver",
]
