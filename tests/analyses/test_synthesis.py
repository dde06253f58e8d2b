"""Four-bar synthesis (mixdyn.synthesis) against independent truths.

* the coupler curve against Freudenstein's closed-form position analysis (a second method);
* the coupler curve and the motor torque against mixdyn's own kinematic and inverse analyses
  of the built model (Newton's assembly and the Lagrange multipliers, against the closed form
  and the energy balance);
* derivatives through the implicit assembly against central finite differences;
* an infeasible candidate: finite values and derivatives, its infeasibility measured;
* synthesis that recovers a known four-bar from points on its coupler curve (error ~ 0);
* the torque objective: a lower motor torque at the same path error than the
  kinematics-only optimum (slow).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import (
    FourBar,
    Masses,
    Objective,
    PathTask,
    coupler_curve,
    four_bar_model,
    motor_torque,
    synthesize,
    transmission_cosine,
)

# A Grashof crank-rocker (the crank 0.2 m shortest, 0.2 + 0.6 < 0.55 + 0.4: it turns fully),
# placed off the origin with a tilted ground link.
V = np.array([0.6, 0.2, 0.55, 0.4, 0.275, 0.55 / 3, 0.1, -0.05, 0.2])


def fourbar(branch=1.0, v=V):
    return FourBar.from_vector(jnp.asarray(v), branch)


def freudenstein(v, theta2, root):
    """The coupler point from Freudenstein's equation (crank a, coupler b, rocker c, ground
    d; angles from the ground link): ``K1 cos t4 - K2 cos t2 + K3 = cos(t2 - t4)`` solved by
    the half-angle tangent, ``root`` = +1 or -1 picking its sign."""
    d, a, b, c, rcx, rcy, x0, y0, t0 = v
    k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    ca, sa = np.cos(theta2), np.sin(theta2)
    aa = ca - k1 - k2 * ca + k3
    bb = -2 * sa
    cc = k1 - (k2 + 1) * ca + k3
    t4 = 2 * np.arctan((-bb + root * np.sqrt(bb * bb - 4 * aa * cc)) / (2 * aa))
    pa = a * np.stack([ca, sa])  # in the ground link's frame, O2 at the origin
    pb = np.stack([d + c * np.cos(t4), c * np.sin(t4)])
    t3 = np.arctan2(pb[1] - pa[1], pb[0] - pa[0])
    pc = pa + np.stack([np.cos(t3) * rcx - np.sin(t3) * rcy, np.sin(t3) * rcx + np.cos(t3) * rcy])
    rot = np.array([[np.cos(t0), -np.sin(t0)], [np.sin(t0), np.cos(t0)]])
    return (rot @ pc).T + np.array([x0, y0])


@pytest.mark.parametrize("branch", [1.0, -1.0])
def test_coupler_curve_is_freudensteins(branch):
    """Over a full crank turn the curve equals one of Freudenstein's two roots throughout
    (no branch jump), and the two branches give the two roots."""
    theta = np.linspace(0.0, 2 * np.pi, 73)
    curve = np.asarray(coupler_curve(fourbar(branch), theta))
    gaps = [np.max(np.abs(curve - freudenstein(V, theta, root))) for root in (1.0, -1.0)]
    assert min(gaps) < 1e-12 and max(gaps) > 1e-2


@pytest.mark.slow  # long: run by CI's slow set (compiles the model's analyses)
def test_coupler_curve_and_torque_are_mixdyns_analyses():
    """The built model run by md.kinematic and md.inverse: the coupler point P and the motor
    torque (Lagrange multipliers) equal the closed-form curve and the energy-balance torque."""
    masses = Masses(density=2.0, payload=0.3)
    fb = fourbar(-1.0)
    start, speed = 0.3, 2.0
    model = four_bar_model(fb, masses, start=start, speed=speed)
    t = np.linspace(0.0, np.pi / speed, 25)
    theta = start + speed * t
    inv = md.inverse(model, t)
    p, _, _ = inv.point("coupler.P")
    assert np.max(np.abs(p - np.asarray(coupler_curve(fb, theta)))) < 1e-10
    tau = np.asarray(motor_torque(fb, masses, theta, speed))
    assert np.max(np.abs(inv["motor"] - tau)) < 1e-9 * np.max(np.abs(tau))
    assert np.max(np.abs(tau)) > 1.0  # a real load (gravity and inertia), not zero


def _curve(x):
    """The coupler point at the input angles x[9:] of the four-bar x[:9] (branch +1)."""
    return coupler_curve(fourbar(1.0, x[:9]), x[9:])


_curve_jacobian = jax.jit(jax.jacfwd(_curve))
_curve_compiled = jax.jit(_curve)


def _check_against_differences(f, x, rtol, jf=None):
    """f's forward and reverse Jacobians at x against central differences."""
    jf = (jf or jax.jit(jax.jacfwd(f)))(x)
    jr = jax.jit(jax.jacrev(f))(x)
    f = jax.jit(f)
    h = 1e-6
    fd = np.stack([(f(x.at[k].add(h)) - f(x.at[k].add(-h))) / (2 * h) for k in range(len(x))], -1)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(np.asarray(jf) - fd)) < rtol * scale
    assert np.max(np.abs(np.asarray(jr) - np.asarray(jf))) < 1e-12 * scale


