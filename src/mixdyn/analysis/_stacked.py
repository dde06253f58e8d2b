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
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import MixdynError, ModelError
from ..model import Model
from ..model._element import Resolver
from ..model._geometry import point
from ._assembly import length_scale
from ._reactions import check_contacts
from ._schedule import (
    CHUNK,
    Outcome,
    _default_batch_size,
    _integrate_batch_jit,
    _post_batch_jit,
    for_batch,
)
from ._setup import Analysis, prepare
from ._simulate import Case, energy_tolerance, finish, post_columns, require_masses
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

    @property
    def model(self) -> Model:
        """Member 0's model (the names, units and structure every member shares)."""
        return self.case.problem.model

    @property
    def kind(self) -> str:
        """The analysis' name (``"forward"``, ``"mixed"``, ``"inverse"``)."""
        return self.case.kind

    def columns(self, arrays, results, errors, output_units=None, points=()):
        """Every member's columns as arrays (:func:`columns`)."""
        return columns(self, arrays, results, errors, output_units, points)

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
    return _stacked(value._case(setup, t), len(leaves), positions, values, masses)


def _stacked(case: Case, n_model: int, positions, values, masses) -> Stacked | None:
    """The members of ``case``'s problem with ``values[k]`` at its leaf ``positions[k]``
    (the model's leaves come first, ``n_model`` of them, then the constraint set's)."""
    problem_leaves = jax.tree_util.tree_leaves(case.problem)
    if len(problem_leaves) != n_model + len(jax.tree_util.tree_leaves(case.problem.c)):
        return None  # pragma: no cover - a problem field beside the model and constraints
    stacked = list(problem_leaves)
    for k, v in zip(positions, values, strict=True):
        stacked[k] = np.asarray(v, dtype=np.float64)
    return Stacked(case, stacked, frozenset(positions), len(values[0]), masses)


def stack_driven(
    model: Model,
    paths: Sequence[str],
    positions: Sequence[int],
    values: Sequence[np.ndarray],
    value: Analysis,
    t,
) -> tuple[Stacked, Result] | None:
    """An inverse sweep's members (the motion fixed by the drivers, the same for every
    member where only masses, inertias and forces vary), as :func:`stack`: member 0 run
    whole, ``(stacked, its result)``, whose motion every member shares.

    Raises:
        ModelError: as :func:`stack`.
        MixdynError: member 0's run fails (every member's motion).
    """
    leaves, treedef = jax.tree_util.tree_flatten(model)

    def model_of(i: int) -> Model:
        row = list(leaves)
        for k, v in zip(positions, values, strict=True):
            row[k] = jnp.asarray(v[i])
        return jax.tree_util.tree_unflatten(treedef, row)

    masses = _masses_and_inertias(model, dict(zip(paths, values, strict=True)), model_of)
    t0 = float(np.atleast_1d(np.asarray(t, dtype=float))[0])
    try:
        setup = prepare(model_of(0), value, t0=t0)
        first = value._run(setup, t)
    except ModelError as err:
        err.add_note("in member 0 of the sweep")
        raise
    ts, n_drivers = np.asarray(first.t), len(model.drivers)
    case = Case(value.name, setup.problem, ts, first.q[0], first.qd[0], None, n_drivers, None)
    stacked = _stacked(case, len(leaves), positions, values, masses)
    return None if stacked is None else (stacked, first)


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


class Motion(NamedTuple):
    """An inverse sweep's motion, every member's (M, N, nq) (broadcast: shared)."""

    q: np.ndarray
    qd: np.ndarray
    w: None = None


def _width(count: int, batch_size: int | None) -> tuple[int, int]:
    """``(members a call, members vectorized at a time)``: :data:`~._schedule.CHUNK` a call
    on a CPU without ``batch_size``, else every member in one call."""
    width = batch_size or _default_batch_size()
    chunk = CHUNK if width is None else count
    return chunk, min(width or CHUNK, chunk)


def _chunks(count: int, chunk: int):
    """The members of each call (K,), and the call's members filled up to ``chunk`` with
    copies of its first member."""
    for first in range(0, count, chunk):
        idx = np.arange(first, min(first + chunk, count))
        yield idx, np.concatenate([idx, np.full(chunk - len(idx), first)])


def post_driven(stacked: Stacked, first: Result) -> Arrays:
    """Every member's post-processing (:func:`~._simulate._post_arrays`) along member 0's
    motion ``first``, by one vectorized program (:data:`~._schedule.CHUNK` members a call
    on a CPU)."""
    count = stacked.count
    chunk, width = _width(count, None)
    ts = np.asarray(stacked.case.ts, dtype=np.float64)
    q, qd = np.asarray(first.q), np.asarray(first.qd)
    Q, QD = (np.broadcast_to(a, (chunk, *a.shape)) for a in (q, qd))
    parts = []
    for idx, full in _chunks(count, chunk):
        post = _post_batch_jit(width, stacked.problems(full), ts, Q, QD)
        parts.append(jax.tree.map(lambda x, n=len(idx): np.asarray(x)[:n], post))
    post = parts[0] if len(parts) == 1 else jax.tree.map(lambda *xs: np.concatenate(xs), *parts)
    motion = Motion(*(np.broadcast_to(a, (count, *a.shape)) for a in (q, qd)))
    return Arrays(motion, post)


