"""The runs of a model file: checked, ordered by their dependencies, and executed.

A run names an analysis (``kinematic``, ``forward``, ``inverse``, ``mixed``), its output times,
solver settings and, for mixed runs, the unknown forces and the prescribed motions. A prescribed
motion may replay a coordinate of another run's result (``from_run``), so a file can hold the
paper's round trip: a forward run, then a mixed run that recovers the force from its motion.

Example::

    import mixdyn.io as mio
    spec = mio.read("examples/antonya.yaml")
    results = mio.execute(spec)            # {"forward": Result, "mixed": Result}
"""

from __future__ import annotations

import dataclasses
import time as _time
from collections.abc import Callable

import numpy as np

from .. import analysis as an
from .. import model as m
from ..analysis._prepare import Prepared, prepare_dynamic, prepare_kinematic
from ..analysis.mixed import bind_prescribed
from ..errors import AssemblyError, ModelError, NumericalError
from ..io import schema as s
from ..io._errors import FileError
from ..io.expressions import ExpressionError
from ..io.expressions import parse as parse_expression
from ..io.load import Builder
from . import checks as settings
from .plan import Plan

#: Suffixes of the per-body columns of a result.
BODY_COLUMNS = ("x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha")
#: The analyses of the runs, by kind.
ANALYSES = {
    "kinematic": an.kinematic,
    "statics": an.quasi_static,
    "inverse": an.inverse,
    "forward": an.forward,
    "mixed": an.mixed,
}
#: Run kinds that repeat another run (``run:``): a sweep, an identification, an optimization.
STUDIES = ("sweep", "identify", "optimize")
#: Each such kind's ``(plan(runner, index, spec), its plan class, execute(runner, plan,
#: progress))``, registered by its module (:mod:`.sweep`, :mod:`.identify`, :mod:`.optimize`,
#: imported by the package) so that the runner does not import them.
STUDY_KINDS: dict[str, tuple] = {}


#: Kinds of quantity of the numbers of bodies and force elements, by field.
_NUMBER_KINDS = {
    "mass": "mass",
    "inertia": "inertia",
    "free_length": "length",
    "stiffness": "stiffness",
    "damping": "damping",
}


def register_study(kind: str, planner, plan_class, execute) -> None:
    """Register a run kind that repeats another run (see :data:`STUDY_KINDS`)."""
    STUDY_KINDS[kind] = (planner, plan_class, execute)


