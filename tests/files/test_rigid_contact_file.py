"""A rigid contact in a model file: a forward or mixed run by a fixed-step method, or with a
fixed step, is refused by ``mixdyn check`` and by ``mixdyn run`` before computing (exit 2,
the line of the method or step, the contact named, with the fix; a mixed run by the
projection method takes its impacts: ``tests/validation/test_mixed_impacts.py``)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from mixdyn.cli import app

BALL = """\
mixdyn: 1
name: bouncing-ball
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81 m/s^2]
ground:
  points: {O: [0, 0]}
bodies:
  - {name: ball, mass: 0.1 kg, inertia: 1.0e-5, q0: [0, 1.05, 0]}
forces:
  - {type: circle_line_contact, name: floor, center: ball, radius: 50 mm,
     line_point: ground.O, contact_model: rigid, restitution: 0.8}
  - {type: point_force, name: push, point: ball, along: [1, 0], law: "0"}
runs:
  - name: drop
    kind: mixed
    prescribed: [{coordinate: ball.x, law: "0"}]
    unknown: [push]
    method: baumgarte
    dt: 1 ms
    time: {span: [0, 2], n: 201}
"""


@pytest.mark.parametrize(
    "old, new, line, words",
    [
        ("", "", 18, "rigid contacts are integrated with the projection method, not baumgarte"),
        ("    method: baumgarte\n", "", 18, "rigid contacts need the adaptive steps"),
        (
            '    kind: mixed\n    prescribed: [{coordinate: ball.x, law: "0"}]\n'
            "    unknown: [push]\n",
            "    kind: forward\n",
            16,
            "rigid contacts are integrated with the projection method, not baumgarte",
        ),
    ],
    ids=["mixed by baumgarte", "mixed with dt", "forward by baumgarte"],
)
@pytest.mark.parametrize("command", ["check", "run"])
def test_a_rigid_contact_needs_the_projection_methods_adaptive_steps(
    tmp_path, command, old, new, line, words
):
    path = tmp_path / "ball.yaml"
    path.write_text(BALL.replace(old, new) if old else BALL)
    out = tmp_path / "out"
    args = [command, str(path)] + (["--out", str(out)] if command == "run" else [])
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    assert f"ball.yaml:{line}: run 'drop'" in res.output
    assert f"floor: {words}" in res.output
    assert not out.exists()  # refused before anything ran


PLASTIC = """\
mixdyn: 1
name: plastic-ball
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81 m/s^2]
ground:
  points: {O: [0, 0]}
bodies:
  - {name: ball, mass: 0.1 kg, inertia: 1.0e-5, q0: [0, 0.25, 0]}
forces:
  - {type: circle_line_contact, name: floor, center: ball, radius: 50 mm,
     line_point: ground.O, contact_model: rigid, restitution: 0}
runs:
  - name: drop
    kind: forward
    time: {span: [0, 0.5], n: 11}
"""


def test_a_plastic_rigid_contact_runs_and_a_plastic_compliant_one_is_refused(tmp_path):
    """``restitution: 0`` on a rigid contact: the ball dropped from 0.2 m strikes once,
    with the impulse ``m sqrt(2 g h0)``, and rests; ``impacts.csv`` holds the impact's time,
    impulse and velocities, in the file's output units; on a compliant contact (a material,
    no ``contact_model``) it is refused at its line (exit 2), before computing."""
    import math

    import pandas as pd

    path = tmp_path / "ball.yaml"
    path.write_text(PLASTIC)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    table = pd.read_csv(tmp_path / "out" / "drop" / "results.csv")
    impulse = table["floor.impulse [N·s]"].to_numpy()
    assert impulse[-1] == pytest.approx(0.1 * math.sqrt(2 * 9.81 * 0.2), rel=1e-9)
    assert table["ball.y [m]"].iloc[-1] == pytest.approx(0.05, rel=1e-9)
    impacts = pd.read_csv(tmp_path / "out" / "drop" / "impacts.csv")  # one row an impact
    assert list(impacts["contact"]) == ["floor"]
    assert impacts["t [s]"].iloc[0] == pytest.approx(math.sqrt(2 * 0.2 / 9.81), abs=1e-9)
    assert impacts["impulse [N·s]"].iloc[0] == pytest.approx(impulse[-1], rel=1e-12)
    assert impacts["normal_velocity_before [m/s]"].iloc[0] == pytest.approx(
        -math.sqrt(2 * 9.81 * 0.2), rel=1e-9
    )
    shown = "output_units: {time: ms, velocity: mm/s}\nunits: {"
    path.write_text(PLASTIC.replace("units: {", shown))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    in_ms = pd.read_csv(tmp_path / "out" / "drop" / "impacts.csv")
    assert in_ms["t [ms]"].iloc[0] == pytest.approx(1e3 * impacts["t [s]"].iloc[0], rel=1e-12)
    assert in_ms["normal_velocity_before [mm/s]"].iloc[0] == pytest.approx(
        1e3 * impacts["normal_velocity_before [m/s]"].iloc[0], rel=1e-12
    )
    compliant = PLASTIC.replace("contact_model: rigid", "young_modulus: 1 GPa, impact_speed: 1")
    path.write_text(compliant)
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert "ball.yaml:11: force 'floor', restitution:" in res.output
    assert "contact_model: rigid for a perfectly plastic impact" in res.output
