"""Six-bar path generation (mixdyn.synthesis, ``linkage="stephenson1"``, ``"stephenson3"``,
``"watt1"`` and ``"watt2"``) against independent truths.

* the closed-form assembly against its loop-closure equations on every branch (the links'
  lengths, the pins where the angles put them, the sides the branches name, the transmission
  angles as the angles between the links), in NumPy from the returned angles;
* derivatives through the two implicit circle intersections against central finite
  differences, forward and reverse; an open second loop finite and measured;
* a six-bar's task checked by its numbers;
* (slow) the motor torque, the joint reactions and the shaking force and moment against
  md.inverse of the written model (its Lagrange multipliers, a second method);
* (slow) the written model's kinematic analysis (Newton's assembly of seven revolute joints,
  a second method) puts the coupler point where the closed form does;
* (slow) a search recovers a known six-bar's coupler curve from eight of its points, and its
  written model file, run by md.kinematic, passes them;
* (slow) motion generation carries a six-bar's tracer through six poses of a known one, its
  written model run by md.kinematic.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import (
    Masses,
    PathTask,
    StephensonI,
    StephensonIII,
    WattI,
    WattII,
    coupler_curve,
    motor_torque,
    reactions,
    shaking,
    six_bar_model,
    synthesize,
)

# A Grashof crank-rocker (ground 1, crank 0.3, coupler 1.1, rocker 0.9) with a dyad that
# closes over the whole turn on every branch [m, rad]: r5, r6, D in the coupler (in the
# rocker: Watt II), then O6 in the ground link's frame (Stephenson III, Watt II) or F in the
# rocker's (Watt I), the coupler point on the tracer, the crank's pivot and the ground link's
# angle.
HEAD = [1.0, 0.3, 1.1, 0.9, 1.2, 1.0, 0.6, 0.4]
TAIL = [0.5, 0.2, 0.1, -0.2, 0.3]
CASES = {
    StephensonIII: np.array([*HEAD, 1.5, 1.2, *TAIL]),
    WattI: np.array([*HEAD, 0.5, 0.3, *TAIL]),
    WattII: np.array([*HEAD, 1.0, 1.3, *TAIL]),
    # D in the crank's frame, F in the rocker's
    StephensonI: np.array([*HEAD[:6], 0.2, 0.25, 0.9, 0.6, *TAIL]),
}


def _rot(phi, p):
    """``R(phi) p`` for angles (K,) and a point (2,): (K, 2)."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * p[0] - s * p[1], s * p[0] + c * p[1]], -1)


def _unit(phi):
    return np.stack([np.cos(phi), np.sin(phi)], -1)


def _cross(u, w):
    return u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]


@jax.jit
def _assembly(lk, theta):
    """The closed form at ``theta`` (K,): its joints, angles and transmission cosines."""
    joints = jax.vmap(lk.joints)(theta)
    return joints, jax.vmap(lk.transmission_cosines)(theta), coupler_curve(lk, theta)