class Runner:
    """Checks and executes the runs of one description.

    Args:
        spec: the validated description.
        model: its model (built if not given).
    """

    def __init__(self, spec: s.ModelFile, model: m.Model | None = None):
        self.spec = spec
        self.b = Builder(spec)
        self.model = model if model is not None else self.b.model()
        studies = {kind: planner for kind, (planner, _, _) in STUDY_KINDS.items()}
        self.plans = {}  # sweeps and fits last: they take their settings from other runs
        for i, r in enumerate(spec.runs):
            if r.kind not in studies:
                self.plans[r.name] = self._plan(i, r)
        for i, r in enumerate(spec.runs):
            if r.kind in studies:
                self.plans[r.name] = studies[r.kind](self, i, r)
        self.plans = {r.name: self.plans[r.name] for r in spec.runs}
        self._check_cycles()
        settings.check_replays(self)
        self.output_units = self._output_units()

    def _output_units(self) -> dict[str, str]:
        """``output_units`` checked: known kinds, units of their dimension."""
        from ..units import DIMENSIONS

        out = {}
        for kind, unit in self.spec.output_units.items():
            path = ("output_units", kind)
            if kind not in DIMENSIONS:
                from .._hints import did_you_mean

                self.fail(
                    path, f"no kind of quantity {kind!r}", did_you_mean(kind, DIMENSIONS, "kinds")
                )
            self.b.factor(unit, kind, path)  # the dimension checked
            out[kind] = unit
        return out

    @classmethod
    def member(cls, spec: s.ModelFile, model: m.Model, run: str, like: Runner | None = None):
        """A runner of one run of ``spec`` (a sweep's member: ``spec`` with its parameters
        changed) on ``model``, its other runs not planned or checked; ``like``: a runner of
        the same ``spec`` whose builder and plan it shares."""
        self = cls.__new__(cls)
        self.spec = spec
        self.model = model
        if like is not None:
            self.b, self.plans = like.b, {run: like.plans[run]}
            return self
        self.b = Builder(spec)
        index = next(i for i, r in enumerate(spec.runs) if r.name == run)
        self.plans = {run: self._plan(index, spec.runs[index])}
        return self

    def study_base(self, index: int, r, kinds: tuple[str, ...], verb: str) -> Plan:
        """The run a sweep, fit or optimization repeats (``r.run``), checked: of one of
        ``kinds``, with its prescribed motions given by laws (not replayed ``from_run``, which
        its members or trials would not share); ``verb`` names the study in the hints."""
        path = ("runs", index, "run")
        kind = {x.name: x.kind for x in self.spec.runs}.get(r.run)
        known = ", ".join(x.name for x in self.spec.runs if x.kind in kinds) or "(none)"
        allowed = " or ".join([", ".join(kinds[:-1]), kinds[-1]] if len(kinds) > 1 else kinds)
        if kind is None or r.run not in self.plans:
            self.fail(path, f"unknown run {r.run!r}", f"runs to {verb}: {known}")
        if kind not in kinds:
            self.fail(
                path,
                f"run {r.run!r} is a {kind} run, not a {allowed} run",
                f"runs to {verb}: {known}",
            )
        base = self.plans[r.run]
        if any(p.from_run is not None for p in base.spec.prescribed):
            self.fail(
                path,
                f"run {r.run!r} replays another run's motion (from_run)",
                f"{verb} a run whose prescribed motions are laws",
            )
        return base

    def number_kind(self, path: str) -> str | None:
        """The kind of quantity of a body's or force element's number ``"name.field"`` (a
        mass, a spring's stiffness...), for its values with units; None (model units) for a
        law's number or a field of no fixed kind."""
        head, _, field = path.rpartition(".")
        if "." in head:  # a law's number: its unit is the law's
            return None
        kinds = dict(_NUMBER_KINDS)
        rotary = head not in self.b.body_index and isinstance(
            self.model.element(head), m.RotarySpringDamper
        )
        if rotary:
            kinds.update(stiffness="rotational_stiffness", damping="rotational_damping")
            kinds["free_angle"] = "angle"
        return kinds.get(field)

    def model_number(self, name: str, path, verb: str) -> str | None:
        """Check that ``name`` is one number of a body or force element (what a fit or an
        optimization may change); its kind of quantity (:meth:`number_kind`)."""
        from ..analysis.sweep import _leaf_getter

        try:
            _, shape = _leaf_getter(self.model, name)
        except ModelError as e:
            self.fail(path, str(e.args[0]), "name a number of a body or force element")
        owners = {b.name for b in self.model.bodies} | {f.name for f in self.model.forces}
        if shape != () or name.split(".", 1)[0] not in owners:
            self.fail(
                path,
                f"{name!r} is not a number of a body or force element",
                f"{verb} masses, inertias, and numbers of forces and their laws",
            )
        return self.number_kind(name)

    def base(self, plan: Plan) -> Plan:
        """The run a sweep sweeps or a fit uses (``plan`` itself for the other kinds)."""
        return self.plans[plan.spec.run] if plan.spec.kind in STUDIES else plan

    # ----------------------------------------------------------------- checking
    def fail(self, path, problem, hint=""):
        self.b.fail(path, problem, hint)

    def _times(self, t: s.TimeSpec, path) -> np.ndarray:
        b = self.b
        if t.values is not None:
            ts = np.asarray(b.times(t.values, (*path, "values")), dtype=float)
        else:
            t0 = b.scalar(t.span[0], "time", (*path, "span", 0))
            t1 = b.scalar(t.span[1], "time", (*path, "span", 1))
            if not t1 > t0:
                self.fail(
                    (*path, "span"), f"the span [{t0:g}, {t1:g}] is empty", "give [start, stop]"
                )
            if t.n is not None:
                ts = np.linspace(t0, t1, t.n)
            else:
                step = b.scalar(t.step, "time", (*path, "step"))
                if not step > 0:
                    self.fail((*path, "step"), "the step must be positive", "")
                n = int(np.floor((t1 - t0) / step * (1 + 1e-12))) + 1
                if n > 1_000_000:
                    self.fail(
                        (*path, "step"), f"{n} output times are too many", "use a larger step"
                    )
                ts = t0 + step * np.arange(n)
        return ts

    def _plan(self, index: int, r) -> Plan:
        path = ("runs", index)
        b = self.b
        ts = self._times(r.time, (*path, "time"))
        if r.kind not in ("kinematic", "statics") and ts.size < 2:
            self.fail((*path, "time"), "a dynamic run needs at least two output times", "")
        model_drivers = {d.name for d in self.model.drivers}
        if r.drivers is not None:
            for k, name in enumerate(r.drivers):
                if name not in model_drivers:
                    self.fail(
                        (*path, "drivers", k),
                        f"unknown driver {name!r}",
                        f"the model's drivers: {', '.join(model_drivers) or '(none)'}",
                    )
        for k, ref in enumerate(r.hold or ()):
            b.coordinate(ref, (*path, "hold", k))
        if r.velocities and r.kind in ("kinematic", "inverse", "statics"):
            self.fail(
                (*path, "velocities"),
                f"initial velocities have no effect in a {r.kind} run (the drivers fix them)",
                "remove them",
            )
        for key, kind_of in (("initial", _position_kind), ("velocities", _velocity_kind)):
            for ref, value in getattr(r, key).items():
                _, coord = b.coordinate(ref, (*path, key, ref))
                b.scalar(value, kind_of(coord), (*path, key, ref))
        depends = []
        names = {e.name for e in (*self.model.joints, *self.model.drivers, *self.model.forces)}
        for k, p in enumerate(r.prescribed):
            pp = (*path, "prescribed", k)
            self._prescribed_ref(p.coordinate, (*pp, "coordinate"))
            if p.name is not None and p.name in names:
                self.fail((*pp, "name"), f"the name {p.name!r} is taken by the model", "rename")
            if p.from_run is not None:
                if p.from_run == r.name:
                    self.fail((*pp, "from_run"), "a run cannot replay itself", "name another run")
                src = next((x for x in self.spec.runs if x.name == p.from_run), None)
                if src is None:
                    self.fail(
                        (*pp, "from_run"),
                        f"unknown run {p.from_run!r}",
                        f"runs: {', '.join(x.name for x in self.spec.runs)}",
                    )
                if src.kind in STUDIES:
                    self.fail(
                        (*pp, "from_run"),
                        f"run {p.from_run!r} is "
                        + ("a sweep run, with a motion per member" if src.kind == "sweep" else "")
                        + ("an identify run" if src.kind == "identify" else "")
                        + ("an optimize run" if src.kind == "optimize" else ""),
                        "replay a forward, inverse, kinematic or mixed run",
                    )
                depends.append(p.from_run)
            else:
                self._prescribed_driver(p, pp)
        if isinstance(r, s.MixedRunSpec):
            self._check_mixed(r, path)
        for k, plot in enumerate(r.plots):
            pp = (*path, "plots", k)
            for c, col in enumerate(plot.columns):
                self._check_column(col, r, (*pp, "columns", c))
            if plot.x != "t":
                self._check_column(plot.x, r, (*pp, "x"))
                if plot.reference is not None:
                    self.fail(
                        (*pp, "reference"),
                        "a reference curve is a law of t: it needs the plot against t",
                        "remove 'x' or the reference",
                    )
            if plot.reference is not None:
                try:
                    parse_expression(plot.reference.expr, self.b.parameters)
                except ExpressionError as e:
                    self.fail((*pp, "reference", "expr"), e.message, e.hint)
                if plot.reference.unit is not None:
                    b.factor(plot.reference.unit, None, (*pp, "reference", "unit"))
        if r.animation is not None:
            for k, ref in enumerate(r.animation.trace):
                b.point(ref, (*path, "animation", "trace", k))
        if getattr(r, "dt", None) is not None:
            dt = b.scalar(r.dt, "time", (*path, "dt"))
            if not dt > 0:
                self.fail((*path, "dt"), "dt must be positive", "")
        plan = Plan(r, index, ts, tuple(dict.fromkeys(depends)))
        self._check_settings(plan)
        return plan

    def _check_settings(self, plan: Plan) -> None:
        """The run's options, step, outputs and laws (see :mod:`mixdyn.runs.checks`)."""
        settings.check_options(self, plan.spec, plan.path)
        settings.check_step(self, plan)
        settings.check_outputs(self, plan)
        settings.check_laws(self, plan)

    def _prescribed_ref(self, ref: str, path):
        parts = ref.split(".")
        if len(parts) == 3:
            self.b.point(f"{parts[0]}.{parts[1]}", path, ground=False)
            if parts[2] not in ("x", "y"):
                self.fail(path, f"{ref!r}: a point coordinate is x or y", "write body.point.x")
            return
        self.b.coordinate(ref, path)

    def _prescribed_driver(self, p: s.PrescribedSpec, path) -> m.Driver:
        parts = p.coordinate.split(".")
        name = p.name or f"prescribed {p.coordinate}"
        if len(parts) == 3:
            law = self.b.law(p.law, "length", (*path, "law"))
            return m.PointDriver(name, f"{parts[0]}.{parts[1]}", parts[2], law=law)
        kind = "angle" if parts[1] == "phi" else "length"
        return m.CoordinateDriver(
            name, parts[0], parts[1], law=self.b.law(p.law, kind, (*path, "law"))
        )

    def _check_mixed(self, r: s.MixedRunSpec, path):
        forces = {f.name: f for f in self.model.forces}
        seen = set()
        for k, name in enumerate(r.unknown):
            pp = (*path, "unknown", k)
            if name not in forces:
                self.fail(
                    pp,
                    f"unknown force {name!r}",
                    f"the model's forces: {', '.join(forces) or '(none)'}",
                )
            if not forces[name].has_magnitude:
                self.fail(pp, f"force {name!r} has no magnitude that could be unknown", "")
            if name in seen:
                self.fail(pp, f"force {name!r} is listed twice", "list it once")
            seen.add(name)
        if len(r.unknown) != len(r.prescribed):
            self.fail(
                path,
                f"{len(r.unknown)} unknown force(s) but {len(r.prescribed)} prescribed motion(s)",
                "a mixed run needs one prescribed motion per unknown force",
            )
        for k, ref in enumerate(r.independent or ()):
            self.b.coordinate(ref, (*path, "independent", k))
        prescribed = {p.coordinate: k for k, p in enumerate(r.prescribed)}
        for k, ref in enumerate(r.hold or ()):
            if ref in prescribed:
                self.fail(
                    (*path, "hold", k),
                    f"{ref} is held, but the run prescribes it (prescribed[{prescribed[ref]}]): "
                    "a held coordinate cannot follow a prescribed motion",
                    "remove it from the run's hold",
                )

    def columns(self, r) -> tuple[list[str], set[str]]:
        """The columns a run's result has: ``(names, owners of lambda.* columns)`` (the
        multipliers ``lambda.{row}`` of the joints' and drivers' rows; point columns
        ``body.P.x`` are checked apart)."""
        cols = ["t"] + [f"{b}.{s}" for b in self.b.body_names for s in BODY_COLUMNS]
        if r.kind == "kinematic":
            return cols, set()
        for j in self.model.joints:
            if j.generic_reaction:
                cols += [f"{j.name}.Fx", f"{j.name}.Fy"]
                cols += [f"{j.name}.M"] if j.carries_moment else []
            cols += [f"{j.name}.{k}" for k in j.contact_kinds]
        drivers = [d.name for d in self.model.drivers if r.drivers is None or d.name in r.drivers]
        if r.kind != "mixed":  # a mixed run's prescribed motions are paired with its unknowns
            drivers += [p.name or f"prescribed {p.coordinate}" for p in r.prescribed]
        unknown = tuple(getattr(r, "unknown", None) or ())
        for name in [*drivers, *unknown]:
            cols += [name, f"{name}.power"]
        if r.kind != "statics":
            from ..equations import force_output_kinds

            cols += list(force_output_kinds(self.model, exclude=unknown))
        cols += ["energy.kinetic", "energy.potential", "energy.total", "constraint.violation"]
        if r.kind in ("forward", "mixed"):
            cols += ["work.nonconservative", "work.constraints"]
        owners = {j.name for j in self.model.joints} | set(drivers)
        return cols, owners

    def plots(self, plan: Plan) -> list:
        """The figures a run draws: its ``plots``, or for a dynamic or inverse run without
        any, the plots every designer draws first: the drivers' efforts, the unknown forces
        (mixed) and the joints' reactions (a panel per unit each). A kinematic run has none
        by default; sweeps, fits and optimizations draw their own."""
        r = plan.spec
        if r.kind in STUDIES:
            return []
        if r.plots or r.kind == "kinematic":
            return list(r.plots)
        names, _ = self.columns(r)
        drivers = [d.name for d in self.model.drivers if r.drivers is None or d.name in r.drivers]
        if r.kind != "mixed":
            drivers += [p.name or f"prescribed {p.coordinate}" for p in r.prescribed]
        reactions = [c for c in names if c.rsplit(".", 1)[-1] in ("Fx", "Fy", "M")]
        reactions = [c for c in reactions if c.rsplit(".", 1)[0] in self._joint_names]
        out = []
        for file, cols, title in (
            ("efforts.png", drivers, "Driver efforts"),
            ("unknown_forces.png", list(getattr(r, "unknown", None) or ()), "Unknown forces"),
            ("reactions.png", reactions, "Joint reactions (on body j)"),
        ):
            if cols:
                out.append(s.PlotSpec(file=file, columns=cols, title=f"{r.name}: {title}"))
        return out

    @property
    def _joint_names(self) -> set[str]:
        return {j.name for j in self.model.joints}

    def _check_column(self, col: str, r, path):
        parts = col.split(".")
        if len(parts) == 3 and parts[0] in self.b.body_index and parts[1] not in BODY_COLUMNS:
            self.b.point(f"{parts[0]}.{parts[1]}", path)
            if parts[2] in ("x", "y", "vx", "vy", "ax", "ay"):
                return
        names, owners = self.columns(r)
        if col in names:
            return
        if col.startswith("lambda.") and any(
            col == f"lambda.{o}" or col.startswith(f"lambda.{o}.") for o in owners
        ):
            return
        from .._hints import did_you_mean

        what = "a kinematic run has the motion only" if r.kind == "kinematic" else ""
        self.fail(
            path,
            f"no column {col!r} in run {r.name!r}" + (f" ({what})" if what else ""),
            did_you_mean(col, names) + "; points: body.P.x (.y, .vx, .vy, .ax, .ay)",
        )

    def _check_cycles(self):
        state: dict[str, int] = {}

        def visit(name, chain):
            if state.get(name) == 2:
                return
            if state.get(name) == 1:
                plan = self.plans[name]
                self.fail(
                    (*plan.path, "prescribed"),
                    "runs depend on each other in a cycle: " + " -> ".join([*chain, name]),
                    "break the cycle",
                )
            state[name] = 1
            for d in self.plans[name].depends:
                visit(d, [*chain, name])
            state[name] = 2

        for name in self.plans:
            visit(name, [])

    # ----------------------------------------------------------------- ordering
    def order(self, names=None) -> list[Plan]:
        """The plans to execute for runs ``names`` (default all), dependencies first."""
        if names is None:
            names = list(self.plans)
        for n in names:
            if n not in self.plans:
                known = ", ".join(self.plans) or "(the file has no runs)"
                raise FileError(
                    f"no run {n!r}", "--run", file=self.b.file, hint=f"runs in the file: {known}"
                )
        out: list[str] = []

        def add(n):
            for d in self.plans[n].depends:
                add(d)
            if n not in out:
                out.append(n)

        for n in names:
            add(n)
        return [self.plans[n] for n in out]

    # ----------------------------------------------------------------- checks needing numbers
    def q_start(self, plan: Plan, model: m.Model):
        """Rough starting coordinates of a run: the bodies' q0 with the run's ``initial``."""
        q = start_q(model)
        for ref, value in plan.spec.initial.items():
            _, coord = ref.split(".")
            q[model.coordinate_index(ref)] = self.b.scalar(
                value, _position_kind(coord), (*plan.path, "initial", ref)
            )
        return q

    def qd_start(self, plan: Plan, model: m.Model):
        """The run's ``velocities``: velocity conditions ``{coordinate: value}`` (model units)
        that the analysis keeps exactly, the other velocities following; None if none."""
        if not plan.spec.velocities:
            return None
        qd = {}
        for ref, value in plan.spec.velocities.items():
            _, coord = ref.split(".")
            model.coordinate_index(ref)
            qd[ref] = self.b.scalar(value, _velocity_kind(coord), (*plan.path, "velocities", ref))
        return qd

    def hold(self, plan: Plan) -> tuple[str, ...]:
        """The coordinates a run holds at its start: kept at their starting value while the
        joints are closed (and, in a dynamic run, at their starting speed).

        The run's own ``hold``, else the file's ``assembly.hold``. A mixed run does not inherit
        a hold on a coordinate it prescribes: the prescribed motion fixes that coordinate's
        start position and speed, so it wins and that hold is dropped for the run (a run's own
        ``hold`` naming a coordinate it prescribes is refused when the run is planned).

        Args:
            plan: the run.

        Returns:
            The held coordinates, e.g. ``("crank.phi",)``.
        """
        if plan.spec.hold is not None:
            return tuple(plan.spec.hold)
        prescribed = self._prescribed_coordinates(plan)
        return tuple(h for h in self.spec.assembly.hold if h not in prescribed)

    def _prescribed_coordinates(self, plan: Plan) -> set[str]:
        """The body coordinates (``body.x``, ``.y``, ``.phi``) a mixed run prescribes."""
        if not isinstance(plan.spec, s.MixedRunSpec):
            return set()
        return {p.coordinate for p in plan.spec.prescribed if p.coordinate.count(".") == 1}

    def _hold_source(self, plan: Plan) -> tuple[tuple, str]:
        """Where a run's hold comes from: its path in the file and how to name it."""
        if plan.spec.hold is not None:
            return (*plan.path, "hold"), "the run's hold"
        return ("assembly", "hold"), "assembly.hold"

    def run_model(self, plan: Plan, drivers=()) -> m.Model:
        """The model of a run: the model's drivers it selects, plus extra drivers."""
        r = plan.spec
        selected = (
            self.model.drivers
            if r.drivers is None
            else tuple(d for d in self.model.drivers if d.name in set(r.drivers))
        )
        all_drivers = (*selected, *drivers)
        if tuple(all_drivers) == tuple(self.model.drivers):
            return self.model
        return self.model.replace(drivers=all_drivers)

    def mobility(self, plan: Plan):
        """Degrees of freedom of a run's model with its drivers and prescribed motions, at the
        assembled start.

        The check is made on the run's own set-up where it can be (:meth:`prepare`: the start
        the run will start from and its mobility analysis), which :meth:`execute_one` then
        hands to the analysis, so that the check and the run share one assembly and one rank
        analysis. A run replaying another run's motion (``from_run``) is checked with a
        stand-in for that motion and prepares itself when it runs.

        The prescribed motions are bound to their bodies as :func:`mixdyn.mixed` binds them,
        so the check counts the coordinates the run will drive. A mixed run is then checked
        as :meth:`check_solvable` does (its start with the held coordinates, the pairing of
        forces and motions), so that ``mixdyn run`` refuses it before any long computation.

        Args:
            plan: the run.

        Returns:
            The :class:`~mixdyn.DofReport` of the run's model and drivers.

        Raises:
            FileError: a kinematic or inverse run is not fully driven, a dynamic run is
                over-driven, or a mixed run fails a check of :meth:`check_solvable`.
        """
        plan = self.base(plan)  # a sweep: the run it sweeps, at its nominal numbers
        r = plan.spec
        mixed = isinstance(r, s.MixedRunSpec)
        report = None
        if _replays(plan):
            if mixed:
                report = self._standin_report(plan)
        else:
            try:
                report = self.prepare(plan).report
            except FileError:
                raise
            except (ModelError, NumericalError):
                pass  # checked as before below; the run prepares itself and says why it fails
        if report is None:
            report = self._rough_report(plan)
        n = report.n_drivers
        if r.kind in ("kinematic", "inverse"):
            if report.redundant_drivers:
                self.fail(
                    plan.path,
                    f"driver(s) {', '.join(report.redundant_drivers)} prescribe a motion the "
                    "joints or other drivers already fix",
                    "remove them or drive another coordinate",
                )
            if n != report.dof:
                more = "remove" if n > report.dof else "add"
                self.fail(
                    plan.path,
                    f"the mechanism has {report.dof} degree(s) of freedom but the {r.kind} run "
                    f"has {n} driver(s)",
                    f"{more} {abs(n - report.dof)} driver(s) (drivers: or prescribed:)",
                )
        elif n > report.dof or report.redundant_drivers:
            self.fail(
                plan.path,
                f"the mechanism has {report.dof} degree(s) of freedom but the run prescribes "
                f"{n} motion(s)"
                + (
                    f" (redundant: {', '.join(report.redundant_drivers)})"
                    if report.redundant_drivers
                    else ""
                ),
                "prescribe fewer motions, or motions of coordinates the joints leave free",
            )
        if mixed:
            self.check_solvable(plan)
        return report

    # ----------------------------------------------------------------- set-ups
    def prepare(self, plan: Plan) -> Prepared:
        """The run's set-up, made as its analysis would make it: the consistent start (a
        dynamic run) or the assembled one (kinematic, inverse), and the mobility analysis
        there (:mod:`mixdyn.analysis._prepare`). Kept for :meth:`execute_one`, which hands it
        to the analysis; made once per run (and once for runs with the same set-up).

        Args:
            plan: a run that replays no other run's motion (``from_run``: that motion is known
                only once the other run has run).

        Returns:
            The :class:`~mixdyn.analysis._prepare.Prepared` set-up (its drivers are not
            checked against the degrees of freedom here: :meth:`mobility` reports that).

        Raises:
            ModelError, NumericalError: the start cannot be made (the run itself would fail
                there).
        """
        kept = self._prepared.get(plan.name)
        if kept is not None:
            return kept[1]
        if _replays(plan):
            raise ModelError("a run replaying another run's motion prepares itself", plan.name)
        r = plan.spec
        mixed = isinstance(r, s.MixedRunSpec)
        laws = [
            self._prescribed_driver(p, (*plan.path, "prescribed", k))
            for k, p in enumerate(r.prescribed)
        ]
        model = self.run_model(plan, () if mixed else laws)
        args = self._start_args(plan, model)
        t0 = float(plan.times[0])
        kinematic = r.kind in ("kinematic", "inverse", "statics")
        drivers = (*model.drivers, *(bind_prescribed(model, laws) if mixed else ()))
        key = (
            "kinematic" if kinematic else "dynamic",
            _drivers_key(drivers),
            t0,
            tuple(sorted((k, _arg_key(v)) for k, v in args.items())),
        )
        cache = self._setups
        if key not in cache:
            try:
                if kinematic:
                    cache[key] = prepare_kinematic(
                        model, t0, drivers=drivers, balanced=False, **args
                    )
                else:
                    cache[key] = prepare_dynamic(model, t0, drivers=drivers, **args)
            except (ModelError, NumericalError) as e:
                cache[key] = e  # not made again by the checks that follow
        if isinstance(cache[key], Exception):
            raise cache[key]
        self._prepared[plan.name] = (args, cache[key])
        return cache[key]

    def _mixed_setup(self, plan: Plan):
        """What :meth:`check_solvable` checks a mixed run on: ``(model, q0, qd0, prescribed
        motions, Prepared)``, the run's own set-up (:meth:`prepare`) or, for a run replaying
        another run's motion, the stand-ins' (:meth:`_standin_report`); None where the start
        cannot be made."""
        if _replays(plan):
            if plan.name not in self._checked:
                self._standin_report(plan)
            return self._checked.get(plan.name)
        try:
            prep = self.prepare(plan)
        except FileError:
            raise
        except (ModelError, NumericalError):
            return None
        args, _ = self._prepared[plan.name]
        prescribed = prep.drivers[len(prep.model.drivers) :]
        return prep.model, args["q0"], args["qd0"], prescribed, prep

    def _start_args(self, plan: Plan, model: m.Model) -> dict:
        """The arguments a run's analysis makes its start from: ``q0`` (the rough start),
        ``hold``, ``linear_solver``, and ``qd0`` (dynamic runs) or ``assemble_first``
        (kinematic and inverse runs; an inverse run's option). An inverse run that does not
        assemble first starts from the rough start closed with its held coordinates."""
        r = plan.spec
        opts = getattr(r, "options", {}) or {}
        ls = opts.get("linear_solver", r.linear_solver)
        q0 = self.q_start(plan, model)
        hold = self.hold(plan)
        if r.kind not in ("kinematic", "inverse", "statics"):
            qd0 = self.qd_start(plan, model)
            return dict(q0=q0, qd0=qd0, hold=hold, linear_solver=ls)
        first = bool(opts.get("assemble_first", True)) if r.kind == "inverse" else True
        if hold and not first:
            q0 = np.asarray(an.assemble(model, q0, hold=hold, linear_solver=ls).q)
            hold = ()
        return dict(q0=q0, hold=hold, assemble_first=first, linear_solver=ls)

    @property
    def _prepared(self) -> dict:
        """The runs' set-ups made by the checks: ``{run name: (start arguments, Prepared)}``."""
        return self.__dict__.setdefault("_prepared_runs", {})

    @property
    def _setups(self) -> dict:
        """The set-ups by what they are made from (runs with the same start share one)."""
        return self.__dict__.setdefault("_setup_cache", {})

    def _standin_report(self, plan: Plan):
        """A mixed run replaying another run's motion, checked with stand-ins held at their
        value at the assembled start (:meth:`_prescribed_motions`): the start the checks of
        :func:`mixdyn.check_mixed` make, kept for :meth:`check_solvable`. None where that
        start cannot be made (the checks then report as before)."""
        r = plan.spec
        model = self.run_model(plan, ())
        hold = self.hold(plan)
        try:
            q = self._assembled(plan, model, hold)
            prescribed = self._prescribed_motions(plan, model, q)
        except ModelError as e:
            self._model_error(plan, e)
        try:
            prep = prepare_dynamic(
                model,
                float(plan.times[0]),
                drivers=(*model.drivers, *prescribed),
                q0=q,
                hold=hold,
                linear_solver=r.linear_solver,
            )
        except FileError:
            raise
        except (ModelError, NumericalError):
            return None
        self._checked[plan.name] = (model, q, None, prescribed, prep)
        return prep.report

    @property
    def _checked(self) -> dict:
        """Mixed runs' set-ups for :meth:`check_solvable`: ``{run name: (model, q0, qd0,
        prescribed motions, Prepared)}``."""
        return self.__dict__.setdefault("_checked_runs", {})

    def _assembled(self, plan: Plan, model: m.Model, hold) -> np.ndarray:
        """The rough start closed on the joints (the run's drivers aside) with ``hold``,
        made once for runs that share it."""
        cache = self.__dict__.setdefault("_mobility_cache", {})
        q_rough = np.asarray(self.q_start(plan, model), dtype=float)
        key = ("assemble", _drivers_key(model.drivers), hold, q_rough.tobytes())
        if key not in cache:
            cache[key] = np.asarray(an.assemble(model, q_rough, hold=hold).q)
        return cache[key]

    def _rough_report(self, plan: Plan):
        """The mobility of a run at its rough start closed on the joints, where the run's own
        start could not be made (the run then fails there, saying why)."""
        r = plan.spec
        mixed = isinstance(r, s.MixedRunSpec)
        if mixed:
            model = self.run_model(plan, ())
        else:
            model = self.run_model(
                plan,
                [
                    self._dummy_driver(k, p)
                    if p.from_run is not None
                    else self._prescribed_driver(p, (*plan.path, "prescribed", k))
                    for k, p in enumerate(r.prescribed)
                ],
            )
        # Assembly and analysis are cached by what they depend on (the drivers, the held
        # coordinates, the start, the time): runs that share them are analysed once.
        cache = self.__dict__.setdefault("_mobility_cache", {})
        hold = self.hold(plan)
        try:
            q = self._assembled(plan, model, hold)
            prescribed = self._prescribed_motions(plan, model, q) if mixed else ()
        except ModelError as e:
            self._model_error(plan, e)
        drivers = (*model.drivers, *prescribed)
        t0 = float(plan.times[0])
        key = ("dof", _drivers_key(drivers), q.tobytes(), t0)
        if key not in cache:
            cache[key] = an.degrees_of_freedom(model, q, t0, drivers=drivers)
        return cache[key]

    def check_solvable(self, plan: Plan) -> None:
        """For a mixed run, every solvability check of :func:`mixdyn.check_mixed` at the
        assembled start, without integrating.

        The prescribed motions are those of the run, built and bound as the run builds them
        (:meth:`_prescribed_motions`); a motion taken from another run is held at its value at
        the assembled start for the check. A start the held coordinates make impossible (a
        hold that fights a prescribed motion) is reported at the hold, naming where it comes
        from (the run's ``hold`` or ``assembly.hold``). Checked once per run.

        Args:
            plan: the run (other kinds pass).

        Raises:
            FileError: the run cannot be solved, with the reason.
        """
        plan = self.base(plan)
        r = plan.spec
        if not isinstance(r, s.MixedRunSpec):
            return
        done = self.__dict__.setdefault("_solvable_runs", set())
        if plan.name in done:
            return
        hold = self.hold(plan)
        setup = self._mixed_setup(plan)
        if setup is not None:  # on the set-up the run starts from (no second assembly)
            model, q0, qd0, prescribed, prep = setup
            try:
                self._solvable_at(
                    plan, model, prescribed, q0, qd0, hold, prep.linear_solver, prepared=prep
                )
            except (ModelError, NumericalError):
                self._prepared.pop(plan.name, None)  # the run prepares itself; see below why
            else:
                done.add(plan.name)
                return
        model = self.run_model(plan, ())
        try:
            q = np.asarray(an.assemble(model, self.q_start(plan, model), hold=hold).q)
            prescribed = self._prescribed_motions(plan, model, q)
        except ModelError as e:
            self._model_error(plan, e)
        # A stand-in for another run's motion has no speed: the run's start speeds are
        # checked only where every prescribed motion is a law.
        laws_only = all(p.from_run is None for p in r.prescribed)

        def check(hold):
            qd0 = self.qd_start(plan, model) if laws_only else None
            self._solvable_at(plan, model, prescribed, q, qd0, hold, r.linear_solver)

        try:
            check(hold)
        except (ModelError, AssemblyError) as e:
            if hold and self._passes(check, ()):
                path, source = self._hold_source(plan)
                cause = str(e)
                element = getattr(e, "element", None)
                if element and cause.startswith(f"{element}: "):
                    cause = cause[len(element) + 2 :]
                self.fail(
                    path,
                    f"run {plan.name!r}: the held coordinate(s) {', '.join(hold)} (from "
                    f"{source}) conflict with its prescribed motion(s) "
                    f"{', '.join(d.name for d in prescribed)} at t = {plan.times[0]:g}: {cause}",
                    "remove them from the run's hold"
                    if r.hold is not None
                    else "give the run its own hold: (hold: [] holds nothing)",
                )
            if isinstance(e, AssemblyError):
                raise
            self._model_error(plan, e)
        done.add(plan.name)

    @staticmethod
    def _solvable_at(plan: Plan, model, prescribed, q0, qd0, hold, linear_solver, prepared=None):
        """:func:`mixdyn.check_mixed` of a mixed run's unknown forces and solver."""
        r = plan.spec
        an.check_mixed(
            model,
            prescribed,
            tuple(r.unknown),
            t0=float(plan.times[0]),
            solver=r.solver,
            independent=r.independent,
            q0=q0,
            qd0=qd0,
            hold=hold,
            linear_solver=linear_solver,
            prepared=prepared,
        )

    @staticmethod
    def _passes(check: Callable, hold) -> bool:
        """Whether ``check(hold)`` raises no :class:`ModelError` or :class:`NumericalError`."""
        try:
            check(hold)
        except (ModelError, NumericalError):
            return False
        return True

    def _prescribed_motions(self, plan: Plan, model: m.Model, q) -> tuple[m.Driver, ...]:
        """A mixed run's prescribed motions as the checks see them, bound to the bodies of
        ``model`` exactly as :func:`mixdyn.mixed` binds them: a ``law`` as written, a motion
        ``from_run`` by a stand-in held at its value in ``q`` (that run has not run yet)."""
        r = plan.spec
        drivers = [
            self._dummy_driver(k, p)
            if p.from_run is not None
            else self._prescribed_driver(p, (*plan.path, "prescribed", k))
            for k, p in enumerate(r.prescribed)
        ]
        bound = bind_prescribed(model, drivers)
        q = np.asarray(q, dtype=float)
        return tuple(
            d if p.from_run is None else dataclasses.replace(d, law=self._held(p, d, q))
            for d, p in zip(bound, r.prescribed, strict=True)
        )

    def _held(self, p: s.PrescribedSpec, d: m.Driver, q) -> m.Law:
        """The stand-in's law: held at its value in ``q``, in the form the replayed motion
        will have (:func:`mixdyn.analysis.prescribe`: a quintic Hermite interpolant on the
        source run's output times, here of constant samples, exactly constant), so that the
        programs the checks compile are the ones the run then calls."""
        value = float(d.measure(q))
        source = self.plans.get(p.from_run)
        if source is None or len(source.times) < 2 or np.any(np.diff(source.times) <= 0):
            return m.Constant(value)
        n = len(source.times)
        return m.QuinticHermite(source.times, np.full(n, value), np.zeros(n), np.zeros(n))

    def check_masses(self, plan: Plan) -> None:
        """A dynamic run needs every body's mass and inertia > 0."""
        plan = self.base(plan)
        if plan.spec.kind in ("kinematic", "statics"):
            return
        for i, body in enumerate(self.model.bodies):
            for key in ("mass", "inertia"):
                if not float(getattr(body, key)) > 0:
                    self.fail(
                        ("bodies", i, key),
                        f"{key} is {float(getattr(body, key)):g}, but run {plan.name!r} "
                        f"({plan.spec.kind}) is dynamic",
                        f"give the body a {key} > 0, or make the run kinematic",
                    )

    def _dummy_driver(self, k, p: s.PrescribedSpec) -> m.Driver:
        """An unbound stand-in (law 0) for the motion ``p`` replays from another run."""
        parts = p.coordinate.split(".")
        name = p.name or f"prescribed {p.coordinate}"
        if len(parts) == 3:
            return m.PointDriver(name, f"{parts[0]}.{parts[1]}", parts[2], law=0.0)
        return m.CoordinateDriver(name, parts[0], parts[1], law=0.0)

    def _model_error(self, plan: Plan, e: ModelError):
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

    # ----------------------------------------------------------------- executing
    def execute_one(self, plan: Plan, results: dict, progress: Callable | None = None):
        """Run one plan (its dependencies' results in ``results``) and return its Result (a
        sweep's: its :class:`~mixdyn.runs.sweep.FileSweep`; ``progress`` then gets member
        indices)."""
        try:
            for _, kind_of_plan, run in STUDY_KINDS.values():
                if isinstance(plan, kind_of_plan):
                    return run(self, plan, progress)
            try:
                analysis, model, kwargs = self.call(plan, results)
                if progress is not None and analysis in ("forward", "mixed"):
                    kwargs["progress"] = progress
                return ANALYSES[analysis](model, plan.times, **kwargs)
            except TypeError as e:
                if "unexpected keyword argument" in str(e):
                    self.fail((*plan.path, "options"), f"unknown option ({e})", "remove the option")
                raise
        except FileError:
            raise
        except ModelError as e:
            self._model_error(plan, e)
        except NumericalError as e:
            e.run = plan.name
            e.file = self.b.file
            raise

    def call(
        self, plan: Plan, results: dict, *, checked: bool = True, stand_ins: bool = False
    ) -> tuple[str, m.Model, dict]:
        """What a run computes: ``(analysis, model, keywords)``, the analysis a key of
        :data:`ANALYSES` called as ``ANALYSES[analysis](model, plan.times, **keywords)``.

        Args:
            plan: the run.
            results: the results of the runs it replays (``from_run``).
            checked: start from the set-up the checks made (:meth:`mobility`), if any.
            stand_ins: a replayed motion by the stand-in its checks made (held at its start
                value, in the replayed law's form: :meth:`_held`) instead of ``results``.
        """
        r = plan.spec
        drivers = []
        for k, p in enumerate(r.prescribed):
            if p.from_run is not None and stand_ins:
                law = self._checked[plan.name][3][k].law  # KeyError: not checked so
                drivers.append(dataclasses.replace(self._dummy_driver(k, p), law=law))
            elif p.from_run is not None:
                src = results[p.from_run]
                t0, t1 = float(src.t[0]), float(src.t[-1])
                if plan.times[0] < t0 - 1e-12 or plan.times[-1] > t1 + 1e-12:
                    self.fail(
                        (*plan.path, "prescribed", k, "from_run"),
                        f"run {p.from_run!r} covers t = {t0:g}..{t1:g}, this run needs "
                        f"{plan.times[0]:g}..{plan.times[-1]:g}",
                        "run the source over at least this run's time span",
                    )
                try:
                    drivers.append(an.prescribe(src, p.coordinate, p.name))
                except ModelError as e:
                    self._model_error(plan, e)
            else:
                drivers.append(self._prescribed_driver(p, (*plan.path, "prescribed", k)))
        mixed = isinstance(r, s.MixedRunSpec)
        # The set-up the check made (mobility), if any: the run starts from it, not assembled
        # and analysed again.
        args, prep = self._prepared.get(plan.name, (None, None)) if checked else (None, None)
        model = prep.model if prep is not None else self.run_model(plan, () if mixed else drivers)
        opts = dict(getattr(r, "options", {}) or {})
        opts.pop("linear_solver", None)
        dt = None
        if getattr(r, "dt", None) is not None:
            dt = self.b.scalar(r.dt, "time", (*plan.path, "dt"))
        if args is None:
            args = self._start_args(plan, model)
        if r.kind == "kinematic":
            kw = {"max_iter": r.max_iter}
            if r.tol is not None:
                kw["tol"] = r.tol
            return "kinematic", model, dict(prepared=prep, **args, **kw)
        if r.kind == "statics":
            return "statics", model, dict(**args, tol=r.tol, max_iter=r.max_iter)
        if r.kind == "inverse":
            opts.pop("assemble_first", None)
            return "inverse", model, dict(prepared=prep, **args, **opts)
        common = dict(
            method=r.method, rtol=r.rtol, atol=r.atol, dt=dt, **args, prepared=prep, **opts
        )
        if r.kind == "forward":
            return "forward", model, common
        return (
            "mixed",
            model,
            dict(
                prescribed=drivers,
                unknown=list(r.unknown),
                solver=r.solver,
                independent=None if r.independent is None else list(r.independent),
                **common,
            ),
        )

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
        results: dict[str, an.Result] = {}
        plans = self.order(names)
        for k, plan in enumerate(plans):
            if on_start is not None:
                on_start(plan)
            t0 = _time.perf_counter()
            cb = progress(plan) if progress is not None else None
            if k + 1 < len(plans):
                self.ahead(plans[k + 1])
            res = self.execute_one(plan, results, cb)
            results[plan.name] = res
            if on_done is not None:
                on_done(plan, res, _time.perf_counter() - t0)
        return results

    def ahead(self, plan: Plan) -> None:
        """Start preparing a later forward or mixed run's programs (its integrator's and its
        post-processing's: :func:`mixdyn.analysis._simulate.ahead`) in a second thread, while
        the runs before it compute: a file's first run compiles them, and two programs
        compile at once. A run replaying another run's motion is set up with the stand-ins
        its checks made (:meth:`call`), which have the replayed motion's form. Nothing when
        the programs are read from the cache anyway
        (:func:`mixdyn.runtime._programs.reading_ahead`), with the cache off, or for other
        runs; a failure here is left for the run to meet."""
        import threading

        from ..analysis import _simulate
        from ..analysis.forward import forward_case
        from ..analysis.mixed import mixed_case
        from ..runtime import _programs

        if _programs.cache_folder() is None or _programs.reading_ahead():
            return
        if plan.spec.kind not in ("forward", "mixed"):
            return

        def prepare():
            try:
                analysis, model, kwargs = self.call(plan, {}, stand_ins=True)
                make = {"forward": forward_case, "mixed": mixed_case}[analysis]
                _simulate.ahead(make(model, plan.times, **kwargs))
            except Exception:  # the run itself meets it, and names it
                pass

        threading.Thread(target=prepare, name="mixdyn-next-run", daemon=True).start()


