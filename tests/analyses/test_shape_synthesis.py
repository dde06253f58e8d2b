"""Shape-only path synthesis (mixdyn.synthesis.ShapeTask) against independent truths.

* the normalised elliptic Fourier descriptors of a curve equal those of the same curve moved,
  turned, scaled and started elsewhere, and the similarity recovered from them is the one
  applied; a different shape differs;
* an ellipse's descriptors against its closed-form arc length (the complete and incomplete
  elliptic integrals, scipy) integrated by adaptive quadrature; a circle's: its radius;
* the shape error's derivatives through the assembly against central differences;
* a search on points of a known four-bar's coupler curve, scaled, turned and moved, finds a
  linkage of that shape, placed onto the points; its written model, run by mixdyn's
  kinematic analysis, passes them (slow).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, special

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import FourBar, Masses, Objective, ShapeTask, coupler_curve, synthesize
from mixdyn.synthesis._fourier import describe, normalise, shape_error, shape_gap, similarity
from mixdyn.synthesis._shape import _make, normalised


def _curve(t):
    """A smooth closed curve without symmetry at the parameter values ``t``."""
    return np.c_[
        np.cos(t) + 0.3 * np.cos(2 * t + 0.4) + 0.05 * np.sin(3 * t),
        0.6 * np.sin(t) + 0.2 * np.sin(3 * t) - 0.1 * np.cos(2 * t),
    ]


_describe = jax.jit(describe, static_argnums=1)


def _rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def test_normalised_descriptors_are_invariant_and_give_the_similarity():
    """Moved by (3, -4), turned by 1.1 rad, scaled by 2.5 and started 0.37 rad later along
    its parameter: the same normalised descriptors (1e-10); the similarity from them is the
    one applied; another curve is another shape."""
    t = np.linspace(0.0, 2 * np.pi, 512, endpoint=False)
    scale, angle, shift = 2.5, 1.1, np.array([3.0, -4.0])
    base = normalised(_curve(t), 8)
    moved = normalised(scale * _curve(t + 0.37) @ _rot(angle).T + shift, 8)
    gap, flip = shape_gap(base, moved)
    assert np.max(np.abs(np.asarray(gap))) < 1e-10
    s, a, d = (np.asarray(x) for x in similarity(base, moved, flip))
    assert abs(s - scale) < 1e-10 * scale
    assert abs(np.angle(np.exp(1j * (a - angle)))) < 1e-10
    assert np.max(np.abs(d - shift)) < 1e-9
    other = np.c_[np.cos(t) + 0.3 * np.cos(2 * t), 0.6 * np.sin(t)]  # symmetric: not the same
    assert float(shape_error(normalised(other, 8), base)) > 1e-3


def test_ellipse_descriptors_against_its_arc_length():
    """x = a cos t, y = b sin t: the perimeter 4 a E(m) and the harmonics ``(2/L) int x
    cos(2 pi n l / L) dl`` with the arc length ``l(t) = a (E(m) - E(pi/2 - t | m))``
    (quadrature); the even harmonics and the cross terms vanish (symmetry); a circle's first
    harmonic is its radius on both axes, the rest zero."""
    a, b = 2.0, 1.0
    m = 1.0 - (b / a) ** 2
    perimeter = 4 * a * special.ellipe(m)
    t = np.linspace(0.0, 2 * np.pi, 256, endpoint=False)
    d = _describe(np.c_[a * np.cos(t), b * np.sin(t)], 5)
    assert abs(float(d.perimeter) - perimeter) < 1e-12 * perimeter

    def arc(t):
        return a * (special.ellipe(m) - special.ellipeinc(np.pi / 2 - t, m))

    def speed(t):
        return np.sqrt((a * np.sin(t)) ** 2 + (b * np.cos(t)) ** 2)

    def harmonic(x, wave, n):
        f = lambda t: x(t) * wave(2 * np.pi * n * arc(t) / perimeter) * speed(t)  # noqa: E731
        return 2 * integrate.quad(f, 0, 2 * np.pi, limit=200)[0] / perimeter

    coefficients = np.asarray(d.coefficients)
    for n in (1, 3, 5):
        an = harmonic(lambda t: a * np.cos(t), np.cos, n)
        dn = harmonic(lambda t: b * np.sin(t), np.sin, n)
        assert abs(coefficients[n - 1, 0, 0] - an) < 1e-10
        assert abs(coefficients[n - 1, 1, 1] - dn) < 1e-10
    assert np.max(np.abs(coefficients[[1, 3]])) < 1e-12
    assert np.max(np.abs(coefficients[:, [0, 1], [1, 0]])) < 1e-12
    assert coefficients[0, 0, 0] > coefficients[0, 1, 1] > b  # the first harmonic's semi-axes
    circle = np.asarray(_describe(0.7 * np.c_[np.cos(t), np.sin(t)], 5).coefficients)
    assert np.max(np.abs(circle[0] - 0.7 * np.eye(2))) < 1e-12
    assert np.max(np.abs(circle[1:])) < 1e-12


_EXACT = np.array([0.35, 1.1, 0.9, 0.6, 0.4])  # r2, r3, r4, rcx, rcy over r1 = 1: a crank-rocker


def _shape_of(target):
    """The shape error of variables u against ``target``'s normalised descriptors."""
    angles = jnp.linspace(0.0, 2 * np.pi, 64, endpoint=False)

    def f(u):
        lk = _make(FourBar, u, 1.0)
        return shape_error(normalise(describe(jax.vmap(lk.coupler_point)(angles), 6)), target)

    return f


