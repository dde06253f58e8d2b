"""A run's checks with numbers, on the run's own set-up (:mod:`..setup`): every body's mass and
inertia for a dynamic run (:func:`check_masses`), the drivers against the degrees of freedom
(:func:`mobility`) and a mixed run's solvability (:func:`check_solvable`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ... import analysis as an
from ... import model as m
from ..._hints import count, listed
from ...analysis._setup import prepare
from ...analysis.mixed import Mixed, bind_prescribed
from ...errors import AssemblyError, ModelError, NumericalError
from ...io import schema as s
from ...io._errors import FileError
from ...model._compliant import refuse_contacts
from .. import setup
from ..kinds import kind_of
from ..plan import Plan

#: "degree of freedom" in its two numbers, for :func:`mixdyn._hints.count`.
_DOF = ("degree of freedom", "degrees of freedom")


def check_masses(runner, plan: Plan) -> None:
    """A dynamic run needs every body's mass and inertia > 0."""
    plan = plan.subject
    if not kind_of(plan).dynamic:
        return
    for i, body in enumerate(runner.model.bodies):
        for key in ("mass", "inertia"):
            if not float(getattr(body, key)) > 0:
                runner.fail(
                    ("bodies", i, key),
                    f"{key} is {float(getattr(body, key)):g}, but run {plan.name!r} "
                    f"({plan.spec.kind}) is dynamic",
                    f"give the body a {key} > 0, or make the run kinematic",
                )


def mobility(runner, plan: Plan):
    """Degrees of freedom of a run's model with its drivers and prescribed motions, at the
    assembled start.

    The check is made on the run's own set-up where it can be (:func:`.setup.prepare`: the
    start the run will start from and its mobility analysis), which the run then hands to its
    analysis, so that the check and the run share one assembly and one rank analysis. A run
    replaying another run's motion (``from_run``) is checked with a stand-in for that motion
    and prepares itself when it runs.

    The prescribed motions are bound to their bodies as :func:`mixdyn.mixed` binds them, so
    the check counts the coordinates the run will drive. A mixed run is then checked as
    :func:`check_solvable` does (its start with the held coordinates, the pairing of forces
    and motions), so that ``mixdyn run`` refuses it before any long computation.

    Args:
        runner: the file's runner.
        plan: the run (a sweep, fit or optimization: the run it repeats, at its nominal
            numbers).

    Returns:
        The :class:`~mixdyn.DofReport` of the run's model and drivers; None for a run that
        needs no mechanism (:attr:`.kinds.RunKind.needs_mechanism`).

    Raises:
        FileError: a fully driven run (kinematic, inverse) does not have one driver per
            degree of freedom, another run is over-driven, or a mixed run fails a check of
            :func:`check_solvable`.
    """
    plan = plan.subject
    r = plan.spec
    kind = kind_of(plan)
    if not kind.needs_mechanism:
        return None
    mixed = isinstance(r, s.MixedRunSpec)
    report = None
    if plan.replays:
        if mixed:
            report = _standin_report(runner, plan)
    else:
        try:
            report = setup.prepare(runner, plan).report
        except FileError:
            raise
        except (ModelError, NumericalError):
            pass  # checked as before below; the run prepares itself and says why it fails
    if report is None:
        report = _rough_report(runner, plan)
    n = report.n_drivers
    if kind.fully_driven:
        try:
            refuse_contacts(runner.model, r.kind)
        except ModelError as e:
            runner.model_error(plan, e)
        if report.redundant_drivers:
            runner.fail(
                plan.path,
                f"{listed(report.redundant_drivers, 'driver')} prescribe"
                f"{'s' if len(report.redundant_drivers) == 1 else ''} a motion the joints or "
                "other drivers already fix",
                "remove them or drive another coordinate",
            )
        if n != report.dof:
            more = "remove" if n > report.dof else "add"
            runner.fail(
                plan.path,
                f"the mechanism has {count(report.dof, *_DOF)} but the {r.kind} run "
                f"has {count(n, 'driver')}",
                f"{more} {count(abs(n - report.dof), 'driver')} (drivers: or prescribed:)",
            )
    elif n > report.dof or report.redundant_drivers:
        runner.fail(
            plan.path,
            f"the mechanism has {count(report.dof, *_DOF)} but the run prescribes "
            f"{count(n, 'motion')}"
            + (
                f" (redundant: {', '.join(report.redundant_drivers)})"
                if report.redundant_drivers
                else ""
            ),
            "prescribe fewer motions, or motions of coordinates the joints leave free",
        )
    if mixed:
        check_solvable(runner, plan)
    return report


