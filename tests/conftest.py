"""Shared test setup: float64 JAX (enabled by importing mixdyn) and the fixture models.

The tests directory is put on ``sys.path`` so that test modules can ``from fixtures import ...``
(see ``tests/fixtures.py``) whatever pytest's import mode.
"""

import pathlib
import sys

import jax

import mixdyn  # noqa: F401  (enables float64)

sys.path.insert(0, str(pathlib.Path(__file__).parent))

assert jax.config.jax_enable_x64, "mixdyn must enable float64 on import"
