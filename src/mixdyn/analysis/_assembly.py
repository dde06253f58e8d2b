"""Assembly: close the joints from a rough pose (damped Gauss–Newton, least-norm steps)."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..equations import _constraints as _cons
from ..equations._constraints import Packed
from ..errors import AssemblyError, ModelError
from ..linalg import DenseSolver, LinearSolver, min_norm_step
from ..model import CoordinateDriver, Model, Polynomial
from ..model._element import Resolver
from ..runtime._programs import cached_jit, register_key, skeleton

# The static part of a packed constraint set compares by the identity of its layout (cached
# per structure) and holds the set with its numbers: across processes it is keyed by the
# set's structure (its numbers by shape only), which decides the layout.
register_key(
    _cons._Key,
    lambda k: (skeleton(k.c), k.c.active, k.c.rank, k.c.nq, k.c.linear_solver),
)


@dataclasses.dataclass(frozen=True)
class Assembly:
    """Result of an assembly.

    Attributes:
        q: (nq,) assembled coordinates.
        residual: largest joint-equation residual [model units].
        iterations: Gauss–Newton iterations used.
    """

    q: np.ndarray
    residual: float
    iterations: int


def length_scale(model: Model) -> float:
    """A characteristic length of the model [length]: the largest point or body offset."""
    vals = [1e-300]  # NumPy, not one small JAX operation per point (slow for large models)
    for b in model.bodies:
        vals.append(float(np.max(np.abs(np.asarray(b.q0)[:2]))))
        vals += [float(np.max(np.abs(np.asarray(p)))) for p in b.points.values()]
    vals += [float(np.max(np.abs(np.asarray(p)))) for p in model.ground.points.values()]
    L = max(vals)
    return L if L > 1e-300 else 1.0


def start_q(model: Model) -> np.ndarray:
    """The bodies' rough start ``q0`` (nq,) stacked with NumPy [length, length, rad]."""
    return np.concatenate([np.asarray(b.q0, dtype=float) for b in model.bodies])


def hold_drivers(model: Model, hold, q) -> list[CoordinateDriver]:
    """Coordinate drivers that keep the coordinates named in ``hold`` at their value in ``q``."""
    out = []
    q = np.asarray(q)
    for ref in hold:
        idx = model.coordinate_index(ref)
        body, coord = ref.split(".")
        d = CoordinateDriver(f"hold {ref}", body, coord, law=Polynomial([float(q[idx])]))
        out.append(d.bind(Resolver(model.ground, model.bodies)))
    return out


@cached_jit(optimize=False)  # runs a few times per analysis
def _gn_step(c: Constraints, q, t, damping):
    """One damped Gauss–Newton step ``dq = -J^T (J J^T + damping I)^-1 Phi``; returns the new
    ``q`` and the pivot ratio of the solve (1 on the dense path, which does not report it)."""
    r = c(q, t)
    if c.banded:
        solve, ratio = c.min_norm_solver(c.jacobian_values(q, t), shift=damping)
        return q - solve(r), ratio
    J = c.phi_q(q, t)
    return q + min_norm_step(J, r, damping=damping), jnp.ones(())


#: On the sparse path a step whose pivot ratio (of ``J``, the square root of ``J J^T``'s) is
#: below this, or not finite, is taken again on the dense path (LU of the damped ``J J^T``):
#: redundant joint equations make ``J J^T`` singular once the damping has faded.
SPARSE_STEP_MIN_RATIO = 1e-8


@cached_jit(optimize=False)  # runs a few times per analysis
def _residual(c: Constraints, q, t):
    return c.full(q, t)


@cached_jit(optimize=False)  # runs a few times per analysis
def _gn_step_packed(p: Packed, q, t, damping, floor=0.0):
    """:func:`_gn_step` on the sparse path for a packed set: a program whose size does not
    depend on the number of joints (one vectorized evaluation per kind). The damping is at
    least ``floor`` times the largest diagonal entry of ``J J^T``."""
    v = p.jacobian_values(q, t)
    rows, _ = p.c.coo()
    diag = jax.ops.segment_sum(v**2, jnp.asarray(rows), num_segments=p.c.m)
    damping = jnp.maximum(damping, floor * jnp.max(diag, initial=0.0))
    solve, ratio = p.c.min_norm_solver(v, shift=damping)
    return q - solve(p(q, t)), ratio


#: Above this many Jacobian entries (rows x coordinates) a failed sparse step is not taken
#: again on the dense path (a dense ``J`` and ``J J^T``: memory and time growing as the
#: square and the cube of the size) but on the sparse path with the damping at least
#: :data:`SPARSE_DAMPING_FLOOR` times the largest diagonal entry of ``J J^T``.
DENSE_FALLBACK_MAX_ENTRIES = 4_000_000
SPARSE_DAMPING_FLOOR = 1e-10


@cached_jit(optimize=False)  # runs a few times per analysis
def _residual_packed(p: Packed, q, t):
    return p.full(q, t)


