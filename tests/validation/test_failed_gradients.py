"""A failed run inside ``md.differentiable`` gives NaN derivatives, not zero (issue 31, part
2, item 4), in reverse mode (``jax.grad``) and forward mode (``jax.jacfwd``); a good run's
derivatives are unchanged and agree with central finite differences.

The model is a mass on a spring and damper (``fixtures.spring_slider``): at the nominal
stiffness the run takes a few dozen steps; a million times stiffer, it needs far more than
``max_steps`` and fails (status: step limit), from the same function ``f``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import spring_slider
from mixdyn.analysis.gradients import nan_if_failed

TS = np.linspace(0.0, 0.5, 6)
PARAMS = ["spring.stiffness", "slider.mass"]


def _final_x(f):
    return lambda th: f(th)["q"][-1, 0]


@pytest.fixture(scope="module")
def runs():
    model = spring_slider()
    out = {}
    for mode in ("reverse", "forward"):
        out[mode] = md.differentiable(
            model, TS, PARAMS, derivatives=mode, rtol=1e-10, atol=1e-12, max_steps=400
        )
    return out


def _central(fun, th0, rel=1e-5):
    fd = np.zeros_like(th0)
    for k in range(th0.size):
        e = np.zeros_like(th0)
        e[k] = h = rel * abs(th0[k])
        fd[k] = (float(fun(th0 + e)) - float(fun(th0 - e))) / (2 * h)
    return fd


@pytest.mark.slow  # long: run by CI's slow set
def test_a_good_runs_derivatives_agree_with_finite_differences(runs):
    f, th0 = runs["reverse"]
    x = jax.jit(_final_x(f))
    assert np.isfinite(float(x(th0)))
    fd = _central(x, th0)
    g = np.asarray(jax.grad(_final_x(f))(th0))
    np.testing.assert_allclose(g, fd, rtol=1e-5)
    ff, _ = runs["forward"]
    J = np.asarray(jax.jacfwd(lambda th: ff(th)["q"][:, 0])(th0))
    np.testing.assert_allclose(J[-1], fd, rtol=1e-5)
    assert np.all(np.isfinite(J))


@pytest.mark.parametrize(
    "mode",
    ["reverse", pytest.param("forward", marks=pytest.mark.slow)],  # slow: CI's slow set
)
def test_a_failed_run_gives_nan_value_and_nan_derivatives(runs, mode):
    """A million times stiffer: the run hits max_steps; value, jax.grad and jax.jacfwd of
    every output are NaN (they were exactly 0.0)."""
    f, th0 = runs[mode]
    stiff = th0 * np.array([1e6, 1.0])
    out = f(stiff)
    assert all(np.all(np.isnan(np.asarray(out[k]))) for k in ("q", "qd", "w"))
    if mode == "reverse":
        g = np.asarray(jax.grad(_final_x(f))(stiff))
        energy = np.asarray(jax.grad(lambda th: jnp.sum(f(th)["w"]))(stiff))
        assert np.all(np.isnan(g)) and np.all(np.isnan(energy)), (g, energy)
    else:
        J = np.asarray(jax.jacfwd(lambda th: f(th)["q"])(stiff))
        assert np.all(np.isnan(J)), J


def test_nan_if_failed_leaves_a_good_derivative_exact_and_poisons_a_failed_one():
    """The operation itself: for ``ok`` its derivative is exactly the tangent in both modes
    (no NaN from the other branch leaks in); for not ``ok`` it is NaN; per member of a batch."""

    def y(th):
        return jnp.stack([jnp.sin(th), th**3])

    th = 0.7
    exact = np.array([np.cos(th), 3 * th**2])
    for ok, want in ((True, exact), (False, np.full(2, np.nan))):
        fwd = np.asarray(jax.jacfwd(lambda t, ok=ok: nan_if_failed(ok, y(t)))(th))
        rev = np.asarray(jax.jacrev(lambda t, ok=ok: nan_if_failed(ok, y(t)))(th))
        np.testing.assert_array_equal(fwd, want)
        np.testing.assert_array_equal(rev, want)
    oks = jnp.array([True, False, True])
    ths = jnp.array([0.1, 0.2, 0.3])
    g = np.asarray(jax.vmap(jax.grad(lambda t, ok: nan_if_failed(ok, jnp.sin(t))))(ths, oks))
    np.testing.assert_array_equal(g, [np.cos(0.1), np.nan, np.cos(0.3)])
