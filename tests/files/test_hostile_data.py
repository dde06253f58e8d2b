"""Hostile data files and output times of model files (issue 31): each one is a named input
error (exit 2, one line naming the file and line, what is wrong and what to do), found by
``mixdyn check`` before any computing — never a hang or an internal error.

* an identify run's ``data`` that is a FIFO is refused at once (never opened for reading);
* a recording over the size limit (:data:`mixdyn.io.tables.MAX_DATA_BYTES`, lowered here) is
  refused before it is read;
* a recording that is not UTF-8 CSV is refused;
* a noise of 1e-300 and a measured value of 1e308 (noise finer than float64 resolves the
  values) are refused at the noise's line;
* an output time step of 1e-320 (a denormal: infinitely many times) is refused at its line.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np
import pytest
from typer.testing import CliRunner

from mixdyn.cli import app
from mixdyn.io import tables

MODEL = """\
mixdyn: 1
name: pendulum
units: {length: m, mass: kg, time: s}
gravity: [0, -9.81]
bodies:
  - {name: bob, mass: 1, inertia: 0.01, q0: [0.1, -0.49, 0.2], points: {O: [0, 0.5]}}
joints:
  - {type: revolute, name: pin, point_i: ground, point_j: bob.O}
runs:
  - name: swing
    kind: forward
    time: {span: [0, 1], n: 11}
  - name: fit
    kind: identify
    run: swing
    data: rec.csv
    measured:
      - {column: bob.phi, data: phi, noise: 1 mrad}
    fit:
      bob.mass: {bounds: [0.1, 10]}
"""


def _line(text: str, needle: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if needle in line)


def _write(tmp_path: pathlib.Path, text: str = MODEL, rows: int = 11, big=None):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    t = np.linspace(0.0, 1.0, rows)
    phi = 0.2 * np.cos(4.4 * t)
    if big is not None:
        phi[3] = big
    body = "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, phi, strict=True))
    (tmp_path / "rec.csv").write_text("t,phi\n" + body)
    return path


def _check(path: pathlib.Path) -> str:
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, (res.exit_code, res.output)
    assert "Traceback" not in res.output and "internal error" not in res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    return lines[0]


def test_the_recording_is_read_and_checked(tmp_path):
    """The other side of the checks below: the same file with a sound recording passes."""
    res = CliRunner().invoke(app, ["check", str(_write(tmp_path))])
    assert res.exit_code == 0, res.output
    assert "from 11 times of bob.phi" in res.output


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_data_is_refused_without_waiting(tmp_path):
    path = _write(tmp_path)
    (tmp_path / "rec.csv").unlink()
    os.mkfifo(tmp_path / "rec.csv")  # nobody writes to it: opening it to read would block
    line = _check(path)
    assert line.startswith(f"{path}:{_line(MODEL, 'data: rec.csv')}:")
    assert "is a pipe, socket or device, not a file" in line


def test_a_recording_over_the_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = _write(tmp_path, rows=201)
    size = (tmp_path / "rec.csv").stat().st_size
    monkeypatch.setattr(tables, "MAX_DATA_BYTES", size - 1)
    line = _check(path)
    assert f"the file has {size:,} bytes, more than the limit of {size - 1:,}" in line
    assert "thin the recording" in line
    monkeypatch.setattr(tables, "MAX_DATA_BYTES", size)  # at the limit: read
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 0, res.output


def test_a_recording_that_is_not_text_is_refused(tmp_path):
    path = _write(tmp_path)
    (tmp_path / "rec.csv").write_bytes(bytes(range(128, 256)) * 4)
    line = _check(path)
    assert line.startswith(f"{path}:{_line(MODEL, 'data: rec.csv')}:")
    assert "is not UTF-8 text" in line, line


@pytest.mark.parametrize(
    ("noise", "big", "words"),
    [
        ("1e-300", None, "the noise 1e-300 is finer"),
        ("1 mrad", 1e308, "the value 1e+308 in line 5"),
    ],
)
def test_a_noise_finer_than_the_values_resolve_is_refused(tmp_path, noise, big, words):
    text = MODEL.replace("noise: 1 mrad", f"noise: {noise}")
    path = _write(tmp_path, text, big=big)
    line = _check(path)
    assert line.startswith(f"{path}:{_line(text, 'noise:')}:"), line
    assert words in line, line


@pytest.mark.parametrize("step", ["1e-320", "5e-324"])
def test_a_denormal_output_step_is_refused_at_its_line(tmp_path, step):
    text = MODEL.replace("time: {span: [0, 1], n: 11}", f"time: {{span: [0, 1], step: {step}}}")
    path = _write(tmp_path, text)
    line = _check(path)
    assert line.startswith(f"{path}:{_line(text, 'step:')}:"), line
    assert "too many (at most 1,000,000)" in line and "use a step of at least 1e-06" in line


def test_a_step_below_the_resolution_of_the_times_is_refused(tmp_path):
    """1e-10 after 1e9 s: the output times would repeat (float64 spacing there is 1.2e-7)."""
    text = MODEL.replace(
        "time: {span: [0, 1], n: 11}", "time: {span: [1000000000, 1000000000.000001], step: 1e-10}"
    )
    line = _check(_write(tmp_path, text))
    assert "successive output times are equal" in line, line


def test_a_step_limit_of_1e300_is_refused_at_its_line(tmp_path):
    text = MODEL.replace(
        "time: {span: [0, 1], n: 11}",
        "time: {span: [0, 1], n: 11}\n    options: {max_steps: 1e300}",
    )
    line = _check(_write(tmp_path, text))
    assert line.startswith(f"{tmp_path / 'm.yaml'}:{_line(text, 'max_steps')}:"), line
    assert "give a whole number from 1 to 2,147,483,647" in line, line
