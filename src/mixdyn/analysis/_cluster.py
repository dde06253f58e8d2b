"""A sweep on a Dask cluster: the members sent to its workers in chunks, each chunk set up
and run member by member on its worker, the outcomes gathered in order.
"""

from __future__ import annotations

import contextlib
import dataclasses

import jax

from ..errors import ModelError
from ..model import Model
from ._members import run_members
from ._setup import Analysis

#: How long a sweep waits for a Dask scheduler given by its address [s].
CONNECT_TIMEOUT = 5.0


def _run_chunk(
    members: list[Model], t, analysis: Analysis, recorded, first: int, same_start: bool = False
):
    """On a worker: set up and run ``members`` (the sweep's members ``first``...) member by
    member in one thread, with one start where ``same_start`` (:func:`.run_members`); an
    input error names its member."""
    outcomes = run_members(
        members, t, analysis, recorded=recorded, threads=1, offset=first, same_start=same_start
    )
    return [(_without(res, m), err) for (res, err), m in zip(outcomes, members, strict=True)]


def _without(result, member: Model):
    """``result`` without its model where that is ``member`` (the same leaves under the same
    structure): the calling process holds the member, and unpickling a model there costs
    more than the rest of a result (~2.6 of 3 ms, the paper's model); put back by
    :func:`_with`."""
    if result is None:
        return None
    ours, theirs = jax.tree_util.tree_flatten(result.model), jax.tree_util.tree_flatten(member)
    if ours[1] != theirs[1] or any(a is not b for a, b in zip(ours[0], theirs[0], strict=True)):
        return result
    return _Stripped(dataclasses.replace(result, model=None))


@dataclasses.dataclass(frozen=True)
class _Stripped:
    """A result sent back without its model, which is the member's (:func:`_without`)."""

    result: object


def _with(outcome, member: Model):
    """An outcome of :func:`_run_chunk` with the member's model put back in its result."""
    res, err = outcome
    if isinstance(res, _Stripped):
        res = dataclasses.replace(res.result, model=member)
    return res, err


@contextlib.contextmanager
def connected(client):
    """The Dask client of ``client``: a ``distributed.Client`` as it is, or a scheduler's
    address (``"tcp://host:8786"``) connected within :data:`CONNECT_TIMEOUT` and closed
    after the sweep.

    Raises:
        ModelError: not a client nor an address, distributed not installed, or no scheduler
            answering at the address.
    """
    if not isinstance(client, str):
        if not (hasattr(client, "submit") and hasattr(client, "gather")):
            raise ModelError(
                f"a Dask distributed.Client or a scheduler's address, got {client!r:.60}",
                "client",
            )
        yield client
        return
    try:
        from distributed import Client
    except ImportError:
        raise ModelError(
            "a sweep on a cluster needs Dask's distributed, which is not installed",
            "client",
        ) from None
    try:
        own = Client(client, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as e:
        raise ModelError(
            f"no Dask scheduler answers at {client!r} within {CONNECT_TIMEOUT:g} s ({e}); "
            "check the address and that the scheduler runs, or leave client out to run here",
            "client",
        ) from None
    try:
        yield own
    finally:
        own.close()


def _on_cluster(
    client, members, t, analysis, recorded, chunk_size, on_member=None, same_start=False
):
    """The members run on a Dask ``client``'s workers (a client or a scheduler's address:
    :func:`connected`), ``chunk_size`` at a time (default: four chunks per worker thread),
    gathered in order; ``on_member(i)`` for each member of a chunk as the chunk comes back;
    ``same_start``: the members of a chunk share its first member's start."""
    with connected(client) as c:
        return _on_client(c, members, t, analysis, recorded, chunk_size, on_member, same_start)


def _on_client(client, members, t, analysis, recorded, chunk_size, on_member, same_start):
    if chunk_size is None:
        slots = sum(client.nthreads().values()) or 1
        chunk_size = max(1, -(-len(members) // (4 * slots)))
    starts = range(0, len(members), chunk_size)
    futures = [
        client.submit(
            _run_chunk,
            members[s : s + chunk_size],
            t,
            analysis,
            recorded,
            s,
            same_start,
            pure=False,
        )
        for s in starts
    ]
    if on_member is not None:
        from distributed import as_completed

        first = {f.key: s for f, s in zip(futures, starts, strict=True)}
        for done in as_completed(futures):
            s = first[done.key]
            for i in range(s, min(s + chunk_size, len(members))):
                on_member(i)
    out = []
    for chunk in client.gather(futures):
        out.extend(chunk)
    return [_with(o, m) for o, m in zip(out, members, strict=True)]
