"""The runs of a model file: planned, checked, set up and executed.

A :class:`Runner` holds one description, its model and its runs' plans, and reports faults
at their place in the file. Its jobs are done by their modules, each run by its kind
(:mod:`.kinds`): :mod:`.plan` (output times, order, what a study may change), :mod:`.checks`
(settings, columns, masses, mobility, a mixed run's solvability), :mod:`.setup` (the model, the
start and the analysis' keywords of a run, made once) and :mod:`.execute` (the runs in order).

Example::

    import mixdyn.io as mio
    from mixdyn.runs import Runner
    runner = Runner(mio.read("examples/antonya.yaml"))
    results = runner.execute()            # {"forward": Result, "mixed": Result}
"""

from __future__ import annotations

from collections.abc import Callable

from .. import analysis as an
from .. import model as m
from ..analysis._prepare import Prepared
from ..errors import ModelError
from ..io import schema as s
from ..io.load import Builder
from . import checks, setup
from . import execute as _execute
from . import plan as _plan
from .checks import BODY_COLUMNS
from .kinds import KINDS, kind_of
from .plan import Plan


class Runner:
    """Checks and executes the runs of one description.

    Planning every run checks its settings (an input error names the file, line and setting);
    :meth:`check_masses`, :meth:`mobility` and :meth:`check_solvable` check a run with numbers,
    on the set-up it then runs from; :meth:`execute` runs them.

    Args:
        spec: the validated description.
        model: its model (built if not given).

    Attributes:
        spec: the description.
        b: its builder (quantities, names, where each fault lies in the file).
        model: its model; None for a file without bodies (its runs are all syntheses, which
            need no mechanism).
        plans: the plans of its runs, by name, in the file's order.
        output_units: the file's ``output_units``, checked.
        setups: the runs' set-ups made by the checks (:class:`~.setup.Setups`).
    """

    def __init__(self, spec: s.ModelFile, model: m.Model | None = None):
        self.spec = spec
        self.b = Builder(spec)
        if model is None and spec.bodies:  # no bodies: a file of synthesis runs alone
            model = self.b.model()
        self.model = model
        self.setups = setup.Setups()
        self.plans = {}  # sweeps and fits last: they take their settings from other runs
        for repeats in (False, True):
            for i, r in enumerate(spec.runs):
                kind = KINDS[r.kind]
                if kind.repeats == repeats:
                    self.plans[r.name] = kind.plan(self, i, r)
        self.plans = {r.name: self.plans[r.name] for r in spec.runs}
        _plan.check_cycles(self)
        checks.check_replays(self)
        self.output_units = checks.output_units(self)

    @classmethod
    def member(cls, spec: s.ModelFile, model: m.Model, run: str, like: Runner | None = None):
        """A runner of one run of ``spec`` (a sweep's member: ``spec`` with its parameters
        changed) on ``model``, its other runs not planned or checked; ``like``: a runner of the
        same ``spec`` whose builder and plan it shares."""
        self = cls.__new__(cls)
        self.spec = spec
        self.model = model
        self.setups = setup.Setups()
        if like is not None:
            self.b, self.plans = like.b, {run: like.plans[run]}
            return self
        self.b = Builder(spec)
        index = next(i for i, r in enumerate(spec.runs) if r.name == run)
        r = spec.runs[index]
        self.plans = {run: KINDS[r.kind].plan(self, index, r)}
        return self

    # ----------------------------------------------------------------- reporting
    def fail(self, path, problem, hint=""):
        """Raise the :class:`~mixdyn.io.FileError` of ``problem`` at ``path`` in the file."""
        self.b.fail(path, problem, hint)

    def model_error(self, plan: Plan, e: ModelError):
        """Raise a run's :class:`ModelError` as the :class:`~mixdyn.io.FileError` at its place
        in the file: a body's, a setting's (``method``, ``dt``, ``solver``), else the run's."""
        element = e.element
        msg = str(e)
        path = plan.path
        if element and msg.startswith(f"{element}: "):
            msg = msg[len(element) + 2 :]
        if element in self.b.body_index:
            path = self.b.path_of(element)
            element = None
        elif element in ("method", "dt", "solver"):
            path = (*path, element)
            element = None
        prefix = f"{element}: " if element else ""
        self.fail(path, prefix + msg)

    # ----------------------------------------------------------------- planning
    def order(self, names=None) -> list[Plan]:
        """The plans to execute for runs ``names`` (default all), dependencies first
        (:func:`.plan.order`)."""
        return _plan.order(self, names)

    def study_base(self, index: int, r, kinds: tuple[str, ...], verb: str) -> Plan:
        """The run a sweep, fit or optimization repeats, checked (:func:`.plan.study_base`)."""
        return _plan.study_base(self, index, r, kinds, verb)

    def number_kind(self, path: str) -> str | None:
        """The kind of quantity of a number ``"name.field"`` (:func:`.plan.number_kind`)."""
        return _plan.number_kind(self, path)

    def model_number(self, name: str, path, verb: str) -> str | None:
        """Check a number a fit or an optimization changes (:func:`.plan.model_number`)."""
        return _plan.model_number(self, name, path, verb)

    def base(self, plan: Plan) -> Plan:
        """The run a sweep sweeps or a fit uses (``plan`` itself for the other kinds)."""
        return plan.subject

    def columns(self, r) -> tuple[list[str], set[str]]:
        """The columns a run's result has (:func:`.checks.columns`)."""
        return checks.columns(self, r)

    def check_column(self, col: str, r, path) -> None:
        """Refuse a column the run's result does not have (:func:`.checks.check_column`)."""
        checks.check_column(self, col, r, path)

    def plots(self, plan: Plan) -> list:
        """The figures a run draws: its ``plots``, or the ones its kind draws by default
        (:meth:`.kinds.RunKind.plots`)."""
        return kind_of(plan).plots(self, plan)

    # ----------------------------------------------------------------- checks with numbers
    def check_masses(self, plan: Plan) -> None:
        """A dynamic run needs every body's mass and inertia > 0."""
        checks.check_masses(self, plan)

    def mobility(self, plan: Plan):
        """The run's degrees of freedom, checked against its drivers (:func:`.checks.mobility`)."""
        return checks.mobility(self, plan)

    def check_solvable(self, plan: Plan) -> None:
        """A mixed run's solvability at its start (:func:`.checks.check_solvable`)."""
        checks.check_solvable(self, plan)

    # ----------------------------------------------------------------- set-ups
    def q_start(self, plan: Plan, model: m.Model):
        """Rough starting coordinates of a run (:func:`.setup.q_start`)."""
        return setup.q_start(self, plan, model)

    def qd_start(self, plan: Plan, model: m.Model):
        """A run's velocity conditions (:func:`.setup.qd_start`)."""
        return setup.qd_start(self, plan, model)

    def hold(self, plan: Plan) -> tuple[str, ...]:
        """The coordinates a run holds at its start (:func:`.setup.hold_of`)."""
        return setup.hold_of(self, plan)

    def run_model(self, plan: Plan, drivers=()) -> m.Model:
        """The model of a run: the drivers it selects, plus ``drivers``."""
        return setup.run_model(self, plan, drivers)

    def prepare(self, plan: Plan) -> Prepared:
        """The run's set-up, made once (:func:`.setup.prepare`)."""
        return setup.prepare(self, plan)

    def call(
        self, plan: Plan, results: dict, *, checked: bool = True, stand_ins: bool = False
    ) -> tuple[str, m.Model, dict]:
        """What a run computes: ``(kind, model, keywords)`` (:func:`.setup.call`)."""
        return setup.call(self, plan, results, checked=checked, stand_ins=stand_ins)

    # ----------------------------------------------------------------- executing
    def execute_one(self, plan: Plan, results: dict, progress: Callable | None = None):
        """Run one plan by its kind (:func:`.execute.execute_one`)."""
        return _execute.execute_one(self, plan, results, progress)

    def execute(
        self,
        names=None,
        *,
        progress: Callable | None = None,
        on_start: Callable | None = None,
        on_done: Callable | None = None,
    ) -> dict[str, an.Result]:
        """Execute runs ``names`` (default all) and the runs they depend on.

        Args:
            names: run names, or None for every run.
            progress: optional ``progress(plan) -> f(t)`` giving a per-time callback for the
                dynamic runs (see ``mixdyn.forward``'s ``progress``).
            on_start, on_done: optional callbacks ``(plan)`` and ``(plan, result, seconds)``.

        Returns:
            The results by run name, in execution order.
        """
        return _execute.execute(self, names, progress=progress, on_start=on_start, on_done=on_done)

    def ahead(self, plan: Plan) -> None:
        """Start preparing a later run's programs in a second thread (:func:`.execute.ahead`)."""
        _execute.ahead(self, plan)


def execute(spec: s.ModelFile, names=None, **kwargs) -> dict[str, an.Result]:
    """Execute the runs of a description (see :meth:`Runner.execute`)."""
    return Runner(spec).execute(names, **kwargs)


__all__ = ["BODY_COLUMNS", "Plan", "Runner", "execute"]
