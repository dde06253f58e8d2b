"""``generalized-alpha``: implicit, index 3 (Arnold & Brüls, *Multibody System Dynamics* 18,
2007), Newton on the full system ``M qdd + G mu = Q``, ``Phi(q, t) = 0``, for stiff springs.

Second order; numerical damping set by ``rho_inf`` (1: none, 0: asymptotic annihilation).
After each step the velocities are projected onto ``Phi_q qd + Phi_t = 0`` (optional), which
removes the index-3 velocity drift.

The Newton iteration of a step solves for ``x = (qdd1, mu1)`` the residual
``r1 = M qdd1 + G(q1) mu1 - Q(q1, qd1)``, ``r2 = Phi(q1) / beta'``, where
``q1 = q_pred + beta' qdd1``, ``qd1 = qd_pred + gamma' qdd1`` (``beta' ~ h^2 / 4``). Its exact
Jacobian is ``[[M + beta' (K_c - Q_q) - gamma' Q_qd, G], [C, 0]]`` (``K_c`` the derivative
of ``G mu`` with respect to ``q``, ``C = Phi_q``). Two iterations are available:

* *modified* Newton drops the ``O(beta')`` stiffness and damping terms: the matrix
  ``[[M, G], [C, 0]]`` is the acceleration-level KKT matrix, taken at the step's predicted
  state and factorized once per step through its Schur complement ``C M^-1 G`` (dense LU, or
  the banded block Cholesky of the sparse path; the damped SVD solve at a singular position,
  as for the accelerations); the residual's ``G mu`` comes from one
  reverse pass through ``Phi``, so an iteration needs no Jacobian. It contracts by a factor
  ``~ beta' |K| / M`` per iteration (``~1e-3`` for pendulum chains at ``h = 1e-3``);
* *full* Newton builds the exact matrix by forward differentiation of the residual (dense,
  ``(nq + m)`` directions) and solves it by dense LU: quadratic convergence, for stiff forces
  (``h^2 K / M`` not small) where the modified iteration contracts slowly or diverges.

Each step starts from ``(qdd, mu)`` extrapolated quadratically from the last three steps.
The iteration has converged when the scaled force and position residuals are below 1; near a
singular position, where the iteration matrix is ill-conditioned and the force residual
stalls at the noise floor of its solve (the rounding of the positions amplified like
1/distance), an iterate whose positions meet their tolerance and whose force residual is below
:data:`STALL_TOL` tolerances is accepted once an exact-matrix iteration stops reducing it (only
there: the pivot ratio of the iteration matrix's Schur complement below :data:`STALL_RATIO`).
``newton="auto"`` (the default) starts each step with the modified iteration and switches,
within the step, to full Newton from the better of the last two iterates as soon as an
iteration contracts the error by less than :data:`SWITCH_RATE` (or diverges), or when, at the
rate measured, it would not converge within half of ``max_newton`` iterations.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ...equations import force_directions
from ...errors import ModelError
from .._problem import Problem
from ..methods import GeneralizedAlpha
from ._common import NEWTON_FAILED, NOT_FINITE, OK, Trajectory, report_progress

#: The Newton iterations of ``newton=...`` (see the module docstring).
NEWTON_CHOICES = ("auto", "modified", "full")
#: ``newton="auto"``: an iteration of the modified Newton method that does not reduce the
#: scaled error at least by this factor makes the step switch to full Newton.
SWITCH_RATE = 0.5
#: A Newton iteration that stalls (an iteration of the exact matrix reduces the scaled
#: residual by less than ``STALL_RATE``) with the positions within tolerance and the force
#: residual below ``STALL_TOL`` tolerances is converged to the noise floor of its solve.
STALL_RATE = 0.5
STALL_TOL = 1e4
#: ... and only near a singular position: the pivot ratio of the iteration matrix's Schur
#: complement below this (elsewhere, e.g. a stiff spring at a huge step, a stalled iteration
#: is a failure).
STALL_RATIO = 1e-6


def coefficients(rho_inf):
    """``(alpha_m, alpha_f, gamma, beta)`` of Chung & Hulbert / Arnold & Brüls."""
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    g = 0.5 + af - am
    b = 0.25 * (g + 0.5) ** 2
    return am, af, g, b


#: Placeholder length of the steps before the first one [time]: with it the first step starts
#: from the initial (qdd, mu) and the second extrapolates linearly.
_NO_STEP = 1e100


def _start_history(x):
    """``(x_prev, x_prev2, h_prev, h_prev2)`` before the first step."""
    return x, x, jnp.asarray(_NO_STEP, x.dtype), jnp.asarray(_NO_STEP, x.dtype)


def _extrapolate(x, hist, h):
    """The Newton start at the next step: the quadratic through the last three values of
    ``x = (qdd, mu)`` (``x`` now, ``x_prev`` a step ``h1`` ago, ``x_prev2`` a further ``h2``
    ago) at ``h`` ahead (``3 x - 3 x_prev + x_prev2`` at constant step); Lagrange weights."""
    x1, x2, h1, h2 = hist
    w0 = (h + h1) / h1 * (h + h1 + h2) / (h1 + h2)
    w1 = -h / h1 * (h + h1 + h2) / h2
    w2 = h / (h1 + h2) * (h + h1) / h2
    return w0 * x + w1 * x1 + w2 * x2


def _constraint_terms(problem: Problem):
    """``f(q, qd, t, mu) -> (G mu (nq,), Phi (m,))``, by one reverse-mode pass through
    ``Phi``: ``G mu = Phi_q^T lambda - B u`` needs no Jacobian matrix."""
    c, p, m = problem.c, problem.p, problem.c.m

    def terms(q, qd, t, mu):
        phi, pull = jax.vjp(lambda q: c(q, t), q)
        if p == 0:
            return pull(mu)[0], phi
        mk = m - p
        (f,) = pull(jnp.concatenate([mu[:mk], jnp.zeros(p, mu.dtype)]))
        B = force_directions(problem.model, problem.unknown, q, qd, t)
        return f - B @ mu[mk:], phi

    return terms


def _iteration_matrix(problem: Problem):
    """``factorize(q, qd, t) -> (kkt, ratio)``: the modified Newton matrix ``[[M, G], [C, 0]]``
    at one state, factorized once (:meth:`Problem.kkt`: through its Schur complement
    ``C M^-1 G``, whose pivot ratio is ``ratio``; dense LU, the banded Cholesky factors or
    their Woodbury update, the damped SVD at a singular position); ``kkt(r1, r2)`` returns
    ``(dqdd, dmu)`` solving ``[[M, G], [C, 0]] [dqdd; dmu] = [r1; r2]``."""
    return problem.kkt


@eqx.filter_jit
def generalized_alpha(
    problem: Problem, ts, q0, qd0, options: GeneralizedAlpha, progress=None
) -> Trajectory:
    """Integrate with the index-3 generalized-alpha method at fixed step ``dt``.

    Args:
        problem: the equations of motion.
        ts: (N,) output times [time].
        q0, qd0: (nq,) consistent initial state.
        options: the method's options (:class:`~mixdyn.analysis.methods.GeneralizedAlpha`):
            ``dt``: step [time], each output interval split into equal steps no longer than
            it; ``rho_inf``: spectral radius at infinite frequency, in [0, 1]; ``tol``: Newton
            tolerance on the scaled residual (default ``1e-10 x`` force scale);
            ``max_newton``: Newton iterations per step; ``newton``: ``"auto"`` (modified
            Newton, switching to full Newton within a step where it contracts poorly, e.g. a
            stiff spring at a large step), ``"modified"`` (the acceleration-level KKT matrix
            only: cheap, no Jacobian of the residual, sparse on the sparse path) or ``"full"``
            (the exact Newton matrix, dense); ``project_velocities``: project velocities onto
            the velocity constraints after a step. (``max_steps`` bounds the step count
            before the run: :func:`~mixdyn.analysis.methods.check_steps`.)
        progress: optional callback ``f(t)`` at each output time.
    """
    dt, rho_inf, tol = options.dt, options.rho_inf, options.tol
    max_newton, newton = options.max_newton, options.newton
    if newton not in NEWTON_CHOICES:
        raise ModelError(
            f"newton must be one of {', '.join(NEWTON_CHOICES)}, got {newton!r}", "newton"
        )
    am, af, gm, bt = coefficients(rho_inf)
    Mdiag = problem.model.mass_diagonal
    n = q0.shape[0]
    constraint_terms = _constraint_terms(problem)
    factorize = _iteration_matrix(problem)
    qdd0, mu0, _ = problem.accelerations(q0, qd0, ts[0])
    fscale = jnp.maximum(
        jnp.max(jnp.abs(Mdiag * qdd0)) + jnp.max(jnp.abs(problem.known_forces(q0, qd0, ts[0]))),
        1e-300,
    )
    lscale = jnp.maximum(jnp.max(jnp.abs(q0)), 1.0)
    ftol = 1e-10 * fscale if tol is None else tol
    ptol = 1e-13 * lscale

    def one_step(state, h, t1):
        q, qd, a, qdd, mu, w, newt, hist = state
        beta_p = h**2 * bt * (1 - af) / (1 - am)

        def predict(qdd1):
            a1 = ((1 - af) * qdd1 + af * qdd - am * a) / (1 - am)
            q1 = q + h * qd + h**2 * (0.5 - bt) * a + h**2 * bt * a1
            qd1 = qd + h * (1 - gm) * a + h * gm * a1
            return q1, qd1, a1

        def residual(x):
            qdd1, mu1 = x[:n], x[n:]
            q1, qd1, _ = predict(qdd1)
            Gmu, phi = constraint_terms(q1, qd1, t1, mu1)
            r1 = Mdiag * qdd1 + Gmu - problem.known_forces(q1, qd1, t1)
            return jnp.concatenate([r1, phi / beta_p])

        def parts(r):
            # Force residual against ftol; position residual (r2 * beta_p) against ptol.
            return jnp.max(jnp.abs(r[:n])) / ftol, jnp.max(
                jnp.abs(r[n:]) * beta_p, initial=0.0
            ) / ptol

        def error(r):
            return jnp.maximum(*parts(r))

        x_last = jnp.concatenate([qdd, mu])
        x0 = _extrapolate(x_last, hist, h)
        # The modified Newton matrix, at the predicted state, factorized once per step.
        if newton == "full":
            kkt, kratio = None, jnp.ones(())
        else:
            kkt, kratio = factorize(*predict(x0[:n])[:2], t1)

        def modified_dx(x, r):
            return jnp.concatenate(kkt(r[:n], r[n:]))

        def full_dx(x, r):
            J = jax.jacfwd(residual)(x)
            return problem.c.solve(J, r, extra_rank=n)[0]

        def cond(s):
            _, _, res, it, _, done = s
            return ~done & (it < max_newton) & jnp.isfinite(res)

        def iteration(full: bool):
            """One Newton iteration with the modified (``full=False``) or the exact matrix."""

            def body(s):
                x, r, res, it, switched, _ = s
                dx = full_dx(x, r) if full else modified_dx(x, r)
                x1 = x - dx
                r1 = residual(x1)
                f1, p1 = parts(r1)
                res1 = jnp.maximum(f1, p1)
                # Converged; or stalled at the noise floor of the solve: near a singular
                # position the iteration matrix is ill-conditioned, the rounding of the
                # positions (1 ulp of Phi) is amplified like 1/distance in the update and the
                # force residual stops decreasing. Such an iterate is accepted if the
                # positions meet their tolerance and the force residual is below STALL_TOL x
                # ftol (1e-6 of the force scale by default: an acceleration error far below
                # the method's own), once the exact (or the chosen modified) Newton matrix no
                # longer reduces it, and only where the iteration matrix is near singular
                # (STALL_RATIO). With newton="auto", only the exact matrix's iterations stall.
                stalled = (
                    (kratio < STALL_RATIO)
                    & (p1 <= 1.0)
                    & (f1 <= STALL_TOL)
                    & ~(res1 <= STALL_RATE * res)
                    & jnp.isfinite(res1)
                )
                if newton == "auto" and not full:
                    stalled = jnp.zeros_like(stalled)
                done = (res1 <= 1.0) | stalled
                if newton == "auto" and not full:
                    # A modified iteration that contracts poorly, or would at its rate need
                    # more than half the budget, hands the step to full Newton, from the
                    # better of the last two iterates.
                    rate = res1 / res
                    need = jnp.log(res1) / -jnp.log(rate)  # iterations still needed
                    slow = ~(rate <= SWITCH_RATE) | ~(it + 1 + need <= max_newton // 2)
                    slow = slow & ~(res1 <= 1.0)
                    back = slow & ~(res1 < res)
                    x1, r1, res1 = jax.tree.map(
                        lambda old, new: jnp.where(back, old, new), (x, r, res), (x1, r1, res1)
                    )
                    switched = slow
                return x1, r1, res1, it + 1, switched, done

            return body

        r0 = residual(x0)
        res0 = error(r0)
        init = (x0, r0, res0, 0, jnp.asarray(newton == "full"), res0 <= 1.0)
        # The modified iterations, then (newton="auto": once they contract poorly) the exact
        # ones, each in a loop of its own: a loop whose program holds the exact matrix's
        # (nq + m)^2 buffers runs its small kernels through XLA's concurrent executor, at
        # several times their cost, and the modified iterations of every step would pay it.
        state = init
        if newton != "full":
            state = jax.lax.while_loop(lambda s: cond(s) & ~s[4], iteration(False), state)
        if newton != "modified":
            state = jax.lax.while_loop(cond, iteration(True), state)
        x, r, res, it, _, done = state
        q1, qd1, a1 = predict(x[:n])
        qdd1, mu1 = x[:n], x[n:]
        if options.project_velocities:
            qd1 = problem.project_velocities(q1, qd1, t1)
        rates0 = problem.work_rates(q, qd, t1 - h, qdd)
        rates1 = problem.work_rates(q1, qd1, t1, qdd1)
        w1 = w + 0.5 * h * (rates0 + rates1)
        ok = done
        # Phi(q1), from the last residual: the position violation before any projection.
        viol = jnp.max(jnp.abs(r[n:]) * beta_p, initial=0.0)
        new = (q1, qd1, a1, qdd1, mu1, w1, newt + it, (x_last, hist[0], h, hist[2]))
        return new, ok, jnp.isfinite(res), viol

    N = ts.shape[0]
    zeros = jnp.zeros((N, n))
    init = (
        jnp.asarray(1),
        (
            q0,
            qd0,
            qdd0,
            qdd0,
            mu0,
            jnp.zeros(2),
            jnp.asarray(0),
            _start_history(jnp.concatenate([qdd0, mu0])),
        ),
        zeros.at[0].set(q0),
        zeros.at[0].set(qd0),
        jnp.zeros((N, 2)),
        jnp.asarray(0),
        jnp.asarray(OK),
        ts[0],
        jnp.asarray(0.0),
    )

    def outer_cond(s):
        k, _, _, _, _, _, status, _, _ = s
        return (k < N) & (status == OK)

    def outer_body(s):
        k, state, Q, QD, W, nsteps, status, t, viol = s
        span = ts[k] - ts[k - 1]
        nsub = jnp.maximum(jnp.ceil(span / dt * (1 - 1e-12)).astype(int), 1)
        h = span / nsub

        def inner_cond(c):
            i, _, st, _, _ = c
            return (i < nsub) & (st == OK)

        def inner_body(c):
            i, state, st, t, viol = c
            t1 = ts[k - 1] + (i + 1) * h
            new, ok, finite, v = one_step(state, h, t1)
            st = jnp.where(ok, st, jnp.where(finite, NEWTON_FAILED, NOT_FINITE))
            return i + 1, new, st, jnp.where(ok, t1, t), jnp.maximum(viol, v)

        i, state, status, t, viol = jax.lax.while_loop(
            inner_cond, inner_body, (0, state, status, t, viol)
        )
        report_progress(progress, t)
        Q, QD, W = Q.at[k].set(state[0]), QD.at[k].set(state[1]), W.at[k].set(state[5])
        return k + 1, state, Q, QD, W, nsteps + i, status, t, viol

    _, state, Q, QD, W, nsteps, status, t, viol = jax.lax.while_loop(outer_cond, outer_body, init)
    return Trajectory(Q, QD, W, nsteps, jnp.asarray(0), state[6], viol, status, t, state[0])
