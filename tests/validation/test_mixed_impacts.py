"""Rigid impacts in mixed runs: a prescribed motion's velocity cannot jump, its unknown
force takes an impulse.

The case: a slider on a rail along x, its x prescribed at a constant velocity ``v`` by an
unknown force ``F`` along x on it, carries a pendulum (a uniform rod pinned at one end to the
slider) whose tip (a circle of radius ``R``) strikes a vertical wall (rigid, restitution
``e``, its outward normal ``n = (-1, 0)``). With the slider's velocity unchanged by the
impact, the closed forms (``r``: pin to tip, ``c``: pin to centre of mass):

- the tip's normal velocity ``v_n = n . (v e_x + omega k x r)`` reverses to ``-e v_n-``:
  ``omega+ = (-e v_n- - n_x v) / (n . (k x r))``;
- the wall's impulse ``P`` from the rod's angular momentum about the pin (which keeps its
  velocity: the pin's impulse has no moment there), ``J_O (omega+ - omega-) = (r x n) P``;
- the impulse of ``F`` (along the unit direction ``d`` on the slider) from the system's x
  momentum (the rail acts along y and on the angle only),
  ``F_imp d_x = m (omega+ - omega-) (-c_y) - P n_x``;
- the energy: the wall's impulse works ``P (v_n- + v_n+) / 2`` (the impacts' loss) and
  ``F``'s ``F_imp v``.

Fast: the impulse solve at a hand-written state (the joints' Jacobian by hand). Slow: the
mixed run (both solvers), a ball rolling under a prescribed x coming to rest on a rigid
floor, a model file's mixed run writing the impulse columns, and a prescribed motion driven
into a rigid contact (a named failure at the impact).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.analysis._impulses import impulse
from mixdyn.cli import app

L, M_ROD, M_SLIDER, R, V = 0.4, 0.5, 2.0, 0.01, 0.5  # [m, kg, kg, m, m/s]
J_ROD = M_ROD * L**2 / 12  # about the rod's centre [kg m^2]
J_PIN = J_ROD + M_ROD * L**2 / 4
N_WALL = np.array([-1.0, 0.0])  # the wall's outward normal


def _rot(phi):
    return np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])


def _closed_form(phi, omega, e, along_x=1.0):
    """``(omega+, P, F_imp)`` of the rod at angle ``phi`` (its body axis, pin to tip)
    turning at ``omega`` [rad/s] on the slider moving at ``V``; ``along_x``: the x part of
    ``F``'s unit direction (its y part goes into the rail)."""
    r = _rot(phi) @ np.array([L, 0.0])  # pin to tip
    c = r / 2  # pin to the centre of mass
    k_x = np.array([-r[1], r[0]])  # k x r
    vn = N_WALL @ (np.array([V, 0.0]) + omega * k_x)
    omega_after = (-e * vn - N_WALL[0] * V) / (N_WALL @ k_x)
    P = J_PIN * (omega_after - omega) / (r[0] * N_WALL[1] - r[1] * N_WALL[0])
    F_imp = (M_ROD * (omega_after - omega) * (-c[1]) - P * N_WALL[0]) / along_x
    return omega_after, P, F_imp


def _hand_system(phi):
    """The joints' Jacobian (4, 6) by hand (the rail: slider y and angle; the pin: the
    slider's centre at the rod's end), the prescribed motion's row (6,) and the wall gap's
    gradient (6,), at the rod angle ``phi``; q = [slider x, y, phi, rod x, y, phi]."""
    dA = np.array([[-math.sin(phi), -math.cos(phi)], [math.cos(phi), -math.sin(phi)]])
    s_pin, s_tip = np.array([-L / 2, 0.0]), np.array([L / 2, 0.0])
    Phi_q = np.zeros((4, 6))
    Phi_q[0, 1] = Phi_q[1, 2] = 1.0
    Phi_q[2:4, 0:2] = np.eye(2)
    Phi_q[2:4, 3:5] = -np.eye(2)
    Phi_q[2:4, 5] = -dA @ s_pin
    Psi_q = np.array([1.0, 0, 0, 0, 0, 0])
    G = np.concatenate([[0.0, 0.0, 0.0], N_WALL, [N_WALL @ (dA @ s_tip)]])
    return Phi_q, Psi_q, G


