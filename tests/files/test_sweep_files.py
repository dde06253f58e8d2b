"""Sweep runs of model files (``kind: sweep``): each member equals the single run of the file
with the member's numbers (by a file parameter or by a body's number: the same member two
ways), the summaries are the reductions of the members' columns, ``mixdyn run`` writes the
member table, the long table and the plots, a failed member is reported by index and cause
(exit 1, the others written), and a bad sweep is refused at its line (exit 2)."""

from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from fixtures import EXAMPLES, FORWARD_RUN, SWEEP_MODEL
from mixdyn.cli import app
from mixdyn.runs import Runner, execute

EXAMPLE = EXAMPLES / "antonya_sweep.yaml"
MODEL = SWEEP_MODEL

BASE = FORWARD_RUN

SWEEP = """
  - name: sweep
    kind: sweep
    run: forward
    vary:
      F0: {values: [8, 12.5]}
      m5: {values: [0.006, 0.01]}
    summaries:
      - {name: x_max, column: slider.x, reduce: max}
      - {name: turn, column: crank.phi, reduce: last}
      - {name: d_rms, column: D.Fx, reduce: rms}
      - {name: x_range, column: slider.x, reduce: range}
    plots:
      - {file: turn.png, x: F0, y: turn, by: m5}
      - {file: band.png, band: slider.x}
"""


def _file(tmp_path, text: str, name: str = "sweep.yaml") -> pathlib.Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _single(f0: float, m5: float) -> Runner:
    """The nominal run of the file with ``F0`` and ``m5`` written in: the member's truth."""
    text = MODEL.replace("  F0: 10 ", f"  F0: {float(f0)!r} ")
    text = text.replace("  m5: 0.00786", f"  m5: {float(m5)!r}")
    return execute(mio.reads(text + BASE))["forward"]


@pytest.fixture(scope="module")
def swept():
    spec = mio.reads(MODEL + BASE + SWEEP)
    return execute(spec, ["sweep"])["sweep"]


def test_members_equal_the_single_runs_of_the_edited_file(swept):
    assert swept.plan.members == 4 and not swept.sweep.errors
    grid = list(zip(swept.plan.values["F0"], swept.plan.values["m5"], strict=True))
    assert grid == [(8, 0.006), (8, 0.01), (12.5, 0.006), (12.5, 0.01)]
    for i, (f0, m5) in enumerate(grid):
        single = _single(f0, m5)
        member = swept.sweep[i]
        for c in ("slider.x", "crank.phi", "D.Fx", "work.nonconservative"):
            scale = float(np.max(np.abs(single[c])))
            assert float(np.max(np.abs(member[c] - single[c]))) <= 1e-10 * scale, (i, c)
    # the numbers did change the motion
    assert len({round(float(r["slider.x"][-1]), 6) for r in swept.sweep.results}) == 4


def test_summaries_are_the_reductions_of_the_members_columns(swept):
    table = swept.members()
    for i, res in enumerate(swept.sweep.results):
        x, phi, d = res["slider.x"], res["crank.phi"], res["D.Fx"]
        row = table.iloc[i]
        assert row["status"] == "ok" and row["error"] == ""
        assert row["x_max"] == np.max(x)
        assert row["turn"] == phi[-1]
        assert row["x_range"] == np.max(x) - np.min(x)
        assert abs(row["d_rms"] - np.sqrt(np.mean(d**2))) <= 1e-14 * np.max(np.abs(d))
    assert swept.units["x_max"] == "mm" and swept.units["turn"] == "rad"


def test_a_body_number_varies_like_the_parameter_it_is_built_from():
    """``slider.mass`` varied directly gives the members that ``m5`` gives."""
    by_body = SWEEP.replace("m5: {values:", "slider.mass: {values:").replace("by: m5", "by: F0")
    by_body = by_body.replace("x: F0, y: turn, by: F0", "x: slider.mass, y: turn, by: F0")
    a = execute(mio.reads(MODEL + BASE + by_body), ["sweep"])["sweep"]
    b = execute(mio.reads(MODEL + BASE + SWEEP), ["sweep"])["sweep"]
    for i in range(4):
        np.testing.assert_array_equal(a.sweep[i].q, b.sweep[i].q)