def driven_result(stacked: Stacked, first: Result, arrays: Arrays, i: int) -> Result:
    """Member ``i``'s result of an inverse sweep: member 0's motion with member ``i``'s
    efforts and reactions, checked as the single run's (its contacts, finite values)."""
    case = stacked.member(i)
    _, post = arrays.of(i)
    _, _, ratio, cols = post_columns(case.problem, post, case.n_drivers)
    check_contacts(case.problem.c, case.ts, cols)
    stats = dict(first.stats, min_pivot_ratio_dynamics=float(np.min(np.asarray(ratio))))
    extra = {k: np.asarray(v) for k, v in cols.items()}
    return dataclasses.replace(first, model=case.problem.model, extra=extra, stats=stats)


def integrate(stacked: Stacked, batch_size: int | None) -> Arrays:
    """Every member integrated and post-processed by one vectorized program: on a CPU
    without ``batch_size``, :data:`~._schedule.CHUNK` members a call (the last call filled
    up with copies of its first member, whose outcomes are dropped: one program shape for
    any count); otherwise the whole sweep in one call, ``batch_size`` (default: the
    accelerator's) members at a time vectorized."""
    count = stacked.count
    chunk, width = _width(count, batch_size)
    case = stacked.case
    ts = np.asarray(case.ts, dtype=np.float64)
    options = case.options.as_argument()
    q0, qd0 = np.asarray(case.q0), np.asarray(case.qd0)
    parts = []
    for idx, full in _chunks(count, chunk):
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
    if isinstance(trajs, Motion):  # an inverse sweep: its post-processing alone varies
        flagged = np.zeros(count, dtype=bool)
        for leaf in jax.tree_util.tree_leaves(post):
            a = np.asarray(leaf)
            if a.dtype.kind == "f":
                flagged |= ~np.isfinite(a.reshape(count, -1)).all(axis=1)
        return flagged
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

    def __init__(self, count: int, build: Callable[[int], Result], outcomes: dict[int, Outcome]):
        self._count, self._build = count, build
        self._built = {i: r for i, (r, _) in outcomes.items()}

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = range(len(self))[i]
        if i not in self._built:
            self._built[i] = self._build(i)
        return self._built[i]

    def __repr__(self) -> str:
        return f"<{len(self)} results, {len(self._built)} built>"

    def __reduce__(self):
        """Pickled as the list of every member's result (each built)."""
        return list, (list(self),)


def run(
    stacked: Stacked,
    batch_size: int | None,
    on_member: Callable[[int], None] | None,
    seconds: dict,
    clock: Callable[[], float],
    first: Result | None = None,
) -> tuple[LazyResults, dict[int, MixdynError], Arrays]:
    """The members of ``stacked`` integrated (an inverse sweep, ``first`` member 0's result:
    post-processed along its motion), screened, the flagged ones finished:
    ``(results, errors, arrays)``; ``seconds`` gains ``integration`` (or
    ``post-processing``) and ``finishing``."""
    start = clock()
    if first is None:
        arrays = integrate(stacked, batch_size)

        def build(i: int) -> Result:
            return finish(stacked.member(i), *arrays.of(i))
    else:
        arrays = post_driven(stacked, first)

        def build(i: int) -> Result:
            return driven_result(stacked, first, arrays, i)

    middle = clock()
    outcomes = {}
    for i in np.flatnonzero(screen(stacked, arrays)):
        try:
            outcomes[int(i)] = build(int(i)), None
        except MixdynError as err:
            outcomes[int(i)] = None, err
    errors = {i: e for i, (_, e) in outcomes.items() if e is not None}
    if on_member is not None:
        for i in range(stacked.count):
            on_member(i)
    seconds["integration" if first is None else "post-processing"] = middle - start
    seconds["finishing"] = clock() - middle
    return LazyResults(stacked.count, build, outcomes), errors, arrays


