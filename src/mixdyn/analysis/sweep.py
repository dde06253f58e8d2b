"""Sweeps: one analysis over many variants of a mechanism, compiled once.

A sweep takes an analysis value (:mod:`mixdyn.analyses`). Each member of a forward or mixed
sweep (an analysis that is integrated, :attr:`~._setup.Analysis.integrated`) is prepared like
a single run (:func:`~._setup.prepare`: its start made consistent, its mobility analysed),
or, where the varied numbers do not enter the start (masses, inertias, force numbers:
:func:`shares_start`), takes the first member's set-up with its own numbers; all members share
one structure, hence one compiled program.
On a CPU the members are integrated one by one by the single run's program, from a thread
per core (XLA runs without the GIL); with a ``batch_size`` (the default on an accelerator)
the members' equations are stacked and one program integrates the whole batch
(``jax.lax.map`` over chunks vectorized by ``vmap``). Each member is finished like a single
run: a failure or a broken energy balance is reported by member index and cause
(:attr:`Sweep.errors`) without losing the others.

A kinematic, inverse or quasi-static sweep prepares and runs the single analysis member by
member (its programs are compiled for the first member and reused), from a thread per core.

Members differ in numbers only: masses, inertias, law and force parameters, start guesses
(any float leaf of the model, named by a parameter path such as ``"slider.mass"`` or
``"F1.law.amplitude"``: :mod:`mixdyn.paths`), or whole models built by the user with the same
structure.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import os
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import paths
from ..errors import MixdynError, ModelError
from ..model import Model
from ..runtime._programs import cached_jit
from ._keywords import from_keywords, study_analysis
from ._setup import Analysis, prepare, run
from ._simulate import Case, _post_arrays, finish, integrate, require_masses
from .integrators import INTEGRATORS
from .result import Result

#: The checked accessor of a parameter path, for the model-file layer's modules that read it
#: here (the public one: :func:`mixdyn.paths.getter`).
_leaf_getter = paths.getter


def grid(**axes: Sequence[float]) -> dict[str, np.ndarray]:
    """Every combination of the values of ``axes`` (path -> values), as the flat columns of
    a ``vary=`` mapping (the first axis varies slowest), e.g.
    ``md.grid(**{"slider.mass": [1, 2], "F1.law.a": [5, 10, 20]})`` gives 6 members."""
    names = list(axes)
    combos = list(itertools.product(*(np.asarray(axes[n], dtype=float) for n in names)))
    return {n: np.asarray([c[k] for c in combos]) for k, n in enumerate(names)}


def latin_hypercube(samples: int, seed: int = 0, **ranges: Sequence[float]) -> dict:
    """``samples`` members spread over the box ``ranges`` (path -> ``(low, high)``) by Latin
    hypercube sampling: each range cut into ``samples`` equal strata, each stratum sampled once
    (uniformly within it) per path, the strata of different paths paired at random
    (``numpy.random.default_rng(seed)``: the same seed, the same members). Returns the flat
    columns of a ``vary=`` mapping, e.g. ``md.latin_hypercube(100, **{"slider.mass": (1, 2)})``.
    """
    if int(samples) != samples or samples < 1:
        raise ModelError(f"samples must be a whole number >= 1, got {samples!r}", "samples")
    if not ranges:
        raise ModelError("give at least one range: path=(low, high)", "ranges")
    rng = np.random.default_rng(seed)
    out = {}
    for name, bounds in ranges.items():
        lo, hi = (float(v) for v in np.asarray(bounds, dtype=float).reshape(-1))
        if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
            raise ModelError(f"a range (low, high) with low < high, got {bounds!r}", name)
        strata = rng.permutation(int(samples)) + rng.uniform(size=int(samples))
        out[name] = lo + (hi - lo) * strata / samples
    return out


#: The bodies' fields that do not enter the kinematics (a forward run's start).
_INERTIAL = ("mass", "inertia")


def shares_start(model: Model, vary: Mapping[str, Sequence], unknown: Sequence[str] = ()) -> bool:
    """Whether every path of ``vary`` names a number that does not enter a forward or mixed
    run's start (the consistent positions and velocities, the constraint set, a mixed run's
    solvability): a body's mass or inertia, or any number of a force element but the
    ``unknown`` forces of a mixed run (their geometry gives the directions the solvability
    check reads). Such members share the nominal model's set-up, made once
    (:func:`run_members`)."""
    forces = {f.name for f in model.forces} - set(unknown)
    bodies = {b.name for b in model.bodies}
    for path in vary:
        head, _, rest = path.partition(".")
        field = rest.split(".")[0]
        if head in forces:
            continue
        if head in bodies and field in _INERTIAL:
            continue
        return False
    return bool(vary)


def vary_models(model: Model, vary: Mapping[str, Sequence]) -> list[Model]:
    """The member models of ``vary`` (path -> (B,) or (B, ...) values, one row per member):
    ``model`` with the named numbers replaced, member by member."""
    if not vary:
        raise ModelError("nothing to vary: give vary={'body.mass': [...], ...}", "vary")
    getters, values, count = [], [], None
    for path, vals in vary.items():
        get, shape = paths.getter(model, path)
        v = np.asarray(vals, dtype=float)
        if v.ndim == 0 or v.shape[1:] != shape:
            raise ModelError(
                f"values of shape {v.shape}: one row of shape {shape} per member expected",
                f"vary {path!r}",
            )
        if not np.all(np.isfinite(v)):
            k = int(np.argmax(~np.isfinite(v.reshape(len(v), -1)).all(axis=1)))
            raise ModelError(f"member {k}: value {v[k]} is not finite", f"vary {path!r}")
        if count is not None and len(v) != count:
            raise ModelError(
                f"{len(v)} values where the first varied quantity has {count}; give one value "
                "per member for each (md.grid(...) makes combinations)",
                f"vary {path!r}",
            )
        count = len(v)
        getters.append(get)
        values.append(v)
    # Each varied number's position among the model's leaves (found by putting a marker
    # there), then each member unflattened from the nominal leaves with its numbers: one
    # unflatten a member instead of a tree_at per member and number (5 ms a member).
    leaves, treedef = jax.tree_util.tree_flatten(model)
    positions = []
    for get in getters:
        marker = _Marker()
        marked = jax.tree_util.tree_leaves(eqx.tree_at(get, model, marker))
        positions.append(next(k for k, leaf in enumerate(marked) if leaf is marker))
    members = []
    for i in range(count):
        row = list(leaves)
        for k, v in zip(positions, values, strict=True):
            row[k] = jnp.asarray(v[i])
        members.append(jax.tree_util.tree_unflatten(treedef, row))
    return members


class _Marker:
    """A leaf put where a varied number sits (:func:`vary_models`)."""


def for_batch(problem):
    """``problem`` solved in a sweep's one vectorized program: its guard at singular
    positions decides once per batch (:meth:`~mixdyn.equations.Constraints.for_batch`)."""
    return eqx.tree_at(lambda p: p.c, problem, problem.c.for_batch())


def model_swapper(problem):
    """A function ``model -> problem`` with that model (of the same structure) in place of
    ``problem``'s own: the problem's leaves are the model's followed by the constraint set's,
    read once here (one unflatten a member; ``eqx.tree_at`` takes 2.5 ms)."""
    c_leaves = jax.tree_util.tree_leaves(problem.c)
    treedef = jax.tree_util.tree_structure(problem)
    n_model = len(jax.tree_util.tree_leaves(problem.model))
    if treedef.num_leaves != n_model + len(c_leaves):  # pragma: no cover - a new field
        return lambda model: eqx.tree_at(lambda p: p.model, problem, model)
    return lambda model: jax.tree_util.tree_unflatten(
        treedef, jax.tree_util.tree_leaves(model) + c_leaves
    )


def _integrate_batch(method: str, batch_size: int, problems, ts, q0, qd0, options):
    """The trajectories of a batch of cases of one structure (leading axis: the member)."""
    integrate_one = INTEGRATORS[method]

    def one(x):
        p, a, b = x
        return integrate_one(p, ts, a, b, options, progress=None)

    return jax.lax.map(one, (problems, q0, qd0), batch_size=batch_size)


_integrate_batch_jit = cached_jit(_integrate_batch)


def _post_batch(batch_size: int, problems, ts, Q, QD):
    """The post-processing's arrays (:func:`~._simulate._post_arrays`) of a batch of members
    (leading axis: the member), in one program, ``batch_size`` members at a time
    vectorized."""

    def one(x):
        p, q, qd = x
        return _post_arrays(p, ts, q, qd)

    return jax.lax.map(one, (problems, Q, QD), batch_size=batch_size)


_post_batch_jit = cached_jit(_post_batch)


@functools.cache
def _default_batch_size() -> int | None:
    """None on a CPU: member by member, each by the single run's program (compiled once for
    every sweep), from a thread per core (measured on the paper's model, 2 cores, 128
    members: 13.4 ms a member so; 8.4 ms in one vectorized program, but that program is
    compiled per number of members, ~10 s the first time); on an accelerator
    :data:`ACCELERATOR_BATCH` (an H200, the paper's model: 0.45 ms a member in a batch of
    1,024, 0.10 ms of 10,000, 0.08-0.09 ms of 30,000 to 100,000; ``benchmarks/gpu_sweep.py``)."""
    return None if jax.default_backend() == "cpu" else ACCELERATOR_BATCH


#: Members vectorized at a time on an accelerator by default: wider batches cost less a member
#: up to ~30,000 (each loop iteration's fixed cost is shared), then no more; ~65 kB of outputs
#: a member of the paper's model (201 times), ~2 GB for a full batch.
ACCELERATOR_BATCH = 32768


@dataclasses.dataclass
class Sweep:
    """The members of a sweep, in order.

    Attributes:
        results: per member its :class:`~mixdyn.Result`, or None where it failed.
        errors: member index -> the named error of a failed member.
        parameters: member index -> the varied values (path -> value), empty for ``models=``.
        seconds: wall times [s]: ``total``; in process also ``setup`` (every member's start;
            one shared start when only masses, inertias and forces vary) and, on the
            vectorized path, ``integration`` (the one program) and ``finishing``.
    """

    results: list[Result | None]
    errors: dict[int, MixdynError]
    parameters: list[dict[str, float | list]]
    seconds: dict[str, float]

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, i: int) -> Result:
        """Member ``i``'s result; a failed member raises its error."""
        if i in self.errors:
            raise self.errors[i]
        return self.results[i]

    def table(self, columns: Sequence[str] = (), output_units: dict | None = None):
        """A long-format pandas DataFrame: one row per (member, output time), with the member
        index, its varied values, ``t`` and the result ``columns`` (default: every column),
        in ``output_units`` (kind -> unit, as :meth:`mixdyn.Result.table`; default the
        model's units); the units in ``df.attrs["units"]``. Failed members have no rows."""
        import pandas as pd

        from .result import in_units

        frames, units = [], {}
        for i, res in enumerate(self.results):
            if res is None:
                continue
            cols, member_units = in_units(res, res.columns(), res.units(), output_units)
            if not units:
                units = member_units
            keep = ["t", *columns] if columns else list(cols)
            for c in keep:
                if c not in cols:
                    res[c]  # the error names the columns close to it
            df = pd.DataFrame({c: cols[c] for c in keep})
            for k, (name, v) in enumerate(self.parameters[i].items() if self.parameters else ()):
                df.insert(k, name, v if np.ndim(v) == 0 else str(v))
            df.insert(0, "member", i)
            frames.append(df)
        out = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
        out.attrs["units"] = units
        return out

    def dataset(self, columns: Sequence[str] = (), output_units: dict | None = None):
        """The sweep as a labelled N-dimensional array: an xarray ``Dataset`` with a variable
        per result column on the dimensions ``(member, t)``, the varied numbers and each
        member's ``status`` (``ok`` or its error's class) as coordinates along ``member``,
        and every variable's unit in its ``attrs["units"]`` (in ``output_units`` as
        :meth:`table`). A failed member's values are NaN. Write it with ``ds.to_netcdf(path)``
        (NetCDF) or ``ds.to_zarr(path)``. Needs xarray (``pip install 'mixdyn[xarray]'``).

        Raises:
            ValueError: no member succeeded (nothing gives the output times and columns).
        """
        import xarray as xr

        from .result import in_units

        first = next((r for r in self.results if r is not None), None)
        if first is None:
            raise ValueError("no member of the sweep succeeded: there is nothing to label")
        cols0, units = in_units(first, first.columns(), first.units(), output_units)
        names = [c for c in (columns or cols0) if c != "t"]
        for c in names:
            if c not in cols0:
                first[c]  # the error names the columns close to it
        n, nt = len(self.results), len(first.t)
        data = {c: np.full((n, nt), np.nan) for c in names}
        for i, res in enumerate(self.results):
            if res is not None:
                cols, _ = in_units(res, res.columns(), res.units(), output_units)
                for c in names:
                    data[c][i] = cols[c]
        coords = {
            "member": np.arange(n),
            "t": ("t", np.asarray(cols0["t"]), {"units": units["t"]}),
            "status": ("member", [type(self.errors[i]).__name__ if i in self.errors else "ok"
                                  for i in range(n)]),
        }  # fmt: skip
        if self.parameters and all(np.ndim(v) == 0 for v in self.parameters[0].values()):
            for name in self.parameters[0]:
                coords[name] = ("member", np.array([float(p[name]) for p in self.parameters]))
        variables = {c: (("member", "t"), data[c], {"units": units.get(c, "")}) for c in names}
        return xr.Dataset(
            variables, coords=coords, attrs={"model": first.model.name, "analysis": first.kind}
        )


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