@pytest.mark.parametrize("cls", [StephensonIII, WattI, WattII, StephensonI])
def test_closed_form_closes_both_loops_on_every_branch(cls):
    """Over a crank turn, on each of the four branch codes: |AB| = r3, |O4 B| = r4,
    |DE| = r5, |XE| = r6, each pin where its link's angle puts it (1e-12); D, the
    follower's pivot X and the coupler point from the numbers by hand; B on the side b4 of
    A -> O4, E on the side b6 of D -> X; cos mu1 = cos(phi3 - phi4), cos mu2 = cos(phi5 -
    phi6); the four branches draw four different curves."""
    v = CASES[cls]
    n = dict(zip(cls.NAMES, v, strict=True))
    theta = jnp.linspace(0.0, 2 * np.pi, 61)
    phi2 = n["theta0"] + np.asarray(theta)
    o2 = np.array([n["x0"], n["y0"]])
    curves = []
    for code in cls.BRANCHES:
        b6 = 1.0 if code > 0 else -1.0
        b4 = code - 2 * b6
        j, cos_mu, curve = _assembly(cls.from_vector(jnp.asarray(v), code), theta)
        j = {k: np.asarray(x) for k, x in j.items()}
        a = o2 + n["r2"] * _unit(phi2)
        o4 = o2 + n["r1"] * _unit(np.array([n["theta0"]]))[0]
        np.testing.assert_allclose(j["A"], a, atol=1e-12)
        np.testing.assert_allclose(j["B"], a + n["r3"] * _unit(j["phi3"]), atol=1e-12)
        np.testing.assert_allclose(j["B"], o4 + n["r4"] * _unit(j["phi4"]), atol=1e-12)
        if cls is WattII:  # D on the rocker
            d = o4 + _rot(j["phi4"], (n["dx"], n["dy"]))
        elif cls is StephensonI:  # D on the crank
            d = o2 + _rot(phi2, (n["dx"], n["dy"]))
        else:
            d = a + _rot(j["phi3"], (n["dx"], n["dy"]))
        if cls in (StephensonIII, WattII):
            x = np.broadcast_to(o2 + _rot(np.array([n["theta0"]]), (n["gx"], n["gy"]))[0], d.shape)
        else:
            x = o4 + _rot(j["phi4"], (n["fx"], n["fy"]))
        np.testing.assert_allclose(j["D"], d, atol=1e-12)
        np.testing.assert_allclose(j["X"], x, atol=1e-12)
        np.testing.assert_allclose(j["E"], d + n["r5"] * _unit(j["phi5"]), atol=1e-12)
        np.testing.assert_allclose(j["E"], x + n["r6"] * _unit(j["phi6"]), atol=1e-12)
        np.testing.assert_allclose(np.asarray(curve), d + _rot(j["phi5"], (n["rcx"], n["rcy"])),
                                   atol=1e-12)  # fmt: skip
        assert np.all(b4 * _cross(o4 - a, j["B"] - a) > 0)
        assert np.all(b6 * _cross(x - d, j["E"] - d) > 0)
        cos_mu = np.asarray(cos_mu)
        np.testing.assert_allclose(cos_mu[:, 0], np.cos(j["phi3"] - j["phi4"]), atol=1e-12)
        np.testing.assert_allclose(cos_mu[:, 1], np.cos(j["phi5"] - j["phi6"]), atol=1e-12)
        assert np.max(np.abs(cos_mu)) < 0.96  # both loops close along the whole turn
        curves.append(np.asarray(curve))
    for k in range(4):
        for m in range(k):
            assert np.max(np.abs(curves[k] - curves[m])) > 0.05


def _curve(cls):
    def f(x):
        lk = cls.from_vector(x[:15], -1.0)  # b4 = +1, b6 = -1
        return coupler_curve(lk, x[15:]).ravel()

    return f


@pytest.mark.parametrize(
    "cls, reverse",
    [
        (WattI, False),  # the follower's pivot on the rocker: both loops' rules chained
        pytest.param(WattI, True, marks=pytest.mark.slow),  # long: run by CI's slow set
        pytest.param(StephensonIII, True, marks=pytest.mark.slow),  # long: CI's slow set
        pytest.param(WattII, False, marks=pytest.mark.slow),  # long: CI's slow set
        pytest.param(StephensonI, False, marks=pytest.mark.slow),  # long: CI's slow set
    ],
)
def test_derivatives_are_finite_differences_and_an_open_dyad_is_finite(cls, reverse):
    """dC/d(numbers, theta2) through both implicit rules, forward (and, slow, reverse)
    against central differences; a follower too short to reach: finite values and
    derivatives, the worse transmission cosine beyond 1."""
    x = jnp.concatenate([jnp.asarray(CASES[cls]), jnp.array([0.4, 2.5, -1.0])])
    f = _curve(cls)
    forward = jax.jit(jax.jacfwd(f))
    jf = np.asarray(forward(x))
    g = jax.jit(f)
    h = 1e-6
    fd = np.stack([(g(x.at[k].add(h)) - g(x.at[k].add(-h))) / (2 * h) for k in range(len(x))], -1)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(jf - fd)) < 1e-7 * scale
    if reverse:
        assert np.max(np.abs(np.asarray(jax.jit(jax.jacrev(f))(x)) - jf)) < 1e-12 * scale
    short = x.at[4].set(0.05).at[5].set(0.05)  # r5 + r6 = 0.1 < |D X|
    lk = cls.from_vector(short[:15], -1.0)
    assert abs(float(lk.transmission_cosine(0.4))) > 1.0
    assert np.all(np.isfinite(np.asarray(g(short))))
    assert np.all(np.isfinite(np.asarray(forward(short))))