def test_coupler_curve_derivatives_are_finite_differences():
    """d C / d(numbers, theta2) through the implicit rule, forward and reverse."""
    x = jnp.concatenate([jnp.asarray(V), jnp.array([0.4, 2.5])])
    _check_against_differences(_curve_compiled, x, 1e-7, _curve_jacobian)


@pytest.mark.slow  # long: run by CI's slow set (third derivatives through the assembly)
def test_torque_derivatives_are_finite_differences():
    """d tau / d(numbers, theta2): the torque is itself a second derivative of the assembly."""
    masses = Masses(density=1.5, payload=0.2)
    x = jnp.concatenate([jnp.asarray(V), jnp.array([0.4, 2.5])])
    _check_against_differences(
        lambda x: motor_torque(fourbar(-1.0, x[:9]), masses, x[9:], 3.0), x, 1e-6
    )


def test_infeasible_candidate_is_finite_and_measured():
    """A rocker too short to reach: no NaN in the curve or its derivative, and the
    transmission cosine says by how much the loop fails to close (|cos mu| > 1)."""
    v = V.copy()
    v[3] = 0.05
    assert abs(float(transmission_cosine(fourbar(1.0, v), 0.5))) > 1.0
    x = jnp.concatenate([jnp.asarray(v), jnp.array([0.5, 1.0])])
    curve, grad = _curve_compiled(x), _curve_jacobian(x)
    assert np.all(np.isfinite(curve)) and np.all(np.isfinite(grad))


def test_bad_tasks_are_named_before_searching():
    with pytest.raises(ModelError, match="increase"):
        PathTask(np.zeros((3, 2)) + np.arange(3)[:, None], timing=[0.0, 0.5, 0.4])
    with pytest.raises(ModelError, match="r9"):
        PathTask(np.eye(2), bounds={"r9": (0, 1)})
    with pytest.raises(ModelError, match="masses"):
        Objective(torque_weight=1.0)


@pytest.mark.slow  # long: run by CI's slow set
def test_synthesis_recovers_a_known_four_bar(tmp_path):
    """Six points of the fixture's curve at prescribed input angles: the best linkage draws
    them exactly (error ~ 0), and its written model file, loaded and run by mixdyn's kinematic
    analysis, passes them."""
    theta = np.linspace(0.3, 4.0, 6)
    points = np.asarray(coupler_curve(fourbar(1.0), theta))
    out = synthesize(PathTask(points, timing=theta), starts=256, chunk=256, seed=1)
    best = out.best
    assert best.error < 1e-20
    assert np.allclose(np.diff(best.angles), np.diff(theta))
    out.write(tmp_path / "best.yaml")
    loaded = md.load(tmp_path / "best.yaml")
    assert {r.kind for r in loaded.runs.values()} == {"kinematic"}
    kin = md.kinematic(loaded.model, (best.angles - best.angles[0]) / out.objective.speed)
    p, _, _ = kin.point("coupler.P")
    assert np.max(np.abs(p - points)) < 1e-9


@pytest.mark.slow  # long: run by CI's slow set (two searches; benchmarks/synthesis_torque.py)
def test_torque_objective_lowers_the_torque_at_the_same_path_error():
    """Five points, timing-free (a family of exact four-bars): with the RMS motor torque in
    the objective the best linkage still passes the points (error ~ 0) and its torque, from
    md.inverse of its model (the multipliers, not the search's energy balance), is a third
    or less of the kinematics-only optimum's."""
    points = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
    masses, speed = Masses(density=2.0, payload=0.5), 2 * np.pi
    task = PathTask(points)
    kin = synthesize(task, Objective(masses=masses, speed=speed), starts=64, seed=3)
    dyn = synthesize(
        task, Objective(masses=masses, speed=speed, torque_weight=1e-4), starts=64, seed=3
    )
    rms = []
    for out in (kin, dyn):
        assert out.best.error < 1e-20
        c = out.best
        t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / speed, 129)
        tau = md.inverse(out.model(), t)["motor"]
        assert np.sqrt(np.mean(tau**2)) == pytest.approx(c.torque_rms, rel=0.02)
        rms.append(np.sqrt(np.mean(tau**2)))
    assert rms[1] < rms[0] / 3


