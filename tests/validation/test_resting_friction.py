"""Coulomb friction at a resting rigid contact, with stick and slip, against closed forms.

A resting point's normal force ``N`` is its held row's multiplier; its friction is
``-mu N sign(v_t)`` while it slides and holds it still up to ``mu N``
(:class:`~mixdyn.analysis._resting.RestFriction`).

- The equations alone (fast), at a state resting on an incline of angle ``theta``: a block
  held by ``mu >= tan(theta)`` has no acceleration, its friction ``m g sin(theta)`` and normal
  force ``m g cos(theta)``; one on a steeper incline slides at
  ``g (sin(theta) - mu cos(theta))``; a disc rolls at ``2/3 g sin(theta)`` (``J = m R^2 / 2``)
  with ``mu >= tan(theta) / 3`` and otherwise slides at ``g (sin(theta) - mu cos(theta))``
  while it spins up at ``mu m g cos(theta) R / J``.
- A disc dropped with ``e = 0.1`` on a rough incline bounces until the bounces accumulate at
  ``t_inf = t_1 (1 + e) / (1 - e)`` (``t_1 = sqrt(2 h / (g cos(theta)))``: Newton's law fixes
  the normal velocities whatever the friction does), then rests and rolls on at
  ``2/3 g sin(theta)``, its contact point still (slow).
- A block thrown on rough flat ground slides to a stop at ``v0^2 / (2 mu g)`` at
  ``t = v0 / (mu g)`` and stays there; on inclines it stays put or slides as the closed forms
  say; its energy balance closes with the friction's work (slow).
- With ``mu = 0`` the disc slides down at ``g sin(theta) t^2 / 2`` throughout (slow).
- On rough flat ground a disc dropped rests with ``m g``; one thrown level sticks at its
  first impact (its angular momentum about the contact point kept:
  ``v_x+ = m R^2 v_x / (m R^2 + J)``) and rolls on at that speed (slow).
- ``mixdyn run`` of a model file with the rough incline writes the friction column (slow).
- A block sliding on rough ground into a rigid stop reaches it at the closed-form time and
  speed, rebounds level at ``-e v1``, slides back to its closed-form stop and sticks there;
  the impact's and the friction's losses close the energy balance (slow).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.analysis._problem import Problem
from mixdyn.analysis._resting import friction_at, hold, holding
from mixdyn.cli import app
from mixdyn.equations import Constraints
from mixdyn.model._compliant import rigid_contacts

G_ACC, M, R, H, E = 9.81, 2.0, 0.05, 0.1, 0.1
J = 0.5 * M * R**2
THETA = math.radians(20.0)
W_BOX, H_BOX, R_CORNER = 0.2, 0.1, 0.01
J_BOX = M * (W_BOX**2 + H_BOX**2) / 12


def _axes(theta):
    """The incline's direction down it and its outward normal (2,), (2,)."""
    return (
        np.array([math.cos(theta), -math.sin(theta)]),
        np.array([math.sin(theta), math.cos(theta)]),
    )


def _disc(mu, theta=THETA, h=H):
    """A disc whose centre is ``h + R`` above the incline through the origin (along its
    normal), released at rest: a rigid contact with ``e = 0.1``."""
    down, normal = _axes(theta)
    c = (h + R) * normal
    disc = md.Body("disc", M, J, q0=(c[0], c[1], 0.0))
    incline = md.CircleLineContact(
        "incline", "disc", R, ("ground", (0.0, 0.0)), axis=tuple(down), contact_model="rigid",
        restitution=E, mu=mu,
    )  # fmt: skip
    return md.Model([disc], forces=[incline], gravity=(0, -G_ACC))


