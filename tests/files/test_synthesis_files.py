"""Synthesis runs in model files (``kind: synthesis``): a file without a mechanism, its
numbers read with their units, bad input refused at its line before anything computes; the
file's search is the Python API's (same seed, same best error), and the written best.yaml,
run by mixdyn's own kinematic and inverse analyses, passes the targets within the reported
error at the reported torque (slow: each search compiles its program)."""

import dataclasses
import json

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
from mixdyn.synthesis import FourBar, Objective, PathTask, coupler_curve, transmission_cosine

EXAMPLE = EXAMPLES / "synthesis_path.yaml"

HEAD = "mixdyn: 1\nunits: {length: mm, mass: kg, time: s}\nruns:\n  - name: path\n"


def _text(*lines: str) -> str:
    body = ["    kind: synthesis", "    points: [[0, 0], [100, 50], [150, 120]]", *lines]
    return HEAD + "\n".join(body) + "\n"


def test_the_example_is_checked_without_a_mechanism():
    """``mixdyn check``: no mechanism, the run described; its numbers in SI (the example in
    mm, kg/m, m^2/(N m)^2, rad/s, deg: converted by hand here)."""
    lines = list(report(EXAMPLE))
    assert "no mechanism" in lines[0] and lines[-1].endswith("ok[/green]")
    assert any("synthesis" in line and "5 points" in line for line in lines)
    plan = Runner(mio.read(EXAMPLE)).plans["path"]
    np.testing.assert_allclose(plan.task.points[0], [0.5, 0.3], rtol=1e-15)
    assert plan.task.min_transmission == pytest.approx(np.pi / 9, rel=1e-15)
    o = plan.objective
    assert o.masses.density == pytest.approx(2.0) and o.masses.payload == 0.5
    assert o.masses.gravity == pytest.approx((0.0, -9.81))
    assert o.speed == pytest.approx(2 * np.pi) and o.torque_weight == pytest.approx(1e-4)


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


@pytest.mark.parametrize(
    "extra, marker, words",
    [
        (["    timing: [0 deg, 50 deg, 40 deg]"], "timing", "increase"),
        (["    bounds: {r9: [1, 2]}"], "bounds", "no number 'r9'"),
        (["    bounds:", "      r2: [50 mm, 10 mm]"], "r2:", "low <= high"),
        (["    bounds:", "      r2: [1 kg, 2 kg]"], "r2:", "kg"),
        (["    min_transmission: 95 deg"], "min_transmission", "pi/2"),
        (["    torque_weight: 1e-4 m^2/(N*m)^2"], "torque_weight", "masses"),
        (["    shaking_force_weight: 1e-4 m^2/N^2"], "shaking_force_weight", "masses"),
        (["    timing_from: ground"], "timing_from", "needs a timing"),
        (
            ["    timing: [0 deg, 50 deg, 90 deg]", "    timing_from: start"],
            "timing_from",
            "ground",
        ),
        (
            ["    masses: {density: 2 kg/m}", "    shaking_moment_weight: 1e-4 m^2/N^2"],
            "shaking_moment_weight",
            "N^2",
        ),
        (["    masses: {density: -2 kg/m}"], "masses", "density must be > 0"),
        (["    speed: 3 m/s"], "speed", "m/s"),
    ],
)
def test_bad_input_is_refused_at_its_line(extra, marker, words):
    """Each fault an input error (exit 2) at the line that holds it, before any search."""
    text = _text(*extra)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


