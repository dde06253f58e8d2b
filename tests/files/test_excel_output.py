"""Excel output (issue 32): ``mixdyn run --excel``, ``run_file(..., excel=True)`` and
``mixdyn.write_excel`` write a workbook whose sheet ``results`` is ``results.csv`` (the same
``name [unit]`` headers, the same numbers) and whose sheet ``meta`` holds the columns' units
and the run's settings; without openpyxl the request is an input error naming the extra.

The truth for the numbers is the written ``results.csv`` (17 significant digits) and the
format openpyxl writes numbers in, ``%.16g``: a number read back lies within half a unit of
its 16th significant digit (5e-16 relative) plus the rounding of reading it (1.2e-16).
"""

from __future__ import annotations

import builtins
import textwrap

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
from fixtures import CRANK_FILE
from mixdyn.cli import app
from mixdyn.io import FileError

pytest.importorskip("openpyxl")

#: openpyxl's %.16g read back: 5e-16 relative, and the reading's half ulp.
RTOL = 5e-16 + 1.2e-16

CRANK = CRANK_FILE


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("excel")
    path = folder / "crank.yaml"
    path.write_text(CRANK)
    results = md.run_file(path, folder / "out", excel=True)
    return folder, folder / "out" / "turn", results["turn"]


def test_the_workbook_is_the_csv_with_its_units(written):
    _, run, _ = written
    csv = pd.read_csv(run / "results.csv")
    book = pd.read_excel(run / "results.xlsx", sheet_name=None)
    assert list(book) == ["results", "meta"]
    sheet = book["results"]
    assert list(sheet.columns) == list(csv.columns)  # the same name [unit] headers
    assert "motor [N·m]" in sheet.columns and "crank.phi [deg]" in sheet.columns
    assert sheet.columns[0] == "t [s]"
    np.testing.assert_allclose(sheet.to_numpy(float), csv.to_numpy(float), rtol=RTOL, atol=0)
    # the sheet meta: every column's unit, as its header says, and the run's settings
    meta = dict(zip(book["meta"]["entry"], book["meta"]["value"], strict=True))
    assert meta["units.motor"] == "N·m" and meta["units.crank.phi"] == "deg"
    assert meta["settings.kind"] == "inverse" and meta["status"] == "ok"
    assert meta["unit_system.length"] == "mm"  # the model's, beside the output units


def test_write_excel_writes_the_same_table_from_python(written, tmp_path):
    _, run, result = written
    path = md.write_excel(result, tmp_path / "turn.xlsx")
    sheet = pd.read_excel(path, sheet_name="results")
    csv = pd.read_csv(run / "results.csv")
    assert list(sheet.columns) == list(csv.columns)
    np.testing.assert_allclose(sheet.to_numpy(float), csv.to_numpy(float), rtol=RTOL, atol=0)
    # the crank's motor torque m g L/2 cos(phi) in N·m, in the file's output units
    phi = np.radians(sheet["crank.phi [deg]"].to_numpy())
    np.testing.assert_allclose(
        sheet["motor [N·m]"], 2.0 * 9.81 * 0.125 * np.cos(phi), rtol=1e-9, atol=1e-12
    )


@pytest.fixture
def no_openpyxl(monkeypatch):
    real = builtins.__import__

    def refuse(name, *args, **kw):
        if name == "openpyxl" or name.startswith("openpyxl."):
            raise ImportError(f"No module named {name!r}")
        return real(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", refuse)


def test_without_openpyxl_excel_is_an_input_error_naming_the_extra(written, tmp_path, no_openpyxl):
    folder, _, result = written
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(folder / "crank.yaml"), "--out", str(out), "--excel"])
    assert res.exit_code == 2, res.output
    assert 'pip install "mixdyn[excel]"' in res.output and "--excel" in res.output
    assert not out.exists()  # refused before anything ran
    with pytest.raises(FileError, match=r"openpyxl, which is not installed.*mixdyn\[excel\]"):
        md.write_excel(result, tmp_path / "x.xlsx")
    assert not (tmp_path / "x.xlsx").exists()


def test_the_help_names_the_extra(monkeypatch):
    monkeypatch.setenv("COLUMNS", "100")
    text = CliRunner().invoke(app, ["run", "--help"]).output
    assert "mixdyn[excel]" in text.replace("│ ", "").replace(" │", "")


def test_a_table_longer_than_a_sheet_is_refused_before_computing(tmp_path):
    """Excel's sheet holds 1,048,576 rows, the header one of them: a sweep of 1,049 members
    of 1,000 output times (1,049,000 rows) is refused with --excel before anything runs."""
    text = CRANK.replace("n: 11}", "n: 1000}") + textwrap.indent(
        textwrap.dedent(
            """\
            - name: masses
              kind: sweep
              run: turn
              vary:
                crank.mass: {span: [1 kg, 2 kg], n: 1049}
              summaries:
                - {name: torque_max, column: motor, reduce: max}
            """
        ),
        "  ",
    )
    path = tmp_path / "big.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    args = ["run", str(path), "--out", str(out), "--run", "masses", "--excel", "--no-figures"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2, res.output
    assert "1,049,000 rows, more than an Excel sheet holds (1,048,575)" in res.output
    assert not out.exists()
