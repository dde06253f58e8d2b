"""Sweep runs of a model file: another run repeated over many values of some numbers.

A sweep run names the run it sweeps (``run:``), what changes (``vary:``: file parameters, or
numbers of bodies and elements such as ``slider.mass``), how members are sampled (``grid``:
every combination; ``latin_hypercube``: ``samples`` members spread over the spans), numbers per
member (``summaries:``) and its figures. Member ``i`` is the swept run of the file with member
``i``'s numbers: the model built again from the file with its parameters (so every quantity
written with a parameter follows it: laws, masses, points, start values), the numbers of
bodies and elements replaced, set up exactly as the single run would be; the members run as
one :func:`mixdyn.analysis._members.run_members` (one compiled program for all). Where the
varied numbers reach only forces and bodies' masses and inertias, only those parts are built
again (:mod:`.sweep_members`: the same numbers) and the members share one start; where they
also run as one vectorized program (the file's ``batch_size``, or at least
:data:`~mixdyn.analysis._schedule.CHUNK` members) the sweep is held as arrays, as
:func:`mixdyn.sweep` holds it (:func:`_as_arrays`: one set-up, one stacked problem), and its
tables, summaries and bands are read from the arrays, no member's result built. A kinematic
or quasi-static (``statics``) sweep of at least that many members is held as arrays too
(:func:`_prepared_arrays`: each member prepared like its single run, or a quasi-static
sweep's members from one start where its varied numbers reach only forces, masses and
inertias; one vectorized program running the scan or the equilibria).

Example (``examples/antonya_sweep.yaml``)::

    - name: sweep
      kind: sweep
      run: forward
      vary:
        F0: {span: [5, 15], n: 40}
        m5: {span: [0.004, 0.012], n: 25}
      summaries:
        - {name: x_peak, column: slider.x, reduce: max}
      plots:
        - {file: peak.png, x: F0, y: x_peak, by: m5}
        - {file: band.png, band: slider.x}

``mixdyn run`` writes, per sweep, ``members.csv`` (a row per member: index, varied values,
``status`` ``ok`` or the error's class, the error, the summaries), ``table.csv`` (long
format: a row per member and output time with the ``outputs`` columns), the plots and
``meta.json`` (units, settings, timings). The varied values are in the model's units; the
summaries and table columns in the file's ``output_units`` where it gives them.
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
import re
import time
from collections.abc import Callable

import numpy as np

from .. import paths
from ..analysis import _kinematic_members, _static_members
from ..analysis._keywords import from_keywords, member_values
from ..analysis._members import run_members
from ..analysis._schedule import CHUNK, _default_batch_size
from ..analysis.sweep import Sweep, as_arrays, grid, latin_hypercube, shares_start
from ..errors import MixdynError, ModelError
from ..io import schema as s
from ..io._errors import FileError
from ..io.load import Builder
from . import checks, setup
from .console import esc
from .kinds import RunKind, register
from .plan import Plan, number_kind, study_base, times
from .runner import Runner
from .sweep_members import chunk_size, in_chunks, quick_members

#: Most members a sweep may have.
MAX_MEMBERS = 1_000_000


@dataclasses.dataclass(frozen=True)
class SweepPlan(Plan):
    """A checked sweep run.

    Attributes:
        values: varied name -> (M,) its value for each member [model units]; ``base`` is
            the plan of the run swept.
        member_times: each member's output times, where the swept run's ``time`` is written
            with a swept parameter and they differ between members; None: every member
            has the swept run's times (``times``).
        value_units: varied name -> the model's unit of its values (pint spelling; ``""``
            for a plain number: a parameter without a unit, a law's number).
    """

    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    member_times: tuple[np.ndarray, ...] | None = None
    value_units: dict[str, str] = dataclasses.field(default_factory=dict)

    def times_of(self, i: int) -> np.ndarray:
        """Member ``i``'s output times [model time unit]: the swept run's, or its own where
        the swept run's ``time`` is written with a swept parameter (:attr:`member_times`)."""
        return self.times if self.member_times is None else self.member_times[i]

    @property
    def spec_outputs(self) -> list[str]:
        """The columns of the long table (:func:`outputs_of`)."""
        return outputs_of(self.spec)

    @property
    def members(self) -> int:
        return len(next(iter(self.values.values())))

    def describe(self, i: int) -> str:
        """Member ``i``'s values in words."""
        return ", ".join(f"{k} = {v[i]:.6g}" for k, v in self.values.items())


