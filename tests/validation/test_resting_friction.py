"""A resting rigid contact point with a friction coefficient must not slide: its held row is
frictionless, so that a slide would be a Coulomb-wrong motion (``mu`` acts in impacts only).

A disc dropped with ``e = 0.1`` on a rigid line bounces until the bounces accumulate at
``t_inf = t_1 (1 + e) / (1 - e)`` (``t_1 = sqrt(2 h / (g cos(theta)))``, ``h`` its gap along
the normal: Newton's law fixes the normal velocities whatever the friction does), then rests.

- On a rough incline of 20 degrees it rests and would slide down: the run ends as a named
  numerical failure after ``t_inf``, at the next output, naming the contact, the sliding
  speed and the compliant contact to use; the states before it lie on the incline (slow).
  The check alone (fast): at a disc's states on the incline, rolling passes and sliding
  fails at the first state past the limit, with the closed form's sliding speed.
- With ``mu = 0`` the same run goes on: the frictionless impulses act along the normal, so
  that the centre moves along the incline as ``g sin(theta) t^2 / 2`` throughout, resting on
  it after ``t_inf`` with the normal force ``m g cos(theta)`` (slow).
- On rough flat ground a disc dropped rests with ``m g``; one thrown level sticks at its
  first impact (the angular momentum about the contact point kept:
  ``v_x+ = m R^2 v_x / (m R^2 + J)``) and rolls on at that speed through its bounces and
  its rest: no false alarm (slow).
- ``mixdyn run`` of a model file with the rough incline exits 1 with the message (slow).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.analysis._impacts import _refuse_resting_slide
from mixdyn.cli import app
from mixdyn.model._compliant import rigid_contacts

G_ACC, M, R, H, E = 9.81, 2.0, 0.05, 0.1, 0.1
J = 0.5 * M * R**2
THETA = math.radians(20.0)
DOWN = np.array([math.cos(THETA), -math.sin(THETA)])  # down the incline
NORMAL = np.array([math.sin(THETA), math.cos(THETA)])  # the incline's outward normal


def _on_incline(mu, theta=THETA):
    """A disc whose centre is ``H + R`` above the incline through the origin (along its
    normal), released at rest: a rigid contact with ``e = 0``."""
    c = (H + R) * NORMAL if theta else np.array([0.0, H + R])
    axis = DOWN if theta else np.array([1.0, 0.0])
    disc = md.Body("disc", M, J, q0=(c[0], c[1], 0.0))
    incline = md.CircleLineContact(
        "incline", "disc", R, ("ground", (0.0, 0.0)), axis=tuple(axis), contact_model="rigid",
        restitution=E, mu=mu,
    )  # fmt: skip
    return md.Model([disc], forces=[incline], gravity=(0, -G_ACC))


def _t_land(theta=THETA):
    """The first impact's time [s] (the fall along the normal at ``g cos(theta)``)."""
    return math.sqrt(2 * H / (G_ACC * math.cos(theta)))


def _t_rest(theta=THETA):
    """The bounces' accumulation (Zeno) time [s]: the frictional impulses leave the normal
    velocity to Newton's law, ``t_inf = t_1 (1 + e) / (1 - e)``."""
    return _t_land(theta) * (1 + E) / (1 - E)


TS = np.linspace(0.0, 0.3, 7)


def test_a_resting_point_sliding_past_the_rest_speed_is_a_named_failure():
    """The check alone, at states of a disc touching the incline: rolling down it (its
    contact point still: ``v + w R = 0`` along it) passes; sliding (no spin) fails at the
    first state past the limit, with the sliding speed ``|v|`` of the closed form."""
    model = _on_incline(0.5)
    contacts = rigid_contacts(model)
    q = np.r_[R * NORMAL, 0.0]
    v = np.array([0.0, 0.2, 0.3])  # speeds down the incline [m/s]
    rolling = np.stack([np.r_[u * DOWN, -u / R] for u in v])  # clockwise: w = -v / R
    sliding = np.stack([np.r_[u * DOWN, 0.0] for u in v])
    times, Q, limit = np.array([1.0, 2.0, 3.0]), np.tile(q, (3, 1)), 0.1
    errors = []

    def fail(err):
        errors.append(err)
        raise err

    check = np.ones(3, bool)
    _refuse_resting_slide(contacts, [0], times, Q, rolling, check, limit, [contacts[0]], fail)
    assert not errors
    with pytest.raises(md.NumericalError, match="resting friction at a rigid contact") as err:
        _refuse_resting_slide(contacts, [0], times, Q, sliding, check, limit, [contacts[0]], fail)
    assert err.value.time == 2.0 and err.value.elements == ("incline",)
    assert "sliding speed 0.2 [velocity]" in str(err.value)
    unchecked = np.array([True, False, False])  # only the states the run checks count
    _refuse_resting_slide(contacts, [0], times, Q, sliding, unchecked, limit, [contacts[0]], fail)
    assert len(errors) == 1


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_resting_on_a_rough_rigid_incline_is_a_named_failure():
    with pytest.raises(md.NumericalError, match="resting friction at a rigid contact") as err:
        md.forward(_on_incline(0.5), TS)
    t_rest = _t_rest()
    assert err.value.elements == ("incline",)
    assert t_rest - 1e-6 < err.value.time <= TS[t_rest < TS][0] + 1e-12
    assert "[velocity]" in str(err.value) and "contact_friction" in str(err.value)
    done = err.value.partial  # the states up to the failure: on the incline after resting
    on = done.t > t_rest
    np.testing.assert_allclose(done.q[on, :2] @ NORMAL, R, rtol=0, atol=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_on_a_frictionless_rigid_incline_slides_at_g_sin_theta():
    r = md.forward(_on_incline(0.0), TS, rtol=1e-10, atol=1e-12)
    t_rest = _t_rest()
    assert r.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    s = 0.5 * G_ACC * math.sin(THETA) * TS**2
    np.testing.assert_allclose(r.q[:, :2] @ DOWN, s, rtol=0, atol=1e-8)
    after = t_rest < TS
    np.testing.assert_allclose(r.q[after, :2] @ NORMAL, R, rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["incline.normal"][after], M * G_ACC * math.cos(THETA), rtol=1e-7)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_disc_resting_or_rolling_on_rough_flat_ground_runs():
    r = md.forward(_on_incline(0.5, theta=0.0), TS)
    t_land, t_rest = _t_land(0.0), _t_rest(0.0)
    assert r.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    after = t_rest < TS
    np.testing.assert_allclose(r.q[after, 1], R, rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["incline.normal"][after], M * G_ACC, rtol=1e-9)
    vx = 1.0  # thrown level: sticks at the landing and rolls
    rolled = md.forward(_on_incline(1.0, theta=0.0), TS, qd0=np.array([vx, 0.0, 0.0]))
    v_roll = M * R**2 * vx / (M * R**2 + J)
    assert bool(rolled.stats["impacts"]["sticks"][0])
    assert rolled.stats["rests"]["start"][0] == pytest.approx(t_rest, abs=1e-6)
    later = t_land < TS
    x = vx * t_land + v_roll * (TS[later] - t_land)
    np.testing.assert_allclose(rolled.q[later, 0], x, rtol=0, atol=1e-8)
    np.testing.assert_allclose(rolled.qd[later, 2], -v_roll / R, rtol=1e-9)


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
def test_mixdyn_run_of_a_rough_rigid_incline_exits_1(tmp_path):
    path = tmp_path / "incline.yaml"
    path.write_text(FILE)
    out = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert out.exit_code == 1, out.output
    assert "resting friction at a rigid contact is not modelled" in out.output
    assert "incline" in out.output
