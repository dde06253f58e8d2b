"""The force elements' result columns: a spring's length and tension, a point force's value
and each element's power, against the motion they come from (positions and velocities of
the result, Hooke's law, P = F . v), and their units."""

import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES, antonya_mixed, paper_under_loads, spring_slider

HOLD = ("crank.phi", "coupler.phi")


def test_spring_length_tension_and_power():
    model = spring_slider()
    res = md.forward(model, np.linspace(0, 0.5, 51), rtol=1e-10, atol=1e-12)
    x, v = res["slider.x"], res["slider.vx"]
    assert np.allclose(res["spring.length"], np.abs(x), rtol=1e-12)
    T = 800.0 * (np.abs(x) - 0.5) + 4.0 * np.sign(x) * v  # pulls the slider to the origin
    np.testing.assert_allclose(res["spring.tension"], T, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res["spring.power"], -T * np.sign(x) * v, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res["spring"], 0.0)  # no actuator
    units = res.units()
    assert (units["spring.tension"], units["spring.length"], units["spring.power"]) == (
        "N",
        "m",
        "W",
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_a_known_point_force_and_its_power_in_the_paper_mechanism():
    """F1 = 10 sin(pi t / 2) on the slider (the paper's forward run): its column is the law,
    its power F1 times the slider's speed along F1's direction."""
    model = paper_under_loads()
    res = md.forward(model, np.linspace(0, 1, 21), hold=HOLD, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(res["F1"], 10 * np.sin(np.pi * res.t / 2), atol=1e-12)
    np.testing.assert_allclose(res["F1.power"], res["F1"] * res["slider.vx"], atol=1e-10)
    assert res.kind_of("F1") == "force" and res.kind_of("F1.power") == "power"
    np.testing.assert_allclose(res["T3"], -500.0)
    np.testing.assert_allclose(res["T3.power"], -500.0 * res["coupler.omega"], atol=1e-9)
    assert res.units()["T3"] == "mN*mm" and res.units()["F1.power"] == "µW"


@pytest.mark.slow  # a long validation run (issue 12: the README's command within 6 min); CI runs it
def test_unknown_forces_keep_their_own_columns():
    """In a mixed run the unknown F1 is the solved magnitude (not the law): one column each."""
    model = paper_under_loads()
    t = np.linspace(0, 1, 11)
    fwd = md.forward(model, t, hold=HOLD, rtol=1e-10, atol=1e-12)
    mixed = antonya_mixed(model, t, fwd, hold=HOLD)
    assert list(mixed.columns()).count("F1") == 1
    # recovered from 11 samples of slider.x (a spline): to 0.03 % of the amplitude
    np.testing.assert_allclose(mixed["F1"], fwd["F1"], atol=3e-3)


@pytest.mark.parametrize("law", [0.0, 2.5])
def test_rotary_spring_torque_and_angle(law):
    model = md.Model(
        bodies=[md.Body("bar", 1.0, 0.1, q0=(0.5, 0.0, 0.0), points={"O": (-0.5, 0.0)})],
        joints=[md.Revolute("O", "ground", "bar.O")],
        forces=[
            md.RotarySpringDamper(
                "k", "ground", "bar", stiffness=20.0, damping=0.5, free_angle=0.3, actuator=law
            )
        ],
        units=md.SI,
    )
    res = md.forward(model, np.linspace(0, 0.4, 21), rtol=1e-10, atol=1e-12)
    phi, w = res["bar.phi"], res["bar.omega"]
    np.testing.assert_allclose(res["k.angle"], phi, atol=1e-12)
    tau = -20.0 * (phi - 0.3) - 0.5 * w + law
    np.testing.assert_allclose(res["k.torque"], tau, atol=1e-9)
    np.testing.assert_allclose(res["k.power"], tau * w, atol=1e-9)
    assert res.units()["k.torque"] == "N*m"


def test_force_arrows_in_a_file_are_checked_before_running(tmp_path):

    from typer.testing import CliRunner

    from mixdyn.cli import app

    text = (EXAMPLES / "four_bar.yaml").read_text()
    assert "forces: true}" in text
    for old, new, words in (
        ("forces: true}", "forces: [O2, Q4]}", "'Q4' is neither a joint nor a point force"),
        ("trace: [coupler.P]}", "trace: [coupler.P], forces: true}", "no forces to draw"),
    ):
        path = tmp_path / "bad.yaml"
        path.write_text(text.replace(old, new, 1))
        res = CliRunner().invoke(app, ["check", str(path)])
        assert res.exit_code == 2, res.output
        assert words in res.output
        if "Q4" in new:
            assert "O4" in res.output  # the close match