def _mixed_setup(runner, plan: Plan):
    """What :func:`check_solvable` checks a mixed run on: ``(model, q0, qd0, prescribed
    motions, Prepared)``, the run's own set-up (:func:`.setup.prepare`) or, for a run
    replaying another run's motion, the stand-ins' (:func:`_standin_report`); None where the
    start cannot be made."""
    if plan.replays:
        if plan.name not in runner.setups.checked:
            _standin_report(runner, plan)
        return runner.setups.checked.get(plan.name)
    try:
        prep = setup.prepare(runner, plan)
    except FileError:
        raise
    except (ModelError, NumericalError):
        return None
    args, _ = runner.setups.prepared[plan.name]
    prescribed = prep.drivers[len(prep.model.drivers) :]
    return prep.model, args["q0"], args["qd0"], prescribed, prep


def _standin_report(runner, plan: Plan):
    """A mixed run replaying another run's motion, checked with stand-ins held at their value
    at the assembled start (:func:`prescribed_motions`): the start the checks of
    :func:`mixdyn.check_mixed` make, kept for :func:`check_solvable`. None where that start
    cannot be made (the checks then report as before)."""
    r = plan.spec
    model = setup.run_model(runner, plan, ())
    hold = setup.hold_of(runner, plan)
    try:
        q = _assembled(runner, plan, model, hold)
        prescribed = prescribed_motions(runner, plan, model, q)
    except ModelError as e:
        runner.model_error(plan, e)
    value = Mixed(
        prescribed=prescribed, unknown=r.unknown, q0=q, hold=hold, linear_solver=r.linear_solver
    )
    try:
        prep = value._initial(model, float(plan.times[0]))
    except FileError:
        raise
    except (ModelError, NumericalError):
        return None
    runner.setups.checked[plan.name] = (model, q, None, prescribed, prep)
    return prep.report


def _assembled(runner, plan: Plan, model: m.Model, hold) -> np.ndarray:
    """The rough start closed on the joints (the run's drivers aside) with ``hold``, made once
    for runs that share it."""
    cache = runner.setups.mobility
    q_rough = np.asarray(setup.q_start(runner, plan, model), dtype=float)
    key = ("assemble", setup.drivers_key(model.drivers), hold, q_rough.tobytes())
    if key not in cache:
        cache[key] = np.asarray(an.assemble(model, q_rough, hold=hold).q)
    return cache[key]


def _rough_report(runner, plan: Plan):
    """The mobility of a run at its rough start closed on the joints, where the run's own
    start could not be made (the run then fails there, saying why)."""
    r = plan.spec
    mixed = isinstance(r, s.MixedRunSpec)
    if mixed:
        model = setup.run_model(runner, plan, ())
    else:
        model = setup.run_model(
            runner,
            plan,
            [
                setup.dummy_driver(k, p)
                if p.from_run is not None
                else setup.prescribed_driver(runner, p, (*plan.path, "prescribed", k))
                for k, p in enumerate(r.prescribed)
            ],
        )
    # Assembly and analysis are cached by what they depend on (the drivers, the held
    # coordinates, the start, the time): runs that share them are analysed once.
    cache = runner.setups.mobility
    hold = setup.hold_of(runner, plan)
    try:
        q = _assembled(runner, plan, model, hold)
        prescribed = prescribed_motions(runner, plan, model, q) if mixed else ()
    except ModelError as e:
        runner.model_error(plan, e)
    drivers = (*model.drivers, *prescribed)
    t0 = float(plan.times[0])
    key = ("dof", setup.drivers_key(drivers), q.tobytes(), t0)
    if key not in cache:
        cache[key] = an.degrees_of_freedom(model, q, t0, drivers=drivers)
    return cache[key]


