"""Resting rigid contacts (``contact_model: rigid``): a contact point whose impacts
accumulate is held on its contact, its normal force the multiplier of the held gap.

- Statics, a second method: a rod pinned at one end and lying horizontal on a stop under
  its other end is held with ``m g / 2`` (the moment balance about the pin), the pin
  carrying the other half (fast); a ball resting on a frictionless slope of angle
  ``theta`` is held with the normal force ``m g cos(theta)`` and slides down at
  ``g sin(theta)`` (slow).
- Several points settling at once (fast, by hand): a box landing flat at ``v`` takes
  ``m v / 2`` at each bottom corner and stops; landing while spinning so fast that one
  corner leaves, only the other takes an impulse, ``v_1 / (1/m + x^2/J)`` (its effective
  mass), and stops.
- A ball dropped on the ground with ``e < 1`` (slow): impacts at the closed-form times
  ``t_1 = v0 / g``, ``t_{n+1} = t_n + 2 e^n v0 / g``; it comes to rest at the sum of the
  series ``t_inf = t_1 + 2 e v0 / (g (1 - e))`` (to the run's rest speed) and stays at
  height ``R`` with the normal force ``m g`` (1e-9); the energy the impacts took is all the
  energy lost (the resting contact does no work).
- Lift-off (slow): a ball resting on the ground pulled up by ``F = k t`` leaves it at
  ``t = m g / k`` (1e-9), pressing on it with ``m g - k t`` until then, and rises as
  ``k (t - m g / k)^3 / (6 m)`` after; a block resting on two corners, pulled at its
  centre, leaves with both at once and rises level.
- The ball on the slope in a run (slow): held from the start, it slides as
  ``g sin(theta) t^2 / 2`` along the slope with the normal force ``m g cos(theta)``.
- Runs that come to rest (slow): a pinned rod falling on a stop rests on it with
  ``m g / 2`` (the pin the other half); a tilted box dropped settles flat on two corners
  with ``m g`` in all; ``examples/resting_ball.yaml`` rests at ``t_inf`` and lifts off at
  ``1 + m g / k``.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.analysis._impulses import settle
from mixdyn.analysis._problem import Problem
from mixdyn.analysis._resting import hold, holding, normal_forces
from mixdyn.equations import Constraints

G_ = 9.81


def _ball_on_slope(theta, m=2.0, R=0.05, e=0.5):
    """A ball touching a frictionless slope that falls to the right at ``theta``."""
    n = np.array([math.sin(theta), math.cos(theta)])  # the slope's outward normal
    ball = md.Body("ball", m, 0.4 * m * R**2, q0=(R * n[0], R * n[1], 0.0))
    slope = md.CircleLineContact(
        "slope", "ball", R, ("ground", (0.0, 0.0)), axis=(math.cos(theta), -math.sin(theta)),
        contact_model="rigid", restitution=e,
    )  # fmt: skip
    return md.Model([ball], forces=[slope], gravity=(0, -G_))


def _held(model, name):
    problem = Problem(model, Constraints.of(model))
    return holding(problem, (hold(model.element(name), 0, 1),))


def test_points_touching_at_once_settle_with_pushing_impulses():
    m, J, w = 2.0, 0.01, 0.2
    Minv = 1.0 / np.array([m, m, J])
    x = np.array([-w / 2, w / 2])  # the bottom corners, about the centre
    G = np.stack([np.zeros(2), np.ones(2), x], axis=1)  # d(gap)/d(x, y, phi) at phi = 0
    none = np.zeros((0, 3)), np.zeros(0)
    v = 1.5
    after, points, P = settle(Minv, *none, G, np.array([0.0, -v, 0.0]), np.ones(2, bool), 0.0)[:3]
    assert sorted(points) == [0, 1]
    np.testing.assert_allclose(P, [m * v / 2] * 2, rtol=1e-12)
    np.testing.assert_allclose(after, 0.0, atol=1e-12)
    spin = 40.0  # corner 1 leaves at -v + spin w / 2 > 0
    qd = np.array([0.0, -v, spin])
    after, points, P = settle(Minv, *none, G, qd, np.ones(2, bool), 0.0)[:3]
    v1 = G[0] @ qd
    assert points == [0] and G[1] @ after > 0.0
    np.testing.assert_allclose(P, [-v1 / (1 / m + x[0] ** 2 / J)], rtol=1e-12)
    assert abs(G[0] @ after) < 1e-12


@pytest.mark.parametrize("u", [2.0, 0.3], ids=["slides", "sticks"])
def test_a_rough_box_settling_flat_skids_by_mu_v_or_stops(u):
    """Settling flat (a plastic impact at both bottom corners, ``(-+a, -b)`` from the
    centre) on a rough floor, a box moving sideways at ``u`` loses ``mu m v`` of its momentum
    to the corners' friction impulses, ``T_k = mu P_k`` (sliding), or stops (``mu v > u``),
    without turning: the corners' normal impulses balance the friction's moment,
    ``a (P_2 - P_1) = b (T_1 + T_2)``."""
    m, J, a, b, mu, v = 2.0, 0.01, 0.1, 0.05, 0.4, 1.5
    Minv = 1.0 / np.array([m, m, J])
    G = np.array([[0.0, 1.0, -a], [0.0, 1.0, a]])
    Gt = np.array([[-1.0, 0.0, -b], [-1.0, 0.0, -b]])  # the slips along z x n = (-1, 0)
    none = np.zeros((0, 3)), np.zeros(0)
    qd = np.array([u, -v, 0.0])
    found = settle(Minv, *none, G, qd, np.ones(2, bool), 0.0, None, Gt, np.full(2, mu))
    assert sorted(found.points) == [0, 1]
    np.testing.assert_allclose(found.qd[1:], 0.0, atol=1e-12)
    np.testing.assert_allclose(found.P.sum(), m * v, rtol=1e-12)
    P, T = found.P[np.argsort(found.points)], found.T[np.argsort(found.points)]
    np.testing.assert_allclose(a * (P[1] - P[0]), b * T.sum(), rtol=1e-12)
    np.testing.assert_allclose(found.qd[0], max(u - mu * v, 0.0), atol=1e-12)
    if u > mu * v:
        np.testing.assert_allclose(T, mu * P, rtol=1e-12)
    else:
        assert np.all(np.abs(T) <= mu * P * (1 + 1e-12)) and found.sticks.any()
    frictionless = settle(Minv, *none, G, qd, np.ones(2, bool), 0.0)
    np.testing.assert_allclose(frictionless.qd, [u, 0.0, 0.0], atol=1e-12)  # keeps sliding


@pytest.mark.slow  # long: run by CI's slow set
def test_a_ball_resting_on_a_slope_presses_with_m_g_cos_theta():
    theta, m = 0.3, 2.0
    model = _ball_on_slope(theta, m)
    held = _held(model, "slope")
    q, qd, t = jnp.asarray(model.q0), jnp.zeros(3), jnp.zeros(())
    np.testing.assert_allclose(normal_forces(held, q, qd, t), [m * G_ * math.cos(theta)],
                               rtol=1e-12)  # fmt: skip
    qdd = np.asarray(held.accelerations(q, qd, t)[0])
    down = np.array([math.cos(theta), -math.sin(theta)])
    np.testing.assert_allclose(qdd[:2], G_ * math.sin(theta) * down, rtol=1e-12)


def _rod_on_a_stop(phi0, L=0.4, m=1.5, R=0.01, e=0.5):
    """A rod pinned at its end O on the ground's origin at the angle ``phi0``, its other
    end's rounded tip (radius ``R``) above a stop that it touches lying horizontal."""
    c = (L / 2 * math.cos(phi0), L / 2 * math.sin(phi0), phi0)
    rod = md.Body("rod", m, m * L**2 / 12, q0=c, points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)})
    stop = md.CircleLineContact("stop", "rod.tip", R, ("ground", (L, -R)), contact_model="rigid",
                                restitution=e)  # fmt: skip
    return md.Model([rod], [md.Revolute("O", "ground", "rod.O")], forces=[stop],
                    gravity=(0, -G_))  # fmt: skip