@pytest.mark.parametrize("d", [(1.0, 0.0), (0.6, 0.8)])
def test_the_impulse_keeps_the_prescribed_velocity_and_matches_the_closed_forms(d):
    """Along x (``B = Psi_q^T``) and tilted (``B != Psi_q^T``: its impulse along ``B``)."""
    phi, omega, e = -1.2, 2.5, 0.6  # the rod below the pin, the tip approaching the wall
    Phi_q, Psi_q, G = _hand_system(phi)
    B = np.array([d[0], d[1], 0, 0, 0, 0])
    c = _rot(phi) @ np.array([L / 2, 0.0])
    qd = np.array([V, 0.0, 0.0, V - omega * c[1], omega * c[0], omega])
    assert np.max(np.abs(Phi_q @ qd)) < 1e-14 and G @ qd < 0  # consistent, approaching
    Minv = 1.0 / np.array([M_SLIDER, M_SLIDER, 0.01, M_ROD, M_ROD, J_ROD])
    J = np.vstack([Phi_q, Psi_q])
    D = np.vstack([Phi_q, B])  # the prescribed motion's impulse acts along F
    after, lam, P = impulse(Minv, J, np.array([0, 0, 0, 0, -V]), G, qd, e, D)
    omega_after, P_hand, F_hand = _closed_form(phi, omega, e, d[0])
    assert abs(after[0] - V) < 1e-12  # the slider's velocity kept
    np.testing.assert_allclose(after[5], omega_after, rtol=1e-12)
    np.testing.assert_allclose(P, P_hand, rtol=1e-12)
    np.testing.assert_allclose(lam[-1], F_hand, rtol=1e-12)
    assert np.max(np.abs(Phi_q @ after)) < 1e-12  # the joints kept
    np.testing.assert_allclose((after - qd) / Minv, D.T @ lam + G * P, atol=1e-12)
    # the impulses' work: the wall's loses P (v_n- + v_n+) / 2, F's gives F_imp v
    dT = 0.5 * (after @ (after / Minv) - qd @ (qd / Minv))
    loss = P * (G @ qd + G @ after) / 2
    np.testing.assert_allclose(dT, loss + lam[-1] * d[0] * V, rtol=1e-12)


def _slider_pendulum(theta0, e, wall_x, d=(1.0, 0.0)):
    """The slider at x = 0 and the rod hanging from it at ``theta0`` from the vertical
    (the tip at ``L (sin theta0, -cos theta0)``), the wall's surface at ``wall_x``, ``F``
    along ``d`` on the slider."""
    slider = md.Body("slider", M_SLIDER, 0.01, q0=(0.0, 0.0, 0.0))
    rod = md.Body(
        "rod", M_ROD, J_ROD,
        q0=(L / 2 * math.sin(theta0), -L / 2 * math.cos(theta0), theta0 - math.pi / 2),
        points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)},
    )  # fmt: skip
    wall = md.CircleLineContact(
        "wall", "rod.tip", R, ("ground", (wall_x, 0.0)), axis=(0.0, 1.0),
        contact_model="rigid", restitution=e,
    )  # fmt: skip
    F = md.PointForce("F", "slider", along=d, law=md.Polynomial([0.0]))
    joints = [md.Translational("rail", "ground", "slider", axis=(1, 0)),
              md.Revolute("pin", "slider", "rod.O")]  # fmt: skip
    return md.Model([slider, rod], joints, forces=[wall, F], gravity=(0, -9.81))


