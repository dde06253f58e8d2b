"""Coulomb friction in rigid impacts (``mu`` on a rigid contact) against closed forms.

- A disc (radius ``r``, mass ``m``, inertia ``J`` about its centre) with backspin striking
  the ground: the normal impulse ``P = m (1 + e) |v_y-|`` (Newton's law); sticking (large
  ``mu``), the angular momentum about the contact point ``L = J w - m r v_x`` is kept (the
  impulses pass through it) and the contact point leaves without sliding,
  ``v_x+ = -L r / (m r**2 + J)``, ``w+ = -v_x+ / r``; sliding (small ``mu``), the friction
  impulse is ``mu P`` against the contact point's slip ``s = sign(v_x + w r)``:
  ``v_x+ = v_x- - mu (1 + e) |v_y-| s`` and ``J (w+ - w-) = -r mu P s``. Fast: the impulse
  solve with the disc's rows written by hand (and the contact's own rows against them);
  slow: forward runs, the impact's velocities before and after to 1e-9.
- A frictional impact that would give the bodies energy (Newton's law with sticking in a
  system whose normal and tangential motions are coupled, Kane's and Stronge's paradox):
  the impulses' work equals the kinetic energy's jump computed by hand, and is positive
  (fast); a run with such an impact (a tilted rod dropped on a rough floor, ``e = 1``) ends
  as a named numerical failure (slow).
- A rod pendulum striking a tilted wall (slow): one degree of freedom, so no sticking
  solution; it slides against the tangential velocity: ``w+ = -e w-`` whatever the
  friction, the wall's impulse from the angular momentum about the pin,
  ``J_O (w+ - w-) = (r x n) P + (r x t) T`` with ``T = -mu P sign(v_t-)``, the impacts'
  loss ``J_O (w+**2 - w-**2) / 2``, and the energy balance closed with it.
- The same in a mixed run (slow): a pendulum on a slider whose x is prescribed strikes a
  rough wall; its ``w+``, the wall's impulses and the unknown force's impulse from the x
  momentum, the balance closed.
- A box landing flat on a rough floor, both bottom corners struck at once (contact points
  ``(-+a, -b)`` from its centre): Newton's law at each corner keeps it from turning
  (``w+ = 0``, ``v_y+ = e v``), so the friction's moment is balanced by the corners' normal
  impulses, ``a (P_2 - P_1) = b (T_1 + T_2)``; sliding, ``T_k = mu P_k`` and
  ``u+ = u - mu (1 + e) v``, the leading corner taking ``(1 + b mu / a) / 2`` of
  ``m (1 + e) v``; below ``u = mu (1 + e) v`` it stops, ``u+ = 0`` with ``T_1 + T_2 = m u``
  within ``mu P_k`` at each corner (fast, the rows by hand). In a run (slow) the box thrown
  flat bounces level, losing ``mu (1 + e) v_n`` of its speed at each bounce, comes to rest on
  both corners at ``t_inf`` with ``u_inf = u0 - mu (1 + e) v1 / (1 - e)`` and skids to a
  stop ``u_inf^2 / (2 mu g)`` further on, where it stays.
- A model file with ``mu`` on a rigid contact (slow): ``mixdyn run`` writes the friction
  impulse column ``floor.friction_impulse`` (the disc's sliding impulse).
"""

from __future__ import annotations

import json
import math

import jax
import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.analysis._impact_friction import coulomb_impulse, coulomb_impulses
from mixdyn.cli import app

R_DISC, M_DISC, E_DISC, G_ACC, H_DROP = 0.05, 2.0, 0.5, 9.81, 0.2
J_DISC = 0.5 * M_DISC * R_DISC**2
QD0 = (1.0, -0.5, 30.0)  # v_x, v_y [m/s] and w [rad/s] at the release
NONE = np.zeros((0, 3))


