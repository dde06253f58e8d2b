"""The kinds of run of a model file, found by name in one registry.

A run's ``kind:`` names a :class:`RunKind`, registered once in :data:`KINDS` by the module
that implements it: :mod:`.analyses` (the runs of one analysis: kinematic, statics, inverse,
forward, mixed), :mod:`.sweep`, :mod:`.identify` and :mod:`.optimize` (the runs that repeat
another run) and :mod:`.synthesis` (a four-bar made to draw a path). The kind knows how its
runs are planned and checked, what they compute, how they execute, what they write and how
they are shown; the runner, the checks and the command look the kind up (:func:`kind_of`) and
ask it, as :mod:`scipy.integrate` looks a method up in its ``METHODS``.

Example::

    from mixdyn.runs.kinds import kind_of
    kind_of(plan).output_files(runner, plan, figures=True)   # ["results.csv", "meta.json", ...]
"""

from __future__ import annotations

import pathlib
from collections.abc import Callable
from typing import ClassVar

from .plan import Plan


class RunKind:
    """A kind of run (``kind:`` in a model file): what its runs are and how they are done.

    The class attributes are what the planning, the checks and the set-up read of a kind; the
    methods are its jobs. A kind is registered with :func:`register`; its runs are planned
    with :meth:`plan` (the runs that repeat another run, ``repeats``, after the others).
    """

    #: The file's ``kind:``.
    name: ClassVar[str] = ""
    #: The run repeats another run (``run:``): a sweep, an identification, an optimization.
    repeats: ClassVar[bool] = False
    #: The run uses the bodies' masses (each must be > 0) and needs two output times.
    dynamic: ClassVar[bool] = False
    #: The motion is integrated in time (forward, mixed): the run starts with velocities,
    #: follows its simulated time in a progress bar, balances its work, and its programs may
    #: be prepared while the runs before it compute. Otherwise the drivers fix the motion.
    integrated: ClassVar[bool] = False
    #: The run needs as many drivers as the mechanism has degrees of freedom.
    fully_driven: ClassVar[bool] = False
    #: The result has the motion only: no forces, reactions or efforts.
    motion_only: ClassVar[bool] = False
    #: The result has the force elements' columns (a spring's force, a damper's...).
    element_columns: ClassVar[bool] = True
    #: The run solves for unknown forces, one per prescribed motion: its prescribed motions
    #: are paired with them, not drivers with efforts of their own.
    unknown_forces: ClassVar[bool] = False
    #: The run's differentiable outputs (:func:`mixdyn.differentiable`) hold the joints'
    #: reactions and the drivers' efforts, besides the motion.
    differentiable_efforts: ClassVar[bool] = False
    #: The run analyses the file's mechanism: its model is built and its start and mobility
    #: are checked. False for a run that makes a mechanism of its own (a synthesis), which a
    #: file without bodies may hold.
    needs_mechanism: ClassVar[bool] = True
    #: How a run that replays this kind's motion (``from_run``) is refused, after
    #: ``"run NAME is "``; None where the motion can be replayed.
    not_replayable: ClassVar[str | None] = None

    # ----------------------------------------------------------------- planning and checks
    def plan(self, runner, index: int, spec) -> Plan:
        """Check run ``spec`` (at ``runs[index]``) against the file and its model.

        Args:
            runner: the file's :class:`~mixdyn.runs.Runner` (its builder, model, plans).
            index: the run's position in the file's ``runs``.
            spec: the run's description.

        Returns:
            The run's :class:`~.plan.Plan`.

        Raises:
            FileError: the run is wrong, with where and what to do.
        """
        raise NotImplementedError

    def plots(self, runner, plan: Plan) -> list:
        """The plots a run draws, as ``PlotSpec`` (none but its own figures by default)."""
        return []

    # ----------------------------------------------------------------- executing
    def execute(self, runner, plan: Plan, results: dict, progress: Callable | None):
        """Run one plan (the results of the runs it replays in ``results``); ``progress``
        from :meth:`progress`, or None."""
        raise NotImplementedError

    # ----------------------------------------------------------------- outputs
    def output_files(self, runner, plan: Plan, figures: bool) -> list[str]:
        """The files the run writes in its folder (with ``figures``, its figures too), in the
        order they are checked before anything runs."""
        raise NotImplementedError

    def draws(self, runner, plan: Plan) -> bool:
        """Whether the run draws a figure or an animation (when figures are written)."""
        return False

    def write(self, runner, plan: Plan, result, seconds: float, outputs) -> list[pathlib.Path]:
        """Write the run's result in its folder (:class:`~.outputs.Outputs`: where, which
        formats, the figure worker) and hand its figures to the worker.

        Returns:
            The files written (the figures are counted when drawn).
        """
        raise NotImplementedError

    # ----------------------------------------------------------------- shown
    def describe(self, plan: Plan, report, model) -> str:
        """``mixdyn check``'s line about the run (rich markup); ``report``: the degrees of
        freedom of the run's model and drivers (:class:`~mixdyn.DofReport`)."""
        raise NotImplementedError

    def task(self, plan: Plan, mode: str) -> tuple[str, float | None]:
        """The run's progress bar: its label and total (None: no total). ``mode``:
        ``"runs"``, ``"steps"``, ``"log"`` or ``"off"``."""
        span = float(plan.times[-1] - plan.times[0]) or 1.0
        return f"{plan.name} ({plan.spec.kind})", span if mode == "steps" else None

    def progress(self, plan: Plan, console) -> Callable | None:
        """The run's progress callback, from ``console`` (:class:`~.console.RunProgress`);
        None: none."""
        return None

    def done(self, plan: Plan, result, seconds: float, folder: pathlib.Path) -> str:
        """The line shown when the run is written to ``folder``."""
        raise NotImplementedError

    def animation_refusal(self, plan: Plan) -> tuple[str, str] | None:
        """Why the run cannot be animated ``(problem, hint)``; None where it can."""
        return None


#: The kinds of run by their name in a file (``kind:``).
KINDS: dict[str, RunKind] = {}


def register(cls: type[RunKind]) -> type[RunKind]:
    """Register a kind of run (a class decorator): its one instance under its ``name``."""
    KINDS[cls.name] = cls()
    return cls


def kind_of(run) -> RunKind:
    """The kind of a run: of a :class:`~.plan.Plan`, a run's description or a result (by its
    ``kind``)."""
    spec = getattr(run, "spec", run)
    return KINDS[spec.kind]


__all__ = ["KINDS", "RunKind", "kind_of", "register"]
