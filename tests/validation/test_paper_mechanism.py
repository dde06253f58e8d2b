"""The paper's worked example (``shared/paper/README.md``, section 3): structure, assembly
from the printed rounded coordinates, and a two-driver kinematic run against closed form."""

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import PAPER_COM, PAPER_INERTIA, PAPER_MASS, paper_mechanism

HOLD = ("crank.phi", "coupler.phi")
H_EXACT = 25 * math.sin(math.pi / 3)  # printed as 21.6506
NAMES = ("crank", "coupler", "link", "slider")


def rot(phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])


def body_point(model, q, ref):
    """Global position of ``"body.point"`` computed here, independently of mixdyn."""
    body, point = ref.split(".")
    if body == "ground":
        return np.asarray(model.ground.points[point])
    b = model.body_index(body)
    s = np.asarray(model.bodies[b].points[point])
    return q[3 * b : 3 * b + 2] + rot(q[3 * b + 2]) @ s


def joint_violations(model, q):
    """Largest violation [mm] of every joint, computed from the geometry alone."""
    out = {}
    for name in "ABCD":
        j = model.element(name)
        out[name] = np.max(
            np.abs(body_point(model, q, j.point_i) - body_point(model, q, j.point_j))
        )
    # slider E on the ground line y = y_E, slider parallel to the ground
    y_line = float(model.ground.points["E"][1])
    out["EF"] = max(abs(body_point(model, q, "slider.E")[1] - y_line), abs(q[11]))
    return out


def test_model_matches_the_paper_table():
    model = paper_mechanism()
    assert model.nq == 12
    assert model.n_joint_equations == 10
    assert model.units == md.UnitSystem("mm", "kg", "s")
    np.testing.assert_allclose(
        model.mass_diagonal,
        np.concatenate([[PAPER_MASS[n], PAPER_MASS[n], PAPER_INERTIA[n]] for n in NAMES]),
    )
    assert PAPER_MASS["crank"] == 0.0221 and PAPER_INERTIA["slider"] == 50.63
    # The printed start closes every joint to the printed precision (1e-4 mm).
    q0 = np.asarray(model.q0)
    assert max(joint_violations(model, q0).values()) < 1e-4


def test_degrees_of_freedom():
    model = paper_mechanism()
    q = md.assemble(model, hold=HOLD).q
    report = md.degrees_of_freedom(model, q)
    assert (report.n_coordinates, report.n_equations, report.rank, report.dof) == (12, 10, 10, 2)
    assert report.redundant == ()
    assert report.n_drivers == 0 and not report.balanced


@pytest.mark.parametrize("exact", [False, True], ids=["printed", "exact"])
def test_assembly_closes_every_joint(exact):
    model = paper_mechanism(exact=exact)
    asm = md.assemble(model, hold=HOLD)
    assert asm.residual <= 1e-10
    violations = joint_violations(model, asm.q)
    assert max(violations.values()) <= 1e-10, violations


def test_assembled_centres_of_mass_are_exact():
    """With the exact point table the assembled start is the paper's, unrounded:
    ``link`` at ``(62.5, 50 - 25 sin 60)``, ``slider`` at ``(80, 50 - 50 sin 60)``."""
    model = paper_mechanism(exact=True)
    q = md.assemble(model, hold=HOLD).q.reshape(4, 3)
    exact = np.array(
        [[0, 25, 0], [25, 50, 0], [62.5, 50 - H_EXACT, 0], [80, 50 - 2 * H_EXACT, 0]], dtype=float
    )
    np.testing.assert_allclose(q, exact, rtol=0, atol=1e-10)
    # and the printed coordinates are these, rounded to 4 decimals
    printed = np.array([PAPER_COM[n] for n in NAMES])
    np.testing.assert_allclose(printed, exact[:, :2], rtol=0, atol=0.5e-4)


def test_assembly_keeps_the_held_coordinates():
    """Held coordinates stay at their starting values (to the assembly tolerance, 1e-10)."""
    model = paper_mechanism()
    q0 = np.asarray(model.q0).copy()
    q0[2], q0[5] = 0.02, -0.03  # start crank and coupler slightly turned
    q = md.assemble(model, q0, hold=HOLD).q
    assert q[2] == pytest.approx(0.02, abs=1e-10)
    assert q[5] == pytest.approx(-0.03, abs=1e-10)
    assert max(joint_violations(model, q).values()) <= 1e-10


def test_assembled_centres_of_mass_with_the_printed_table():
    """With the printed (rounded) table and the crank and coupler held at 0, the link turns a
    little so that ``D`` reaches the ground line: solve ``25 sin p - 2h cos p = y_E - 50``
    for the link angle ``p`` (``h = 21.6506``)."""
    h, y_line = 21.6506, 6.6987
    R = math.hypot(25.0, 2 * h)
    p = math.atan2(2 * h, 25.0) + math.asin((y_line - 50.0) / R)
    C = np.array([50.0, 50.0])
    link = C - rot(p) @ np.array([-12.5, h])
    D = C + rot(p) @ np.array([25.0, -2 * h])
    assert D[1] == pytest.approx(y_line, abs=1e-12)
    expected = np.array(
        [[0, 25, 0], [25, 50, 0], [link[0], link[1], p], [D[0] + 5, y_line, 0]], dtype=float
    )
    q = md.assemble(paper_mechanism(), hold=HOLD).q.reshape(4, 3)
    np.testing.assert_allclose(q, expected, rtol=0, atol=1e-10)


def test_two_driver_kinematics_against_closed_form():
    """Crank turning at ``w`` and coupler kept level: ``C = (50 - 50 sin th, 50 cos th)``, and
    the link and slider form a slider-crank with ``D`` on the ground line."""
    w = 0.5
    model = paper_mechanism(
        exact=True,
        drivers=[
            md.CoordinateDriver("crank angle", "crank", "phi", law=md.Ramp(0.0, w)),
            md.RelativeAngleDriver("coupler level", "crank", "coupler", law=md.Ramp(0.0, -w)),
        ],
    )
    t = np.linspace(0.0, 1.0, 51)  # crank from 0 to 0.5 rad
    res = md.kinematic(model, t)
    th = w * t
    cx, cy = 50 - 50 * np.sin(th), 50 * np.cos(th)
    cxd, cyd = -50 * w * np.cos(th), -50 * w * np.sin(th)
    y_line = 50 - 2 * H_EXACT
    ell = 50.0  # C to D on the link
    dy = cy - y_line
    root = np.sqrt(ell**2 - dy**2)
    slider_x = cx + root + 5.0
    slider_v = cxd - dy * cyd / root
    np.testing.assert_allclose(res["coupler.phi"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["coupler.x"], cx - 25, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["slider.x"], slider_x, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["slider.vx"], slider_v, rtol=0, atol=1e-9)
    np.testing.assert_allclose(res["slider.y"], y_line, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res["link.phi"], np.arctan2(-dy, root) + math.pi / 3, atol=1e-12)