def _block(mu, theta):
    """A block ``W_BOX`` by ``H_BOX`` (rounded corners) lying on the incline, its long side
    along it: a rigid contact at its four corners, two of which touch."""
    down, normal = _axes(theta)
    c = 0.5 * H_BOX * normal
    block = md.Body("block", M, J_BOX, q0=(c[0], c[1], -theta))
    floor = md.BoxLineContact(
        "floor", "block", W_BOX, H_BOX, R_CORNER, ("ground", (0.0, 0.0)), axis=tuple(down),
        contact_model="rigid", restitution=0.5, mu=mu,
    )  # fmt: skip
    return md.Model([block], forces=[floor], gravity=(0, -G_ACC))


def _resting(model, points, band=1e-7):
    """The forward problem of ``model`` with ``points`` of its contact held, with friction."""
    (c,) = rigid_contacts(model)
    n = int(np.size(np.asarray(c.penetration(model.q0))))
    holds = tuple(hold(c, k, n) for k in points)
    frictions = (friction_at(c, tuple(points), n, band),)
    return holding(Problem(model, Constraints.of(model)), holds, frictions)


@eqx.filter_jit
def _solved(problem, q, qd):
    return problem.accelerations(q, qd, jnp.zeros(()))[:2]


def _accelerations(problem, q, qd):
    qdd, mu = _solved(problem, jnp.asarray(q), jnp.asarray(qd, dtype=jnp.float64))
    return np.asarray(qdd), np.asarray(mu)


