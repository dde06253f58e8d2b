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

__all__ = [
    "dependent_rows",
    "independent_rows",
    "lu_solve_checked",
    "min_norm_step",
    "min_pivot",
    "solve_kkt",
    "solve_ranked",
]
