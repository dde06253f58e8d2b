"""Shape-only path generation in model files (``kind: synthesis`` with ``shape: fourier``):
the points read with their units into a shape task, the keys that fix a place, a size or a
timing refused at their line before any search (exit 2); slow: a run on a known four-bar's
curve in mm writes candidates with a dimensionless shape error and a distance, and its
best.yaml, run by md.kinematic (Newton's assembly of the written model), passes the points."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from mixdyn.cli import app
from mixdyn.io import FileError
from mixdyn.runs import Runner
from mixdyn.runs.report import report
from mixdyn.synthesis import FourBar, ShapeTask, coupler_curve

T = np.linspace(0.0, 2 * np.pi, 20, endpoint=False)
CURVE = np.c_[100 * np.cos(T) + 30 * np.cos(2 * T), 60 * np.sin(T) + 20 * np.sin(3 * T)]  # mm


SHAPE = "    shape: fourier\n    harmonics: 6\n"


def _text(points, keys: str = SHAPE) -> str:
    rows = "\n".join(f"      - [{x:.9f} mm, {y:.9f} mm]" for x, y in points)
    return f"""mixdyn: 1
runs:
  - name: loop
    kind: synthesis
{keys}    min_transmission: 20 deg
    starts: 32
    points:
{rows}
"""


TEXT = _text(CURVE)


def test_a_shape_run_is_checked_and_its_points_read_in_si(tmp_path):
    """``mixdyn check`` describes it; the task a ShapeTask of the points in m (mm / 1000),
    its harmonics and least transmission angle (20 deg in rad) from the file."""
    task = Runner(mio.reads(TEXT)).plans["loop"].task
    assert isinstance(task, ShapeTask) and task.harmonics == 6
    np.testing.assert_allclose(task.points, np.round(CURVE, 9) / 1000, rtol=0, atol=1e-16)
    assert task.min_transmission == pytest.approx(np.deg2rad(20), rel=1e-15)
    assert task.sense == "either"
    text = TEXT.replace("    harmonics: 6\n", "    harmonics: 6\n    sense: positive\n")
    assert Runner(mio.reads(text)).plans["loop"].task.sense == "positive"
    (tmp_path / "shape.yaml").write_text(TEXT)
    lines = list(report(tmp_path / "shape.yaml"))
    words = "20 points of a closed curve, its shape alone (6 harmonics, either sense)"
    assert any(words in line for line in lines)


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


@pytest.mark.parametrize(
    "keys, marker, words",
    [
        (SHAPE + "    timing: [0 deg, 10 deg]\n", "timing", "'timing' does not go with"),
        (SHAPE + "    bounds: {r2: [1 mm, 5 mm]}\n", "bounds", "'bounds' does not go with"),
        (SHAPE + "    masses: {density: 2 kg/m}\n    torque_weight: 1\n", "torque_weight",
         "the search is for the shape alone"),
        ("    shape: fourier\n    harmonics: 12\n", "      - [", "describe at most 9 harmonics"),
        ("    shape: fourier\n    harmonics: 1\n", "harmonics: 1", "harmonics"),
        ("    shape: circle\n", "shape: circle", "shape"),
        ("    harmonics: 6\n", "- name: loop", "'harmonics' and 'sense' go with 'shape: fourier'"),
        (SHAPE + "    sense: backwards\n", "sense: backwards", "sense"),
    ],
)  # fmt: skip
def test_bad_shape_input_is_refused_at_its_line(keys, marker, words):
    """Each fault an input error at the line that holds it, before any search."""
    text = _text(CURVE, keys)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert words in str(e.value), str(e.value)
    assert e.value.line == _line(text, marker), str(e.value)


@pytest.mark.slow  # long: run by CI's slow set (the search and best.yaml's run compile)
def test_a_shape_run_finds_and_places_a_known_four_bar(tmp_path):
    """24 points (mm) of a crank-rocker's coupler curve at even crank steps: ``mixdyn run``
    finds a linkage of that shape (shape error <= 1e-8, dimensionless) placed within 1e-6 of
    the points' size; best.yaml, loaded and run by md.kinematic at the crank angles of
    meta.json (the points' nearest), passes them."""
    fb = FourBar.from_vector(np.array([1.0, 0.35, 1.1, 0.9, 0.6, 0.4, 0.0, 0.0, 0.0]), 1.0)
    points = 200 * np.asarray(coupler_curve(fb, np.linspace(0, 2 * np.pi, 24, endpoint=False)))
    path = tmp_path / "shape.yaml"
    path.write_text(_text(points).replace("    min_transmission: 20 deg\n", ""))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "loop"
    table = pd.read_csv(folder / "candidates.csv")
    size = np.max(np.linalg.norm(points - points.mean(axis=0), axis=1)) / 1000
    assert table["error"].iloc[0] <= 1e-8 and table["distance [m]"].iloc[0] <= 1e-6 * size
    angles = np.asarray(json.loads((folder / "meta.json").read_text())["synthesis"]["angles"])
    best = md.load(folder / "best.yaml")
    sense = table["sense"].iloc[0]  # the crank at 1 rad/s, turning backwards where -1
    kin = md.kinematic(best.model, (sense * (angles - angles[0])) % (2 * np.pi))
    p, _, _ = kin.point("coupler.P")
    assert np.max(np.linalg.norm(p - points / 1000, axis=1)) <= 1e-6 * size
