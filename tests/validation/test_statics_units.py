"""Statics in any unit system (issue 31, part 2, item 1): the same mechanism written in m and
in mm reaches the same equilibrium, converted, and the same stability verdict and measure.

The truth is the mechanism itself: the equilibrium in mm is the one in m with every length
times 1000, every force times 1000 (kg*mm/s**2 is a millinewton) and every torque or energy
times 1e6 (kg*mm**2/s**2 is a micro-joule); angles, masses and times are the same numbers.
Newton's method from the same start must then take the same steps and stop at the same
point, and the reduced stiffness' eigenvalues (an energy: scaled coordinates x/L, y/L, phi)
must convert like a torque.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import four_bar_pose

G = 9.81
MM = md.UnitSystem(length="mm", mass="kg", time="s")
#: Length, force and energy factors from the m-kg-s to the mm-kg-s numbers.
K_LENGTH, K_FORCE, K_ENERGY = 1e3, 1e3, 1e6


def _units(k: float) -> md.UnitSystem:
    return md.SI if k == 1.0 else MM


def spring_four_bar(k: float, *, driven: bool) -> md.Model:
    """The spring-loaded four-bar of ``examples/statics_four_bar.yaml`` with its lengths in
    ``1/k`` m (k = 1: m, k = 1000: mm); free (``driven=False``) or turned by its crank."""
    a, b, c, d, theta0 = 0.2, 0.55, 0.4, 0.6, 1.2
    (ax, ay), (bx, by) = four_bar_pose(a, b, c, d, theta0)
    th3, th4 = math.atan2(by - ay, bx - ax), math.atan2(by, bx - d)
    drivers = (
        [md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.0, 2 * math.pi))]
        if driven
        else []
    )
    return md.Model(
        bodies=[
            md.Body(
                "crank",
                1.0,
                0.01 * k**2,
                q0=(k * ax / 2, k * ay / 2, theta0),
                points={"O": (-k * a / 2, 0), "A": (k * a / 2, 0)},
            ),
            md.Body(
                "coupler",
                1.0,
                0.01 * k**2,
                q0=(k * (ax + bx) / 2, k * (ay + by) / 2, th3),
                points={"A": (-k * b / 2, 0), "B": (k * b / 2, 0), "P": (0, k * b / 3)},
            ),
            md.Body(
                "rocker",
                1.0,
                0.01 * k**2,
                q0=(k * (d + bx) / 2, k * by / 2, th4),
                points={"O": (-k * c / 2, 0), "B": (k * c / 2, 0)},
            ),
        ],
        joints=[
            md.Revolute("O2", "ground.O2", "crank.O"),
            md.Revolute("A", "crank.A", "coupler.A"),
            md.Revolute("B", "coupler.B", "rocker.B"),
            md.Revolute("O4", "ground.O4", "rocker.O"),
        ],
        drivers=drivers,
        # stiffness in N/m is kg/s**2: the same number in both systems
        forces=[
            md.SpringDamper("spring", "ground.S", "coupler.P", stiffness=60.0, free_length=0.2 * k)
        ],
        ground={"O2": (0.0, 0.0), "O4": (k * d, 0.0), "S": (k * 0.1, k * 0.9)},
        gravity=(0.0, -G * k),
        units=_units(k),
    )


def loaded_slider_crank(k: float) -> md.Model:
    """A slider-crank with a free crank: a 2 N*m torque on the crank against a spring on the
    slider and gravity, lengths in ``1/k`` m."""
    r, l, th = 0.1, 0.3, 0.8
    beta = -math.asin(r * math.sin(th) / l)
    ax, ay = r * math.cos(th), r * math.sin(th)
    bx = ax + l * math.cos(beta)
    return md.Model(
        bodies=[
            md.Body(
                "crank",
                1.0,
                0.01 * k**2,
                q0=(k * ax / 2, k * ay / 2, th),
                points={"O": (-k * r / 2, 0), "A": (k * r / 2, 0)},
            ),
            md.Body(
                "rod",
                1.0,
                0.01 * k**2,
                q0=(k * (ax + bx) / 2, k * ay / 2, beta),
                points={"A": (-k * l / 2, 0), "B": (k * l / 2, 0)},
            ),
            md.Body("slider", 1.0, 0.01 * k**2, q0=(k * bx, 0.0, 0.0)),
        ],
        joints=[
            md.Revolute("O", "ground", "crank.O"),
            md.Revolute("A", "crank.A", "rod.A"),
            md.Revolute("B", "rod.B", "slider"),
            md.Translational("slide", "ground", "slider", axis=(1, 0)),
        ],
        forces=[
            md.Torque("T", "crank", law=2.0 * k**2),
            md.SpringDamper("spring", "ground.S", "slider", stiffness=500.0, free_length=0.45 * k),
        ],
        ground={"S": (0.6 * k, 0.0)},
        gravity=(0.0, -G * k),
        units=_units(k),
    )


def _in_m(column: str, value):
    """A result column of a model in mm-kg-s converted to m-kg-s."""
    kind = {"x": "length", "y": "length", "phi": "angle"}.get(column.rsplit(".", 1)[-1])
    if kind is None:
        kind = "torque" if column.endswith(".M") or column == "motor" else "force"
    factor = {"length": K_LENGTH, "angle": 1.0, "force": K_FORCE, "torque": K_ENERGY}[kind]
    return np.asarray(value) / factor


def _assert_same(eq_m, eq_mm, columns):
    for col in columns:
        a, b = eq_m[col], float(_in_m(col, eq_mm[col]))
        assert abs(b - a) <= 1e-9 * max(abs(a), 1e-6), (col, a, b)


@pytest.mark.parametrize(
    ("build", "columns", "stable"),
    [
        (
            lambda k: spring_four_bar(k, driven=False),
            ["crank.phi", "coupler.x", "rocker.y", "O2.Fx", "O2.Fy", "B.Fx", "O4.Fy"],
            True,
        ),
        (
            loaded_slider_crank,
            ["crank.phi", "slider.x", "rod.y", "O.Fx", "O.Fy", "slide.Fy", "slide.M"],
            False,
        ),
    ],
    ids=["spring-four-bar", "slider-crank"],
)
def test_the_equilibrium_in_mm_is_the_one_in_m(build, columns, stable):
    """Both converge (in mm they ended in ConvergenceError after 100 iterations: the line
    search weighed moment rows as forces and angle rows as lengths), to the same point, with
    the same stability verdict; the eigenvalues convert like an energy."""
    eq_m, eq_mm = md.statics(build(1.0)), md.statics(build(K_LENGTH))
    _assert_same(eq_m, eq_mm, columns)
    assert eq_m.stable is eq_mm.stable is stable
    assert eq_m.eigenvalues.size == eq_mm.eigenvalues.size == 1
    np.testing.assert_allclose(eq_mm.eigenvalues / K_ENERGY, eq_m.eigenvalues, rtol=1e-9)


def test_newton_takes_the_same_steps_in_mm_and_in_m():
    """From the same start (an assembled pose, converted) the iteration is the same: the same
    number of Newton steps and the same dimensionless residual measure, to rounding."""
    model_m = spring_four_bar(1.0, driven=False)
    start = md.statics(model_m, tol=1e300).q  # the assembled start (no Newton step)
    scale = np.tile([K_LENGTH, K_LENGTH, 1.0], model_m.nb)
    eq_m = md.statics(model_m, q0=start)
    eq_mm = md.statics(spring_four_bar(K_LENGTH, driven=False), q0=start * scale)
    assert eq_m.iterations == eq_mm.iterations
    assert eq_m.residual <= 1e-10 and eq_mm.residual <= 1e-10
    np.testing.assert_allclose(eq_mm.q / scale, eq_m.q, rtol=0, atol=1e-12)


def test_a_quasi_static_turn_in_mm_is_the_one_in_m():
    """The four-bar turned slowly through a revolution: the same motor torque (converted) at
    every crank angle, the same reactions, the same stability record."""
    t = np.linspace(0.0, 1.0, 25)
    res_m = md.quasi_static(spring_four_bar(1.0, driven=True), t)
    res_mm = md.quasi_static(spring_four_bar(K_LENGTH, driven=True), t)
    for col in ("crank.phi", "coupler.phi", "rocker.x", "motor", "O2.Fx", "A.Fy", "O4.Fx"):
        a, b = np.asarray(res_m[col]), _in_m(col, res_mm[col])
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-9 * np.max(np.abs(a)))
    assert res_m.stats["stable"] == res_mm.stats["stable"]
    assert res_m.stats["min_eigenvalue_unit"] == "kg*m**2/s**2"
    assert res_mm.stats["min_eigenvalue_unit"] == "kg*mm**2/s**2"


def test_the_stability_measure_of_a_pendulum_is_its_energy_curvature():
    """A pendulum hanging from its point O at (0, L) (so the model's length scale is L): along
    the one free motion in the scaled coordinates (x/L, y/L, phi), whose tangent has length
    sqrt(2), the eigenvalue is ``m g L cos(phi) / 2`` [energy], in either unit system."""
    L, m = 0.5, 2.0
    for k in (1.0, K_LENGTH):
        model = md.Model(
            bodies=[
                md.Body(
                    "bob", m, 0.01 * k**2, q0=(0.1 * k, -L * k, 0.2), points={"O": (0.0, L * k)}
                )
            ],
            joints=[md.Revolute("pin", "ground.O", "bob.O")],
            ground={"O": (0.0, 0.0)},
            gravity=(0.0, -G * k),
            units=_units(k),
        )
        eq = md.statics(model)
        assert abs(eq["bob.phi"]) <= 1e-12
        np.testing.assert_allclose(eq.eigenvalues / k**2, [m * G * L / 2], rtol=1e-12)