def columns(
    stacked: Stacked,
    arrays: Arrays,
    results: LazyResults,
    errors: dict,
    output_units=None,
    points: Sequence[str] = (),
) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Every result column of every member, (M, N) each (``t``: (N,)), with, for each point
    reference of ``points``, its global position, velocity and acceleration
    (``coupler.P.x``, ``.y``, ``.vx``, ``.vy``, ``.ax``, ``.ay``: :meth:`~.result.Result.point`),
    in ``output_units`` as :func:`~.result.in_units`, and their units; a failed member's
    rows NaN. Read from the stacked arrays at once (the result of the first member that did
    not fail gives the names, kinds and units)."""
    first = next((i for i in range(stacked.count) if i not in errors), None)
    if first is None:
        raise ValueError("no member of the sweep succeeded: there is nothing to label")
    result: Result = results[first]
    case, (trajs, post) = stacked.case, (arrays.trajs, arrays.post)
    count, n = stacked.count, len(case.ts)
    flat = jax.tree.map(lambda x: np.asarray(x).reshape(count * n, *np.shape(x)[2:]), post)
    qdd, _, _, extra = post_columns(case.problem, flat, case.n_drivers)
    qdd = np.asarray(qdd).reshape(count, n, -1)
    cols = body_columns(case.problem.model, case.ts, np.asarray(trajs.q), np.asarray(trajs.qd), qdd)
    cols.update({k: np.asarray(v).reshape(count, n) for k, v in extra.items()})
    if trajs.w is not None:
        W = np.asarray(trajs.w)
        cols["work.nonconservative"], cols["work.constraints"] = W[..., 0], W[..., 1]
    if set(cols) != set(result.columns()):  # pragma: no cover - a column made elsewhere
        raise RuntimeError("the stacked columns differ from a member's result's")
    units = result.units()
    states = (np.asarray(trajs.q), np.asarray(trajs.qd), qdd)
    add_points(cols, units, case.problem.model, points, *states)
    if errors:
        bad = np.asarray(sorted(errors))
        cols = {k: v if k == "t" else _without(v, bad) for k, v in cols.items()}
    return in_units(result, cols, units, output_units)


def body_columns(model: Model, ts, q, qd, qdd) -> dict[str, np.ndarray]:
    """``t`` (N,) and each body's ``x, y, phi, vx, vy, omega, ax, ay, alpha``, (M, N) each,
    from every member's ``q``, ``qd``, ``qdd`` (M, N, nq) [model units]."""
    states = {"q": q, "qd": qd, "qdd": qdd}
    cols = {"t": np.asarray(ts)}
    for b, body in enumerate(model.bodies):
        for suffix, src, k, _ in _BODY_COLUMNS:
            cols[f"{body.name}.{suffix}"] = states[src][:, :, 3 * b + k]
    return cols


def add_points(cols: dict, units: dict, models, points: Sequence[str], q, qd, qdd) -> None:
    """Add to ``cols`` and ``units`` each point reference of ``points``' global position,
    velocity and acceleration (``coupler.P.x``, ``.y``, ``.vx``, ``.vy``, ``.ax``, ``.ay``:
    :meth:`~.result.Result.point`), (M, N) each [model units], from every member's ``q``,
    ``qd``, ``qdd`` (M, N, nq); ``models``: the model every member shares, or each member's
    (M,) (its points' body-frame coordinates)."""
    count, n = np.shape(q)[:2]
    one = isinstance(models, Model)
    first = models if one else models[0]
    flat = [np.reshape(a, (count * n, -1)) for a in (q, qd, qdd)]
    for ref in points:
        b, s = Resolver(first.ground, first.bodies).point(ref, "point")
        if one:
            S = np.broadcast_to(np.asarray(s), (count * n, 2))
        else:
            own = [Resolver(m.ground, m.bodies).point(ref, "point")[1] for m in models]
            S = np.repeat(np.stack([np.asarray(x) for x in own]), n, axis=0)
        pva = _point(b, S, *flat)
        for arr, pre, kind in zip(pva, ("", "v", "a"), _POINT_KINDS, strict=True):
            for k, axis in enumerate("xy"):
                cols[f"{ref}.{pre}{axis}"] = arr[:, k].reshape(count, n)
                units[f"{ref}.{pre}{axis}"] = first.units.label(kind)


#: The kinds of quantity of a point's position, velocity and acceleration.
_POINT_KINDS = ("length", "velocity", "acceleration")


def _point(b: int, S, q, qd, qdd) -> tuple[np.ndarray, ...]:
    """The global position, velocity and acceleration, each (K, 2) [model units], of the
    point with body-frame coordinates ``S`` (K, 2) on body ``b`` at the K states ``q``,
    ``qd``, ``qdd`` (K, nq), as :meth:`~.result.Result.point`."""

    def pva(q, qd, qdd, s):
        def pos(q):
            return point(q, b, s)

        p, v = jax.jvp(pos, (q,), (qd,))
        _, a2 = jax.jvp(lambda qq: jax.jvp(pos, (qq,), (qd,))[1], (q,), (qd,))
        return p, v, a2 + jax.jacfwd(pos)(q) @ qdd

    out = jax.vmap(pva)(jnp.asarray(q), jnp.asarray(qd), jnp.asarray(qdd), jnp.asarray(S))
    return tuple(np.asarray(a) for a in out)


def _without(a: np.ndarray, bad: np.ndarray) -> np.ndarray:
    out = np.array(a, dtype=float)
    out[bad] = np.nan
    return out


__all__ = [
    "Arrays",
    "LazyResults",
    "Motion",
    "Stacked",
    "add_points",
    "body_columns",
    "columns",
    "driven_result",
    "integrate",
    "post_driven",
    "run",
    "screen",
    "stack",
    "stack_driven",
]
