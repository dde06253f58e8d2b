"""A sweep whose members share one start, held as arrays.

Where the varied numbers reach only masses, inertias and force numbers
(:func:`~.sweep.shares_start`), member 0 is set up like a single run and the members are one
problem with a leading member axis: the varied leaves stacked (M, ...), every other leaf the
set-up's own, broadcast. One vectorized program integrates them (:data:`~._schedule.CHUNK`
members at a time on a CPU, one shape for any count; a whole batch of ``batch_size``
otherwise) and post-processes them; the members are then screened at once (status, finite
values, the energy balance: :func:`screen`), a flagged member finished like a single run
(:func:`~._simulate.finish`, which names its error), and every other member's
:class:`~.result.Result` built only when asked for (:class:`LazyResults`). No member model,
problem or result is made per member before then.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import MixdynError, ModelError
from ..model import Model
from ._assembly import length_scale
from ._schedule import (
    CHUNK,
    Outcome,
    _default_batch_size,
    _finish,
    _integrate_batch_jit,
    _post_batch_jit,
    for_batch,
)
from ._setup import Analysis, prepare
from ._simulate import Case, energy_tolerance, post_columns, require_masses
from .result import _BODY_COLUMNS, Result, in_units


@dataclasses.dataclass(frozen=True)
class Stacked:
    """The members of a sweep sharing member 0's set-up, as one problem with a member axis.

    Attributes:
        case: member 0's run, set up (start, options, output times: every member's).
        leaves: the problem's leaves: a (M, ...) array where the leaf is varied, else the
            set-up's own leaf (shared by every member).
        varied: the indices of the varied leaves.
        count: M, the number of members.
        masses: (M,) each member's total mass [mass] (the energy balance's scale).
    """

    case: Case
    leaves: list
    varied: frozenset[int]
    count: int
    masses: np.ndarray

    def problems(self, idx: np.ndarray):
        """The problem of the members ``idx`` (K,), batched (:func:`~._schedule.for_batch`):
        every leaf (K, ...)."""
        treedef = jax.tree_util.tree_structure(for_batch(self.case.problem))
        rows = [
            leaf[idx] if k in self.varied else np.broadcast_to(leaf, (len(idx), *np.shape(leaf)))
            for k, leaf in enumerate(self.leaves)
        ]
        return jax.tree_util.tree_unflatten(treedef, rows)

    def member(self, i: int) -> Case:
        """Member ``i``'s run: member 0's with member ``i``'s numbers, as the single run of
        its model is set up."""
        treedef = jax.tree_util.tree_structure(self.case.problem)
        row = [
            jnp.asarray(leaf[i]) if k in self.varied else leaf for k, leaf in enumerate(self.leaves)
        ]
        return dataclasses.replace(self.case, problem=jax.tree_util.tree_unflatten(treedef, row))


def stack(
    model: Model,
    paths: Sequence[str],
    positions: Sequence[int],
    values: Sequence[np.ndarray],
    value: Analysis,
    t,
    recorded: dict | None,
) -> Stacked | None:
    """The members of ``model`` with ``values[k]`` (M, ...) at its leaf ``positions[k]`` (the
    number named by ``paths[k]``),
    sharing member 0's set-up; None where they cannot share it (a mixed run whose solvability
    may depend on the masses: :meth:`~._simulate.Integrated._shares_setup`), then the sweep
    sets up member by member.

    Raises:
        ModelError: member 0's input error, or a member's mass or inertia not positive
            (with the member's index in a note).
        MixdynError: member 0's start cannot be made (every member's).
    """
    leaves, treedef = jax.tree_util.tree_flatten(model)
    count = len(values[0])

    def model_of(i: int) -> Model:
        row = list(leaves)
        for k, v in zip(positions, values, strict=True):
            row[k] = jnp.asarray(v[i])
        return jax.tree_util.tree_unflatten(treedef, row)

    masses = _masses_and_inertias(model, dict(zip(paths, values, strict=True)), model_of)
    t0 = float(np.atleast_1d(np.asarray(t, dtype=float))[0])
    try:
        setup = prepare(model_of(0), value, t0=t0)
    except ModelError as err:
        err.add_note("in member 0 of the sweep")
        raise
    if recorded is not None:
        setup = dataclasses.replace(setup, recorded=recorded)
    if not value._shares_setup(setup):
        return None
    case = value._case(setup, t)
    problem_leaves = jax.tree_util.tree_leaves(case.problem)
    if len(problem_leaves) != len(leaves) + len(jax.tree_util.tree_leaves(case.problem.c)):
        return None  # pragma: no cover - a problem field beside the model and constraints
    stacked = list(problem_leaves)
    for k, v in zip(positions, values, strict=True):
        stacked[k] = np.asarray(v, dtype=np.float64)
    return Stacked(case, stacked, frozenset(positions), count, masses)


def _masses_and_inertias(model: Model, varied: dict[str, np.ndarray], model_of) -> np.ndarray:
    """(M,) each member's total mass [mass], every member's masses and inertias checked
    positive (:func:`~._simulate.require_masses` names the first member that is not);
    ``varied``: path -> (M,) values."""
    count = len(next(iter(varied.values())))
    total = np.zeros(count)
    bad = np.zeros(count, dtype=bool)
    for b in model.bodies:
        for name in ("mass", "inertia"):
            column = varied.get(f"{b.name}.{name}")
            if column is None:
                column = np.full(count, float(getattr(b, name)))
            bad |= ~(column > 0)
            if name == "mass":
                total += column
    if bad.any():
        i = int(np.argmax(bad))
        try:
            require_masses(model_of(i))
        except ModelError as err:
            err.add_note(f"in member {i} of the sweep")
            raise
    return total


@dataclasses.dataclass(frozen=True)
class Arrays:
    """Every member's trajectory and post-processing's arrays (leading axis: the member):
    :class:`~.integrators.Trajectory` and :func:`~._simulate._post_arrays`' output."""

    trajs: object
    post: tuple

    def of(self, i: int) -> tuple:
        """Member ``i``'s ``(trajectory, post arrays)``."""
        return tuple(jax.tree.map(lambda x, i=i: x[i], a) for a in (self.trajs, self.post))


