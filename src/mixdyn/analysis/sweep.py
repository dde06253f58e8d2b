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

Members that share one start and are integrated by one program (a ``batch_size``, an
accelerator, or on a CPU at least :data:`~._schedule.CHUNK` members, run that many a call)
are held as arrays (:mod:`._stacked`): one set-up, one stacked problem, the members screened
at once, each member's :class:`~.result.Result` built when it is read.

A kinematic sweep of at least :data:`~._schedule.CHUNK` members (or on an accelerator) is
held as arrays too (:mod:`._kinematic_members`): each member prepared like a single run (its
own start), their constraint sets stacked, one vectorized program running the single run's
scan. A quasi-static sweep of as many members is held as arrays (:mod:`._static_members`:
one vectorized program making each member's start as its set-up makes it, or, where only
masses, inertias and forces vary, every member from member 0's start, and running the
single run's Newton iterations at every output time). An inverse sweep of members sharing
the drivers' motion is held as arrays (member 0 run, every member post-processed along its
motion). Other inverse, kinematic and quasi-static sweeps prepare and run the single analysis member
by member (its programs are compiled for the first member and reused), from a thread per
core.

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
import warnings
from collections.abc import Callable, Mapping, Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import paths
from ..errors import MixdynError, ModelError
from ..model import Model
from . import _kinematic_members, _members, _stacked, _static_members
from ._cluster import _on_cluster
from ._keywords import member_values, study_analysis
from ._members import model_swapper as model_swapper
from ._schedule import ACCELERATOR_BATCH as ACCELERATOR_BATCH
from ._schedule import CHUNK, _default_batch_size
from ._schedule import for_batch as for_batch
from ._setup import Analysis
from .result import Result


def grid(**axes: Sequence[float]) -> dict[str, np.ndarray]:
    """Every combination of the values of ``axes`` (path -> values), as the flat columns of
    a ``vary=`` mapping (the first axis varies slowest), e.g.
    ``md.grid(**{"slider.mass": [1, 2], "F1.law.a": [5, 10, 20]})`` gives 6 members."""
    names = list(axes)
    combos = list(itertools.product(*(np.asarray(axes[n], dtype=float) for n in names)))
    return {n: np.asarray([c[k] for c in combos]) for k, n in enumerate(names)}


#: The most samples :func:`latin_hypercube` draws (80 MB a range).
MAX_SAMPLES = 10_000_000


def _bytes(n: float) -> str:
    """``n`` bytes in binary units (``7.28 TiB``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} PiB"  # pragma: no cover


def latin_hypercube(samples: int, seed: int = 0, **ranges: Sequence[float]) -> dict:
    """``samples`` members spread over the box ``ranges`` (path -> ``(low, high)``) by Latin
    hypercube sampling: each range cut into ``samples`` equal strata, each stratum sampled once
    (uniformly within it) per path, the strata of different paths paired at random
    (``numpy.random.default_rng(seed)``: the same seed, the same members). Returns the flat
    columns of a ``vary=`` mapping, e.g. ``md.latin_hypercube(100, **{"slider.mass": (1, 2)})``.
    At most :data:`MAX_SAMPLES` samples.
    """
    whole = isinstance(samples, int | np.integer | float | np.floating) and float(samples) >= 1
    if not whole or not float(samples).is_integer():
        raise ModelError(f"samples must be a whole number >= 1, got {samples!r}", "samples")
    if not ranges:
        raise ModelError("give at least one range: path=(low, high)", "ranges")
    if samples > MAX_SAMPLES:
        size = 8 * float(samples) * len(ranges)
        raise ModelError(
            f"{samples:,.0f} samples of {len(ranges)} range(s) would take {_bytes(size)} "
            f"(8 bytes a value), more than the limit of {MAX_SAMPLES:,} samples; a sweep "
            "runs each sample: give fewer",
            "samples",
        )
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
    (:func:`~._members.run_members`)."""
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
    positions, values, count = varied_leaves(model, vary)
    leaves, treedef = jax.tree_util.tree_flatten(model)
    members = []
    for i in range(count):
        row = list(leaves)
        for k, v in zip(positions, values, strict=True):
            row[k] = jnp.asarray(v[i])
        members.append(jax.tree_util.tree_unflatten(treedef, row))
    if any(path.split(".")[1] == "q0" for path in vary):
        # The elements' constants that come from the bodies' start (a gear mesh's phase, a
        # rolling disk's side) follow a member's start: its elements bound to it again.
        members = [paths.bound_again(m) for m in members]
    return members


