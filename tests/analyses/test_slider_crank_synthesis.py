"""Slider-crank path generation (mixdyn.synthesis, ``linkage="slider_crank"``) against
independent truths.

* the closed-form assembly against its closure equations (the rod's length, the slide), and
  (slow) its rod angle, slider pin, coupler point and transmission angle against mixdyn's
  own kinematic analysis of the built model (Newton's assembly of a revolute-translational
  model, a second method);
* derivatives through the implicit assembly against central finite differences; an
  infeasible slider-crank finite and its infeasibility measured;
* a search that recovers a known slider-crank from points sampled on its coupler curve, with
  prescribed and with free timing, and its written model file passing the points (slow);
* the motor torque of the energy balance against md.inverse's multipliers, its derivatives
  against finite differences, and the torque objective (slow).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import (
    Masses,
    Objective,
    PathTask,
    SliderCrank,
    coupler_curve,
    motor_torque,
    rod_and_slider,
    slider_crank_model,
    synthesize,
    transmission_cosine,
)

# An offset slider-crank [m, rad]: crank 0.1, rod 0.35, offset 0.04 (0.1 + 0.04 < 0.35: the
# crank turns fully), the coupler point off the rod, the pivot off the origin, the slide
# tilted by 0.25 rad.
V = np.array([0.1, 0.35, 0.04, 0.15, 0.08, 0.02, -0.01, 0.25])


def slider_crank(branch=1.0, v=V):
    return SliderCrank.from_vector(jnp.asarray(v), branch)


@jax.jit
def _closed_form(sc, theta):
    """``(C (K, 2), phi3 (K,), B (K, 2), cos mu (K,))`` of the closed form at ``theta``."""
    phi3, s = jax.vmap(lambda a: rod_and_slider(sc, a))(theta)
    p0, d = sc.slide()
    cos_mu = jax.vmap(lambda a: transmission_cosine(sc, a))(theta)
    return coupler_curve(sc, theta), phi3, p0 + s[:, None] * d, cos_mu


def _cross(d, w):
    """``d x w`` (K,) of a direction (2,) and vectors (K, 2)."""
    return d[0] * w[:, 1] - d[1] * w[:, 0]


def test_closed_form_closes_the_loop_on_its_branch():
    """Over a full crank turn, on each branch: the pin B lies on the slide at the rod's
    length from the crank pin, along the rod's angle, ahead of A along the slide on branch
    +1 and behind it on -1; the two branches differ."""
    theta = jnp.linspace(0.0, 2 * np.pi, 73)
    pins = []
    for branch in (1.0, -1.0):
        sc = slider_crank(branch)
        _, phi3, b, cos_mu = (np.asarray(x) for x in _closed_form(sc, theta))
        a = np.asarray(jax.vmap(sc.crank_pin)(theta))
        p0, d = (np.asarray(x) for x in sc.slide())
        ab = b - a
        np.testing.assert_allclose(np.linalg.norm(ab, axis=1), V[1], rtol=1e-14)
        np.testing.assert_allclose(_cross(d, b - p0), 0.0, atol=1e-15)  # on the slide
        np.testing.assert_allclose(
            ab, V[1] * np.stack([np.cos(phi3), np.sin(phi3)], -1), atol=1e-15
        )
        assert np.all(branch * (ab @ d) > 0)
        np.testing.assert_allclose(cos_mu, _cross(d, a - p0) / V[1], atol=1e-15)  # h / r3
        pins.append(b)
    assert np.max(np.abs(pins[0] - pins[1])) > 0.1


@pytest.mark.slow  # long: run by CI's slow set (compiles the model's kinematic analysis)
@pytest.mark.parametrize("branch", [1.0, -1.0])
def test_closed_form_is_mixdyns_kinematic_analysis(branch):
    """Over a full crank turn the built model's kinematic analysis (the rod's and slider's
    coordinates from Newton's assembly) gives the closed form's coupler point, rod angle and
    slider pin to 1e-9; the transmission cosine is the rod's angle to the slide as defined
    (cos mu = -sin(phi3 - theta0): mu between the rod and the slide's normal), within ±1
    along a turn that closes."""
    sc = slider_crank(branch)
    start, speed = 0.4, 2.0
    t = np.linspace(0.0, 2 * np.pi / speed, 37)
    model = slider_crank_model(sc, start=start, speed=speed)
    kin = md.kinematic(model, t)
    curve, phi3, b, cos_mu = (
        np.asarray(x) for x in _closed_form(sc, jnp.asarray(start + speed * t))
    )
    rod = next(body for body in model.bodies if body.name == "rod")
    local = np.asarray(rod.points["P"])
    phi = kin["rod.phi"]
    rot = np.stack([[np.cos(phi), -np.sin(phi)], [np.sin(phi), np.cos(phi)]])
    p = np.stack([kin["rod.x"], kin["rod.y"]], -1) + np.einsum("ijk,j->ki", rot, local)
    assert np.max(np.abs(p - curve)) < 1e-9
    assert np.max(np.abs(np.angle(np.exp(1j * (phi - phi3))))) < 1e-9
    slider = np.stack([kin["slider.x"], kin["slider.y"]], -1)  # its frame at the pin B
    assert np.max(np.abs(slider - b)) < 1e-9
    np.testing.assert_allclose(cos_mu, -np.sin(phi - V[7]), atol=1e-9)
    assert np.max(np.abs(cos_mu)) < 1.0


def _curve(x):
    """The coupler point and slider position at the input angles x[8:] of the slider-crank
    x[:8] (branch +1)."""
    sc = slider_crank(1.0, x[:8])
    s = jax.vmap(lambda a: rod_and_slider(sc, a)[1])(x[8:])
    return jnp.concatenate([coupler_curve(sc, x[8:]).ravel(), s])


def test_derivatives_are_finite_differences_and_infeasible_is_finite():
    """d(C, s)/d(numbers, theta2) through the implicit rule, forward and reverse, against
    central differences; a rod too short to reach the slide: finite values and derivatives,
    |cos mu| > 1."""
    x = jnp.concatenate([jnp.asarray(V), jnp.array([0.4, 2.5, -1.0])])
    f = jax.jit(_curve)
    jf = np.asarray(jax.jit(jax.jacfwd(_curve))(x))
    jr = np.asarray(jax.jit(jax.jacrev(_curve))(x))
    h = 1e-6
    fd = np.stack([(f(x.at[k].add(h)) - f(x.at[k].add(-h))) / (2 * h) for k in range(len(x))], -1)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(jf - fd)) < 1e-7 * scale
    assert np.max(np.abs(jr - jf)) < 1e-12 * scale
    short = x.at[1].set(0.05)  # rod 0.05 < the crank pin's height above the slide
    assert abs(float(transmission_cosine(slider_crank(1.0, short[:8]), 1.5))) > 1.0
    jac = jax.jit(jax.jacfwd(_curve))(short)
    assert np.all(np.isfinite(f(short))) and np.all(np.isfinite(np.asarray(jac)))


def test_a_slider_cranks_task_is_checked_by_its_numbers():
    points = np.array([[0.0, 0.0], [0.1, 0.05], [0.15, 0.12]])
    with pytest.raises(ModelError, match="no number 'r4' of a slider-crank"):
        PathTask(points, bounds={"r4": (0.1, 0.2)}, linkage="slider_crank")
    with pytest.raises(ModelError, match="no linkage 'slider-crank'"):
        PathTask(points, linkage="slider-crank")
    box = PathTask(points, bounds={"e": (-0.01, 0.02)}, linkage="slider_crank").box()
    assert box.shape == (8, 2) and tuple(box[2]) == (-0.01, 0.02)
    with pytest.raises(ModelError, match="slider"):
        slider_crank_model(slider_crank(), Masses(density=1.0))  # a slider of no mass
    task = PathTask(points, linkage="slider_crank")
    with pytest.raises(ModelError, match="slider"):  # before any search
        synthesize(task, Objective(masses=Masses(density=1.0)), starts=1)


@pytest.mark.slow  # long: run by CI's slow set (two searches compile their programs)
def test_search_recovers_a_known_slider_crank(tmp_path):
    """Six points of the fixture's coupler curve: with their input angles given, the best
    slider-crank passes them (path error <= 1e-8, in fact ~0) and is the fixture; timing-free,
    the best passes them too. The written model file, loaded and run by mixdyn's kinematic
    analysis, passes the points."""
    theta = np.linspace(0.3, 4.0, 6)
    points = np.asarray(coupler_curve(slider_crank(1.0), theta))
    task = PathTask(points, timing=theta, linkage="slider_crank")
    out = synthesize(task, starts=64, chunk=64, seed=1)
    best = out.best
    assert best.error <= 1e-8 and best.error < 1e-20
    assert isinstance(best.linkage, SliderCrank)
    found = np.array([best.numbers()[n] for n in SliderCrank.NAMES])
    found[-1] = np.angle(np.exp(1j * (found[-1] - V[-1]))) + V[-1]
    np.testing.assert_allclose(found, V, atol=1e-8)
    out.write(tmp_path / "best.yaml")
    loaded = md.load(tmp_path / "best.yaml")
    kin = md.kinematic(loaded.model, (best.angles - best.angles[0]) / out.objective.speed)
    p, _, _ = kin.point("rod.P")
    assert np.max(np.abs(p - points)) < 1e-9
    free = synthesize(PathTask(points, linkage="slider_crank"), starts=64, chunk=64, seed=1)
    assert free.best.error <= 1e-8 and np.all(np.diff(free.best.angles) > 0)


@pytest.mark.slow  # long: run by CI's slow set (compiles the model's inverse analysis)
def test_motor_torque_is_mixdyns_inverse_dynamics():
    """The built model (bars of 2 kg/m, a payload, a slider of 0.7 kg, gravity) run by
    md.inverse: the motor torque (Lagrange multipliers) equals the energy balance's over a
    full turn on both branches."""
    masses = Masses(density=2.0, payload=0.3, slider=0.7)
    start, speed = 0.4, 3.0
    t = np.linspace(0.0, 2 * np.pi / speed, 25)
    for branch in (1.0, -1.0):
        sc = slider_crank(branch)
        inv = md.inverse(slider_crank_model(sc, masses, start=start, speed=speed), t)
        tau = np.asarray(motor_torque(sc, masses, start + speed * t, speed))
        assert np.max(np.abs(inv["motor"] - tau)) < 1e-9 * np.max(np.abs(tau))
        assert np.max(np.abs(tau)) > 1.0  # a real load


@pytest.mark.slow  # long: run by CI's slow set (third derivatives through the assembly)
def test_torque_derivatives_are_finite_differences():
    """d tau / d(numbers, theta2): the torque is itself a second derivative of the assembly
    (the slider's acceleration along the slide among its terms)."""
    masses = Masses(density=1.5, payload=0.2, slider=0.4)

    def f(x):
        return motor_torque(slider_crank(-1.0, x[:8]), masses, x[8:], 3.0)

    x = jnp.concatenate([jnp.asarray(V), jnp.array([0.4, 2.5, -1.0])])
    jf = np.asarray(jax.jit(jax.jacfwd(f))(x))
    jr = np.asarray(jax.jit(jax.jacrev(f))(x))
    g = jax.jit(f)
    h = 1e-6
    fd = np.stack([(g(x.at[k].add(h)) - g(x.at[k].add(-h))) / (2 * h) for k in range(len(x))], -1)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(jf - fd)) < 1e-6 * scale
    assert np.max(np.abs(jr - jf)) < 1e-12 * scale


@pytest.mark.slow  # long: run by CI's slow set (the torque term compiles third derivatives)
def test_torque_objective_searches_a_slider_crank():
    """Timing-free, with the RMS torque by weight: the best still passes the points (~0
    error) and reports the torque of its own model's inverse dynamics."""
    theta = np.linspace(0.3, 4.0, 6)
    points = np.asarray(coupler_curve(slider_crank(1.0), theta))
    masses, speed = Masses(density=2.0, payload=0.3, slider=0.5), 6.0
    objective = Objective(masses=masses, speed=speed, torque_weight=1e-4)
    out = synthesize(PathTask(points, linkage="slider_crank"), objective, starts=32, seed=1)
    c = out.best
    assert c.error < 1e-16
    t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / speed, 129)
    tau = md.inverse(out.model(), t)["motor"]
    assert np.sqrt(np.mean(tau**2)) == pytest.approx(c.torque_rms, rel=0.02)
