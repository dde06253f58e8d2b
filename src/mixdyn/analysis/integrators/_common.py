"""What every integrator returns, and the adaptive step loop shared by the explicit ones."""

from __future__ import annotations

import contextlib
import itertools
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

OK, MAX_STEPS, STEP_COLLAPSE, NEWTON_FAILED, NOT_FINITE, UNCLOSED = 0, 1, 2, 3, 4, 5

#: What each status code means, and what to do about it.
STATUS_MESSAGES = {
    OK: "ok",
    MAX_STEPS: "the step limit was reached; raise max_steps or loosen the tolerances",
    STEP_COLLAPSE: "the step size collapsed: the motion may be singular (a dead point or "
    "lock-up) or the tolerances too tight for float64",
    NEWTON_FAILED: "the Newton iteration of the implicit step did not converge; use a smaller "
    "step or check for a singular configuration",
    NOT_FINITE: "the solution became non-finite (NaN/inf): a singular configuration or a "
    "diverging force",
    UNCLOSED: "the constraints cannot be closed beyond this time, however short the step: "
    "the motion reached a dead point or a lock-up (a driver pushing past a limit position)",
}


class Trajectory(eqx.Module):
    """States at the output times and the integrator's counters.

    Attributes:
        q, qd: (N, nq) coordinates and velocities at the output times.
        w: (N, 2) accumulated work [energy]: non-conservative applied forces; constraint forces
            (drivers, unknown forces).
        steps, rejected, newton: counters (accepted steps, rejected steps, Newton iterations).
        max_violation: largest position-constraint residual met before projection [length].
        status: 0 on success, else a key of :data:`STATUS_MESSAGES`.
        t_fail: time of the failure (or the end time).
        q_last: (nq,) coordinates at ``t_fail``, the last accepted state (for diagnosis).
    """

    q: jax.Array
    qd: jax.Array
    w: jax.Array
    steps: jax.Array
    rejected: jax.Array
    newton: jax.Array
    max_violation: jax.Array
    status: jax.Array
    t_fail: jax.Array
    q_last: jax.Array


# --------------------------------------------------------------------------- progress
#: Progress callbacks by key: the compiled loop calls one fixed host function,
#: :func:`_dispatch`, with the key as an array, so a new callback is a new number, not a new
#: program (a callable argument of a jitted function is static: each new one would be traced
#: and compiled again).
_PROGRESS: dict[int, Callable] = {}
_PROGRESS_KEYS = itertools.count()


class Progress(eqx.Module):
    """A progress callback as data: ``key`` (an int64 array, a leaf of the program's
    arguments) names a function ``f(t)`` registered by :func:`progress_hook`.

    Inside the compiled loop, :func:`report_progress` calls it at each output time.
    """

    key: jax.Array


def _dispatch(key, t) -> None:
    fn = _PROGRESS.get(int(key))
    if fn is not None:
        fn(t)


@contextlib.contextmanager
def progress_hook(fn: Callable | None):
    """Register ``fn(t)`` for the duration of a run; yields the :class:`Progress` to pass
    to the integrator (None for None)."""
    if fn is None or isinstance(fn, Progress):
        yield fn
        return
    key = next(_PROGRESS_KEYS)
    _PROGRESS[key] = fn
    try:
        yield Progress(np.asarray(key, dtype=np.int64))
    finally:
        _PROGRESS.pop(key, None)


def report_progress(progress, t, when=None) -> None:
    """Inside a traced loop: call the progress callback with ``t`` (where ``when`` is true).

    ``progress`` is None (nothing), a :class:`Progress` (one program for every callback) or a
    plain function (a static argument: one program per function)."""
    if progress is None:
        return
    if isinstance(progress, Progress):
        emit = lambda: jax.debug.callback(_dispatch, progress.key, t)  # noqa: E731
    else:
        emit = lambda: jax.debug.callback(progress, t)  # noqa: E731
    if when is None:
        emit()
    else:
        jax.lax.cond(when, emit, lambda: None)


def rms_error(y0, y1, yerr, rtol, atol):
    """Hairer's scaled RMS norm of an error estimate over a pytree of arrays."""
    num, cnt = 0.0, 0
    for a, b, e in zip(
        jax.tree.leaves(y0), jax.tree.leaves(y1), jax.tree.leaves(yerr), strict=True
    ):
        scale = atol + rtol * jnp.maximum(jnp.abs(a), jnp.abs(b))
        num = num + jnp.sum((e / scale) ** 2)
        cnt += e.size
    return jnp.sqrt(num / max(cnt, 1))


#: The explicit Runge–Kutta methods of the adaptive integrators: diffrax's class name and
#: the order. diffrax is imported when a program is traced (:func:`runge_kutta`), not by a
#: run whose programs come from the persistent cache (0.3-0.5 s of importing).
SOLVERS = {
    "tsit5": ("Tsit5", 5),
    "dopri5": ("Dopri5", 5),
    "dopri8": ("Dopri8", 8),
}


