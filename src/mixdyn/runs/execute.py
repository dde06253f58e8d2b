"""Executing a file's runs: each by its kind, in the order of their dependencies, the next
run's programs prepared while one computes."""

from __future__ import annotations

import time as _time
from collections.abc import Callable

from .. import analysis as an
from ..errors import ModelError, NumericalError
from ..io._errors import FileError
from . import setup
from .kinds import kind_of
from .plan import Plan, order


def execute_one(runner, plan: Plan, results: dict, progress: Callable | None = None):
    """Run one plan (its dependencies' results in ``results``) by its kind and return its
    result (a :class:`~mixdyn.Result`; a sweep's :class:`~mixdyn.runs.sweep.FileSweep`, whose
    ``progress`` gets member indices...).

    Raises:
        FileError: an input error met only now (named at the run).
        NumericalError: the run failed, with the run's name and file added.
    """
    try:
        return kind_of(plan).execute(runner, plan, results, progress)
    except FileError:
        raise
    except ModelError as e:
        runner.model_error(plan, e)
    except NumericalError as e:
        e.run = plan.name
        e.file = runner.b.file
        raise


def execute(
    runner,
    names=None,
    *,
    progress: Callable | None = None,
    on_start: Callable | None = None,
    on_done: Callable | None = None,
) -> dict[str, an.Result]:
    """Execute runs ``names`` (default all) and the runs they depend on.

    Args:
        runner: the file's runner.
        names: run names, or None for every run.
        progress: optional ``progress(plan) -> f(t)`` giving a per-time callback for the
            dynamic runs (see ``mixdyn.forward``'s ``progress``).
        on_start, on_done: optional callbacks ``(plan)`` and ``(plan, result, seconds)``.

    Returns:
        The results by run name, in execution order.
    """
    results: dict[str, an.Result] = {}
    plans = order(runner, names)
    for k, plan in enumerate(plans):
        if on_start is not None:
            on_start(plan)
        t0 = _time.perf_counter()
        cb = progress(plan) if progress is not None else None
        if k + 1 < len(plans):
            ahead(runner, plans[k + 1])
        res = execute_one(runner, plan, results, cb)
        results[plan.name] = res
        if on_done is not None:
            on_done(plan, res, _time.perf_counter() - t0)
    return results


def ahead(runner, plan: Plan) -> None:
    """Start preparing a later run's programs, where its kind integrates in time (its
    integrator's and its post-processing's: :func:`mixdyn.analysis._simulate.ahead`), in a
    second thread while the runs before it compute: a file's first run compiles them, and
    two programs compile at once. A run replaying another run's motion is set up with the
    stand-ins its checks made (:func:`.setup.analysis_of`), which have the replayed motion's form.
    Nothing when the programs are read from the cache anyway
    (:func:`mixdyn.runtime._programs.reading_ahead`), with the cache off, or for other runs; a
    failure here is left for the run to meet."""
    import threading

    from ..analysis import _simulate
    from ..runtime import _programs

    if _programs.cache_folder() is None or _programs.reading_ahead():
        return
    kind = kind_of(plan)
    if not kind.integrated:
        return

    def prepare():
        try:
            run = setup.analysis_of(runner, plan, {}, stand_ins=True)
            t0 = float(plan.times[0])
            _simulate.ahead(run.analysis._case(run.setup(t0), plan.times))
        except Exception:  # the run itself meets it, and names it
            pass

    threading.Thread(target=prepare, name="mixdyn-next-run", daemon=True).start()


__all__ = ["ahead", "execute", "execute_one"]