def _disc_closed_form(mu, vx, vy, w):
    """The disc's ``(v_x+, v_y+, w+)``, ``P``, the friction impulse ``T`` on the disc along
    ``z x n = (-1, 0)`` and whether it sticks, after striking the ground at ``(vx, vy, w)``
    (``vy < 0``)."""
    m, r, J, e = M_DISC, R_DISC, J_DISC, E_DISC
    P = m * (1 + e) * -vy
    L = J * w - m * r * vx  # about the contact point
    vx_stick = -L * r / (m * r**2 + J)
    if abs(m * (vx_stick - vx)) <= mu * P:
        return np.array([vx_stick, -e * vy, -vx_stick / r]), P, -m * (vx_stick - vx), True
    s = math.copysign(1.0, vx + w * r)
    Fx = -mu * P * s  # the friction impulse along x
    return np.array([vx + Fx / m, -e * vy, w + r * Fx / J]), P, -Fx, False


def _disc(mu, qd0=QD0):
    disc = md.Body("disc", M_DISC, J_DISC, q0=(0.0, H_DROP + R_DISC, 0.0))
    floor = md.CircleLineContact(
        "floor", "disc", R_DISC, ("ground", (0.0, 0.0)), contact_model="rigid",
        restitution=E_DISC, mu=mu,
    )  # fmt: skip
    return md.Model([disc], forces=[floor], gravity=(0, -G_ACC))


@pytest.mark.parametrize("mu", [1.0, 0.1])
def test_a_disc_with_backspin_sticks_or_slides_by_the_closed_forms(mu):
    """The impulse solve with the rows by hand (``G = [0, 1, 0]``, the sliding speed along
    ``(-1, 0)``: ``G_t = [-1, 0, -r]``), and the contact's own rows equal to them."""
    vx, vy, w = 1.0, -2.0, 30.0
    G, Gt = np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, -R_DISC])
    Minv = 1.0 / np.array([M_DISC, M_DISC, J_DISC])
    qd = np.array([vx, vy, w])
    found = coulomb_impulse(Minv, NONE, np.zeros(0), G, Gt, qd, E_DISC, mu)
    after, P, T, sticks = _disc_closed_form(mu, vx, vy, w)
    assert found.sticks == sticks == (mu == 1.0)
    np.testing.assert_allclose(found.qd, after, rtol=0, atol=1e-12 * abs(w))
    np.testing.assert_allclose([found.P, found.T], [P, T], rtol=1e-12)
    if sticks:
        assert abs(Gt @ found.qd) < 1e-12 * abs(w) * R_DISC  # the contact point stops
    else:
        assert abs(found.T) == pytest.approx(mu * found.P, rel=1e-14)
    lost = 0.5 * (found.qd**2 - qd**2) @ (1.0 / Minv)
    assert found.work == pytest.approx(lost, rel=1e-12) and lost < 0.0
    floor = _disc(mu).forces[0]  # the contact's rows at a pose touching the ground
    q = np.array([0.3, R_DISC, 1.2])
    np.testing.assert_allclose(jax.jacfwd(lambda v: floor.sliding(q, v))(qd), [Gt], atol=1e-15)
    np.testing.assert_allclose(jax.jacfwd(lambda x: -floor.penetration(x))(q), G, atol=1e-15)


def test_a_sticking_impact_that_would_give_energy_shows_its_work():
    """Two coordinates, ``M = I``, the tangential row coupled to the normal one
    (``G = [1, 0]``, ``G_t = [-3, 1]``): ``v_n- = -1``, ``v_t- = 2``, ``e = 1`` sticks with
    ``qd+ = [1, 3]`` (``v_n+ = 1``, ``v_t+ = 0``): the kinetic energy goes from 1 to 5."""
    G, Gt = np.array([1.0, 0.0]), np.array([-3.0, 1.0])
    qd = np.array([-1.0, -1.0])
    found = coulomb_impulse(np.ones(2), np.zeros((0, 2)), np.zeros(0), G, Gt, qd, 1.0, 0.5)
    assert found.sticks
    np.testing.assert_allclose(found.qd, [1.0, 3.0], atol=1e-12)
    assert found.work == pytest.approx(0.5 * (found.qd @ found.qd - qd @ qd), rel=1e-12)
    assert found.work == pytest.approx(4.0, rel=1e-12)