@pytest.mark.slow  # long: run by CI's slow set (derivatives through the assembly compile)
def test_shape_error_derivatives_are_finite_differences():
    """d e / d(r2, r3, r4, rcx, rcy) through the assembly's implicit rule, forward and
    reverse, against central differences, away from the exact linkage."""
    target = ShapeTask(2 * _curve(np.linspace(0, 2 * np.pi, 40, endpoint=False)), 6).target()
    f = jax.jit(_shape_of(target))
    u = jnp.asarray(_EXACT)
    forward = np.asarray(jax.jit(jax.jacfwd(f))(u))
    reverse = np.asarray(jax.jit(jax.grad(f))(u))
    h = 1e-6
    fd = np.array([(f(u.at[k].add(h)) - f(u.at[k].add(-h))) / (2 * h) for k in range(5)])
    assert np.max(np.abs(fd)) > 1e-2
    assert np.max(np.abs(forward - fd)) < 1e-6 * np.max(np.abs(fd))
    assert np.max(np.abs(reverse - forward)) < 1e-12 * np.max(np.abs(fd))


def test_shape_task_refuses_bad_input():
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    with pytest.raises(ModelError, match="harmonics"):
        ShapeTask(_curve(t), harmonics=8)
    with pytest.raises(ModelError, match="coincide"):
        ShapeTask(np.zeros((20, 2)), harmonics=4)
    with pytest.raises(ModelError, match="shape error alone"):
        synthesize(
            ShapeTask(_curve(t), harmonics=4),
            Objective(masses=Masses(density=1.0), torque_weight=1.0),
        )
    task = ShapeTask(np.vstack([_curve(t), _curve(t[:1])]), harmonics=4)
    assert len(task.points) == 12  # the repeated first point dropped


@pytest.mark.slow  # long: run by CI's slow set (the search's programs compile)
def test_search_finds_and_places_a_known_shape(tmp_path):
    """40 points of a crank-rocker's coupler curve (even crank steps), scaled by 2, turned by
    0.7 rad and moved, the transmission angle at least 30 deg: the best linkage's shape error
    <= 1e-8, its placed curve within 1e-6 (relative) of every point, every kept linkage's
    crank turning fully with mu >= 30 deg (3600 crank angles); its written model, run by
    md.kinematic over the turn from the first point's nearest crank angle, passes the
    points."""
    exact = FourBar.from_vector(jnp.asarray([1.0, *_EXACT, 0.0, 0.0, 0.0]), 1.0)
    theta = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    points = 2.0 * np.asarray(coupler_curve(exact, theta)) @ _rot(0.7).T + [3.0, -1.0]
    task = ShapeTask(points, harmonics=8, min_transmission=np.deg2rad(30))  # its own: 36 deg
    out = synthesize(task, starts=64, chunk=64, seed=0)
    best = out.best
    assert best.error <= 1e-8
    assert best.distance <= 1e-6 * task.size
    grid = jnp.linspace(0.0, 2 * np.pi, 3600)
    for c in out.candidates:  # every kept linkage's crank turns fully, mu >= 30 deg
        cos_mu = np.asarray(jax.vmap(c.linkage.transmission_cosine)(grid))
        assert np.max(np.abs(cos_mu)) <= np.cos(np.deg2rad(30))
    out.write(tmp_path / "best.yaml")
    loaded = md.load(tmp_path / "best.yaml")
    turns = np.angle(np.exp(1j * (best.angles - best.angles[0]))) % (2 * np.pi)
    kin = md.kinematic(loaded.model, turns / out.objective.speed)
    p, _, _ = kin.point("coupler.P")
    assert np.max(np.linalg.norm(p - points, axis=1)) <= 1e-6 * task.size


@pytest.mark.slow  # long: run by CI's slow set (the search's programs compile)
def test_a_curve_given_against_the_cranks_sense_is_found_with_the_crank_reversed():
    """The same points in the reverse order: with either sense allowed the best linkage draws
    them exactly, its crank turning negatively (sense -1); its model, run by md.kinematic
    with the crank at the negative speed, passes the points at the reported crank angles."""
    exact = FourBar.from_vector(jnp.asarray([1.0, *_EXACT, 0.0, 0.0, 0.0]), 1.0)
    theta = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    points = np.asarray(coupler_curve(exact, theta))[::-1] * 0.5 + [1.0, 2.0]
    task = ShapeTask(points, harmonics=8)
    out = synthesize(task, starts=64, chunk=64, seed=0)
    best = out.best
    assert best.sense == -1.0 and best.error <= 1e-8
    assert best.distance <= 1e-6 * task.size
    model = out.model()
    times = ((best.angles[0] - best.angles) % (2 * np.pi)) / out.objective.speed
    p, _, _ = md.kinematic(model, times).point("coupler.P")
    assert np.all(np.diff(times[1:]) > 0)  # the points passed in their order
    assert np.max(np.linalg.norm(p - points, axis=1)) <= 1e-6 * task.size