def runge_kutta(solver: str):
    """``(method, order)``: a diffrax solver instance for ``solver`` (a key of
    :data:`SOLVERS`) and its order."""
    import diffrax

    name, order = SOLVERS[solver]
    return getattr(diffrax, name)(), order


def ode_term(f):
    """``diffrax.ODETerm(f)`` (diffrax imported on first use)."""
    import diffrax

    return diffrax.ODETerm(f)


def adaptive_loop(
    step: Callable,
    accept: Callable,
    ts,
    y0,
    args0,
    *,
    rtol,
    atol,
    order: int,
    dt,
    h0,
    max_steps,
    progress=None,
):
    """Adaptive (or fixed-step, with ``dt``) explicit integration landing on every output time.

    Args:
        step: ``(t0, t1, y, args) -> (y1, y_err, y_controlled, y1_controlled)``: one step and
            the parts of ``y``/``y1`` under error control.
        accept: ``(t1, y1, args) -> (y1, args, violation[, closed])``: called on each step
            whose error is within tolerance (projection, re-partitioning); ``closed`` False
            (the constraints could not be closed) rejects the step after all.
        ts: (N,) output times; ``ts[0]`` is the start.
        y0, args0: initial state (pytree) and loop-carried data.
        order: order of the method (the error estimate is of order ``order - 1``).
        dt: fixed step (None for adaptive control).
        h0: initial step guess.
        max_steps: step limit.
        progress: optional :class:`Progress` (or ``f(t)``) called at each output time
            (:func:`report_progress`).

    Returns:
        ``(outputs (pytree stacked over N), args, steps, rejected, max_violation, status, t,
        y)``, with ``t`` and ``y`` the last accepted time and state.
    """
    N = ts.shape[0]
    fixed = dt is not None
    outs0 = jax.tree.map(lambda a: jnp.zeros((N, *a.shape), a.dtype).at[0].set(a), y0)
    init = (
        ts[0],
        y0,
        args0,
        jnp.asarray(dt if fixed else h0, dtype=ts.dtype),
        jnp.asarray(1),
        outs0,
        jnp.asarray(0),
        jnp.asarray(0),
        jnp.asarray(0.0),
        jnp.asarray(OK),
    )

    def cond(s):
        _, _, _, _, k, _, _, _, _, status = s
        return (k < N) & (status == OK)

    def body(s):
        t, y, args, h, k, outs, n, nrej, viol, status = s
        target = ts[jnp.minimum(k, N - 1)]
        hit = (target - t) <= h * (1 + 1e-8)
        t1 = jnp.where(hit, target, t + h)
        y1, yerr, yc0, yc1 = step(t, t1, y, args)
        finite = jnp.all(jnp.array([jnp.all(jnp.isfinite(a)) for a in jax.tree.leaves(y1)]))
        if fixed:
            err = jnp.where(finite, 0.0, jnp.inf)
        else:
            err = jnp.where(finite, rms_error(yc0, yc1, yerr, rtol, atol), jnp.inf)
        accepted = accept(t1, y1, args)
        y1p, args1, v = accepted[:3]
        # an accept may also say whether it closed the constraints (else: a rejected step)
        closed = accepted[3] if len(accepted) > 3 else jnp.asarray(True)
        ok = (err <= 1.0) & closed
        y = jax.tree.map(lambda a, b: jnp.where(ok, a, b), y1p, y)
        args = jax.tree.map(lambda a, b: jnp.where(ok, a, b), args1, args)
        store = ok & hit
        kk = jnp.minimum(k, N - 1)
        outs = jax.tree.map(lambda o, a: o.at[kk].set(jnp.where(store, a, o[kk])), outs, y)
        report_progress(progress, t1, store)
        t_new = jnp.where(ok, t1, t)
        k = k + store.astype(int)
        viol = jnp.where(ok, jnp.maximum(viol, v), viol)
        if fixed:
            h_new = jnp.asarray(dt, dtype=ts.dtype)
        else:
            factor = jnp.clip(0.9 * jnp.where(err > 0, err, 1e-10) ** (-1.0 / order), 0.2, 10.0)
            h_used = t1 - t
            shrink = jnp.where(closed, jnp.minimum(factor, 0.9), 0.25)
            h_new = h_used * jnp.where(ok, factor, shrink)
            # A step shortened to land on an output does not shrink the next one.
            h_new = jnp.where(ok & hit & (h_used < h), jnp.maximum(h_new, h), h_new)
        status = jnp.where(n + 1 >= max_steps, MAX_STEPS, status)
        if fixed:
            status = jnp.where(finite, status, NOT_FINITE)
        else:
            too_small = h_new < 1e-13 * jnp.maximum(jnp.abs(t_new), 1.0)
            cause = jnp.where(finite, jnp.where(closed, STEP_COLLAPSE, UNCLOSED), NOT_FINITE)
            status = jnp.where(too_small, cause, status)
        nrej = nrej + (~ok).astype(int)
        return (t_new, y, args, h_new, k, outs, n + 1, nrej, viol, status)

    t, y, args, _, _, outs, n, nrej, viol, status = jax.lax.while_loop(cond, body, init)
    return outs, args, n - nrej, nrej, viol, status, t, y
