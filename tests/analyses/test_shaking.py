"""The shaking force and moment and the joint reactions of synthesized linkages
(:func:`mixdyn.synthesis.shaking`, :func:`mixdyn.synthesis.reactions`) against independent
truths:

* the rates of the links' momentum by central finite differences of the assembled positions
  (force ``-Omega^2 d2/dtheta2 sum m G``; moment about the crank's pivot ``-Omega^2 d/dtheta
  sum (J phi' + m (G - O2) x G')``), for a four-bar and a slider-crank;
* the reactions of mixdyn's inverse dynamics of the built model, gravity off: the ground
  joints' forces and the motor's torque passed to the frame (slow);
* the joint reactions (each link's Newton-Euler equations, one linear solve) against the
  energy balance's motor torque and the momentum balance (the ground's forces on the links
  are ``sum m (a - g)``: minus the shaking force minus the weight), and against md.inverse's
  reactions joint by joint (slow);
* the objective: refused without masses; with the shaking force weighed, a search finds a
  linkage through the same points that shakes less than the kinematics-only optimum, by
  md.inverse's reactions (slow); with a reaction weight the search's last residual is the
  joints' forces' measure recomputed here (slow), and the search finds a linkage through the
  same points whose largest pin force, by md.inverse, is under half the kinematics-only
  optimum's (slow).
"""

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
    SliderCrank,
    four_bar_model,
    link_angles,
    link_inertia,
    motor_torque,
    reactions,
    rod_and_slider,
    shaking,
    slider_crank_model,
    synthesize,
)

FOUR_BAR = FourBar.from_vector(
    jnp.asarray([0.6, 0.2, 0.55, 0.4, 0.275, 0.55 / 3, 0.1, -0.05, 0.2]), 1.0
)
SLIDER_CRANK = SliderCrank.from_vector(
    jnp.asarray([0.1, 0.35, 0.04, 0.15, 0.08, 0.02, -0.01, 0.25]), 1.0
)
MASSES = Masses(density=2.0, payload=0.3, gravity=(0.0, 0.0), slider=0.4)
SPEED = 3.0


def _rot(phi, v):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _state(lk, theta, inertia):
    """The links' centres from the crank's pivot (3, 2) and angles (3,), by the assembly of
    positions alone; ``inertia``: the links' centres in their frames."""
    phi2 = float(lk.theta0) + theta
    e2 = np.array([np.cos(phi2), np.sin(phi2)])
    if isinstance(lk, SliderCrank):
        phi3, _ = (float(x) for x in rod_and_slider(lk, theta))
        third = lk.r2 * e2 + lk.r3 * np.array([np.cos(phi3), np.sin(phi3)])  # the slider's pin
        phi_last = float(lk.theta0)  # the slider turns not
    else:
        phi3, phi_last = (float(x) for x in link_angles(lk, theta))
        ground = lk.r1 * np.array([np.cos(float(lk.theta0)), np.sin(float(lk.theta0))])
        third = ground + _rot(phi_last, inertia[2])
    g = np.stack([_rot(phi2, inertia[0]), lk.r2 * e2 + _rot(phi3, inertia[1]), third])
    return g, np.array([phi2, phi3, phi_last])


@pytest.mark.parametrize(
    "lk",
    [
        FOUR_BAR,
        pytest.param(SLIDER_CRANK, marks=pytest.mark.slow),  # long: run by CI's slow set
    ],
    ids=["four-bar", "slider-crank"],
)
def test_shaking_is_the_rate_of_the_links_momentum(lk):
    """The force and moment against central differences of the assembled positions."""
    links = link_inertia(lk, MASSES).values()
    m, j = (np.array([float(v[k]) for v in links]) for k in (0, 2))
    centres = [np.asarray(v[1], dtype=float) for v in links]
    h = 1e-4
    theta = np.linspace(0.2, 5.5, 4)
    force, moment = (np.asarray(a) for a in shaking(lk, MASSES, theta, SPEED))

    def momentum_rate(t):  # d/dtheta of sum (J phi' + m g x g')
        def h_of(u):
            (g0, p0), (g1, p1) = _state(lk, u - h, centres), _state(lk, u + h, centres)
            g, dg, dp = _state(lk, u, centres)[0], (g1 - g0) / (2 * h), (p1 - p0) / (2 * h)
            return np.sum(j * dp + m * (g[:, 0] * dg[:, 1] - g[:, 1] * dg[:, 0]))

        return (h_of(t + h) - h_of(t - h)) / (2 * h)

    for k, t in enumerate(theta):
        gm, g0, gp = (_state(lk, t + d, centres)[0] for d in (-h, 0.0, h))
        want = -(SPEED**2) * np.sum(m[:, None] * (gp - 2 * g0 + gm), axis=0) / h**2
        assert np.max(np.abs(force[k] - want)) < 1e-6 * np.max(np.abs(force))
        want_m = -(SPEED**2) * momentum_rate(t)
        assert abs(moment[k] - want_m) < 1e-6 * np.max(np.abs(moment))
    assert np.max(np.abs(force)) > 0.1 and np.max(np.abs(moment)) > 0.01  # real loads


