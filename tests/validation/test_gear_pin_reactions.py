"""The pins of meshing gears carry the whole tooth force (issue 31, part 2, item 2).

Teeth push along the line of action, at the pressure angle ``alpha`` to the pitch line. A gear
on a pin, turned at constant speed against a torque ``T`` (no gravity, no other force), is in
equilibrium under the torque, the tooth force and the pin: the pin's reaction is minus the
tooth force, of magnitude ``|Fn| = T / (R cos(alpha))`` (it was ``T / R``, the tangential part
alone, 9.4% low at 25 degrees), at ``alpha`` to the tangent, its radial part pointing from the
pitch point into the gear. The same in statics and inverse dynamics, whichever way the torque
goes; for an internal pair, a rack and pinion, and in any unit system.
"""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

import mixdyn as md

ALPHA = math.radians(25.0)
R1, R2 = 0.03, 0.06


def gear_pair(load: float, *, internal: bool = False, alpha: float = ALPHA) -> md.Model:
    """Gear 1 (pitch radius R1) driven by its motor at 5 rad/s, gear 2 (R2) loaded by the
    torque ``load``; both on ground pins. External: gear 2 to the right of gear 1. Internal:
    gear 2 a ring about the origin, gear 1 inside it, its centre at (R2 - R1, 0)."""
    if internal:
        bodies = [
            md.Body("g1", 0.1, 2e-4, q0=(R2 - R1, 0.0, 0.0)),  # the pinion, inside
            md.Body("g2", 0.4, 1e-3, q0=(0.0, 0.0, 0.0)),  # the ring
        ]
        ground = {"O1": (R2 - R1, 0.0), "O2": (0.0, 0.0)}
        mesh = md.GearPair("mesh", "g2", "g1", R2, R1, internal=True, pressure_angle=alpha)
    else:
        bodies = [
            md.Body("g1", 0.1, 2e-4, q0=(0.0, 0.0, 0.0)),
            md.Body("g2", 0.2, 4e-4, q0=(R1 + R2, 0.0, 0.0)),
        ]
        ground = {"O1": (0.0, 0.0), "O2": (R1 + R2, 0.0)}
        mesh = md.GearPair("mesh", "g1", "g2", R1, R2, pressure_angle=alpha)
    return md.Model(
        bodies=bodies,
        ground=ground,
        joints=[md.Revolute("O1", "ground.O1", "g1"), md.Revolute("O2", "ground.O2", "g2"), mesh],
        drivers=[md.CoordinateDriver("motor", "g1", "phi", law=md.Ramp(0.0, 5.0))],
        forces=[md.Torque("load", "g2", law=load)],
        units=md.SI,
    )


def _pin(res, name):
    return np.stack([np.asarray(res[f"{name}.Fx"]), np.asarray(res[f"{name}.Fy"])], axis=-1)


def _check_pin(F, T, R, centre_to_pitch, *, ring=False, alpha=ALPHA):
    """The pin's force ``F`` (..., 2) on a gear of pitch radius R under the torque T, its
    pitch point along the unit vector ``centre_to_pitch`` from its centre: the pin holds the
    tooth force, so it is of magnitude T / (R cos alpha); its radial part is |F| sin(alpha),
    towards the pitch point (the teeth push an external gear or a pinion away from it, into
    the gear), or away from it for a ring (whose teeth are pushed outwards); and the tooth
    force -F at the pitch point balances T about the centre."""
    Fn = abs(T) / (R * math.cos(alpha))
    np.testing.assert_allclose(np.hypot(F[..., 0], F[..., 1]), Fn, rtol=1e-9)
    e = np.asarray(centre_to_pitch)
    np.testing.assert_allclose(F @ e, (-1.0 if ring else 1.0) * Fn * math.sin(alpha), rtol=1e-9)
    moment = R * (e[0] * -F[..., 1] - e[1] * -F[..., 0])
    np.testing.assert_allclose(moment, -T, rtol=1e-9)


