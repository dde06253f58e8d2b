"""How a sweep's cases are integrated: member by member, each by the single run's program,
from a thread per core (XLA runs without the GIL), or stacked into one program that
integrates a whole batch (``jax.lax.map`` over chunks vectorized by ``vmap``), then each
member finished like a single run (a failure kept as that member's outcome).
"""

from __future__ import annotations

import contextlib
import functools
import gc
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..errors import MixdynError, ModelError
from ..runtime._programs import cached_jit
from ._simulate import Case, _post_arrays, finish
from .integrators import INTEGRATORS
from .result import Result


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic garbage collector held off within (and set back as it was after): for
    a set-up's loops over every member (flattening each member's model, reading its
    numbers), which allocate no reference cycles but so many objects that the collector
    runs again and again over every member's model, whose objects all stay alive (measured:
    the set-up of 10,000 quasi-static members, each its own slider-crank, 3.0 s with it,
    1.7-1.8 s held off over its loops, ``benchmarks/kinematic_sweep.py``)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def for_batch(problem):
    """``problem`` solved in a sweep's one vectorized program: its guard at singular
    positions decides once per batch (:meth:`~mixdyn.equations.Constraints.for_batch`)."""
    return eqx.tree_at(lambda p: p.c, problem, problem.c.for_batch())


def batched_map(f, xs, batch_size: int):
    """``jax.lax.map(f, xs, batch_size=batch_size)`` with the shapes written out: ``f`` over
    the leading axis of ``xs``, ``batch_size`` members at a time vectorized (a scan over the
    full batches, then the remainder vectorized). ``jax.lax.map`` infers its reshapes
    (``-1``), which fails on outputs of no entries (a model without constraints has
    multipliers of shape (N, 0)); here every shape is given."""
    n = jax.tree.leaves(xs)[0].shape[0]
    full, rest = divmod(n, batch_size)
    parts = []
    if full:
        head = jax.tree.map(
            lambda x: x[: full * batch_size].reshape(full, batch_size, *x.shape[1:]), xs
        )
        _, ys = jax.lax.scan(lambda c, x: (c, jax.vmap(f)(x)), (), head)
        parts.append(jax.tree.map(lambda y: y.reshape(full * batch_size, *y.shape[2:]), ys))
    if rest:
        parts.append(jax.vmap(f)(jax.tree.map(lambda x: x[full * batch_size :], xs)))
    if len(parts) == 1:
        return parts[0]
    return jax.tree.map(lambda a, b: jnp.concatenate([a, b], axis=0), *parts)


def _integrate_batch(method: str, batch_size: int, problems, ts, q0, qd0, options):
    """The trajectories of a batch of cases of one structure (leading axis: the member)."""
    integrate_one = INTEGRATORS[method]

    def one(x):
        p, a, b = x
        return integrate_one(p, ts, a, b, options, progress=None)

    return batched_map(one, (problems, q0, qd0), batch_size)


_integrate_batch_jit = cached_jit(_integrate_batch)


def _post_batch(batch_size: int, problems, ts, Q, QD):
    """The post-processing's arrays (:func:`~._simulate._post_arrays`) of a batch of members
    (leading axis: the member), in one program, ``batch_size`` members at a time
    vectorized."""

    def one(x):
        p, q, qd = x
        return _post_arrays(p, ts, q, qd)

    return batched_map(one, (problems, Q, QD), batch_size)


_post_batch_jit = cached_jit(_post_batch)


@functools.cache
def _default_batch_size() -> int | None:
    """None on a CPU: member by member, each by the single run's program (compiled once for
    every sweep), from a thread per core (measured on the paper's model, 2 cores, 128
    members: 13.4 ms a member so; 8.4 ms in one vectorized program, but that program is
    compiled per number of members, ~10 s the first time); on an accelerator
    :data:`ACCELERATOR_BATCH` (an H200, the paper's model: 0.61 ms a member in a batch of
    1,024, 0.082 ms of 10,000, 0.062 ms of 30,000; ``benchmarks/gpu_sweep.py``)."""
    return None if jax.default_backend() == "cpu" else ACCELERATOR_BATCH