def test_bad_input_exits_2_from_the_command(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(_text("    timing: [0, 1]"))
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2 and "bad.yaml:7" in res.output and "timing" in res.output
    assert not (tmp_path / "out" / "path").exists()


@pytest.mark.parametrize("command", [["show"], ["animate", "--run", "path"]])
def test_no_mechanism_to_draw_is_an_input_error(command, tmp_path):
    """``mixdyn show`` and ``mixdyn animate`` of a file of synthesis runs alone: exit 2,
    saying where the mechanism is (best.yaml), before anything is computed."""
    args = [command[0], str(EXAMPLE), *command[1:], "--output", str(tmp_path / "x.png")]
    if command[0] == "animate":
        args[-1] = str(tmp_path / "x.html")
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2 and "best.yaml" in res.output, res.output
    assert not list(tmp_path.iterdir())


def test_only_synthesis_runs_go_without_a_mechanism():
    text = "runs:\n  - {name: k, kind: kinematic, time: {span: [0, 1], n: 2}}\n"
    with pytest.raises(FileError, match="missing field 'bodies'"):
        mio.reads(text)


# A Grashof crank-rocker [m, rad] and six points near its coupler curve (moved by a few mm:
# no four-bar passes them exactly), at given input angles.
V = np.array([0.6, 0.2, 0.55, 0.4, 0.275, 0.55 / 3, 0.1, -0.05, 0.2])
W = np.array([0.6, 0.5, 0.55, 0.4, 0.275, 0.55 / 3, 0.1, -0.05, 0.2])  # opens part of a turn


def _curves_angles(c, samples=241):
    """The input angles of the rest of the turn in the figure (:func:`_curves`)."""
    return np.linspace(c.angles[-1], c.angles[0] + 2 * np.pi, samples)


THETA_DEG = np.array([20.0, 60.0, 100.0, 140.0, 180.0, 220.0])
MOVED = np.array([[3, -2], [-4, 1], [2, 5], [0, -3], [-5, 2], [4, 4]]) * 1e-3


def _targets() -> np.ndarray:
    fb = FourBar.from_vector(V, 1.0)
    return np.asarray(coupler_curve(fb, np.deg2rad(THETA_DEG))) + MOVED


def test_a_synthesis_is_written_as_its_files(tmp_path):
    """The run's files from a known outcome (no search): candidates.csv with SI headers and
    the candidate's numbers, best.yaml a model file whose crank pivot, coupler point and
    driver are the candidate's, meta.json, and the figure drawn."""
    from mixdyn.runs.outputs import Outputs
    from mixdyn.runs.synthesis import FileSynthesis, SynthesisKind, _curves
    from mixdyn.synthesis import Candidate, Synthesis

    theta = np.deg2rad(THETA_DEG)
    fb = FourBar(*(np.float64(x) for x in V), np.float64(1.0))
    points = np.asarray(coupler_curve(fb, theta))
    runner = Runner(mio.reads(_text()))
    plan = runner.plans["path"]
    c = Candidate(fb, theta, 0.0, 0.0, np.nan, np.nan, 0.7)
    out = Synthesis(PathTask(points, theta), Objective(), (c,), 4, 1, 0, 0.1)
    SynthesisKind().write(runner, plan, FileSynthesis(plan, out), 0.1, Outputs(tmp_path, "x"))
    table = pd.read_csv(tmp_path / "path" / "candidates.csv")
    assert list(table.columns) == [
        *(f"{n} [m]" for n in ("r1", "r2", "r3", "r4", "rcx", "rcy", "x0", "y0")),
        "theta0 [rad]", "branch", "theta_first [rad]", "theta_last [rad]", "error [m²]",
        "score [m²]", "min_transmission [rad]",
    ]  # fmt: skip
    np.testing.assert_array_equal(table.iloc[0, :9], V)
    best = mio.read(tmp_path / "path" / "best.yaml")
    assert best.ground.points["O2"] == (V[6], V[7])
    coupler = next(b for b in best.bodies if b.name == "coupler")
    a, p = (np.asarray(coupler.points[k], float) for k in ("A", "P"))
    np.testing.assert_allclose(p - a, V[4:6], atol=1e-15)  # in the coupler's frame
    meta = json.loads((tmp_path / "path" / "meta.json").read_text())
    assert "torque_rms" not in meta["synthesis"]["best"]  # no masses: no torque
    page = (tmp_path / "path" / "report.html").read_text()
    assert 'class="candidates"' in page and "r1 [m]" in page and "best.yaml" in page
    np.testing.assert_array_equal(meta["synthesis"]["angles"], theta)
    run, rest = _curves(c)  # the figure's curves: the loop closes over the whole turn
    np.testing.assert_allclose(run[[0, -1]], points[[0, -1]], atol=1e-12)
    assert not np.isnan(rest).any()
    c_open = dataclasses.replace(c, fourbar=FourBar(*(np.float64(x) for x in W), fb.branch))
    angles = jnp.asarray(_curves_angles(c))
    cos_mu = np.asarray(jax.vmap(lambda a: transmission_cosine(c_open.fourbar, a))(angles))
    np.testing.assert_array_equal(np.isnan(_curves(c_open)[1][:, 0]), np.abs(cos_mu) > 1)


@pytest.mark.slow  # long: run by CI's slow set (two searches compile their programs)
def test_file_search_is_the_apis_and_best_yaml_passes_the_targets(tmp_path):
    """The file's run (targets in mm, timing in deg) finds the API's best four-bar with the
    same seed; its best.yaml, loaded and run by md.kinematic (Newton's assembly of the
    written model, not the search's closed form), passes the targets with the reported
    error."""
    targets = _targets()
    mm = targets * 1e3
    points = ", ".join(f"[{float(x)!r} mm, {float(y)!r} mm]" for x, y in mm)
    timing = ", ".join(f"{a:g} deg" for a in THETA_DEG)
    path = tmp_path / "task.yaml"
    path.write_text(
        _text("    starts: 24", "    seed: 5", "    keep: 3").replace(
            "[[0, 0], [100, 50], [150, 120]]", f"[{points}]"
        )
        + f"    timing: [{timing}]\n"
    )
    md.run_file(path, tmp_path / "out")
    folder = tmp_path / "out" / "path"
    table = pd.read_csv(folder / "candidates.csv")
    assert list(table.columns[:3]) == ["r1 [m]", "r2 [m]", "r3 [m]"]
    assert "error [m²]" in table.columns and "branch" in table.columns
    error = float(table["error [m²]"].iloc[0])
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["status"] == "ok" and meta["synthesis"]["best"]["error"] == error

    api = md.synthesize(
        PathTask(mm * 1e-3, timing=np.deg2rad(THETA_DEG)), Objective(), starts=24, seed=5
    )
    assert error == pytest.approx(api.best.error, rel=1e-9)
    assert 1e-7 < error < 1e-3  # the moved points: a real, small error

    best = md.load(folder / "best.yaml")
    t = np.deg2rad(THETA_DEG - THETA_DEG[0]) / 1.0  # the crank at the default 1 rad/s
    p, _, _ = md.kinematic(best.model, t).point("coupler.P")
    assert np.sum((p - targets) ** 2) == pytest.approx(error, rel=1e-8)


@pytest.mark.slow  # long: run by CI's slow set (the torque objective's search compiles ~1 min)
def test_the_example_runs_and_its_best_yaml_runs(tmp_path):
    """``mixdyn run`` of the example writes the ranked candidates, best.yaml, meta.json and
    the figure; ``mixdyn run best.yaml`` runs, its coupler point through the five targets
    (exact: five points, timing free) and its motor torque by md.inverse's multipliers the
    search's energy-balance torque."""
    cli = CliRunner()
    res = cli.invoke(app, ["run", str(EXAMPLE), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "path"
    for name in ("candidates.csv", "best.yaml", "meta.json", "synthesis.png"):
        assert (folder / name).is_file(), name
    table = pd.read_csv(folder / "candidates.csv")
    assert table["error [m²]"].iloc[0] < 1e-20
    res = cli.invoke(app, ["run", str(folder / "best.yaml"), "--out", str(tmp_path / "best")])
    assert res.exit_code == 0, res.output
    path = md.read_table(tmp_path / "best" / "path" / "results.csv")
    curve = np.column_stack([path["coupler.P.x"], path["coupler.P.y"]])
    targets = Runner(mio.read(EXAMPLE)).plans["path"].task.points
    gaps = np.min(np.linalg.norm(curve[:, None, :] - targets[None], axis=2), axis=0)
    assert gaps[0] < 1e-9 and gaps[-1] < 1e-9  # the first and last output times
    assert np.all(gaps < 0.02)  # the others between output times, 101 along the motion
    torque = md.read_table(tmp_path / "best" / "torque" / "results.csv")["motor"]
    rms = float(np.sqrt(np.mean(np.asarray(torque) ** 2)))
    assert rms == pytest.approx(table["torque_rms [N·m]"].iloc[0], rel=0.02)


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_no_feasible_four_bar_is_a_named_numerical_failure(tmp_path):
    """Bounds no four-bar can meet (a crank ten times the ground link and the rocker): exit
    1 with the cause and what to relax, meta.json ``status: failed`` and the failure's page."""
    path = tmp_path / "task.yaml"
    path.write_text(
        _text(
            "    bounds: {r1: [10 mm, 11 mm], r2: [1000 mm, 1001 mm], r4: [10 mm, 11 mm]}",
            "    starts: 4",
        )
    )
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 1 and "no feasible four-bar among 4 starts" in res.output
    assert "wider bounds" in res.output and "internal error" not in res.output
    meta = json.loads((tmp_path / "out" / "path" / "meta.json").read_text())
    assert meta["status"] == "failed" and meta["failure"]["error"] == "NumericalError"
    assert (tmp_path / "out" / "path" / "report.html").is_file()


FUNCTION = """mixdyn: 1
parameters: {x1: 2}
runs:
  - name: log
    kind: synthesis
    function:
      expr: log10(x)
      x: [1, x1]
      input: [0 deg, 60 deg]
      output: [240 deg, 180 deg]
    starts: 32
"""


def test_a_function_task_is_read_with_its_units():
    """``function:`` with an expression of x and a parameter: Chebyshev's three points (by
    hand), the angles in rad; the function example checked as mixdyn check does."""
    lines = list(report(EXAMPLES / "synthesis_function.yaml"))
    assert "no mechanism" in lines[0] and "generating a function at 3 points" in lines[1]
    task = Runner(mio.reads(FUNCTION)).plans["log"].task
    x = 1.5 + 0.5 * np.array([-1.0, 0.0, 1.0]) * np.sqrt(3) / 2
    np.testing.assert_allclose(task.inputs, np.deg2rad(60.0) * (x - 1.0), rtol=1e-14)
    y = np.log10(x) / np.log10(2.0)
    np.testing.assert_allclose(task.outputs, np.deg2rad(240.0 - 60.0 * y), rtol=1e-14)


@pytest.mark.parametrize(
    "old, new, marker, words",
    [
        ("    starts: 32", "    timing: free", "timing", "path generation"),
        ("log10(x)", "log10(x) + y", "expr", "y"),
        ("x: [1, x1]", "x: [-1, x1]", "expr", "not finite"),
        ("      expr: log10(x)\n      x: [1, x1]\n      input: [0 deg, 60 deg]\n"
         "      output: [240 deg, 180 deg]\n",
         "      pairs: [[0 deg, 240 deg], [50 deg, 200 deg], [40 deg, 180 deg]]\n",
         "pairs", "increase"),
        ("input: [0 deg, 60 deg]", "input: [0 mm, 60 mm]", "input", "mm"),
    ],
)  # fmt: skip
def test_bad_function_input_is_refused_at_its_line(old, new, marker, words):
    text = FUNCTION.replace(old, new)
    with pytest.raises(FileError) as e:
        Runner(mio.reads(text, "bad.yaml"))
    assert e.value.line == _line(text, marker), str(e.value)
    assert words in str(e.value)


@pytest.mark.slow  # long: run by CI's slow set (the search and best.yaml's run compile)
def test_a_function_file_finds_freudensteins_linkage_and_its_best_yaml_runs(tmp_path):
    """The file's run finds the four-bar of Freudenstein's 3x3 solve (ratios to 1e-9), and its
    best.yaml, run by md.kinematic, turns the rocker through the asked angles."""
    path = tmp_path / "log.yaml"
    path.write_text(FUNCTION)
    md.run_file(path, tmp_path / "out")
    table = pd.read_csv(tmp_path / "out" / "log" / "candidates.csv")
    task = Runner(mio.reads(FUNCTION)).plans["log"].task
    th2, th4 = task.inputs, task.outputs
    k = np.linalg.solve(np.column_stack([np.cos(th4), -np.cos(th2), np.ones(3)]), np.cos(th2 - th4))
    a, c = 1 / k[0], 1 / k[1]
    b = np.sqrt(a * a + c * c + 1 - 2 * a * c * k[2])
    np.testing.assert_allclose(table[["r2", "r3", "r4"]].iloc[0], [a, b, c], rtol=1e-9)
    best = md.load(tmp_path / "out" / "log" / "best.yaml")
    run = md.kinematic(best.model, th2 - th2[0])  # the crank from the first input at 1 rad/s
    gap = np.angle(np.exp(1j * (run["rocker.phi"] - th4)))
    assert np.max(np.abs(gap)) < 1e-8


def test_dynamic_weights_are_read_in_si():
    """``shaking_force_weight: 2 mm^2/N^2`` is 2e-6 m^2/N^2 (by hand), the moment's
    ``3 mm^2/(N*mm)^2`` 3 m^2/(N m)^2, ``reaction_weight: 5 cm^2/N^2`` 5e-4 m^2/N^2; the
    measures as written."""
    text = _text(
        "    masses: {density: 2 kg/m}",
        "    shaking: peak",
        "    shaking_force_weight: 2 mm^2/N^2",
        "    shaking_moment_weight: 3 mm^2/(N*mm)^2",
        "    reaction_weight: 5 cm^2/N^2",
        "    reaction: rms",
    )
    o = Runner(mio.reads(text, "shaking.yaml")).plans["path"].objective
    assert o.shaking_force_weight == pytest.approx(2e-6, rel=1e-14)
    assert o.shaking_moment_weight == pytest.approx(3.0, rel=1e-14)
    assert o.reaction_weight == pytest.approx(5e-4, rel=1e-14) and o.reaction == "rms"
    assert o.shaking == "peak" and o.torque_weight == 0 and o.dynamic
