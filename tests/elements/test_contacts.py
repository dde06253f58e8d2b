"""Gears, rack and pinion, rolling: equations against finite differences, and the mechanics
against closed forms — speed ratios (a gear train, Willis' planetary formula, a rack), the
torque ratio from the tooth force, energy in a frictionless train, a disk rolling down an
incline (acceleration 2/3 g sin(theta), normal force m g cos(theta)) and rolling inside a
ring (small-oscillation period 2 pi sqrt(3 (R - r) / (2 g)))."""

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES, evaluate, fd_gamma, fd_jacobian
from mixdyn.equations import Constraints
from mixdyn.runs import execute

G = 9.81


def _pair(kind, internal=False):
    """Two bodies with a contact joint of ``kind`` in a random pose, for the equations."""
    rng = np.random.default_rng([11, ["gear", "disks", "rack", "line"].index(kind), internal])
    bodies = [
        md.Body("i", 1.0, 0.1, q0=(0.0, 0.0, 0.3), points={"c": (0.1, -0.05)}),
        md.Body("j", 1.0, 0.1, q0=(0.7, 0.4, -0.2), points={"c": (-0.05, 0.02), "L": (0, -0.9)}),
        md.Body("arm", 1.0, 0.1, q0=(0.1, 0.1, 0.5)),
    ]
    if kind == "gear":
        joint = md.GearPair(
            "X",
            "i",
            "j",
            0.9 if internal else 0.3,
            0.2,
            internal=internal,
            carrier="arm",
            center_i="i.c",
            center_j="j.c",
        )
    elif kind == "disks":
        joint = md.RollingDisks(
            "X",
            "i",
            "j",
            0.9 if internal else 0.3,
            0.2,
            internal=internal,
            center_i="i.c",
            center_j="j.c",
        )
    elif kind == "rack":
        joint = md.RackPinion("X", "i", "j.L", radius=0.25, axis=(1.0, 0.3), center="i.c")
    else:
        joint = md.RollingOnLine("X", "i", "j.L", radius=0.25, axis=(1.0, 0.3), center="i.c")
    model = md.Model(bodies=bodies, joints=[joint], units=md.SI)
    return Constraints.of(model), rng


@pytest.mark.parametrize(
    ("kind", "internal"),
    [
        ("gear", False),
        ("gear", True),
        ("disks", False),
        ("disks", True),
        ("rack", False),
        ("line", False),
    ],
)
def test_contact_equations_against_finite_differences(kind, internal):
    c, rng = _pair(kind, internal)
    q0 = np.array([0.0, 0.0, 0.3, 0.7, 0.4, -0.2, 0.1, 0.1, 0.5])  # the bodies' q0
    for _ in range(3):
        q = q0 + rng.uniform(-0.2, 0.2, size=9)
        qd = rng.uniform(-2, 2, size=9)
        _, Phi_q, Phi_t, gamma = evaluate(c, q, qd, 0.3)
        np.testing.assert_allclose(Phi_q, fd_jacobian(c, q, 0.3), rtol=0, atol=1e-8)
        np.testing.assert_allclose(gamma, fd_gamma(c, q, qd, 0.3), rtol=1e-6, atol=1e-6)
        np.testing.assert_array_equal(Phi_t, np.zeros(c.m))


def _gear(name, mass, inertia, x, y, r, phi=0.0):
    return md.Body(name, mass, inertia, q0=(x, y, phi), points={"rim": (r, 0.0)})


def train(drive=None, load=0.0):
    """Three gears on ground pins in a line (radii 30, 60, 45 mm): 1 drives 2 (idler), 2
    drives 3. ``drive``: the motor law on gear 1's angle; ``load``: a torque on gear 3."""
    R = (0.03, 0.06, 0.045)
    x = (0.0, R[0] + R[1], R[0] + 2 * R[1] + R[2])
    bodies = [_gear(f"g{k + 1}", 0.1 * (k + 1), 2e-4 * (k + 1), x[k], 0.0, R[k]) for k in range(3)]
    return md.Model(
        bodies=bodies,
        ground={f"O{k + 1}": (x[k], 0.0) for k in range(3)},
        joints=[
            *[md.Revolute(f"O{k + 1}", f"ground.O{k + 1}", f"g{k + 1}") for k in range(3)],
            md.GearPair("m12", "g1", "g2", R[0], R[1]),
            md.GearPair("m23", "g2", "g3", R[1], R[2]),
        ],
        drivers=[] if drive is None else [md.CoordinateDriver("motor", "g1", "phi", law=drive)],
        forces=[md.Torque("load", "g3", law=load)] if load else [],
        units=md.SI,
    ), R


