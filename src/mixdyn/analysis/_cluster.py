"""A sweep on a Dask cluster: the members sent to its workers in chunks, each chunk set up
and run member by member on its worker, the outcomes gathered in order.
"""

from __future__ import annotations

from ..model import Model
from ._members import run_members
from ._setup import Analysis


def _run_chunk(members: list[Model], t, analysis: Analysis, recorded, first: int):
    """On a worker: set up and run ``members`` (the sweep's members ``first``...) member by
    member in one thread; an input error names its member."""
    return run_members(members, t, analysis, recorded=recorded, threads=1, offset=first)


def _on_cluster(client, members, t, analysis, recorded, chunk_size, on_member=None):
    """The members run on a Dask ``client``'s workers, ``chunk_size`` at a time (default:
    four chunks per worker thread), gathered in order; ``on_member(i)`` for each member of a
    chunk as the chunk comes back."""
    if chunk_size is None:
        slots = sum(client.nthreads().values()) or 1
        chunk_size = max(1, -(-len(members) // (4 * slots)))
    starts = range(0, len(members), chunk_size)
    futures = [
        client.submit(_run_chunk, members[s : s + chunk_size], t, analysis, recorded, s, pure=False)
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
    return out