class _Steps:
    """The residual and Gauss–Newton step of a constraint set: on the sparse path through
    its packed form (compiled once per structure), else the set itself."""

    def __init__(self, c: Constraints):
        self.c = c
        self.p = c.packed() if c.banded else None

    def residual(self, q, t):
        return _residual(self.c, q, t) if self.p is None else _residual_packed(self.p, q, t)

    def step(self, q, t, damping, floor=0.0):
        if self.p is None:
            return _gn_step(self.c, q, t, damping)
        return _gn_step_packed(self.p, q, t, damping, floor)


def assemble(
    model: Model,
    q=None,
    hold=(),
    t: float = 0.0,
    drivers=(),
    tol: float | None = None,
    max_iter: int = 100,
    linear_solver: str | LinearSolver = "auto",
) -> Assembly:
    """Close the joints (and optional drivers) starting from a rough pose.

    Damped Gauss–Newton with least-norm steps: the result is the consistent configuration
    nearest (in the Euclidean sense, locally) to the starting one.

    Args:
        model: the mechanism.
        q: (nq,) rough configuration (default: the bodies' ``q0``).
        hold: coordinates kept at their starting value, e.g. ``("crank.phi",)``.
        t: time [time] at which drivers are evaluated.
        drivers: drivers to satisfy as well (none by default).
        tol: largest residual accepted [length] (default ``1e-12 x`` the model's size).
        max_iter: iteration limit.
        linear_solver: a :class:`~mixdyn.LinearSolver`, or its name: ``"dense"`` (LU of ``J J^T``),
            ``"sparse"`` (banded Cholesky of ``J J^T``, falling back to the dense step where it is
            singular: redundant joint equations) or ``"auto"`` (sparse for large mechanisms of small
            bandwidth, see :mod:`mixdyn.linalg`).

    Raises:
        ModelError: ``q`` of the wrong shape, or holding a NaN or an infinity.
        AssemblyError: naming the joint equations that could not be closed.
    """
    # NumPy between the compiled programs (a JAX operation outside them is a program too).
    q = np.asarray(start_q(model) if q is None else q, dtype=np.float64)
    if q.shape != (model.nq,):
        raise ModelError(f"q must have shape ({model.nq},), got {tuple(q.shape)}", model.name)
    if not np.all(np.isfinite(q)):
        k = int(np.argmax(~np.isfinite(q)))
        raise ModelError(
            f"the starting pose holds {q[k]}: give finite numbers (a rough pose is enough; "
            "assembly closes the joints from it)",
            model.coordinate_names[k],
        )
    hold = tuple(hold)
    c = Constraints(
        model.joints,
        [*hold_drivers(model, hold, q), *drivers],
        model.nq,
        linear_solver=linear_solver,
    )
    L = length_scale(model)
    tol = 1e-12 * L if tol is None else tol
    t = np.asarray(t, dtype=np.float64)
    steps = _Steps(c)
    r = np.asarray(steps.residual(q, t))
    err = float(np.max(np.abs(r))) if r.size else 0.0
    it = 0
    while err > tol and it < max_iter:
        # Levenberg–Marquardt damping from the residual size keeps the step bounded far away.
        damping = np.asarray(min(err / L, 1.0) * 1e-3)
        q_new, ratio = steps.step(q, t, damping)
        q_new = np.asarray(q_new)
        if c.banded and not (
            float(ratio) >= SPARSE_STEP_MIN_RATIO and bool(np.all(np.isfinite(q_new)))
        ):
            if c.m * c.nq <= DENSE_FALLBACK_MAX_ENTRIES:
                q_new, _ = _gn_step(c.with_linear_solver(DenseSolver()), q, t, damping)
            else:
                q_new, _ = steps.step(q, t, damping, SPARSE_DAMPING_FLOOR)
            q_new = np.asarray(q_new)
        r_new = np.asarray(steps.residual(q_new, t))
        err_new = float(np.max(np.abs(r_new)))
        if not np.isfinite(err_new):
            break
        # Backtracking line search on the residual norm.
        step = q_new - q
        alpha = 1.0
        while err_new > err and alpha > 1e-3:
            alpha *= 0.5
            q_new = q + alpha * step
            r_new = np.asarray(steps.residual(q_new, t))
            err_new = float(np.max(np.abs(r_new)))
        q, r, err = q_new, r_new, err_new
        it += 1
    if not err <= tol:
        r = np.asarray(r)
        bad = [c.labels[i] for i in np.argsort(-np.abs(r)) if abs(r[i]) > tol][:6]
        raise AssemblyError(
            f"could not close the constraints from the given pose in {it} iterations "
            f"(largest residual {err:.3g}, tolerance {tol:.3g}); check the point coordinates "
            "and the starting pose, or hold fewer coordinates",
            None,
            bad,
        )
    return Assembly(np.asarray(q), err, it)
