"""The constrained equations of motion of one analysis, as pure functions of ``(q, qd, t)``.

Forward, inverse and mixed dynamics differ only in which constraint rows exist and which
multipliers are forces of unknown magnitude:

    M qdd + G mu = Q(q, qd, t)          G = [Phi_q^T | -B]
    C qdd       = gamma                 C = [Phi_q ; Psi_q]

with ``Phi`` the joints and drivers (their multipliers ``lambda``), ``Psi`` the prescribed
motions of a mixed problem and ``B`` the directions of the unknown forces ``u`` (the last
``p`` entries of ``mu``). In forward dynamics ``p = 0`` and ``G = C^T``. Two solvers of the
acceleration problem exist: ``"augmented"`` (Schur complement, any ``B``) and
``"partition"`` (the paper's equations (28)–(29), unknown forces along coordinates).
"""

from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np

from ..equations import Constraints, applied_forces, force_directions, potential_energy
from ..equations import _reaction_dependent as rd
from ..equations._jacobian import JacobianOperator
from ..linalg import lu_solve_checked, min_pivot
from ..model import Model


def pivot_columns(A, k: int):
    """Indices (k,) of ``k`` well-conditioned columns of ``A`` (m, n), by partial-pivoting LU
    of ``A^T``; and the other columns (n - k,). Jittable."""
    n = A.shape[1]
    if k == 0:
        return jnp.zeros(0, dtype=int), jnp.arange(n)
    P, _, _ = jsl.lu(A.T)
    perm = jnp.argmax(P, axis=0)  # row of A^T (column of A) chosen at each pivot position
    dep = perm[:k]
    mask = jnp.ones(n, dtype=bool).at[dep].set(False)
    rest = jnp.argsort(~mask, stable=True)[: n - k]
    return dep, rest


class Stages(NamedTuple):
    """One state's stages (:meth:`Problem.stages`), in the manner of MJX's ``Data``.

    Attributes:
        q, qd: (nq,) positions and velocities; t: time.
        phi: (m,) constraint residuals ``Phi(q, t)``.
        J: the operator ``Phi_q(q, t)`` of the set's path.
        qdd: (nq,) accelerations; mu: (m,) multipliers; ratio: the pivot ratio of the solve.
        dependent: the reaction-dependent forces ``f`` (nf,) and relative speeds ``v`` (nf,)
            of the same solve, or None without them.
    """

    q: jax.Array
    qd: jax.Array
    t: jax.Array
    phi: jax.Array
    J: JacobianOperator
    qdd: jax.Array
    mu: jax.Array
    ratio: jax.Array
    dependent: tuple | None = None


