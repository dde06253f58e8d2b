"""Arrays built outside the compiled programs."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def as_f64(x) -> jax.Array:
    """``x`` as a float64 JAX array. Concrete data (numbers, NumPy arrays) is put on the
    device as it is: ``jnp.asarray`` of it is a small compiled program of its own, looked up
    (and, in a new process, loaded) each time a model is built. Traced values and JAX arrays
    go through ``jnp.asarray`` (no program for an array already float64)."""
    if isinstance(x, jax.Array):  # tracers included
        return jnp.asarray(x, dtype=jnp.float64)
    return jax.device_put(np.asarray(x, dtype=np.float64))


__all__ = ["as_f64"]