WEIGHING = Masses(density=2.0, payload=0.3, slider=0.4)  # gravity on: -9.81 m/s^2 along y


@pytest.mark.parametrize(
    "lk, ground",
    [
        (FOUR_BAR, (0, 3)),
        pytest.param(SLIDER_CRANK, (0, 3), marks=pytest.mark.slow),  # long: CI's slow set
    ],
    ids=["four-bar", "slider-crank"],
)
def test_joint_reactions_balance_the_links_momentum_and_energy(lk, ground):
    """Newton-Euler's reactions, gravity on: the motor's torque is the energy balance's
    (:func:`motor_torque`), and the ground's forces on the links sum to ``sum m (a - g)``,
    i.e. minus the shaking force (a third way: momentum) minus the links' weight."""
    theta = np.linspace(0.2, 5.5, 4)
    forces, torque = (np.asarray(a) for a in reactions(lk, WEIGHING, theta, SPEED))
    tau = np.asarray(motor_torque(lk, WEIGHING, theta, SPEED))
    force, _ = (np.asarray(a) for a in shaking(lk, WEIGHING, theta, SPEED))
    assert np.max(np.abs(torque - tau)) < 1e-10 * np.max(np.abs(tau))
    mass = sum(float(v[0]) for v in link_inertia(lk, WEIGHING).values())
    want = -force - mass * np.array(WEIGHING.gravity)
    got = forces[:, ground[0]] + forces[:, ground[1]]
    assert np.max(np.abs(got - want)) < 1e-10 * np.max(np.abs(want))


def test_a_shaking_objective_needs_masses_and_a_measure():
    with pytest.raises(ModelError, match="masses"):
        Objective(shaking_force_weight=1.0)
    with pytest.raises(ModelError, match="shaking_moment_weight"):
        Objective(masses=MASSES, shaking_moment_weight=-1.0)
    with pytest.raises(ModelError, match="shaking"):
        Objective(masses=MASSES, shaking="max")
    assert Objective(masses=MASSES, shaking_moment_weight=1.0).dynamic


@pytest.mark.slow  # long: run by CI's slow set (compiles the models' inverse analyses)
def test_shaking_is_what_mixdyns_inverse_dynamics_passes_to_the_frame():
    """md.inverse of the built models, gravity off: the shaking force is minus the sum of the
    ground joints' reactions on the links (four-bar: O2 and O4; slider-crank: O2 and the
    slide), the four-bar's shaking moment about O2 minus the moment of O4's reaction and the
    motor's torque."""
    start = 0.3
    t = np.linspace(0.0, 2.0, 9)
    theta = start + SPEED * t
    for lk, build, ground in (
        (FOUR_BAR, four_bar_model, ("O2", "O4")),
        (SLIDER_CRANK, slider_crank_model, ("O2", "slide")),
    ):
        inv = md.inverse(build(lk, MASSES, start=start, speed=SPEED), t)
        force, moment = (np.asarray(a) for a in shaking(lk, MASSES, theta, SPEED))
        on_links = np.stack([sum(inv[f"{g}.Fx"] for g in ground),
                             sum(inv[f"{g}.Fy"] for g in ground)], axis=1)  # fmt: skip
        assert np.max(np.abs(force + on_links)) < 1e-9 * np.max(np.abs(force))
        joints = ("O2", "A", "B", ground[1])
        weighed = build(lk, WEIGHING, start=start, speed=SPEED)
        loads = md.inverse(weighed, t)
        pins, _ = (np.asarray(a) for a in reactions(lk, WEIGHING, theta, SPEED))
        for k, name in enumerate(joints):
            want = np.stack([loads[f"{name}.Fx"], loads[f"{name}.Fy"]], axis=1)
            assert np.max(np.abs(pins[:, k] - want)) < 1e-9 * np.max(np.abs(pins))
        if lk is FOUR_BAR:
            o4 = float(lk.r1) * np.array([np.cos(float(lk.theta0)), np.sin(float(lk.theta0))])
            lever = o4[0] * inv["O4.Fy"] - o4[1] * inv["O4.Fx"]
            assert np.max(np.abs(moment + lever + inv["motor"])) < 1e-9 * np.max(np.abs(moment))