@pytest.mark.slow  # long: run by CI's slow set
def test_gear_train_speed_and_torque_ratios():
    model, R = train(md.Ramp(0.0, 12.0), load=-0.8)
    res = md.inverse(model, np.linspace(0, 1, 21))
    np.testing.assert_allclose(res["g2.omega"], -12.0 * R[0] / R[1], rtol=1e-12)
    np.testing.assert_allclose(res["g3.omega"], 12.0 * R[0] / R[2], rtol=1e-12)
    # At constant speed the motor holds the load through the train: T1 = -T3 R1 / R3, and
    # the tooth force on gear 3 balances the load about its pin: Ft R3 = -load.
    np.testing.assert_allclose(res["motor"], 0.8 * R[0] / R[2], rtol=1e-12)
    np.testing.assert_allclose(np.abs(res["m23.Ft"]) * R[2], 0.8, rtol=1e-12)
    np.testing.assert_allclose(np.abs(res["m12.Ft"]), np.abs(res["m23.Ft"]), rtol=1e-12)
    np.testing.assert_allclose(
        res["m12.Fn"], res["m12.Ft"] / math.cos(math.radians(20)), rtol=1e-12
    )
    # The pins carry the tooth forces: gear 3's pin pushes back on it.
    np.testing.assert_allclose(res["O3.Fy"], -res["m23.Ft"], rtol=1e-12)
    assert "m12.Fx" not in res.columns() and res.units()["m12.Ft"] == "N"