#: Members vectorized at a time on an accelerator by default: wider batches cost less a member
#: up to ~30,000 (each loop iteration's fixed cost is shared), then no more; ~65 kB of outputs
#: a member of the paper's model (201 times), ~2 GB for a full batch.
ACCELERATOR_BATCH = 32768


#: Members integrated at a time by one vectorized program where a sweep's members share one
#: start and give no ``batch_size`` on a CPU (a model file's sweep, ``md.sweep`` of at least
#: this many members; fewer: the single run's program member by member): one program, of
#: this shape, for any number of members, compiled once.
CHUNK = 64


Outcome = tuple[Result | None, MixdynError | None]


def _finish(case: Case, traj, arrays=None) -> Outcome:
    try:
        return finish(case, traj, arrays), None
    except MixdynError as err:
        return None, err


def _in_threads(work: Callable[[int], Outcome], indices: list[int], threads: int, on_member):
    """``work(i)`` for each index, the first alone (it compiles the programs the others
    reuse), the others from ``threads`` threads (XLA runs without the GIL); ``on_member(i)``
    after each."""

    def run(i):
        out = work(i)
        if on_member is not None:
            on_member(i)
        return out

    if not indices:
        return []
    first = run(indices[0])
    rest = indices[1:]
    if threads <= 1 or len(rest) <= 1:
        return [first, *map(run, rest)]
    with ThreadPoolExecutor(threads) as pool:
        return [first, *pool.map(run, rest)]


def _stack_column(col) -> np.ndarray:
    """One leaf of every member stacked (leading axis: the member); a leaf that is the same
    object in every member (a shared start's constraint set, the numbers not varied) is read
    once and broadcast: on an accelerator each read is a transfer."""
    if all(x is col[0] for x in col):
        a = np.asarray(col[0])
        return np.broadcast_to(a, (len(col), *a.shape))
    return np.stack([np.asarray(x) for x in col])


def _batched(cases: list[Case], batch_size: int, seconds: dict | None = None) -> list[Outcome]:
    """The members integrated by one program (``batch_size`` at a time vectorized), then
    finished one by one (``seconds``: filled with the times of both)."""
    clock = time.perf_counter()
    if batch_size < 1:
        raise ModelError(f"batch_size must be >= 1, got {batch_size}", "batch_size")
    first = cases[0]
    # Stacked leaf by leaf (NumPy), under the structure of the batched problem (for_batch
    # changes a static field only: the leaves are the same).
    treedef = jax.tree_util.tree_structure(for_batch(first.problem))
    rows = [jax.tree_util.tree_leaves(c.problem) for c in cases]
    problems = jax.tree_util.tree_unflatten(
        treedef, [_stack_column(col) for col in zip(*rows, strict=True)]
    )
    ts = np.asarray(first.ts, dtype=np.float64)
    trajs = _integrate_batch_jit(
        first.options.method,
        int(min(batch_size, len(cases))),
        problems,
        ts,
        _stack_column([c.q0 for c in cases]),
        _stack_column([c.qd0 for c in cases]),
        first.options.as_argument(),
    )
    trajs = jax.tree.map(np.asarray, trajs)
    middle = time.perf_counter()
    arrays = _post_batch_jit(int(min(batch_size, len(cases))), problems, ts, trajs.q, trajs.qd)
    arrays = jax.tree.map(np.asarray, arrays)
    done = [
        _finish(c, *(jax.tree.map(lambda x, i=i: x[i], a) for a in (trajs, arrays)))
        for i, c in enumerate(cases)
    ]
    if seconds is not None:
        seconds["integration"] = middle - clock
        seconds["finishing"] = time.perf_counter() - middle
    return done
