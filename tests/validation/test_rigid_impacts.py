"""Rigid impacts (``contact_model: rigid``) against closed forms and conservation laws.

- The impulse over a constrained system (a four-bar whose rocker hits a stop), against a
  hand derivation: a one-degree-of-freedom mechanism at rest but for its motion along the
  velocity-ratio vector ``v`` (the null space of its hand-written constraint Jacobian) has
  the effective inertia ``I = v^T M v``; Newton's law on the contact's normal velocity
  ``G v w`` reverses the crank's speed, ``w+ = -e w-``, and the normal impulse is
  ``P = -(1 + e) I w- / (G v)`` (the one-coordinate momentum balance). The velocities after
  keep the joints (1e-12) and ``M (qd+ - qd-) = Phi_q^T Lambda + G^T P``.
- A ball dropped on the ground: impact times ``t_1 = sqrt(2 h0 / g)``,
  ``t_{n+1} = t_n + 2 e^n sqrt(2 g h0) / g`` and apex heights ``h_n = e^(2n) h0`` (1e-9).
- A pendulum striking a wall at the bottom of its swing: the impact at a quarter of the
  large-amplitude period (``K(sin(theta0 / 2)) / sqrt(m g l / J_O)``, SciPy's elliptic
  integral) and the rebound ``-e omega`` (exact for a rigid impact).
- The four-bar's rocker striking a stop in a run: the instant found at the hand pose, the
  joints' velocity constraints kept after it, the rebound and the impulse as above.
- The same four-bar with its crank driven: a named failure at the impact (the drivers fix
  the stop's normal velocity).
- Newton's cradle (three balls, ``e = 1``, the last two touching): sequential impacts pass
  the first ball's velocity to the last; momentum and energy kept.
- A sweep over the restitution: each member's first impulse is ``(1 + e) m v0``.
- Impacts past the most a run takes: a named failure at the closed-form time of the next
  impact, never a hang (a ball coming to rest: ``test_resting_contact.py``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import four_bar_pose
from mixdyn.analysis._impacts import HORIZON, PASS_FRACTION, _longest_step
from mixdyn.analysis._impulses import impulse

A_, B_, C_, D_ = 0.2, 0.55, 0.4, 0.6  # crank, coupler, rocker, ground [m]
MASS = np.array([1.0, 2.0, 1.5])  # crank, coupler, rocker [kg]
INERTIA = np.array([0.004, 0.05, 0.02])  # [kg m^2]
TIP_R = 0.01  # the rocker tip's radius [m]


def _B(phi, s):
    """d(A(phi) s)/dphi."""
    return np.array([-math.sin(phi) * s[0] - math.cos(phi) * s[1],
                     math.cos(phi) * s[0] - math.sin(phi) * s[1]])  # fmt: skip


def _pose(theta2):
    """The four-bar's coordinates (9,) at crank angle ``theta2`` (by hand)."""
    (ax, ay), (bx, by) = four_bar_pose(A_, B_, C_, D_, theta2)
    th3, th4 = math.atan2(by - ay, bx - ax), math.atan2(by, bx - D_)
    return np.array([ax / 2, ay / 2, theta2, (ax + bx) / 2, (ay + by) / 2, th3,
                     (D_ + bx) / 2, by / 2, th4])  # fmt: skip


#: The revolute joints: (body i or -1 for the ground, its point, body j, its point).
JOINTS = [
    (-1, (0.0, 0.0), 0, (-A_ / 2, 0.0)),
    (0, (A_ / 2, 0.0), 1, (-B_ / 2, 0.0)),
    (1, (B_ / 2, 0.0), 2, (C_ / 2, 0.0)),
    (-1, (D_, 0.0), 2, (-C_ / 2, 0.0)),
]


def _jacobian(q):
    """The revolute joints' constraint Jacobian (8, 9), written out by hand."""
    J = np.zeros((8, 9))
    for k, (i, si, j, sj) in enumerate(JOINTS):
        for b, s, sign in ((i, si, 1.0), (j, sj, -1.0)):
            if b < 0:
                continue
            J[2 * k : 2 * k + 2, 3 * b : 3 * b + 2] = sign * np.eye(2)
            J[2 * k : 2 * k + 2, 3 * b + 2] = sign * _B(q[3 * b + 2], s)
    return J


