"""A circle on a polyline (``md.CirclePolylineContact``) against independent truths.

- The geometry written out by hand: each segment's penetration ``radius - |c - p_k|`` (``p_k``
  the segment's point nearest the centre), a convex corner carried once (by the segment that
  starts there), a concave corner by both sides.
- Statics in closed form: a ball in a V notch of half-angle ``beta`` from the vertical is held
  by two equal Hertz forces ``K delta**1.5`` with ``2 K delta**1.5 sin(beta) = m g``; placed at
  that penetration, the contact's generalized force is ``(0, m g, 0)`` (1e-10). A ball on a
  convex corner is pushed by one force ``K delta**1.5``, not two.
- Without damping the force is minus the gradient of the elastic energy (central differences).
- A model file with a rigid contact: a ball dropped on a ground outline of three segments
  strikes the middle one at ``sqrt(2 h / g)`` and rebounds at ``e`` times its speed (1e-9).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.cli import app
from mixdyn.model._contact_law import hertz_stiffness

G = 9.81
R, M = 0.01, 0.05  # ball radius [m] and mass [kg]
E = 2e11  # [Pa]


def ball_on(polyline, q0, **law) -> md.Model:
    ball = md.Body("ball", M, 0.4 * M * R**2, q0=q0)
    law = {"young_modulus": E, "restitution": 1.0, **law}
    points = [("ground", p) for p in polyline]
    contact = md.CirclePolylineContact("notch", "ball", R, points, **law)
    return md.Model([ball], forces=[contact], gravity=(0.0, -G))


def test_each_segment_carries_its_nearest_point_and_a_convex_corner_once():
    """A polyline ``(-1, 0) -> (0, 0) -> (1, 1)`` (a convex corner at the origin seen from
    below-right, a concave one from above-left) and circles placed by hand."""
    model = ball_on([(-1.0, 0.0), (0.0, 0.0), (1.0, 1.0)], (0.0, 0.1, 0.0))
    f = model.forces[0]
    # above the first segment's middle: only it touches
    q = np.array([-0.5, 0.008, 0.0])
    delta = np.asarray(f.penetration(q))
    np.testing.assert_allclose(delta[0], R - 0.008, rtol=1e-12)
    assert delta[1] < 0
    # below and right of the corner (convex side): both segments' nearest point is the
    # corner, which the second segment carries alone
    c = np.array([0.004, -0.005])
    delta = np.asarray(f.penetration(np.array([*c, 0.0])))
    np.testing.assert_allclose(delta[1], R - np.hypot(*c), rtol=1e-12)
    np.testing.assert_allclose(delta[0], -(R + np.hypot(*c)), rtol=1e-12)
    # in the concave corner (above, between the sides): both sides touch
    c = np.array([-0.001, 0.006])
    delta = np.asarray(f.penetration(np.array([*c, 0.0])))
    d_second = abs(c[1] - c[0]) / math.sqrt(2.0)  # distance to the line y = x
    np.testing.assert_allclose(delta, [R - c[1], R - d_second], rtol=1e-12)
    P, n = (np.asarray(x) for x in f.frame(np.array([*c, 0.0])))
    np.testing.assert_allclose(n[0], [0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(n[1], np.array([-1.0, 1.0]) / math.sqrt(2.0), rtol=1e-12)
    np.testing.assert_allclose(P[0], [c[0], c[1] - R + delta[0] / 2], rtol=1e-12)
    drawn = f.drawing()  # the circle on the ball, the polyline's sides on the ground
    assert drawn["circles"][0][2] == R
    np.testing.assert_array_equal(np.asarray(drawn["edges"]),
                                  [[(-1, 0), (0, 0)], [(0, 0), (1, 1)]])  # fmt: skip


@pytest.mark.parametrize("beta_deg", [30.0, 60.0])
def test_a_ball_in_a_v_notch_is_held_by_two_equal_hertz_forces(beta_deg):
    beta = math.radians(beta_deg)
    K = float(hertz_stiffness(E, 0.3, R))
    delta = (M * G / (2 * K * math.sin(beta))) ** (2 / 3)
    h = (R - delta) / math.sin(beta)  # the centre's height above the notch's vertex
    wall = (math.sin(beta), math.cos(beta))  # the right side's direction, up from the vertex
    polyline = [(-wall[0], wall[1]), (0.0, 0.0), wall]
    model = ball_on(polyline, (0.0, h, 0.0))
    f = model.forces[0]
    q = np.array([0.0, h, 0.0])
    np.testing.assert_allclose(np.asarray(f.penetration(q)), [delta, delta], rtol=1e-10)
    Q = np.asarray(f.generalized(q, np.zeros(3), 0.0, model.nq))
    # 1e-10: the penetration is a difference of lengths ~1e4 times larger (rounding)
    np.testing.assert_allclose(Q, [0.0, M * G, 0.0], rtol=1e-10, atol=1e-12 * M * G)


def test_a_ball_on_a_convex_corner_is_pushed_once():
    """A ball right above the apex of ``/\\`` presses it by ``delta``: one Hertz force
    ``K delta**1.5`` straight up (the corner is carried by one segment only)."""
    K = float(hertz_stiffness(E, 0.3, R))
    delta = 2e-6
    model = ball_on([(-1.0, -1.0), (0.0, 0.0), (1.0, -1.0)], (0.0, R - delta, 0.0))
    f = model.forces[0]
    q = np.array([0.0, R - delta, 0.0])
    Q = np.asarray(f.generalized(q, np.zeros(3), 0.0, model.nq))
    np.testing.assert_allclose(Q, [0.0, K * delta**1.5, 0.0], rtol=1e-10, atol=1e-20)


def test_without_damping_the_force_derives_from_the_elastic_energy():
    model = ball_on([(-1.0, 0.0), (0.0, 0.0), (1.0, 1.0)], (0.0, 0.1, 0.0))
    f = model.forces[0]
    for c in ([-0.3, 0.0095], [-0.001, 0.008], [0.005, -0.006]):  # side, notch, corner
        q = np.array([*c, 0.0])
        Q = np.asarray(f.generalized(q, np.zeros(3), 0.0, model.nq))
        h = 1e-9
        grad = [(f.potential(q + h * e) - f.potential(q - h * e)) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(Q, -np.asarray(grad), rtol=1e-5, atol=1e-9 * np.abs(Q).max())
        assert np.abs(Q).max() > 0


FILE = """\
mixdyn: 1
name: ball-on-an-outline
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81 m/s^2]
ground:
  points: {A: [-1, 0.5], B: [-0.2, 0], C: [0.2, 0], D: [1, 0.5]}
