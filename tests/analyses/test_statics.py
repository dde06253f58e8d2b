"""Statics (``md.statics``, issue 13): the equilibrium of a mechanism under its loads against
energy minimization done independently (scipy over the four-bar's closed-form poses), its
stability against the closed-form reduced stiffness of a pendulum (hanging: stable, inverted:
unstable), and the static force analysis against the virtual-work result."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import mixdyn as md
from fixtures import (
    EXAMPLES,
    four_bar,
    four_bar_pose,
    pendulum,
    pushed_spring_slider,
    slider_crank,
)

G = 9.81


@pytest.mark.parametrize(
    ("start", "phi", "stable"), [(0.3, 0.0, True), (math.pi - 0.2, math.pi, False)]
)
def test_a_pendulum_hangs_stably_and_balances_unstably(start, phi, stable):
    L, m = 0.5, 2.0
    eq = md.statics(pendulum(L, m, 0.01, start, g=G))
    assert abs(eq["bob.phi"] - phi) <= 1e-9
    assert eq.stable is stable
    # along the one free motion, in the scaled coordinates (x/L, y/L, phi) (the model's length
    # scale is L, the pin's offset): d2V/dphi2 / |d(x/L, y/L, phi)/dphi|^2, the tangent's
    # length squared 2
    k = m * G * L * math.cos(phi) / 2
    np.testing.assert_allclose(eq.eigenvalues, [k], rtol=1e-9)
    assert abs(eq["pin.Fy"] - m * G) <= 1e-9 * m * G and abs(eq["pin.Fx"]) <= 1e-9


def _spring_four_bar():
    base = four_bar(theta0=1.2)
    spring = md.SpringDamper("spring", "ground.S", "coupler.P", stiffness=60.0, free_length=0.2)
    return base.replace(
        drivers=(),
        forces=(spring,),
        ground={"O2": (0.0, 0.0), "O4": (0.6, 0.0), "S": (0.1, 0.9)},
        gravity=(0.0, -G),
    )


def _potential(theta):
    """The spring-loaded four-bar's potential energy at crank angle theta, from the closed-form
    pose (fixtures.four_bar_pose), not from mixdyn."""
    a, b, c, d = 0.2, 0.55, 0.4, 0.6
    (ax, ay), (bx, by) = four_bar_pose(a, b, c, d, theta)
    th3 = math.atan2(by - ay, bx - ax)
    com = [(ax / 2, ay / 2), ((ax + bx) / 2, (ay + by) / 2), ((d + bx) / 2, by / 2)]
    px = com[1][0] - math.sin(th3) * b / 3
    py = com[1][1] + math.cos(th3) * b / 3
    spring = 0.5 * 60.0 * (math.hypot(px - 0.1, py - 0.9) - 0.2) ** 2
    return sum(1.0 * G * y for _, y in com) + spring


def test_a_spring_loaded_four_bar_rests_where_its_energy_is_least():
    eq = md.statics(_spring_four_bar())
    truth = minimize_scalar(
        _potential, bounds=(1.5, 3.0), method="bounded", options={"xatol": 1e-12}
    )
    assert abs(eq["crank.phi"] - truth.x) <= 1e-6
    assert eq.stable and len(eq.eigenvalues) == 1 and eq.eigenvalues[0] > 0


def test_the_static_efforts_are_the_virtual_work_ones():
    """A slider-crank held at 1 rad against a 100 N force on the slider: the motor torque is
    ``-P dx/dtheta`` (virtual work); the slider's guide carries no x force."""
    r, l, theta, P = 0.1, 0.3, 1.0, -100.0
    base = slider_crank(r, l, theta0=theta)
    model = base.replace(forces=(md.PointForce("P", "slider", along=(1, 0), law=P),))
    eq = md.statics(model)
    s, c = math.sin(theta), math.cos(theta)
    dx = -r * s - r**2 * s * c / math.sqrt(l**2 - (r * s) ** 2)
    assert abs(eq["motor"] - (-P * dx)) <= 1e-9 * abs(P * dx)
    assert abs(eq["crank.phi"] - theta) <= 1e-12  # the driver holds it
    assert eq.eigenvalues.size == 0 and eq.stable  # no free degree of freedom


