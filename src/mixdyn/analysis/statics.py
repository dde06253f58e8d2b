"""Statics: the equilibrium of a mechanism under its loads, its stability, and the efforts and
reactions that hold it (static force analysis, no inertia forces).

At rest the equations of motion ``M qdd = Q(q, 0, t) - Phi_q^T lambda`` with ``Phi(q, t) = 0``
become

    R(q, lambda) = [ Q(q, 0, t) - Phi_q(q)^T lambda ;  Phi(q, t) ] = 0,

solved by Newton's method from the assembled start, the Jacobian of ``R`` by ``jax.jacfwd``
(each step halved until the residual's measure decreases). Free degrees of freedom move to the
equilibrium (gravity, springs, constant forces and laws at ``t``); driven ones stay where the
drivers put them and their efforts are the static ones (kinetostatics without inertia; with
inertia: :func:`~mixdyn.inverse`).

The residual's measure is the same in every unit system. Each row is taken relative to its
own scale: with ``L`` the model's characteristic length (its largest point or body offset) and
the coordinate scales ``D = diag(L, L, 1, ...)`` (a body's x, y [length] and phi [rad]), a
force row ``Q_i`` counts as the work ``Q_i D_ii`` relative to ``F L`` (``F`` the largest
applied force, a moment counting as a force at ``L``; each load taken alone, gravity and each
force element, so that loads that balance at the start keep their size), and a constraint
row ``Phi_j`` relative to ``max_i |dPhi_j/dq_i| D_ii`` at the start, i.e. in its own unit
(length for a point on a point, rad for an angle driver). The same mechanism written in m or
in mm then takes the same Newton steps and reaches the same equilibrium.

Stability: the tangent stiffness ``K = -d(Q - Phi_q^T lambda)/dq`` (for conservative loads the
Hessian of ``V + lambda . Phi``) in the scaled coordinates ``(x/L, y/L, phi)``,
``K~ = D K D`` [energy], restricted to the motions the constraints allow,
``K_r = N^T K~ N`` with ``N`` an orthonormal basis of the null space of ``Phi_q D``: the
equilibrium is stable when every eigenvalue of ``K_r``'s symmetric part is positive, unstable
when one is negative (then the mechanism, nudged, leaves it). Every entry of ``K~`` is an
energy (force times length, or torque per rad squared), so the eigenvalues are energies in
the model's units: the same physical quantity in m and in mm (converted like a torque).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..equations import applied_forces, largest_load
from ..equations._reaction_dependent import check_supported
from ..errors import ConvergenceError, ModelError
from ..linalg import DenseSolver, LinearSolver
from ..model import Model
from . import _setup
from ._assembly import length_scale
from ._prepare import kinematic_start
from ._reactions import (
    contact_columns,
    driver_efforts,
    joint_reactions,
    reaction_columns,
    reaction_kinds,
)
from ._setup import Setup
from .kinematic import output_times
from .result import Result


@dataclasses.dataclass(frozen=True)
class Statics:
    """An equilibrium.

    Attributes:
        q: (nq,) the equilibrium positions [model units].
        lam: (m,) the multipliers of the independent constraint rows.
        result: the equilibrium as a one-row :class:`~mixdyn.Result` (kind ``"statics"``):
            positions, the joints' reactions and the drivers' efforts by name, with units.
        eigenvalues: the reduced stiffness' eigenvalues in the scaled coordinates
            ``(x/L, y/L, phi)`` (module docstring), ascending (empty without free degrees of
            freedom) [energy: force * length].
        stable: every eigenvalue positive (True without free degrees of freedom).
        iterations: Newton iterations.
        residual: the largest residual after, each row relative to its own scale (module
            docstring) [-].
    """

    q: np.ndarray
    lam: np.ndarray
    result: Result
    eigenvalues: np.ndarray
    stable: bool
    iterations: int
    residual: float

    def __getitem__(self, column: str) -> float:
        """A column of the equilibrium (``"crank.phi"``, ``"O.Fx"``, ``"motor"``)."""
        return float(self.result[column][0])


def _residual_of(model, c, t, x):
    q, lam = x[: model.nq], x[model.nq :]
    Q = applied_forces(model, q, jnp.zeros_like(q), t)
    return jnp.concatenate([Q - c.jacobian(q, t).rmv(lam), c(q, t)])


@eqx.filter_jit
def _residual(model, c, t, x):
    """``R(q, lambda)`` (nq + m,) at time ``t`` (traced once per structure)."""
    return _residual_of(model, c, t, x)


@eqx.filter_jit
def _jacobian(model, c, t, x):
    """``dR/d(q, lambda)`` (nq + m, nq + m), by forward-mode differentiation."""
    return jax.jacfwd(lambda y: _residual_of(model, c, t, y))(x)


def _positive(option: str):
    def convert(value):
        try:
            ok = not isinstance(value, bool) and np.isfinite(float(value)) and float(value) > 0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ModelError(f"{option} must be a finite number > 0, got {value!r}", option)
        return float(value)

    return convert


class _Equilibria(_setup.Analysis):
    """The options that static and quasi-static analyses share (see either)."""

    _: dataclasses.KW_ONLY
    q0: np.ndarray | None = eqx.field(default=None, converter=_setup.start_positions)
    hold: tuple[str, ...] = eqx.field(default=(), converter=_setup.held)
    tol: float = eqx.field(default=1e-10, converter=_positive("tol"))
    max_iter: int = eqx.field(default=100, converter=_setup.checked("max_iter"))

    def _initial(self, model: Model, t0: float, given=None):
        """The assembled start of an equilibrium at ``t0`` (dense path; the drivers'
        balance not required: free degrees of freedom settle)."""
        check_supported(model, "statics (its equilibrium leaves out the joint reactions)")
        return kinematic_start(
            model, t0, given, q0=self.q0, hold=self.hold, linear_solver=DenseSolver()
        )


class Static(_Equilibria):
    """Statics as a value: the equilibrium of a mechanism under its loads at one time, and its
    stability (``md.statics``' options, for :func:`~mixdyn.prepare`). Its run takes the one
    time ``t0`` of its set-up and gives a :class:`~mixdyn.Statics`.

    Attributes:
        q0: (nq,) rough start [model units], or None (the bodies' ``q0``); the equilibrium
            found is the one Newton's method reaches from there.
        hold: coordinates held while the start is assembled (not at the equilibrium).
        tol: relative tolerance on the force and constraint residuals [-] (default 1e-10).
        max_iter: Newton iterations at most, 1 to 1000 (default 100).
    """

    name: ClassVar[str] = "statics"

    def _prepare(self, model: Model, t0: float, given=None) -> Setup:
        return Setup(self, model, t0, self._initial(model, t0))

    def _run(self, setup: Setup, t, progress=None) -> Statics:
        _setup.no_progress(self, progress)
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        if ts.shape != (1,):
            raise ModelError(
                f"a static analysis is at one time, its set-up's t0 = {setup.t0:g}; got "
                f"{ts.size} times (a quasi-static analysis follows many: QuasiStatic)",
                "t",
            )
        _setup.check_start(setup, ts, accelerations=False)  # none reported
        return _equilibrium(setup)


def statics(
    model: Model,
    *,
    t: float = 0.0,
    q0=None,
    hold=(),
    tol: float = 1e-10,
    max_iter: int = 100,
) -> Statics:
    """The equilibrium of ``model`` under its loads at time ``t``, and its stability.

    Args:
        model: the mechanism: its free degrees of freedom move to the equilibrium; its drivers
            hold theirs (their efforts are the static ones).
        t: the time at which loads and drivers' laws are taken [time].
        q0: (nq,) rough start (default: the bodies' ``q0``); the equilibrium found is the one
            Newton's method reaches from there (a mechanism may have several: start near the
            one wanted).
        hold: coordinates held while the start is assembled (not at the equilibrium).
        tol: relative tolerance on the force and constraint residuals.
        max_iter: Newton iterations at most.

    Returns:
        A :class:`Statics`.

    Raises:
        ConvergenceError: no equilibrium reached (a load no position can balance, e.g. an
            unbalanced constant force on a free slider).
    """
    analysis = Static(q0=q0, hold=hold, tol=tol, max_iter=max_iter)
    return analysis._run(analysis._prepare(model, float(t)), float(t))


def _equilibrium(setup: Setup) -> Statics:
    """Newton's method on ``R(q, lambda) = 0`` from the set-up's start at its time ``t0``,
    then the stability (module docstring)."""
    analysis, model, prep, t = setup.analysis, setup.model, setup.start, setup.t0
    tol, max_iter = analysis.tol, analysis.max_iter
    c = prep.constraints(independent_rows_only=True)
    nq, m = model.nq, c.m
    tj = jnp.asarray(float(t))

    def R(x):
        return _residual(model, c, tj, x)

    def K(x):
        return _jacobian(model, c, tj, x)

    q = np.asarray(prep.q, dtype=float)
    r0 = np.asarray(R(jnp.concatenate([jnp.asarray(q), jnp.zeros(m)])))
    Q0 = r0[:nq]  # the applied forces (no multipliers yet)
    _, J0 = _tangent(model, c, tj, jnp.asarray(q), jnp.zeros(m))
    J0 = np.asarray(J0)
    L = length_scale(model)
    D = coordinate_scales(model, L)
    F0 = float(largest_load(model, jnp.asarray(q), tj, jnp.asarray(D))) / L  # as a force
    rows = np.max(np.abs(J0) * D, axis=1) if m else np.zeros(0)  # each row's own unit
    rows = np.where(rows > 0.0, rows, 1.0)
    # the start's multipliers: the loads balanced in the least-squares sense of virtual work
    lam = np.linalg.lstsq(D[:, None] * J0.T, D * Q0, rcond=None)[0] if m else np.zeros(0)
    x = np.concatenate([q, lam])

    def scaled(r):
        work = np.abs(r[:nq]) * D / L  # a moment as the force at L
        force = max(F0, float(np.max(work, initial=0.0)), 1e-300)
        return max(np.max(work, initial=0.0) / force, np.max(np.abs(r[nq:]) / rows, initial=0.0))

    # Newton's step in dimensionless unknowns and rows (the same step in every unit system,
    # also where the Jacobian is singular and the least-squares step is taken)
    energy = max(F0, 1e-300) * L
    row_w = np.concatenate([D / energy, 1.0 / rows])
    col_w = np.concatenate([D, energy / rows])
    r = np.asarray(R(jnp.asarray(x)))
    err = scaled(r)
    it = 0
    while err > tol and it < max_iter:
        it += 1
        Kx = row_w[:, None] * np.asarray(K(jnp.asarray(x))) * col_w[None, :]
        step = col_w * np.linalg.lstsq(Kx, -row_w * r, rcond=None)[0]
        a = 1.0
        while True:
            trial = x + a * step
            rt = np.asarray(R(jnp.asarray(trial)))
            et = scaled(rt)
            if np.all(np.isfinite(rt)) and (et < err or a < 1e-6):
                break
            a *= 0.5
        x, r, err = trial, rt, et
    if not (err <= tol and np.all(np.isfinite(x))):
        raise ConvergenceError(
            f"no equilibrium reached from the start: residual {err:.2e} after {it} Newton "
            "iterations; a load no position can balance (a constant force on a free slider), "
            "or a start too far from the equilibrium",
            float(t),
        )
    q, lam = x[:nq], x[nq:]
    eig = _reduced_stiffness(model, c, float(t), q, lam)
    stable = bool(np.all(eig > 1e-9 * max(np.max(np.abs(eig), initial=0.0), 1e-300)))
    return Statics(q, lam, _result(model, c, prep, float(t), q, lam), eig, stable, it, err)


@eqx.filter_jit
def _tangent(model, c, t, q, lam):
    """``(K, Phi_q)``: the tangent stiffness ``-d(Q - Phi_q^T lambda)/dq`` and ``Phi_q``."""

    def force(qq):
        return applied_forces(model, qq, jnp.zeros_like(qq), t) - c.jacobian(qq, t).rmv(lam)

    return -jax.jacfwd(force)(q), c.jacobian(q, t).dense()


@eqx.filter_jit
def _reactions(c, q, t, lam):
    return joint_reactions(c, q, t, lam)


def coordinate_scales(model: Model, L: float) -> np.ndarray:
    """The coordinates' scales ``D`` (nq,): ``L`` for a body's x and y [length], 1 for its
    phi [rad]."""
    return np.tile(np.array([L, L, 1.0]), model.nb)


def _reduced_stiffness(model, c, t, q, lam) -> np.ndarray:
    """Eigenvalues of ``N^T (D K D) N`` (symmetric part), ascending [energy]."""
    nq = model.nq
    K, J = (
        np.asarray(a) for a in _tangent(model, c, jnp.asarray(t), jnp.asarray(q), jnp.asarray(lam))
    )
    D = coordinate_scales(model, length_scale(model))
    K, J = D[:, None] * K * D[None, :], J * D[None, :]
    if J.shape[0]:
        _, s, vt = np.linalg.svd(J)
        rank = int(np.sum(s > 1e-10 * s[0])) if s.size else 0
        N = vt[rank:].T
    else:
        N = np.eye(nq)
    if N.shape[1] == 0:
        return np.zeros(0)
    Kr = N.T @ K @ N
    return np.sort(np.linalg.eigvalsh(0.5 * (Kr + Kr.T)))


def _result(model, c, prep, t, q, lam) -> Result:
    qj, lj = jnp.asarray(q), jnp.asarray(lam)
    R = np.asarray(_reactions(c, qj, jnp.asarray(t), lj))[None]
    extra = {k: np.asarray(v) for k, v in reaction_columns(c, R).items()}
    extra.update({k: np.asarray(v)[None] for k, v in contact_columns(c, qj, lj[: c.m]).items()})
    powers = np.zeros((1, c.m))
    efforts = driver_efforts(c, np.asarray(lam)[None], powers, len(prep.drivers))
    kinds = reaction_kinds(c)
    for d in prep.drivers:
        extra[d.name] = np.asarray(efforts[d.name])
        kinds[d.name] = d.effort_kind
    zeros = np.zeros((1, model.nq))
    return Result(
        kind="statics",
        model=model,
        t=np.array([t]),
        q=np.asarray(q)[None],
        qd=zeros,
        qdd=zeros,
        extra=extra,
        kinds=kinds,
    )


class QuasiStatic(_Equilibria):
    """Quasi-statics as a value: the equilibria at the output times, each from the one
    before (``md.quasi_static``'s options, for :func:`~mixdyn.prepare` and the studies). Its
    set-up holds the first equilibrium's assembled start.

    Attributes:
        q0: (nq,) rough start of the first equilibrium [model units], or None.
        hold: coordinates held while the first start is assembled.
        tol: relative tolerance on the force and constraint residuals [-] (default 1e-10).
        max_iter: Newton iterations at most per time, 1 to 1000 (default 100).
    """

    name: ClassVar[str] = "quasi-static"

    def _prepare(self, model: Model, t0: float, given=None) -> Setup:
        return Setup(self, model, t0, self._initial(model, t0))

    def _run(self, setup: Setup, t, progress=None) -> Result:
        _setup.no_progress(self, progress)
        model = setup.model
        ts = output_times(t, minimum=1)
        _setup.check_start(setup, ts, accelerations=False)  # none reported
        rows, smallest, iters = [], [], 0
        for k, tk in enumerate(ts):
            if k == 0:
                eq = _equilibrium(setup)
            else:
                nxt = Static(q0=eq.q, tol=self.tol, max_iter=self.max_iter)
                eq = _equilibrium(nxt._prepare(model, float(tk)))
            rows.append(eq.result)
            smallest.append(float(eq.eigenvalues[0]) if eq.eigenvalues.size else float("nan"))
            iters += eq.iterations
        first_row = rows[0]
        extra = {c: np.concatenate([r.extra[c] for r in rows]) for c in first_row.extra}
        zeros = np.zeros((len(ts), model.nq))
        stable = [bool(np.isnan(e) or e > 0) for e in smallest]
        return Result(
            kind="statics",
            model=model,
            t=ts,
            q=np.concatenate([r.q for r in rows]),
            qd=zeros,
            qdd=zeros,
            extra=extra,
            kinds=dict(first_row.kinds),
            stats={
                "newton_iterations": iters,
                "min_eigenvalue": smallest,
                "min_eigenvalue_unit": model.units.unit("energy"),
                "stable": all(stable),
                "unstable_at": [float(tk) for tk, s in zip(ts, stable, strict=True) if not s],
            },
        )

    @classmethod
    def _from_keywords(cls, t, kwargs: dict):
        # assemble_first and linear_solver: quasi_static's, without effect
        skip = ("prepared", "assemble_first", "linear_solver")
        return cls(**{k: v for k, v in kwargs.items() if k not in skip}), None


def quasi_static(
    model: Model,
    t,
    *,
    q0=None,
    hold=(),
    tol: float = 1e-10,
    max_iter: int = 100,
    assemble_first: bool = True,
    linear_solver: str | LinearSolver = "auto",
) -> Result:
    """The equilibria at the times ``t`` (N,), each from the one before (the drivers' laws
    and the loads taken at each time): a quasi-static analysis, e.g. a mechanism slowly
    driven against its springs and gravity. A :class:`~mixdyn.Result` of kind ``"statics"``
    (positions, reactions, efforts; velocities and accelerations 0); ``stats`` holds the
    reduced stiffness' smallest eigenvalue at each time and whether every equilibrium is
    stable (the eigenvalue in the model's unit of energy, named by ``min_eigenvalue_unit``:
    see the module docstring). (The start is always assembled, and the dense path taken:
    ``assemble_first`` and ``linear_solver`` are accepted for the model-file runner's sake.)"""
    del assemble_first, linear_solver
    ts = output_times(t, minimum=1)
    analysis = QuasiStatic(q0=q0, hold=hold, tol=tol, max_iter=max_iter)
    return analysis._run(analysis._prepare(model, float(ts[0])), ts)


__all__ = ["QuasiStatic", "Static", "Statics", "quasi_static", "statics"]