def test_a_rigid_contact_takes_mu_but_no_friction_regularization():
    with pytest.raises(md.ModelError, match="remove v_stick") as err:
        md.CircleLineContact("floor", "ball", 0.05, ("ground", (0.0, 0.0)), contact_model="rigid",
                             restitution=0.8, mu=0.3, v_stick=1e-3)  # fmt: skip
    assert err.value.field == "v_stick"


@pytest.mark.slow  # long: run by CI's slow set
def test_disc_runs_stick_and_slide_by_the_closed_forms():
    vx, vy0, w = QD0
    vy = -math.sqrt(vy0**2 + 2 * G_ACC * H_DROP)
    t_hit = (vy0 - vy) / G_ACC
    for mu in (1.0, 0.1):
        r = md.forward(_disc(mu), np.linspace(0.0, 0.25, 26), qd0=np.array(QD0), rtol=1e-11,
                       atol=1e-13)  # fmt: skip
        imp = r.stats["impacts"]
        assert len(imp["t"]) == 1
        np.testing.assert_allclose(imp["t"][0], t_hit, rtol=0, atol=1e-9)
        np.testing.assert_allclose(imp["qd_before"][0], [vx, vy, w], rtol=0, atol=1e-9)
        after, P, T, sticks = _disc_closed_form(mu, vx, vy, w)
        assert bool(imp["sticks"][0]) == sticks == (mu == 1.0)
        np.testing.assert_allclose(imp["qd_after"][0], after, rtol=0, atol=1e-9)
        np.testing.assert_allclose([imp["impulse"][0], imp["friction_impulse"][0]], [P, T],
                                   rtol=0, atol=1e-9)  # fmt: skip
        vt_after = -(after[0] + after[2] * R_DISC)
        np.testing.assert_allclose(imp["tangential_velocity_after"][0], vt_after, atol=1e-9)
        lost = 0.5 * (M_DISC * (after[:2] @ after[:2] - vx**2 - vy**2)
                      + J_DISC * (after[2] ** 2 - w**2))  # fmt: skip
        np.testing.assert_allclose(r["work.impacts"][-1], lost, rtol=0, atol=1e-9)
        np.testing.assert_allclose(r["floor.friction_impulse"][[0, -1]], [0.0, T], atol=1e-9)
        assert r.stats["energy_balance_error"] < 1e-8