def varied_leaves(
    model: Model, vary: Mapping[str, Sequence]
) -> tuple[list[int], list[np.ndarray], int]:
    """``vary`` checked (paths, shapes, finite values, the owners' own checks) as
    ``(positions, values, B)``: each varied number's index among ``model``'s leaves, its
    (B, ...) values, the number of members."""
    if not isinstance(vary, Mapping):
        raise ModelError(
            f"vary must be a mapping path -> values, got {type(vary).__name__} {vary!r:.60}",
            "vary",
        )
    if not vary:
        raise ModelError("nothing to vary: give vary={'body.mass': [...], ...}", "vary")
    getters, values, count = [], [], None
    for path, vals in vary.items():
        if not isinstance(path, str):
            raise ModelError(f"a path is a string such as 'slider.mass', got {path!r}", "vary")
        get, shape = paths.getter(model, path)
        try:
            if isinstance(vals, str | bytes):
                raise ValueError(vals)
            v = np.asarray(vals, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(
                f"values {vals!r:.60}: give numbers, one value (or row) per member",
                f"vary {path!r}",
            ) from None
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
    # Each member's numbers meet the checks of a model built with them (their owners'
    # constructors): a value a model file refuses is refused here, naming its member.
    paths.check(model, dict(zip(vary, values, strict=True)))
    # Each varied number's position among the model's leaves (found by putting a marker
    # there): a member is the nominal leaves with its numbers, one unflatten
    # (vary_models) instead of a tree_at per member and number (5 ms a member), or a
    # column of the stacked problem (._stacked).
    positions = []
    for get in getters:
        marker = _Marker()
        marked = jax.tree_util.tree_leaves(eqx.tree_at(get, model, marker))
        positions.append(next(k for k, leaf in enumerate(marked) if leaf is marker))
    return positions, values, count


class _Marker:
    """A leaf put where a varied number sits (:func:`vary_models`)."""


@dataclasses.dataclass
class Sweep:
    """The members of a sweep, in order.

    Where the members share one start (only masses, inertias and forces vary) and are
    integrated by one vectorized program, or a kinematic or quasi-static sweep's members
    are run by one vectorized program, the sweep is held as arrays (member × time): a
    member's :class:`~mixdyn.Result` is built when it is first read (``sweep[i]``,
    ``sweep.results[i]``, iteration), and :meth:`columns` and :meth:`dataset` read every
    member at once.

    Attributes:
        results: per member its :class:`~mixdyn.Result`, or None where it failed (a
            sequence; on the array path each result built when read).
        errors: member index -> the named error of a failed member.
        parameters: member index -> the varied values (path -> value), empty for ``models=``.
        seconds: wall times [s]: ``total``; in process also ``setup`` (every member's start;
            one shared start when only masses, inertias and forces vary) and, on the
            vectorized path, ``integration`` (the one program; a quasi-static sweep's:
            ``equilibria``) and ``finishing``.
        stacked: on the array path, the members as one problem with a member axis
            (:class:`~._stacked.Stacked`; a kinematic sweep's:
            :class:`~._kinematic_members.KinematicStack`; a quasi-static sweep's:
            :class:`~._static_members.StaticStack`); else None.
        arrays: on the array path, every member's trajectory and post-processing's arrays
            (:class:`~._stacked.Arrays`, leading axis: the member; a kinematic or
            quasi-static sweep's arrays are its ``stacked``'s); else None.
        values: on the array path, the varied values (path -> (M,) or (M, ...) [model
            units]), the coordinates of :meth:`dataset`.
    """

    results: Sequence[Result | None]
    errors: dict[int, MixdynError]
    parameters: list[dict[str, float | list]]
    seconds: dict[str, float]
    stacked: (
        _stacked.Stacked | _kinematic_members.KinematicStack | _static_members.StaticStack | None
    ) = dataclasses.field(default=None, repr=False)
    arrays: _stacked.Arrays | None = dataclasses.field(default=None, repr=False)
    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, i: int) -> Result:
        """Member ``i``'s result; a failed member raises its error."""
        if i in self.errors:
            raise self.errors[i]
        return self.results[i]

    def columns(
        self, output_units: dict | None = None, points: Sequence[str] = ()
    ) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """Every result column of every member as NumPy arrays, ``(columns, units)``: ``t``
        (N,), every other column (M, N) on (member, time), a failed member's rows NaN, with
        each point reference of ``points``' global position, velocity and acceleration
        (``coupler.P.x``, ``.vx``, ``.ax``...: :meth:`mixdyn.Result.point`), in
        ``output_units`` (kind -> unit, as :meth:`mixdyn.Result.table`; default the
        model's units), the units named as :meth:`mixdyn.Result.units`. On the array path
        read from the members' arrays at once; otherwise gathered from the results.

        Raises:
            ValueError: no member succeeded (nothing gives the output times and columns).
        """
        if self.stacked is not None:
            return self.stacked.columns(
                self.arrays, self.results, self.errors, output_units, points
            )
        from .result import in_units, point_columns

        first = next((r for r in self.results if r is not None), None)
        if first is None:
            raise ValueError("no member of the sweep succeeded: there is nothing to label")
        cols0, units = in_units(first, *point_columns(first, points), output_units)
        out = {c: np.full((len(self.results), len(first.t)), np.nan) for c in cols0 if c != "t"}
        for i, res in enumerate(self.results):
            if res is not None:
                cols, _ = in_units(res, *point_columns(res, points), output_units)
                for c in out:
                    out[c][i] = cols[c]
        return {"t": np.asarray(cols0["t"]), **out}, units

    def table(self, columns: Sequence[str] = (), output_units: dict | None = None):
        """A long-format pandas DataFrame: one row per (member, output time), with the member
        index, its varied values, ``t`` and the result ``columns`` (default: every column),
        in ``output_units`` (kind -> unit, as :meth:`mixdyn.Result.table`; default the
        model's units); the units in ``df.attrs["units"]`` (engineering labels, as
        :meth:`mixdyn.Result.table`). Failed members have no rows."""
        import pandas as pd

        from ..units import engineering
        from .result import in_units

        if self.stacked is not None and len(self.errors) < len(self):
            return self._table(columns, output_units)
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
        out.attrs["units"] = {c: engineering(u) for c, u in units.items() if c in out.columns}
        return out

    def _table(self, columns: Sequence[str], output_units: dict | None):
        """:meth:`table` from the members' arrays (:meth:`columns`), at once."""
        import pandas as pd

        from ..units import engineering

        cols, units = self.columns(output_units)
        keep = ["t", *columns] if columns else list(cols)
        for c in keep:
            if c not in cols:
                next(r for r in self.results if r is not None)[c]  # names the close columns
        ok = np.array([i for i in range(len(self)) if i not in self.errors])
        n = len(cols["t"])
        data = {"member": np.repeat(ok, n)}
        for name, v in self.values.items():
            data[name] = (
                np.repeat(v[ok], n)
                if v.ndim == 1
                else [str(r.tolist()) for r in v[ok] for _ in range(n)]
            )
        data["t"] = np.tile(cols["t"], len(ok))
        data.update({c: cols[c][ok].reshape(-1) for c in keep if c != "t"})
        out = pd.DataFrame(data)
        out.attrs["units"] = {c: engineering(u) for c, u in units.items() if c in out.columns}
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

        cols0, units = self.columns(output_units)
        names = [c for c in (columns or cols0) if c != "t"]
        for c in names:
            if c not in cols0:
                first = next(r for r in self.results if r is not None)
                first[c]  # the error names the columns close to it
        n = len(self.results)
        coords = {
            "member": np.arange(n),
            "t": ("t", np.asarray(cols0["t"]), {"units": units["t"]}),
            "status": ("member", [type(self.errors[i]).__name__ if i in self.errors else "ok"
                                  for i in range(n)]),
        }  # fmt: skip
        if self.values and all(np.ndim(v) == 1 for v in self.values.values()):
            coords.update({name: ("member", v) for name, v in self.values.items()})
        elif self.parameters and all(np.ndim(v) == 0 for v in self.parameters[0].values()):
            for name in self.parameters[0]:
                coords[name] = ("member", np.array([float(p[name]) for p in self.parameters]))
        variables = {c: (("member", "t"), cols0[c], {"units": units.get(c, "")}) for c in names}
        if self.stacked is not None:
            model, kind = self.stacked.model, self.stacked.kind
        else:
            first = next(r for r in self.results if r is not None)
            model, kind = first.model, first.kind
        return xr.Dataset(variables, coords=coords, attrs={"model": model.name, "analysis": kind})

    def to_xarray(self, columns: Sequence[str] = (), output_units: dict | None = None):
        """:meth:`dataset`: the sweep as an xarray ``Dataset`` on (member, t)."""
        return self.dataset(columns, output_units)


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
            program (compiled once), from ``threads`` threads, but for at least
            :data:`~._schedule.CHUNK` (64) members sharing one start (:func:`shares_start`),
            which run that many at a time in one vectorized program (one shape for any
            count); on an accelerator up to
            :data:`~._schedule.ACCELERATOR_BATCH` (32,768) members at a time. A
            number (forward and mixed sweeps): every member integrated by one program,
            ``batch_size`` members at a time vectorized (``vmap``): on a CPU faster once
            compiled (8.4 ms a member against 13.4 ms member by member, 128 members of the
            paper's model; ``benchmarks/sweep.py``), but compiled per number of members.
        threads: threads of the member-by-member path (default: one per core).
        client: a Dask ``distributed.Client``: the members run on its workers (each sets up
            and runs its chunk member by member, its members sharing one start where the
            in-process sweep's do; a local cluster,
            ``Client(LocalCluster(n_workers=2, threads_per_worker=1))``), or a scheduler's
            address (``"tcp://host:8786"``: connected within 5 s, else a ModelError).
            Results come back in order; a member's input error is raised with its index.
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
    counts = {"batch_size": batch_size, "threads": threads, "chunk_size": chunk_size}
    for name, count in counts.items():
        if count is not None and (not isinstance(count, int | np.integer) or count < 1):
            raise ModelError(f"{name} must be a whole number >= 1 or None, got {count!r}", name)
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
        positions, values, count = varied_leaves(model, vary or {})
        params = _parameters(list(vary), values, count)
    same_start = (
        models is None and value.integrated
        and shares_start(model, vary or {}, value._start_forces())
    )  # fmt: skip
    if (
        same_start
        and client is None
        and (batch_size is not None or _default_batch_size() is not None or count >= CHUNK)
    ):
        done = as_arrays(model, list(vary), positions, values, value, t, recorded, batch_size,
                         on_member, params, started)  # fmt: skip
        if done is not None:
            return done
    if (
        models is None
        and value.name == "inverse"
        and client is None
        and batch_size is None
        and (count >= CHUNK or _default_batch_size() is not None)
        and shares_start(model, vary)
    ):
        done = as_arrays(model, list(vary), positions, values, value, t, None, None,
                         on_member, params, started, driven=True)  # fmt: skip
        if done is not None:
            return done
    shared = value.name == "quasi-static" and models is None and shares_start(model, vary)
    if shared:  # made when read (no member's start depends on its numbers)
        members = _static_members.VariedModels(model, positions, values)
    elif models is None:
        members = vary_models(model, vary)
    if (
        value.name in ("kinematic", "quasi-static")
        and client is None
        and batch_size is None
        and (len(members) >= CHUNK or _default_batch_size() is not None)
    ):
        seconds = {}
        if value.name == "kinematic":
            held = _kinematic_members.run
        else:  # the start of an equilibrium does not see masses, inertias or forces
            held = functools.partial(_static_members.run, shared=shared, seconds=seconds)
        made = held(
            members, value, t, threads or os.cpu_count() or 1, on_member,
            lambda i: _describe(params, i),
        )  # fmt: skip
        if made is not None:
            stack, results, errors = made
            named = {} if models is not None else dict(zip(vary, values, strict=True))
            seconds["total"] = time.perf_counter() - started
            return Sweep(results, errors, params, seconds, stack, None, named)
    if client is not None:
        if not value.integrated:
            raise ModelError(f"a {value.name} sweep runs in this process: no client", "client")
        outcomes = _on_cluster(
            client, members, t, value, recorded, chunk_size, on_member, same_start
        )
        results = [r for r, _ in outcomes]
        errors = {i: e for i, (_, e) in enumerate(outcomes) if e is not None}
        return Sweep(results, errors, params, {"cluster": time.perf_counter() - started})
    seconds: dict[str, float] = {}
    outcomes = _members.run_members(
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


def run_members(
    members: Sequence[Model],
    t,
    analysis: Analysis | str,
    kwargs_of: Callable[[int], dict] | None = None,
    **options,
):
    """Deprecated: :func:`sweep` with ``models=`` and the analysis value runs members
    (``md.sweep(models=[...], t=t, analysis=md.analyses.Forward(...))``, a DeprecationWarning
    says so). Each member's ``(Result, None)`` or ``(None, its numerical error)``, in order.

    Args:
        members: the member models, of one structure.
        t: (N,) output times [time].
        analysis: the analysis value; or an analysis' name (``"forward"``, ``"mixed"``,
            ``"kinematic"``, ``"inverse"``, ``"statics"``) with ``kwargs_of(i)`` member
            ``i``'s keywords.
        kwargs_of: member index -> the analysis' keywords for it (with a name only).
        **options: ``batch_size``, ``threads``, ``on_member``, ``describe``, ``offset``,
            ``same_start``, ``seconds``, as the sweep takes them.
    """
    warnings.warn(
        "mixdyn.analysis.sweep.run_members is deprecated: run the members with "
        "mixdyn.sweep(models=[...], t=t, analysis=mixdyn.analyses.Forward(...))",
        DeprecationWarning,
        stacklevel=2,
    )
    if not isinstance(analysis, Analysis):
        kwargs = [kwargs_of(i) for i in range(len(members))]
        describe = options.get("describe", lambda i: "")
        analysis, options["recorded"] = member_values(
            analysis, t, kwargs, describe, options.get("offset", 0)
        )
    return _members.run_members(members, t, analysis, **options)


def _parameters(names: list[str], values: list[np.ndarray], count: int) -> list[dict]:
    """Each member's varied values, path -> a float (or a list for a row)."""
    columns = [v.tolist() for v in values]
    return [{p: c[i] for p, c in zip(names, columns, strict=True)} for i in range(count)]


def as_arrays(
    model,
    names,
    positions,
    values,
    value,
    t,
    recorded,
    batch_size,
    on_member,
    params,
    started,
    driven: bool = False,
    named: dict[str, np.ndarray] | None = None,
) -> Sweep | None:
    """The sweep of members sharing one start as arrays (:mod:`._stacked`): member 0 set
    up, every member integrated by one vectorized program (``driven``, an inverse sweep:
    member 0 run, every member post-processed along its motion), screened at once, each
    result built when read; None where the members cannot share the set-up (then member by
    member).

    Args:
        model: the nominal model.
        names, positions, values: per varied leaf, a name (a body's ``"slider.mass"``
            gives its members' masses), its index among ``model``'s leaves and its (M, ...)
            values [model units].
        value, t, recorded: the analysis value, the output times (N,) [time], the
            integrator options the results record (None: the value's own).
        batch_size, on_member: as :func:`sweep` takes them.
        params: per member, its varied values (:attr:`Sweep.parameters`).
        started: the sweep's start (``time.perf_counter()``) [s].
        named: the varied values, name -> (M,) or (M, ...) (:attr:`Sweep.values`; default
            ``names`` with ``values``).
    """
    clock = time.perf_counter
    seconds: dict[str, float] = {}
    first = None
    try:
        if driven:
            made = _stacked.stack_driven(model, names, positions, values, value, t)
            stacked, first = made if made is not None else (None, None)
        else:
            stacked = _stacked.stack(model, names, positions, values, value, t, recorded)
    except ModelError:
        raise  # an input error: refused, named
    except MixdynError as err:  # the shared start cannot be made: every member fails
        n = len(values[0])
        errors = dict.fromkeys(range(n), err)
        for i in range(n) if on_member is not None else ():
            on_member(i)
        seconds["total"] = clock() - started
        return Sweep([None] * n, errors, params, seconds)
    if stacked is None:
        return None
    seconds["setup"] = clock() - started
    results, errors, arrays = _stacked.run(stacked, batch_size, on_member, seconds, clock, first)
    seconds["total"] = clock() - started
    if named is None:
        named = {p: v for p, v in zip(names, values, strict=True)}
    return Sweep(results, errors, params, seconds, stacked, arrays, named)


def _describe(params, i) -> str:
    if not params:
        return ""
    return " (" + ", ".join(f"{k} = {v}" for k, v in params[i].items()) + ")"


__all__ = [
    "Sweep",
    "grid",
    "latin_hypercube",
    "run_members",
    "sweep",
    "vary_models",
]
