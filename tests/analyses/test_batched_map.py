"""``batched_map``: a function over a leading axis, a batch vectorized at a time, against the
plain loop (``jax.lax.map`` without batches), including outputs of no entries (a model
without constraints has multipliers of shape (N, 0), on which ``jax.lax.map``'s batches fail)
and a count that the batch does not divide."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from jax import lax

from mixdyn.analysis._schedule import batched_map


def f(x):
    a, b = x
    return {"sum": a.sum() + b, "scaled": 2.0 * a, "none": jnp.zeros((a.shape[0], 0))}


@pytest.mark.parametrize(("n", "batch"), [(6, 2), (7, 3), (2, 5), (4, 4)])
def test_batched_map_equals_the_plain_loop(n, batch):
    xs = (np.arange(n * 3.0).reshape(n, 3), np.linspace(0.0, 1.0, n))
    got = batched_map(f, xs, batch)
    want = lax.map(f, xs)
    for key in want:
        assert got[key].shape == want[key].shape
        np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]))
    assert got["none"].shape == (n, 3, 0)
