"""Room on the interpreter's frame stack for tracing (:func:`roomy`).

CPython (3.11 at least) keeps a thread's Python frames in chunks of 16 KiB, each mapped from
the system when a call needs one and unmapped again when the call returns. A loop whose
calls cross a chunk's end maps and unmaps 16 KiB at every call: JAX's tracing, whose
recursion is deep and repetitive, did so ~45,000 times in one empty-cache run of the paper's
example (``strace -c``: 47,232 ``mmap`` and 45,592 ``munmap`` calls), each costing page
faults, and, with several threads, the other processors' address-translation caches
(measured alone: a call at a chunk's end took 6.7 us instead of 0.04 us).

:func:`roomy` calls a function from a frame made large enough (an over-sized operand stack
in its code object, never used) that the interpreter puts it at the start of a chunk of
512 KiB: the calls it makes, ~1,000 frames deep, stay in that chunk. It changes nothing
but where the frames live.
"""

from __future__ import annotations

from collections.abc import Callable

#: Operand-stack slots given to :func:`roomy`'s frame: 33,000 x 8 bytes (264 KB) does not
#: fit in a 16 KiB chunk nor in 256 KiB, so its chunk is 512 KiB, ~248 KiB of it left for
#: the calls made from it.
SLOTS = 33_000


def roomy(fn: Callable, *args, **kwargs):
    """``fn(*args, **kwargs)``, its calls on a roomy chunk of the frame stack."""
    return fn(*args, **kwargs)


roomy.__code__ = roomy.__code__.replace(co_stacksize=SLOTS)


__all__ = ["SLOTS", "roomy"]