def _tip(q):
    """The rocker tip's centre (2,) and its gradient (2, 9)."""
    phi = q[8]
    s = (C_ / 2, 0.0)
    c = q[6:8] + np.array([math.cos(phi) * s[0], math.sin(phi) * s[0]])
    dc = np.zeros((2, 9))
    dc[:, 6:8] = np.eye(2)
    dc[:, 8] = _B(phi, s)
    return c, dc


def _ratios(q):
    """The velocity-ratio vector ``v`` (9,): the Jacobian's null space with ``v[2] = 1``."""
    v = np.linalg.svd(_jacobian(q))[2][-1]
    return v / v[2]


def _stop(theta2):
    """The stop's unit normal ``n`` (pointing out of it, against the tip's motion at
    ``theta2``) and its line point ``p`` (the tip touching it there)."""
    q = _pose(theta2)
    c, dc = _tip(q)
    u = dc @ _ratios(q)
    n = -u / np.linalg.norm(u)
    return n, c - TIP_R * n


def _mass_diagonal():
    return np.repeat(MASS, 3) * np.tile([1.0, 1.0, 0.0], 3) + np.repeat(INERTIA, 3) * np.tile(
        [0.0, 0.0, 1.0], 3
    )


def test_four_bar_impulse_keeps_the_joints_and_matches_the_hand_derivation():
    theta2, w, e = 0.7, 3.0, 0.6
    q = _pose(theta2)
    J = _jacobian(q)
    assert np.max(np.abs(J @ _ratios(q))) < 1e-12
    M = _mass_diagonal()
    n, _ = _stop(theta2)
    G = n @ _tip(q)[1]  # the gap's gradient
    v = _ratios(q)
    qd = w * v
    assert G @ qd < 0  # approaching
    qd_after, lam, P = impulse(1.0 / M, J, np.zeros(8), G, qd, e)
    scale = np.max(np.abs(qd))
    assert np.max(np.abs(J @ qd_after)) < 1e-12 * scale  # the joints kept
    assert abs(G @ qd_after + e * (G @ qd)) < 1e-12 * abs(G @ qd)  # Newton's law
    np.testing.assert_allclose(qd_after, -e * qd, rtol=0, atol=1e-12 * scale)  # w+ = -e w-
    inertia = v @ (M * v)
    np.testing.assert_allclose(P, -(1 + e) * inertia * w / (G @ v), rtol=1e-12)
    assert P > 0
    np.testing.assert_allclose(M * (qd_after - qd), J.T @ lam + G * P, atol=1e-12 * P)


def test_the_longest_step_keeps_up_with_a_falling_body():
    """A body falling from rest (``a0 = g``) over a contact of effective radius ``rho``: by
    the segment's horizon ``T`` it falls at ``g T``, and a step of the bound then moves it
    ``PASS_FRACTION rho`` at most; thrown at ``v0`` without acceleration the step is
    ``PASS_FRACTION rho / v0`` and the horizon infinite; at rest, the output interval. With
    ``gap`` to close before a watched point touches, the steps are the output interval's
    until the body has moved ``gap`` (where that is longer than the bounded segment)."""
    g, rho, dt_out = 9.81, 0.5e-3, 0.05

    class Contact:
        def effective_radius(self):
            return rho

    d = PASS_FRACTION * rho
    h, horizon = _longest_step([Contact()], np.zeros(3), np.array([0.0, -g, 0.0]), dt_out, 1.0)
    assert horizon == pytest.approx(HORIZON * h, rel=1e-15)
    assert (g * horizon) * h == pytest.approx(d, rel=1e-12)  # the speed reached, one step
    h, horizon = _longest_step([Contact()], np.array([2.0, 0.0, 0.0]), np.zeros(3), dt_out, 1.0)
    assert h == pytest.approx(d / 2.0, rel=1e-15) and horizon == math.inf
    h, horizon = _longest_step([Contact()], np.zeros(3), np.zeros(3), dt_out, 1.0)
    assert (h, horizon) == (dt_out, math.inf)
    # 0.5 m to close before a watched point touches: steps up to the output interval until the
    # falling body has moved that far (g T^2 / 2 = 0.5 m), the bounded steps nearer
    gap = 0.5
    h, horizon = _longest_step([Contact()], np.zeros(3), np.array([0.0, -g, 0.0]), dt_out, 1.0,
                               gap)  # fmt: skip
    assert h == dt_out and g * horizon**2 / 2 == pytest.approx(gap, rel=1e-12)
    near = _longest_step([Contact()], np.zeros(3), np.array([0.0, -g, 0.0]), dt_out, 1.0, 1e-5)
    assert near == _longest_step([Contact()], np.zeros(3), np.array([0.0, -g, 0.0]), dt_out, 1.0)