@dataclasses.dataclass
class FileSweep:
    """The result of a sweep run.

    Attributes:
        plan: the sweep's plan.
        sweep: the members' results and errors (:class:`mixdyn.Sweep`).
        summaries: summary name -> (M,) its value per member (NaN for a failed member).
        units: unit of each summary and output column (pint spelling).
        seconds: wall time of building the members and of running them [s].
        output_units: kind -> unit of the summaries and table columns (the file's
            ``output_units``; default the model's units).
    """

    plan: SweepPlan
    sweep: Sweep
    summaries: dict[str, np.ndarray]
    units: dict[str, str]
    seconds: dict[str, float]
    output_units: dict[str, str] = dataclasses.field(default_factory=dict)

    @property
    def kind(self) -> str:
        return "sweep"

    def members(self):
        """A pandas DataFrame, a row per member: ``member``, the varied values, ``status``
        (``ok`` or the error's class), ``error`` (its message), ``t_error`` (the time it
        failed at, if known) and the summaries; their units in :meth:`member_units`."""
        import pandas as pd

        n = self.plan.members
        data = {"member": np.arange(n)}
        data.update({k: np.asarray(v) for k, v in self.plan.values.items()})
        errors = self.sweep.errors
        data["status"] = [type(errors[i]).__name__ if i in errors else "ok" for i in range(n)]
        data["error"] = [_message(errors[i]) if i in errors else "" for i in range(n)]
        data["t_error"] = [_error_time(errors.get(i)) for i in range(n)]
        data.update(self.summaries)
        return pd.DataFrame(data)

    def member_units(self) -> dict[str, str]:
        """The unit of each column of :meth:`members` that has one (pint spelling): the
        varied values' in model units (:attr:`SweepPlan.value_units`), ``t_error`` in the
        model's unit of time, the summaries' in the file's ``output_units``."""
        model = next((r.model for r in self.sweep.results if r is not None), None)
        units = {k: u for k, u in self.plan.value_units.items() if u}
        if model is not None:
            units["t_error"] = model.units.label("time")
        units.update({x.name: self.units[x.name] for x in self.plan.spec.summaries})
        return {k: u for k, u in units.items() if u}

    def dataset(self):
        """The table's columns as an ``xarray.Dataset`` on (member, t) with the varied numbers
        and the status as coordinates, in the file's ``output_units``
        (:meth:`mixdyn.analysis.sweep.Sweep.dataset`); members at their own output times
        (:attr:`SweepPlan.member_times`): on (member, step), with ``t`` a coordinate on both
        (NaN past a member's last time)."""
        if self.plan.member_times is None:
            ds = self.sweep.dataset(self.plan.spec_outputs, self.output_units)
        else:
            ds = self._at_own_times()
        return ds.assign_coords(
            {name: ("member", np.asarray(v, dtype=float)) for name, v in self.plan.values.items()}
        )

    def _at_own_times(self):
        """The dataset of members at their own output times (see :meth:`dataset`)."""
        import xarray as xr

        names = [c for c in self.plan.spec_outputs if c != "t"]
        n, steps = self.plan.members, max(len(t) for t in self.plan.member_times)
        data = {c: np.full((n, steps), np.nan) for c in ("t", *names)}
        for i, res in enumerate(self.sweep.results):
            if res is not None:
                cols = _columns(res, names, self.output_units)
                for c, values in data.items():
                    values[i, : len(cols[c])] = cols[c]
        errors = self.sweep.errors
        status = [type(errors[i]).__name__ if i in errors else "ok" for i in range(n)]
        coords = {
            "member": np.arange(n),
            "step": np.arange(steps),
            "t": (("member", "step"), data["t"], {"units": self.units.get("t", "")}),
            "status": ("member", status),
        }
        variables = {
            c: (("member", "step"), data[c], {"units": self.units.get(c, "")}) for c in names
        }
        return xr.Dataset(variables, coords=coords, attrs={"model": self.plan.base.name})

    def table(self):
        """The long table: a row per member and output time, with the member index, its
        varied values, ``t`` and the ``outputs`` columns (failed members have no rows)."""
        import pandas as pd

        cols = _stacked_columns(self.sweep, self.plan.spec_outputs, self.output_units)
        if cols is not None:  # every member at once
            errors = self.sweep.errors
            ok = np.array([i for i in range(self.plan.members) if i not in errors])
            n = len(cols["t"])
            data = {"member": np.repeat(ok, n)}
            data.update(
                {
                    k: np.repeat(np.asarray(v, dtype=float)[ok], n)
                    for k, v in self.plan.values.items()
                }
            )
            data["t"] = np.tile(cols["t"], len(ok))
            data.update({c: cols[c][ok].reshape(-1) for c in cols if c != "t"})
            return pd.DataFrame(data)
        frames = []
        for i, res in enumerate(self.sweep.results):
            if res is None:
                continue
            cols = _columns(res, self.plan.spec_outputs, self.output_units)
            df = pd.DataFrame(cols)
            for k, (name, v) in enumerate(self.plan.values.items()):
                df.insert(k, name, float(v[i]))
            df.insert(0, "member", i)
            frames.append(df)
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def _message(err: MixdynError) -> str:
    return " ".join(str(getattr(err, "message", None) or err).split())


