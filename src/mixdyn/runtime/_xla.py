"""XLA CPU settings for mixdyn's compiled programs, given to XLA as each program's compile
options (:func:`compile_options`): a user's own JAX programs and ``$XLA_FLAGS`` are left as
they are.

Two XLA CPU features are turned off: the concurrency-optimized scheduler (a vmapped
``while_loop`` of mixdyn deadlocked with it) and multi-threaded Eigen (others' programs
wedged in its thread pool, PyAutoFit issues 1528/1530; for mixdyn's small matrices it buys
nothing: the N = 40 four-bar, Dopri8 at 1e-9, took 12-16 s without it against 15-21 s with it).

A third, XLA CPU's MLIR fusion emitters, is turned off where the installed jaxlib has the
flag (:data:`IF_KNOWN`): the older LLVM-IR emitters compile mixdyn's programs about 30% faster
(the paper example's 18 programs: 6.9-7.5 s against 9.6-10.4 s); small mechanisms run as
fast or faster (``benchmarks/per_step.py``: 0.89-1.04 of the time), mid-sized ones up to ~10%
slower (a 128-link chain 1.07-1.14, 256 links 0.97-1.05, the N = 40 four-bar 1.03-1.07).
Where a long run of a large mechanism matters more than compiling, set
``XLA_FLAGS=--xla_cpu_use_fusion_emitters=true``. An unknown option is refused by XLA, so
the option is given only for the jaxlib versions in which it was checked (:data:`IF_KNOWN`;
jaxlib 0.12 no longer has it).

What they do not change: XLA's CPU runtime still runs one of mixdyn's programs on two threads
(its execution thread and one of its pool), handing work to each other; two such processes
on two cores (pytest's two workers) slowed two N = 40 runs from 21-46 s to past 900 s. The test
suite pins each worker to a core of its own (``tests/conftest.py``); a user running several
mixdyn processes at once on few cores may do the same (``taskset -c``).

A flag the user names in ``$XLA_FLAGS`` (either value) is not given (the user's value holds);
``MIXDYN_KEEP_XLA_FLAGS=1`` gives none of them.
"""

from __future__ import annotations

import functools
import os

#: Flag name -> the value mixdyn sets when the user has not named the flag.
SAFE_FLAGS = {
    "--xla_cpu_multi_thread_eigen": "false",
    "--xla_cpu_enable_concurrency_optimized_scheduler": "false",
}

#: Flags added only for the jaxlib versions in which they were checked to exist (an unknown
#: flag aborts the process): name -> (value, first such version, first version not checked).
#: ``--xla_cpu_use_fusion_emitters``: unknown to jaxlib 0.4.35 and 0.5.0; accepted by 0.6.0,
#: 0.7.0, 0.8.0, 0.9.0 and 0.10.2 (each installed and started with it).
IF_KNOWN = {
    "--xla_cpu_use_fusion_emitters": ("false", (0, 6), (0, 11)),
}

#: The environment variable with which mixdyn gives XLA none of its options (``1``).
KEEP_ENV = "MIXDYN_KEEP_XLA_FLAGS"


def jaxlib_version() -> tuple[int, ...] | None:
    """The installed jaxlib's version as numbers (None: not installed)."""
    import importlib.metadata
    import re

    try:
        version = importlib.metadata.version("jaxlib")
    except importlib.metadata.PackageNotFoundError:
        return None
    return tuple(int(x) for x in re.findall(r"\d+", version)[:3])


def flags_to_add(named=frozenset(), version: tuple[int, ...] | None = None) -> dict[str, str]:
    """The flags mixdyn gives where the user named none of them in ``named`` (name ->
    value), for jaxlib ``version`` (default: the installed one)."""
    version = jaxlib_version() if version is None else version
    flags = {k: v for k, v in SAFE_FLAGS.items() if k not in named}
    for k, (value, first, after) in IF_KNOWN.items():
        if k not in named and version is not None and first <= version < after:
            flags[k] = value
    return flags


def user_flags() -> frozenset[str]:
    """The flags named in ``$XLA_FLAGS`` (``--name``)."""
    return frozenset(tok.split("=", 1)[0] for tok in os.environ.get("XLA_FLAGS", "").split())


@functools.cache
def compile_options() -> dict[str, bool]:
    """XLA's compile options for every program of mixdyn (``jax.jit``'s ``compiler_options``):
    :func:`flags_to_add` for the installed jaxlib, less the flags the user named in
    ``$XLA_FLAGS``; none with ``MIXDYN_KEEP_XLA_FLAGS=1``. Read once per process."""
    if os.environ.get(KEEP_ENV, "").strip() not in ("", "0"):
        return {}
    return {name.lstrip("-"): value == "true" for name, value in flags_to_add(user_flags()).items()}
