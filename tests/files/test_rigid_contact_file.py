"""A rigid contact in a model file: a mixed run by a fixed-step method is refused before
computing (exit 2, the run's line and the contact named, with the fix; a mixed run by the
projection method takes its impacts: ``tests/validation/test_mixed_impacts.py``)."""

from __future__ import annotations

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


def test_a_mixed_run_with_a_rigid_contact_by_a_fixed_step_method_is_an_input_error(tmp_path):
    path = tmp_path / "ball.yaml"
    path.write_text(BALL)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2, res.output
    assert "ball.yaml:14: run 'drop': floor: rigid contacts are integrated with the" in res.output
    assert "projection method, not baumgarte: use method='projection'" in res.output