def test_latin_hypercube_members_lie_in_their_strata():
    lhs = """
  - name: sweep
    kind: sweep
    run: forward
    sampling: latin_hypercube
    samples: 5
    seed: 7
    vary:
      F0: {span: [5, 15]}
      slider.mass: {span: ["4 g", "12 g"]}
"""
    runner = Runner(mio.reads(MODEL + BASE + lhs))
    values = runner.plans["sweep"].values
    f0, m = values["F0"], values["slider.mass"]
    assert sorted(np.floor((f0 - 5) / 10 * 5).astype(int)) == [0, 1, 2, 3, 4]
    # "4 g" in a model in kg: converted by the field's unit (mass)
    assert sorted(np.floor((m - 0.004) / 0.008 * 5).astype(int)) == [0, 1, 2, 3, 4]


def test_the_command_line_writes_the_tables_and_figures(tmp_path):
    path = _file(tmp_path, MODEL + BASE + SWEEP)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--run", "sweep"])
    assert res.exit_code == 0, res.output
    folder = out / "sweep"
    members = pd.read_csv(folder / "members.csv")
    assert list(members["member"]) == [0, 1, 2, 3]
    assert list(members.columns[:3]) == ["member", "F0", "m5"]
    table = mio.read_table(folder / "table.csv")
    assert len(table) == 4 * 21  # a row per member and output time
    head = (folder / "table.csv").read_text().partition("\n")[0].split(",")
    assert "slider.x [mm]" in head and "member" in head  # a name with its unit; a count without
    assert table.attrs["units"]["slider.x"] == "mm" and "member" not in table.attrs["units"]
    # the long table's rows are the members' columns
    single = _single(12.5, 0.01)
    rows = table[table["member"] == 3]
    np.testing.assert_allclose(rows["slider.x"], single["slider.x"], rtol=1e-10, atol=0)
    for png in ("turn.png", "band.png"):
        assert (folder / png).stat().st_size > 10_000
    assert not (out / "forward").exists()  # the swept run is not run for itself


def test_netcdf_holds_the_sweep_as_a_labelled_array(tmp_path):
    """``--netcdf``: sweep.nc, a variable per column on (member, t), the file's varied
    parameters and the status as coordinates, equal to the long table."""
    xr = pytest.importorskip("xarray")
    path = _file(tmp_path, MODEL + BASE + SWEEP)
    out = tmp_path / "out"
    res = CliRunner().invoke(
        app, ["run", str(path), "--out", str(out), "--run", "sweep", "--netcdf"]
    )
    assert res.exit_code == 0, res.output
    ds = xr.load_dataset(out / "sweep" / "sweep.nc", engine="scipy")
    table = mio.read_table(out / "sweep")
    assert ds["slider.x"].dims == ("member", "t") and ds.sizes == {"member": 4, "t": 21}
    np.testing.assert_array_equal(ds["F0"].values, [8, 8, 12.5, 12.5])
    assert list(ds["status"].values) == ["ok"] * 4
    for k in range(4):
        rows = table[table["member"] == k]
        np.testing.assert_allclose(ds["slider.x"].values[k], rows["slider.x"], rtol=1e-15)
    assert ds["slider.x"].attrs["units"] == "mm"


