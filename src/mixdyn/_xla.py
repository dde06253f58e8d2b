"""XLA CPU settings for mixdyn's compiled loops.

Two XLA CPU features are turned off: the concurrency-optimized scheduler (a vmapped
``while_loop`` of mixdyn deadlocked with it) and multi-threaded Eigen (others' programs
wedged in its thread pool, PyAutoFit issues 1528/1530; for mixdyn's small matrices it buys
nothing: the N = 40 four-bar, Dopri8 at 1e-9, took 12-16 s without it against 15-21 s with it).

A third, XLA CPU's MLIR fusion emitters, is turned off where the installed jaxlib knows the
flag (:data:`IF_KNOWN`): the older LLVM-IR emitters compile mixdyn's programs about 30% faster
(the paper example's 18 programs: 6.9-7.5 s against 9.6-10.4 s); small mechanisms run as
fast or faster (``benchmarks/per_step.py``: 0.89-1.04 of the time), mid-sized ones up to ~10%
slower (a 128-link chain 1.07-1.14, 256 links 0.97-1.05, the N = 40 four-bar 1.03-1.07).
Where a long run of a large mechanism matters more than compiling, set
``XLA_FLAGS=--xla_cpu_use_fusion_emitters=true``. An unknown flag would abort the process,
so the flag is added only when its name is found in jaxlib's library.

What they do not change: XLA's CPU runtime still runs one of mixdyn's programs on two threads
(its execution thread and one of its pool), handing work to each other; two such processes
on two cores (pytest's two workers) slowed two N = 40 runs from 21-46 s to past 900 s. The test
suite pins each worker to a core of its own (``tests/conftest.py``); a user running several
mixdyn processes at once on few cores may do the same (``taskset -c``).

:func:`apply` adds these flags to ``$XLA_FLAGS`` on import of mixdyn, before JAX starts its
CPU backend. A flag the user names in ``$XLA_FLAGS`` (either value) is left as the user set
it; ``MIXDYN_KEEP_XLA_FLAGS=1`` leaves ``$XLA_FLAGS`` untouched. Once a JAX backend has
started (JAX used before mixdyn was imported), flags can no longer change and none is added.
"""

from __future__ import annotations

import os
import sys

#: Flag name -> the value mixdyn sets when the user has not named the flag.
SAFE_FLAGS = {
    "--xla_cpu_multi_thread_eigen": "false",
    "--xla_cpu_enable_concurrency_optimized_scheduler": "false",
}

#: Flags added only where jaxlib's library names them (an unknown flag aborts XLA).
IF_KNOWN = {
    "--xla_cpu_use_fusion_emitters": "false",
}

#: The environment variable that keeps ``$XLA_FLAGS`` exactly as the user set it (``1``).
KEEP_ENV = "MIXDYN_KEEP_XLA_FLAGS"


def _backend_started() -> bool:
    if "jax" not in sys.modules:
        return False
    from jax._src import xla_bridge

    return xla_bridge.backends_are_initialized()


#: The oldest jaxlib whose library is searched for :data:`IF_KNOWN` (older ones are not: the
#: search of a library that lacks a name reads all of it, ~0.2 s at each import).
RECENT_JAXLIB = (0, 6)


def _recent_jaxlib() -> bool:
    import importlib.metadata
    import re

    try:
        version = importlib.metadata.version("jaxlib")
    except importlib.metadata.PackageNotFoundError:
        return False
    parts = tuple(int(x) for x in re.findall(r"\d+", version)[:2])
    return parts >= RECENT_JAXLIB


def _known(flags) -> set[str]:
    """The names among ``flags`` that the installed jaxlib's XLA library contains (read
    from its shared libraries, memory-mapped; a few milliseconds where the name is found)."""
    import importlib.util
    import mmap
    import pathlib

    spec = importlib.util.find_spec("jaxlib")
    if spec is None or not spec.submodule_search_locations or not _recent_jaxlib():
        return set()
    wanted = {name: name.lstrip("-").encode() for name in flags}
    found: set[str] = set()
    folder = pathlib.Path(next(iter(spec.submodule_search_locations)))
    libraries = sorted(folder.glob("*.so"), key=lambda p: -p.stat().st_size)
    for lib in libraries:
        try:
            with open(lib, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
                found |= {name for name, raw in wanted.items() if m.find(raw) >= 0}
        except (OSError, ValueError):
            continue
        if found == set(wanted):
            break
    return found


def flags_to_add(named: set[str] = frozenset()) -> dict[str, str]:
    """The flags :func:`apply` adds where the user named none of them (name -> value)."""
    flags = {k: v for k, v in SAFE_FLAGS.items() if k not in named}
    optional = [k for k in IF_KNOWN if k not in named]
    if optional:
        flags |= {k: IF_KNOWN[k] for k in optional if k in _known(optional)}
    return flags


def apply() -> tuple[str, ...]:
    """Add the missing :data:`SAFE_FLAGS` (and the known :data:`IF_KNOWN`) to
    ``$XLA_FLAGS``; returns the flags added."""
    if os.environ.get(KEEP_ENV, "").strip() not in ("", "0") or _backend_started():
        return ()
    current = os.environ.get("XLA_FLAGS", "")
    named = {tok.split("=", 1)[0] for tok in current.split()}
    added = tuple(f"{k}={v}" for k, v in flags_to_add(named).items())
    if added:
        os.environ["XLA_FLAGS"] = " ".join([*current.split(), *added])
    return added
