"""A run's laws, checked when it is planned: every expression law finite at the run's output
times, the drivers' and prescribed motions' laws continuous over the run; and motions replayed
``from_run`` covering the replaying run's span (:func:`check_replays`)."""

from __future__ import annotations

import numpy as np

from ...errors import ModelError
from ...io import schema as s
from ...io.expressions import ExpressionLaw, evaluate
from .. import setup
from ..plan import Plan


def check_laws(runner, plan: Plan) -> None:
    """Every expression law of the run's drivers, prescribed motions and known forces finite
    at its output times; the drivers' and prescribed motions' laws continuous with their
    slopes over the run, and with their second derivatives but in a statics run or where the
    element's ``continuity`` is ``C1`` (:meth:`~mixdyn.model.Driver.check_law`)."""
    r = plan.spec
    used = None if r.drivers is None else set(r.drivers)
    unknown = set(getattr(r, "unknown", ()))
    drivers = [
        (("drivers", i, "law"), d)
        for i, d in enumerate(runner.model.drivers)
        if used is None or d.name in used
    ]
    laws = [(path, d.law) for path, d in drivers]
    for i, f in enumerate(runner.model.forces):
        key = "actuator" if hasattr(f, "actuator") else "law"
        if f.name not in unknown:
            laws.append((("forces", i, key), getattr(f, key, None)))
    for k, p in enumerate(r.prescribed):
        if p.law is not None:
            path = (*plan.path, "prescribed", k)
            driver = setup.prescribed_driver(runner, p, path)
            laws.append(((*path, "law"), driver.law))
            drivers.append(((*path, "law"), driver))
    for path, law in laws:
        if isinstance(law, ExpressionLaw):
            _finite_law(runner, law, plan.times, path)
    accelerations = not isinstance(r, s.StaticsRunSpec)  # a statics run reports none
    for path, driver in drivers:
        try:
            driver.check_law(plan.times[0], plan.times[-1], accelerations)
        except ModelError as e:
            runner.fail(path, e.message, "")


def check_replays(runner) -> None:
    """A motion replayed ``from_run`` covers the replaying run's time span."""
    for plan in runner.plans.values():
        for k, p in enumerate(getattr(plan.spec, "prescribed", ())):
            if p.from_run is None or p.from_run not in runner.plans:
                continue
            src = runner.plans[p.from_run].times
            t0, t1 = float(src[0]), float(src[-1])
            tol = 1e-12 * max(abs(t0), abs(t1), 1.0)
            if plan.times[0] < t0 - tol or plan.times[-1] > t1 + tol:
                runner.fail(
                    (*plan.path, "prescribed", k, "from_run"),
                    f"run {p.from_run!r} covers t = {t0:g}..{t1:g}, but run {plan.name!r} "
                    f"needs its motion over {plan.times[0]:g}..{plan.times[-1]:g}",
                    f"run {p.from_run!r} over at least this run's time span, or shorten it",
                )


def _finite_law(runner, law: ExpressionLaw, times, path) -> None:
    values = [float(v) for v in np.asarray(law.values)]
    try:
        with np.errstate(all="ignore"):
            y = np.asarray(evaluate(law.tree, times, values, xp=np), dtype=float)
    except (ArithmeticError, ValueError, TypeError):
        return
    y = np.broadcast_to(y, np.shape(times))
    bad = ~np.isfinite(y)
    if bad.any():
        k = int(np.argmax(bad))
        runner.fail(
            path,
            f"the law {law.source!r} is not finite at t = {float(times[k]):g} ({y[k]!r})",
            "change the law or the run's time span",
        )


__all__ = [
    "check_laws",
    "check_replays",
]