bodies:
  - {name: ball, mass: 0.05 kg, inertia: 2.0e-6, q0: [0.05, 0.21, 0]}
forces:
  - {type: circle_polyline_contact, name: floor, center: ball, radius: 10 mm,
     polyline: [ground.A, ground.B, ground.C, ground.D], contact_model: rigid,
     restitution: 0.6}
runs:
  - name: drop
    kind: forward
    time: {span: [0, 0.3], n: 7}
"""


def test_a_model_file_drops_a_ball_on_a_rigid_outline(tmp_path):
    path = tmp_path / "outline.yaml"
    path.write_text(FILE)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    impacts = pd.read_csv(tmp_path / "out" / "drop" / "impacts.csv")
    h0 = 0.2  # the ball's bottom above the middle segment
    t1, v1 = math.sqrt(2 * h0 / G), math.sqrt(2 * G * h0)
    assert impacts["t [s]"].iloc[0] == pytest.approx(t1, abs=1e-9)
    assert impacts["normal_velocity_before [m/s]"].iloc[0] == pytest.approx(-v1, rel=1e-9)
    assert impacts["normal_velocity_after [m/s]"].iloc[0] == pytest.approx(0.6 * v1, rel=1e-9)
    # a polyline of one body: refused where its points are on two
    bad = FILE.replace("ground.D]", "ball]")
    path.write_text(bad)
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert "on several bodies" in res.output