def _input_error(err: ModelError, i: int, describe: str) -> ModelError:
    err.add_note(f"in member {i} of the sweep{describe}")
    return err


def run_members(
    members: Sequence[Model],
    t,
    analysis: Analysis | str,
    kwargs_of: Callable[[int], dict] | None = None,
    *,
    recorded: dict | None = None,
    batch_size: int | None = None,
    threads: int | None = None,
    on_member: Callable[[int], None] | None = None,
    describe: Callable[[int], str] = lambda i: "",
    offset: int = 0,
    same_start: bool = False,
    seconds: dict | None = None,
) -> list[Outcome]:
    """Each member's ``(Result, None)`` or ``(None, its numerical error)``, in order.

    Args:
        members: the member models, of one structure.
        t: (N,) output times [time].
        analysis: the analysis value, the same for every member; or (the model-file
            layer's spelling) an analysis' name (``"forward"``, ``"mixed"``, ``"kinematic"``,
            ``"inverse"``, ``"statics"``) with ``kwargs_of(i)`` member ``i``'s keywords.
        kwargs_of: member index -> the analysis' keywords for it (with a name only).
        recorded: the integrator options the members' results record (``stats["options"]``;
            default: the method object's own).
        batch_size, threads: as in :func:`sweep`.
        on_member: called with a member's index when it is done (from any thread).
        describe: member index -> words naming it in an error (its varied values).
        offset: the sweep's index of ``members[0]`` (a chunk of a larger sweep), for errors.
        same_start: the members differ only in numbers that do not enter a forward or mixed
            run's start (:func:`shares_start`): the first member is set up and the others
            take its start and constraint set with their own model (their masses checked). A
            mixed run whose unknown forces are not collocated with its prescribed motions is
            still set up member by member (its solvability, the rank of ``C M^-1 G``, may
            depend on the masses).
        seconds: if given, filled with the wall time of the set-up, the integration and the
            finishing [s].

    Raises:
        ModelError: a member's input error (named with its index), or members of different
            structures.
    """
    threads = threads or os.cpu_count() or 1
    if isinstance(analysis, Analysis):
        values = [analysis] * len(members)
        records: list[dict | None] = [recorded] * len(members)
    else:  # the keyword spelling, member by member (its keywords may differ)
        values, records = [], []
        for i in range(len(members)):
            try:
                value, record = from_keywords(analysis, t, kwargs_of(i))
            except ModelError as err:
                raise _input_error(err, offset + i, describe(i)) from None
            values.append(value)
            records.append(record)
    first_value = values[0] if values else analysis
    t0 = float(np.atleast_1d(np.asarray(t, dtype=float))[0])

    def setup_of(i: int):
        setup = prepare(members[i], values[i], t0=t0)
        if records[i] is not None:
            setup = dataclasses.replace(setup, recorded=records[i])
        return setup

    if not first_value.integrated:

        def whole(i: int) -> Outcome:
            try:
                return run(setup_of(i), t), None
            except ModelError as err:
                raise _input_error(err, offset + i, describe(i)) from None
            except MixdynError as err:
                return None, err

        if batch_size is not None:
            raise ModelError(
                f"a {first_value.name} sweep runs member by member: no batch_size", "batch_size"
            )
        return _in_threads(whole, list(range(len(members))), threads, on_member)

    cases: dict[int, Case] = {}
    outcomes: dict[int, Outcome] = {}
    clock = time.perf_counter()
    shared = same_start
    swap = None
    first_setup = None
    for i, m in enumerate(members):
        try:
            if shared and first_setup is not None:
                shared = first_value._shares_setup(first_setup)
            if shared and cases:
                require_masses(m)
                first = cases[next(iter(cases))]
                swap = swap or model_swapper(first.problem)
                cases[i] = dataclasses.replace(first, problem=swap(m))
            elif shared and outcomes:  # the shared start could not be made
                outcomes[i] = outcomes[next(iter(outcomes))]
                if on_member is not None:
                    on_member(i)
            else:
                setup = setup_of(i)
                first_setup = first_setup or setup
                cases[i] = values[i]._case(setup, t)
        except ModelError as err:
            raise _input_error(err, offset + i, describe(i)) from None
        except MixdynError as err:  # a start that cannot be made: this member fails
            outcomes[i] = (None, err)
            if on_member is not None:
                on_member(i)
    if seconds is not None:
        seconds["setup"] = time.perf_counter() - clock
    if cases:
        k0 = next(iter(cases))
        first = cases[k0]
        tree = jax.tree.structure(first.problem)
        for i, c in cases.items():
            if jax.tree.structure(c.problem) != tree or c.options != first.options:
                raise ModelError(
                    f"member {i} differs from member {k0} in structure (its bodies, elements, "
                    "kinds of laws or constraint rows): a sweep varies numbers only",
                    "models",
                )
        order = list(cases)
        if batch_size is None and _default_batch_size() is None:
            done = _in_threads(
                lambda i: _finish(cases[i], integrate(cases[i])), order, threads, on_member
            )
        else:
            done = _batched([cases[i] for i in order], batch_size or _default_batch_size(), seconds)
            if on_member is not None:
                for i in order:
                    on_member(i)
        outcomes.update(zip(order, done, strict=True))
    return [outcomes[i] for i in range(len(members))]