def test_a_six_bars_task_is_checked_by_its_numbers():
    """The task checks a six-bar's numbers and bounds them all."""
    points = np.array([[0.0, 0.0], [0.1, 0.05], [0.15, 0.12]])
    box = PathTask(points, linkage="watt1", bounds={"fx": (-0.1, 0.2)}).box()
    assert box.shape == (15, 2) and tuple(box[8]) == (-0.1, 0.2)
    assert np.all(np.isfinite(box[:-1]))  # every number but theta0 bounded by default
    with pytest.raises(ModelError, match="no number 'gx' of a Watt I six-bar"):
        PathTask(points, linkage="watt1", bounds={"gx": (0.1, 0.2)})
    with pytest.raises(ModelError, match="no linkage 'stephenson'"):
        PathTask(points, linkage="stephenson")
    assert PathTask(points, linkage="stephenson3").linkage is StephensonIII


@pytest.mark.slow  # long: run by CI's slow set (compiles the model's kinematic analysis)
@pytest.mark.parametrize(
    "cls, code", [(StephensonIII, 3.0), (WattI, -1.0), (WattII, 1.0), (StephensonI, -3.0)]
)
def test_closed_form_is_mixdyns_kinematic_analysis(cls, code):
    """Over a crank turn the built model's kinematic analysis (Newton's assembly of the five
    links and seven revolute joints) puts tracer.P where the closed form puts the coupler
    point, and the tracer at the closed form's angle, to 1e-9."""
    lk = cls.from_vector(jnp.asarray(CASES[cls]), code)
    start, speed = 0.4, 2.0
    t = np.linspace(0.0, 2 * np.pi / speed, 37)
    kin = md.kinematic(six_bar_model(lk, start=start, speed=speed), t)
    p, _, _ = kin.point("tracer.P")
    theta = jnp.asarray(start + speed * t)
    assert np.max(np.abs(p - np.asarray(coupler_curve(lk, theta)))) < 1e-9
    phi5 = np.asarray(jax.vmap(lk.coupler_angle)(theta))
    assert np.max(np.abs(np.angle(np.exp(1j * (kin["tracer.phi"] - phi5))))) < 1e-9


#: The links' masses of the dynamics tests: bars of 2 kg/m, 0.3 kg at the coupler point, gravity
#: on (the torque and reactions) and off (the shaking).
MASSES = Masses(density=2.0, payload=0.3)
FLOATING = Masses(density=2.0, payload=0.3, gravity=(0.0, 0.0))


@pytest.mark.slow  # long: run by CI's slow set (compiles the models' inverse analyses)
@pytest.mark.parametrize(
    "cls, code", [(StephensonIII, 3.0), (WattI, -1.0), (WattII, -3.0), (StephensonI, 1.0)]
)
def test_dynamics_are_mixdyns_inverse_dynamics(cls, code):
    """The built model with masses run by md.inverse over a crank turn: the motor torque of
    the energy balance and the reactions' torque equal its driver effort, each joint's
    reaction its {joint}.Fx/.Fy (1e-9 relative); gravity off, the shaking force is minus the
    sum of the ground joints' reactions on the links, and the shaking moment about O2 minus
    their moments and the motor's torque."""
    lk = cls.from_vector(jnp.asarray(CASES[cls]), code)
    start, speed = 0.4, 3.0
    t = np.linspace(0.0, 2 * np.pi / speed, 25)
    theta = start + speed * t
    inv = md.inverse(six_bar_model(lk, MASSES, start=start, speed=speed), t)
    tau = np.asarray(motor_torque(lk, MASSES, theta, speed))
    forces, torque = (np.asarray(a) for a in reactions(lk, MASSES, theta, speed))
    assert np.max(np.abs(tau)) > 10.0  # a real load
    assert np.max(np.abs(inv["motor"] - tau)) < 1e-9 * np.max(np.abs(tau))
    assert np.max(np.abs(torque - tau)) < 1e-9 * np.max(np.abs(tau))
    names = ("O2", "A", "B", "O4", "D", "E", "F" if cls.PIVOT_BODY == "rocker" else "O6")
    for k, name in enumerate(names):
        want = np.stack([inv[f"{name}.Fx"], inv[f"{name}.Fy"]], axis=1)
        assert np.max(np.abs(forces[:, k] - want)) < 1e-9 * np.max(np.abs(forces))
    free = md.inverse(six_bar_model(lk, FLOATING, start=start, speed=speed), t)
    force, moment = (np.asarray(a) for a in shaking(lk, FLOATING, theta, speed))
    ground = [n for n in names if n in ("O2", "O4", "O6")]
    on_links = np.stack([sum(free[f"{g}.Fx"] for g in ground),
                         sum(free[f"{g}.Fy"] for g in ground)], axis=1)  # fmt: skip
    assert np.max(np.abs(force + on_links)) < 1e-9 * np.max(np.abs(force))
    o2 = np.array([lk.x0, lk.y0], dtype=float)
    points = {"O4": np.asarray(lk.pivots()[1]), "O6": np.asarray(lk.dyad_pivot(0.0))}
    lever = sum((points[g] - o2)[0] * free[f"{g}.Fy"] - (points[g] - o2)[1] * free[f"{g}.Fx"]
                for g in ground if g != "O2")  # fmt: skip
    assert np.max(np.abs(moment + lever + free["motor"])) < 1e-9 * np.max(np.abs(moment))


