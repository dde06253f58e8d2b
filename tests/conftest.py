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


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop JAX's compiled programs after each test module: a whole session compiles
    hundreds of them, and the XLA CPU compiler crashed (segmentation fault) late in long
    sessions on this 2-core machine; each module compiles what it needs afresh."""
    yield
    jax.clear_caches()