def _error_time(err) -> float:
    t = getattr(err, "time", None)
    return float(t) if t is not None else float("nan")


def _columns(result, names, output_units=None) -> dict[str, np.ndarray]:
    from ..io.results import in_units
    from ..viz.plots import result_columns

    cols, units = result_columns(result, list(names))
    return in_units(result, cols, units, output_units)[0]


# --------------------------------------------------------------------------- planning
def outputs_of(r: s.SweepRunSpec) -> list[str]:
    """The columns of the long table: ``outputs``, or the summaries' and bands' columns."""
    if r.outputs is not None:
        return list(dict.fromkeys(r.outputs))
    cols = [x.column for x in r.summaries] + [p.band for p in r.plots if p.band is not None]
    return list(dict.fromkeys(cols))


def plan(runner: Runner, index: int, r: s.SweepRunSpec) -> SweepPlan:
    """Check a sweep run against the file and its model; its members' values made."""
    path = ("runs", index)
    base = study_base(
        runner, index, r, ("kinematic", "statics", "forward", "inverse", "mixed"), "sweep"
    )
    axes, spans, value_units = {}, {}, {}
    for name, v in r.vary.items():
        vpath = (*path, "vary", name)
        kind = _check_name(runner, name, vpath)
        value_units[name] = _value_unit(runner, name, kind)
        read = _reader(runner, name, kind)
        if v.values is not None:
            vals = [read(x, (*vpath, "values", k)) for k, x in enumerate(v.values)]
            axes[name] = np.asarray(vals, dtype=float)
            continue
        lo = read(v.span[0], (*vpath, "span", 0))
        hi = read(v.span[1], (*vpath, "span", 1))
        if not hi > lo:
            runner.fail((*vpath, "span"), f"the span [{lo:g}, {hi:g}] is empty", "give [low, high]")
        spans[name] = (lo, hi)
        if v.n is not None:
            axes[name] = np.linspace(lo, hi, v.n)
    if r.sampling == "latin_hypercube":
        values = latin_hypercube(r.samples, r.seed, **spans)
    else:
        count = int(np.prod([len(a) for a in axes.values()], dtype=float))
        if count > MAX_MEMBERS:
            runner.fail((*path, "vary"), f"{count} members are too many", "sample fewer values")
        values = grid(**axes)
    _check_numbers(runner, path, values)
    member_times = _member_times(runner, path, base, values)
    names = set(r.vary)
    taken = {"member", "status", "error", "t_error", "t"}
    seen: set[str] = set()
    for k, x in enumerate(r.summaries):
        sp = (*path, "summaries", k)
        if x.name in names or x.name in taken or x.name in seen:
            runner.fail((*sp, "name"), f"the name {x.name!r} is taken", "rename the summary")
        seen.add(x.name)
        checks.check_column(runner, x.column, base.spec, (*sp, "column"))
    for k, col in enumerate(r.outputs or ()):
        checks.check_column(runner, col, base.spec, (*path, "outputs", k))
    for k, p in enumerate(r.plots):
        pp = (*path, "plots", k)
        if p.band is not None:
            checks.check_column(runner, p.band, base.spec, (*pp, "band"))
            if member_times is not None:
                runner.fail(
                    (*pp, "band"),
                    "a band needs every member at the same output times, and the members' "
                    f"times differ (run {base.name!r}'s time is written with a swept parameter)",
                    "plot a summary against the swept parameter instead",
                )
            continue
        for key in ("x", "by"):
            v = getattr(p, key)
            if v is not None and v not in names:
                runner.fail((*pp, key), f"{v!r} is not swept", f"swept: {', '.join(r.vary)}")
        if p.by is not None and p.by == p.x:
            runner.fail((*pp, "by"), "'by' repeats 'x'", "name another swept quantity")
        if p.y not in seen:
            known = ", ".join(seen) or "(none: add summaries)"
            runner.fail((*pp, "y"), f"{p.y!r} is not a summary", f"summaries: {known}")
    return SweepPlan(
        r,
        index,
        base.times,
        (),
        base=base,
        values=values,
        member_times=member_times,
        value_units=value_units,
    )


