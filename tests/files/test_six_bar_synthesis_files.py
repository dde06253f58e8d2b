"""Six-bar synthesis runs in model files (``kind: synthesis``, ``linkage: stephenson3`` or
``watt1``): the linkage, its numbers and masses read with their units, another linkage's
numbers refused at its line before anything computes, a bad
linkage name an input error (exit 2) from the command; the figure's curve left out where the
dyad opens (slow); the file's search finds a known Watt I and its best.yaml runs (slow)."""

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from mixdyn.cli import app
from mixdyn.io import FileError
from mixdyn.runs import Runner
from mixdyn.runs.report import report
from mixdyn.synthesis import (
    Candidate,
    StephensonI,
    StephensonIII,
    WattI,
    WattII,
    coupler_curve,
)

HEAD = "mixdyn: 1\nunits: {length: mm, mass: kg, time: s}\nruns:\n  - name: path\n"


def _text(*lines: str) -> str:
    body = ["    kind: synthesis", "    points: [[0, 0], [100, 50], [150, 120]]", *lines]
    return HEAD + "\n".join(body) + "\n"


def _line(text: str, marker: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), 1) if marker in line)


@pytest.mark.parametrize("name, cls, number", [("stephenson3", StephensonIII, "gx"),
                                               ("watt1", WattI, "fx"),
                                               ("watt2", WattII, "dy"),
                                               ("stephenson1", StephensonI, "fy")])  # fmt: skip
def test_the_linkage_and_its_bounds_are_read_in_si(name, cls, number, tmp_path):
    """``linkage: stephenson3`` / ``watt1`` / ``watt2``: the task's linkage, a bound in SI
    (mm -> m, by hand), its masses and torque weight read; ``mixdyn check`` names the
    linkage."""
    text = _text(
        f"    linkage: {name}",
        f"    bounds: {{{number}: [-20, 30], r5: [10, 90]}}",
        "    masses: {density: 2 kg/m, payload: 300 g}",
        "    torque_weight: 1e-4 m^2/(N*m)^2",
    )
    plan = Runner(mio.reads(text, "six.yaml")).plans["path"]
    assert plan.task.linkage is cls
    assert plan.objective.masses.payload == pytest.approx(0.3, rel=1e-15)
    assert plan.objective.torque_weight == pytest.approx(1e-4, rel=1e-15)
    box = plan.task.box()
    np.testing.assert_allclose(box[cls.NAMES.index(number)], [-0.02, 0.03], rtol=1e-15)
    np.testing.assert_allclose(box[4], [0.01, 0.09], rtol=1e-15)
    path = tmp_path / "six.yaml"
    path.write_text(text)
    assert any(f"a {cls.TITLE} through 3 points" in line for line in report(path))