def test_a_rod_lying_on_a_stop_presses_with_half_its_weight():
    m = 1.5
    model = _rod_on_a_stop(0.0, m=m)
    held = _held(model, "stop")
    q, qd, t = jnp.asarray(model.q0), jnp.zeros(3), jnp.zeros(())
    np.testing.assert_allclose(normal_forces(held, q, qd, t), [m * G_ / 2], rtol=1e-12)
    qdd, mu, _ = held.accelerations(q, qd, t)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)
    pin_y = -np.asarray(held.c.phi_q(q, t)).T[:, :2] @ np.asarray(mu)[:2]
    np.testing.assert_allclose(pin_y[1], m * G_ / 2, rtol=1e-12)  # the pin's share


@pytest.mark.slow  # long: run by CI's slow set
def test_a_dropped_ball_comes_to_rest_at_the_zeno_time_and_stays():
    e, h0, R, m = 0.5, 0.1, 0.05, 1.0
    ball = md.Body("ball", m, 0.4 * m * R**2, q0=(0.0, h0 + R, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", R, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=e
    )
    model = md.Model([ball], forces=[floor], gravity=(0, -G_))
    v0 = math.sqrt(2 * G_ * h0)
    t_inf = v0 / G_ + 2 * e * v0 / (G_ * (1 - e))
    r = md.forward(model, np.linspace(0.0, 1.0, 21), rtol=1e-11, atol=1e-13)
    imp, rests = r.stats["impacts"], r.stats["rests"]
    t_hit = [v0 / G_]
    for n in range(1, 6):
        t_hit.append(t_hit[-1] + 2 * e**n * v0 / G_)
    np.testing.assert_allclose(imp["t"][:6], t_hit, rtol=0, atol=1e-9)
    assert rests["contact"] == ["floor"]
    assert 0.0 <= t_inf - rests["start"][0] < 1e-6  # the series' sum, to the rest speed
    assert rests["end"][0] == 1.0  # it stays
    after = r.t > t_inf
    np.testing.assert_allclose(r["ball.vy"][after], 0.0, atol=1e-12)
    np.testing.assert_allclose(r["ball.y"][after], R, rtol=1e-9)
    np.testing.assert_allclose(r["floor.normal"][after], m * G_, rtol=1e-9)
    np.testing.assert_allclose(r["ball.ay"][after], 0.0, atol=1e-9)
    assert np.all(r["floor.normal"][~after] == 0.0)
    # its arrow: m g upwards at the contact point under the ball while it rests, none before
    from mixdyn.viz.arrows import force_arrows

    (arrow,) = force_arrows(r, ["floor"])
    np.testing.assert_allclose(arrow["F"][after], [[0.0, m * G_]] * int(after.sum()), rtol=1e-9)
    np.testing.assert_allclose(arrow["at"][after], 0.0, atol=1e-9)
    assert np.all(arrow["F"][~after] == 0.0)
    # all the energy lost went into the impacts: the resting contact does no work
    E = r["energy.kinetic"] + r["energy.potential"]
    np.testing.assert_allclose(r["work.impacts"][-1], -m * G_ * h0, rtol=1e-9)
    np.testing.assert_allclose(E - E[0], r["work.impacts"], atol=1e-9 * m * G_ * h0)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_ball_pulled_up_by_a_ramp_lifts_off_at_m_g_over_k():
    g, R, m, k = G_, 0.05, 2.0, 40.0
    ball = md.Body("ball", m, 0.4 * m * R**2, q0=(0.0, R, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", R, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=0.5
    )
    lift = md.PointForce("lift", "ball", along=(0, 1), law=md.Polynomial([0.0, k]))
    model = md.Model([ball], forces=[floor, lift], gravity=(0, -g))
    r = md.forward(model, np.linspace(0.0, 1.0, 21), rtol=1e-11, atol=1e-13)
    t_lift = m * g / k
    rests = r.stats["rests"]
    assert rests["start"][0] == 0.0 and len(r.stats["impacts"]["t"]) == 0
    assert abs(rests["end"][0] - t_lift) < 1e-9
    before, after = r.t < t_lift, r.t > t_lift
    np.testing.assert_allclose(r["floor.normal"][before], m * g - k * r.t[before], rtol=1e-9)
    np.testing.assert_allclose(r["ball.y"][before], R, rtol=1e-12)
    rise = k * (r.t[after] - t_lift) ** 3 / (6 * m)
    np.testing.assert_allclose(r["ball.y"][after] - R, rise, rtol=1e-8, atol=1e-12)
    assert np.all(r["floor.normal"][after] == 0.0)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_ball_held_on_a_slope_slides_at_g_sin_theta():
    theta, m = 0.3, 2.0
    model = _ball_on_slope(theta, m)
    r = md.forward(model, np.linspace(0.0, 0.5, 11), rtol=1e-11, atol=1e-13)
    assert r.stats["rests"]["start"][0] == 0.0 and r.stats["rests"]["end"][0] == 0.5
    s = 0.5 * G_ * math.sin(theta) * r.t**2
    x0 = model.q0[0]
    np.testing.assert_allclose(r["ball.x"] - x0, s * math.cos(theta), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(r["slope.normal"], m * G_ * math.cos(theta), rtol=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_the_resting_ball_example_rests_then_lifts_off(tmp_path):
    """``examples/resting_ball.yaml``: at rest at ``t_inf``, lifted off by a force
    ``k (t - 1)`` from 1 s at ``1 + m g / k``."""
    from fixtures import EXAMPLES

    (r,) = md.run_file(EXAMPLES / "resting_ball.yaml", tmp_path).values()
    m, e, h0, k = 0.1, 0.5, 0.1, 1.962
    v0 = math.sqrt(2 * G_ * h0)
    rests = r.stats["rests"]
    assert 0.0 <= v0 / G_ + 2 * e * v0 / (G_ * (1 - e)) - rests["start"][0] < 1e-6
    assert abs(rests["end"][0] - (1.0 + m * G_ / k)) < 1e-9
    resting = (r.t > rests["start"][0]) & (r.t < rests["end"][0])
    pull = k * np.maximum(r.t[resting] - 1.0, 0.0)
    np.testing.assert_allclose(r["floor.normal"][resting], m * G_ - pull, rtol=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_rod_falling_on_a_stop_comes_to_rest_on_it_with_half_its_weight():
    """The rod released 0.2 rad above its stop bounces (``e = 0.3``), comes to rest lying
    on it, held with ``m g / 2`` (the moment balance about the pin); the impacts took all the
    potential energy its centre lost, ``m g (L / 2) sin(0.2)``."""
    L, m, phi0 = 0.4, 1.5, 0.2
    model = _rod_on_a_stop(phi0, L=L, m=m, e=0.3)
    r = md.forward(model, np.linspace(0.0, 1.0, 21), rtol=1e-11, atol=1e-13)
    rests = r.stats["rests"]
    assert rests["contact"] == ["stop"] and rests["end"][0] == 1.0
    assert len(r.stats["impacts"]["t"]) > 3  # it bounced before resting
    after = r.t > rests["start"][0]
    np.testing.assert_allclose(r["rod.phi"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["stop.normal"][after], m * G_ / 2, rtol=1e-9)
    np.testing.assert_allclose(r["O.Fy"][after], m * G_ / 2, rtol=1e-9)  # the pin on the rod
    lost = -m * G_ * (L / 2) * math.sin(phi0)
    np.testing.assert_allclose(r["work.impacts"][-1], lost, rtol=1e-8)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_tilted_box_dropped_on_the_ground_settles_flat_on_two_corners():
    """A box dropped tilted rocks from corner to corner until both bottom corners touch
    at one instant, settles on them together (a plastic impact with two non-negative
    impulses) and lies flat at ``y = h / 2`` with the corners' normal forces summing to
    ``m g``; the impacts took all the energy it lost."""
    m, w, h, rc = 1.0, 0.2, 0.1, 0.005
    box = md.Body("box", m, m * (w**2 + h**2) / 12, q0=(0.0, 0.15, 0.1))
    floor = md.BoxLineContact("floor", "box", w, h, rc, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=0.4)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G_))
    r = md.forward(model, np.linspace(0.0, 1.0, 11), rtol=1e-10, atol=1e-12)
    rests = r.stats["rests"]
    assert sorted(rests["end"])[-2:] == [1.0, 1.0]  # two corners rest to the end
    after = r.t > max(rests["start"])
    np.testing.assert_allclose(r["box.y"][after], h / 2, rtol=1e-9)
    np.testing.assert_allclose(r["box.phi"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["floor.normal"][after], m * G_, rtol=1e-9)
    E = r["energy.kinetic"] + r["energy.potential"]
    np.testing.assert_allclose(E - E[0], r["work.impacts"], atol=1e-9 * m * G_ * 0.15)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_tilted_box_settles_at_the_default_tolerances():
    """The same landing at the default tolerances, the box lighter to turn: once both
    corners are held, the next interval starts with a step of its own size (the held
    corners' gaps, which rounding shows as separating, do not shrink it to nothing) and the
    box lies flat to the end with the corners carrying ``m g``."""
    m, w, h, rc = 1.0, 0.2, 0.1, 0.005
    box = md.Body("box", m, 0.01, q0=(0.0, 0.15, 0.1))
    floor = md.BoxLineContact("floor", "box", w, h, rc, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=0.4)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G_))
    r = md.forward(model, np.linspace(0.0, 0.5, 6))
    assert sorted(r.stats["rests"]["end"])[-2:] == [0.5, 0.5]
    after = r.t > max(r.stats["rests"]["start"])
    np.testing.assert_allclose(r["box.y"][after], h / 2, rtol=1e-9)
    np.testing.assert_allclose(r["box.phi"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["floor.normal"][after], m * G_, rtol=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_box_dropped_flat_bounces_level_at_e_times_its_speed():
    """A box dropped flat strikes with both bottom corners at once, Newton's law at each
    (solved together): it bounces level, ``v+ = e sqrt(2 g h0)`` at ``t_1 = sqrt(2 h0 / g)``
    and strikes again at ``t_1 + 2 v+ / g``, never turning."""
    m, w, h, rc, e, h0 = 1.0, 0.2, 0.1, 0.005, 0.4, 0.1
    box = md.Body("box", m, m * (w**2 + h**2) / 12, q0=(0.0, h / 2 + h0, 0.0))
    floor = md.BoxLineContact("floor", "box", w, h, rc, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=e)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G_))
    r = md.forward(model, np.linspace(0.0, 0.4, 9), rtol=1e-10, atol=1e-12)
    imp = r.stats["impacts"]
    t1 = math.sqrt(2 * h0 / G_)
    v1 = e * G_ * t1
    np.testing.assert_allclose(imp["t"][:4], [t1, t1, t1 + 2 * v1 / G_, t1 + 2 * v1 / G_],
                               rtol=0, atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(imp["normal_velocity_after"][:2], [v1, v1], rtol=1e-9)
    np.testing.assert_allclose(np.sum(imp["impulse"][:2]), m * (1 + e) * G_ * t1, rtol=1e-9)
    assert np.max(np.abs(r["box.phi"])) < 1e-12 and np.max(np.abs(r["box.x"])) < 1e-12


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_pulled_up_by_a_ramp_lifts_off_both_corners_at_m_g_over_k():
    """A block resting flat on two corners, pulled up at its centre by ``F = k t``: each
    corner presses with ``(m g - k t) / 2``, both leave at ``t = m g / k`` (1e-9) and the
    block rises level as ``k (t - m g / k)^3 / (6 m)``."""
    m, w, h, rc, k = 2.0, 0.2, 0.1, 0.005, 40.0
    block = md.Body("block", m, m * (w**2 + h**2) / 12, q0=(0.0, h / 2, 0.0))
    floor = md.BoxLineContact("floor", "block", w, h, rc, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=0.4)  # fmt: skip
    lift = md.PointForce("lift", "block", along=(0, 1), law=md.Polynomial([0.0, k]))
    model = md.Model([block], forces=[floor, lift], gravity=(0, -G_))
    r = md.forward(model, np.linspace(0.0, 1.0, 21), rtol=1e-11, atol=1e-13)
    t_lift = m * G_ / k
    rests = r.stats["rests"]
    assert rests["contact"] == ["floor", "floor"] and list(rests["start"]) == [0.0, 0.0]
    np.testing.assert_allclose(rests["end"], t_lift, rtol=0, atol=1e-9)
    before, after = r.t < t_lift, r.t > t_lift
    np.testing.assert_allclose(r["floor.normal"][before], m * G_ - k * r.t[before], rtol=1e-9)
    rise = k * (r.t[after] - t_lift) ** 3 / (6 * m)
    np.testing.assert_allclose(r["block.y"][after] - h / 2, rise, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(r["block.phi"], 0.0, atol=1e-12)
