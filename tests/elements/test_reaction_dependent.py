"""Reaction-dependent forces (``md.ReactionDependent``): elements written in this file only,
solved by the analyses through the protocol, with no change to the solver.

- ``PinDrag``: a torque ``-c |R| omega`` in a revolute joint, ``R`` the pin's reaction (it
  never sticks). A wheel pinned at its centre of mass, pushed sideways by a constant force
  ``P`` under gravity, has ``|R| = sqrt(P^2 + (m g)^2)`` whatever it turns, so
  ``I omega' = -c |R| omega``: ``omega = omega0 exp(-k t)``, ``k = c |R| / I``.
- ``GuideFriction``: Coulomb friction in a slide with stick and slip, written again under
  another name. A block launched up an incline at ``v0`` (``mu > tan(theta)``) decelerates at
  ``g (sin + mu cos)``, stops at ``v0 / a``, ``v0^2 / (2 a)`` up the slope, and stays: the
  stick force and the stop (``Problem.halt_sticking``) work for it as for
  ``md.JointFriction``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md

G = 9.81


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class PinDrag(md.ReactionDependent):
    """A drag torque ``-c |R| omega`` [torque] in the revolute joint ``joint`` (``omega`` the
    relative angular velocity, ``R`` the pin's reaction force, ``c`` [length time])."""

    joint: str = eqx.field(static=True)
    c: jax.Array = eqx.field(converter=_f64)
    kind_name: ClassVar[str] = "pin drag"

    def reaction_rows(self):
        return (f"{self.joint}.x", f"{self.joint}.y")

    def relative_coordinate(self, model, q):
        j = model.element(self.joint)
        return (q[3 * j.bj + 2] if j.bj >= 0 else 0.0) - (q[3 * j.bi + 2] if j.bi >= 0 else 0.0)

    def slip_force(self, v, reactions):
        return -self.c * jnp.sqrt(jnp.sum(reactions**2)) * v

    def reaction_outputs(self, reactions):
        return {"reaction": jnp.sqrt(jnp.sum(reactions**2))}

    @property
    def output_kinds(self):
        return {"": "torque", "reaction": "force", "speed": "angular_velocity"}


class GuideFriction(md.ReactionDependent):
    """Coulomb friction ``mu |N|`` with stick and slip in the translational joint ``joint``."""

    joint: str = eqx.field(static=True)
    mu: jax.Array = eqx.field(converter=_f64)
    band: jax.Array = eqx.field(default=1e-6, converter=_f64)

    def reaction_rows(self):
        return (f"{self.joint}.normal",)

    def relative_coordinate(self, model, q):
        j = model.element(self.joint)  # a slide on the ground: the axis is fixed
        b = 3 * j.bj
        return jnp.dot(j.u, q[b : b + 2])

    def holding_limit(self, reactions):
        return self.mu * jnp.abs(reactions[0])

    def slip_force(self, v, reactions):
        return -self.holding_limit(reactions) * jnp.sign(v)

    def stick_band(self):
        return self.band

    @property
    def no_arrow(self):
        return None

    def arrow(self, model, q):
        j = model.element(self.joint)
        return j.bj, np.zeros(2), np.broadcast_to(np.asarray(j.u, dtype=float), (len(q), 2))

    @property
    def output_kinds(self):
        return {"": "force", "speed": "velocity"}


def pushed_wheel(c: float, P: float, m: float = 2.0, inertia: float = 0.05) -> md.Model:
    return md.Model(
        bodies=[md.Body("wheel", m, inertia, q0=(0.0, 0.0, 0.0))],
        joints=[md.Revolute("pin", "ground", "wheel")],
        forces=[PinDrag("drag", joint="pin", c=c), md.PointForce("push", "wheel", law=P)],
        gravity=(0.0, -G),
    )


def test_a_drag_proportional_to_the_pin_reaction_decays_the_spin_exponentially():
    c, P, m, inertia, w0 = 0.002, 3.0, 2.0, 0.05, 5.0
    t = np.linspace(0.0, 1.0, 11)
    res = md.forward(pushed_wheel(c, P, m, inertia), t, qd0={"wheel.phi": w0}, rtol=1e-10)
    R = math.hypot(P, m * G)
    k = c * R / inertia
    omega = w0 * np.exp(-k * t)
    np.testing.assert_allclose(res["wheel.phi"], w0 / k * (1 - np.exp(-k * t)), rtol=1e-8)
    np.testing.assert_allclose(res.qd[:, 2], omega, rtol=1e-8)
    # its columns: the torque from the reaction the analysis solved, the speed and power
    np.testing.assert_allclose(res["drag.reaction"], R, rtol=1e-12)
    np.testing.assert_allclose(res["drag"], -c * R * omega, rtol=1e-8)
    np.testing.assert_allclose(res["drag.speed"], omega, rtol=1e-8)
    np.testing.assert_allclose(res["drag.power"], -c * R * omega**2, rtol=1e-8)
    # the energy it takes out is the kinetic energy lost (the wheel's centre does not move)
    lost = 0.5 * inertia * (omega**2 - w0**2)
    np.testing.assert_allclose(res["work.nonconservative"], lost, atol=1e-8 * inertia * w0**2)


def test_a_method_without_reaction_dependent_forces_refuses_the_element_by_its_kind():
    model = pushed_wheel(0.002, 3.0)
    with pytest.raises(md.ModelError, match=r"pin drag \(drag\).*generalized-alpha"):
        md.forward(model, np.linspace(0.0, 1.0, 3), method="generalized-alpha", dt=0.01)


@pytest.mark.slow  # two forward runs with stick and slip (~30 s)
def test_coulomb_friction_written_in_a_test_stops_a_block_where_it_should_and_holds_it():
    theta, mu, m, v0 = 0.25, 0.5, 2.0, 1.0
    c, s = math.cos(theta), math.sin(theta)
    model = md.Model(
        bodies=[md.Body("block", m, 0.1, q0=(0.0, 0.0, -theta))],
        joints=[md.Translational("slide", "ground", "block", axis=(c, -s))],
        forces=[GuideFriction("guide", joint="slide", mu=mu)],
        gravity=(0.0, -G),
    )
    a = G * (s + mu * c)
    t_stop, d = v0 / a, v0**2 / (2 * a)
    t = np.linspace(0.0, 2.0, 201)
    res = md.forward(model, t, qd0={"block.x": -v0 * c, "block.y": v0 * s}, rtol=1e-10, atol=1e-12)
    up = -(res["block.x"] * c - res["block.y"] * s)
    after, before = t_stop + 0.01 < t, t_stop - 0.01 > t
    np.testing.assert_allclose(up[before], v0 * t[before] - 0.5 * a * t[before] ** 2, atol=1e-9)
    assert np.max(np.abs(up[after] - d)) <= 1e-9  # stopped at the closed-form place...
    assert np.max(np.abs(res["guide.speed"][after])) <= 1e-12  # ...and held there
    # held by its static friction, m g sin up the slope; sliding, mu m g cos against it
    np.testing.assert_allclose(res["guide"][after], -m * G * s, rtol=1e-9)
    np.testing.assert_allclose(res["guide"][before][1:], mu * m * G * c, rtol=1e-9)
    work = float(np.asarray(res["work.nonconservative"])[-1])
    assert abs(work - (-mu * m * G * c * d)) <= 1e-8
    # the arrow the element gives: against the slope's axis while it slides up
    from mixdyn.viz.arrows import force_arrows

    (arrow,) = force_arrows(res, ["guide"])
    np.testing.assert_allclose(arrow["F"][1], mu * m * G * c * np.array([c, -s]), rtol=1e-9)
