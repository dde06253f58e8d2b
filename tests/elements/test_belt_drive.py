"""The belt drive (``md.BeltDrive``), against the geometry of a belt around two pulleys.

The truth is computed here from the spans themselves: each span is a common tangent of the two
pitch circles (the outer tangents for an open belt, the inner ones for a crossed belt), its
tension acting along it at its tangent points. The tight span is the one whose tension turns
the driven pulley against its load; with the tension at rest ``T0`` in each span, ``T_tight +
T_slack = 2 T0``. The pins must carry the vector sum of both spans' forces on each pulley.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES

R1, R2, C = 0.1, 0.05, 0.4  # pulley radii and centre distance [m]
LOAD = -2.0  # torque on pulley 2 [N m]
RATE = 3.0  # pulley 1's speed [rad/s]


def belt_model(crossed: bool, T0: float, load: float = LOAD) -> md.Model:
    return md.Model(
        bodies=[
            md.Body("p1", mass=2.0, inertia=0.01, q0=(0.0, 0.0, 0.0)),
            md.Body("p2", mass=1.0, inertia=0.002, q0=(C, 0.0, 0.0)),
        ],
        joints=[
            md.Revolute("O1", "ground", "p1"),
            md.Revolute("O2", ("ground", (C, 0.0)), "p2"),
            md.BeltDrive(
                "belt", "p1", "p2", radius_i=R1, radius_j=R2, crossed=crossed, initial_tension=T0
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "p1", "phi", law=md.Ramp(0.0, RATE))],
        forces=[md.Torque("load", "p2", law=load)],
        gravity=(0.0, 0.0),
    )


def spans(crossed: bool) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The two spans: ``(point on pulley 1, point on pulley 2, unit direction from 2 to 1)``,
    common tangents of the pitch circles (pulley 1 at the origin, pulley 2 at (C, 0))."""
    c1, c2 = np.zeros(2), np.array([C, 0.0])
    e, t = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    sin_b = (R1 + R2) / C if crossed else (R1 - R2) / C
    cos_b = math.sqrt(1.0 - sin_b**2)
    out = []
    for side in (1.0, -1.0):
        n = sin_b * e + side * cos_b * t  # the tangent's normal, from pulley 1's centre
        p1 = c1 + R1 * n
        p2 = c2 - R2 * n if crossed else c2 + R2 * n
        u = (p1 - p2) / np.linalg.norm(p1 - p2)
        assert abs(np.dot(p1 - c1, u)) < 1e-12 and abs(np.dot(p2 - c2, u)) < 1e-12  # tangent
        out.append((p1, p2, u))
    return out


def cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


@pytest.mark.parametrize("crossed", [False, True])
@pytest.mark.parametrize("T0", [0.0, 50.0])
def test_speeds_tensions_and_pin_loads_follow_the_spans(crossed, T0):
    r = md.inverse(belt_model(crossed, T0), np.linspace(0.0, 0.5, 6))
    df = r.table()
    w1, w2 = df["p1.omega"].to_numpy(), df["p2.omega"].to_numpy()
    np.testing.assert_allclose(w2, (-1.0 if crossed else 1.0) * w1 * R1 / R2, rtol=1e-12)
    # The belt turns pulley 2 against its load: the spans' torques on it sum to -LOAD.
    need = -LOAD
    torques = [cross(p2 - np.array([C, 0.0]), u) for _, p2, u in spans(crossed)]
    dT = need / R2  # tension difference
    tight = int(np.argmax([np.sign(need) * tq for tq in torques]))
    T_tight = T0 + dT / 2 if T0 > 0 else dT
    T_slack = T0 - dT / 2 if T0 > 0 else 0.0
    tensions = [T_slack, T_slack]
    tensions[tight] = T_tight
    assert abs(sum(T * tq for T, tq in zip(tensions, torques, strict=True)) - need) < 1e-12
    np.testing.assert_allclose(np.abs(df["belt.F"]), dT, rtol=1e-12)
    np.testing.assert_allclose(df["belt.T_tight"], T_tight, rtol=1e-12)
    np.testing.assert_allclose(df["belt.T_slack"], T_slack, rtol=1e-12, atol=1e-12)
    # the motor holds the belt on pulley 1: the spans' torques there
    on_1 = sum(T * cross(p1, -u) for T, (p1, _, u) in zip(tensions, spans(crossed), strict=True))
    np.testing.assert_allclose(df["motor"], -on_1, rtol=1e-12)
    # The pins carry both spans' forces: on pulley 2 along u (towards pulley 1), on pulley 1
    # the opposite. Reactions: the force of the ground on the pulley.
    F2 = sum(T * u for T, (_, _, u) in zip(tensions, spans(crossed), strict=True))
    for pin, F in (("O2", F2), ("O1", -F2)):
        got = np.stack([df[f"{pin}.Fx"], df[f"{pin}.Fy"]], axis=1)
        np.testing.assert_allclose(got, np.tile(-F, (len(df), 1)), rtol=1e-9, atol=1e-9)


