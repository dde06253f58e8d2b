"""A kinematic sweep held as arrays.

Each member is prepared like a single run (:func:`~._setup.prepare`: its start assembled from
its own rough pose, the drivers checked to fix every degree of freedom), from a thread per
core; the members' constraint sets, of one structure, are stacked (leading axis: the member)
and one vectorized program runs the single run's scan (:func:`~.kinematic._kinematic_scan`)
for :data:`~._schedule.CHUNK` members a call (the last call filled up with copies of its
first member: one program shape for any count). The members are screened at once (a time
whose Newton iteration did not converge or whose Jacobian lost rank); a flagged member is
finished like a single run (:func:`~.kinematic.kinematic_result`, which names its error), and
every other member's :class:`~.result.Result` is built when it is read
(:class:`~._stacked.LazyResults`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import jax.numpy as jnp
import numpy as np

from ..errors import MixdynError
from ..model import Model
from ..runtime._programs import cached_jit
from . import _setup
from ._prepared_members import finished, in_chunks, one_structure, prepare_each
from ._prepared_members import stack as stack_trees
from ._schedule import CHUNK, batched_map
from ._stacked import LazyResults, add_points, body_columns
from .kinematic import Kinematic, _kinematic_scan, kinematic_result, output_times, tolerance
from .result import Result, in_units


def _scan_batch(width: int, c, q_start, ts, tol, max_iter):
    """The kinematic scans of a batch of members (leading axis: the member), ``width`` at a
    time vectorized: each member's ``(q, qd, qdd, it, res, ratio)``."""

    def one(x):
        cc, q, tl = x
        return _kinematic_scan(cc, q, ts, tl, max_iter)

    return batched_map(one, (c, q_start, tol), width)


_scan_batch_jit = cached_jit(_scan_batch)


@dataclasses.dataclass(frozen=True)
class KinematicStack:
    """The members of a kinematic sweep, each set up, as arrays.

    Attributes:
        values: per member its analysis value (the same object for every member of a
            sweep of one value).
        setups: per member its set-up (:class:`~._setup.Setup`), None where it failed.
        ts: (N,) the output times [time].
        tol: (M,) each member's Newton tolerance [length].
        scans: each member's scan, ``(q, qd, qdd, it, res, ratio)``, leading axes
            (member, time); a failed member's rows are its copy of another member's.
    """

    values: Sequence[Kinematic]
    setups: list
    ts: np.ndarray
    tol: np.ndarray
    scans: tuple

    @property
    def count(self) -> int:
        return len(self.setups)

    @property
    def model(self) -> Model:
        """The first member's model (the names, units and structure every member shares)."""
        return next(s for s in self.setups if s is not None).model

    kind = "kinematic"

    def result(self, i: int) -> Result:
        """Member ``i``'s result, checked as the single run's (its named error raised)."""
        setup = self.setups[i]
        c = setup.start.constraints()
        scan = tuple(np.asarray(a[i]) for a in self.scans)
        v = self.values[i]
        return kinematic_result(
            setup.start, c, self.ts, scan, float(self.tol[i]), v.max_iter, v.singular_tol
        )

    def flagged(self) -> np.ndarray:
        """(M,) the members whose scan fails a check of :func:`~.kinematic.check_run`."""
        _, _, _, _, res, ratio = self.scans
        singular = np.array([v.singular_tol for v in self.values])
        bad = ~(np.asarray(res) <= self.tol[:, None]) | (np.asarray(ratio) < singular[:, None])
        return bad.any(axis=1)

    def columns(
        self,
        arrays,
        results: LazyResults,
        errors: dict,
        output_units=None,
        points: Sequence[str] = (),
    ) -> tuple[dict[str, np.ndarray], dict[str, str]]:
        """Every result column of every member, (M, N) each (``t``: (N,)), with the points'
        columns, in ``output_units``, and their units; a failed member's rows NaN (as
        :func:`~._stacked.columns`). Each member's own model gives its points."""
        first = next((i for i in range(self.count) if i not in errors), None)
        if first is None:
            raise ValueError("no member of the sweep succeeded: there is nothing to label")
        result: Result = results[first]
        q, qd, qdd = (np.asarray(a) for a in self.scans[:3])
        cols, units = body_columns(result.model, self.ts, q, qd, qdd), result.units()
        if points:
            models = [s.model if s is not None else result.model for s in self.setups]
            add_points(cols, units, models, points, q, qd, qdd)
        if errors:
            bad = np.asarray(sorted(errors))
            for k, v in cols.items():
                if k != "t":
                    v = np.array(v, dtype=float)
                    v[bad] = np.nan
                    cols[k] = v
        return in_units(result, cols, units, output_units)


def run(
    members: Sequence[Model],
    value: Kinematic | Sequence[Kinematic],
    t,
    threads: int,
    on_member: Callable[[int], None] | None,
    describe: Callable[[int], str],
) -> tuple[KinematicStack, LazyResults, dict[int, MixdynError]] | None:
    """The members of a kinematic sweep set up, run by one vectorized program and screened:
    ``(stack, results, errors)``; None where their constraint sets differ in structure or
    their values in ``max_iter`` (then member by member). ``value``: the analysis value, or
    one per member (the model-file layer's members, whose settings may differ).

    Raises:
        ModelError: a member's input error (with its index in a note).
    """
    ts = output_times(t, minimum=1)
    t0 = float(ts[0])
    values = [value] * len(members) if isinstance(value, Kinematic) else list(value)
    if len({v.max_iter for v in values}) > 1:
        return None

    def setup_of(i: int):
        setup = _setup.prepare(members[i], values[i], t0=t0)
        _setup.check_start(setup, ts)
        return setup

    setups, errors = prepare_each(len(members), setup_of, threads, describe)
    if len(errors) == len(members):
        stack = KinematicStack(values, setups, ts, np.zeros(0), ())
        return (stack, *finished(len(members), np.zeros(0), stack.result, errors, on_member))
    made = [None if s is None else s.start.constraints().for_batch() for s in setups]
    if not one_structure(made):
        return None
    tol = np.array([tolerance(s.model, v.tol) if s is not None else 1.0
                    for s, v in zip(setups, values, strict=True)])  # fmt: skip

    def program(idx: list[int]) -> tuple:
        q0 = np.stack([np.asarray(setups[i].start.q) for i in idx])
        c = stack_trees([made[i] for i in idx])
        return _scan_batch_jit(
            CHUNK, c, q0, jnp.asarray(ts), jnp.asarray(tol[idx]), jnp.asarray(values[0].max_iter)
        )

    stack = KinematicStack(values, setups, ts, tol, in_chunks(program, made, CHUNK))
    return (stack, *finished(len(members), stack.flagged(), stack.result, errors, on_member))


__all__ = ["KinematicStack", "run"]