def test_rigid_contact_refusals():
    """A rigid contact with a friction regularization (``v_stick``: its impacts stick or
    slip exactly), or run (forward or mixed) by a fixed-step method, is refused before any
    computing (named input errors)."""
    ball = md.Body("ball", 1.0, 1e-3, q0=(0.0, 1.0, 0.0))
    with pytest.raises(md.ModelError, match="remove v_stick"):
        md.CircleLineContact(
            "floor", "ball", 0.05, ("ground", (0.0, 0.0)), contact_model="rigid",
            restitution=0.8, mu=0.3, v_stick=1e-3,
        )  # fmt: skip
    with pytest.raises(md.ModelError, match="Young's modulus"):
        md.CircleLineContact("floor", "ball", 0.05, ("ground", (0.0, 0.0)), restitution=1.0)
    floor = md.CircleLineContact(
        "floor", "ball", 0.05, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=0.8
    )
    lift = md.PointForce("lift", "ball", along=(0, 1), law=md.Polynomial([0.0]))
    model = md.Model([ball], forces=[floor, lift], gravity=(0, -9.81))
    with pytest.raises(md.ModelError, match="projection method") as err:
        md.forward(model, [0.0, 1.0], method="baumgarte", dt=1e-3)
    assert err.value.element == "floor"
    up = md.CoordinateDriver("up", "ball", "y", law=md.Polynomial([1.0, 0.1]))
    with pytest.raises(md.ModelError, match="projection method") as err:
        md.mixed(model, [0.0, 1.0], prescribed=[up], unknown=["lift"], method="baumgarte",
                 dt=1e-3)  # fmt: skip
    assert err.value.element == "floor"


def _ball(e, h0, R=0.05, g=9.81):
    ball = md.Body("ball", 1.0, 0.4 * R**2, q0=(0.0, h0 + R, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", R, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=e
    )
    return md.Model([ball], forces=[floor], gravity=(0, -g))


@pytest.mark.slow  # long: run by CI's slow set
def test_a_dropped_ball_bounces_to_e_squared_heights_at_closed_form_times():
    e, h0, R, g = 0.8, 1.0, 0.05, 9.81
    v0 = math.sqrt(2 * g * h0)
    t_hit = [v0 / g]
    for n in range(1, 5):
        t_hit.append(t_hit[-1] + 2 * e**n * v0 / g)
    apex = [t_hit[n] + e ** (n + 1) * v0 / g for n in range(4)]  # after the (n+1)-th impact
    ts = np.sort(np.concatenate([np.linspace(0.0, 3.0, 61), apex]))
    r = md.forward(_ball(e, h0), ts, rtol=1e-11, atol=1e-13)
    imp = r.stats["impacts"]
    hits = np.asarray(imp["t"])
    n = int(np.sum(np.asarray(t_hit) < 3.0))
    np.testing.assert_allclose(hits[:n], t_hit[:n], rtol=0, atol=1e-9)
    y = np.interp(apex, r.t, r["ball.y"])
    np.testing.assert_allclose(y - R, [e ** (2 * (k + 1)) * h0 for k in range(4)], atol=1e-9)
    np.testing.assert_allclose(imp["impulse"][0], (1 + e) * v0, rtol=1e-10)  # m = 1 kg
    lost = -0.5 * v0**2 * (1 - e**2)  # the first impact's loss
    assert abs(r["work.impacts"][np.searchsorted(r.t, t_hit[1]) - 1] - lost) < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_a_pendulum_striking_a_wall_rebounds_at_minus_e_omega():
    from scipy.special import ellipk

    L, m, e, g, R = 0.3, 0.5, 0.7, 9.81, 0.01
    J = m * L**2 / 12
    JO = J + m * L**2 / 4
    theta0 = math.radians(40)
    rod = md.Body(
        "rod", m, J, q0=(L / 2 * math.sin(theta0), -L / 2 * math.cos(theta0), theta0 - math.pi / 2),
        points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)},
    )  # fmt: skip
    wall = md.CircleLineContact(
        "wall", "rod.tip", R, ("ground", (-R, 0.0)), axis=(0.0, -1.0), contact_model="rigid",
        restitution=e,
    )  # fmt: skip
    model = md.Model([rod], [md.Revolute("O", "ground", "rod.O")], forces=[wall], gravity=(0, -g))
    r = md.forward(model, np.linspace(0.0, 0.5, 51), rtol=1e-11, atol=1e-13)
    imp = r.stats["impacts"]
    quarter = ellipk(math.sin(theta0 / 2) ** 2) / math.sqrt(m * g * L / 2 / JO)
    np.testing.assert_allclose(imp["t"][0], quarter, rtol=0, atol=1e-9)
    omega = math.sqrt(m * g * L * (1 - math.cos(theta0)) / JO)
    before, after = imp["qd_before"][0][2], imp["qd_after"][0][2]
    np.testing.assert_allclose(before, -omega, rtol=1e-9)
    np.testing.assert_allclose(after, -e * before, rtol=1e-12)
    k = np.searchsorted(r.t, imp["t"][0])
    assert r["rod.omega"][k] > 0  # the output after the impact has rebounded