def test_free_pulleys_keep_their_energy_and_ratio():
    """Two pulleys coupled by the belt, spun and left alone: the kinetic energy stays (the
    belt does no work) and the speeds keep the ratio of the radii."""
    model = md.Model(
        bodies=[
            md.Body("p1", mass=2.0, inertia=0.01, q0=(0.0, 0.0, 0.0)),
            md.Body("p2", mass=1.0, inertia=0.002, q0=(C, 0.0, 0.0)),
        ],
        joints=[
            md.Revolute("O1", "ground", "p1"),
            md.Revolute("O2", ("ground", (C, 0.0)), "p2"),
            md.BeltDrive("belt", "p1", "p2", radius_i=R1, radius_j=R2, initial_tension=20.0),
        ],
        gravity=(0.0, 0.0),
    )
    r = md.forward(model, np.linspace(0.0, 2.0, 21), qd0={"p1.phi": 5.0}, rtol=1e-11, atol=1e-11)
    df = r.table()
    np.testing.assert_allclose(df["p2.omega"], 5.0 * R1 / R2, rtol=1e-9)
    energy = 0.5 * 0.01 * df["p1.omega"] ** 2 + 0.5 * 0.002 * df["p2.omega"] ** 2
    np.testing.assert_allclose(energy, energy.iloc[0], rtol=1e-10)


def test_a_belt_that_would_push_slips():
    """A load whose tension difference exceeds twice the tension at rest makes the slack span
    push: the run stops with the belt named."""
    with pytest.raises(md.errors.ContactLostError, match="belt"):
        md.inverse(belt_model(False, T0=5.0), np.linspace(0.0, 0.2, 3))


def test_bad_numbers_are_named():
    with pytest.raises(md.errors.ModelError, match="initial_tension"):
        md.BeltDrive("b", "p1", "p2", radius_i=R1, radius_j=R2, initial_tension=-1.0)
    with pytest.raises(md.errors.ModelError, match="radius"):
        md.BeltDrive("b", "p1", "p2", radius_i=0.0, radius_j=R2)


def test_the_example_file_runs_and_writes_back():
    """The example's spindle belt: its tensions from the cutting torque, and the file read,
    written and read again gives the same mechanism."""
    path = EXAMPLES / "belt_drive.yaml"
    spec = mio.read(path)
    model = mio.build(spec)
    (belt,) = [j for j in model.joints if isinstance(j, md.BeltDrive)]
    assert float(belt.radius_i) == 60.0 and float(belt.initial_tension) == 400e3  # mN
    again = mio.build(mio.reads(mio.dumps(model)))
    (belt2,) = [j for j in again.joints if isinstance(j, md.BeltDrive)]
    assert float(belt2.initial_tension) == float(belt.initial_tension)
    assert belt2.crossed == belt.crossed
    r = md.inverse(model, np.linspace(0.0, 0.01, 3))
    df = r.table()
    dT = 30e6 / 150.0  # 30 N m on a 150 mm pulley [mN]
    np.testing.assert_allclose(df["belt.T_tight"], 400e3 + dT / 2, rtol=1e-12)
    np.testing.assert_allclose(df["belt.T_slack"], 400e3 - dT / 2, rtol=1e-12)
