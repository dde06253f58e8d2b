"""Design optimization (``md.optimize`` and ``kind: optimize`` runs): the spring that best
relieves a slider-crank's motor (``examples/slider_crank_spring.yaml``) is the least-squares
solution in closed form (the motor torque is linear in the stiffness k and in k times the free
length, so three inverse runs give the truth); the command line writes the optimum; a bad run
is refused at its line before any computing."""

from __future__ import annotations

import json

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.cli import app

EXAMPLE = EXAMPLES / "slider_crank_spring.yaml"
TEXT = EXAMPLE.read_text()
PARAMS = ["spring.stiffness", "spring.free_length"]
BOUNDS = {"spring.stiffness": (0.0, 1e5), "spring.free_length": (0.0, 1000.0)}


@pytest.fixture(scope="module")
def setup():
    spec = mio.read(EXAMPLE)
    model = mio.build(spec)
    t = mio.Runner(spec).plans["revolution"].times
    return model, t


def _least_squares(model, t):
    """``(k, L0)`` minimizing the RMS motor torque, from three inverse runs: the torque is
    ``tau0 + k A + (k L0) B``."""

    def at(k, length):
        m = eqx.tree_at(lambda m: m.forces[0].stiffness, model, jnp.asarray(k))
        return eqx.tree_at(lambda m: m.forces[0].free_length, m, jnp.asarray(length))

    tau0 = md.inverse(at(0.0, 0.0), t)["motor"]
    a = md.inverse(at(1.0, 0.0), t)["motor"] - tau0
    b = md.inverse(at(1.0, 1.0), t)["motor"] - tau0 - a
    (k, c), *_ = np.linalg.lstsq(np.stack([a, b], 1), -tau0, rcond=None)
    return np.array([k, c / k]), np.sqrt(np.mean((tau0 + k * a + c * b) ** 2))


def test_the_optimal_spring_is_the_least_squares_one(setup):
    model, t = setup
    truth, rms = _least_squares(model, t)
    opt = md.optimize(
        model,
        t,
        lambda o: jnp.sqrt(jnp.mean(o["motor"] ** 2)),
        PARAMS,
        BOUNDS,
        analysis="inverse",
    )
    np.testing.assert_allclose(opt.values, truth, rtol=1e-7)
    assert abs(opt.objective / rms - 1) <= 1e-8
    assert opt.objective < 0.25 * opt.objective_start  # the spring relieves the motor
    assert np.all(np.diff(opt.history) <= 1e-9 * opt.history[0])  # never worse
    assert list(opt.table()["parameter"]) == PARAMS


def test_the_command_line_writes_the_optimum(setup, tmp_path):
    model, t = setup
    truth, rms = _least_squares(model, t)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(EXAMPLE), "--out", str(out), "--run", "spring"])
    assert res.exit_code == 0, res.output
    table = pd.read_csv(out / "spring" / "optimum.csv")
    np.testing.assert_allclose(table["optimum"], truth, rtol=1e-7)
    meta = json.loads((out / "spring" / "meta.json").read_text())
    assert abs(meta["optimize"]["objective_optimum"] / rms - 1) <= 1e-8
    run = md.read_table(out / "spring")  # the inverse run at the optimum
    assert abs(np.sqrt(np.mean(run["motor"] ** 2)) / rms - 1) <= 1e-8
    assert (out / "spring" / "optimize.png").stat().st_size > 10_000


def test_maximizing_ends_on_a_bound(tmp_path):
    """The RMS torque is convex in the stiffness alone (the free length held): maximized, it
    climbs to a bound; maximize reports the objective itself (positive)."""
    text = TEXT.replace("reduce: rms}", "reduce: rms}\n    sense: maximize")
    text = text.replace("      spring.free_length: {bounds: [0 mm, 1000 mm]}\n", "")
    path = tmp_path / "max.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out), "--run", "spring"])
    assert res.exit_code == 0, res.output
    table = pd.read_csv(out / "spring" / "optimum.csv")
    at_bound = np.isclose(table["optimum"], table["low"]) | np.isclose(
        table["optimum"], table["high"]
    )
    assert at_bound.all(), table
    meta = json.loads((out / "spring" / "meta.json").read_text())["optimize"]
    assert meta["objective_optimum"] > meta["objective_start"] > 0


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (("    run: revolution", "    run: nope"), "unknown run 'nope'"),
        (("{column: motor, reduce: rms}", "{column: motr, reduce: rms}"), "'motr' is not"),
        (("spring.stiffness: {bounds", "spring.stifness: {bounds"), "no field 'stifness'"),
        (("spring.stiffness: {bounds", "O.si: {bounds"), "geometry"),
        (('["0 N/mm", "100 N/mm"]', '["0 N/mm", "100 N"]'), "expected a stiffness"),
        (('["0 N/mm", "100 N/mm"]', '["5 N/mm", "1 N/mm"]'), "are empty"),
        (("[0 mm, 1000 mm]}", "[0 mm, 1000 mm], start: 2 m}"), "outside"),
        (("reduce: rms}", "reduce: median}"), "reduce"),
    ],
)
def test_a_bad_optimize_run_is_refused_before_computing(tmp_path, edit, words):
    old, new = edit
    assert old in TEXT
    path = tmp_path / "bad.yaml"
    path.write_text(TEXT.replace(old, new, 1))
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert words in res.output and "bad.yaml" in res.output


def test_python_bounds_are_checked(setup):
    model, t = setup
    rms = lambda o: jnp.sqrt(jnp.mean(o["motor"] ** 2))  # noqa: E731
    with pytest.raises(md.ModelError, match="needs bounds"):
        md.optimize(model, t, rms, PARAMS, {"spring.stiffness": (0, 1)}, analysis="inverse")
    with pytest.raises(md.ModelError, match=r"not varied: rod\.mass"):
        md.optimize(model, t, rms, PARAMS, {**BOUNDS, "rod.mass": (0, 1)}, analysis="inverse")
