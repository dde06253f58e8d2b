"""diffrax's end-of-interval floor computed in one loop instead of a hundred copies.

Every ``diffrax.diffeqsolve`` (its ``_integrate.loop``, diffrax 0.7) computes the time below
which a step is not rounded to ``t1`` as ``t1`` moved 100 floating-point numbers down, by a
Python loop of 100 calls of ``equinox.internal.prevbefore``. Traced, that is 100 copies of
``nextafter`` (~22 XLA operations each): in mixdyn's projection integrator ~28% of the
optimized program (1,605 of 5,754 instructions for the paper example), so ~25% of its compile
time (~0.35 s of ~1.4 s), of its trace and of the time to load its stored executable.

:class:`Internal` is a view of ``equinox.internal`` whose ``prevbefore``
(:class:`ChainedPrevbefore`) returns exactly what the chain of calls returns,
as one ``lax.fori_loop`` of ``prevbefore`` from the chain's start: the ``k``-th call of a chain
gives ``prevbefore`` applied ``k`` times to its start, in the same order, so the result is
the same bits; the 99 intermediate loops feed nothing and JAX drops them when it lowers the
program. The loop is one jitted function of the start and of ``k`` (an argument, so traced
once, not per ``k``), with ``prevbefore``'s derivative (the tangent passes through): each
call costs one cached call in the trace. A call on anything but the previous call's result
starts a new chain. :func:`mixdyn.runtime._private.chained_floor` hands it to diffrax while
mixdyn traces one of its own solves; nothing else of diffrax or equinox changes, and other
callers of ``equinox.internal.prevbefore`` are not touched.
"""

from __future__ import annotations

import functools
import threading
import types
import weakref

import jax


class ChainedPrevbefore:
    """``prevbefore`` for a chain of calls ``x = prevbefore(x)`` (see the module): the
    ``k``-th call of a chain is ``lax.fori_loop`` of ``prevbefore``, ``k`` times, from the
    chain's start. Chains are followed per thread (weak references: nothing is kept alive)."""

    def __init__(self, prevbefore):
        self.prevbefore = prevbefore
        self.repeated = _repeated(prevbefore)
        self._local = threading.local()

    def __call__(self, x):
        last = getattr(self._local, "last", None)
        start, k = x, 1
        if last is not None and last[0]() is x and last[1]() is not None:
            start, k = last[1](), last[2] + 1
        y = self.repeated(start, k)
        self._local.last = (_ref(y), _ref(start), k)
        return y


@functools.cache
def _repeated(step):
    """``(x, k) -> step`` applied ``k`` times to ``x`` (``k`` a traced integer), jitted; its
    derivative in ``x`` is the identity, as ``prevbefore``'s is."""

    @jax.custom_jvp
    def repeated(x, k):
        return jax.lax.fori_loop(0, k, lambda _, v: step(v), x)

    @repeated.defjvp
    def _(primals, tangents):
        x, k = primals
        return repeated(x, k), tangents[0]

    return jax.jit(repeated)


def _ref(value):
    """A weak reference to ``value``; a Python number (not weakly referenceable) is held."""
    try:
        return weakref.ref(value)
    except TypeError:
        return lambda: value


class Internal(types.ModuleType):
    """``equinox.internal`` with :class:`ChainedPrevbefore` as ``prevbefore``."""

    def __init__(self, internal):
        super().__init__(internal.__name__, internal.__doc__)
        self._internal = internal
        self.prevbefore = ChainedPrevbefore(internal.prevbefore)

    def __getattr__(self, name):
        return getattr(self._internal, name)
