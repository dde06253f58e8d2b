"""A failed run leaves no stale answer (issue 31): a run clears its previous outputs from its
folder as it starts (only the files it writes), and a run that fails numerically writes the
states it computed up to the failure with a ``meta.json`` saying ``status: failed``, the
failure's time and cause; a run that succeeds says ``status: ok``.

The failing variant is the succeeding file with a step limit (``max_steps``) that the
adaptive integrator reaches part-way: up to the failure it takes the same steps, so its
partial table equals the first rows of the succeeding run's.
"""

from __future__ import annotations

import importlib.util
import json
import re

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn as md
from fixtures import EXAMPLES
from mixdyn.cli import app

OK = """\
mixdyn: 1
name: pendulum
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81]
bodies:
  - {name: bob, mass: 1, inertia: 0.01, q0: [0.3, -0.4, 0.6435011087932844], points: {O: [0, 0.5]}}
joints:
  - {type: revolute, name: pin, point_i: ground, point_j: bob.O}
runs:
  - {name: swing, kind: forward, time: {span: [0, 1], n: 21}}
"""

FAILS = OK.replace("n: 21}}", "n: 21}, options: {max_steps: 40}}")


def _run(tmp_path, text: str, *args):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    return CliRunner().invoke(
        app, ["run", str(path), "--out", str(tmp_path / "out"), "--no-figures", *args]
    )


def _meta(folder) -> dict:
    return json.loads((folder / "meta.json").read_text())


def test_a_failed_run_replaces_the_earlier_answer_by_its_partial_one(tmp_path):
    parquet = importlib.util.find_spec("pyarrow") is not None
    res = _run(tmp_path, OK, *(["--parquet"] if parquet else []))
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "swing"
    assert _meta(folder)["status"] == "ok"
    full = md.read_table(folder)
    assert len(full) == 21
    (folder / "notes.txt").write_text("mine")  # not the run's: kept

    res = _run(tmp_path, FAILS)
    assert res.exit_code == 1, res.output
    said = float(re.search(r"at t = ([0-9.eE+-]+)", res.stderr).group(1))
    meta = _meta(folder)
    assert meta["status"] == "failed"
    failure = meta["failure"]
    assert failure["time"] == pytest.approx(said, rel=1e-5)
    assert 0.05 < failure["time"] < 0.95  # part-way: some rows, not all
    assert "step limit" in failure["cause"] and failure["error"] == "NumericalError"
    assert failure["time_unit"] == "s"

    # no stale table: the rows end at the last output time before the failure
    part = md.read_table(folder)
    assert meta["rows"] == len(part) and meta["columns"] == list(part.columns)
    assert part["t"].iloc[-1] <= failure["time"] < part["t"].iloc[-1] + 0.05 + 1e-12
    # the same steps up to the failure: the succeeding run's rows
    cols = ["t", "bob.x", "bob.y", "bob.phi", "bob.vx", "bob.vy", "bob.omega"]
    assert list(part.columns) == cols
    np.testing.assert_allclose(part[cols], full[cols].iloc[: len(part)], rtol=0, atol=1e-12)
    assert not (folder / "results.parquet").exists()  # the first run's, removed
    assert (folder / "notes.txt").read_text() == "mine"

    # and back: a succeeding run writes its whole answer again
    res = _run(tmp_path, OK)
    assert res.exit_code == 0, res.output
    assert _meta(folder)["status"] == "ok" and "failure" not in _meta(folder)
    assert len(md.read_table(folder)) == 21


def test_a_folder_named_like_an_output_is_left_alone(tmp_path):
    res = _run(tmp_path, OK)
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "swing"
    # a plot's file name taken by a folder of the user's: clearing does not remove folders
    (folder / "results.parquet").mkdir()
    (folder / "results.parquet" / "keep.txt").write_text("mine")
    res = _run(tmp_path, FAILS)
    assert res.exit_code == 1, res.output
    assert (folder / "results.parquet" / "keep.txt").read_text() == "mine"


def test_a_kinematic_run_that_leaves_the_workspace_writes_the_solved_times(tmp_path):
    """The slider of the example's slider-crank driven beyond the reach of crank + rod: the
    output times before the failure were solved (the slider where its law puts it), the one
    that failed is not written."""
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    text = text.replace(
        "{type: coordinate, name: motor, coordinate: crank.phi, law: omega*t}",
        "{type: coordinate, name: motor, coordinate: slider.x, law: 0.35 + 0.2*t}",
    ).replace("    kind: kinematic\n", "    kind: kinematic\n    initial: {crank.phi: 1.0}\n")
    path = tmp_path / "reach.yaml"
    path.write_text(text)
    args = ["run", str(path), "--run", "kinematics", "--out", str(tmp_path / "out")]
    res = CliRunner().invoke(app, [*args, "--no-figures"])
    assert res.exit_code == 1, res.output
    folder = tmp_path / "out" / "kinematics"
    meta = _meta(folder)
    assert meta["status"] == "failed" and meta["failure"]["error"] == "ConvergenceError"
    assert meta["failure"]["time_unit"] == "s"
    part = md.read_table(folder)
    assert len(part) > 0 and part["t"].iloc[-1] < meta["failure"]["time"]
    np.testing.assert_allclose(part["slider.x"], 0.35 + 0.2 * part["t"], rtol=0, atol=1e-9)