@pytest.mark.slow  # long: run by CI's slow set
def test_a_tilted_rod_sticking_on_a_rough_floor_with_e_1_is_a_named_failure():
    """The rod's lower end strikes the floor at 30 degrees, sliding sideways at 0.5 m/s:
    its normal and tangential motions are coupled, and Newton's ``e = 1`` with sticking
    would give it energy (see the fast test above)."""
    m, L, th = 1.0, 0.4, math.radians(30)
    rod = md.Body("rod", m, m * L**2 / 12, q0=(0.0, 0.1 + L / 2 * math.sin(th), th),
                  points={"end": (-L / 2, 0.0)})  # fmt: skip
    floor = md.CircleLineContact("floor", "rod.end", 0.005, ("ground", (0.0, -0.005)),
                                 contact_model="rigid", restitution=1.0, mu=5.0)  # fmt: skip
    model = md.Model([rod], forces=[floor], gravity=(0, -9.81))
    with pytest.raises(md.NumericalError, match="would give the bodies energy") as err:
        md.forward(model, np.linspace(0.0, 0.3, 7), qd0=np.array([0.5, 0.0, 0.0]))
    assert err.value.elements == ("floor",)
    assert err.value.time == pytest.approx(math.sqrt(2 * 0.1 / 9.81), abs=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_pendulum_striking_a_tilted_wall_slides_and_closes_its_energy_balance():
    L, m, e, g, R, mu = 0.3, 0.5, 0.7, 9.81, 0.01, 0.3
    J_O = m * L**2 / 3
    th0, th_hit, beta = math.radians(40), math.radians(-10), math.radians(30)
    rod = md.Body(
        "rod", m, m * L**2 / 12, q0=(L / 2 * math.sin(th0), -L / 2 * math.cos(th0),
                                     th0 - math.pi / 2),
        points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)},
    )  # fmt: skip
    n = np.array([math.cos(th_hit + beta), math.sin(th_hit + beta)])  # out of the wall
    tip = L * np.array([math.sin(th_hit), -math.cos(th_hit)])
    wall = md.CircleLineContact(
        "wall", "rod.tip", R, ("ground", tuple((tip - R * n).tolist())),
        axis=(float(n[1]), float(-n[0])),
        contact_model="rigid", restitution=e, mu=mu,
    )  # fmt: skip
    model = md.Model([rod], [md.Revolute("O", "ground", "rod.O")], forces=[wall],
                     gravity=(0, -g))  # fmt: skip
    r = md.forward(model, np.linspace(0.0, 0.4, 41), rtol=1e-11, atol=1e-13)
    imp = r.stats["impacts"]
    w_before = -math.sqrt(m * g * L * (math.cos(th_hit) - math.cos(th0)) / J_O)
    w_after = -e * w_before
    contact = tip - R * n  # the contact point, from the pin
    t = np.array([-n[1], n[0]])
    vt = w_before * (np.array([-contact[1], contact[0]]) @ t)
    tau = -mu * math.copysign(1.0, vt)  # T / P

    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]

    P = J_O * (w_after - w_before) / (cross(contact, n) + tau * cross(contact, t))
    assert not imp["sticks"][0]
    np.testing.assert_allclose(imp["qd_before"][0][2], w_before, rtol=1e-9)
    np.testing.assert_allclose(imp["qd_after"][0][2], w_after, rtol=1e-9)
    np.testing.assert_allclose([imp["impulse"][0], imp["friction_impulse"][0]], [P, tau * P],
                               rtol=1e-9)  # fmt: skip
    k = int(np.searchsorted(r.t, imp["t"][0]))
    lost = 0.5 * J_O * (w_after**2 - w_before**2)
    np.testing.assert_allclose(r["work.impacts"][k], lost, rtol=1e-9)
    closure = r["energy.total"] - r["energy.total"][0] - r["work.impacts"]
    assert np.max(np.abs(closure)) < 1e-9 * abs(lost)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_pendulum_on_a_driven_slider_strikes_a_rough_wall_in_a_mixed_run():
    """The slider's x prescribed (``V``, its force ``F`` unknown), the rod on its pin
    striking a vertical wall (``n = (-1, 0)``, ``t = (0, -1)``) with friction: the rod's
    one degree of freedom slides; Newton's law on the contact point gives ``w+``, the
    angular momentum about the pin (moving uniformly) the wall's impulse
    ``J_pin (w+ - w-) = r x (P n + T t)``, ``T = -mu P sign(v_t-)``, and the x momentum
    ``F``'s impulse ``m (w+ - w-) (-r_cm,y) = P n_x + F_imp``."""
    L, m, ms, R, V, e, mu = 0.4, 0.5, 2.0, 0.01, 0.5, 0.6, 0.3
    J_pin = m * L**2 / 3
    th0 = math.radians(-30)
    slider = md.Body("slider", ms, 0.01, q0=(0.0, 0.0, 0.0))
    rod = md.Body("rod", m, m * L**2 / 12,
                  q0=(L / 2 * math.sin(th0), -L / 2 * math.cos(th0), th0 - math.pi / 2),
                  points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)})  # fmt: skip
    wall = md.CircleLineContact("wall", "rod.tip", R, ("ground", (0.13, 0.0)), axis=(0.0, 1.0),
                                contact_model="rigid", restitution=e, mu=mu)  # fmt: skip
    F = md.PointForce("F", "slider", along=(1.0, 0.0), law=md.Polynomial([0.0]))
    joints = [md.Translational("rail", "ground", "slider", axis=(1, 0)),
              md.Revolute("pin", "slider", "rod.O")]  # fmt: skip
    model = md.Model([slider, rod], joints, forces=[wall, F], gravity=(0, -9.81))
    drive = md.CoordinateDriver("drive", "slider", "x", law=md.Polynomial([0.0, V]))
    r = md.mixed(model, np.linspace(0.0, 0.3, 31), prescribed=[drive], unknown=["F"],
                 qd0={"rod.phi": 1.5}, rtol=1e-11, atol=1e-13)  # fmt: skip
    imp = r.stats["impacts"]
    q, w_before = imp["q"][0], imp["qd_before"][0][5]
    n, t = np.array([-1.0, 0.0]), np.array([0.0, -1.0])
    arm = L * np.array([math.cos(q[5]), math.sin(q[5])]) - R * n  # pin to the contact point
    k_arm = np.array([-arm[1], arm[0]])
    vn = n @ (np.array([V, 0.0]) + w_before * k_arm)
    w_after = (-e * vn - n[0] * V) / (n @ k_arm)
    vt = t @ (np.array([V, 0.0]) + w_before * k_arm)
    tau = -mu * math.copysign(1.0, vt)
    P = J_pin * (w_after - w_before) / (arm[0] * n[1] - arm[1] * n[0]
                                        + tau * (arm[0] * t[1] - arm[1] * t[0]))  # fmt: skip
    F_imp = m * (w_after - w_before) * (-L / 2 * math.sin(q[5])) - P * n[0]
    assert not imp["sticks"][0] and P > 0
    np.testing.assert_allclose(imp["qd_after"][0][5], w_after, rtol=1e-9)
    np.testing.assert_allclose([imp["impulse"][0], imp["friction_impulse"][0]], [P, tau * P],
                               rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(imp["unknown"][0]["F"], F_imp, rtol=1e-9)
    np.testing.assert_allclose(r["wall.friction_impulse"][-1], tau * P, rtol=1e-9)
    np.testing.assert_allclose(r["slider.vx"], V, rtol=1e-12)
    assert r.stats["energy_balance_error"] < 1e-9


FILE = """\
mixdyn: 1
name: spinning-disc
units: {{length: m, mass: kg, time: s}}
gravity: [0, -{g} m/s^2]
ground:
  points: {{O: [0, 0]}}
bodies:
  - {{name: disc, mass: {m} kg, inertia: {J}, q0: [0, {y0}, 0]}}
forces:
  - {{type: circle_line_contact, name: floor, center: disc, radius: {r} m,
     line_point: ground.O, contact_model: rigid, restitution: {e}, mu: {mu}}}
runs:
  - name: drop
    kind: forward
    velocities: {{disc.x: {vx}, disc.y: {vy}, disc.phi: {w}}}
    time: {{span: [0, 0.25], n: 26}}
    rtol: 1.0e-11
    atol: 1.0e-13
"""


@pytest.mark.slow  # long: run by CI's slow set
def test_a_model_file_with_friction_on_a_rigid_contact_writes_the_friction_impulse(tmp_path):
    mu = 0.1
    vx, vy0, w = QD0
    text = FILE.format(g=G_ACC, m=M_DISC, J=J_DISC, y0=H_DROP + R_DISC, r=R_DISC, e=E_DISC,
                       mu=mu, vx=vx, vy=vy0, w=w)  # fmt: skip
    path = tmp_path / "disc.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out"),
                                   "--no-figures"])  # fmt: skip
    assert res.exit_code == 0, res.output
    table = md.read_table(tmp_path / "out" / "drop" / "results.csv")
    vy = -math.sqrt(vy0**2 + 2 * G_ACC * H_DROP)
    t_hit = (vy0 - vy) / G_ACC
    _, P, T, sticks = _disc_closed_form(mu, vx, vy, w)
    assert not sticks
    after = table["t"].to_numpy() > t_hit
    np.testing.assert_allclose(table["floor.friction_impulse"].to_numpy()[after], T, rtol=1e-9)
    np.testing.assert_allclose(table["floor.friction_impulse"].to_numpy()[~after], 0.0, atol=0)
    np.testing.assert_allclose(table["floor.impulse"].to_numpy()[after], P, rtol=1e-9)
    meta = json.loads((tmp_path / "out" / "drop" / "meta.json").read_text())
    impacts = meta["stats"]["impacts"]
    np.testing.assert_allclose(impacts["friction_impulse"], [T], rtol=1e-9)
    assert impacts["sticks"] == [False]