def _check_numbers(runner: Runner, path, values: dict[str, np.ndarray]) -> None:
    """Refuse a member whose body or element number (``slider.mass``) the model's
    constructors refuse (the check a file with that number meets,
    :func:`mixdyn.paths.check`), at the ``vary`` line of the number; members made from file
    parameters meet them when each is built from its file."""
    numbers = {k: v for k, v in values.items() if "." in k}
    try:
        paths.check(runner.model, numbers, where=lambda name: name)
    except ModelError as e:
        runner.fail((*path, "vary", e.element), e.message, "narrow the swept values")


#: A name in a file's text (a parameter is named like this in an expression or a quantity).
_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def _time_parameters(spec: s.ModelFile, time_spec) -> set[str]:
    """The file parameters a run's ``time`` is written with, directly or through other
    parameters."""
    known = set(spec.parameters)
    found = set(_NAME.findall(repr(time_spec.model_dump()))) & known
    todo = list(found)
    while todo:
        for name in set(_NAME.findall(str(spec.parameters[todo.pop()]))) & known - found:
            found.add(name)
            todo.append(name)
    return found


@dataclasses.dataclass(frozen=True)
class _Reader:
    """What :func:`.plan.times` reads a run's times with: a member's builder."""

    b: Builder

    def fail(self, path, problem, hint=""):
        self.b.fail(path, problem, hint)


def _member_times(runner: Runner, path, base: Plan, values: dict[str, np.ndarray]):
    """Each member's output times, where the swept run's ``time`` is written with a swept
    parameter and they differ between members (None: every member has the swept run's
    times); a member whose times are refused is named at the sweep's ``vary``."""
    reach = _time_parameters(runner.spec, base.spec.time) & set(values)
    if not reach:
        return None
    out = []
    for i in range(len(next(iter(values.values())))):
        params = {k: float(values[k][i]) for k in reach}
        spec = runner.spec.model_copy(update={"parameters": {**runner.spec.parameters, **params}})
        try:
            out.append(times(_Reader(Builder(spec)), base.spec.time, (*base.path, "time")))
        except FileError as e:
            shown = ", ".join(f"{k} = {v:.6g}" for k, v in params.items())
            runner.fail(
                (*path, "vary"),
                f"member {i} ({shown}): its output times are refused: {_message(e)}",
                "narrow the swept values",
            )
    if all(len(t) == len(base.times) and np.array_equal(t, base.times) for t in out):
        return None
    return tuple(out)


def _value_unit(runner: Runner, name: str, kind) -> str:
    """The model's unit of the values of a varied name (pint spelling; ``""``: plain
    numbers): a file parameter's by its own unit's dimension (an angle's: rad), a body's or
    element's number by its ``kind``."""
    from ..units import COMMON_UNITS, DIMENSIONS, kind_of, unit_for

    units = runner.model.units
    if "." in name:
        return units.label(kind) if kind is not None else ""
    p = runner.b.readings.parameters[name]
    if p.dim is None or any(e.denominator != 1 for e in p.dim):
        return ""
    exps = tuple(int(e) for e in p.dim)
    if not any(exps):
        angle = p.unit is not None and p.unit.strip() in (*COMMON_UNITS["angle"], "degree")
        return "rad" if angle else ""  # an angle in rad, a ratio as it is
    known = kind_of(exps)
    return units.label(known) if known in DIMENSIONS else unit_for(exps, units)


def _reader(runner: Runner, name: str, kind) -> Callable[[object, tuple], float]:
    """What reads the values of a varied name in model units: a file parameter's by the
    parameter's own units (:meth:`mixdyn.io.readings.Readings.parameter_value`), a body's
    or element's number by its ``kind`` of quantity."""
    if "." not in name:
        return lambda value, path: runner.b.readings.parameter_value(name, value, path)
    return lambda value, path: runner.b.scalar(value, kind, path)


