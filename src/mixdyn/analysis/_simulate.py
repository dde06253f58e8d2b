"""What forward, inverse and mixed dynamics share: a consistent start, the integrator call,
failures turned into named errors, and results in physical terms."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..equations import Constraints, kinetic_energy, potential_energy
from ..errors import ModelError, NumericalError, SingularityError, StepSizeError
from ..linalg import dependent_rows
from ..model import Model
from ._assembly import assemble, hold_drivers, length_scale
from ._problem import Problem
from ._reactions import driver_efforts, joint_reactions, reaction_columns, reaction_kinds
from ._structure import _jac
from .integrators import INTEGRATORS, STATUS_MESSAGES
from .integrators._common import NEWTON_FAILED, STEP_COLLAPSE
from .kinematic import output_times
from .result import Result

FIXED_STEP = ("baumgarte", "generalized-alpha")


def require_masses(model: Model) -> None:
    """Every body of a dynamic run needs a positive mass and inertia."""
    for b in model.bodies:
        if not (float(b.mass) > 0 and float(b.inertia) > 0):
            raise ModelError(
                f"body has mass {float(b.mass):g} and inertia {float(b.inertia):g}; a dynamic "
                "analysis needs both > 0 (give the body a mass and a moment of inertia about its "
                "centre of mass, or weld it to a body that has them)",
                b.name,
            )


@eqx.filter_jit
def _velocity_fix(c: Constraints, q, qd, t, hold_idx):
    J = c.phi_q(q, t)
    rhs = -c.phi_t(q, t)
    if hold_idx.size:
        E = jnp.eye(q.shape[0])[hold_idx]
        J = jnp.concatenate([J, E])
        rhs = jnp.concatenate([rhs, qd[hold_idx]])
    r = rhs - J @ qd
    dqd, *_ = jnp.linalg.lstsq(J, r)
    return qd + dqd, jnp.max(jnp.abs(c.phi_q(q, t) @ (qd + dqd) + c.phi_t(q, t)), initial=0.0)


@eqx.filter_jit
def _velocity_fix_sparse(c: Constraints, q, qd, t, weights):
    """:func:`_velocity_fix` on the sparse path: the least change ``dqd = -W J^T (J W J^T)^-1
    (J qd + Phi_t)``, ``W`` zero on the held coordinates (so the same least-squares solution),
    with one step of iterative refinement; returns ``(qd, residual, pivot_ratio)``."""
    v = c.jacobian_values(q, t)
    phi_t = c.phi_t(q, t)
    solve, ratio = c.min_norm_solver(v, weights, refine=1)
    qd = qd - solve(c.matvec(v, qd) + phi_t)
    return qd, jnp.max(jnp.abs(c.matvec(v, qd) + phi_t), initial=0.0), ratio


def consistent_state(model: Model, c: Constraints, t0: float, q0=None, qd0=None, hold=()):
    """Positions on ``Phi(q, t0) = 0`` and velocities on ``Phi_q qd = -Phi_t``.

    Positions: assembled from ``q0`` (default the bodies' ``q0``) keeping the ``hold``
    coordinates; velocities: the least change of ``qd0`` (default 0) that satisfies the velocity
    constraints, keeping the held coordinates' velocities. Both on ``c``'s linear-solver path
    (the sparse one falls back to the dense least-squares solve where ``Phi_q`` is rank
    deficient: redundant equations, too many held coordinates).
    """
    q = model.q0 if q0 is None else jnp.asarray(q0, dtype=jnp.float64)
    asm = assemble(model, q, hold=hold, t=t0, drivers=c.drivers, linear_solver=c.linear_solver)
    q = jnp.asarray(asm.q)
    qd = jnp.zeros(model.nq) if qd0 is None else jnp.asarray(qd0, dtype=jnp.float64)
    if qd.shape != (model.nq,):
        raise ModelError(f"qd0 must have shape ({model.nq},)", model.name)
    hold_idx = [model.coordinate_index(h) for h in hold]
    qd_in, ok = qd, False
    if c.linear_solver == "sparse":
        W = np.ones(model.nq)
        W[hold_idx] = 0.0
        qd, err, ratio = _velocity_fix_sparse(c, q, qd_in, jnp.asarray(t0), jnp.asarray(W))
        ok = float(ratio) >= 1e-8 and bool(jnp.all(jnp.isfinite(qd)))
    if not ok:
        qd, err = _velocity_fix(
            c.with_linear_solver("dense"), q, qd_in, jnp.asarray(t0), jnp.asarray(hold_idx, int)
        )
    scale = length_scale(model)
    if not float(err) < 1e-8 * max(scale, 1.0) * max(1.0, float(jnp.max(jnp.abs(qd)))):
        raise ModelError(
            "the initial velocities cannot satisfy the velocity constraints with "
            f"the held coordinates {', '.join(hold)}; hold fewer velocities",
            model.name,
        )
    return q, qd


@eqx.filter_jit
def _post_arrays(problem: Problem, ts, Q, QD):
    """Per output time: accelerations, multipliers, pivot ratio, joint reactions (n_joints, 3),
    multipliers' powers, energies ``[T, V, T + V]`` and the constraint violation.

    ``lax.map`` (one time after the other), not ``vmap``: under ``vmap`` the fallback of the
    acceleration solve at singular positions (a ``lax.cond``) would run at every time.
    On the sparse path everything comes from the constraints' sparse form: no dense
    ``Phi_q``.
    """
    c = problem.c

    def one(x):
        q, qd, t = x
        qdd, mu, ratio = problem.accelerations(q, qd, t)
        R = joint_reactions(c, q, t, mu)
        powers = problem.powers(q, qd, t, mu)
        T = kinetic_energy(problem.model, qd)
        V = potential_energy(problem.model, q)
        viol = jnp.max(jnp.abs(c(q, t))) if c.m else jnp.zeros(())
        return qdd, mu, ratio, R, powers, jnp.stack([T, V, T + V]), viol

    return jax.lax.map(one, (Q, QD, ts))


def _post(problem: Problem, ts, Q, QD, n_drivers: int):
    """Accelerations, multipliers and pivot ratios (N, ...) at the output times ``ts`` of the
    states ``Q``, ``QD`` (N, nq), and the result columns in physical terms (NumPy arrays):
    reactions, driver efforts and powers, ``lambda.*``, unknown forces and their powers,
    energies and the constraint violation."""
    c = problem.c
    qdd, mu, ratio, R, powers, E, viol = _post_arrays(problem, ts, Q, QD)
    mu, R, powers, E = (np.asarray(a) for a in (mu, R, powers, E))
    out = reaction_columns(c, R)
    out.update(driver_efforts(c, mu, powers, n_drivers))
    for k in range(c.m - problem.p):
        out[f"lambda.{c.labels[c.active[k]]}"] = mu[:, k]
    for k, name in enumerate(problem.unknown):
        out[name] = mu[:, c.m - problem.p + k]
        out[f"{name}.power"] = powers[:, c.m - problem.p + k]
    out["energy.kinetic"], out["energy.potential"], out["energy.total"] = E[:, 0], E[:, 1], E[:, 2]
    out["constraint.violation"] = np.asarray(viol)
    return qdd, mu, ratio, out


def post_kinds(problem: Problem, n_drivers: int) -> dict[str, str]:
    kinds = reaction_kinds(problem.c)
    c = problem.c
    for k in range(c.m - problem.p):
        row = c.active[k]
        owner = c.owners[row]
        if owner >= len(c.joints):
            kind = c.drivers[owner - len(c.joints)].effort_kind
        else:
            kind = "torque" if c.labels[row].endswith(".angle") else "force"
        kinds[f"lambda.{c.labels[row]}"] = kind
    for d in problem.c.drivers[:n_drivers]:
        kinds[d.name] = d.effort_kind
        kinds[f"{d.name}.power"] = "power"
    for name in problem.unknown:
        kinds[name] = problem.model.element(name).magnitude_kind
        kinds[f"{name}.power"] = "power"
    kinds.update(
        {
            "energy.kinetic": "energy",
            "energy.potential": "energy",
            "energy.total": "energy",
            "work.nonconservative": "energy",
            "work.constraints": "energy",
            "constraint.violation": "length",
        }
    )
    return kinds


def _raise_failure(problem: Problem, traj, ts, method):
    status = int(traj.status)
    t = float(traj.t_fail)
    # Diagnose at the last accepted state (the failure), not at the last output time.
    q = np.asarray(traj.q_last)
    J = np.asarray(_jac(problem.c, jnp.asarray(q), jnp.asarray(t, dtype=jnp.float64)))
    rows = dependent_rows(J, 1e-8) if J.size else []
    names = []
    for i in rows:
        e = problem.c.element_names[problem.c.owners[problem.c.active[i]]]
        if e not in names:
            names.append(e)
    s = np.linalg.svd(J, compute_uv=False) if J.size else np.ones(1)
    r = problem.c.rank or min(J.shape) if J.size else 1
    singular = bool(s[r - 1] < 1e-6 * s[0])
    msg = f"{method} integrator failed: {STATUS_MESSAGES[status]}"
    if singular:
        raise SingularityError(
            msg + "; the constraint Jacobian is (nearly) singular here", t, names
        )
    cls = StepSizeError if status == STEP_COLLAPSE else NumericalError
    if status == NEWTON_FAILED:
        from ..errors import ConvergenceError

        cls = ConvergenceError
    raise cls(msg, t, names if singular else ())


def simulate(
    kind: str,
    problem: Problem,
    ts,
    q0,
    qd0,
    method: str,
    options: dict,
    n_drivers: int,
    progress=None,
) -> Result:
    """Integrate ``problem`` from the consistent state ``(q0, qd0)`` and build the result."""
    if method not in INTEGRATORS:
        raise ModelError(
            f"unknown integrator {method!r}; choose one of {', '.join(INTEGRATORS)}", "method"
        )
    opts = dict(options)
    if method in FIXED_STEP:
        if opts.get("dt") is None:
            raise ModelError(
                f"the {method} integrator has a fixed step: give dt [time], e.g. "
                f"dt={(ts[-1] - ts[0]) / 2000:.3g}",
                "dt",
            )
        opts.pop("rtol", None)
        opts.pop("atol", None)
    integrator = INTEGRATORS[method]
    traj = integrator(problem, jnp.asarray(ts), q0, qd0, progress=progress, **opts)
    if int(traj.status) != 0:
        _raise_failure(problem, traj, ts, method)
    Q, QD, W = np.asarray(traj.q), np.asarray(traj.qd), np.asarray(traj.w)
    qdd, _, ratio, cols = _post(
        problem, jnp.asarray(ts), jnp.asarray(Q), jnp.asarray(QD), n_drivers
    )
    extra = {k: np.asarray(v) for k, v in cols.items()}
    extra["work.nonconservative"] = W[:, 0]
    extra["work.constraints"] = W[:, 1]
    ratio = np.asarray(ratio)
    if not np.all(np.isfinite(np.asarray(qdd))):
        k = int(np.argmax(~np.all(np.isfinite(np.asarray(qdd)), axis=1)))
        raise SingularityError(
            "accelerations are not finite: singular equations of motion", float(ts[k])
        )
    stats = {
        "method": method,
        "options": {k: v for k, v in opts.items() if k != "progress"},
        "steps": int(traj.steps),
        "rejected_steps": int(traj.rejected),
        "newton_iterations": int(traj.newton),
        "max_violation_before_projection": float(traj.max_violation),
        "max_violation": float(np.max(extra["constraint.violation"])),
        "min_pivot_ratio": float(np.min(ratio)),
        "constraint_rows": problem.c.active_labels,
        "unknown_forces": problem.unknown,
        "linear_solver": "sparse" if problem.sparse else "dense",
    }
    return Result(
        kind=kind,
        model=problem.model,
        t=ts,
        q=Q,
        qd=QD,
        qdd=np.asarray(qdd),
        extra=extra,
        kinds=post_kinds(problem, n_drivers),
        stats=stats,
    )


__all__ = ["consistent_state", "hold_drivers", "output_times", "require_masses", "simulate"]
