"""Perfectly plastic rigid impacts (``contact_model: rigid``, ``restitution: 0``) against
closed forms.

- A ball dropped from ``h0`` (frictionless): it strikes once, at ``t_1 = sqrt(2 h0 / g)``,
  with the impulse ``m sqrt(2 g h0)``, and rests from then on at height ``R`` with the
  normal force ``m g``; the impact took all the energy it lost, ``m g h0``.
- A box thrown flat at ``u0`` from ``h0`` onto rough ground (``mu``): both bottom corners
  strike at ``t_1`` with ``v_1 = g t_1``; the normal impulses ``m v_1`` in all bring their
  Coulomb impulses ``mu m v_1``, so that the box lands at ``u+ = max(u0 - mu v_1, 0)``,
  never turning, then skids at ``-mu g`` to a stop at ``x = u0 t_1 + u+**2 / (2 mu g)``.
  The impact and the friction took all the kinetic energy: ``m (u0**2 / 2 + g h0)``.
- A compliant contact refuses ``restitution: 0`` by name (its damping has no bound there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md

G = 9.81


@pytest.mark.slow  # long: run by CI's slow set (the model file's run checks it by default)
def test_a_ball_dropped_on_plastic_ground_strikes_once_and_rests():
    m, R, h0 = 1.5, 0.05, 0.2
    ball = md.Body("ball", m, 0.4 * m * R**2, q0=(0.0, R + h0, 0.0))
    floor = md.CircleLineContact(
        "floor", "ball", R, ("ground", (0.0, 0.0)), contact_model="rigid", restitution=0.0
    )
    model = md.Model([ball], forces=[floor], gravity=(0, -G))
    ts = np.linspace(0.0, 0.5, 11)
    r = md.forward(model, ts, rtol=1e-10, atol=1e-12)
    t1 = math.sqrt(2 * h0 / G)
    imp = r.stats["impacts"]
    np.testing.assert_allclose(imp["t"], [t1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(imp["impulse"], [m * G * t1], rtol=1e-9)
    np.testing.assert_allclose(imp["normal_velocity_after"], [0.0], atol=1e-12)
    before, after = ts < t1, ts > t1
    np.testing.assert_allclose(r["ball.y"][before], R + h0 - G * ts[before] ** 2 / 2, rtol=1e-10)
    np.testing.assert_allclose(r["ball.y"][after], R, rtol=1e-10)
    np.testing.assert_allclose(r["ball.vy"][after], 0.0, atol=1e-10)
    np.testing.assert_allclose(r["floor.normal"][after], m * G, rtol=1e-9)
    assert r.stats["rests"]["start"] == pytest.approx([t1], abs=1e-9)
    np.testing.assert_allclose(r["work.impacts"][-1], -m * G * h0, rtol=1e-9)


@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.parametrize("u0", [1.2, 0.3], ids=["skids", "stops"])
def test_a_box_thrown_flat_on_rough_plastic_ground_lands_then_skids_to_its_stop(u0):
    m, w, h, rc, mu, h0 = 1.0, 0.2, 0.1, 0.005, 0.4, 0.1
    box = md.Body("box", m, m * (w**2 + h**2) / 12, q0=(0.0, h / 2 + h0, 0.0))
    floor = md.BoxLineContact("floor", "box", w, h, rc, ("ground", (0.0, 0.0)),
                              contact_model="rigid", restitution=0.0, mu=mu)  # fmt: skip
    model = md.Model([box], forces=[floor], gravity=(0, -G))
    ts = np.linspace(0.0, 0.6, 13)
    r = md.forward(model, ts, qd0=np.array([u0, 0.0, 0.0]), rtol=1e-10, atol=1e-12)
    t1 = math.sqrt(2 * h0 / G)
    v1 = G * t1
    u_plus = max(u0 - mu * v1, 0.0)
    t_stop = t1 + u_plus / (mu * G)
    assert ts[-1] > t_stop + 0.05
    imp = r.stats["impacts"]
    np.testing.assert_allclose(imp["t"][:2], [t1, t1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.sum(imp["impulse"][:2]), m * v1, rtol=1e-9)
    np.testing.assert_allclose(np.asarray(imp["normal_velocity_after"][:2]), 0.0, atol=1e-10)
    s = np.clip(ts - t1, 0.0, t_stop - t1)
    x = np.where(ts < t1, u0 * ts, u0 * t1 + u_plus * s - 0.5 * mu * G * s**2)
    np.testing.assert_allclose(r["box.x"], x, rtol=0, atol=1e-9)
    after = ts > t1
    np.testing.assert_allclose(r["box.y"][after], h / 2, rtol=1e-10)
    assert np.max(np.abs(r["box.phi"])) < 1e-10
    np.testing.assert_allclose(r["box.vx"][ts > t_stop], 0.0, atol=1e-10)
    E = r["energy.kinetic"] + r["energy.potential"]
    np.testing.assert_allclose(E[-1] - E[0], -m * (u0**2 / 2 + G * h0), rtol=1e-9)


def test_a_compliant_contact_refuses_plastic_restitution():
    with pytest.raises(md.ModelError, match="contact_model: rigid") as err:
        md.CircleLineContact("floor", "ball", 0.05, ("ground", (0.0, 0.0)),
                             young_modulus=2e11, restitution=0.0, impact_speed=1.0)  # fmt: skip
    assert err.value.field == "restitution"
