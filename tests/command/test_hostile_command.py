"""Hostile inputs of ``mixdyn plot`` and ``mixdyn run --parquet`` (issue 31): each one is a
named input error (exit 2, one line naming the file or option, what is wrong and what to do),
never an internal error: a results file that is not UTF-8 CSV, not Parquet, a FIFO, or whose
``meta.json`` is not JSON; a column of text given to ``--x`` or ``--column``; ``--parquet``
without pyarrow (refused before anything runs). Nothing here compiles a JAX program.
"""

from __future__ import annotations

import os
import sys

import pytest
from typer.testing import CliRunner

from mixdyn.cli import app

TABLE = "t,name,bob.x\n0,a,1.5\n0.5,b,2.5\n1,c,3.5\n"


def _error(args) -> str:
    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exit_code == 2, (res.exit_code, res.output)
    assert "Traceback" not in res.output and "internal error" not in res.output, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    return lines[0]


def test_a_table_with_numbers_is_plotted(tmp_path):
    """The other side of the checks below: the numeric columns of the same table plot."""
    (tmp_path / "r.csv").write_text(TABLE)
    out = tmp_path / "x.png"
    res = CliRunner().invoke(app, ["plot", str(tmp_path / "r.csv"), "-c", "bob.x", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert out.stat().st_size > 0


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["-c", "bob.x", "--x", "name"], "--x: column 'name' holds text, not numbers ('a'"),
        (["-c", "name"], "--column: column 'name' holds text, not numbers"),
    ],
)
def test_a_text_column_is_refused_by_its_option(tmp_path, args, words):
    (tmp_path / "r.csv").write_text(TABLE)
    line = _error(["plot", tmp_path / "r.csv", *args, "-o", tmp_path / "x.png"])
    assert line.startswith(str(tmp_path / "r.csv")) and words in line, line
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    ("name", "content", "words"),
    [
        ("results.csv", bytes(range(128, 256)), "is not UTF-8 text (byte 0)"),
        ("results.csv", b"", "cannot be read as CSV"),
        ("results.parquet", b"PAR1 but not parquet at all" * 10, "is not a Parquet file"),
    ],
)
def test_a_garbage_results_file_is_refused(tmp_path, name, content, words):
    if name.endswith(".parquet"):
        pytest.importorskip("pyarrow")
    (tmp_path / name).write_bytes(content)
    line = _error(["plot", tmp_path / name, "-c", "bob.x"])
    assert line.startswith(str(tmp_path / name)) and words in line, line


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_results_is_refused_without_waiting(tmp_path):
    os.mkfifo(tmp_path / "results.csv")  # nobody writes to it
    line = _error(["plot", tmp_path, "-c", "bob.x"])
    assert "is a pipe, socket or device, not a file" in line, line


def test_a_meta_json_that_is_not_json_is_refused(tmp_path):
    (tmp_path / "results.csv").write_text(TABLE)
    (tmp_path / "meta.json").write_text("{units: ")
    line = _error(["plot", tmp_path, "-c", "bob.x", "-o", tmp_path / "x.png"])
    assert line.startswith(str(tmp_path / "meta.json")) and "is not JSON" in line, line


def test_parquet_without_pyarrow_is_refused_before_running(tmp_path, monkeypatch):
    # pyarrow missing: its import fails as it would where it is not installed
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    path = tmp_path / "m.yaml"
    path.write_text(
        "mixdyn: 1\nname: p\nbodies:\n  - {name: b, mass: 1, inertia: 1}\n"
        "runs:\n  - {name: r, kind: forward, time: {span: [0, 1], n: 3}}\n"
    )
    line = _error(["run", path, "--out", tmp_path / "out", "--parquet", "--no-figures"])
    assert line.startswith(f"{path}: --parquet: writing Parquet needs pyarrow"), line
    assert "pip install pyarrow (or leave --parquet out)" in line
    assert not (tmp_path / "out").exists()  # refused before anything ran or was written
