"""Coulomb friction with stick and slip at a compliant contact (``md.ContactFriction``)
against closed forms.

A disk of radius ``R`` rests on an incline of angle ``theta`` (a ``circle_line_contact``),
started at the static penetration ``delta`` (Hertz: ``K delta**1.5 = m g cos(theta)``):

- its rotation held (a block): below the friction angle it sticks, not moving at all (a
  regularized friction creeps at the same slope), its friction ``m g sin(theta)``; above it,
  it slides at ``g (sin(theta) - mu cos(theta))``;
- free to turn: it rolls without slipping at ``g sin(theta) / (1 + I / (m r**2))``, ``r = R -
  delta / 2`` the distance from its centre to the contact point, its sliding speed zero, its
  friction ``I a / r**2``.

A block (a ``box_line_contact``, friction at each corner) rests on two of its corners:

- on the ground, pushed at the height of its contact points by ``P``: below ``mu m g`` its
  corners hold it with ``-P`` between them (their rows are the same: the split is shared and
  finite), the corners in the air take nothing; above, it accelerates at ``(P - mu m g) / m``
  with each corner at its limit ``mu m g / 2``; a sliding speed inside the band is halted;
- on an incline, started at rest on its corners' static penetrations: below the friction angle
  it stays (no creep), its friction ``m g sin(theta)`` and normal force ``m g cos(theta)``;
  above, it slides at ``g (sin(theta) - mu cos(theta))``; the energy balance holds;
- dropped on a corner with a sideways speed, it lands, rocks and comes to rest without creep
  (its energy balance held).

Bad declarations are refused by name, and the analyses without reaction-dependent forces
refuse it.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from mixdyn.analysis._problem import Problem
from mixdyn.equations import Constraints

G = 9.81
R = 0.02  # disk radius [m]
M = 0.5  # [kg]
E = 1e9  # Young's modulus [Pa]
LAW = dict(young_modulus=E, restitution=0.5, impact_speed=0.1)
TS = np.linspace(0.0, 0.4, 41)


def static_penetration(theta):
    """Hertz's penetration [m] under the normal load ``m g cos(theta)`` (poisson 0.3)."""
    K = 4.0 / 3.0 * E / (2 * (1 - 0.3**2)) * math.sqrt(R)
    return (M * G * math.cos(theta) / K) ** (2.0 / 3.0)


def disk_on_incline(theta, mu, held=True, friction="stick"):
    u = (math.cos(theta), math.sin(theta))
    n = np.array([-math.sin(theta), math.cos(theta)])  # out of the solid
    c = n * (R - static_penetration(theta))
    body = md.Body("disk", M, 0.5 * M * R**2, q0=(c[0], c[1], 0.0))
    if friction == "stick":
        forces = [
            md.CircleLineContact("floor", "disk", R, "ground", axis=u, **LAW),
            md.ContactFriction("grip", "floor", mu=mu, v_stick=1e-5),
        ]
    else:  # the contact's own regularized friction
        forces = [
            md.CircleLineContact("floor", "disk", R, "ground", axis=u, mu=mu, v_stick=1e-3, **LAW)
        ]
    drivers = [md.CoordinateDriver("hold", "disk", "phi", law=0.0)] if held else []
    return md.Model([body], drivers=drivers, forces=forces, gravity=(0.0, -G))


def down_the_slope(r, theta):
    """The distance travelled along the incline and the speed along it, over the outputs."""
    u = np.array([math.cos(theta), math.sin(theta)])
    x = np.stack([r["disk.x"], r["disk.y"]], axis=1)
    v = np.stack([r["disk.vx"], r["disk.vy"]], axis=1)
    return (x - x[0]) @ u, v @ u


def test_a_held_disk_sticks_below_the_friction_angle():
    theta, mu = math.radians(20.0), 0.5  # tan(theta) = 0.36 < mu
    r = md.forward(disk_on_incline(theta, mu), TS, rtol=1e-10, atol=1e-12)
    s, v = down_the_slope(r, theta)
    assert np.max(np.abs(s)) < 1e-12 and np.max(np.abs(v)) < 1e-12
    np.testing.assert_allclose(-r["grip"], M * G * math.sin(theta), rtol=1e-9)
    # the compliant normal force rests within the integrator's tolerance
    np.testing.assert_allclose(r["grip.normal"], M * G * math.cos(theta), rtol=1e-7)
    np.testing.assert_allclose(r["grip.limit"], mu * M * G * math.cos(theta), rtol=1e-7)
    assert r.units()["grip"] == "N" and r.units()["grip.speed"] == "m/s"


