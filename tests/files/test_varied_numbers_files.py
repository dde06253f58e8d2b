"""A sweep run's member is the swept run of the file with the member's numbers, its output
times included, and a member whose number the model file would refuse is refused at the
sweep's line before any computing (exit 2)."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.cli import app
from mixdyn.runs import Runner

MODEL = """
mixdyn: 1
name: pendulum
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81]
parameters:
  t_end: 1
ground:
  points: {O: [0, 0]}
bodies:
  - {name: bob, mass: 1, inertia: 0.01, q0: [0.5, 0, 0], points: {O: [-0.5, 0]}}
joints:
  - {type: revolute, name: pin, point_i: ground.O, point_j: bob.O}
"""

BASE = """
runs:
  - name: forward
    kind: forward
    time: {span: [0, t_end], n: 11}
    rtol: 1.0e-8
    atol: 1.0e-10
"""

SWEEP = """
  - name: sweep
    kind: sweep
    run: forward
    vary:
      t_end: {values: [0.5, 1.0, 1.5]}
    summaries:
      - {name: y_end, column: bob.y, reduce: last}
"""


def _run(tmp_path, text: str, *options: str):
    path = tmp_path / "sweep.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--run", "sweep", *options])
    return res, out


@pytest.mark.slow  # ~12 s on two cores: the forward run's program is compiled
def test_each_member_runs_to_its_own_end(tmp_path):
    """A swept end time: each member's times are those of the file with its end written in
    (its last time is its end), its motion that of the single run, in the tables and the
    NetCDF file too (``t`` a coordinate per member)."""
    xr = pytest.importorskip("xarray")
    res, out = _run(tmp_path, MODEL + BASE + SWEEP, "--netcdf")
    assert res.exit_code == 0, res.output
    ds = xr.load_dataset(out / "sweep" / "sweep.nc", engine="scipy")
    table = mio.read_table(out / "sweep")
    members = mio.read_table(out / "sweep" / "members.csv")
    assert list(members["status"]) == ["ok"] * 3
    for i, t_end in enumerate([0.5, 1.0, 1.5]):
        text = MODEL.replace("t_end: 1\n", f"t_end: {t_end}\n") + BASE
        single = Runner(mio.reads(text)).execute(["forward"])["forward"]
        np.testing.assert_allclose(single.t, np.linspace(0.0, t_end, 11), rtol=0, atol=1e-15)
        rows = table[table["member"] == i]
        np.testing.assert_allclose(rows["t"], single.t, rtol=1e-15)
        scale = float(np.max(np.abs(single["bob.y"])))
        np.testing.assert_allclose(rows["bob.y"], single["bob.y"], atol=1e-10 * scale)
        assert members["y_end"][i] == pytest.approx(float(single["bob.y"][-1]), rel=1e-9)
        np.testing.assert_allclose(ds["t"].values[i], rows["t"], rtol=1e-15)
        np.testing.assert_allclose(ds["bob.y"].values[i], rows["bob.y"], rtol=1e-15)


def test_a_band_over_members_at_different_times_is_refused(tmp_path):
    res, _ = _run(
        tmp_path, MODEL + BASE + SWEEP + "    plots:\n      - {file: b.png, band: bob.y}\n"
    )
    assert res.exit_code == 2, res.output
    assert "a band needs every member at the same output times" in res.output


def _line(text: str, words: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if words in line)


@pytest.mark.parametrize(
    ("example", "vary", "written", "words"),
    [
        (
            "gear_train.yaml",
            "mesh12.radius_i: {values: [20, 0]}",
            ("body_j: idler, radius_i: R1", "body_j: idler, radius_i: 0"),
            "radius_i 0 is not positive",
        ),
        (
            "friction.yaml",
            "hold1.v_stick: {values: [1.0e-6, 0]}",
            ("joint: slide1, mu: mu}", "joint: slide1, mu: mu, v_stick: 0}"),
            "v_stick 0 is not positive",
        ),
        (
            "friction.yaml",
            "pin_friction.mu: {values: [0.2, -0.1]}",
            ("joint: pin, mu: 0.2", "joint: pin, mu: -0.1"),
            "mu must be >= 0, got -0.1",
        ),
    ],
)
def test_a_member_number_a_file_refuses_is_refused_at_its_line(
    tmp_path, example, vary, written, words
):
    """A member's number that the file refuses when written in (the truth: the file with
    that number, checked) is refused at its line in the sweep with the same reason, naming
    the member and the value, before any computing (a stick band of 0 ran for minutes)."""
    text = (EXAMPLES / example).read_text()
    assert written[0] in text
    (tmp_path / "single.yaml").write_text(text.replace(written[0], written[1], 1))
    single = CliRunner().invoke(app, ["check", str(tmp_path / "single.yaml")])
    assert single.exit_code == 2 and words in single.output, single.output
    run = text.split("\nruns:")[1].split("name:")[1].split(",")[0].split("\n")[0].strip()
    text += f"""
  - name: sweep
    kind: sweep
    run: {run}
    vary:
      {vary}
"""
    res, _ = _run(tmp_path, text)
    assert res.exit_code == 2, res.output
    assert "member 1" in res.output and words in res.output
    assert f"sweep.yaml:{_line(text, vary)}" in res.output