@pytest.mark.parametrize("T", [3.0, -3.0], ids=["resisting", "reversed"])
def test_inverse_dynamics_pin_reaction_is_the_whole_tooth_force(T):
    """At constant speed, each pin carries |Fn| = T / (R2 cos alpha) on gear 2 and the same
    force on gear 1 (the pair's tooth forces are opposite); the radial part pushes each gear
    away from the other whichever way the torque goes; the tooth force columns agree."""
    res = md.inverse(gear_pair(-T), np.linspace(0.0, 1.0, 5))
    _check_pin(_pin(res, "O2"), -T, R2, (-1.0, 0.0))  # gear 2's pitch point: towards gear 1
    F1 = _pin(res, "O1")
    np.testing.assert_allclose(F1, -_pin(res, "O2"), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.abs(res["mesh.Fn"]), abs(T) / (R2 * math.cos(ALPHA)), rtol=1e-12)
    np.testing.assert_allclose(res["mesh.Fr"], abs(T) / R2 * math.tan(ALPHA), rtol=1e-12)
    np.testing.assert_allclose(res["motor"], -T * R1 / R2, rtol=1e-12)  # unchanged: T R1/R2


def test_statics_pin_reaction_is_the_whole_tooth_force():
    eq = md.statics(gear_pair(-3.0))
    F = np.array([eq["O2.Fx"], eq["O2.Fy"]])
    _check_pin(F, -3.0, R2, (-1.0, 0.0))
    assert abs(eq["motor"] + 3.0 * R1 / R2) <= 1e-12  # as in inverse dynamics at rest


