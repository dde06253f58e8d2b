"""Function generation by a slider-crank or a six-bar in a model file (``kind: synthesis``
with ``function:`` and the run's ``linkage:``): a slider's positions read as lengths, the
linkages without a grounded output refused at their line (exit 2 from the command), and the
file's run writing a best.yaml whose kinematic run moves the slider as the offset
slider-crank's closed form ``s = r2 cos theta + sqrt(r3^2 - (e - r2 sin theta)^2)`` of the
numbers it reports (slow: the search compiles its program)."""

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from mixdyn.cli import app
from mixdyn.io import FileError
from mixdyn.runs import Runner
from mixdyn.synthesis import SliderCrank, WattII

#: A known offset slider-crank [mm]: crank, rod, offset; its crank's angles [deg].
R2, R3, E = 40.0, 150.0, 20.0
DEGREES = (20, 45, 70, 95, 120)


def _position(theta, r2=R2, r3=R3, e=E):
    theta = np.asarray(theta, dtype=float)
    return r2 * np.cos(theta) + np.sqrt(r3**2 - (e - r2 * np.sin(theta)) ** 2)


def _pairs() -> str:
    s = _position(np.deg2rad(DEGREES))
    return ", ".join(f"[{d} deg, {float(x)!r} mm]" for d, x in zip(DEGREES, s, strict=True))


SLIDER = f"""mixdyn: 1
units: {{length: mm, mass: kg, time: s}}
runs:
  - name: slide
    kind: synthesis
    linkage: slider_crank
    function:
      pairs: [{_pairs()}]
    starts: 32
"""


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


def test_a_sliders_positions_are_read_as_lengths():
    """The pairs' second numbers are lengths in the file's mm, handed over in m; an
    expression's ``output`` too; a Watt II's are angles."""
    task = Runner(mio.reads(SLIDER)).plans["slide"].task
    assert task.linkage is SliderCrank
    np.testing.assert_allclose(task.inputs, np.deg2rad(DEGREES), rtol=1e-15)
    np.testing.assert_allclose(task.outputs, _position(np.deg2rad(DEGREES)) / 1e3, rtol=1e-14)
    expr = SLIDER.replace(
        f"      pairs: [{_pairs()}]",
        "      expr: x**2\n      x: [0, 1]\n      input: [0 deg, 90 deg]\n"
        "      output: [100 mm, 160 mm]",
    )
    task = Runner(mio.reads(expr)).plans["slide"].task
    assert task.outputs[0] == pytest.approx(0.1 + 0.06 * task.inputs[0] ** 2 / (np.pi / 2) ** 2)
    assert task.scale == pytest.approx(np.ptp(task.outputs), rel=1e-15)
    watt = expr.replace("slider_crank", "watt2").replace("[100 mm, 160 mm]", "[10 deg, 50 deg]")
    task = Runner(mio.reads(watt)).plans["slide"].task
    x = task.inputs / (np.pi / 2)
    assert task.linkage is WattII
    np.testing.assert_allclose(task.outputs, np.deg2rad(10.0 + 40.0 * x**2), rtol=1e-14)


@pytest.mark.parametrize(
    "old, new, marker, words",
    [
        ("slider_crank", "watt1", "linkage", "only grounded output is the rocker"),
        ("slider_crank", "stephenson1", "linkage", "give linkage 'four_bar'"),
        ("    starts: 32", "    grashof: double_crank", "grashof", "no double crank"),
        ("linkage: slider_crank", "linkage: watt2\n    grashof: grashof", "grashof", "Grashof"),
        ("mm]", "deg]", "pairs", "deg"),
    ],
)  # fmt: skip
def test_bad_linkage_input_is_refused_at_its_line(old, new, marker, words):
    text = SLIDER.replace(old, new)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


def test_a_watt_i_function_exits_2_from_the_command(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(SLIDER.replace("slider_crank", "watt1"))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2, res.output
    assert "bad.yaml:6" in res.output and "rocker" in res.output
    assert not (tmp_path / "out" / "slide").exists()


@pytest.mark.slow  # long: run by CI's slow set (the search and best.yaml's run compile)
def test_a_slider_crank_file_finds_the_linkage_and_its_best_yaml_runs(tmp_path):
    """The file's run finds the slider-crank (its lengths in m to 1e-6), and its best.yaml,
    run by md.kinematic, moves the slider (``slider.x``) as the closed form of the numbers
    in candidates.csv."""
    path = tmp_path / "slide.yaml"
    path.write_text(SLIDER)
    md.run_file(path, tmp_path / "out")
    folder = tmp_path / "out" / "slide"
    table = pd.read_csv(folder / "candidates.csv")
    assert list(table.columns[:3]) == ["r2 [m]", "r3 [m]", "e [m]"]
    assert "error [m²]" in table.columns and "output_start [m]" in table.columns
    found = table.iloc[0, :3].to_numpy(dtype=float)
    np.testing.assert_allclose(found, np.array([R2, R3, E]) / 1e3, rtol=1e-6)
    best = md.load(folder / "best.yaml")
    theta = np.deg2rad(np.linspace(DEGREES[0], DEGREES[-1], 21))
    run = md.kinematic(best.model, theta - theta[0])
    np.testing.assert_allclose(run["slider.x"], _position(theta, *found), atol=1e-11)