def _check_name(runner: Runner, name: str, path) -> str | None:
    """The kind of quantity of a varied body's or element's number (None: model units of
    any kind, and for a file parameter: its values are read by its own units), checked."""
    if "." not in name:
        if name not in runner.b.parameters:
            known = ", ".join(runner.b.parameters) or "(the file has none)"
            runner.fail(
                path,
                f"no parameter {name!r}",
                f"parameters: {known}; a number of a body or element is named like 'slider.mass'",
            )
        return None
    try:
        _, shape = paths.getter(runner.model, name)
    except ModelError as e:
        runner.fail(path, str(e.args[0]), "name a number, e.g. slider.mass, or a file parameter")
    if shape != ():
        runner.fail(
            path,
            f"{name!r} holds {int(np.prod(shape))} numbers, not one",
            "put the number in a file parameter and vary the parameter",
        )
    return number_kind(runner, name)


# --------------------------------------------------------------------------- executing
def _member_runner(runner: Runner, plan: SweepPlan, i: int) -> Runner:
    """The runner of member ``i``: the file with its parameters, its model's numbers."""
    import equinox as eqx
    import jax.numpy as jnp

    params = {k: float(v[i]) for k, v in plan.values.items() if "." not in k}
    spec = runner.spec
    if params:
        spec = spec.model_copy(update={"parameters": {**spec.parameters, **params}})
        model = Builder(spec).model()
    else:
        model = runner.model
    for k, v in plan.values.items():
        if "." in k:
            get, _ = paths.getter(model, k)
            model = eqx.tree_at(get, model, jnp.asarray(float(v[i])))
    if not params:
        return Runner.member(spec, model, plan.base.name, like=runner)
    return Runner.member(spec, model, plan.base.name)


def _members_from_file(runner: Runner, plan: SweepPlan) -> tuple[str, list, list]:
    """``(analysis, models, keywords)``: every member's model and its run's keywords,
    built from its file."""
    models, kwargs, analysis = [], [], None
    for i in range(plan.members):
        try:
            member = _member_runner(runner, plan, i)
            analysis, model, kw = setup.call(
                member, member.plans[plan.base.name], {}, checked=False
            )
        except (FileError, ModelError) as e:
            runner.fail(
                (*plan.path, "vary"),
                f"member {i} ({plan.describe(i)}) cannot be built: {_message(e)}",
                "narrow the swept values",
            )
        models.append(model)
        kwargs.append(kw)
    return analysis, models, kwargs


def execute(runner: Runner, plan: SweepPlan, progress: Callable[[int], None] | None = None):
    """Run every member of a sweep; ``progress(i)`` as member ``i`` is done.

    The members' models are made from the swept run's model where the varied numbers reach
    only forces and bodies' masses and inertias (:func:`.sweep_members.quick_members`), and
    then share its start (:func:`mixdyn.analysis.sweep.shares_start`); else each is built
    from its file. The sweep is held as arrays where its members run as one vectorized
    program (:func:`_as_arrays`, :func:`_prepared_arrays`); else the members run by
    :func:`~mixdyn.analysis._members.run_members`."""
    r: s.SweepRunSpec = plan.spec
    started = time.perf_counter()
    analysis, model, kw = setup.call(runner, plan.base, {}, checked=False)
    quick = quick_members(runner, plan, model)
    same_start = False
    if quick is None:
        analysis, models, kwargs = _members_from_file(runner, plan)
    else:
        value, record = from_keywords(analysis, plan.times, kw)
        same_start = value.integrated and shares_start(
            model, dict.fromkeys(quick.reached), value._start_forces()
        )
        built = time.perf_counter()
        try:
            sweep = _as_arrays(plan, quick, value, record, same_start, progress, built)
        except ModelError as e:
            notes = " ".join(getattr(e, "__notes__", []))
            runner.fail((*plan.path, "vary"), f"{_message(e)} {notes}".strip(), "narrow the values")
        if sweep is not None:
            done = time.perf_counter()
            summaries, units = _summaries(runner, plan, sweep)
            seconds = {"build": built - started, "run": done - built}
            return FileSweep(plan, sweep, summaries, units, seconds, runner.output_units)
        if value.name == "quasi-static":  # each member's model made when read
            models = _static_members.VariedModels(quick.model, quick.positions, quick.values)
        else:
            models = quick.models
        kwargs = [kw] * plan.members
    built = time.perf_counter()
    try:

        def describe(i: int) -> str:
            return f" ({plan.describe(i)})"

        if plan.member_times is not None:
            outcomes = _at_own_times(plan, models, analysis, kwargs, describe, progress)
        else:
            values, recorded = member_values(analysis, plan.times, kwargs, describe)
            shared = quick is not None
            sweep = _prepared_arrays(plan, models, values, describe, progress, shared)
            if sweep is not None:
                sweep.seconds["total"] = time.perf_counter() - built
                summaries, units = _summaries(runner, plan, sweep)
                seconds = {"build": built - started, "run": sweep.seconds["total"]}
                return FileSweep(plan, sweep, summaries, units, seconds, runner.output_units)

            def run(idx: list[int], first: int = 0, batch_size=r.batch_size) -> list:
                def done(k: int) -> None:  # a chunk's filling (copies of idx[0]) not shown
                    if progress is not None and (k == 0 or idx[k] != idx[0]):
                        progress(idx[k])

                return run_members(
                    [models[i] for i in idx],
                    plan.times,
                    [values[i] for i in idx],
                    recorded=[recorded[i] for i in idx],
                    batch_size=batch_size,
                    on_member=done,
                    describe=lambda k: describe(idx[k]),
                    offset=first,
                    same_start=same_start,
                )

            size = chunk_size(r.batch_size, plan.members) if same_start else None
            if size is not None:
                outcomes = in_chunks(lambda idx, first: run(idx, first, size), plan.members, size)
            else:
                outcomes = run(list(range(plan.members)))
    except ModelError as e:
        notes = " ".join(getattr(e, "__notes__", []))
        runner.fail((*plan.path, "vary"), f"{_message(e)} {notes}".strip(), "narrow the values")
    done = time.perf_counter()
    results = [res for res, _ in outcomes]
    errors = {i: e for i, (_, e) in enumerate(outcomes) if e is not None}
    sweep = Sweep(results, errors, _params(plan), {"total": done - built})
    summaries, units = _summaries(runner, plan, sweep)
    seconds = {"build": built - started, "run": done - built}
    return FileSweep(plan, sweep, summaries, units, seconds, runner.output_units)