def _four_bar_with_stop(theta0, theta_hit, e, drivers=()):
    """The four-bar from ``theta0``, its rocker's tip (radius ``TIP_R``) striking a rigid
    stop at the crank angle ``theta_hit``."""
    n, p = _stop(theta_hit)
    q0 = _pose(theta0)
    bodies = [
        md.Body("crank", MASS[0], INERTIA[0], q0=q0[0:3],
                points={"O": (-A_ / 2, 0), "A": (A_ / 2, 0)}),
        md.Body("coupler", MASS[1], INERTIA[1], q0=q0[3:6],
                points={"A": (-B_ / 2, 0), "B": (B_ / 2, 0)}),
        md.Body("rocker", MASS[2], INERTIA[2], q0=q0[6:9],
                points={"O": (-C_ / 2, 0), "B": (C_ / 2, 0)}),
    ]  # fmt: skip
    joints = [
        md.Revolute("O2", "ground.O2", "crank.O"),
        md.Revolute("A", "crank.A", "coupler.A"),
        md.Revolute("B", "coupler.B", "rocker.B"),
        md.Revolute("O4", "ground.O4", "rocker.O"),
    ]
    stop = md.CircleLineContact(
        "stop", "rocker.B", TIP_R, ("ground", (float(p[0]), float(p[1]))),
        axis=(float(n[1]), -float(n[0])), contact_model="rigid", restitution=e,
    )  # fmt: skip
    ground = {"O2": (0, 0), "O4": (D_, 0)}
    return md.Model(bodies, joints, list(drivers), forces=[stop], ground=ground)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_four_bar_rocker_striking_a_stop():
    theta_hit, w0, e = 0.7, 3.0, 0.6
    n, _ = _stop(theta_hit)
    q0 = _pose(0.5)  # the tip 2.6 mm from the stop
    model = _four_bar_with_stop(0.5, theta_hit, e)
    r = md.forward(model, np.linspace(0.0, 0.2, 21), qd0={"crank.phi": w0}, rtol=1e-11,
                   atol=1e-13)  # fmt: skip
    imp = r.stats["impacts"]
    assert len(imp["t"]) == 1
    q, before, after = imp["q"][0], imp["qd_before"][0], imp["qd_after"][0]
    np.testing.assert_allclose(q, _pose(theta_hit), atol=1e-9)
    M = _mass_diagonal()
    v = _ratios(q)
    inertia = v @ (M * v)
    T0 = 0.5 * w0**2 * (_ratios(q0) @ (M * _ratios(q0)))
    w = math.sqrt(2 * T0 / inertia)  # no forces: the kinetic energy kept
    np.testing.assert_allclose(before[2], w, rtol=1e-8)
    J = _jacobian(q)
    assert np.max(np.abs(J @ after)) < 1e-12 * np.max(np.abs(after))
    G = n @ _tip(q)[1]
    assert abs(G @ after + e * (G @ before)) < 1e-12 * abs(G @ before)
    np.testing.assert_allclose(after, -e * before, atol=1e-12 * np.max(np.abs(before)))
    P = imp["impulse"][0]
    np.testing.assert_allclose(P, -(1 + e) * inertia * before[2] / (G @ v), rtol=1e-9)
    # the momentum balance: what the contact's impulse leaves is a combination of Phi_q^T
    rest = M * (after - before) - G * P
    lam = np.linalg.lstsq(J.T, rest, rcond=None)[0]
    assert np.max(np.abs(J.T @ lam - rest)) < 1e-10 * P
    reported = np.abs(list(imp["reactions"][0].values()))
    np.testing.assert_allclose(sorted(np.abs(lam)), sorted(reported), rtol=1e-8, atol=1e-12 * P)
    np.testing.assert_allclose(r["work.impacts"][-1], -0.5 * (1 - e**2) * w**2 * inertia,
                               rtol=1e-8)  # fmt: skip


