"""The roomy frame stack (mixdyn.runtime._private.roomy): calls at the end of one of CPython's
16 KiB frame-stack chunks map and unmap memory at every call; under ``roomy`` they do not.

The truth is the operating system's count of minor page faults (``getrusage``): a chunk
mapped afresh faults when its first page is written, so a loop of calls that each map a new
chunk faults at least once per call."""

from __future__ import annotations

import resource
import sys
import threading

import pytest

from mixdyn.runtime import _private
from mixdyn.runtime._private import SLOTS, roomy

CALLS = 400


def _leaf():
    return 1


# A leaf frame larger than a frame of _at_depth: whatever the stack's depth where the test
# starts, some depth of _at_depth leaves room for _at_depth's frames but not for the leaf's.
_leaf.__code__ = _leaf.__code__.replace(co_stacksize=64)


def _at_depth(n: int) -> int:
    """Recurse ``n`` frames, then make CALLS calls from there."""
    if n == 0:
        s = 0
        for _ in range(CALLS):
            s += _leaf()
        return s
    return _at_depth(n - 1)


def _faults(n: int) -> int:
    before = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt
    _at_depth(n)
    return resource.getrusage(resource.RUSAGE_THREAD).ru_minflt - before


def _worst_depth(depths) -> tuple[int, int]:
    """``(depth, faults)`` of the depth whose calls fault most (the chunk's end)."""
    return max(((n, min(_faults(n) for _ in range(3))) for n in depths), key=lambda x: x[1])


needs_rusage_thread = pytest.mark.skipif(
    not hasattr(resource, "RUSAGE_THREAD"), reason="per-thread page faults (Linux)"
)


def _in_thread(target) -> tuple[int, int]:
    """``target()``'s result, computed in a new thread (a frame stack of its own: the test
    itself runs roomy, tests/conftest.py)."""
    out = {}
    thread = threading.Thread(target=lambda: out.setdefault("r", target()))
    thread.start()
    thread.join()
    return out["r"]


def _plain_faults() -> tuple[int, int]:
    worst = _in_thread(lambda: _worst_depth(range(0, 400)))
    if worst[1] < CALLS:
        pytest.skip(f"this Python ({sys.version.split()[0]}) does not map a chunk per call")
    return worst


@needs_rusage_thread
def test_calls_at_a_chunk_end_fault_without_roomy_and_not_with_it():
    depth, faults = _plain_faults()
    # The same depths under roomy: every depth reached from the roomy frame stays in its chunk.
    inside = _in_thread(lambda: roomy(_worst_depth, range(0, 400)))
    assert inside[1] < CALLS // 10, (depth, faults, inside)


def test_roomy_passes_arguments_results_and_exceptions():
    assert roomy(lambda a, b=1: (a, b), 3, b=4) == (3, 4)
    assert roomy(roomy, sum, [1, 2, 3]) == 6  # nested
    with pytest.raises(ZeroDivisionError):
        roomy(lambda: 1 / 0)
    assert _private._roomy.__code__.co_stacksize == SLOTS


def test_roomy_is_a_plain_call_where_not_chosen(monkeypatch):
    """Outside the command's process (and the tests', tests/conftest.py) or on an unchecked
    interpreter, roomy calls from an ordinary frame; use_roomy_frames says whether it may."""
    monkeypatch.setitem(_private._roomy_on, "on", False)
    assert roomy(lambda: sys._getframe(1).f_code) is _private._plain.__code__
    monkeypatch.setitem(_private._roomy_on, "on", True)
    assert roomy(lambda: sys._getframe(1).f_code) is _private._roomy.__code__
    monkeypatch.setenv(_private.PUBLIC_ONLY_ENV, "1")
    assert not _private.allowed("python")