class Problem(eqx.Module):
    """Equations of motion of one dynamic analysis.

    Attributes:
        model: the mechanism.
        c: constraint rows ``[Phi; Psi]`` (joints, drivers, then prescribed motions).
        unknown: names of the force elements of unknown magnitude (``p`` of them).
        solver: ``"augmented"`` or ``"partition"``.
        j_index: (p,) coordinates along which the unknown forces act (partition solver).
        i_index: user-chosen independent coordinates, or ``()`` for automatic choice.
        collocated: for each unknown force, the prescribed motion (0..p-1) along whose
            gradient it acts (``B[:, a] = s_a Psi_q[b]^T``), or ``()``: with it the augmented
            system is symmetric, ``G = C^T diag(1, -1/s)``, and can take the sparse path.
    """

    model: Model
    c: Constraints
    unknown: tuple[str, ...] = eqx.field(static=True)
    solver: str = eqx.field(static=True)
    j_index: tuple[int, ...] = eqx.field(static=True)
    i_index: tuple[int, ...] = eqx.field(static=True)
    collocated: tuple[int, ...] = eqx.field(static=True)

    def __init__(
        self, model, c, unknown=(), solver="augmented", j_index=(), i_index=(), collocated=()
    ):
        self.model = model
        self.c = c
        self.unknown = tuple(unknown)
        self.solver = solver
        self.j_index = tuple(int(i) for i in j_index)
        self.i_index = tuple(int(i) for i in i_index)
        self.collocated = tuple(int(i) for i in collocated)
        if solver == "partition":
            rd.check_supported(model, "the partition method", "use solver='augmented'")

    @property
    def p(self) -> int:
        return len(self.unknown)

    @property
    def Minv(self):
        return 1.0 / self.model.mass_diagonal

    # ------------------------------------------------------------------ forces
    def known_forces(self, q, qd, t):
        """Known generalized forces ``Q`` (nq,)."""
        return applied_forces(self.model, q, qd, t, exclude=self.unknown)

    # ------------------------------------------------------------------ accelerations
    def kkt(self, q, qd, t, J=None):
        """The matrix ``[[M, G], [C, 0]]`` at one state, factorized once (through its Schur
        complement ``C M^-1 G``) by the constraint set's operator
        (:meth:`~mixdyn.equations._jacobian.JacobianOperator.kkt`: dense LU, banded
        Cholesky, or its Woodbury update for unknown forces of any direction); ``J`` the
        operator at ``(q, t)`` if already built.

        Returns:
            ``(solve, ratio)``: ``solve(r1 (nq,), r2 (m,)) -> (x (nq,), mu (m,))`` with
            ``M x + G mu = r1``, ``C x = r2``; the pivot ratio of the Schur complement.
        """
        J = self.c.jacobian(q, t) if J is None else J
        B = force_directions(self.model, self.unknown, q, qd, t) if self.p else None
        return J.kkt(self.Minv, B, self.collocated)

    def accelerations(self, q, qd, t, alpha=None, beta=None, J=None):
        """``(qdd (nq,), mu (m,), pivot_ratio)`` at one state (``J``: the operator at
        ``(q, t)`` if already built).

        With ``alpha``, ``beta`` [1/time] the acceleration constraints are Baumgarte-stabilized:
        ``C qdd = gamma - 2 alpha (Phi_q qd + Phi_t) - beta**2 Phi``.
        """
        c = self.c
        J = c.jacobian(q, t) if J is None else J
        gam = c.gamma(q, qd, t)
        if alpha is not None:
            gam = gam - 2 * alpha * (J.mv(qd) + c.phi_t(q, t)) - beta**2 * c(q, t)
        Q = self.known_forces(q, qd, t)
        if self.solver == "partition":
            return self._partition(q, qd, t, J.dense(), gam, Q)
        solve, ratio = self.kkt(q, qd, t, J)
        qdd, mu = solve(Q, gam)
        if self.reaction_dependent:
            qdd, mu, _ = self._with_dependent(q, qd, t, solve, qdd, mu)
        return qdd, mu, ratio

    def _accelerations_and_dependent(self, q, qd, t, J):
        """As :meth:`accelerations` at ``(q, t)`` with the operator ``J``, and the
        reaction-dependent forces' record ``(f, v)`` of the same solve (None without them)."""
        if not self.reaction_dependent:
            return (*self.accelerations(q, qd, t, J=J), None)
        solve, ratio = self.kkt(q, qd, t, J)
        qdd, mu = solve(self.known_forces(q, qd, t), self.c.gamma(q, qd, t))
        qdd, mu, record = self._with_dependent(q, qd, t, solve, qdd, mu)
        return qdd, mu, ratio, record

    # ------------------------------------------------------------------ reaction-dependent forces
    @property
    def reaction_dependent(self) -> tuple:
        """The model's reaction-dependent force elements (static)."""
        return rd.elements(self.model)

    def _dependent_solve(self, q, qd, t, solve, qdd0, mu0, stopped=None):
        """The reaction-dependent forces at one state from the KKT solve factorized once
        (:mod:`mixdyn.equations._reaction_dependent`): ``(f, stick, A, Mu_f, H, v, D)``, the
        forces of the elements' ``nf`` rows (nf,), which rows stick (nf,), the constrained
        responses to a unit force along each row ``A`` (nq, nf) and ``Mu_f`` (m, nf),
        ``H = D^T A`` (nf, nf), the relative speeds ``v`` (nf,) and the directions ``D``
        (nq, nf). ``stopped`` (nf,), bool: rows taken as inside the stick band whatever their
        speed (default none)."""
        elements = self.reaction_dependent
        pos = rd.rows(self.model, self.c, elements)
        # D (nq, nf) and its rate along the motion, in one pass: dd = qd^T (dD/dq) qd
        D, D_rate = jax.jvp(lambda qq: rd.directions(self.model, elements, qq), (q,), (qd,))
        v = D.T @ qd
        dd = D_rate.T @ qd
        zeros = jnp.zeros(mu0.shape[0], qdd0.dtype)
        cols = [solve(D[:, k], zeros) for k in range(D.shape[1])]
        A = jnp.stack([x for x, _ in cols], axis=1)
        Mu_f = jnp.stack([m for _, m in cols], axis=1)
        H = D.T @ A
        a0 = D.T @ qdd0 + dd
        h_free = jnp.sum(D**2 * self.Minv[:, None], axis=0)
        v_band = v if stopped is None else jnp.where(stopped, 0.0, v)
        state_loads = rd.loads(self.model, elements, q, qd, t)
        f, stick = rd.solve(elements, pos, v_band, a0, H, mu0, Mu_f, h_free, state_loads)
        return f, stick, A, Mu_f, H, v, D

    def _with_dependent(self, q, qd, t, solve, qdd0, mu0):
        """Accelerations and multipliers with the reaction-dependent forces, from the KKT
        solve factorized once (:meth:`_dependent_solve`); and their record ``(f, v)``."""
        f, _, A, Mu_f, _, v, _ = self._dependent_solve(q, qd, t, solve, qdd0, mu0)
        return qdd0 + A @ f, mu0 + Mu_f @ f, (f, v)

    def halt_sticking(self, q, qd, w, t, q_start, qd_start, stopped=None):
        """The velocities ``qd`` (nq,) and works ``w`` (2,) at the end of a step with every
        sticking reaction-dependent element brought to rest.

        An element sticks at ``(q, qd, t)`` where it has stopped, inside its stick band or
        with its relative speed reversed since the step's start ``(q_start, qd_start)`` (it
        stopped within the step), and it holds within its limit
        (:func:`~mixdyn.equations._reaction_dependent.solve`). The sticking elements get the
        impulse ``A y`` along their directions that makes their relative speeds exactly 0
        (``H_ss y_s = -v_s``, least-norm where their rows depend on each other:
        :func:`~mixdyn.equations._reaction_dependent.held`), the constraints' velocities
        kept (``C A = 0``). The stick force then holds their relative accelerations at 0,
        so that a stopped element stays where it stopped instead of creeping on at the speed
        it was left with (up to its stick band, a step's worth of deceleration past a
        reversal). The kinetic energy the impulse takes out, the elements' work in the stop,
        is added to the nonconservative work ``w[0]``. ``stopped`` (nf,), bool: rows taken
        as stopped besides (default none). ``(qd, w)`` themselves without
        reaction-dependent elements."""
        if not self.reaction_dependent:
            return qd, w
        elements = self.reaction_dependent
        v_start = rd.directions(self.model, elements, q_start).T @ qd_start
        v_end = rd.directions(self.model, elements, q).T @ qd
        J = self.c.jacobian(q, t)
        solve, _ = self.kkt(q, qd, t, J)
        qdd0, mu0 = solve(self.known_forces(q, qd, t), self.c.gamma(q, qd, t))
        reversed_ = v_start * v_end < 0.0
        if stopped is not None:
            reversed_ = reversed_ | stopped
        _, stick, A, _, H, v, _ = self._dependent_solve(q, qd, t, solve, qdd0, mu0, reversed_)
        y = rd.held(H, stick, jnp.where(stick, -v, 0.0), rd.may_depend(elements))
        halted = qd + A @ jnp.where(stick, y, 0.0)
        mass = self.model.mass_diagonal
        work = 0.5 * (jnp.dot(mass * halted, halted) - jnp.dot(mass * qd, qd))
        return halted, w.at[0].add(work)

    def dependent_columns(self, st: Stages) -> dict:
        """The reaction-dependent elements' result columns at the state of ``st``
        (:func:`~mixdyn.equations._reaction_dependent.columns`: ``name``, the element's own,
        ``name.speed``, ``name.power``)."""
        if st.dependent is None:
            return {}
        f, v = st.dependent
        elements = self.reaction_dependent
        pos = rd.rows(self.model, self.c, elements)
        state_loads = rd.loads(self.model, elements, st.q, st.qd, st.t)
        return rd.columns(elements, pos, f, v, st.mu, state_loads)

    def stages(self, q, qd, t) -> Stages:
        """The state record of ``(q, qd, t)`` filled stage by stage (positions: ``Phi`` and
        the operator ``Phi_q``; accelerations and multipliers from them), each equation
        evaluated once for everything that reads it (reactions, powers, checks)."""
        J = self.c.jacobian(q, t)
        phi = self.c(q, t)
        qdd, mu, ratio, dependent = self._accelerations_and_dependent(q, qd, t, J)
        return Stages(q, qd, t, phi, J, qdd, mu, ratio, dependent)

    def _partition(self, q, qd, t, C, gam, Q):
        """The paper's method, eqs. (28)–(29), with ``j`` the prescribed coordinates."""
        n, p = self.model.nq, self.p
        mk = C.shape[0] - p  # constraint rows other than the prescribed motions
        Phi_q = C[:mk]
        j = jnp.asarray(self.j_index, dtype=int)
        Mdiag = self.model.mass_diagonal
        free = np.setdiff1d(np.arange(n), np.asarray(self.j_index, dtype=int))
        k_auto, rest = pivot_columns(Phi_q[:, free], mk)
        k_auto = jnp.asarray(free)[k_auto]
        i_auto = jnp.asarray(free)[rest]
        if self.i_index:
            i_user = jnp.asarray(self.i_index, dtype=int)
            mask = np.ones(n, dtype=bool)
            mask[list(self.i_index) + list(self.j_index)] = False
            k_user = jnp.asarray(np.where(mask)[0])
            # Fall back to the pivoted choice where the user's Phi_qk is ill-conditioned
            # (its smallest pivot far below the best choice's).
            use_user = min_pivot(Phi_q[:, k_user]) > 1e-3 * min_pivot(Phi_q[:, k_auto])
            k = jnp.where(use_user, k_user, k_auto)
            i = jnp.where(use_user, i_user, i_auto)
        else:
            k, i = k_auto, i_auto
        Pk, Pi = Phi_q[:, k], Phi_q[:, i]
        Mrows = jnp.diag(Mdiag)
        # X = (Phi_qk^T)^-1 [M_k. | Q_k]
        X, ratio = lu_solve_checked(Pk.T, jnp.concatenate([Mrows[k], Q[k][:, None]], axis=1))
        A_i = Mrows[i] - Pi.T @ X[:, :n]  # (29), left side
        b_i = Q[i] - Pi.T @ X[:, n]  # (29), right side (the source's sign repaired)
        A = jnp.concatenate([A_i, Phi_q, C[mk:]], axis=0)
        b = jnp.concatenate([b_i, gam[:mk], gam[mk:]])
        qdd, r2 = lu_solve_checked(A, b)
        lam = jnp.linalg.solve(Pk.T, Q[k] - Mdiag[k] * qdd[k])  # (28)
        B = force_directions(self.model, self.unknown, q, qd, t)
        # j rows: M_j qdd_j + Phi_qj^T lam = Q_j + B_j u
        Bj = B[j, :]
        u = jnp.linalg.solve(Bj, Mdiag[j] * qdd[j] + Phi_q[:, j].T @ lam - Q[j])
        return qdd, jnp.concatenate([lam, u]), jnp.minimum(ratio, r2)

    # ------------------------------------------------------------------ work
    def powers(self, q, qd, t, mu, J=None):
        """Power of each multiplier's force (m,): ``-(G[:, r] mu_r) . qd``, with
        ``G^T qd = [Phi_q qd; -B^T qd]`` (``J``: the operator at ``(q, t)`` if built)."""
        c = self.c
        J = c.jacobian(q, t) if J is None else J
        Gqd = J.mv(qd)[: c.m - self.p]
        if self.p:
            B = force_directions(self.model, self.unknown, q, qd, t)
            Gqd = jnp.concatenate([Gqd, -(B.T @ qd)])
        return -Gqd * mu

    def work_rates(self, q, qd, t, qdd, mu=None):
        """``[P_nonconservative_applied, P_constraints_and_unknowns]`` (2,) [power].

        By the equations of motion the constraint forces (joints, drivers, unknown forces) on
        the bodies are ``-G mu = M qdd - Q``, so their power needs no Jacobian:
        ``(M qdd - Q) . qd``. With reaction-dependent forces, part of ``Q`` but solved with
        the accelerations, the multipliers ``mu`` of the same state (if given)
        give the constraints' power ``-(G mu) . qd`` directly and the applied forces' the
        rest, ``(M qdd + dV/dq) . qd`` less it: no second solve for those forces.
        """
        dV = jax.grad(lambda qq: potential_energy(self.model, qq))(q)
        if self.reaction_dependent and mu is not None:
            p_c = jnp.sum(self.powers(q, qd, t, mu))
            p_nc = jnp.dot(self.model.mass_diagonal * qdd + dV, qd) - p_c
            return jnp.stack([p_nc, p_c])
        if self.reaction_dependent:  # the multipliers of this state, then as above
            return self.work_rates(q, qd, t, qdd, self.accelerations(q, qd, t)[1])
        Q = self.known_forces(q, qd, t)
        p_nc = jnp.dot(Q + dV, qd)
        p_c = jnp.dot(self.model.mass_diagonal * qdd - Q, qd)
        return jnp.stack([p_nc, p_c])

    # ------------------------------------------------------------------ projections
    def project_positions(self, q, t, tol, iters: int = 4):
        """Mass-weighted least-norm projection of ``q`` onto ``Phi(q, t) = 0``: at most
        ``iters`` Newton steps, none once ``max |Phi| <= tol`` [length] (usually one after an
        integration step, so the loop stops early rather than solving ``iters`` times).

        Differentiated implicitly, as the exact projection (:func:`_projection_jvp`): the
        tangent is projected onto the constraints' tangent space whether or not a Newton
        step was taken (the derivative of a skipped step would be the identity, and its
        drift off the tangent space is amplified near singular positions).

        Returns:
            ``(q (nq,), residual)``: the projected positions and ``max |Phi|`` there.
        """
        return _projection(self, q, t, tol, iters=iters)

    def project_velocities(self, q, qd, t):
        """Mass-weighted least-norm projection of ``qd`` onto ``Phi_q qd + Phi_t = 0``.

        Both projections solve with ``S = Phi_q M^-1 Phi_q^T`` through the path's operator
        (:meth:`~mixdyn.equations.Constraints.jacobian`); near a singular position the damped
        SVD solve, as for the accelerations, so that the residual's part along the direction
        losing rank (rounding, drift) is not amplified like ``1/s`` into a jump of the
        positions or velocities."""
        J = self.c.jacobian(q, t)
        r = J.mv(qd) + self.c.phi_t(q, t)
        return qd - J.min_norm(self.Minv, guard=True).solve(r)


