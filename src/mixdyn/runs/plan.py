"""A file's run once checked (:class:`Plan`), and what planning runs of any kind reads: their
output times, the order they run in, the run a study repeats and the numbers it may change.

Each run is planned by its kind (:meth:`.kinds.RunKind.plan`); the runner plans the runs that
repeat another run (sweeps, fits, optimizations) after the others, whose plans they take.
Planning reads the file and the model only: every fault found here is an input error (exit 2)
before anything is computed.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import paths
from ..errors import ModelError
from ..io import schema as s
from ..io._errors import FileError
from ..model._declare import number_kind as declared_number_kind

#: Kinds of quantity of the numbers of bodies, by field (an element's are declared by its
#: class: :func:`mixdyn.model._declare.number_kind`).
_BODY_KINDS = {"mass": "mass", "inertia": "inertia"}

#: The most output times a run's ``time`` may give (as ``n`` allows).
MAX_OUTPUT_TIMES = 1_000_000


@dataclasses.dataclass(frozen=True)
class Plan:
    """A checked run ready to execute.

    Attributes:
        spec: the run's description.
        index: its position in the file's ``runs``.
        times: (N,) output times [model time unit].
        depends: names of the runs whose results it needs (``from_run``).
        base: the plan of the run a sweep, fit or optimization repeats (``run:``); None for
            a run of one analysis.
    """

    spec: s.RunSpec
    index: int
    times: np.ndarray
    depends: tuple[str, ...]
    base: Plan | None = None

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def path(self) -> tuple:
        return ("runs", self.index)

    @property
    def subject(self) -> Plan:
        """The run whose analysis this run computes: the run a sweep, fit or optimization
        repeats; the plan itself for a run of one analysis."""
        return self.base if self.base is not None else self

    @property
    def replays(self) -> bool:
        """Whether the run replays another run's motion (``from_run``): its set-up needs that
        run's result."""
        return any(p.from_run is not None for p in getattr(self.spec, "prescribed", ()))


def times(runner, t: s.TimeSpec, path) -> np.ndarray:
    """A run's output times [model time unit], checked: a span that is not empty, a positive
    step, at most a million times.

    Args:
        runner: the file's runner (:class:`~mixdyn.runs.Runner`): its builder reads the
            quantities and reports the faults.
        t: the run's ``time``.
        path: its path in the file.
    """
    b = runner.b
    if t.values is not None:
        return np.asarray(b.times(t.values, (*path, "values")), dtype=float)
    t0 = b.scalar(t.span[0], "time", (*path, "span", 0))
    t1 = b.scalar(t.span[1], "time", (*path, "span", 1))
    if not t1 > t0:
        runner.fail((*path, "span"), f"the span [{t0:g}, {t1:g}] is empty", "give [start, stop]")
    if t.n is not None:
        return np.linspace(t0, t1, t.n)
    step = b.scalar(t.step, "time", (*path, "step"))
    if not step > 0:
        runner.fail((*path, "step"), "the step must be positive", "")
    count = (t1 - t0) / step * (1 + 1e-12)  # inf for a step near the smallest float
    if not count < MAX_OUTPUT_TIMES:
        runner.fail(
            (*path, "step"),
            f"a step of {step:.3g} gives {count:.3g} output times over the span "
            f"[{t0:g}, {t1:g}], too many (at most {MAX_OUTPUT_TIMES:,})",
            f"use a step of at least {(t1 - t0) / (MAX_OUTPUT_TIMES - 1):.3g}",
        )
    times = t0 + step * np.arange(int(np.floor(count)) + 1)
    if not np.all(np.diff(times) > 0):
        runner.fail(
            (*path, "step"),
            f"a step of {step:.3g} is below the resolution of the times near {t1:g}: "
            "successive output times are equal",
            "use a larger step",
        )
    return times


