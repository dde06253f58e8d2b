"""Slider-crank synthesis runs in model files (``kind: synthesis``, ``linkage:
slider_crank``): the linkage and its numbers read with their units, bad input refused at its
line (exit 2) before anything computes, the run's files from a known outcome; slow: the
file's search recovers a slider-crank from points of its curve and its best.yaml, run by
``mixdyn run``'s kinematic analysis, passes them."""

import jax
import jax.numpy as jnp
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
from mixdyn.synthesis import SliderCrank, coupler_curve, transmission_cosine

EXAMPLE = EXAMPLES / "synthesis_slider.yaml"
HEAD = "mixdyn: 1\nunits: {length: mm, mass: kg, time: s}\nruns:\n  - name: path\n"


def _text(*lines: str) -> str:
    body = ["    kind: synthesis", "    points: [[0, 0], [100, 50], [150, 120]]", *lines]
    return HEAD + "\n".join(body) + "\n"


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


def test_the_linkage_and_its_bounds_are_read_in_si(tmp_path):
    """``linkage: slider_crank``: the task's linkage, its offset's bounds in SI (mm -> m, by
    hand), the slider's mass read; ``mixdyn check`` names the linkage."""
    text = _text(
        "    linkage: slider_crank",
        "    bounds: {e: [-20, 30], theta0: [0 deg, 90 deg]}",
        "    masses: {density: 2 kg/m, slider: 500 g}",
    )
    plan = Runner(mio.reads(text, "sc.yaml")).plans["path"]
    assert plan.task.linkage is SliderCrank
    np.testing.assert_allclose(plan.task.box()[2], [-0.02, 0.03], rtol=1e-15)
    np.testing.assert_allclose(plan.task.box()[7], [0.0, np.pi / 2], rtol=1e-15)
    assert plan.objective.masses.slider == pytest.approx(0.5, rel=1e-15)
    path = tmp_path / "sc.yaml"
    path.write_text(text)
    assert any("a slider-crank through 3 points" in line for line in report(path))


def test_the_example_is_checked_without_a_mechanism():
    """``examples/synthesis_slider.yaml``: no mechanism, a slider-crank's run described, its
    points in SI (mm -> m by hand), the slider's mass and the speed read."""
    lines = list(report(EXAMPLE))
    assert "no mechanism" in lines[0] and lines[-1].endswith("ok[/green]")
    assert any("a slider-crank through 5 points" in line for line in lines)
    plan = Runner(mio.read(EXAMPLE)).plans["path"]
    assert plan.task.linkage is SliderCrank
    np.testing.assert_allclose(plan.task.points[0], [0.15, 0.08], rtol=1e-15)
    assert plan.objective.masses.slider == 0.5
    assert plan.objective.speed == pytest.approx(2 * np.pi)
    assert plan.task.min_transmission == pytest.approx(np.pi / 6, rel=1e-15)


@pytest.mark.parametrize(
    "extra, marker, words",
    [
        (["    linkage: slider-crank"], "linkage", "'watt1' or 'watt2'"),
        (["    linkage: slider_crank", "    bounds: {r4: [1, 2]}"], "bounds", "no number 'r4'"),
        (["    linkage: slider_crank", "    masses: {density: 2 kg/m}"], "masses", "slider"),
    ],
)
def test_bad_input_is_refused_at_its_line(extra, marker, words):
    """Each fault an input error at the line that holds it, before any search."""
    text = _text(*extra)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


def test_a_bad_linkage_name_exits_2_from_the_command(tmp_path):
    """``mixdyn run`` of a file whose linkage is misspelt: exit 2, the file's line and the
    key named, the allowed names given, no output written."""
    path = tmp_path / "bad.yaml"
    text = _text("    linkage: slidercrank")
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2, res.output
    assert f"bad.yaml:{_line(text, 'linkage')}" in res.output and "linkage" in res.output
    assert "slider_crank" in res.output
    assert not (tmp_path / "out" / "path").exists()


# An offset slider-crank [m, rad] (as tests/analyses/test_slider_crank_synthesis.py's).
V = np.array([0.1, 0.35, 0.04, 0.15, 0.08, 0.02, -0.01, 0.25])


def test_the_figure_leaves_out_where_the_rod_cannot_reach_the_slide():
    """The figure's rest of the turn (runs.synthesis._curves, in NumPy) is NaN exactly where
    the closed form's |cos mu| > 1, for a slider-crank whose crank does not turn fully
    (r2 + e > r3)."""
    from mixdyn.runs.synthesis import _curves
    from mixdyn.synthesis import Candidate

    v = V.copy()
    v[2] = 0.3  # offset 0.3: 0.1 + 0.3 > 0.35
    sc = SliderCrank(*(np.float64(x) for x in v), np.float64(1.0))
    c = Candidate(sc, np.array([-0.5, 0.5]), 0.0, 0.0, np.nan, np.nan, 0.5)
    run, rest = _curves(c)
    assert not np.isnan(run).any()
    angles = jnp.linspace(0.5, 2 * np.pi - 0.5, 241)
    cos_mu = np.asarray(jax.vmap(lambda a: transmission_cosine(sc, a))(angles))
    assert np.any(np.abs(cos_mu) > 1) and np.any(np.abs(cos_mu[1:]) < 1)
    np.testing.assert_array_equal(np.isnan(rest[:, 0]), np.abs(cos_mu) > 1)


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its programs)
def test_file_search_recovers_a_slider_crank_and_best_yaml_runs(tmp_path):
    """Six points of a slider-crank's curve in mm, their input angles in deg: ``mixdyn run``
    finds it (path error ~ 0, its numbers in candidates.csv); the written best.yaml, run by
    ``mixdyn run`` (Newton's assembly of the written model), puts rod.P on the points."""
    theta = np.linspace(20.0, 230.0, 6)
    points = np.asarray(coupler_curve(SliderCrank.from_vector(V, 1.0), np.deg2rad(theta)))
    listed = ", ".join(f"[{float(x) * 1e3!r}, {float(y) * 1e3!r}]" for x, y in points)
    timing = ", ".join(f"{a:g} deg" for a in theta)
    text = (
        HEAD
        + "    kind: synthesis\n    linkage: slider_crank\n"
        + f"    points: [{listed}]\n    timing: [{timing}]\n    starts: 64\n    seed: 1\n"
    )
    path = tmp_path / "task.yaml"
    path.write_text(text)
    md.run_file(path, tmp_path / "out")
    table = pd.read_csv(tmp_path / "out" / "path" / "candidates.csv")
    assert list(table.columns[:3]) == ["r2 [m]", "r3 [m]", "e [m]"]
    assert float(table["error [m²]"].iloc[0]) < 1e-16
    np.testing.assert_allclose(table.iloc[0, :3], V[:3], atol=1e-8)
    best = md.load(tmp_path / "out" / "path" / "best.yaml")
    assert {j.name for j in best.model.joints} == {"O2", "A", "B", "slide"}
    kin = md.kinematic(best.model, np.deg2rad(theta - theta[0]))
    p, _, _ = kin.point("rod.P")
    assert np.max(np.abs(p - points)) < 1e-9
