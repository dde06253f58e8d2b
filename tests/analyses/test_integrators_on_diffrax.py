"""The explicit integrators on ``diffrax.diffeqsolve`` (integrators/_constrained.py): outputs on
the constraints at exactly the output times, no step slivers before an output time, the work
bounded by ``max_steps``, and reverse-mode gradients through the loop against central finite
differences."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum_chain
from mixdyn.analysis._problem import Problem
from mixdyn.analysis.integrators import INTEGRATORS
from mixdyn.analysis.methods import OPTIONS
from mixdyn.errors import NumericalError


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_outputs_land_on_every_output_time_without_slivers():
    """A five-pendulum chain, 2 s, 201 outputs: diffrax's PID controller clipped to the output
    times left a sliver of a step before t = 0.98 and ended the run below its minimum step;
    the landing controller runs it through, with every output on the constraints and the
    same motion as a run 1000x tighter (the same program: tolerances are arguments)."""
    model = pendulum_chain(5)
    ts = np.linspace(0.0, 2.0, 201)
    r = md.forward(model, ts, rtol=1e-8, atol=1e-10, energy_tol=None)
    assert np.max(r.extra["constraint.violation"]) < 1e-12
    ref = md.forward(model, ts, method="partitioning", rtol=1e-11, atol=1e-13, energy_tol=None)
    assert np.max(np.abs(r.q - ref.q)) < 1e-6
    # about one step per output interval and a few rejections, not thousands of slivers
    assert r.stats["steps"] < 2 * len(ts)


def test_fixed_step_count_is_exact():
    """A fixed step lands on the output times: 0.5 s at dt = 1e-3 with outputs every 0.05 s
    is 500 steps exactly, whatever rounding ``t + dt`` makes."""
    model = pendulum_chain(2)
    ts = np.linspace(0.0, 0.5, 11)
    for method in ("baumgarte", "projection"):
        r = md.forward(model, ts, method=method, dt=1e-3, energy_tol=None)
        assert r.stats["steps"] == 500, method
        assert r.stats["rejected_steps"] == 0


def test_step_limit_is_a_named_failure():
    """``max_steps`` too small for the span ends the run with the step-limit message."""
    model = pendulum_chain(2)
    with pytest.raises(NumericalError, match="step limit"):
        md.forward(model, np.linspace(0, 1, 11), max_steps=5, energy_tol=None)


def _final_angle_coordinate(method, mass, **options):
    """The last body's x at the end of 0.3 s of a two-pendulum chain, as a function of the
    first body's mass [model units], through the integrator alone (differentiable)."""
    model = pendulum_chain(2)
    prep = md.prepare(model, md.analyses.Forward()).start
    model = eqx.tree_at(lambda m: m.bodies[0].mass, model, mass)
    problem = Problem(model, prep.constraints(method == "partitioning"))
    ts = jnp.linspace(0.0, 0.3, 4)
    traj = INTEGRATORS[method](problem, ts, prep.q, prep.qd, OPTIONS[method](**options))
    return traj.q[-1, 3]


@pytest.mark.slow  # 20-45 s of compiling the reverse pass
@pytest.mark.parametrize(
    ("method", "options"),
    [("projection", {}), ("partitioning", {}), ("baumgarte", {"dt": 1e-3})],
)
def test_reverse_mode_gradient_through_the_loop(method, options):
    """``jax.grad`` (reverse mode, diffrax's checkpointed loop) of a final coordinate with
    respect to a mass, against central finite differences of the same integrator."""
    f = lambda m: _final_angle_coordinate(method, m, **options)  # noqa: E731
    m0 = 1.0
    g = float(jax.grad(f)(m0))
    h = 1e-5
    fd = float((f(m0 + h) - f(m0 - h)) / (2 * h))
    assert abs(g) > 1e-4  # the mass matters to the motion
    assert g == pytest.approx(fd, rel=1e-6, abs=1e-9)


def _hundred_down(prevbefore):
    """diffrax's end-of-interval floor: ``t1`` moved down by 100 calls of ``prevbefore``."""

    def floor(t):
        for _ in range(100):
            t = prevbefore(t)
        return t

    return floor


def test_the_clip_floor_in_one_loop_gives_the_same_bits():
    """diffrax's 100 chained ``prevbefore`` calls, computed as one loop from the chain's start
    (runtime/_clip_floor.py), give the chain's bits for every kind of number (zeros,
    subnormals, the smallest normal, infinities, NaN, the largest finite), jitted, vmapped
    and eagerly; a call off the chain starts a new one; the lowered program holds one copy of
    ``nextafter`` instead of a hundred."""
    import diffrax._integrate
    import equinox.internal as eqxi

    from mixdyn.runtime._clip_floor import ChainedPrevbefore

    tiny = np.finfo(np.float64).tiny
    big = np.finfo(np.float64).max
    finite = [0.0, -0.0, 2.0, 1e-300, 5e-324, 3e-322, tiny, 100 * tiny, -3 * tiny, -1.0, 1e6]
    values = np.array([*finite, np.inf, -np.inf, np.nan, big, -big])
    chained = ChainedPrevbefore(eqxi.prevbefore)
    want = np.asarray(jax.jit(jax.vmap(_hundred_down(eqxi.prevbefore)))(values))
    got = np.asarray(jax.jit(jax.vmap(_hundred_down(chained)))(values))
    np.testing.assert_array_equal(want.view(np.int64), got.view(np.int64))
    grads = [jax.grad(_hundred_down(p))(2.0) for p in (chained, eqxi.prevbefore)]
    assert grads == [1.0, 1.0]  # prevbefore's derivative: the tangent passes through
    eager = np.asarray(_hundred_down(chained)(jnp.asarray(2.0)))
    assert eager.view(np.int64) == np.asarray(2.0).view(np.int64) - 100
    a = chained(jnp.asarray(1.0))
    chained(jnp.asarray(3.0))  # another chain in between: a's continues from a itself
    assert np.asarray(chained(a)) == np.nextafter(np.nextafter(1.0, 0.0), 0.0)
    # diffrax's while mixdyn traces one of its solves (checked versions), one loop when lowered
    from mixdyn.runtime import _private

    if not _private.allowed("diffrax"):
        return
    with _private.chained_floor():
        assert isinstance(diffrax._integrate.eqxi.prevbefore, ChainedPrevbefore)
        text = jax.jit(_hundred_down(diffrax._integrate.eqxi.prevbefore)).lower(1.0).as_text()
    assert diffrax._integrate.eqxi is eqxi
    before = jax.jit(_hundred_down(eqxi.prevbefore)).lower(1.0).as_text()
    assert text.count("bitcast_convert") * 50 <= before.count("bitcast_convert")
