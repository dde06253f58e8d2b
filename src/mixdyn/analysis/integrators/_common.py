"""What every integrator returns, its status codes, and the progress callback of a compiled
loop."""

from __future__ import annotations

import contextlib
import itertools
from collections.abc import Callable

import equinox as eqx
import jax
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