@pytest.mark.slow  # long: run by CI's slow set
def test_newtons_cradle_passes_the_momentum_along():
    R, m, V = 0.01, 0.1, 1.0
    balls = [md.Body(f"b{k}", m, 0.4 * m * R**2, q0=(x, 0.0, 0.0))
             for k, x in enumerate((-0.01, 2 * R, 4 * R))]  # fmt: skip
    law = dict(contact_model="rigid", restitution=1.0)
    contacts = [md.CircleContact(f"c{k}", f"b{k}", R, f"b{k + 1}", R, **law) for k in range(2)]
    model = md.Model(balls, forces=contacts)
    qd0 = np.zeros(9)
    qd0[0] = V
    r = md.forward(model, np.linspace(0.0, 0.05, 11), qd0=qd0, rtol=1e-11, atol=1e-13)
    imp = r.stats["impacts"]
    assert imp["contact"] == ["c0", "c1"]  # sequential: ball 0 on 1, then 1 on 2
    np.testing.assert_allclose(imp["t"], [0.01 / V, 0.01 / V], atol=1e-12)
    vx = np.stack([r[f"b{k}.vx"] for k in range(3)], axis=1)
    np.testing.assert_allclose(m * vx.sum(axis=1), m * V, rtol=1e-12)
    E = r["energy.kinetic"]
    np.testing.assert_allclose(E, 0.5 * m * V**2, rtol=1e-12)
    np.testing.assert_allclose(vx[-1], [0.0, 0.0, V], atol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
def test_impacts_past_the_most_a_run_takes_end_as_accumulating_impacts(monkeypatch):
    """Impacts that go on without slowing to the rest speed (here: past a limit of 3) end
    the run as a named failure at the closed-form time of the next impact, never a hang."""
    from mixdyn.analysis import _impacts

    monkeypatch.setattr(_impacts, "MAX_IMPACTS", 3)
    e, h0, g = 0.5, 0.1, 9.81
    v0 = math.sqrt(2 * g * h0)
    t4 = v0 / g + 2 * (e + e**2 + e**3) * v0 / g
    with pytest.raises(md.ImpactAccumulationError, match="chatter") as err:
        md.forward(_ball(e, h0), np.linspace(0.0, 2.0, 21), rtol=1e-11, atol=1e-13)
    assert abs(err.value.time - t4) < 1e-9
    assert err.value.elements == ("floor",)
    assert err.value.partial is not None


@pytest.mark.slow  # long: run by CI's slow set
def test_a_sweep_over_the_restitution_runs_each_member_impact_by_impact():
    h0, g = 1.0, 9.81
    v0 = math.sqrt(2 * g * h0)
    sw = md.sweep(
        _ball(0.8, h0),
        np.linspace(0.0, 1.0, 11),
        vary={"floor.restitution": [0.5, 0.9]},
        analysis=md.analyses.Forward(method=md.Projection(rtol=1e-10, atol=1e-12)),
    )
    for e, r in zip((0.5, 0.9), sw.results, strict=True):
        np.testing.assert_allclose(r.stats["impacts"]["impulse"][0], (1 + e) * v0, rtol=1e-10)
        np.testing.assert_allclose(r.stats["impacts"]["normal_velocity_after"][0], e * v0,
                                   rtol=1e-10)  # fmt: skip


@pytest.mark.slow  # long: run by CI's slow set
def test_a_rigid_contact_penetrating_at_the_start_is_an_input_error():
    with pytest.raises(md.ModelError, match=r"penetrates by 0\.01 ") as err:
        md.forward(_ball(0.8, -0.01), [0.0, 1.0])
    assert err.value.element == "floor"


@pytest.mark.slow  # long: run by CI's slow set
def test_a_driven_four_bar_against_a_rigid_stop_is_a_named_failure():
    """With its crank driven the four-bar cannot rebound: the impulse would be infinite. The
    run fails at the impact, (0.7 - 0.5) / 3 s, naming the stop."""
    motor = md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.5, 3.0))
    model = _four_bar_with_stop(0.5, 0.7, 0.6, [motor])
    with pytest.raises(md.SingularityError, match="cannot reverse its normal velocity") as err:
        md.forward(model, np.linspace(0.0, 0.2, 21), rtol=1e-11, atol=1e-13)
    assert abs(err.value.time - 0.2 / 3.0) < 1e-9
    assert err.value.elements == ("stop",)
