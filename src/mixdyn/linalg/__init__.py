"""The linear-solver layer shared by every analysis."""

from ._dense import (
    dependent_rows,
    independent_rows,
    lu_solve_checked,
    min_norm_step,
    min_pivot,
    solve_kkt,
    solve_ranked,
)
from ._sparse import AUTO_MIN_ROWS, SchurStructure, choose_solver, schur_structure

__all__ = [
    "AUTO_MIN_ROWS",
    "SchurStructure",
    "choose_solver",
    "dependent_rows",
    "independent_rows",
    "lu_solve_checked",
    "min_norm_step",
    "min_pivot",
    "schur_structure",
    "solve_kkt",
    "solve_ranked",
]