def test_an_unbalanced_load_has_no_equilibrium():
    """A block on a guide pushed along it: no position balances the push (a slider-crank
    would rest at a dead point)."""
    model = md.Model(
        bodies=[md.Body("block", 1.0, 0.01, q0=(0.0, 0.0, 0.0))],
        joints=[md.Translational("guide", "ground", "block", axis=(1, 0))],
        forces=[md.PointForce("push", "block", along=(1, 0), law=5.0)],
        units=md.SI,
    )
    with pytest.raises(md.ConvergenceError, match="no equilibrium"):
        md.statics(model, max_iter=30)


def test_loads_that_balance_at_the_start_keep_their_size():
    """A slider held by a spring (k = 800 N/m, free length 0.5 m) against a push of 20 N,
    no gravity: from the second time on the start is the equilibrium, where the loads sum
    to zero; the residual is still measured against the loads' size, so each time rests at
    x = 0.5 + F/k (closed form) in no Newton step rather than failing."""
    model = pushed_spring_slider()
    res = md.quasi_static(model, np.linspace(0.0, 1.0, 4))
    np.testing.assert_allclose(res["slider.x"], 0.5 + 20.0 / 800.0, rtol=1e-12)


def test_the_quasi_static_torque_is_the_energys_slope():
    """Driven slowly, the spring-loaded four-bar needs the motor torque ``dV/dtheta`` (virtual
    work), the potential from the closed-form poses, differentiated by central differences."""
    base = _spring_four_bar()
    model = base.replace(
        drivers=(md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(1.2, 1.0)),)
    )
    t = np.linspace(0.0, 1.5, 7)
    res = md.quasi_static(model, t)
    for theta, torque in zip(res["crank.phi"], res["motor"], strict=True):
        h = 1e-5
        dV = (_potential(theta + h) - _potential(theta - h)) / (2 * h)
        assert abs(torque - dV) <= 1e-6 * max(abs(dV), 1.0), (theta, torque, dV)
    assert res.stats["stable"] and res.kind == "statics"


def test_the_example_file_rests_where_its_turning_torque_vanishes(tmp_path):
    from typer.testing import CliRunner

    from mixdyn.cli import app

    path = EXAMPLES / "statics_four_bar.yaml"
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out)])
    assert res.exit_code == 0, res.output
    rest = md.read_table(out / "rest")
    turning = md.read_table(out / "turning")
    phi, torque = turning["crank.phi"].to_numpy(), turning["motor"].to_numpy()
    k = int(np.argmax((torque[:-1] < 0) & (torque[1:] >= 0)))  # the stable zero (rising)
    zero = phi[k] - torque[k] * (phi[k + 1] - phi[k]) / (torque[k + 1] - torque[k])
    assert abs(zero - rest["crank.phi"][0]) <= 5e-3  # linear interpolation over 5 degrees
    assert (out / "turning" / "motor_torque.png").stat().st_size > 10_000


def test_a_sweep_of_equilibria_equals_the_single_ones():
    """``md.sweep(..., analysis="statics")``: each member's equilibrium is the single one; a
    stiffer spring moves the rest position."""
    model = _spring_four_bar()
    sw = md.sweep(model, [0.0], vary={"spring.stiffness": [40.0, 60.0, 80.0]}, analysis="statics")
    rests = []
    for i, k in enumerate((40.0, 60.0, 80.0)):
        single = md.statics(
            model.replace(
                forces=(
                    md.SpringDamper(
                        "spring", "ground.S", "coupler.P", stiffness=k, free_length=0.2
                    ),
                )
            )
        )
        assert abs(sw[i]["crank.phi"][0] - single["crank.phi"]) <= 1e-12
        rests.append(single["crank.phi"])
    assert len(set(np.round(rests, 6))) == 3
