"""The consistent start of a dynamic run: positions assembled on ``Phi(q, t0) = 0`` and
velocities on ``Phi_q qd = -Phi_t``, the given ones kept (:func:`consistent_state`)."""

from __future__ import annotations

from collections.abc import Mapping

import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints
from ..errors import ModelError
from ..model import Model
from ..runtime._programs import cached_jit
from ._assembly import assemble, length_scale


@cached_jit(optimize=False)  # runs a few times per analysis
def _velocity_fix(c: Constraints, q, qd, t, weights):
    """The least change of ``qd`` (n,) that satisfies ``Phi_q qd = -Phi_t``, the coordinates of
    weight 0 (the held ones and those whose velocity is given) unchanged:
    ``dqd = -W Phi_q^T (Phi_q W Phi_q^T)^-1 (Phi_q qd + Phi_t)``, on the constraint set's path
    through its operator, guarded at singular positions (redundant rows, conditions that
    fight the joints: a least-squares answer whose residual then tells), and one step of
    iterative refinement. Returns ``(qd, residual)``."""
    return _least_change(c.jacobian(q, t), c.phi_t(q, t), qd, weights)


@cached_jit(optimize=False)  # runs a few times per analysis
def _velocity_fix_packed(p, q, qd, t, weights):
    """:func:`_velocity_fix` of a packed set (:class:`~mixdyn.equations._constraints.Packed`)."""
    return _least_change(p.jacobian(q, t), p.phi_t(q, t), qd, weights)


def fix_velocities(c: Constraints, q, qd, t, weights):
    """:func:`_velocity_fix`; on the sparse path with the set packed
    (:meth:`~mixdyn.equations.Constraints.packed`: a few stacked arrays whatever the number
    of joints), so that the program's size and compile time do not grow with the mechanism
    (each joint's numbers as arguments of their own: 155 s to compile for a 4,000-link
    chain, 9 s for 1,000 links)."""
    if c.banded:
        return _velocity_fix_packed(c.packed(), q, qd, t, weights)
    return _velocity_fix(c, q, qd, t, weights)


def _least_change(J, phi_t, qd, weights):
    """:func:`_velocity_fix` of the operator ``J`` and ``Phi_t`` (m,)."""
    solve = J.min_norm(weights, guard=True).solve
    for _ in range(2):  # the solve, then one refinement on its residual
        qd = qd - solve(J.mv(qd) + phi_t)
    return qd, jnp.max(jnp.abs(J.mv(qd) + phi_t), initial=0.0)


def _velocity_conditions(model: Model, qd0) -> tuple[np.ndarray, list[int], bool]:
    """``(qd (nq,), indices of the given velocities, whether qd0 was a full vector)``."""
    if qd0 is None:
        return np.zeros(model.nq), [], False
    if isinstance(qd0, Mapping):
        qd = np.zeros(model.nq)
        idx = []
        for ref, value in qd0.items():
            i = model.coordinate_index(ref)
            try:
                v = float(value)
            except (TypeError, ValueError):
                v = float("nan")
            if not np.isfinite(v):
                raise ModelError(
                    f"the initial velocity must be a finite number, got {value!r}", ref
                )
            qd[i] = v
            idx.append(i)
        return qd, idx, False
    qd = np.asarray(qd0, dtype=float)
    if qd.shape != (model.nq,):
        raise ModelError(
            f"qd0 must have shape ({model.nq},) or be a mapping {{coordinate: velocity}}, "
            f"got shape {qd.shape}",
            model.name,
        )
    if not np.all(np.isfinite(qd)):
        k = int(np.argmax(~np.isfinite(qd)))
        raise ModelError("the initial velocity must be a finite number", model.coordinate_names[k])
    return qd, [], True


def consistent_state(model: Model, c: Constraints, t0: float, q0=None, qd0=None, hold=()):
    """Positions on ``Phi(q, t0) = 0`` and velocities on ``Phi_q qd = -Phi_t``.

    Positions: assembled from ``q0`` (default the bodies' ``q0``) keeping the ``hold``
    coordinates. Velocities: given velocities are kept, never changed silently:

    - ``qd0=None``: the least (mass-unweighted) velocities satisfying the velocity
      constraints (zero for a mechanism without drivers), the held coordinates at rest;
    - ``qd0={"crank.phi": 1.0, ...}``: *velocity conditions*: these velocities are kept
      exactly and the others follow (the least velocities that satisfy the constraints with
      them); too many or inconsistent conditions are a :class:`ModelError` naming them;
    - ``qd0`` a full (nq,) vector: it must satisfy the velocity constraints (to 1e-8 of its
      size; rounding is corrected), else a :class:`ModelError`.

    Both on ``c``'s linear-solver path, through its operator (guarded where ``Phi_q`` is rank
    deficient: redundant equations, too many held coordinates).
    """
    # NumPy between the compiled programs: each JAX operation outside them would be a
    # program of its own to look up (and, in a new process, to load).
    q = np.asarray(model.q0 if q0 is None else q0, dtype=np.float64)
    asm = assemble(model, q, hold=hold, t=t0, drivers=c.drivers, linear_solver=c.linear_solver)
    q = np.asarray(asm.q, dtype=np.float64)
    qd, given, full = _velocity_conditions(model, qd0)
    hold_idx = sorted({model.coordinate_index(h) for h in hold} | set(given))
    qd_in = qd
    t0_ = np.asarray(t0, dtype=np.float64)
    W = np.ones(model.nq)
    W[hold_idx] = 0.0
    qd, err = fix_velocities(c, q, qd_in, t0_, W)
    qd = np.array(qd)  # a copy: writable
    if hold_idx:  # the conditions hold to rounding: keep the given numbers bit for bit
        qd[hold_idx] = qd_in[hold_idx]
    scale = length_scale(model)
    size = max(1.0, float(np.max(np.abs(qd_in), initial=0.0)))
    if not float(err) < 1e-8 * max(scale, 1.0) * max(1.0, float(np.max(np.abs(qd)))):
        names = [model.coordinate_names[i] for i in given]
        what = []
        if names:
            what.append(f"the given velocities of {', '.join(names)}")
        if hold:
            what.append(f"the held coordinates {', '.join(hold)} (at rest)")
        raise ModelError(
            f"{' and '.join(what) or 'the drivers'} cannot all hold with the joints' velocity "
            f"constraints (violated by {float(err):.3g}): they are too many or inconsistent; "
            "give only independent velocities (at most one per degree of freedom)",
            ", ".join(names) or model.name,
        )
    change = float(np.max(np.abs(qd - qd_in), initial=0.0))
    if full and change > 1e-8 * size:
        k = int(np.argmax(np.abs(qd - qd_in)))
        raise ModelError(
            f"the initial velocities qd0 violate the velocity constraints (making them "
            f"consistent would change {model.coordinate_names[k]} by {change:.3g}); give a "
            "consistent vector, or only the velocities you mean as a mapping "
            "{coordinate: velocity} (the others follow)",
            model.name,
        )
    return jax.device_put(q), jax.device_put(qd)  # JAX arrays, as before (no program)


__all__ = ["consistent_state"]
