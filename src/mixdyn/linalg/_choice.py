"""The linear solver of an analysis, as a value.

Every analysis takes ``linear_solver=``: a :class:`LinearSolver` (:class:`DenseSolver`,
:class:`BandedSolver`, :class:`AutoSolver`) or its name (``"dense"``, ``"sparse"``,
``"auto"``), turned into the object once (:func:`as_linear_solver`). A constraint set resolves
it once (:meth:`LinearSolver.resolve`) into the path its solves take, a
:class:`DenseSolver` or a :class:`BandedSolver`, and carries that object: every later stage
reads the decision from it (:attr:`LinearSolver.banded`), none from a string.
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx

from ..errors import ModelError
from ._sparse import AUTO_MIN_ROWS, MAX_AUTO_BLOCK, SchurStructure


class LinearSolver(eqx.Module):
    """How the solves with ``Phi_q`` are done (abstract).

    Attributes:
        name: the name a model file and ``result.stats["linear_solver"]`` use.
        banded: whether the solves go through the banded block Cholesky factorization of
            ``Phi_q W Phi_q^T`` on the per-element Jacobian's pattern (else dense matrices).
    """

    name: ClassVar[str]
    banded: ClassVar[bool] = False

    @abc.abstractmethod
    def resolve(
        self, rows: int, per_element: bool, structure: Callable[[], SchurStructure]
    ) -> DenseSolver | BandedSolver:
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
    reference path, for any mechanism."""

    name: ClassVar[str] = "dense"

    def resolve(self, rows, per_element, structure) -> DenseSolver:
        return self


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
    """The banded path for large mechanisms of small bandwidth, else the dense one.

    Attributes:
        min_rows: fewest kept rows for the banded path (measured: at 32 rows, a 16-link
            chain, it is 1.7x faster per RK4 step; below, the gain is 10-40%).
        max_block: largest reordered bandwidth of ``Phi_q M^-1 Phi_q^T`` for it.
    """

    name: ClassVar[str] = "auto"
    min_rows: int = eqx.field(default=AUTO_MIN_ROWS, static=True)
    max_block: int = eqx.field(default=MAX_AUTO_BLOCK, static=True)

    def resolve(self, rows, per_element, structure) -> DenseSolver | BandedSolver:
        if rows == 0 or not per_element or rows < self.min_rows:
            return DenseSolver()
        if structure().bandwidth <= self.max_block:
            return BandedSolver()
        return DenseSolver()


#: The names a file or a keyword may give, and their objects.
NAMES: dict[str, type[LinearSolver]] = {
    "dense": DenseSolver,
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
        "linear_solver must be one of 'auto', 'dense', 'sparse' or a mixdyn.LinearSolver "
        f"(AutoSolver(), DenseSolver(), BandedSolver()), got {choice!r}"
    )


__all__ = [
    "NAMES",
    "AutoSolver",
    "BandedSolver",
    "DenseSolver",
    "LinearSolver",
    "as_linear_solver",
]