def _params(plan: SweepPlan) -> list[dict[str, float]]:
    """Each member's varied values, name -> value [model units]."""
    columns = {k: np.asarray(v, dtype=float).tolist() for k, v in plan.values.items()}
    return [{k: c[i] for k, c in columns.items()} for i in range(plan.members)]


def _as_arrays(
    plan: SweepPlan, quick, value, record, same_start: bool, progress, started: float
) -> Sweep | None:
    """The sweep held as arrays (:func:`mixdyn.analysis.sweep.as_arrays`: one set-up, one
    stacked problem, no member's model or result made before it is read) where the members
    run as one vectorized program: an integrated run whose members share one start, or an
    inverse run whose varied numbers reach only masses, inertias and forces (its members
    share its motion), at the file's ``batch_size`` or at least :data:`CHUNK` members (as
    :func:`mixdyn.sweep` takes the array path); None otherwise (then the members run by
    :func:`~mixdyn.analysis._members.run_members`)."""
    r: s.SweepRunSpec = plan.spec
    if plan.member_times is not None or not quick.positions:
        return None
    many = plan.members >= CHUNK or _default_batch_size() is not None
    driven = (
        value.name == "inverse"
        and r.batch_size is None
        and many
        and shares_start(quick.model, dict.fromkeys(quick.reached))
    )
    if not driven and not (same_start and (r.batch_size is not None or many)):
        return None
    return as_arrays(
        quick.model,
        list(quick.names),
        list(quick.positions),
        list(quick.values),
        value,
        plan.times,
        None if driven else record,
        None if driven else r.batch_size,
        progress,
        _params(plan),
        started,
        driven=driven,
        named=dict(plan.values),
    )


def _prepared_arrays(
    plan: SweepPlan, models, values, describe, progress, shared: bool
) -> Sweep | None:
    """A kinematic or quasi-static sweep held as arrays, each member prepared like its
    single run (:mod:`mixdyn.analysis._kinematic_members`,
    :mod:`mixdyn.analysis._static_members`: a quasi-static sweep's members from one start
    where ``shared``, its varied numbers reaching only masses, inertias and forces), one
    vectorized program running them, where it has at least :data:`CHUNK` members (or runs
    on an accelerator) and no ``batch_size``, as :func:`mixdyn.sweep` takes that path; None
    otherwise (then member by member)."""
    many = plan.members >= CHUNK or _default_batch_size() is not None
    held = {"kinematic": _kinematic_members.run, "quasi-static": _static_members.run}
    name = values[0].name
    if name not in held or plan.spec.batch_size is not None or not many:
        return None
    extra = {"shared": shared} if name == "quasi-static" else {}
    made = held[name](models, values, plan.times, os.cpu_count() or 1, progress, describe, **extra)
    if made is None:
        return None
    stack, results, errors = made
    return Sweep(results, errors, _params(plan), {}, stack, None, dict(plan.values))