@pytest.mark.slow  # long: run by CI's slow set
def test_the_contacts_regularized_friction_creeps_where_contact_friction_sticks():
    theta, mu = math.radians(20.0), 0.5
    creep = md.forward(disk_on_incline(theta, mu, friction="tanh"), TS, rtol=1e-10)
    s_creep, _ = down_the_slope(creep, theta)
    assert s_creep[-1] < -1e-4  # it creeps downhill at ~v_stick atanh(tan(theta) / mu)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_held_disk_slides_above_the_friction_angle_at_g_sin_minus_mu_cos():
    theta, mu = math.radians(30.0), 0.3  # tan(theta) = 0.58 > mu
    r = md.forward(disk_on_incline(theta, mu), TS, rtol=1e-10, atol=1e-12)
    s, v = down_the_slope(r, theta)
    a = -G * (math.sin(theta) - mu * math.cos(theta))
    np.testing.assert_allclose(s[1:], 0.5 * a * TS[1:] ** 2, rtol=1e-7)
    np.testing.assert_allclose(v[1:], a * TS[1:], rtol=1e-7)
    # the column is the force on the disk along the tangent z x n = -u: uphill, negative;
    # mu N, N the compliant normal force (it vibrates by ~2e-6 while the disk slides)
    np.testing.assert_allclose(-r["grip"][1:], mu * M * G * math.cos(theta), rtol=1e-5)
    np.testing.assert_allclose(-r["grip"], mu * r["grip.normal"], rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
def test_a_free_disk_rolls_without_slipping():
    theta, mu = math.radians(30.0), 0.3  # rolls: tan(theta) < 3 mu
    r = md.forward(disk_on_incline(theta, mu, held=False), TS, rtol=1e-10, atol=1e-12)
    s, v = down_the_slope(r, theta)
    rr = R - static_penetration(theta) / 2  # centre to contact point
    inertia = 0.5 * M * R**2
    a = -G * math.sin(theta) / (1 + inertia / (M * rr**2))
    np.testing.assert_allclose(s[1:], 0.5 * a * TS[1:] ** 2, rtol=1e-6)
    np.testing.assert_allclose(r["disk.omega"][1:], -v[1:] / rr, rtol=1e-9)
    assert np.max(np.abs(r["grip.speed"])) < 1e-12
    np.testing.assert_allclose(-r["grip"][1:], inertia * -a / rr**2, rtol=1e-6)


# A block (width, height, corner radius [m], mass [kg]) on two of its corners.
BW, BH, BR, BM = 0.1, 0.05, 0.005, 1.0
BLOCK_INERTIA = BM * (BW**2 + BH**2) / 12


def corner_penetration(N):
    """Hertz's penetration [m] of a rounded corner under the normal load ``N`` [N]."""
    K = 4.0 / 3.0 * E / (2 * (1 - 0.3**2)) * math.sqrt(BR)
    return (np.asarray(N) / K) ** (2.0 / 3.0)


def pushed_block(P, mu):
    """The block flat on the ground (``y = 0``), each bottom corner at the penetration of
    ``m g / 2``, pushed along x by ``P`` at the height of its contact points (no moment)."""
    d = float(corner_penetration(BM * G / 2))
    body = md.Body(
        "block", BM, BLOCK_INERTIA, q0=(0.0, BH / 2 - d, 0.0), points={"foot": (0, d / 2 - BH / 2)}
    )
    forces = [
        md.BoxLineContact("floor", "block", BW, BH, BR, "ground", **LAW),
        md.ContactFriction("grip", "floor", mu=mu, v_stick=1e-5),
        md.PointForce("push", "block.foot", law=P),
    ]
    return md.Model([body], forces=forces, gravity=(0.0, -G))


@eqx.filter_jit
def _at_rest(problem, q, creep):
    """The accelerations, the rows' forces and the columns at rest, and the velocities after
    the halt from a creep ``(creep, 0, 0)`` inside the stick band."""
    st = problem.stages(q, jnp.zeros(3), 0.0)
    qd = jnp.array([creep, 0.0, 0.0])
    halted, _ = problem.halt_sticking(q, qd, jnp.zeros(2), 0.0, q, qd)
    return st.qdd, st.dependent[0], problem.dependent_columns(st), halted


def test_a_block_on_two_corners_holds_or_slides_on_its_corners_friction():
    mu = 0.5
    for P, holds in ((2.0, True), (7.0, False)):  # mu m g = 4.905 N
        model = pushed_block(P, mu)
        problem = Problem(model, Constraints.of(model))
        q = jnp.asarray(model.q0)
        qdd, rows, cols, halted = _at_rest(problem, q, 3e-6)
        rows = np.asarray(rows)
        assert rows.shape == (4,) and np.all(np.isfinite(rows))
        # corners 0, 1 (the top) touch nothing; 2, 3 share the force along z x n = -x
        assert rows[0] == 0.0 and rows[1] == 0.0
        np.testing.assert_allclose(cols["grip.normal"], BM * G, rtol=1e-12)
        if holds:
            np.testing.assert_allclose(rows[2:], [P / 2, P / 2], rtol=1e-12)
            np.testing.assert_allclose(cols["grip"], P, rtol=1e-12)
            np.testing.assert_allclose(qdd, 0.0, atol=1e-9)
            # the halt stops both bottom corners' sliding, which their rows share
            D = np.asarray(model.element("grip").relative_direction(model, q))
            np.testing.assert_allclose(D[:, 2:].T @ np.asarray(halted), 0.0, atol=1e-18)
        else:
            np.testing.assert_allclose(rows[2:], mu * BM * G / 2, rtol=1e-12)
            np.testing.assert_allclose(cols["grip"], mu * BM * G, rtol=1e-12)
            np.testing.assert_allclose(qdd[0], (P - mu * BM * G) / BM, rtol=1e-12)


def block_on_incline(theta, mu, slides):
    """The block on an incline rising along ``u = (cos theta, sin theta)``, at rest on its two
    lower corners at the penetrations of the normal loads that balance gravity and its
    friction (``m g sin(theta)`` shared by the corners while it sticks, ``mu N_k`` each while it
    slides) about its centre, with the block tilted by their difference."""
    a, b = BW / 2 - BR, BH / 2 - BR
    corner = np.array([[-a, -b], [a, -b]])  # the lower corners' centres, in the block
    normal = BM * G * math.cos(theta)
    N = np.full(2, normal / 2)
    for _ in range(6):  # the moments' arms move with the tilt
        delta = corner_penetration(N)
        tilt = math.asin((delta[0] - delta[1]) / (2 * a))
        c, s = math.cos(tilt), math.sin(tilt)
        arm_x = corner[:, 0] * c - corner[:, 1] * s  # contact points about the centre
        arm_y = corner[:, 0] * s + corner[:, 1] * c - BR + delta / 2
        f = mu * N if slides else np.full(2, BM * G * math.sin(theta) / 2)
        N = np.linalg.solve(np.stack([np.ones(2), arm_x]), [normal, arm_y @ f])
    delta = corner_penetration(N)
    tilt = math.asin((delta[0] - delta[1]) / (2 * a))
    height = BR - delta[0] + a * math.sin(tilt) + b * math.cos(tilt)
    n = np.array([-math.sin(theta), math.cos(theta)])
    body = md.Body("block", BM, BLOCK_INERTIA, q0=(*(height * n), theta + tilt))
    u = (math.cos(theta), math.sin(theta))
    forces = [
        md.BoxLineContact("floor", "block", BW, BH, BR, "ground", axis=u, **LAW),
        md.ContactFriction("grip", "floor", mu=mu, v_stick=1e-5),
    ]
    return md.Model([body], forces=forces, gravity=(0.0, -G))


def block_along(r, theta):
    u = np.array([math.cos(theta), math.sin(theta)])
    x = np.stack([r["block.x"], r["block.y"]], axis=1)
    v = np.stack([r["block.vx"], r["block.vy"]], axis=1)
    return (x - x[0]) @ u, v @ u


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_on_two_corners_sticks_on_an_incline_below_the_friction_angle():
    theta, mu = math.radians(20.0), 0.5
    r = md.forward(
        block_on_incline(theta, mu, False), np.linspace(0, 0.6, 31), rtol=1e-10, atol=1e-12
    )
    s, v = block_along(r, theta)
    assert np.max(np.abs(s)) < 1e-10 and np.max(np.abs(v)) < 1e-10
    np.testing.assert_allclose(-r["grip"], BM * G * math.sin(theta), rtol=1e-9)
    np.testing.assert_allclose(r["grip.normal"], BM * G * math.cos(theta), rtol=1e-9)
    assert r.stats["energy_balance_error"] < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_on_two_corners_slides_above_the_friction_angle_at_g_sin_minus_mu_cos():
    theta, mu = math.radians(30.0), 0.3
    TS = np.linspace(0, 0.4, 21)
    r = md.forward(block_on_incline(theta, mu, True), TS, rtol=1e-10, atol=1e-12)
    s, v = block_along(r, theta)
    a = -G * (math.sin(theta) - mu * math.cos(theta))
    np.testing.assert_allclose(s[1:], 0.5 * a * TS[1:] ** 2, rtol=1e-9)
    np.testing.assert_allclose(v[1:], a * TS[1:], rtol=1e-9)
    np.testing.assert_allclose(-r["grip"], mu * BM * G * math.cos(theta), rtol=1e-9)
    assert r.stats["energy_balance_error"] < 1e-9


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_dropped_on_a_corner_rocks_and_comes_to_rest_where_its_friction_stops_it():
    """Landing on one corner, then on two, it rocks on its corners while the friction holds
    them, slipping where it cannot (the corner in the air takes nothing); the run's energy
    balance holds, and once the rocking has died out it does not creep."""
    body = md.Body("block", BM, BLOCK_INERTIA, q0=(0.0, 0.035, math.radians(5.0)))
    forces = [
        md.BoxLineContact("floor", "block", BW, BH, BR, "ground", **LAW),
        md.ContactFriction("grip", "floor", mu=0.5, v_stick=1e-4),
    ]
    model = md.Model([body], forces=forces, gravity=(0.0, -G))
    TS = np.linspace(0.0, 0.5, 51)
    r = md.forward(model, TS, rtol=1e-8, atol=1e-10, qd0=np.array([0.2, 0.0, 0.0]))
    assert r.stats["energy_balance_error"] < 1e-6
    late = TS >= 0.35
    assert np.max(np.abs(r["grip.speed"][late])) < 1e-9
    assert np.ptp(r["block.x"][late]) < 1e-8
    assert 0.005 < r["block.x"][-1] < 0.02  # it slid while it landed (at 0.2 m/s for ~0.05 s)


@pytest.mark.parametrize(
    "forces, words",
    [
        ([md.ContactFriction("grip", "floor", mu=0.3)], "no force element 'floor'"),
        (
            [
                md.CircleLineContact("floor", "disk", R, "ground", mu=0.2, v_stick=1e-3, **LAW),
                md.ContactFriction("grip", "floor", mu=0.3),
            ],
            "has a friction of its own",
        ),
        (
            [
                md.CircleLineContact(
                    "floor", "disk", R, "ground", contact_model="rigid", restitution=0.5
                ),
                md.ContactFriction("grip", "floor", mu=0.3),
            ],
            "no compliant contact",
        ),
    ],
    ids=["unknown", "own-mu", "rigid"],
)
def test_bad_contact_friction_is_refused_by_name(forces, words):
    body = md.Body("disk", M, 1e-4, q0=(0.0, R, 0.0))
    with pytest.raises(md.ModelError, match=words) as e:
        md.Model([body], forces=forces)
    assert e.value.element == "grip"


def test_contact_friction_is_refused_where_it_is_not_modelled_and_read_from_a_file(tmp_path):
    model = disk_on_incline(0.3, 0.5)
    with pytest.raises(md.ModelError, match=r"contact friction \(grip\).*generalized-alpha"):
        md.forward(model, TS, method="generalized-alpha", dt=0.01)
    path = tmp_path / "disk.yaml"
    path.write_text(
        "mixdyn: 1\nunits: {length: m, mass: kg, time: s}\ngravity: [0, -9.81]\n"
        "bodies:\n  - {name: disk, mass: 0.5 kg, inertia: 1e-4 kg*m^2, q0: [0, 20 mm, 0]}\n"
        "forces:\n"
        "  - {type: circle_line_contact, name: floor, center: disk, radius: 20 mm,\n"
        "     line_point: ground, young_modulus: 1 GPa, restitution: 0.5, impact_speed: 0.1}\n"
        "  - {type: contact_friction, name: grip, contact: floor, mu: 0.4, v_stick: 1 mm/s}\n"
    )
    read = mio.load(path)
    grip = read.element("grip")
    assert isinstance(grip, md.ContactFriction) and grip.contact == "floor"
    assert float(grip.mu) == 0.4 and float(grip.v_stick) == pytest.approx(1e-3)