def study_base(runner, index: int, r, kinds: tuple[str, ...], verb: str) -> Plan:
    """The run a sweep, fit or optimization repeats (``r.run``), checked: of one of ``kinds``,
    with its prescribed motions given by laws (not replayed ``from_run``, which its members or
    trials would not share); ``verb`` names the study in the hints."""
    path = ("runs", index, "run")
    kind = {x.name: x.kind for x in runner.spec.runs}.get(r.run)
    known = ", ".join(x.name for x in runner.spec.runs if x.kind in kinds) or "(none)"
    allowed = " or ".join([", ".join(kinds[:-1]), kinds[-1]] if len(kinds) > 1 else kinds)
    if kind is None or r.run not in runner.plans:
        runner.fail(path, f"unknown run {r.run!r}", f"runs to {verb}: {known}")
    if kind not in kinds:
        runner.fail(
            path,
            f"run {r.run!r} is a {kind} run, not a {allowed} run",
            f"runs to {verb}: {known}",
        )
    base = runner.plans[r.run]
    if base.replays:
        runner.fail(
            path,
            f"run {r.run!r} replays another run's motion (from_run)",
            f"{verb} a run whose prescribed motions are laws",
        )
    return base


def number_kind(runner, path: str) -> str | None:
    """The kind of quantity of a body's or element's number ``"name.field"`` (a mass, a
    spring's stiffness...), for its values with units: a body's by :data:`_BODY_KINDS`, an
    element's as its class declares it; None (model units) for a law's number or a field of
    no declared kind."""
    head, _, field = path.rpartition(".")
    if "." in head:  # a law's number: its unit is the law's
        return None
    if head in runner.b.body_index:
        return _BODY_KINDS.get(field)
    return declared_number_kind(runner.model.element(head), field, runner.model)


def model_number(runner, name: str, path, verb: str) -> str | None:
    """Check that ``name`` is one number of a body or force element (what a fit or an
    optimization may change); its kind of quantity (:func:`number_kind`)."""
    try:
        _, shape = paths.getter(runner.model, name)
    except ModelError as e:
        runner.fail(path, str(e.args[0]), "name a number of a body or force element")
    owners = {b.name for b in runner.model.bodies} | {f.name for f in runner.model.forces}
    if shape != () or name.split(".", 1)[0] not in owners:
        runner.fail(
            path,
            f"{name!r} is not a number of a body or force element",
            f"{verb} masses, inertias, and numbers of forces and their laws",
        )
    return number_kind(runner, name)


def check_value(runner, name: str, value: float, what: str, path) -> None:
    """Refuse a value a study would give the number ``name`` (``what``: ``"the low bound"``,
    ``"the start"``) that a model built with it refuses (:func:`mixdyn.paths.check`: the
    check the file meets with that number written in), at ``path`` in the file; an infinite
    bound (no bound) passes."""
    if not np.isfinite(value):
        return
    try:
        paths.check(runner.model, {name: [value]}, label=lambda i: what, where=lambda p: p)
    except ModelError as e:
        runner.fail(path, e.message, f"give {name} a value a model may have")


def check_cycles(runner) -> None:
    """Refuse runs that replay each other's motion in a cycle."""
    state: dict[str, int] = {}

    def visit(name, chain):
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            plan = runner.plans[name]
            runner.fail(
                (*plan.path, "prescribed"),
                "runs depend on each other in a cycle: " + " -> ".join([*chain, name]),
                "break the cycle",
            )
        state[name] = 1
        for d in runner.plans[name].depends:
            visit(d, [*chain, name])
        state[name] = 2

    for name in runner.plans:
        visit(name, [])


def order(runner, names=None) -> list[Plan]:
    """The plans to execute for runs ``names`` (default all), dependencies first.

    Raises:
        FileError: a name that is no run of the file (named as ``--run``).
    """
    if names is None:
        names = list(runner.plans)
    for n in names:
        if n not in runner.plans:
            known = ", ".join(runner.plans) or "(the file has no runs)"
            raise FileError(
                f"no run {n!r}", "--run", file=runner.b.file, hint=f"runs in the file: {known}"
            )
    out: list[str] = []

    def add(n):
        for d in runner.plans[n].depends:
            add(d)
        if n not in out:
            out.append(n)

    for n in names:
        add(n)
    return [runner.plans[n] for n in out]


__all__ = [
    "Plan",
    "check_cycles",
    "check_value",
    "model_number",
    "number_kind",
    "order",
    "study_base",
    "times",
]