def integrate(stacked: Stacked, batch_size: int | None) -> Arrays:
    """Every member integrated and post-processed by one vectorized program: on a CPU
    without ``batch_size``, :data:`~._schedule.CHUNK` members a call (the last call filled
    up with copies of its first member, whose outcomes are dropped: one program shape for
    any count); otherwise the whole sweep in one call, ``batch_size`` (default: the
    accelerator's) members at a time vectorized."""
    count = stacked.count
    width = batch_size or _default_batch_size()
    chunk = CHUNK if width is None else count
    width = min(width or CHUNK, chunk)
    case = stacked.case
    ts = np.asarray(case.ts, dtype=np.float64)
    options = case.options.as_argument()
    q0, qd0 = np.asarray(case.q0), np.asarray(case.qd0)
    parts = []
    for first in range(0, count, chunk):
        idx = np.arange(first, min(first + chunk, count))
        full = np.concatenate([idx, np.full(chunk - len(idx), first)])
        problems = stacked.problems(full)
        trajs = _integrate_batch_jit(
            case.options.method,
            width,
            problems,
            ts,
            np.broadcast_to(q0, (chunk, *q0.shape)),
            np.broadcast_to(qd0, (chunk, *qd0.shape)),
            options,
        )
        post = _post_batch_jit(width, problems, ts, trajs.q, trajs.qd)
        parts.append(jax.tree.map(lambda x, n=len(idx): np.asarray(x)[:n], (trajs, post)))
    if len(parts) == 1:
        return Arrays(*parts[0])
    trajs, post = jax.tree.map(lambda *xs: np.concatenate(xs), *parts)
    return Arrays(trajs, post)


def screen(stacked: Stacked, arrays: Arrays) -> np.ndarray:
    """(M,) the members to finish like a single run now (their outcome may be an error): a
    failed integration, a value that is not finite, an energy balance past half its
    tolerance, or (every member) one-sided contacts whose force is checked per member. The
    others pass every check of :func:`~._simulate.finish`: their results wait until asked
    for."""
    case, trajs, post = stacked.case, arrays.trajs, arrays.post
    count = stacked.count
    if any(getattr(j, "unilateral", None) is not None for j in case.problem.c.joints):
        return np.ones(count, dtype=bool)
    flagged = np.asarray(trajs.status) != 0
    for leaf in jax.tree_util.tree_leaves((trajs.q, trajs.qd, trajs.w, post)):
        a = np.asarray(leaf)
        if a.dtype.kind == "f":
            flagged |= ~np.isfinite(a.reshape(count, -1)).all(axis=1)
    tol = energy_tolerance(case.energy_tol, case.options)
    if tol is not None:
        with np.errstate(invalid="ignore", over="ignore"):
            rel = _energy_balance(stacked, arrays)
        flagged |= ~(rel <= 0.5 * tol)
    return flagged