# ------------------------------------------------------------- a box landing flat, rough
BOX_M, BOX_W, BOX_H, BOX_RC, BOX_E, BOX_MU = 1.0, 0.2, 0.1, 0.005, 0.4, 0.5
BOX_J = BOX_M * (BOX_W**2 + BOX_H**2) / 12
BOX_A, BOX_B = BOX_W / 2 - BOX_RC, BOX_H / 2  # the corners' contact points (-+a, -b)


@pytest.mark.parametrize("u", [2.0, 0.3, 0.9], ids=["slides", "sticks", "trailing-slides"])
def test_a_rough_box_landing_flat_skids_or_stops_level_by_the_closed_forms(u):
    m, a, b, e, mu, v = BOX_M, BOX_A, BOX_B, BOX_E, BOX_MU, 1.4
    Minv = 1.0 / np.array([m, m, BOX_J])
    G = np.array([[0.0, 1.0, -a], [0.0, 1.0, a]])  # the gaps' rows at phi = 0
    Gt = np.array([[-1.0, 0.0, -b], [-1.0, 0.0, -b]])  # the slips along z x n = (-1, 0)
    qd = np.array([u, -v, 0.0])
    found = coulomb_impulses(Minv, NONE, np.zeros(0), G, Gt, qd, np.full(2, e), np.full(2, mu))
    assert found is not None
    P, T = found.P, found.T
    np.testing.assert_allclose(found.qd[1:], [e * v, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(P.sum(), m * (1 + e) * v, rtol=1e-12)
    np.testing.assert_allclose(a * (P[1] - P[0]), b * T.sum(), rtol=1e-12)  # no turning
    np.testing.assert_allclose(m * (found.qd[0] - u), -T.sum(), rtol=1e-12, atol=1e-12)
    if u > mu * (1 + e) * v:
        np.testing.assert_allclose(found.qd[0], u - mu * (1 + e) * v, rtol=1e-12)
        np.testing.assert_allclose(T, mu * P, rtol=1e-12)
        np.testing.assert_allclose(P[1] / P.sum(), (1 + b * mu / a) / 2, rtol=1e-12)
        assert not found.sticks.any()
    else:
        np.testing.assert_allclose(found.qd[0], 0.0, atol=1e-12)
        assert np.all(np.abs(T) <= mu * P * (1 + 1e-12)) and found.sticks.any()
    assert found.work < 0.0  # the impulses take energy: 1/2 m (u+^2 - u^2) + 1/2 m (e^2 - 1) v^2
    np.testing.assert_allclose(
        found.work, 0.5 * m * (found.qd[0] ** 2 - u**2) + 0.5 * m * (e**2 - 1) * v**2, rtol=1e-12
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_a_rough_box_thrown_flat_bounces_level_and_skids_to_the_closed_form_stop():
    m, e, mu, h0, u0 = BOX_M, BOX_E, BOX_MU, 0.1, 2.0
    box = md.Body("box", m, BOX_J, q0=(0.0, BOX_H / 2 + h0, 0.0))
    floor = md.BoxLineContact("floor", "box", BOX_W, BOX_H, BOX_RC, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=e, mu=mu)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G_ACC))
    r = md.forward(model, np.linspace(0.0, 1.0, 11), qd0=np.array([u0, 0.0, 0.0]), rtol=1e-10,
                   atol=1e-12)  # fmt: skip
    imp = r.stats["impacts"]
    t1, v1 = math.sqrt(2 * h0 / G_ACC), math.sqrt(2 * G_ACC * h0)
    # the first three bounces: both corners at once, sliding, level
    n = np.arange(3)
    t_n = t1 + 2 * v1 / G_ACC * (e - e ** (n + 1)) / (1 - e)
    u_n = u0 - mu * (1 + e) * v1 * (1 - e**n) / (1 - e)  # before bounce n
    np.testing.assert_allclose(imp["t"][:6], np.repeat(t_n, 2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.asarray(imp["qd_after"])[:6:2, 0],
                               u_n - mu * (1 + e) * v1 * e**n, rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(imp["friction_impulse"][:6], mu * np.asarray(imp["impulse"][:6]),
                               rtol=1e-9)  # fmt: skip
    assert np.max(np.abs(r["box.phi"])) < 1e-9
    # the rest: skidding on both corners from t_inf at u_inf, stopping u_inf^2 / (2 mu g) on
    k = np.arange(1, 400)
    u_inf = u0 - mu * (1 + e) * v1 / (1 - e)
    u_k = u0 - mu * (1 + e) * v1 * (1 - e**k) / (1 - e)  # in the flight after bounce k
    x_inf = u0 * t1 + np.sum(u_k * 2 * e**k * v1 / G_ACC)
    t_inf = t1 + 2 * e * v1 / (G_ACC * (1 - e))
    t_stop = t_inf + u_inf / (mu * G_ACC)
    x_stop = x_inf + u_inf**2 / (2 * mu * G_ACC)
    assert t_stop < 0.5
    stopped = r.t > t_stop + 1e-3
    np.testing.assert_allclose(r["box.x"][stopped], x_stop, rtol=0, atol=1e-6)
    np.testing.assert_allclose(r["box.y"][stopped], BOX_H / 2, rtol=1e-9)
    np.testing.assert_allclose(r["box.vx"][stopped], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["floor.normal"][stopped], m * G_ACC, rtol=1e-9)
    E = r["energy.kinetic"] + r["energy.potential"]  # the impacts' and the skid's losses
    np.testing.assert_allclose(E - E[0], r["work.impacts"] + r["work.nonconservative"],
                               atol=1e-9 * m * G_ACC * h0)  # fmt: skip


@pytest.mark.slow  # long: run by CI's slow set
def test_a_rough_box_dropped_tilted_and_thrown_settles_flat_and_stays():
    """A box dropped tilted (0.1 rad) and thrown sideways at 1 m/s onto a rough floor
    (``mu = 0.5``, ``e = 0.4``): it strikes on one corner, bounces on it until it rests on
    it, slides on that corner and rocks flat onto both, where it stops and stays
    (``y = h / 2``, ``phi = 0``, the corners carrying ``m g``); the energy it lost is the
    impacts' and the friction's work. On the way: the forces of a corner sliding with
    friction, where ``mu dN/dF`` is 0.23 (:mod:`mixdyn.equations._reaction_dependent`), and
    a corner that stops sliding but that its friction cannot hold (it slides on the other
    way, not watched for the stop it has just made)."""
    m, e, mu = BOX_M, BOX_E, BOX_MU
    box = md.Body("box", m, BOX_J, q0=(0.0, 0.15, 0.1))
    floor = md.BoxLineContact("floor", "box", BOX_W, BOX_H, BOX_RC, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=e, mu=mu)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G_ACC))
    r = md.forward(model, np.linspace(0.0, 0.4, 5), qd0=np.array([1.0, 0.0, 0.0]), rtol=1e-10,
                   atol=1e-12)  # fmt: skip
    rests = r.stats["rests"]
    assert sorted(rests["end"])[-2:] == [0.4, 0.4]  # two corners rest to the end
    after = r.t > max(rests["start"])
    assert after.sum() >= 2
    np.testing.assert_allclose(r["box.y"][after], BOX_H / 2, rtol=1e-9)
    np.testing.assert_allclose(r["box.phi"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["box.vx"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(np.diff(r["box.x"][after]), 0.0, atol=1e-9)
    np.testing.assert_allclose(r["floor.normal"][after], m * G_ACC, rtol=1e-9)
    assert np.any(r.stats["impacts"]["friction_impulse"])
    E = r["energy.kinetic"] + r["energy.potential"]
    np.testing.assert_allclose(E - E[0], r["work.impacts"] + r["work.nonconservative"],
                               atol=1e-9 * m * G_ACC * 0.15)  # fmt: skip
