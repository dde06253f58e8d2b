"""The columns a model file may name (plots, summaries, objectives) are exactly those its runs
produce: ``Runner.columns`` against the executed results of every kind of run, and a column a
run will not have is refused by ``mixdyn check`` (exit 2) with close matches (issue 14)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.cli import app
from mixdyn.runs import Runner


def _short(name: str) -> str:
    """An example with short runs (the column names do not depend on the length); the
    paper's example as it is (its runs take milliseconds, and its programs are those of the
    other tests that run it)."""
    text = (EXAMPLES / name).read_text()
    return text.replace("n: 181", "n: 5")


@pytest.mark.parametrize("name", ["slider_crank.yaml", "antonya.yaml"])
def test_the_promised_columns_are_the_results_columns(name):
    runner = Runner(mio.reads(_short(name)))
    results = runner.execute()
    assert {r.kind for r in results.values()} >= (
        {"kinematic", "inverse"} if "slider" in name else {"forward", "mixed"}
    )
    for plan in runner.plans.values():
        promised, owners = runner.columns(plan.spec)
        got = list(results[plan.name].columns())
        lambdas = [c for c in got if c.startswith("lambda.")]
        assert sorted(promised) == sorted(c for c in got if c not in lambdas), plan.name
        assert all(any(c.startswith(f"lambda.{o}") for o in owners) for c in lambdas)


@pytest.mark.parametrize(
    ("run", "column", "words"),
    [
        ("forward", "A.M", "no column 'A.M'"),  # a revolute joint carries no moment
        ("forward", "B.Fz", "no column 'B.Fz'"),
        ("forward", "F1.tension", "no column 'F1.tension'"),  # a point force: no tension
        ("forward", "work.total", "no column"),
        ("mixed", "F1.powr", "F1.power"),
    ],
)
def test_a_column_the_run_will_not_have_is_refused(tmp_path, run, column, words):
    text = _short("antonya.yaml")
    if run == "forward":
        text = text.replace("columns: [slider.x]", f"columns: [slider.x, {column}]", 1)
    else:
        text = text.replace("columns: [F1]", f"columns: [F1, {column}]", 1)
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert words in res.output and "bad.yaml" in res.output


def test_a_kinematic_run_has_the_motion_only(tmp_path):
    text = _short("slider_crank.yaml")
    assert "kind: kinematic" in text
    runner = Runner(mio.reads(text))
    kin = next(p for p in runner.plans.values() if p.spec.kind == "kinematic")
    with pytest.raises(mio.FileError, match="a kinematic run has the motion only"):
        runner.check_column("O.Fx", kin.spec, kin.path)
    runner.check_column("rod.B.ay", kin.spec, kin.path)  # a point's acceleration: there


def test_a_plot_against_another_column(tmp_path):
    """``x: crank.phi`` (the torque against the crank angle): written; an unknown x column,
    or a reference curve (a law of t) with another x, refused at the line."""
    text = _short("slider_crank.yaml")
    assert "columns: [motor], title" in text
    good = text.replace("columns: [motor], title", "columns: [motor], x: crank.phi, title", 1)
    path = tmp_path / "x.yaml"
    path.write_text(good)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert (out / "inverse" / "motor_torque.svg").stat().st_size > 10_000
    path.write_text(
        text.replace("columns: [motor], title", "columns: [motor], x: crank.phy, title")
    )
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2 and "no column 'crank.phy'" in res.output, res.output


def test_a_run_without_plots_draws_the_usual_ones(tmp_path):
    """No plots: section: an inverse run draws its drivers' efforts and its reactions (what
    check promised and run wrote); a kinematic run draws nothing by default."""
    lines = [ln for ln in _short("slider_crank.yaml").splitlines() if "{file:" not in ln]
    text = "\n".join(ln for ln in lines if ln.strip() != "plots:") + "\n"
    path = tmp_path / "noplots.yaml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(out)])
    assert res.exit_code == 0, res.output
    inverse = next(p for p in out.iterdir() if (p / "efforts.png").exists())
    assert (inverse / "reactions.png").stat().st_size > 10_000
    kinematic = [p for p in out.iterdir() if p != inverse]
    assert kinematic and not list(kinematic[0].glob("*.png"))
