"""Motion generation in model files (``kind: synthesis`` with ``motion:``): the poses read
with their units (an angle without one refused), bad input refused at its line before any
search (exit 2); slow: the example's run and its best.yaml, run by md.kinematic (Newton's
assembly of the written model, not the search's closed form), carry the coupler through the
poses."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.cli import app
from mixdyn.io import FileError
from mixdyn.runs import Runner
from mixdyn.runs.report import report
from mixdyn.synthesis import MotionTask

EXAMPLE = EXAMPLES / "synthesis_motion.yaml"

TEXT = """mixdyn: 1
units: {length: mm, mass: kg, time: s}
runs:
  - name: poses
    kind: synthesis
    motion:
      poses:
        - [0, 0, 0 deg]
        - [300, 250, 40 deg]
        - [450, 600, 1.5 rad]
    starts: 8
"""


def test_the_example_is_checked_and_its_poses_read_in_si():
    """``mixdyn check``: no mechanism, the run described; the poses in m and rad (by hand:
    mm / 1000, deg * pi / 180), the length from the file in its units."""
    lines = list(report(EXAMPLE))
    assert "no mechanism" in lines[0] and lines[-1].endswith("ok[/green]")
    assert any("synthesis" in line and "4 poses" in line for line in lines)
    task = Runner(mio.read(EXAMPLE)).plans["poses"].task
    assert isinstance(task, MotionTask)
    np.testing.assert_allclose(task.poses[1], [0.3, 0.25, 40 * np.pi / 180], rtol=1e-15)
    np.testing.assert_allclose(task.min_transmission, np.pi / 6, rtol=1e-15)
    text = TEXT.replace("    starts: 8", "      length: 250 mm\n    starts: 8")
    task = Runner(mio.reads(text)).plans["poses"].task
    assert task.weight_length == pytest.approx(0.25, rel=1e-15) and task.poses[2, 2] == 1.5


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


@pytest.mark.parametrize(
    "old, new, marker, words",
    [
        (
            "        - [450, 600, 1.5 rad]\n",
            "",
            "[0, 0, 0 deg]",
            "motion.poses: List should have at least 3",
        ),
        ("[300, 250, 40 deg]", "[300, 250, 40]", "[300, 250, 40]", "no unit"),
        ("[300, 250, 40 deg]", "[300, 250, 40 mm]", "[300, 250, 40 mm]", "mm"),
        ("[300, 250, 40 deg]", "[300, 250]", "[300, 250]", "motion.poses[1]: missing"),
        ("    starts: 8", "    timing: [0 deg, 10 deg, 20 deg]", "timing", "path generation"),
        ("    starts: 8", "      length: -5 mm", "length: -5", "length must be > 0"),
        ("    starts: 8", "    bounds: {r2: [5 mm, 1 mm]}", "r2", "low <= high"),
        ("    starts: 8", "    points: [[0, 0], [1, 1]]", "- name: poses", "one of"),
    ],
)
def test_bad_motion_input_is_refused_at_its_line(old, new, marker, words):
    """Each fault an input error at the line that holds it, before any search."""
    text = TEXT.replace(old, new)
    assert text != TEXT
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


def test_bad_motion_input_exits_2_from_the_command(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(TEXT.replace("[300, 250, 40 deg]", "[300, 250, 40]"))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2 and "bad.yaml:9" in res.output and "no unit" in res.output
    assert not (tmp_path / "out" / "poses").exists()


@pytest.mark.slow  # long: run by CI's slow set (the search and best.yaml's run compile)
def test_the_example_runs_and_its_best_yaml_carries_the_coupler_through_the_poses(tmp_path):
    """``mixdyn run`` of the example: an exact four-bar (four poses leave a family), ranked
    with its coupler angle; best.yaml loaded and run by md.kinematic at the crank's angles of
    the poses (meta.json) puts coupler.P on their points and coupler.phi on their angles."""
    res = CliRunner().invoke(app, ["run", str(EXAMPLE), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "poses"
    table = pd.read_csv(folder / "candidates.csv")
    assert table["error [m²]"].iloc[0] < 1e-16 and "coupler_angle [rad]" in table.columns
    angles = np.asarray(json.loads((folder / "meta.json").read_text())["synthesis"]["angles"])
    assert np.all(np.diff(angles) > 0) and angles[-1] - angles[0] <= 2 * np.pi  # in order
    poses = Runner(mio.read(EXAMPLE)).plans["poses"].task.poses
    best = md.load(folder / "best.yaml")
    run = md.kinematic(best.model, angles - angles[0])  # the crank at 1 rad/s from the first
    p, _, _ = run.point("coupler.P")
    np.testing.assert_allclose(p, poses[:, :2], atol=1e-8)
    turn = np.angle(np.exp(1j * (np.asarray(run["coupler.phi"]) - poses[:, 2])))
    assert np.max(np.abs(turn)) < 1e-8