@pytest.mark.parametrize(
    "extra, marker, words",
    [
        (["    linkage: stephenson3", "    bounds: {fx: [1, 2]}"], "bounds", "no number 'fx'"),
        (["    linkage: watt1", "    bounds: {e: [1, 2]}"], "bounds", "no number 'e'"),
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
    """``linkage: watt_1``: exit 2, the line and the key named, the six-bars' names given, no
    output written."""
    path = tmp_path / "bad.yaml"
    text = _text("    linkage: watt_1")
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2, res.output
    assert f"bad.yaml:{_line(text, 'linkage')}" in res.output and "linkage" in res.output
    assert "stephenson3" in res.output and "watt1" in res.output
    assert not (tmp_path / "out" / "path").exists()


@pytest.mark.slow  # long: run by CI's slow set (compiles the six-bar's curve twice)
def test_the_figure_leaves_out_where_the_dyad_opens():
    """The figure's rest of the turn (runs.synthesis._curves) is NaN exactly where either loop
    opens (the worse transmission cosine beyond 1): a Watt I whose tracer and follower
    (0.35 + 0.3 m) span |D F| (0.42 to 0.76 m along the turn) over part of it only."""
    from mixdyn.runs.synthesis import _curves

    v = np.array([1.0, 0.3, 1.1, 0.9, 0.35, 0.3, 0.6, 0.4, 0.5, 0.3, 0.5, 0.2, 0.1, -0.2, 0.3])
    lk = WattI(*(np.float64(x) for x in v), np.float64(3.0))
    c = Candidate(lk, np.array([-0.5, 0.5]), 0.0, 0.0, np.nan, np.nan, 0.5)
    _, rest = _curves(c)
    angles = jnp.linspace(0.5, 2 * np.pi - 0.5, 241)
    cos_mu = np.asarray(jax.jit(jax.vmap(lk.transmission_cosine))(angles))
    assert np.any(np.abs(cos_mu) > 1) and np.any(np.abs(cos_mu) < 1)
    np.testing.assert_array_equal(np.isnan(rest[:, 0]), np.abs(cos_mu) > 1)


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its programs, ~25 s)
def test_file_search_finds_a_watt_i_and_best_yaml_runs(tmp_path):
    """Eight points of a Watt I's curve in mm, their input angles in deg, every number bounded
    within 20 % of the fixture's: ``mixdyn run`` (the command, figures on) finds a Watt I
    through them (error <= 1e-8 m², its numbers and branch code in candidates.csv, its figure
    written); the written best.yaml, run by Newton's assembly of its seven joints, puts
    tracer.P on the candidate's closed-form points."""
    v = np.array([1.0, 0.3, 1.1, 0.9, 1.2, 1.0, 0.6, 0.4, 0.5, 0.3, 0.5, 0.2, 0.1, -0.2, 0.3])
    theta = np.linspace(20.0, 250.0, 8)
    points = np.asarray(coupler_curve(WattI.from_vector(jnp.asarray(v), 3.0), np.deg2rad(theta)))
    listed = ", ".join(f"[{float(x) * 1e3!r}, {float(y) * 1e3!r}]" for x, y in points)
    timing = ", ".join(f"{a:g} deg" for a in theta)
    box = ", ".join(
        f"{n}: [{(x - 0.2 * max(abs(x), 0.3)) * 1e3!r}, {(x + 0.2 * max(abs(x), 0.3)) * 1e3!r}]"
        for n, x in zip(WattI.NAMES[:-1], v[:-1].tolist(), strict=True)
    )
    text = (
        HEAD
        + "    kind: synthesis\n    linkage: watt1\n"
        + (
            f"    points: [{listed}]\n    timing: [{timing}]\n    bounds: {{{box}}}\n"
            "    starts: 64\n    seed: 1\n"
        )
    )
    path = tmp_path / "task.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "out" / "path"
    table = pd.read_csv(folder / "candidates.csv")
    assert list(table.columns[8:10]) == ["fx [m]", "fy [m]"]
    assert float(table["error [m²]"].iloc[0]) <= 1e-8
    assert float(table["branch"].iloc[0]) in WattI.BRANCHES
    assert (folder / "synthesis.png").exists()
    best = md.load(folder / "best.yaml")
    assert {j.name for j in best.model.joints} == {"O2", "A", "B", "O4", "D", "E", "F"}
    row = table.iloc[0]
    found = WattI(*(np.float64(row[f"{n} [{'rad' if n == 'theta0' else 'm'}]"])
                    for n in WattI.NAMES), np.float64(row["branch"]))  # fmt: skip
    first, last = float(row["theta_first [rad]"]), float(row["theta_last [rad]"])
    angles = first + np.deg2rad(theta - theta[0])
    assert angles[-1] == pytest.approx(last, abs=1e-12)
    kin = md.kinematic(best.model, angles - first)
    p, _, _ = kin.point("tracer.P")
    assert np.max(np.abs(p - np.asarray(coupler_curve(found, jnp.asarray(angles))))) < 1e-9
    assert np.sum((p - points) ** 2) <= 1e-8