@pytest.mark.slow  # long: run by CI's slow set (each search compiles its programs, ~10 s)
@pytest.mark.parametrize("cls", [StephensonIII, WattI, WattII, StephensonI])
def test_search_recovers_a_known_six_bars_curve(cls, tmp_path):
    """Eight points of the fixture's coupler curve with their input angles (a Stephenson
    I's: twelve), every number bounded within 20 % of the fixture's (a designer's box): the
    best six-bar passes the points (error <= 1e-8) and draws the fixture's curve between
    them (1e-5); its model file, loaded and run by md.kinematic, passes the points."""
    v = CASES[cls]
    truth = cls.from_vector(jnp.asarray(v), 3.0)
    # a Stephenson I's curve through eight timed points is not unique (another of its
    # numbers draws another curve through them, 4e-4 apart): twelve fix it
    theta = np.linspace(0.3, 4.5, 12 if cls is StephensonI else 8)
    points = np.asarray(coupler_curve(truth, theta))
    bounds = {
        name: (x - 0.2 * max(abs(x), 0.3), x + 0.2 * max(abs(x), 0.3))
        for name, x in zip(cls.NAMES[:-1], v[:-1], strict=True)
    }
    out = synthesize(PathTask(points, timing=theta, linkage=cls, bounds=bounds), starts=64,
                     chunk=64, seed=1)  # fmt: skip
    best = out.best
    assert isinstance(best.linkage, cls) and best.error <= 1e-8
    fine = np.linspace(theta[0], theta[-1], 200)
    drawn = coupler_curve(best.linkage, fine - theta[0] + best.angles[0])
    assert np.max(np.abs(np.asarray(drawn) - np.asarray(coupler_curve(truth, fine)))) < 1e-5
    out.write(tmp_path / "best.yaml")
    loaded = md.load(tmp_path / "best.yaml")
    kin = md.kinematic(loaded.model, (best.angles - best.angles[0]) / out.objective.speed)
    p, _, _ = kin.point("tracer.P")
    assert np.max(np.abs(p - np.asarray(coupler_curve(best.linkage, best.angles)))) < 1e-9
    assert np.sum((p - points) ** 2) <= 1e-8


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its programs, ~35 s)
def test_motion_generation_carries_a_six_bars_tracer_through_poses(tmp_path):
    """Six poses of the Stephenson III fixture's tracer (its coupler point, and its angle
    plus 0.4 rad), every number within 20 % of the fixture's: the best six-bar's pose error
    <= 1e-8, and its written model file, run by md.kinematic, puts tracer.P and tracer.phi
    on the poses (1e-8)."""
    from mixdyn.synthesis import MotionTask

    v = CASES[StephensonIII]
    truth = StephensonIII.from_vector(jnp.asarray(v), 3.0)
    theta = np.linspace(0.3, 4.5, 6)
    points = np.asarray(coupler_curve(truth, theta))
    angles = np.asarray(jax.vmap(truth.coupler_angle)(jnp.asarray(theta))) + 0.4
    bounds = {
        name: (x - 0.2 * max(abs(x), 0.3), x + 0.2 * max(abs(x), 0.3))
        for name, x in zip(StephensonIII.NAMES[:-1], v[:-1], strict=True)
    }
    task = MotionTask(np.column_stack([points, angles]), linkage="stephenson3", bounds=bounds)
    out = synthesize(task, starts=64, chunk=64, seed=1)
    best = out.best
    assert isinstance(best.linkage, StephensonIII) and best.error <= 1e-8
    out.write(tmp_path / "best.yaml")
    loaded = md.load(tmp_path / "best.yaml")
    kin = md.kinematic(loaded.model, (best.angles - best.angles[0]) / out.objective.speed)
    p, _, _ = kin.point("tracer.P")
    assert np.max(np.abs(p - points)) < 1e-8
    assert np.max(np.abs(np.angle(np.exp(1j * (kin["tracer.phi"] - angles))))) < 1e-8