def _ground_force(inv):
    """The RMS over time of the ground joints' forces' resultant's magnitude [N]."""
    f = np.hypot(inv["O2.Fx"] + inv["O4.Fx"], inv["O2.Fy"] + inv["O4.Fy"])
    return np.sqrt(np.mean(f**2))


@pytest.mark.slow  # long: run by CI's slow set (two searches)
def test_the_shaking_objective_lowers_the_shaking_force_at_the_same_path_error():
    """Five points, timing-free (a family of exact four-bars): with the shaking force in the
    objective the best linkage still passes the points (error ~ 0) and its RMS ground force
    (gravity off), from md.inverse's reactions of its model, is under half the
    kinematics-only optimum's."""
    points = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
    masses, speed = Masses(density=2.0, payload=0.5, gravity=(0.0, 0.0)), 2 * np.pi
    task = PathTask(points)
    kin = synthesize(task, Objective(masses=masses, speed=speed), starts=64, seed=3)
    dyn = synthesize(
        task, Objective(masses=masses, speed=speed, shaking_force_weight=1e-3), starts=64, seed=3
    )
    figures = []
    for out in (kin, dyn):
        c = out.best
        assert c.error < 1e-16
        t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / speed, 257)
        figure = _ground_force(md.inverse(out.model(), t))
        assert figure == pytest.approx(c.shaking_force_rms, rel=0.02)
        figures.append(figure)
    assert figures[1] < figures[0] / 2


@pytest.mark.slow  # long: run by CI's slow set (the residuals run op by op)
def test_a_reaction_weight_scores_the_joint_forces_measure():
    """The search's residuals with a reaction weight end in ``sqrt(w) R / s``: ``R`` the
    mean 8-norm of the joints' forces' magnitudes over the sampled motion (the module's
    measure, recomputed here from :func:`reactions`), ``s`` the targets' size."""
    from mixdyn.synthesis import _search

    points = np.asarray([[0.5, 0.3], [0.58, 0.42], [0.48, 0.55], [0.32, 0.5]])
    task = PathTask(points, timing=np.linspace(0.3, 1.5, 4))
    objective = Objective(masses=WEIGHING, speed=SPEED, reaction_weight=0.04, samples=8)
    layout = _search._Layout(4, task.size, points.mean(axis=0), task.timing, task.linkage)
    data = _search._data(layout, task, objective, task.box())
    program = _search._program(task, objective, 50, torque=True)
    u = np.asarray(_search._starts(layout, task, task.box(), 1, np.random.default_rng(0))[0])
    last = float(_search._residuals(program, data)(u, 1.0)[-1])
    fb, theta = layout.make(u, 1.0), np.asarray(layout.angles(u))
    grid = theta[0] + (theta[-1] - theta[0]) * np.linspace(0.0, 1.0, 8)
    loads = np.linalg.norm(np.asarray(reactions(fb, WEIGHING, grid, SPEED)[0]), axis=2)
    want = 0.2 * np.mean(loads**8) ** (1 / 8) / layout.scale
    assert last == pytest.approx(want, rel=1e-12)


@pytest.mark.slow  # long: run by CI's slow set (two searches, ~30 s)
def test_the_reaction_objective_lowers_the_largest_pin_force_at_the_same_path_error():
    """Five points, timing-free, gravity on: with the peak joint reaction in the objective
    the best linkage still passes the points (error ~ 0) and its largest pin force over the
    motion, from md.inverse's ``{joint}.Fx``, ``.Fy`` of its model, is under half the
    kinematics-only optimum's (benchmarks/synthesis_reactions.py: 121.6 -> 17.5 N)."""
    points = np.array([[0.50, 0.30], [0.58, 0.42], [0.48, 0.55], [0.32, 0.50], [0.30, 0.36]])
    masses, speed = Masses(density=2.0, payload=0.5), 2 * np.pi
    task = PathTask(points)
    plain = Objective(masses=masses, speed=speed)
    weighed = Objective(masses=masses, speed=speed, reaction_weight=1e-6, reaction="peak")
    largest = []
    for objective in (plain, weighed):
        out = synthesize(task, objective, starts=16, seed=3)
        c = out.best
        assert c.error < 1e-16
        t = np.linspace(0.0, (c.angles[-1] - c.angles[0]) / speed, 257)
        r = md.inverse(out.model(), t)
        forces = [np.hypot(r[f"{j}.Fx"], r[f"{j}.Fy"]) for j in ("O2", "A", "B", "O4")]
        largest.append(max(float(np.max(f)) for f in forces))
    assert largest[1] < largest[0] / 2
