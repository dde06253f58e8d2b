"""Gradients of dynamic runs (``md.differentiable``) against central finite differences of
the same runs at tight tolerances; the function's value equals ``md.forward``'s; a failed run
gives NaN, never a finite wrong number; numbers that shape the constraints are refused."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES, double_four_bar, paper_under_loads, slider_crank

TS = np.linspace(0.0, 0.5, 11)
PARAMS = ["slider.mass", "crank.inertia", "F1.law.amplitude", "T2.law.value"]
SLIDER_X = 9  # q index of the slider's x


@pytest.fixture(scope="module")
def paper():
    return paper_under_loads()


def _check_gradient(f, th0, rel=1e-6):
    """``jax.grad`` of the RMS of the slider's x against central differences (step 1e-5 of
    each number), each entry within ``rel`` of the largest."""

    def objective(th):
        return jnp.sqrt(jnp.mean(f(th)["q"][:, SLIDER_X] ** 2))

    run = jax.jit(objective)
    g = np.asarray(jax.jit(jax.grad(objective))(th0))
    fd = np.zeros_like(g)
    for k in range(len(th0)):
        e = np.zeros_like(th0)
        e[k] = h = 1e-5 * abs(th0[k])
        fd[k] = (float(run(th0 + e)) - float(run(th0 - e))) / (2 * h)
    assert np.all(np.abs(g - fd) <= rel * np.abs(fd) + 1e-9 * np.max(np.abs(fd))), (g, fd)
    assert np.all(np.abs(fd) > 1e-6)  # every number moves the slider


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
@pytest.mark.timeout(600)
def test_projection_gradient_against_finite_differences(paper):
    f, th0 = md.differentiable(paper, TS, PARAMS, rtol=1e-12, atol=1e-12)
    _check_gradient(f, th0)


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
@pytest.mark.timeout(600)
def test_forward_mode_jacobian_against_finite_differences(paper):
    """``derivatives="forward"``: ``jax.jacfwd`` of the slider's whole motion (51 outputs)
    with respect to four numbers, column by column against central differences."""
    f, th0 = md.differentiable(paper, TS, PARAMS, rtol=1e-12, atol=1e-12, derivatives="forward")

    def motion(th):
        return f(th)["q"][:, SLIDER_X]

    J = np.asarray(jax.jit(jax.jacfwd(motion))(th0))
    run = jax.jit(motion)
    for k in range(len(th0)):
        e = np.zeros_like(th0)
        e[k] = h = 1e-5 * abs(th0[k])
        fd = (np.asarray(run(th0 + e)) - np.asarray(run(th0 - e))) / (2 * h)
        assert np.max(np.abs(J[:, k] - fd)) <= 1e-6 * np.max(np.abs(fd)), k
    with pytest.raises(ValueError, match="while_loop"):  # no reverse mode in this function
        jax.grad(lambda th: motion(th)[-1])(th0)


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize(
    "opts",
    [dict(method="partitioning", rtol=1e-12, atol=1e-12), dict(method="baumgarte", dt=1e-3)],
    ids=["partitioning", "baumgarte"],
)
def test_other_integrators_gradient_against_finite_differences(paper, opts):
    f, th0 = md.differentiable(paper, TS, PARAMS, **opts)
    _check_gradient(f, th0)


@pytest.mark.slow  # about 30 s; CI runs it
@pytest.mark.timeout(900)
def test_gradient_through_singular_positions_against_finite_differences():
    """The IFToMM double four-bar over 2 s passes two flat positions (cranks horizontal:
    the parallelograms' branch points, where the constraints lose rank); the derivative of a
    crank's final angle with respect to the masses agrees with central differences to 1e-6.
    (Differences at steps of 1e-3 and 1e-2 of the mass agree to 2e-6 of each other.)"""
    model, qd0 = double_four_bar(2)
    ts = np.linspace(0.0, 2.0, 21)
    f, th0 = md.differentiable(
        model, ts, ["crank0.mass", "coupler0.mass"], qd0=qd0, rtol=1e-10, atol=1e-10
    )
    crank = 2  # q index of crank0's phi

    def objective(th):
        return f(th)["q"][-1, crank]

    run = jax.jit(objective)
    phi = np.asarray(jax.jit(f)(th0)["q"][:, crank])
    # the cranks pass the horizontal (phi = 0 mod pi) twice
    assert np.count_nonzero(np.diff(np.floor(phi / np.pi))) == 2, phi
    g = np.asarray(jax.jit(jax.grad(objective))(th0))
    for k in range(len(th0)):
        e = np.zeros_like(th0)
        e[k] = h = 1e-3 * abs(th0[k])
        fd = (float(run(th0 + e)) - float(run(th0 - e))) / (2 * h)
        assert abs(fd) > 1e-3
        assert abs(g[k] - fd) <= 1e-6 * abs(fd), (k, g[k], fd)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_mixed_run_gradient_against_finite_differences(paper):
    """The paper's mixed run (F1 unknown, the slider's x prescribed by a law): the motion of
    the free coordinate (the crank) as a function of the masses and T2."""
    drive = md.CoordinateDriver("xs", "slider", "x", law=md.Harmonic(2.0, 3.0, offset=80.0))
    f, th0 = md.differentiable(
        paper,
        TS,
        ["crank.mass", "coupler.inertia", "T2.law.value"],
        analysis="mixed",
        prescribed=[drive],
        unknown=["F1"],
        rtol=1e-12,
        atol=1e-12,
    )
    crank = 2  # q index of the crank's phi

    def objective(th):
        return jnp.sum(f(th)["q"][:, crank] ** 2)

    g = np.asarray(jax.grad(objective)(th0))
    run = jax.jit(objective)
    for k in range(len(th0)):
        e = np.zeros_like(th0)
        e[k] = h = 1e-5 * abs(th0[k])
        fd = (float(run(th0 + e)) - float(run(th0 - e))) / (2 * h)
        assert abs(g[k] - fd) <= 1e-6 * abs(fd), (k, g[k], fd)


@pytest.mark.slow  # long: run by CI's slow set
def test_value_equals_the_forward_run_and_failure_is_nan(paper):
    f, th0 = md.differentiable(paper, TS, PARAMS, rtol=1e-10, atol=1e-10)
    ref = md.forward(paper, TS, rtol=1e-10, atol=1e-10)
    out = f(th0)
    # The same equations and steps; md.forward's programs carry mixdyn's XLA options, a
    # program around md.differentiable's function is compiled with JAX's: the last bits only.
    scale = np.max(np.abs(ref.q))
    np.testing.assert_allclose(np.asarray(out["q"]), ref.q, rtol=0, atol=1e-13 * scale)
    # a heavier slider moves less: the numbers reach the equations
    heavier = np.asarray(f(th0 * np.array([10.0, 1.0, 1.0, 1.0]))["q"])[-1, SLIDER_X]
    assert abs(heavier - ref["slider.x"][-1]) > 1e-3
    g, _ = md.differentiable(paper, TS, PARAMS, rtol=1e-10, atol=1e-10, max_steps=3)
    assert np.all(np.isnan(np.asarray(g(th0)["q"])))


@pytest.mark.parametrize(
    ("params", "words"),
    [
        (["EF.angle"], "shape the constraints"),
        (["slider.q0"], "scalar"),
        ("slider.mass", "list of paths"),
        (["slider.mas"], "no field 'mas'"),
    ],
    ids=["joint", "vector", "string", "typo"],
)
def test_bad_params_are_refused(paper, params, words):
    with pytest.raises(md.ModelError) as err:
        md.differentiable(paper, TS, params)
    assert words in str(err.value)


@pytest.mark.slow  # long: run by CI's slow set
def test_inverse_reactions_are_differentiable_and_newton_says_how():
    """An inverse run's reactions and efforts as functions of the masses and inertias: the
    values are md.inverse's; the sum of the ground joints' forces on the bodies is
    ``sum_i m_i a_i`` (no applied forces), so its derivative with respect to ``m_i`` is body
    i's acceleration and with respect to an inertia 0 (forward mode, exact to rounding); the
    reverse-mode gradient of the RMS motor torque agrees with central differences."""
    model = slider_crank(omega=3.0)
    t = np.linspace(0.0, 1.5, 31)
    params = ["crank.mass", "rod.mass", "slider.mass", "rod.inertia"]
    f, th0 = md.differentiable(model, t, params, analysis="inverse")
    ref = md.inverse(model, t)
    out = f(th0)
    for c in ("O.Fx", "A.Fy", "slide.M", "motor"):
        np.testing.assert_allclose(
            np.asarray(out[c]), ref[c], rtol=0, atol=1e-12 * np.max(np.abs(ref[c]))
        )

    def ground_force(th):
        o = f(th)
        return jnp.stack([o["O.Fx"] + o["slide.Fx"], o["O.Fy"] + o["slide.Fy"]], -1)

    J = np.asarray(jax.jacfwd(ground_force)(th0))  # (N, 2, P)
    for k, body in enumerate(("crank", "rod", "slider")):
        a = np.stack([ref[f"{body}.ax"], ref[f"{body}.ay"]], -1)
        np.testing.assert_allclose(J[..., k], a, rtol=0, atol=1e-10 * np.max(np.abs(a)))
    assert np.max(np.abs(J[..., 3])) <= 1e-12

    def rms_torque(th):
        return jnp.sqrt(jnp.mean(f(th)["motor"] ** 2))

    g = np.asarray(jax.grad(rms_torque)(th0))
    fd = np.zeros_like(g)
    for k in range(len(th0)):
        e = np.zeros_like(th0)
        e[k] = h = 1e-6 * th0[k]
        fd[k] = (float(rms_torque(th0 + e)) - float(rms_torque(th0 - e))) / (2 * h)
    # the crank turns at a constant speed about a fixed pivot: its mass needs no torque
    assert abs(g[0]) <= 1e-12 and np.all(np.abs(fd[1:]) > 1e-3)
    assert np.all(np.abs(g - fd) <= 1e-7 * np.abs(fd) + 1e-9 * np.max(np.abs(fd))), (g, fd)
    with pytest.raises(md.ModelError, match="depends on no number"):
        md.differentiable(model, t, params, analysis="kinematic")


def test_generalized_alpha_is_refused(paper):
    with pytest.raises(md.ModelError, match="generalized-alpha is not differentiable"):
        md.differentiable(paper, TS, PARAMS, method="generalized-alpha", dt=1e-3)


@pytest.mark.slow  # two fits of a 2 s run (about 15 s); CI runs it
@pytest.mark.timeout(900)
@pytest.mark.parametrize("seed", [0, 1])
def test_identification_recovers_the_numbers_within_the_noise(seed):
    """``examples/identify_slider_crank.py``: masses, inertia and a damper coefficient fitted
    to a noisy recording lie within 4 standard deviations (from the fit's Jacobian) of the
    truth, and the reduced chi-square is that of the noise (198 degrees of freedom: 1 +- 0.3)."""
    import importlib.util

    path = EXAMPLES / "identify_slider_crank.py"
    spec = importlib.util.spec_from_file_location("identify_slider_crank", path)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    est, sd, truth, chi2 = example.identify(seed)
    np.testing.assert_array_equal(truth, example.TRUE)
    assert np.all(np.abs(est - truth) <= 4 * sd), (est, sd)
    assert np.all(sd < 0.02 * truth)  # the recording does identify every number
    assert 0.7 < chi2 < 1.3