def start_q(model: m.Model) -> np.ndarray:
    """The bodies' rough start ``q0`` stacked with NumPy (``Model.q0`` compiles a JAX
    concatenation of every body, whose compile time grows quadratically with their number)."""
    return np.concatenate([np.asarray(b.q0, dtype=float) for b in model.bodies])


def _replays(plan: Plan) -> bool:
    """Whether a run replays another run's motion (``from_run``): its set-up needs that run's
    result."""
    return any(p.from_run is not None for p in plan.spec.prescribed)


def _drivers_key(drivers) -> tuple:
    """The drivers' kinds, structure and numbers, for the caches of set-ups."""
    import jax

    out = []
    for d in drivers:
        leaves, treedef = jax.tree_util.tree_flatten(d)
        out.append((treedef, tuple(np.asarray(x).tobytes() for x in leaves)))
    return tuple(out)


def _arg_key(value):
    """A start argument (an array, a mapping of velocities, a hold...) as a key."""
    if isinstance(value, np.ndarray):
        return ("array", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, dict):
        return ("map", tuple(sorted((k, _arg_key(v)) for k, v in value.items())))
    return value


def _position_kind(coord: str) -> str:
    return "angle" if coord == "phi" else "length"


def _velocity_kind(coord: str) -> str:
    return "angular_velocity" if coord == "phi" else "velocity"


def execute(spec: s.ModelFile, names=None, **kwargs) -> dict[str, an.Result]:
    """Execute the runs of a description (see :meth:`Runner.execute`)."""
    return Runner(spec).execute(names, **kwargs)


__all__ = ["BODY_COLUMNS", "Plan", "Runner", "execute"]