def _at_own_times(plan: SweepPlan, models, analysis: str, kwargs, describe, progress) -> list:
    """The members run one by one, each over its own output times
    (:attr:`SweepPlan.member_times`; members with as many times share a compiled program)."""
    outcomes = []
    for i, model in enumerate(models):
        t = plan.times_of(i)
        values, recorded = member_values(analysis, t, [kwargs[i]], lambda _, i=i: describe(i), i)
        outcomes += run_members(
            [model],
            t,
            values,
            recorded=recorded,
            batch_size=plan.spec.batch_size,
            on_member=None if progress is None else lambda _, i=i: progress(i),
            describe=lambda _, i=i: describe(i),
            offset=i,
        )
    return outcomes


#: A summary's reduction of a member's column along its last axis (time): (N,) -> a
#: number, (M, N) -> (M,).
_REDUCE = {
    "max": lambda y: np.max(y, axis=-1),
    "min": lambda y: np.min(y, axis=-1),
    "absmax": lambda y: np.max(np.abs(y), axis=-1),
    "mean": lambda y: np.mean(y, axis=-1),
    "rms": lambda y: np.sqrt(np.mean(np.square(y), axis=-1)),
    "first": lambda y: y[..., 0],
    "last": lambda y: y[..., -1],
    "range": lambda y: np.ptp(y, axis=-1),
}


def _summaries(runner: Runner, plan: SweepPlan, sweep: Sweep) -> tuple[dict, dict]:
    """Each summary per member and the units of the summaries and table columns (in the
    file's ``output_units``)."""
    from ..io.results import in_units
    from ..viz.plots import result_columns

    r: s.SweepRunSpec = plan.spec
    results = sweep.results
    ok = next((res for res in results if res is not None), None)
    units: dict[str, str] = {}
    if ok is not None:
        wanted = [x.column for x in r.summaries] + plan.spec_outputs
        try:
            cols, units = result_columns(ok, wanted)
        except KeyError as e:
            runner.fail((*plan.path, "summaries"), str(e.args[0]), "fix the column name")
        units = in_units(ok, cols, units, runner.output_units)[1]
    out = {x.name: np.full(len(results), np.nan) for x in r.summaries}
    columns = list(dict.fromkeys(x.column for x in r.summaries))
    stacked = _stacked_columns(sweep, columns, runner.output_units) if columns else None
    if stacked is not None:  # every member at once (a failed member's rows NaN)
        for x in r.summaries:
            out[x.name] = np.asarray(_REDUCE[x.reduce](stacked[x.column]), dtype=float)
    for i, res in enumerate(results if stacked is None else ()):
        if res is not None and columns:
            cols = _columns(res, columns, runner.output_units)  # once a member
            for x in r.summaries:
                out[x.name][i] = float(_REDUCE[x.reduce](np.asarray(cols[x.column])))
    for x in r.summaries:
        units[x.name] = units.get(x.column, "")
    return out, units


def _stacked_columns(sweep: Sweep, names, output_units=None) -> dict[str, np.ndarray] | None:
    """Columns ``names`` of every member, (M, N) each, a failed member's rows NaN, and
    ``t`` (N,), in ``output_units`` (as :func:`_columns` gives them member by member), read
    at once from a sweep held as arrays (:attr:`mixdyn.Sweep.stacked`); None for another
    sweep or where no member succeeded."""
    from ..viz.plots import _POINT_SUFFIXES

    if sweep.stacked is None or len(sweep.errors) == len(sweep):
        return None
    own = next(r for r in sweep.results if r is not None).columns()
    points = {
        n.rsplit(".", 1)[0]
        for n in names
        if n not in own and n.count(".") == 2 and n.split(".")[2] in _POINT_SUFFIXES
    }
    cols, _ = sweep.columns(output_units, points=sorted(points))
    return {c: cols[c] for c in ("t", *names)}


