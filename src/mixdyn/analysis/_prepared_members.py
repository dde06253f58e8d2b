"""What the sweeps held as arrays whose members are each prepared like a single run share
(kinematic: :mod:`._kinematic_members`; quasi-static: :mod:`._static_members`).

Each member is prepared from a thread per core (:func:`prepare_each`: an input error raised
with the member's index, a start that cannot be made kept as the member's error); the
members' inputs are stacked, :data:`~._schedule.CHUNK` members a call, into one vectorized
program (:func:`in_chunks`: a failed member takes a prepared member's place, the last call
filled up with copies of its first member: one program shape for any count); the members
the program flags are finished like a single run and every other member's
:class:`~.result.Result` is built when it is read (:func:`finished`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import jax
import numpy as np

from ..errors import MixdynError, ModelError
from ._schedule import CHUNK, _in_threads, _stack_column
from ._stacked import LazyResults
from .result import Result


def prepare_each(
    count: int, prepare: Callable[[int], object], threads: int, describe: Callable[[int], str]
) -> tuple[list, dict[int, MixdynError]]:
    """``prepare(i)`` of each member, from ``threads`` threads: ``(made, errors)``, ``made[i]``
    None where member ``i``'s start cannot be made (its error in ``errors``).

    Raises:
        ModelError: a member's input error (with its index in a note).
    """

    def one(i: int):
        try:
            return prepare(i), None
        except ModelError as err:
            err.add_note(f"in member {i} of the sweep{describe(i)}")
            raise
        except MixdynError as err:  # a start that cannot be made: this member fails
            return None, err

    done = _in_threads(one, list(range(count)), threads, None)
    return [m for m, _ in done], {i: e for i, (m, e) in enumerate(done) if m is None}


def one_structure(trees: Sequence) -> bool:
    """Whether the PyTrees ``trees`` (None for a failed member, left out) share one
    structure (one program runs them)."""
    made = [t for t in trees if t is not None]
    first = jax.tree_util.tree_structure(made[0]) if made else None
    return all(jax.tree_util.tree_structure(t) == first for t in made)


def stack(trees: Sequence):
    """PyTrees of one structure stacked leaf by leaf (leading axis: the member); a leaf that
    is the same object in every tree (a shared set-up's) is broadcast."""
    leaves = [jax.tree_util.tree_leaves(t) for t in trees]
    return stack_leaves(jax.tree_util.tree_structure(trees[0]), leaves)


def stack_leaves(treedef, rows: Sequence[list]):
    """The PyTree ``treedef`` with every member's leaves ``rows`` (a list of leaves a
    member, flattened once) stacked leaf by leaf, as :func:`stack`."""
    return jax.tree_util.tree_unflatten(
        treedef, [_stack_column(col) for col in zip(*rows, strict=True)]
    )


def in_chunks(program: Callable[[list[int]], tuple], made: Sequence, chunk: int = CHUNK) -> tuple:
    """The outputs of ``program(idx)`` (a tuple of arrays, leading axis: the members of
    ``idx``, ``chunk`` of them) for every member, concatenated: a failed
    member (``made[i]`` None) runs as the first prepared member (its rows are that member's
    copy), the last call filled up with copies of its first member (dropped)."""
    count = len(made)
    first_ok = next(i for i, m in enumerate(made) if m is not None)
    fill = [i if made[i] is not None else first_ok for i in range(count)]
    parts = []
    for first in range(0, count, chunk):
        idx = fill[first : first + chunk]
        idx = idx + [idx[0]] * (chunk - len(idx))
        n = min(chunk, count - first)
        parts.append(jax.tree.map(lambda a, n=n: np.asarray(a)[:n], program(idx)))
    if len(parts) == 1:
        return parts[0]
    return jax.tree.map(lambda *xs: np.concatenate(xs), *parts)


def finished(
    count: int,
    flagged: np.ndarray,
    build: Callable[[int], Result],
    errors: dict[int, MixdynError],
    on_member: Callable[[int], None] | None,
) -> tuple[LazyResults, dict[int, MixdynError]]:
    """The members' results, ``(results, errors)``: each ``flagged`` member (M,) not failed
    already finished now by ``build`` (which raises its named error, then kept as the
    member's), every other member's built by ``build`` when it is read; ``on_member(i)``
    for each member after."""
    outcomes = {i: (None, e) for i, e in errors.items()}
    errors = dict(errors)
    for i in np.flatnonzero(flagged):
        i = int(i)
        if i in outcomes:
            continue
        try:
            outcomes[i] = build(i), None
        except MixdynError as err:
            outcomes[i] = None, err
            errors[i] = err
    if on_member is not None:
        for i in range(count):
            on_member(i)
    return LazyResults(count, build, outcomes), errors


__all__ = ["finished", "in_chunks", "one_structure", "prepare_each", "stack", "stack_leaves"]