def _newton_projection(p: Problem, q, t, tol, *, iters: int):
    """The Newton iteration of :meth:`Problem.project_positions`."""
    c, Minv = p.c, p.Minv

    def newton(q, r):
        q = q - c.jacobian(q, t).min_norm(Minv, guard=True).solve(r)
        return q, c(q, t)

    def far(r):
        return jnp.max(jnp.abs(r), initial=0.0) > tol

    if c.batched:
        # A sweep's one program (not differentiated): under ``vmap`` a ``lax.cond`` runs
        # its branch for every member, so the loop of static length would make all
        # ``iters`` Newton steps; this loop stops once every member is closed (usually
        # after one step).
        def go_on(state):
            k, _, r = state
            return (k < iters) & far(r)

        def step(state):
            k, q, r = state
            return (k + 1, *newton(q, r))

        _, q, r = jax.lax.while_loop(go_on, step, (0, q, c(q, t)))
        return q, jnp.max(jnp.abs(r), initial=0.0)

    def body(_, state):
        q, r = state
        # a branch taken only while far (one Newton step after most integration steps)
        return jax.lax.cond(far(r), newton, lambda q, r: (q, r), q, r)

    q, r = jax.lax.fori_loop(0, iters, body, (q, c(q, t)))
    return q, jnp.max(jnp.abs(r), initial=0.0)