@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.parametrize(("solver", "d"), [("augmented", (0.6, 0.8)), ("partition", (1.0, 0.0))])
def test_a_pendulum_on_a_driven_slider_strikes_a_wall(solver, d):
    """The augmented solver with ``F`` tilted (its impulse along ``B``, not ``Psi_q^T``);
    the partition solver with ``F`` along x (the coordinate it prescribes)."""
    e = 0.6
    model = _slider_pendulum(math.radians(-30), e, 0.13, d)
    drive = md.CoordinateDriver("drive", "slider", "x", law=md.Polynomial([0.0, V]))
    r = md.mixed(model, np.linspace(0.0, 0.3, 31), prescribed=[drive], unknown=["F"],
                 solver=solver, qd0={"rod.phi": 1.5}, rtol=1e-11, atol=1e-13)  # fmt: skip
    imp = r.stats["impacts"]
    assert imp["contact"] == ["wall"]
    q, before, after = imp["q"][0], imp["qd_before"][0], imp["qd_after"][0]
    omega_after, P, F_imp = _closed_form(q[5], before[5], e, d[0])
    assert abs(after[0] - V) < 1e-12 and abs(before[0] - V) < 1e-12
    np.testing.assert_allclose(after[5], omega_after, rtol=1e-9)
    np.testing.assert_allclose(imp["impulse"][0], P, rtol=1e-9)
    np.testing.assert_allclose(imp["unknown"][0]["F"], F_imp, rtol=1e-9)
    k = int(np.searchsorted(r.t, imp["t"][0]))  # the first output after the impact
    np.testing.assert_allclose(r["F.impulse"][[k - 1, k, -1]], [0.0, F_imp, F_imp], atol=1e-9)
    np.testing.assert_allclose(r["wall.impulse"][-1], P, rtol=1e-9)
    np.testing.assert_allclose(r["slider.vx"], V, rtol=1e-12)
    G_tip = np.array([-math.sin(q[5]), math.cos(q[5])]) * L  # d(tip - pin)/dphi
    vn_before = N_WALL @ (np.array([V, 0.0]) + before[5] * G_tip)
    vn_after = N_WALL @ (np.array([V, 0.0]) + after[5] * G_tip)
    np.testing.assert_allclose(imp["normal_velocity_after"][0], -e * vn_before, rtol=1e-9)
    np.testing.assert_allclose(r["work.impacts"][-1], P * (vn_before + vn_after) / 2, rtol=1e-9)
    # the wall's share of the kinetic energy's jump is work.impacts (above), F's (F_imp d_x v)
    # is in work.constraints: the balance T + V - E0 - W closes
    assert r.stats["energy_balance_error"] < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_a_ball_rolling_under_a_prescribed_x_comes_to_rest_on_a_rigid_floor():
    """A ball dropped from ``h0`` while its x is prescribed at 0.1 m/s (by ``push`` along
    x): it comes to rest at ``t_inf = t_1 + 2 e v0 / (g (1 - e))`` and stays pressing with
    ``m g``; ``push`` is zero throughout (nothing resists x), also at the impacts."""
    e, h0, g, m, rb = 0.5, 0.2, 9.81, 1.0, 0.05
    ball = md.Body("ball", m, 0.4 * m * rb**2, q0=(0.0, h0 + rb, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", rb, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=e
    )
    push = md.PointForce("push", "ball", along=(1, 0), law=md.Polynomial([0.0]))
    model = md.Model([ball], forces=[floor, push], gravity=(0, -g))
    x = md.CoordinateDriver("x", "ball", "x", law=md.Polynomial([0.0, 0.1]))
    r = md.mixed(model, np.linspace(0.0, 1.0, 21), prescribed=[x], unknown=["push"],
                 rtol=1e-11, atol=1e-13)  # fmt: skip
    v0 = math.sqrt(2 * g * h0)
    t_inf = v0 / g + 2 * e * v0 / (g * (1 - e))
    assert r.stats["rests"]["contact"] == ["floor"]
    assert abs(r.stats["rests"]["start"][0] - t_inf) < 1e-6
    after = r.t > t_inf
    np.testing.assert_allclose(r["floor.normal"][after], m * g, rtol=1e-9)
    np.testing.assert_allclose(r["ball.y"][after], rb, atol=1e-9)
    assert np.max(np.abs(r["push"])) < 1e-9 and abs(r["push.impulse"][-1]) < 1e-12
    np.testing.assert_allclose(r["ball.x"], 0.1 * r.t, atol=1e-12)


FILE = """\
mixdyn: 1
name: slider-pendulum-wall
units: {{length: m, mass: kg, time: s}}
gravity: [0, -9.81]
ground:
  points: {{W: [{wall}, 0]}}
bodies:
  - {{name: slider, mass: {ms}, inertia: 0.01, q0: [0, 0, 0]}}
  - {{name: rod, mass: {m}, inertia: {J}, q0: [0, {yc}, -90 deg],
     points: {{O: [{s0}, 0], tip: [{s1}, 0]}}}}
joints:
  - {{type: translational, name: rail, point_i: ground, point_j: slider, axis: [1, 0]}}
  - {{type: revolute, name: pin, point_i: slider, point_j: rod.O}}
forces:
  - {{type: circle_line_contact, name: wall, center: rod.tip, radius: {R}, line_point: ground.W,
     axis: [0, 1], contact_model: rigid, restitution: {e}}}
  - {{type: point_force, name: F, point: slider, along: [1, 0], law: "0"}}
runs:
  - name: strike
    kind: mixed
    prescribed: [{{coordinate: slider.x, law: "{v}*t"}}]
    unknown: [F]
    velocities: {{rod.phi: 0}}
    time: {{span: [0, 0.3], n: 31}}
    rtol: 1.0e-11
    atol: 1.0e-13
"""


@pytest.mark.slow  # long: run by CI's slow set
def test_a_model_files_mixed_run_writes_the_impulse_columns(tmp_path):
    """The rod hangs straight down from the slider (it stays so: the pin moves uniformly)
    until its tip strikes the wall at ``t = (wall - R) / v``; the closed forms at
    ``phi = -pi/2``, ``omega- = 0``: ``omega+ = -(1 + e) v / L``, ``P = (1 + e) m v / 3``
    and ``F_imp = -(1 + e) m v / 6``."""
    e, wall = 0.6, 0.1025
    text = FILE.format(wall=wall, ms=M_SLIDER, m=M_ROD, J=J_ROD, yc=-L / 2, s0=-L / 2,
                       s1=L / 2, R=R, e=e, v=V)  # fmt: skip
    path = tmp_path / "wall.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out"),
                                   "--no-figures"])  # fmt: skip
    assert res.exit_code == 0, res.output
    table = md.read_table(tmp_path / "out" / "strike" / "results.csv")
    omega_after, P, F_imp = _closed_form(-math.pi / 2, 0.0, e)
    np.testing.assert_allclose([omega_after, P, F_imp],
                               [-(1 + e) * V / L, (1 + e) * M_ROD * V / 3,
                                -(1 + e) * M_ROD * V / 6], rtol=1e-12)  # fmt: skip
    t_hit = (wall - R) / V
    after = table["t"].to_numpy() > t_hit
    np.testing.assert_allclose(table["F.impulse"].to_numpy()[after], F_imp, rtol=1e-9)
    np.testing.assert_allclose(table["F.impulse"].to_numpy()[~after], 0.0, atol=1e-12)
    np.testing.assert_allclose(table["wall.impulse"].to_numpy()[after], P, rtol=1e-9)
    np.testing.assert_allclose(table["slider.vx"].to_numpy(), V, rtol=1e-12)
    assert table["rod.omega"].to_numpy()[after][0] < 0.5 * omega_after  # rebounded


@pytest.mark.slow  # long: run by CI's slow set
def test_a_prescribed_motion_into_a_rigid_contact_is_a_named_failure():
    """A ball whose height is prescribed to fall at 1 m/s cannot rebound from the floor
    (its normal velocity is the prescribed one): the run fails at the impact, ``h / v``,
    naming the contact."""
    rb, h = 0.05, 0.2
    ball = md.Body("ball", 1.0, 0.4 * rb**2, q0=(0.0, h + rb, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", rb, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=0.5
    )
    lift = md.PointForce("lift", "ball", along=(0, 1), law=md.Polynomial([0.0]))
    model = md.Model([ball], forces=[floor, lift], gravity=(0, -9.81))
    y = md.CoordinateDriver("y", "ball", "y", law=md.Polynomial([h + rb, -1.0]))
    with pytest.raises(md.SingularityError, match="prescribed motions fix it") as err:
        md.mixed(model, np.linspace(0.0, 0.5, 11), prescribed=[y], unknown=["lift"],
                 rtol=1e-11, atol=1e-13)  # fmt: skip
    assert abs(err.value.time - h / 1.0) < 1e-9
    assert err.value.elements == ("floor",)
