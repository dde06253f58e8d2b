"""Shared test setup: float64 JAX (enabled by importing mixdyn) and the fixture models.

The tests directory is put on ``sys.path`` so that test modules can ``from fixtures import ...``
(see ``tests/fixtures.py``) whatever pytest's import mode.
"""

import os
import pathlib
import sys

# The CLI tests call the CLI in this process: keep them from turning on JAX's persistent
# compilation cache for every later test (and from writing to the user's cache folder).
os.environ.setdefault("MIXDYN_NO_CACHE", "1")

import jax
import pytest

import mixdyn  # noqa: F401  (enables float64)

sys.path.insert(0, str(pathlib.Path(__file__).parent))

assert jax.config.jax_enable_x64, "mixdyn must enable float64 on import"

#: Share of the system's limit on memory mappings per process (``vm.max_map_count``, 65530 by
#: default) above which JAX's compiled programs are dropped after a test module.
CLEAR_CACHES_AT_MAPPINGS = 0.5


def memory_mappings() -> tuple[int, int]:
    """``(mappings, limit)``: the test process's memory mappings and the system's limit on
    them (``(0, 1)`` where ``/proc`` is not there)."""
    try:
        with open("/proc/sys/vm/max_map_count") as f:
            limit = int(f.read())
        with open("/proc/self/maps", "rb") as f:
            return sum(1 for _ in f), limit
    except (OSError, ValueError):
        return 0, 1


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop JAX's compiled programs after a test module once the process holds more than
    half the memory mappings it may: every compiled program keeps a few mappings (its code),
    a whole session compiles thousands of them, and at the system's limit (65530) the XLA CPU
    compiler cannot map the next one and crashes (segmentation fault; measured: 16,000
    mappings after two of the heavier modules, the crash late in a session that kept every
    program). Below that the programs are kept, so that later modules reuse what they share
    (clearing after every module cost minutes of recompiling)."""
    yield
    mappings, limit = memory_mappings()
    if mappings > CLEAR_CACHES_AT_MAPPINGS * limit:
        jax.clear_caches()