@pytest.mark.slow  # long: run by CI's slow set (one search's programs compile)
def test_a_second_search_of_the_same_form_runs_the_compiled_programs(monkeypatch):
    """Two tasks of one form (four points, timing given) with other targets and timing: the
    second search traces nothing (the residuals built by the first search's programs only),
    and each search's best passes its own points exactly."""
    from mixdyn.synthesis import _search

    built, counts = [], []
    residuals = _search._residuals
    monkeypatch.setattr(_search, "_residuals", lambda *a: built.append(1) or residuals(*a))
    for theta in (np.linspace(0.3, 3.0, 4), np.linspace(1.0, 4.5, 4)):
        points = np.asarray(coupler_curve(fourbar(1.0), theta))
        out = synthesize(PathTask(points, timing=theta), starts=32, chunk=32, seed=2)
        assert out.best.error < 1e-20
        counts.append(len(built))
    assert 1 <= counts[0] <= 2 and counts[1] == counts[0]  # the solve's, the scores' program


def test_a_timing_from_the_ground_link_is_the_crank_angle_as_given():
    """``timing_from="ground"``: the input angles are the timing itself (the first point's
    angle not a variable), whatever the search's ``theta_1``; without a timing it is refused."""
    from mixdyn.synthesis import _search

    theta = np.linspace(0.3, 4.0, 6)
    points = np.asarray(coupler_curve(fourbar(1.0), theta))
    task = PathTask(points, timing=theta, timing_from="ground")
    layout = _search._Layout(6, task.size, points.mean(axis=0), task.timing, task.linkage, True)
    u = np.zeros(layout.size)
    for first in (0.0, 1.7):
        u[layout.m] = first
        assert np.array_equal(np.asarray(layout.angles(u)), theta)
    with pytest.raises(ModelError, match="needs a timing"):
        PathTask(points, timing_from="ground")
    with pytest.raises(ModelError, match="timing_from"):
        PathTask(points, timing=theta, timing_from="start")


@pytest.mark.slow  # long: run by CI's slow set (a search compiles)
def test_a_search_from_the_ground_link_recovers_the_linkage_at_the_given_angles():
    """Six points of a known four-bar at crank angles from its ground link: the search with
    ``timing_from="ground"`` passes them exactly, at exactly those angles."""
    theta = np.linspace(0.3, 4.0, 6)
    points = np.asarray(coupler_curve(fourbar(1.0), theta))
    out = synthesize(
        PathTask(points, timing=theta, timing_from="ground"), starts=128, chunk=128, seed=1
    )
    assert out.best.error < 1e-20
    assert np.array_equal(out.best.angles, theta)
    again = np.asarray(coupler_curve(out.best.fourbar, theta))
    assert np.max(np.abs(again - points)) < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_numbers_fixed_by_equal_bounds_keep_their_values():
    """The crank's pivot and the ground link's angle fixed (``low == high``, as a literature
    case fixes them), the timing from the ground link: every kept linkage has those values,
    and the best passes the targets of the known four-bar it came from (Freudenstein's closed
    form, the better of its two roots)."""
    v = V.copy()
    v[6:] = 0.0  # x0 = y0 = theta0 = 0
    theta = np.linspace(0.5, 2.0, 5)
    points = np.asarray(coupler_curve(fourbar(1.0, v), theta))
    bounds = {name: (0.0, 0.0) for name in ("x0", "y0", "theta0")}
    bounds.update({name: (0.05, 2.0) for name in ("r1", "r2", "r3", "r4")})  # the arc is short
    task = PathTask(points, timing=theta, timing_from="ground", bounds=bounds, grashof="grashof")
    out = synthesize(task, starts=64, chunk=64, seed=0)
    assert out.feasible >= 1
    box = task.box()
    for c in out.candidates:
        u = np.array([float(getattr(c.fourbar, n)) for n in FourBar.NAMES])
        assert np.all(u[6:] == 0.0) and np.all(box[6:] == 0.0)
    best = np.array([float(getattr(out.best.fourbar, n)) for n in FourBar.NAMES])
    error = min(float(np.sum((freudenstein(best, theta, r) - points) ** 2)) for r in (1, -1))
    assert error < 1e-16 and out.best.error == pytest.approx(error, abs=1e-16)