@pytest.mark.slow  # long: run by CI's slow set
def test_frictionless_train_keeps_its_energy_and_ratio():
    model, R = train()
    res = md.forward(model, np.linspace(0, 0.5, 26), qd0={"g1.phi": 20.0}, rtol=1e-10, atol=1e-12)
    E = res["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-9 * E[0]
    np.testing.assert_allclose(res["g3.omega"] / res["g1.omega"], R[0] / R[2], rtol=1e-9)
    inertia = [2e-4, 4e-4, 6e-4]
    w1 = 20.0
    E_exact = (
        0.5
        * w1**2
        * (inertia[0] + inertia[1] * (R[0] / R[1]) ** 2 + inertia[2] * (R[0] / R[2]) ** 2)
    )
    np.testing.assert_allclose(E[0], E_exact, rtol=1e-12)


def test_planetary_gear_follows_willis():
    """Sun driven, ring fixed (the ground), planet on a carrier arm: the arm turns at
    w_sun R_s / (R_s + R_r), the planet at (w_arm - w_sun) R_s / R_p + w_arm... by Willis."""
    Rs, Rp = 0.04, 0.02
    Rr = Rs + 2 * Rp
    a = Rs + Rp
    model = md.Model(
        bodies=[
            md.Body("sun", 0.2, 1e-4, q0=(0, 0, 0)),
            md.Body("arm", 0.1, 1e-4, q0=(a / 2, 0, 0), points={"O": (-a / 2, 0), "P": (a / 2, 0)}),
            md.Body("planet", 0.05, 1e-5, q0=(a, 0, 0)),
        ],
        joints=[
            md.Revolute("S", "ground", "sun"),
            md.Revolute("A", "ground", "arm.O"),
            md.Revolute("P", "arm.P", "planet"),
            md.GearPair("sun_planet", "sun", "planet", Rs, Rp, carrier="arm"),
            md.GearPair("ring_planet", "ground", "planet", Rr, Rp, internal=True, carrier="arm"),
        ],
        drivers=[md.CoordinateDriver("motor", "sun", "phi", law=md.Ramp(0.0, 10.0))],
        units=md.SI,
    )
    # a full turn of the arm and more: the line of centres turns with the carrier
    res = md.kinematic(model, np.linspace(0, 3.0, 61))
    w_arm = 10.0 * Rs / (Rs + Rr)
    np.testing.assert_allclose(res["arm.omega"], w_arm, rtol=1e-12)
    np.testing.assert_allclose(res["planet.omega"], w_arm - (10.0 - w_arm) * Rs / Rp, rtol=1e-12)
    assert res["arm.phi"][-1] > 2 * math.pi


def test_rack_moves_a_radius_per_radian():
    R = 0.05
    model = md.Model(
        bodies=[
            md.Body("pinion", 0.2, 1e-4, q0=(0, 0, 0)),
            md.Body("rack", 0.5, 1e-3, q0=(0.0, -R, 0.0), points={"P": (0.0, 0.0)}),
        ],
        joints=[
            md.Revolute("O", "ground", "pinion"),
            md.Translational("guide", "ground", "rack", axis=(1, 0)),
            md.RackPinion("mesh", "pinion", "rack.P", radius=R),
        ],
        drivers=[md.CoordinateDriver("motor", "pinion", "phi", law=md.Harmonic(0.7, 3.0))],
        units=md.SI,
    )
    res = md.inverse(model, np.linspace(0, 2, 41))
    # the pinion above the rack: turning counter-clockwise moves the rack along +x
    np.testing.assert_allclose(res["rack.x"], R * res["pinion.phi"], atol=1e-13)
    # the motor torque drives the rack's mass through the tooth force: T = R m a
    np.testing.assert_allclose(
        res["motor"], R * 0.5 * res["rack.ax"] + 1e-4 * res["pinion.alpha"], atol=1e-12
    )
    np.testing.assert_allclose(res["mesh.Ft"], 0.5 * res["rack.ax"], atol=1e-12)


def _incline(theta, r=0.1, m=2.0):
    u = (math.cos(theta), -math.sin(theta))  # down the slope
    n = (math.sin(theta), math.cos(theta))
    return md.Model(
        bodies=[
            md.Body(
                "disk", m, 0.5 * m * r**2, q0=(r * n[0], r * n[1], 0.0), points={"mark": (0.0, r)}
            )
        ],
        joints=[md.RollingOnLine("roll", "disk", "ground.O", radius=r, axis=u)],
        ground={"O": (0.0, 0.0)},
        gravity=(0.0, -G),
        units=md.SI,
    ), u


@pytest.mark.parametrize("theta_deg", [10.0, 30.0])
def test_disk_rolls_down_an_incline(theta_deg):
    th = math.radians(theta_deg)
    model, u = _incline(th)
    res = md.forward(model, np.linspace(0, 1, 11), rtol=1e-10, atol=1e-12)
    a = res["disk.ax"] * u[0] + res["disk.ay"] * u[1]
    np.testing.assert_allclose(a, 2 / 3 * G * math.sin(th), rtol=1e-9)
    np.testing.assert_allclose(res["roll.N"], 2.0 * G * math.cos(th), rtol=1e-9)
    np.testing.assert_allclose(res["roll.T"], -2.0 * G * math.sin(th) / 3, rtol=1e-9)
    s = res["disk.x"] * u[0] + res["disk.y"] * u[1]
    np.testing.assert_allclose(res["disk.phi"], -(s - s[0]) / 0.1, atol=1e-10)


@pytest.mark.slow  # long: run by CI's slow set
def test_disk_rolling_in_a_ring_has_the_pendulum_period():
    R, r, m = 0.5, 0.1, 1.0
    a0 = 0.02  # rad, small
    cx, cy = (R - r) * math.sin(a0), -(R - r) * math.cos(a0)
    model = md.Model(
        bodies=[md.Body("disk", m, 0.5 * m * r**2, q0=(cx, cy, 0.0))],
        joints=[md.RollingDisks("roll", "ground", "disk", R, r, internal=True)],
        gravity=(0.0, -G),
        units=md.SI,
    )
    period = 2 * math.pi * math.sqrt(3 * (R - r) / (2 * G))
    t = np.linspace(0, 2 * period, 2001)
    res = md.forward(model, t, rtol=1e-11, atol=1e-13)
    x = res["disk.x"]
    ups = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    times = t[ups] - x[ups] * (t[ups + 1] - t[ups]) / (x[ups + 1] - x[ups])
    assert len(times) >= 1
    downs = np.flatnonzero((x[:-1] > 0) & (x[1:] <= 0))
    tdown = t[downs] - x[downs] * (t[downs + 1] - t[downs]) / (x[downs + 1] - x[downs])
    half = np.diff(np.sort(np.concatenate([times, tdown])))
    np.testing.assert_allclose(2 * half, period, rtol=1e-4)
    assert np.all(res["roll.N"] > 0)


@pytest.mark.slow  # long: run by CI's slow set
def test_the_gear_train_file_and_its_round_trip():
    """examples/gear_train.yaml: the output turns at R1/R3 of the pinion, the rack at R3 per
    radian of the output, and at rest (t = 0.25, 0.75: zero speed... any time at zero
    acceleration) the motor holds the 20 N load: T = 20 N * R1; the file written back
    (``dump``) builds the same model."""
    import mixdyn.io as mio

    spec = mio.read(EXAMPLES / "gear_train.yaml")
    res = execute(spec)["inverse"]
    R1, R2, R3 = 20.0, 50.0, 35.0  # mm
    np.testing.assert_allclose(res["output.omega"], res["pinion.omega"] * R1 / R3, atol=1e-12)
    np.testing.assert_allclose(res["idler.omega"], -res["pinion.omega"] * R1 / R2, atol=1e-12)
    np.testing.assert_allclose(res["rack.vx"], R3 * res["output.omega"], atol=1e-9)  # rack below
    i = int(np.argmin(np.abs(res.t - 0.0)))  # the pinion's acceleration is 0 at t = 0
    np.testing.assert_allclose(res["motor"][i], 20_000.0 * R1, rtol=1e-9)  # mN*mm
    assert mio.reads(mio.dumps(spec)) == spec
    model = mio.build(spec)
    again = mio.build(mio.reads(mio.dumps(model)))  # a model written by describe()
    for a, b in zip(again.joints, model.joints, strict=True):
        assert type(a) is type(b) and a.name == b.name
        if hasattr(a, "c0"):
            np.testing.assert_allclose(a.c0, b.c0, atol=1e-12)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (("radius_i: R1, radius_j: R2}", "radius_i: -1, radius_j: R2}"), "not positive"),
        (("body_j: idler, radius_i: R1", "body_j: idlr, radius_i: R1"), "unknown body 'idlr'"),
        (("radius_j: R2}", "radius_j: R2, internal: true}"), "radius_i > radius_j"),
        (("forces: [mesh23, rack_mesh]", "forces: [mesh99]"), "neither a joint nor a point"),
    ],
)
def test_bad_contacts_in_files_are_refused_at_their_line(tmp_path, edit, words):
    from typer.testing import CliRunner

    from mixdyn.cli import app

    old, new = edit
    text = (EXAMPLES / "gear_train.yaml").read_text()
    assert old in text
    path = tmp_path / "bad.yaml"
    path.write_text(text.replace(old, new, 1))
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2 and words in res.output, res.output


