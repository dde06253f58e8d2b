"""Degrees of freedom, redundant equations and the balance of drivers."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee
from scipy.sparse.linalg import splu

from ..equations import Constraints
from ..errors import DegreesOfFreedomError, RedundantConstraintError
from ..linalg import independent_rows
from ..model import Model


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


@jax.jit
def _jac(c: Constraints, q, t):
    return c.phi_q(q, t)


#: :func:`_full_row_rank` certifies full row rank above this ratio (the rank decision's own
#: tolerance is ``rtol = 1e-9``; the margin covers the unpivoted factorization).
FULL_RANK_RATIO = 1e-6


def _full_row_rank(A) -> bool:
    """Whether the rows of ``A`` (m, n) are clearly independent, in O(m) work for a sparse,
    banded ``A``: the pivots of the Cholesky factorization of ``A_n A_n^T`` (rows scaled to
    unit norm, bandwidth-reducing order, sparse LU without pivoting), their ratio
    ``sqrt(min / max)`` above :data:`FULL_RANK_RATIO`. False means "not certain": the caller
    then takes the rank-revealing QR."""
    m = A.shape[0]
    if m == 0:
        return True
    norms = np.linalg.norm(A, axis=1)
    if np.any(norms == 0):
        return False
    C = sp.csr_matrix(A / norms[:, None])
    S = (C @ C.T).tocsr()
    perm = reverse_cuthill_mckee(S, symmetric_mode=True)
    S = S[perm][:, perm].tocsc()
    try:
        lu = splu(S, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return False
    d = lu.U.diagonal()
    if not (np.all(np.isfinite(d)) and np.all(d > 0)):
        return False
    return bool(np.sqrt(d.min() / d.max()) > FULL_RANK_RATIO)


def analyse(
    model: Model, q=None, t: float = 0.0, drivers=None, rtol: float = 1e-9
) -> tuple[DofReport, tuple[int, ...]]:
    """Mobility analysis; returns the report and the rows to keep in ``Constraints.of(model,
    drivers)`` (joint rows independent among themselves, then the drivers)."""
    # the Jacobian by the per-element evaluation for a large mechanism (a small program)
    c = Constraints.of(model, drivers).with_linear_solver("auto")
    q = model.q0 if q is None else jnp.asarray(q, dtype=jnp.float64)
    J = np.asarray(_jac(c, q, jnp.asarray(t, dtype=jnp.float64)))
    nk = c.n_joint_rows
    if _full_row_rank(J):  # the usual case, in O(m): every row independent
        keep = tuple(range(c.n_full))
        report = DofReport(model.nq, nk, nk, model.nq - nk, (), c.n_full - nk, ())
        return report, keep
    keep_k, red_k, rank_k = independent_rows(J[:nk], rtol)
    redundant_drivers = []
    keep = list(keep_k)
    drivers_rows = list(range(nk, c.n_full))
    # Drivers that together raise the rank by their number are all independent (one
    # factorization); otherwise add them one by one: a driver that does not raise the rank is
    # redundant.
    if drivers_rows and independent_rows(J[[*keep, *drivers_rows]], rtol)[2] == rank_k + len(
        drivers_rows
    ):
        keep += drivers_rows
        drivers_rows = []
    rank = rank_k
    for k in drivers_rows:
        _, _, r = independent_rows(J[[*keep, k]], rtol)
        if r > rank:
            keep.append(k)
            rank = r
        else:
            redundant_drivers.append(c.labels[k])
    report = DofReport(
        n_coordinates=model.nq,
        n_equations=nk,
        rank=rank_k,
        dof=model.nq - rank_k,
        redundant=tuple(c.labels[i] for i in red_k),
        n_drivers=c.n_full - nk,
        redundant_drivers=tuple(redundant_drivers),
    )
    return report, tuple(int(i) for i in keep)


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


def require_balanced(report: DofReport, what: str = "kinematic analysis") -> None:
    """Raise a clear error unless the drivers fix every degree of freedom once."""
    if report.n_drivers > report.dof:
        raise DegreesOfFreedomError(
            f"{what}: the mechanism has {report.dof} degree(s) of freedom but "
            f"{report.n_drivers} driver(s); remove {report.n_drivers - report.dof} driver(s)"
            + (
                f" (redundant: {', '.join(report.redundant_drivers)})"
                if report.redundant_drivers
                else ""
            )
        )
    if report.redundant_drivers:
        raise RedundantConstraintError(
            f"{what}: driver(s) {', '.join(report.redundant_drivers)} prescribe a motion that "
            "the joints or other drivers already fix; remove them or drive another coordinate"
        )
    if report.n_drivers != report.dof:
        more = "remove" if report.n_drivers > report.dof else "add"
        raise DegreesOfFreedomError(
            f"{what}: the mechanism has {report.dof} degree(s) of freedom but "
            f"{report.n_drivers} driver(s); {more} {abs(report.n_drivers - report.dof)} driver(s)"
        )