@pytest.mark.parametrize(("theta_deg", "mu"), [(20.0, 0.5), (30.0, 0.3)], ids=["holds", "slides"])
def test_a_block_resting_on_an_incline_holds_or_slides_as_coulomb_says(theta_deg, mu):
    theta = math.radians(theta_deg)
    down, normal = _axes(theta)
    model = _block(mu, theta)
    problem = _resting(model, (2, 3))  # the two lower corners
    qdd, lam = _accelerations(problem, model.q0, np.zeros(3))
    a = max(G_ACC * (math.sin(theta) - mu * math.cos(theta)), 0.0)
    np.testing.assert_allclose(qdd[:2] @ down, a, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(qdd[:2] @ normal, 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd[2], 0.0, atol=1e-11)
    np.testing.assert_allclose(lam.sum(), M * G_ACC * math.cos(theta), rtol=1e-12)


@pytest.mark.parametrize("mu", [0.5, 0.05], ids=["rolls", "slides-and-spins"])
def test_a_disc_resting_on_an_incline_rolls_or_slides_as_coulomb_says(mu):
    down, _ = _axes(THETA)
    model = _disc(mu, h=0.0)
    problem = _resting(model, (0,))
    qdd, lam = _accelerations(problem, model.q0, np.zeros(3))
    if mu >= math.tan(THETA) / 3:
        a, alpha = 2 / 3 * G_ACC * math.sin(THETA), -2 / 3 * G_ACC * math.sin(THETA) / R
    else:
        a = G_ACC * (math.sin(THETA) - mu * math.cos(THETA))
        alpha = -mu * M * G_ACC * math.cos(THETA) * R / J  # clockwise, rolling down
    np.testing.assert_allclose(qdd[:2] @ down, a, rtol=1e-12)
    np.testing.assert_allclose(qdd[2], alpha, rtol=1e-12)
    np.testing.assert_allclose(lam, [M * G_ACC * math.cos(THETA)], rtol=1e-12)


TS = np.linspace(0.0, 0.3, 7)


def _t_land(theta=THETA):
    """The first impact's time [s] (the fall along the normal at ``g cos(theta)``)."""
    return math.sqrt(2 * H / (G_ACC * math.cos(theta)))


def _t_rest(theta=THETA):
    """The bounces' accumulation (Zeno) time [s]: the frictional impulses leave the normal
    velocity to Newton's law, ``t_inf = t_1 (1 + e) / (1 - e)``."""
    return _t_land(theta) * (1 + E) / (1 - E)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_dropped_on_a_rough_rigid_incline_rests_and_rolls():
    down, normal = _axes(THETA)
    r = md.forward(_disc(0.5), TS)
    t_rest = _t_rest()
    assert r.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    after = t_rest < TS
    a = 2 / 3 * G_ACC * math.sin(THETA)
    np.testing.assert_allclose(r.qdd[after, :2] @ down, a, rtol=1e-9)
    v = r.qd[:, :2] @ down
    np.testing.assert_allclose(v[after] + R * r.qd[after, 2], 0.0, atol=1e-9)  # rolling
    np.testing.assert_allclose(r.q[after, :2] @ normal, R, rtol=0, atol=1e-9)
    friction = M * G_ACC * math.sin(THETA) / 3  # on the disc, up the incline (along z x n)
    np.testing.assert_allclose(np.abs(r["incline.friction"][after]), friction, rtol=1e-9)
    np.testing.assert_allclose(r["incline.friction"][~after], 0.0)
    np.testing.assert_allclose(r["incline.normal"][after], M * G_ACC * math.cos(THETA), rtol=1e-9)
    assert r.stats["energy_balance_error"] < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_thrown_on_rough_flat_ground_slides_to_a_stop_and_stays():
    mu, v0 = 0.4, 1.0
    ts = np.linspace(0.0, 0.5, 11)
    r = md.forward(_block(mu, 0.0), ts, qd0=np.array([v0, 0.0, 0.0]))
    t_stop = v0 / (mu * G_ACC)
    x = np.where(ts < t_stop, v0 * ts - 0.5 * mu * G_ACC * ts**2, v0**2 / (2 * mu * G_ACC))
    np.testing.assert_allclose(r.q[:, 0], x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.qd[ts > t_stop], 0.0, atol=1e-12)
    moving = ts < t_stop
    np.testing.assert_allclose(np.abs(r["floor.friction"][moving]), mu * M * G_ACC, rtol=1e-12)
    np.testing.assert_allclose(r["floor.friction"][~moving], 0.0, atol=1e-9)
    # the friction took the kinetic energy: m v0^2 / 2 of nonconservative work at the stop
    np.testing.assert_allclose(r["work.nonconservative"][-1], -0.5 * M * v0**2, rtol=1e-9)
    assert r.stats["energy_balance_error"] < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.parametrize(("theta_deg", "mu"), [(20.0, 0.5), (30.0, 0.3)], ids=["stays", "slides"])
def test_a_block_resting_on_a_rough_rigid_incline_stays_or_slides(theta_deg, mu):
    theta = math.radians(theta_deg)
    down, _ = _axes(theta)
    ts = np.linspace(0.0, 0.5, 6)
    r = md.forward(_block(mu, theta), ts)
    a = max(G_ACC * (math.sin(theta) - mu * math.cos(theta)), 0.0)
    s = (r.q[:, :2] - r.q[0, :2]) @ down
    np.testing.assert_allclose(s, 0.5 * a * ts**2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.q[:, 2], -theta, atol=1e-12)
    limit = mu * M * G_ACC * math.cos(theta)
    friction = M * G_ACC * math.sin(theta) if a == 0.0 else limit
    np.testing.assert_allclose(np.abs(r["floor.friction"]), friction, rtol=1e-12)
    np.testing.assert_allclose(r["floor.normal"], M * G_ACC * math.cos(theta), rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_on_a_frictionless_rigid_incline_slides_at_g_sin_theta():
    down, normal = _axes(THETA)
    r = md.forward(_disc(0.0), TS, rtol=1e-10, atol=1e-12)
    t_rest = _t_rest()
    assert r.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    s = 0.5 * G_ACC * math.sin(THETA) * TS**2
    np.testing.assert_allclose(r.q[:, :2] @ down, s, rtol=0, atol=1e-8)
    after = t_rest < TS
    np.testing.assert_allclose(r.q[after, :2] @ normal, R, rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["incline.normal"][after], M * G_ACC * math.cos(THETA), rtol=1e-7)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_resting_or_rolling_on_rough_flat_ground_runs():
    r = md.forward(_disc(0.5, theta=0.0), TS)
    t_land, t_rest = _t_land(0.0), _t_rest(0.0)
    assert r.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    after = t_rest < TS
    np.testing.assert_allclose(r.q[after, 1], R, rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["incline.normal"][after], M * G_ACC, rtol=1e-9)
    np.testing.assert_allclose(r["incline.friction"], 0.0, atol=1e-9)
    vx = 1.0  # thrown level: sticks at the landing and rolls
    rolled = md.forward(_disc(1.0, theta=0.0), TS, qd0=np.array([vx, 0.0, 0.0]))
    v_roll = M * R**2 * vx / (M * R**2 + J)
    assert bool(rolled.stats["impacts"]["sticks"][0])
    assert rolled.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    later = t_land < TS
    x = vx * t_land + v_roll * (TS[later] - t_land)
    np.testing.assert_allclose(rolled.q[later, 0], x, rtol=0, atol=1e-8)
    np.testing.assert_allclose(rolled.qd[later, 2], -v_roll / R, rtol=1e-9)


DOWN, NORMAL = _axes(THETA)
X0, Y0 = (H + R) * NORMAL
FILE = f"""\
mixdyn: 1
name: rough-incline
units: {{length: m, mass: kg, time: s}}
gravity: [0, -{G_ACC} m/s^2]
ground:
  points: {{O: [0, 0]}}
bodies:
  - {{name: disc, mass: {M} kg, inertia: {J}, q0: [{X0}, {Y0}, 0]}}
forces:
  - {{type: circle_line_contact, name: incline, center: disc, radius: {R} m, line_point: ground.O,
     axis: [{DOWN[0]}, {DOWN[1]}], contact_model: rigid, restitution: {E}, mu: 0.5}}
runs:
  - name: drop
    kind: forward
    time: {{span: [0, 0.3], n: 7}}
"""


@pytest.mark.slow  # long: run by CI's slow set
def test_mixdyn_run_of_a_rough_rigid_incline_writes_the_resting_friction(tmp_path):
    path = tmp_path / "incline.yaml"
    path.write_text(FILE)
    out = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert out.exit_code == 0, out.output
    (table,) = (tmp_path / "out").rglob("results.csv")
    frame = pd.read_csv(table)
    (column,) = [c for c in frame.columns if c.startswith("incline.friction ")]
    assert "[N]" in column
    after = frame.filter(like="t ").iloc[:, 0].to_numpy() > _t_rest()
    friction = M * G_ACC * math.sin(THETA) / 3
    np.testing.assert_allclose(np.abs(frame[column].to_numpy()[after]), friction, rtol=1e-9)


@pytest.mark.parametrize("vx", [0.14, -0.3], ids=["slides-right", "slides-left"])
def test_a_box_sliding_on_one_corner_presses_as_its_closed_form_says(vx):
    """A tilted box resting on one rounded corner (its centre ``r_c`` from the box's, the
    contact point ``r_P = r_c - (0, rc)``) that slides, ``F = c N`` with
    ``c = -mu sign(v_P)``: the corner's centre keeps its height (``a_y + alpha r_cx -
    w^2 r_cy = 0``), so ``N = m (g + w^2 r_cy) / (1 + m r_cx (r_cx - c r_Py) / J)`` and
    ``a_x = c N / m``. Here ``mu dN/dF`` is 0.23: a fixed-point iteration of the forces
    alone settles to only 2e-8 in 12 steps; with its Newton step, to rounding."""
    mu, phi, w = 0.5, 0.1365, -0.5
    model = _block(mu, 0.0)
    (c,) = rigid_contacts(model)
    pen = np.asarray(c.penetration(jnp.asarray([0.0, 1.0, phi])))
    k = int(np.argmax(pen))
    q = np.array([0.0, 1.0 + pen[k], phi])
    problem = _resting(model, (k,))
    qdd, lam = _accelerations(problem, q, [vx, 0.0, w])
    s, co = math.sin(phi), math.cos(phi)
    a, b = W_BOX / 2 - R_CORNER, H_BOX / 2 - R_CORNER
    centres = [np.array([co * x - s * y, s * x + co * y]) for x in (-a, a) for y in (-b, b)]
    r_c = min(centres, key=lambda r: r[1])  # the lowest corner's centre
    r_P = r_c - np.array([0.0, R_CORNER])
    slip = vx - w * r_P[1]
    cf = -mu * math.copysign(1.0, slip)
    N = M * (G_ACC + w**2 * r_c[1]) / (1 + M * r_c[0] * (r_c[0] - cf * r_P[1]) / J_BOX)
    np.testing.assert_allclose(lam[-1], N, rtol=1e-12)
    np.testing.assert_allclose(qdd[0], cf * N / M, rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_sliding_into_a_stop_rebounds_slides_back_and_sticks():
    """A block resting on rough ground (``mu``) launched at ``v0`` towards a wall ``d`` ahead
    (a rigid stop, ``e``): it reaches the wall at ``v1 = sqrt(v0^2 - 2 mu g d)``, at
    ``t1 = (v0 - v1) / (mu g)``; both its front corners strike at once and it rebounds
    level at ``-e v1`` (the floor's resting corners take no impulse), slides back to a stop
    ``(e v1)^2 / (2 mu g)`` from the wall at ``t1 + e v1 / (mu g)`` and stays there; the
    impact took ``(1 - e^2) m v1^2 / 2`` and the friction the rest of the kinetic energy."""
    mu, e, v0, d = 0.4, 0.5, 1.5, 0.1
    block = md.Body("block", M, J_BOX, q0=(0.0, H_BOX / 2, 0.0))
    floor = md.BoxLineContact(
        "floor", "block", W_BOX, H_BOX, R_CORNER, ("ground", (0.0, 0.0)),
        contact_model="rigid", restitution=0.5, mu=mu,
    )  # fmt: skip
    wall = md.BoxLineContact(
        "wall", "block", W_BOX, H_BOX, R_CORNER, ("ground", (W_BOX / 2 + d, 0.0)),
        axis=(0.0, 1.0), contact_model="rigid", restitution=e,
    )  # fmt: skip
    model = md.Model([block], forces=[floor, wall], gravity=(0, -G_ACC))
    ts = np.linspace(0.0, 0.4, 17)
    r = md.forward(model, ts, qd0=np.array([v0, 0.0, 0.0]), rtol=1e-10, atol=1e-12)
    a = mu * G_ACC
    v1 = math.sqrt(v0**2 - 2 * a * d)
    t1 = (v0 - v1) / a
    t2 = t1 + e * v1 / a
    imp = r.stats["impacts"]
    assert imp["contact"] == ["wall", "wall"]
    np.testing.assert_allclose(imp["t"], [t1, t1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(imp["normal_velocity_before"], [-v1, -v1], rtol=1e-9)
    np.testing.assert_allclose(imp["normal_velocity_after"], [e * v1, e * v1], rtol=1e-9)
    back = np.clip(ts - t1, 0.0, t2 - t1)
    x = np.where(ts < t1, v0 * ts - a * ts**2 / 2, d - e * v1 * back + a * back**2 / 2)
    np.testing.assert_allclose(r["block.x"], x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["block.vx"][ts > t2], 0.0, atol=1e-10)
    np.testing.assert_allclose(r["block.y"], H_BOX / 2, rtol=1e-12)
    assert np.max(np.abs(r["block.phi"])) < 1e-12
    assert r.stats["rests"]["contact"] == ["floor", "floor"]  # it never leaves the floor
    lost = (1 - e**2) * M * v1**2 / 2
    np.testing.assert_allclose(r["work.impacts"][-1], -lost, rtol=1e-9)
    np.testing.assert_allclose(r["work.nonconservative"][-1], lost - M * v0**2 / 2, rtol=1e-9)
    assert r.stats["energy_balance_error"] < 1e-9