def test_a_disk_held_on_an_incline_statics():
    """Statics: a disk held on a 30 degree incline by a torque: the normal force m g cos,
    the friction m g sin up the slope, the holding torque its moment m g sin r."""
    th, r, m = math.radians(30), 0.1, 2.0
    model, _ = _incline(th, r, m)
    model = md.Model(
        bodies=model.bodies,
        joints=model.joints,
        drivers=[md.CoordinateDriver("hold", "disk", "phi", law=0.0)],
        ground={"O": (0.0, 0.0)},
        gravity=(0.0, -G),
        units=md.SI,
    )
    res = md.statics(model)
    np.testing.assert_allclose(res["roll.N"], m * G * math.cos(th), rtol=1e-12)
    np.testing.assert_allclose(res["roll.T"], -m * G * math.sin(th), rtol=1e-12)
    np.testing.assert_allclose(res["hold"], m * G * math.sin(th) * r, rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set
def test_contact_forces_drawn_as_arrows_where_they_act():
    """The tooth force of a mesh at its pitch point, along the line of action (Ft along the
    tangent, Fr pushing the gears apart); a rolling disk's contact force at the contact point,
    N along the normal and T along the incline."""
    from mixdyn.viz.arrows import force_arrows

    model, R = train(md.Ramp(0.0, 12.0), load=-0.8)
    res = md.inverse(model, np.linspace(0, 1, 5))
    (a,) = force_arrows(res, ["m23"])
    x2 = R[0] + R[1]
    np.testing.assert_allclose(a["at"], np.tile([x2 + R[1], 0.0], (5, 1)), atol=1e-12)
    np.testing.assert_allclose(a["F"][:, 0], res["m23.Fr"], rtol=1e-12)  # g3 pushed along +x
    np.testing.assert_allclose(a["F"][:, 1], res["m23.Ft"], rtol=1e-12)
    np.testing.assert_allclose(np.hypot(*a["F"].T), np.abs(res["m23.Fn"]), rtol=1e-12)
    th = math.radians(30)
    model, u = _incline(th)
    roll = md.forward(model, np.linspace(0, 0.2, 3), rtol=1e-10, atol=1e-12)
    (b,) = force_arrows(roll, ["roll"])
    n = np.array([math.sin(th), math.cos(th)])
    centre = np.stack([roll["disk.x"], roll["disk.y"]], axis=1)
    np.testing.assert_allclose(b["at"], centre - 0.1 * n, atol=1e-12)
    F = roll["roll.N"][:, None] * n + roll["roll.T"][:, None] * np.asarray(u)
    np.testing.assert_allclose(b["F"], F, atol=1e-12)
    # the ground pushes the disk up with m g cos, and holds it back with m g sin / 3
    np.testing.assert_allclose(b["F"] @ n, 2.0 * G * math.cos(th), rtol=1e-9)


@pytest.mark.slow  # reverse mode through the integrator compiles for ~30 s; CI runs it
def test_gear_train_is_differentiable():
    """The motor torque of a train driven harmonically, as a JAX function of the gears'
    inertias (md.differentiable, inverse): T = (I1 + I2 (R1/R2)^2 + I3 (R1/R3)^2) alpha1
    (+ the load's share), so dT/dI3 = (R1/R3)^2 alpha1 exactly; and the forward run's final
    speed of gear 3 against central differences in I3."""
    import jax

    model, R = train(md.Harmonic(0.8, 5.0), load=-0.2)
    t = np.linspace(0, 1, 6)
    f, th0 = md.differentiable(model, t, ["g3.inertia", "g2.inertia"], analysis="inverse")
    J = np.asarray(jax.jacrev(lambda th: f(th)["motor"])(th0))
    alpha1 = -0.8 * 25.0 * np.sin(5.0 * t)
    np.testing.assert_allclose(J[:, 0], (R[0] / R[2]) ** 2 * alpha1, atol=1e-12)
    np.testing.assert_allclose(J[:, 1], (R[0] / R[1]) ** 2 * alpha1, atol=1e-12)
    # forward: the free train under the load alone, w1' = L k / I_eq (k = R1/R3, I_eq the
    # inertia seen by gear 1), so d(w3(T))/dI3 = -L k^4 T / I_eq^2
    free, _ = train(load=-0.2)
    T = 0.2
    g, p0 = md.differentiable(
        free, np.linspace(0, T, 3), ["g3.inertia"], qd0={"g1.phi": 20.0}, rtol=1e-11, atol=1e-13
    )
    d = float(jax.grad(lambda th: g(th)["qd"][-1, 8])(p0)[0])
    k = R[0] / R[2]
    I_eq = 2e-4 + 4e-4 * (R[0] / R[1]) ** 2 + 6e-4 * k**2
    assert d == pytest.approx(0.2 * k**4 * T / I_eq**2, rel=1e-7)