_projection = eqx.filter_custom_jvp(_newton_projection)


@_projection.def_jvp
def _projection_jvp(primals, tangents, *, iters):
    """The derivative of the exact projection ``q* = P(q)`` at a point on the constraints:
    from ``Phi(q*, t) = 0`` and ``q* - q = M^-1 Phi_q^T lambda`` (``lambda`` -> 0 there),

        dq* = dq - M^-1 Phi_q^T S^-1 (Phi_q dq + Phi_t dt + Phi_p dp),

    ``S = Phi_q M^-1 Phi_q^T``, ``Phi_p dp`` the constraints' change with the problem's own
    numbers; one solve with the factor the Newton step uses, instead of the derivative of
    the iteration (which drops the projector where the step is skipped)."""
    p, q, t, tol = primals
    dp, dq, dt, _ = tangents
    qs, r = _projection(p, q, t, tol, iters=iters)
    dyn, static = eqx.partition(p, eqx.is_inexact_array)
    d_dyn = _tangent_or_zeros(None if dp is None else eqx.filter(dp, eqx.is_inexact_array), dyn)
    dq = jnp.zeros_like(qs) if dq is None else dq
    dt = jnp.zeros_like(t) if dt is None else dt

    def residual(dyn, q, t):
        return eqx.combine(dyn, static).c(q, t)

    _, dphi = jax.jvp(residual, (dyn, qs, t), (d_dyn, dq, dt))
    J = p.c.jacobian(qs, t)
    dqs = dq - J.min_norm(p.Minv, guard=True).solve(dphi)
    return (qs, r), (dqs, jnp.zeros_like(r))


def _tangent_or_zeros(tangent, primal):
    """``tangent`` with zeros for its symbolic zeros (None) where ``primal`` has arrays."""
    if tangent is None:
        return jax.tree.map(jnp.zeros_like, primal)
    return jax.tree.map(
        lambda d, x: x if x is None else (jnp.zeros_like(x) if d is None else d),
        tangent,
        primal,
        is_leaf=lambda v: v is None,
    )
