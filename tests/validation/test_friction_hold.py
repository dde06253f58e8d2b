"""A body that friction stops stays where it stopped (issue 31, part 2, item 3).

It crept on at the speed it entered the stick band with (up to ``v_stick``, 1e-6: 1.8e-6 m
in 1.8 s), or, with a fixed step, chattered about zero and slid millimetres. The truth is the
closed form of Coulomb friction with a constant deceleration:

- a block launched up an incline at ``v0`` (friction coefficient ``mu > tan(theta)``, so that
  it stays once stopped) decelerates at ``g (sin + mu cos)``; it stops at
  ``t_s = v0 / a``, ``d = v0**2 / (2 a)`` up the slope, and stays there: the static
  friction ``m g sin`` is below its limit ``mu m g cos``; the friction's work is
  ``-mu m g cos d`` (the energy balance: the kinetic energy less the potential gained);
- a flywheel spinning at ``w0`` on a pin with friction, braked by a torque below the pin's
  friction torque ``mu r m g``: it stops at ``w0**2 / (2 alpha)`` and stays.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md

G = 9.81
T_END = 2.0
TS = np.linspace(0.0, T_END, 201)
#: The methods with joint friction, adaptive and fixed step.
METHODS = {
    "projection": {"rtol": 1e-10, "atol": 1e-12},
    "partitioning": {"method": "partitioning", "rtol": 1e-10, "atol": 1e-12},
    "projection-fixed": {"dt": 1e-3},
    "baumgarte": {"method": "baumgarte", "dt": 1e-3},
}


def incline(theta: float, mu: float, m: float = 2.0) -> md.Model:
    """A block on a translational joint along ``(cos, -sin)`` (down the slope), friction
    ``mu`` in it (default stick band, 1e-6 m/s)."""
    c, s = math.cos(theta), math.sin(theta)
    return md.Model(
        bodies=[md.Body("block", m, 0.1, q0=(0.0, 0.0, -theta))],
        joints=[md.Translational("slide", "ground", "block", axis=(c, -s))],
        forces=[md.JointFriction("friction", "slide", mu=mu)],
        gravity=(0.0, -G),
    )


@pytest.mark.parametrize("method", list(METHODS))
def test_a_block_launched_up_an_incline_stops_where_it_should_and_stays(method):
    theta, mu, m, v0 = 0.25, 0.5, 2.0, 1.0
    c, s = math.cos(theta), math.sin(theta)
    a = G * (s + mu * c)
    t_stop, d = v0 / a, v0**2 / (2 * a)
    res = md.forward(
        incline(theta, mu, m), TS, qd0={"block.x": -v0 * c, "block.y": v0 * s}, **METHODS[method]
    )
    up = -(res["block.x"] * c - res["block.y"] * s)  # the distance up the slope
    after = t_stop + 0.01 < TS
    fixed = "dt" in METHODS[method]
    # where it stops: the closed form (to a step's worth of motion with a fixed step)
    assert np.max(np.abs(up[after] - d)) <= (2e-6 if fixed else 1e-9), up[after][0] - d
    # and stays there, exactly, for the 1.85 s after
    assert np.max(up[after]) - np.min(up[after]) <= 1e-9
    assert np.max(np.abs(res["friction.speed"][after])) <= 1e-12
    # before the stop: d(t) = v0 t - a t**2 / 2
    before = t_stop - 0.01 > TS
    tol = 1e-5 if fixed else 1e-9
    np.testing.assert_allclose(up[before], v0 * TS[before] - 0.5 * a * TS[before] ** 2, atol=tol)
    if not fixed:
        # the friction's work: -mu m g cos(theta) d, the kinetic energy less the potential
        work = np.asarray(res["work.nonconservative"])[-1]
        assert abs(work - (-mu * m * G * c * d)) <= 1e-8
        assert abs(0.5 * m * v0**2 - m * G * s * d + work) <= 1e-8


def test_a_block_at_the_friction_angle_slides_back_down_after_stopping():
    """mu < tan(theta): once stopped, the block slides back at g (sin - mu cos); the hold
    is only where static friction holds."""
    theta, mu, v0 = 0.5, 0.3, 1.0
    c, s = math.cos(theta), math.sin(theta)
    a_up, a_down = G * (s + mu * c), G * (s - mu * c)
    t_stop, d = v0 / a_up, v0**2 / (2 * a_up)
    res = md.forward(
        incline(theta, mu), TS, qd0={"block.x": -v0 * c, "block.y": v0 * s}, **METHODS["projection"]
    )
    up = -(res["block.x"] * c - res["block.y"] * s)
    late = t_stop < TS
    expect = d - 0.5 * a_down * (TS[late] - t_stop) ** 2
    # the stick band's one regularization: a joint that cannot stick turns round inside it
    # at the limit force the other way, a time shift of about v_stick (1/a_down - 1/a_up),
    # 3e-7 s, so 1.3e-6 m after 1.7 s
    shift = 1e-6 * (1 / a_down - 1 / a_up)
    np.testing.assert_allclose(up[late], expect, atol=2 * a_down * T_END * shift)


@pytest.mark.parametrize("method", ["projection", "partitioning", "baumgarte"])
def test_a_braked_flywheel_stops_and_is_held_by_its_pin(method):
    mu, radius, m, R, w0 = 0.2, 0.01, 5.0, 0.15, 1.5
    inertia = 0.5 * m * R**2
    limit = mu * radius * m * G  # the pin's friction torque (its reaction: the weight)
    brake = -0.5 * limit  # held once stopped: below the limit
    model = md.Model(
        bodies=[md.Body("wheel", m, inertia, q0=(0.0, 0.0, 0.0))],
        joints=[md.Revolute("pin", "ground", "wheel")],
        forces=[
            md.JointFriction("pin_friction", "pin", mu=mu, radius=radius),
            md.Torque("brake", "wheel", law=brake),
        ],
        gravity=(0.0, -G),
    )
    alpha = (limit - brake) / inertia
    t_stop, angle = w0 / alpha, w0**2 / (2 * alpha)
    assert t_stop < 0.5 * T_END
    res = md.forward(model, TS, qd0={"wheel.phi": w0}, **METHODS[method])
    phi = np.asarray(res["wheel.phi"])
    after = t_stop + 0.01 < TS
    fixed = "dt" in METHODS[method]
    assert np.max(np.abs(phi[after] - angle)) <= (1e-5 if fixed else 1e-9) * angle
    assert np.max(phi[after]) - np.min(phi[after]) <= 1e-9
    # held by the static friction: the brake's torque, below the limit
    np.testing.assert_allclose(res["pin_friction"][after], -brake, rtol=1e-9)


def test_a_body_at_rest_stays_exactly_at_rest():
    """Below the friction angle, from rest: no motion beyond rounding."""
    res = md.forward(incline(0.25, 0.3), TS, **METHODS["projection"])
    assert np.max(np.abs(res.q[:, :2])) <= 1e-15