def test_a_failed_member_is_named_and_the_others_written(tmp_path):
    """A member whose run needs more steps than allowed: exit 1 naming it, its cause and
    time; every member's outcome in members.csv, the others' rows in the long table."""
    base = BASE.replace("    atol: 1.0e-10\n", "    atol: 1.0e-10\n    options: {max_steps: 400}\n")
    sweep = """
  - name: sweep
    kind: sweep
    run: forward
    vary:
      T: {values: [500, 50000, 520]}
    summaries:
      - {name: x_end, column: slider.x, reduce: last}
"""
    path = _file(tmp_path, MODEL + base + sweep)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--run", "sweep"])
    assert res.exit_code == 1, res.output
    assert "1 of 3 members failed" in res.output and "member 1, T = 50000" in res.output
    members = mio.read_table(out / "sweep" / "members.csv")
    assert list(members["status"] == "ok") == [True, False, True]
    assert "step" in members["error"][1] and np.isfinite(members["t_error"][1])
    assert np.isnan(members["x_end"][1]) and np.isfinite(members["x_end"][[0, 2]]).all()
    table = mio.read_table(out / "sweep")
    assert sorted(set(table["member"])) == [0, 2]
    # its report says so: the count, and the failed member with its cause and time
    page = (out / "sweep" / "report.html").read_text(encoding="utf-8")
    assert "1 of 3 members failed" in page and "3 (grid): 2 ok, 1 failed" in page
    failed = page.split('class="failed"')[1].split("</table>")[0]
    assert "<td class=n>1</td><td class=n>50000</td>" in failed
    assert members["status"][1] in failed and f"{members['t_error'][1]:.6g}" in failed


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (("run: forward", "run: nope"), "unknown run 'nope'"),
        (("F0: {values: [8, 12.5]}", "G0: {values: [8, 12.5]}"), "no parameter 'G0'"),
        (("m5: {values:", "slider.mas: {values:"), "no field 'mas'"),
        (("m5: {values:", "F1.law.values: {values:"), "not one"),
        (("y: turn", "y: spin"), "'spin' is not a summary"),
        (("x: F0, y: turn", "x: T, y: turn"), "'T' is not swept"),
        (("column: slider.x, reduce: max", "column: slider.q, reduce: max"), "no column"),
        (("{values: [8, 12.5]}", "{values: [8], span: [1, 2]}"), "give 'values' alone"),
        (("{values: [8, 12.5]}", "{span: [3, 3], n: 2}"), "is empty"),
        (("m5: {values: [0.006, 0.01]}", "m5: {values: [0.006, -0.01]}"), "member 1"),
        (("kind: sweep\n", "kind: sweep\n    sampling: latin_hypercube\n"), "samples"),
    ],
)
def test_a_bad_sweep_is_refused_before_computing(tmp_path, edit, words):
    old, new = edit
    assert old in SWEEP
    path = _file(tmp_path, MODEL + BASE + SWEEP.replace(old, new, 1))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    assert words in res.output
    assert "sweep.yaml" in res.output


def test_a_sweep_is_not_replayed_nor_swept_nor_animated(tmp_path):
    replay = """
  - name: again
    kind: sweep
    run: sweep
    vary: {F0: {values: [1, 2]}}
"""
    res = CliRunner().invoke(app, ["check", str(_file(tmp_path, MODEL + BASE + SWEEP + replay))])
    assert res.exit_code == 2 and "is a sweep" in res.output, res.output
    mixed = """
  - name: back
    kind: mixed
    time: {span: [0, 1], n: 21}
    unknown: [F1]
    prescribed:
      - {coordinate: slider.x, from_run: sweep}
"""
    res = CliRunner().invoke(app, ["check", str(_file(tmp_path, MODEL + BASE + SWEEP + mixed))])
    assert res.exit_code == 2 and "is a sweep run, with a motion per member" in res.output
    path = _file(tmp_path, MODEL + BASE + SWEEP)
    res = CliRunner().invoke(app, ["animate", str(path), "--run", "sweep", "-o", "x.gif"])
    assert res.exit_code == 2 and "no single motion" in res.output
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 0 and "4 members (grid) over F0, m5" in res.output


def test_output_units_apply_to_the_summaries_and_the_long_table(swept):
    """``output_units: {angle: deg, force: N}`` in the file (model: mm, kg, s, so forces in
    mN): the summaries and the long table in degrees and newtons, the varied values as given."""
    spec = mio.reads("output_units: {angle: deg, force: N}\n" + MODEL + BASE + SWEEP)
    conv = execute(spec, ["sweep"])["sweep"]
    turn, d_rms = swept.summaries["turn"], swept.summaries["d_rms"]
    np.testing.assert_allclose(conv.summaries["turn"], np.degrees(turn), rtol=1e-12)
    np.testing.assert_allclose(conv.summaries["d_rms"], d_rms / 1000, rtol=1e-12)
    np.testing.assert_array_equal(conv.summaries["x_max"], swept.summaries["x_max"])
    assert (conv.units["turn"], conv.units["d_rms"], conv.units["x_max"]) == ("deg", "N", "mm")
    a, b = swept.table(), conv.table()
    np.testing.assert_allclose(b["crank.phi"], np.degrees(a["crank.phi"]), rtol=1e-12)
    np.testing.assert_allclose(b["D.Fx"], a["D.Fx"] / 1000, rtol=1e-12)
    np.testing.assert_array_equal(b["F0"], a["F0"])
