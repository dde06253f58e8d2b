"""Compliant impacts on small mechanisms against conservation laws and closed forms.

- Newton's cradle (three balls, ``e = 1``, Hertz contacts between neighbours): momentum is
  kept exactly (the contact forces are internal) and energy with the contacts' elastic energy
  to the integrator's tolerance through the whole sequence of impacts; the last ball leaves
  with most of the momentum (a Hertz chain's known imperfect transfer keeps a little in the
  others).
- A pendulum striking a wall: its rebound angular velocity is ``-e omega`` within the
  Lankarani-Nikravesh model's accuracy at ``e = 0.9`` (2 %, as for a ball).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md

pytestmark = pytest.mark.slow  # long: run by CI's slow set

R, M, V = 0.01, 0.1, 1.0  # balls' radius [m], mass [kg], first ball's speed [m/s]


def test_newtons_cradle_keeps_momentum_and_energy():
    balls = [
        md.Body(f"b{k}", M, 0.4 * M * R**2, q0=(x, 0.0, 0.0))
        for k, x in enumerate((-0.01, 2 * R, 4 * R))
    ]
    law = dict(young_modulus=2e11, restitution=1.0)
    contacts = [md.CircleContact(f"c{k}", f"b{k}", R, f"b{k + 1}", R, **law) for k in range(2)]
    model = md.Model(balls, forces=contacts)
    ts = np.linspace(0.0, 0.03, 301)
    qd0 = np.zeros(9)
    qd0[0] = V
    r = md.forward(model, ts, qd0=qd0, rtol=1e-11, atol=1e-13)
    p = sum(r[f"b{k}.vx"] for k in range(3)) * M
    np.testing.assert_allclose(p, M * V, rtol=1e-12)
    E = r["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-8 * E[0]
    assert np.max(r["c0.normal"]) > 0 and np.max(r["c1.normal"]) > 0  # both impacts happened
    assert r["b2.vx"][-1] > 0.9 * V  # the last ball leaves with most of the momentum
    assert r["b0.vx"][-1] < r["b2.vx"][-1] and r["b0.vx"][-1] >= -0.1 * V


def test_a_pendulum_striking_a_wall_rebounds_with_minus_e_omega():
    """A rod pivoted at the ground, its tip (a round bob) swinging into a vertical wall at
    the bottom of its swing: the angular velocity after the impact is ``-e`` times the one
    before (Lankarani-Nikravesh, e = 0.9: within 2 %)."""
    L, m, e, g = 0.3, 0.5, 0.9, 9.81
    J = m * L**2 / 12
    theta0 = math.radians(40)
    rod = md.Body(
        "rod", m, J, q0=(L / 2 * math.sin(theta0), -L / 2 * math.cos(theta0), theta0 - math.pi / 2),
        points={"O": (-L / 2, 0.0), "tip": (L / 2, 0.0)},
    )  # fmt: skip
    omega = math.sqrt(m * 9.81 * L / 2 * (1 - math.cos(theta0)) * 2 / (J + m * L**2 / 4))
    wall = md.CircleLineContact(
        "wall", "rod.tip", R, ("ground", (-R, 0.0)), axis=(0.0, -1.0), young_modulus=2e11,
        restitution=e, impact_speed=omega * L,
    )  # fmt: skip
    model = md.Model([rod], [md.Revolute("O", "ground", "rod.O")], forces=[wall], gravity=(0, -g))
    ts = np.linspace(0.0, 0.6, 1201)
    r = md.forward(model, ts, rtol=1e-10, atol=1e-12)
    w = r["rod.omega"]
    k = np.flatnonzero((w[:-1] < 0) & (w[1:] > 0))[0] + 1  # the first rebound
    before, after = w[k - 1], w[k]
    np.testing.assert_allclose(before, -omega, rtol=1e-4)  # energy: the swing down
    assert abs(after / before + e) < 0.02 * e