def check_solvable(runner, plan: Plan) -> None:
    """For a mixed run, every solvability check of :func:`mixdyn.check_mixed` at the assembled
    start, without integrating.

    The prescribed motions are those of the run, built and bound as the run builds them
    (:func:`prescribed_motions`); a motion taken from another run is held at its value at the
    assembled start for the check. A start the held coordinates make impossible (a hold that
    fights a prescribed motion) is reported at the hold, naming where it comes from (the
    run's ``hold`` or ``assembly.hold``). Checked once per run.

    Args:
        runner: the file's runner.
        plan: the run (other kinds pass).

    Raises:
        FileError: the run cannot be solved, with the reason.
    """
    plan = plan.subject
    r = plan.spec
    if not isinstance(r, s.MixedRunSpec):
        return
    done = runner.setups.solvable
    if plan.name in done:
        return
    hold = setup.hold_of(runner, plan)
    found = _mixed_setup(runner, plan)
    if found is not None:  # on the set-up the run starts from (no second assembly)
        model, q0, qd0, prescribed, prep = found
        try:
            _solvable_at(plan, model, prescribed, q0, qd0, hold, prep.linear_solver, prep)
        except (ModelError, NumericalError):
            runner.setups.prepared.pop(plan.name, None)  # the run prepares itself; see below
        else:
            done.add(plan.name)
            return
    model = setup.run_model(runner, plan, ())
    try:
        q = np.asarray(an.assemble(model, setup.q_start(runner, plan, model), hold=hold).q)
        prescribed = prescribed_motions(runner, plan, model, q)
    except ModelError as e:
        runner.model_error(plan, e)
    # A stand-in for another run's motion has no speed: the run's start speeds are
    # checked only where every prescribed motion is a law.
    laws_only = all(p.from_run is None for p in r.prescribed)

    def check(hold):
        qd0 = setup.qd_start(runner, plan, model) if laws_only else None
        _solvable_at(plan, model, prescribed, q, qd0, hold, r.linear_solver)

    try:
        check(hold)
    except (ModelError, AssemblyError) as e:
        if hold and _passes(check, ()):
            path, source = setup.hold_source(plan)
            cause = str(e)
            element = getattr(e, "element", None)
            if element and cause.startswith(f"{element}: "):
                cause = cause[len(element) + 2 :]
            runner.fail(
                path,
                f"run {plan.name!r}: the held {listed(hold, 'coordinate')} (from "
                f"{source}) conflict{'s' if len(hold) == 1 else ''} with its "
                f"{listed((d.name for d in prescribed), 'prescribed motion')} at "
                f"t = {plan.times[0]:g}: {cause}",
                "remove them from the run's hold"
                if r.hold is not None
                else "give the run its own hold: (hold: [] holds nothing)",
            )
        if isinstance(e, AssemblyError):
            raise
        runner.model_error(plan, e)
    done.add(plan.name)


def _solvable_at(plan: Plan, model, prescribed, q0, qd0, hold, linear_solver, start=None):
    """The checks of :func:`mixdyn.check_mixed` of a mixed run's unknown forces and solver:
    its set-up (:func:`mixdyn.prepare`), from ``start`` (a start made beforehand) where
    given."""
    r = plan.spec
    value = Mixed(
        prescribed=prescribed,
        unknown=tuple(r.unknown),
        solver=r.solver,
        independent=r.independent,
        q0=q0,
        qd0=qd0,
        hold=hold,
        linear_solver=linear_solver,
    )
    prepare(model, value, t0=float(plan.times[0]), start=start)


def _passes(check: Callable, hold) -> bool:
    """Whether ``check(hold)`` raises no :class:`ModelError` or :class:`NumericalError`."""
    try:
        check(hold)
    except (ModelError, NumericalError):
        return False
    return True


def prescribed_motions(runner, plan: Plan, model: m.Model, q) -> tuple[m.Driver, ...]:
    """A mixed run's prescribed motions as the checks see them, bound to the bodies of
    ``model`` exactly as :func:`mixdyn.mixed` binds them: a ``law`` as written, a motion
    ``from_run`` by a stand-in held at its value in ``q`` (that run has not run yet)."""
    r = plan.spec
    drivers = [
        setup.dummy_driver(k, p)
        if p.from_run is not None
        else setup.prescribed_driver(runner, p, (*plan.path, "prescribed", k))
        for k, p in enumerate(r.prescribed)
    ]
    bound = bind_prescribed(model, drivers)
    q = np.asarray(q, dtype=float)
    return tuple(
        d if p.from_run is None else dataclasses.replace(d, law=held(runner, p, d, q))
        for d, p in zip(bound, r.prescribed, strict=True)
    )


def held(runner, p: s.PrescribedSpec, d: m.Driver, q) -> m.Law:
    """The stand-in's law: held at its value in ``q``, in the form the replayed motion will
    have (:func:`mixdyn.analysis.prescribe`: a quintic Hermite interpolant on the source run's
    output times, here of constant samples, exactly constant), so that the programs the
    checks compile are the ones the run then calls."""
    value = float(d.measure(q))
    source = runner.plans.get(p.from_run)
    if source is None or len(source.times) < 2 or np.any(np.diff(source.times) <= 0):
        return m.Constant(value)
    n = len(source.times)
    return m.QuinticHermite(source.times, np.full(n, value), np.zeros(n), np.zeros(n))


__all__ = [
    "check_masses",
    "check_solvable",
    "mobility",
]