def _energy_balance(stacked: Stacked, arrays: Arrays) -> np.ndarray:
    """(M,) each member's largest relative energy balance error, as
    :func:`~._simulate.check_energy_balance` computes it member by member."""
    E, W = np.asarray(arrays.post[5]), np.asarray(arrays.trajs.w)
    T, V, Wn, Wc = E[..., 0], E[..., 1], W[..., 0], W[..., 1]
    bal = (T + V) - (T[:, :1] + V[:, :1]) - Wn - Wc
    ts = stacked.case.ts
    span = float(ts[-1] - ts[0])
    rest = stacked.masses * (length_scale(stacked.case.problem.model) / span) ** 2
    scale = np.max(
        np.stack(
            [
                np.ptp(T, axis=1),
                np.ptp(V, axis=1),
                np.max(np.abs(Wn), axis=1),
                np.max(np.abs(Wc), axis=1),
                rest,
                np.full(len(T), 1e-300),
            ]
        ),
        axis=0,
    )
    return np.max(np.abs(bal) / scale[:, None], axis=1)


class LazyResults(Sequence):
    """A sweep's results, member by member (None for a failed member): a member's
    :class:`~.result.Result` is built the first time it is read (:func:`~._simulate.finish`
    of its arrays, equal to the single run's) and kept."""

    def __init__(self, stacked: Stacked, arrays: Arrays, outcomes: dict[int, Outcome]):
        self._stacked, self._arrays = stacked, arrays
        self._built = {i: r for i, (r, _) in outcomes.items()}

    def __len__(self) -> int:
        return self._stacked.count

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = range(len(self))[i]
        if i not in self._built:
            result, err = _finish(self._stacked.member(i), *self._arrays.of(i))
            if err is not None:
                raise err  # pragma: no cover - the screen finishes such members at once
            self._built[i] = result
        return self._built[i]

    def __repr__(self) -> str:
        return f"<{len(self)} results, {len(self._built)} built>"


def run(
    stacked: Stacked,
    batch_size: int | None,
    on_member: Callable[[int], None] | None,
    seconds: dict,
    clock: Callable[[], float],
) -> tuple[LazyResults, dict[int, MixdynError], Arrays]:
    """The members of ``stacked`` integrated, screened, the flagged ones finished:
    ``(results, errors, arrays)``; ``seconds`` gains ``integration`` and ``finishing``."""
    start = clock()
    arrays = integrate(stacked, batch_size)
    middle = clock()
    outcomes = {
        int(i): _finish(stacked.member(int(i)), *arrays.of(int(i)))
        for i in np.flatnonzero(screen(stacked, arrays))
    }
    errors = {i: e for i, (_, e) in outcomes.items() if e is not None}
    if on_member is not None:
        for i in range(stacked.count):
            on_member(i)
    seconds["integration"] = middle - start
    seconds["finishing"] = clock() - middle
    return LazyResults(stacked, arrays, outcomes), errors, arrays


def columns(
    stacked: Stacked, arrays: Arrays, results: LazyResults, errors: dict, output_units=None
) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Every result column of every member, (M, N) each (``t``: (N,)), in ``output_units``
    as :func:`~.result.in_units`, and their units; a failed member's rows NaN. Read from the
    stacked arrays at once (the result of the first member that did not fail gives the
    names, kinds and units)."""
    first = next((i for i in range(stacked.count) if i not in errors), None)
    if first is None:
        raise ValueError("no member of the sweep succeeded: there is nothing to label")
    result: Result = results[first]
    case, (trajs, post) = stacked.case, (arrays.trajs, arrays.post)
    count, n = stacked.count, len(case.ts)
    flat = jax.tree.map(lambda x: np.asarray(x).reshape(count * n, *np.shape(x)[2:]), post)
    qdd, _, _, extra = post_columns(case.problem, flat, case.n_drivers)
    states = {"q": np.asarray(trajs.q), "qd": np.asarray(trajs.qd)}
    states["qdd"] = np.asarray(qdd).reshape(count, n, -1)
    cols = {"t": np.asarray(case.ts)}
    for b, body in enumerate(case.problem.model.bodies):
        for suffix, src, k, _ in _BODY_COLUMNS:
            cols[f"{body.name}.{suffix}"] = states[src][:, :, 3 * b + k]
    cols.update({k: np.asarray(v).reshape(count, n) for k, v in extra.items()})
    W = np.asarray(trajs.w)
    cols["work.nonconservative"], cols["work.constraints"] = W[..., 0], W[..., 1]
    if set(cols) != set(result.columns()):  # pragma: no cover - a column made elsewhere
        raise RuntimeError("the stacked columns differ from a member's result's")
    if errors:
        bad = np.asarray(sorted(errors))
        cols = {k: v if k == "t" else _without(v, bad) for k, v in cols.items()}
    return in_units(result, cols, result.units(), output_units)


def _without(a: np.ndarray, bad: np.ndarray) -> np.ndarray:
    out = np.array(a, dtype=float)
    out[bad] = np.nan
    return out


__all__ = ["Arrays", "LazyResults", "Stacked", "columns", "integrate", "run", "screen", "stack"]
