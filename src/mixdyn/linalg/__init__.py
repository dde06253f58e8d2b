"""The linear-solver layer shared by every analysis.

Three paths, chosen once per constraint set (``Constraints.linear_solver``: a
:class:`DenseSolver`, an :class:`UnrolledSolver` or a :class:`BandedSolver`, resolved from the
analyses' ``linear_solver=`` argument, an object of :mod:`._choice` or its name
``"auto" | "dense" | "unrolled" | "sparse"``):

* dense (:mod:`._dense`): LU of dense matrices built from ``Phi_q``, truncated SVD where
  equations are redundant, a damped (Tikhonov-filtered) SVD at singular positions;
* unrolled (:mod:`._unrolled`): the dense path for a few rows, its Cholesky and LU
  factorizations written out as straight-line array code (no LAPACK call per stage);
* sparse (:mod:`._sparse`): ``Phi_q`` as values on a static pattern, every solve through the
  banded block Cholesky factorization of ``Phi_q W Phi_q^T`` (``W = M^-1``: equations of
  motion; ``W = I``: minimum-norm kinematic steps, refined iteratively where accuracy matters).

:class:`AutoSolver` takes the unrolled path for a few rows and the sparse path for large
mechanisms of small bandwidth.
``Constraints.jacobian(q, t)`` returns the path's operator (:mod:`mixdyn.equations._jacobian`),
whose methods factorize once and return a :class:`Factor` (``solve``, pivot ratio). Redundant
equations make the Schur complement singular: the sparse path solves it by iterated
regularization.
"""

from ._choice import (
    AutoSolver,
    BandedSolver,
    DenseSolver,
    LinearSolver,
    UnrolledSolver,
    as_linear_solver,
)
from ._dense import (
    Factor,
    dependent_rows,
    factor_ranked,
    guarded,
    independent_rows,
    lu_factor_checked,
    lu_solve_checked,
    min_norm_step,
    min_pivot,
    solve_ranked,
)
from ._sparse import AUTO_MIN_ROWS, SchurStructure, schur_structure
from ._unrolled import UNROLLED_MAX_ROWS, UNROLLED_MAX_ROWS_VECTORIZED

__all__ = [
    "AUTO_MIN_ROWS",
    "UNROLLED_MAX_ROWS",
    "UNROLLED_MAX_ROWS_VECTORIZED",
    "AutoSolver",
    "BandedSolver",
    "DenseSolver",
    "Factor",
    "LinearSolver",
    "SchurStructure",
    "UnrolledSolver",
    "as_linear_solver",
    "dependent_rows",
    "factor_ranked",
    "guarded",
    "independent_rows",
    "lu_factor_checked",
    "lu_solve_checked",
    "min_norm_step",
    "min_pivot",
    "schur_structure",
    "solve_ranked",
]