@pytest.mark.slow  # long: run by CI's slow set (its own gear pair's programs compiled)
def test_an_internal_pair_pushes_the_pinion_towards_the_rings_centre():
    """Ring (R2) and pinion (R1) inside it, the pinion's centre at (R2 - R1, 0): the pitch
    point at (R2, 0). The ring's pin carries |Fn| = T / (R2 cos alpha), holding the ring
    against its teeth pushed outwards; the pinion's the same force, pulling the pinion
    towards the pitch point (its teeth pushed in, towards the ring's centre)."""
    T = 2.0
    res = md.inverse(gear_pair(-T, internal=True), np.linspace(0.0, 0.5, 3))
    _check_pin(_pin(res, "O2"), -T, R2, (1.0, 0.0), ring=True)  # its pitch point along +x
    T1 = float(res["motor"][0])  # the motor's torque on the pinion
    _check_pin(_pin(res, "O1"), T1, R1, (1.0, 0.0))
    np.testing.assert_allclose(abs(T1), T * R1 / R2, rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set (its own gear pair's programs compiled)
def test_a_rack_and_pinion_loads_the_pin_and_the_guide_with_the_tooth_force():
    """A pinion (R) on a pin drives a rack on a horizontal guide below it against a force P
    along the rack: the pin carries |Fn| = P / cos(alpha), the guide the radial part
    P tan(alpha) (pushing the rack away from the pinion, down)."""
    R, P = 0.05, 40.0
    model = md.Model(
        bodies=[
            md.Body("pinion", 0.2, 1e-4, q0=(0.0, 0.0, 0.0)),
            md.Body("rack", 0.5, 1e-3, q0=(0.0, -R, 0.0), points={"P": (0.0, 0.0)}),
        ],
        joints=[
            md.Revolute("pin", "ground", "pinion"),
            md.Translational("guide", "ground", "rack", axis=(1, 0)),
            md.RackPinion("mesh", "pinion", "rack.P", R, pressure_angle=ALPHA),
        ],
        drivers=[md.CoordinateDriver("motor", "pinion", "phi", law=md.Ramp(0.0, 2.0))],
        forces=[md.PointForce("load", "rack", along=(1, 0), law=-P)],
        units=md.SI,
    )
    res = md.inverse(model, np.linspace(0.0, 0.5, 3))
    F = _pin(res, "pin")
    np.testing.assert_allclose(np.hypot(F[:, 0], F[:, 1]), P / math.cos(ALPHA), rtol=1e-9)
    # the teeth push the pinion up and the rack down: the pin holds the pinion down, the
    # guide the rack up
    np.testing.assert_allclose(F[:, 1], -P * math.tan(ALPHA), rtol=1e-9)
    np.testing.assert_allclose(res["guide.Fy"], P * math.tan(ALPHA), rtol=1e-9)
    np.testing.assert_allclose(np.abs(res["motor"]), P * R, rtol=1e-12)


def test_a_pin_in_mm_carries_the_same_force():
    """The external pair in mm-kg-s: the pin's force is the one in m-kg-s times 1000."""
    k = 1e3
    m_res = md.inverse(gear_pair(-3.0), np.linspace(0.0, 1.0, 3))
    mm = md.Model(
        bodies=[
            md.Body("g1", 0.1, 2e-4 * k**2, q0=(0.0, 0.0, 0.0)),
            md.Body("g2", 0.2, 4e-4 * k**2, q0=(k * (R1 + R2), 0.0, 0.0)),
        ],
        ground={"O1": (0.0, 0.0), "O2": (k * (R1 + R2), 0.0)},
        joints=[
            md.Revolute("O1", "ground.O1", "g1"),
            md.Revolute("O2", "ground.O2", "g2"),
            md.GearPair("mesh", "g1", "g2", k * R1, k * R2, pressure_angle=ALPHA),
        ],
        drivers=[md.CoordinateDriver("motor", "g1", "phi", law=md.Ramp(0.0, 5.0))],
        forces=[md.Torque("load", "g2", law=-3.0 * k**2)],
        units=md.UnitSystem("mm", "kg", "s"),
    )
    mm_res = md.inverse(mm, np.linspace(0.0, 1.0, 3))
    np.testing.assert_allclose(_pin(mm_res, "O2") / k, _pin(m_res, "O2"), rtol=1e-12)


def test_the_radial_force_leaves_the_motion_alone():
    """Forward dynamics of the free pair (a torque on gear 1 against the load): the motion is
    the one of the gears' reflected inertia, the energy balance holds, and the pins carry
    |Fn| at every output time."""
    model = gear_pair(-0.2).replace(drivers=())
    model = model.replace(forces=(*model.forces, md.Torque("drive", "g1", law=0.5)))
    t = np.linspace(0.0, 0.5, 6)
    res = md.forward(model, t, rtol=1e-10, atol=1e-12)
    k = R1 / R2  # gear 2 turns at -k times gear 1
    inertia = 2e-4 + 4e-4 * k**2
    alpha1 = (0.5 + 0.2 * k) / inertia  # the load -0.2 on gear 2 turning at -k w1 helps
    np.testing.assert_allclose(res["g1.phi"], 0.5 * alpha1 * t**2, rtol=1e-8, atol=1e-12)
    Ft = np.asarray(res["mesh.Ft"])
    F2 = _pin(res, "O2")
    np.testing.assert_allclose(
        np.hypot(F2[:, 0], F2[:, 1]), np.abs(Ft) / math.cos(ALPHA), rtol=1e-9
    )


def test_a_gear_whose_centre_slides_along_the_line_of_centres_is_refused():
    """Gear 2 in a slot along the line of centres: nothing holds the teeth together against
    their radial force: a named input error at the start, not a wrong reaction."""
    model = gear_pair(-3.0).replace(
        joints=(
            md.Revolute("O1", "ground.O1", "g1"),
            md.PinInSlot("O2", "ground.O2", "g2", axis=(1, 0)),
            md.GearPair("mesh", "g1", "g2", R1, R2, pressure_angle=ALPHA),
        ),
        drivers=(),
    )
    with pytest.raises(md.ModelError, match="no joint holds them apart") as err:
        md.forward(model, np.linspace(0.0, 0.1, 3))
    assert err.value.element == "mesh"


@pytest.mark.parametrize("kind", ["external", "internal", "rack"])
def test_the_separating_pair_is_the_gradient_of_the_separation(kind):
    """The NumPy unit pair that the start's check uses against autodiff of the traced
    separation, at a random pose with centres off the bodies' origins."""
    rng = np.random.default_rng(3)
    q0 = [(*rng.uniform(-0.3, 0.3, 2), rng.uniform(-1, 1)) for _ in range(2)]
    bodies = [
        md.Body("a", 1.0, 0.1, q0=q0[0], points={"c": (0.01, 0.02), "l": (0.0, -0.05)}),
        md.Body("b", 1.0, 0.1, q0=q0[1], points={"c": (-0.02, 0.01)}),
    ]
    if kind == "rack":
        joint = md.RackPinion("m", "b.c", "a.l", 0.05, axis=(0.6, 0.8))
    else:
        joint = md.GearPair(
            "m", "a", "b", 0.3, 0.1, internal=kind == "internal", center_i="a.c", center_j="b.c"
        )
    model = md.Model(bodies=bodies, joints=[joint], units=md.SI)
    (j,) = model.joints
    q = np.asarray(model.q0) + rng.normal(0.0, 0.05, 6)
    g = np.zeros(6)
    for b, at, force in j.separating_pair(q):
        r = at - q[3 * b : 3 * b + 2]
        g[3 * b : 3 * b + 3] += (force[0], force[1], r[0] * force[1] - r[1] * force[0])
    np.testing.assert_allclose(g, np.asarray(jax.grad(j.separation)(q)), rtol=0, atol=1e-13)