def _run_chunk(members: list[Model], t, analysis: Analysis, recorded, first: int):
    """On a worker: set up and run ``members`` (the sweep's members ``first``...) member by
    member in one thread; an input error names its member."""
    return run_members(members, t, analysis, recorded=recorded, threads=1, offset=first)


def _on_cluster(client, members, t, analysis, recorded, chunk_size, on_member=None):
    """The members run on a Dask ``client``'s workers, ``chunk_size`` at a time (default:
    four chunks per worker thread), gathered in order; ``on_member(i)`` for each member of a
    chunk as the chunk comes back."""
    if chunk_size is None:
        slots = sum(client.nthreads().values()) or 1
        chunk_size = max(1, -(-len(members) // (4 * slots)))
    starts = range(0, len(members), chunk_size)
    futures = [
        client.submit(_run_chunk, members[s : s + chunk_size], t, analysis, recorded, s, pure=False)
        for s in starts
    ]
    if on_member is not None:
        from distributed import as_completed

        first = {f.key: s for f, s in zip(futures, starts, strict=True)}
        for done in as_completed(futures):
            s = first[done.key]
            for i in range(s, min(s + chunk_size, len(members))):
                on_member(i)
    out = []
    for chunk in client.gather(futures):
        out.extend(chunk)
    return out


def sweep(
    model: Model | None = None,
    t=None,
    *,
    vary: Mapping[str, Sequence] | None = None,
    models: Sequence[Model] | None = None,
    analysis: Analysis | str | None = None,
    batch_size: int | None = None,
    threads: int | None = None,
    client=None,
    chunk_size: int | None = None,
    on_member: Callable[[int], None] | None = None,
    **kwargs,
) -> Sweep:
    """Run one analysis over many variants of a mechanism, compiled once.

    Args:
        model: the nominal mechanism, whose numbers ``vary`` replaces member by member.
        t: (N,) output times [time], shared by every member.
        vary: path -> values, one value (or row) per member, e.g.
            ``{"slider.mass": [1, 2, 3], "F1.law.a": [10, 10, 20]}`` (three members); a path
            names a body or element and a numeric field (model units), the fields of a law
            included (:mod:`mixdyn.paths`); :func:`grid` makes every combination of per-axis
            values, :func:`latin_hypercube` a random spread over a box.
        models: instead of ``model`` and ``vary``: the member models themselves, all of one
            structure (the same bodies, elements and kinds of laws; any numbers).
        analysis: the analysis value, the same for every member (:mod:`mixdyn.analyses`):
            ``Forward(...)`` (default: ``Forward()``), ``Mixed(...)``, ``Kinematic(...)``,
            ``Inverse(...)`` or ``QuasiStatic(...)``, e.g.
            ``analysis=md.analyses.Forward(method=md.Projection(rtol=1e-10))``.
        batch_size: None (default): on a CPU member by member, each by the single run's
            program (compiled once), from ``threads`` threads; on an accelerator up to
            :data:`ACCELERATOR_BATCH` (32,768) members at a time. A
            number (forward and mixed sweeps): every member integrated by one program,
            ``batch_size`` members at a time vectorized (``vmap``): on a CPU faster once
            compiled (8.4 ms a member against 13.4 ms member by member, 128 members of the
            paper's model; ``benchmarks/sweep.py``), but compiled per number of members.
        threads: threads of the member-by-member path (default: one per core).
        client: a Dask ``distributed.Client``: the members run on its workers (each sets up
            and runs its chunk member by member; a local cluster,
            ``Client(LocalCluster(n_workers=2, threads_per_worker=1))``, or a scheduler's
            address for a real one). Results come back in order; a member's input error is
            raised with its index.
        chunk_size: members per task on the cluster (default: four tasks per worker
            thread).
        on_member: called with a member's index as it is done (from the sweep's threads; on
            a cluster, for each member of a chunk as the chunk comes back), e.g. to advance a
            progress bar.
        **kwargs: deprecated (a DeprecationWarning names the value to give instead): the
            analysis' keywords (``method``, ``rtol``, ``prescribed``, ``unknown``, ``q0``...)
            with ``analysis`` an analysis' name (``"forward"``, ``"mixed"``,
            ``"kinematic"``, ``"inverse"`` or ``"statics"``, the quasi-static analysis).

    Returns:
        A :class:`Sweep`: per member a :class:`~mixdyn.Result` equal to the single run's, or
        its named error (``Sweep.errors``: a member's numerical failure, its start that cannot
        be assembled included, does not stop the others).

    Raises:
        ModelError: a bad path or value (before any computing), members of different
            structures, or a member's input error (named with the member's index).
    """
    started = time.perf_counter()
    if "progress" in kwargs:
        raise ModelError("a sweep has no per-time progress callback (see on_member)", "progress")
    if t is None:
        raise ModelError("give the output times t", "t")
    value, recorded = study_analysis("md.sweep", analysis, t, kwargs)
    if models is not None:
        if model is not None or vary is not None:
            raise ModelError("give either models=[...] or a model with vary=, not both", "models")
        members, params = list(models), []
        if not members:
            raise ModelError("models is empty", "models")
    else:
        if model is None:
            raise ModelError("give a model and vary=, or models=[...]", "model")
        members = vary_models(model, vary or {})
        params = [
            {p: (v[i].item() if np.ndim(v[i]) == 0 else v[i].tolist()) for p, v in _rows(vary)}
            for i in range(len(members))
        ]
    if client is not None:
        if not value.integrated:
            raise ModelError(f"a {value.name} sweep runs in this process: no client", "client")
        outcomes = _on_cluster(client, members, t, value, recorded, chunk_size, on_member)
        results = [r for r, _ in outcomes]
        errors = {i: e for i, (_, e) in enumerate(outcomes) if e is not None}
        return Sweep(results, errors, params, {"cluster": time.perf_counter() - started})
    seconds: dict[str, float] = {}
    same_start = (
        models is None and value.integrated
        and shares_start(model, vary or {}, value._start_forces())
    )  # fmt: skip
    outcomes = run_members(
        members,
        t,
        value,
        recorded=recorded,
        batch_size=batch_size,
        threads=threads,
        on_member=on_member,
        describe=lambda i: _describe(params, i),
        same_start=same_start,
        seconds=seconds,
    )
    results = [r for r, _ in outcomes]
    errors = {i: e for i, (_, e) in enumerate(outcomes) if e is not None}
    seconds["total"] = time.perf_counter() - started
    return Sweep(results, errors, params, seconds)


def _describe(params, i) -> str:
    if not params:
        return ""
    return " (" + ", ".join(f"{k} = {v}" for k, v in params[i].items()) + ")"


def _rows(vary):
    return [(p, np.asarray(v, dtype=float)) for p, v in vary.items()]


__all__ = [
    "Sweep",
    "grid",
    "latin_hypercube",
    "run_members",
    "sweep",
    "vary_models",
]