# --------------------------------------------------------------------------- writing
def _figures(plan: SweepPlan, result: FileSweep, folder: pathlib.Path, painter) -> None:
    """Hand a sweep's plots to ``painter``: a summary against a swept quantity, or a band."""
    from ..viz.plots import result_columns

    units = dict(result.units)
    units.update({k: u for k, u in plan.value_units.items() if u})  # the varied values'
    for p in plan.spec.plots:
        if p.band is not None:
            stacked = _stacked_columns(result.sweep, [p.band])
            if stacked is not None:  # every member at once, the failed ones left out
                errors = result.sweep.errors
                ok = [next(r for r in result.sweep.results if r is not None)]
                rows = stacked[p.band][[i for i in range(plan.members) if i not in errors]]
            else:
                ok = [r for r in result.sweep.results if r is not None]
                if not ok:
                    continue
                rows = [np.asarray(result_columns(r, [p.band])[0][p.band]) for r in ok]
            units["t"] = ok[0].units()["t"]
            painter.draw(
                "band",
                np.asarray(plan.times),
                np.stack(rows),
                folder / p.file,
                name=p.band,
                units=units,
                title=p.title,
            )
            continue
        painter.draw(
            "against",
            plan.values[p.x],
            result.summaries[p.y],
            folder / p.file,
            names=(p.x, p.y),
            by=None if p.by is None else plan.values[p.by],
            by_name=p.by or "",
            units=units,
            title=p.title,
            scatter=plan.spec.sampling == "latin_hypercube",
        )


def _failure(plan: SweepPlan, result: FileSweep, outputs) -> str:
    """The line that ends ``mixdyn run`` (exit 1) when members failed: how many, the first
    one and why, where every member's outcome is."""
    errors = result.sweep.errors
    i = min(errors)
    e = errors[i]
    at = f" at t = {e.time:g}" if getattr(e, "time", None) is not None else ""
    return (
        f"{outputs.file}: run {plan.name!r}: {len(errors)} of {plan.members} members failed "
        f"(first: member {i}, {plan.describe(i)}{at}: {type(e).__name__}: "
        f"{getattr(e, 'message', None) or e}); the others are written, each member's "
        f"outcome in {outputs.folder(plan) / 'members.csv'}"
    )


@register
class SweepKind(RunKind):
    """A sweep: another run repeated over many values of some numbers."""

    name = "sweep"
    repeats = True
    not_replayable = "a sweep run, with a motion per member"

    def plan(self, runner, index: int, spec) -> SweepPlan:
        return plan(runner, index, spec)

    def execute(self, runner, plan: SweepPlan, results: dict, progress):
        return execute(runner, plan, progress)

    def output_files(self, runner, plan: SweepPlan, figures: bool) -> list[str]:
        names = ["members.csv", "table.csv", "meta.json", "report.html"]
        return names + ([p.file for p in plan.spec.plots] if figures else [])

    def draws(self, runner, plan: SweepPlan) -> bool:
        return bool(plan.spec.plots)

    def write(self, runner, plan: SweepPlan, result: FileSweep, seconds: float, outputs):
        from ..io.results import run_settings, write_sweep
        from .run_reports import sweep_report

        folder = outputs.folder(plan)
        files = write_sweep(
            result,
            folder,
            parquet=outputs.parquet,
            netcdf=outputs.netcdf,
            excel=outputs.excel,
            settings=run_settings(plan.spec),
            extra={
                "file": str(outputs.file),
                "run": plan.name,
                "wall_time_s": round(seconds, 3),
                "figures": [p.file for p in plan.spec.plots] if outputs.figures else [],
                "base_settings": run_settings(plan.base.spec),
                "report": "report.html",
            },
        )
        if outputs.painter is not None:
            _figures(plan, result, folder, outputs.painter)
        files += outputs.add_report(sweep_report(runner, plan, result, seconds, outputs))
        if result.sweep.errors:
            outputs.failed.append(_failure(plan, result, outputs))
        return files

    def describe(self, plan: SweepPlan, report, model) -> str:
        r = plan.spec
        how = "grid" if r.sampling == "grid" else f"Latin hypercube, seed {r.seed}"
        return (
            f"run [bold]{esc(r.name)}[/bold] (sweep of {esc(r.run)}): "
            f"{plan.members} members ({how}) over {esc(', '.join(r.vary))}"
        )

    def task(self, plan: SweepPlan, mode: str) -> tuple[str, float | None]:
        total = plan.members
        return f"{plan.name} (sweep of {plan.base.name}: {total} members)", total

    def progress(self, plan: SweepPlan, console):
        return console.members(plan)

    def done(self, plan: SweepPlan, result: FileSweep, seconds: float, folder) -> str:
        return (
            f"{plan.name}: sweep of {plan.base.name}, {plan.members} members "
            f"({len(result.sweep.errors)} failed), {seconds:.2f} s -> {folder}"
        )

    def animation_refusal(self, plan: SweepPlan) -> tuple[str, str]:
        return (
            f"run {plan.name!r} is a sweep: its members have no single motion to animate",
            f"animate the run it sweeps, {plan.spec.run!r}",
        )


__all__ = ["FileSweep", "SweepKind", "SweepPlan", "execute", "outputs_of", "plan"]
