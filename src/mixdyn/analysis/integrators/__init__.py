"""Time integrators for the constrained equations of motion (a :class:`~._problem.Problem`).

Every integrator is one jitted loop that lands exactly on the output times and returns the state
there: the explicit ones (projection, partitioning, Baumgarte) are ``diffrax.diffeqsolve`` with
a Runge–Kutta method wrapped to end each step on the constraints (:mod:`._constrained`);
generalized-alpha, an implicit method of its own, is a ``lax.while_loop``.
Integrators are looked up by name in :data:`INTEGRATORS`.
"""

from ._common import STATUS_MESSAGES, Trajectory
from .baumgarte import baumgarte
from .generalized_alpha import generalized_alpha
from .partitioning import partitioning
from .projection import projection

#: Integrators by name.
INTEGRATORS = {
    "projection": projection,
    "baumgarte": baumgarte,
    "partitioning": partitioning,
    "generalized-alpha": generalized_alpha,
}

__all__ = ["INTEGRATORS", "STATUS_MESSAGES", "Trajectory"]
