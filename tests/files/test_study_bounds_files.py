"""The bounds and starts of a file's optimization and identification runs are values of
the numbers they vary: one a model built from the file refuses (a negative mass or free
length) is refused at its line before any search (exit 2), naming the bound or start."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from fixtures import EXAMPLES
from mixdyn.cli import app


def _line(text: str, words: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if words in line)


def test_optimization_bounds_a_file_refuses_are_refused_at_their_line(tmp_path):
    """A bound an optimization would try and the file refuses written in (a negative free
    length) is refused at the bound's line before any search, naming the bound."""
    text = (EXAMPLES / "slider_crank_spring.yaml").read_text()
    written = "free_length: 300 mm}"
    (tmp_path / "single.yaml").write_text(text.replace(written, "free_length: -5 mm}", 1))
    single = CliRunner().invoke(app, ["check", str(tmp_path / "single.yaml")])
    assert single.exit_code == 2 and "free_length must be >= 0" in single.output
    bounds = "spring.free_length: {bounds: [0 mm, 1000 mm]}"
    text = text.replace(bounds, "spring.free_length:\n        bounds: [-5 mm, 1000 mm]", 1)
    path = tmp_path / "opt.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    assert "the low bound: spring.free_length = -5 is refused" in res.output  # [mm]
    assert "free_length must be >= 0" in res.output
    assert f"opt.yaml:{_line(text, 'bounds: [-5 mm, 1000 mm]')}" in res.output


@pytest.mark.parametrize(
    ("fit", "words", "where"),
    [
        ("rod.mass: {bounds: [-10, 10]}", "the low bound: rod.mass = -10", "bounds: [-10"),
        ("rod.mass: {start: -1}", "the start: rod.mass = -1", "start: -1"),
    ],
)
def test_fit_bounds_and_starts_a_file_refuses_are_refused_at_their_line(
    tmp_path, fit, words, where
):
    text = (EXAMPLES / "identify_slider_crank.yaml").read_text().split("\nruns:")[0]
    text += f"""
runs:
  - name: forward
    kind: forward
    time: {{span: [0, 1], n: 5}}
  - name: identify
    kind: identify
    run: forward
    data: rec.csv
    measured:
      - {{column: slider.x, data: x, noise: 1 mm}}
    fit:
      {fit.split(": ", 1)[0]}:
        {fit.split(": ", 1)[1].strip("{}")}
"""
    pd.DataFrame({"t": np.linspace(0, 1, 5), "x": np.linspace(0.1, 0.2, 5)}).to_csv(
        tmp_path / "rec.csv", index=False
    )
    path = tmp_path / "fit.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    assert words in res.output and "mass must be a finite number >= 0" in res.output
    assert f"fit.yaml:{_line(text, where)}" in res.output
