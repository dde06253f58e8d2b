"""A kinematic sweep held as arrays (:mod:`mixdyn.analysis._kinematic_members`): each member
prepared like a single run, one vectorized program running the single run's scan, every
member's result built when read. Truth: ``md.kinematic`` of each member's model (a second
method, member by member): the members' columns and a point's to rounding, the counters, and
a failed member's named error (its class and time)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import mixdyn as md
from fixtures import slider_crank
from mixdyn.analysis import _kinematic_members

sweep_module = importlib.import_module("mixdyn.analysis.sweep")

T = np.linspace(0.0, 1.0, 11)


def _models(count: int, rng) -> list[md.Model]:
    """Slider-cranks of other rod lengths, crank speeds and start angles: each member's own
    start (a rod length changes the assembly), the same structure."""
    return [
        slider_crank(l=float(l), omega=float(w), theta0=float(th))
        for l, w, th in zip(
            rng.uniform(0.2, 0.4, count), rng.uniform(1, 5, count), rng.uniform(0, 1, count),
            strict=True,
        )
    ]  # fmt: skip


def _equal_to_single_runs(sw, models, points=("rod.B",)) -> None:
    cols, units = sw.columns(points=list(points))
    for i, m in enumerate(models):
        if i in sw.errors:
            with pytest.raises(type(sw.errors[i])) as single:
                md.kinematic(m, T)
            assert single.value.time == sw.errors[i].time
            assert all(np.isnan(v[i]).all() for c, v in cols.items() if c != "t")
            continue
        single = md.kinematic(m, T)
        got = sw[i].stats
        assert got.keys() == single.stats.keys()
        for k, v in single.stats.items():  # counters exactly, pivot ratios to rounding
            assert got[k] == pytest.approx(v, rel=1e-12) if isinstance(v, float) else got[k] == v
        for c, v in single.columns().items():
            # To rounding: the vectorized program's solves are straight-line code, the
            # single run's LAPACK's (mixdyn.linalg.LinearSolver.vectorized); a column of
            # rounding noise (a point on the slide's line, y ~ 1e-17 m) against 1 SI unit.
            scale = max(float(np.max(np.abs(v))), 1.0)
            for got in (sw[i][c], cols[c] if c == "t" else cols[c][i]):
                assert float(np.max(np.abs(np.asarray(got) - v))) <= 1e-13 * scale, (i, c)
        for ref in points:
            p, v, a = single.point(ref)
            for arr, pre in ((p, ""), (v, "v"), (a, "a")):
                for k, axis in enumerate("xy"):
                    scale = max(float(np.max(np.abs(arr[:, k]))), 1.0)
                    got = cols[f"{ref}.{pre}{axis}"][i]
                    assert float(np.max(np.abs(got - arr[:, k]))) <= 1e-13 * scale, (i, ref)
        assert units == {**single.units(), **{c: units[c] for c in units if "rod.B." in c}}


@pytest.mark.slow  # long: run by CI's slow set (a program compiled, ~5 s)
def test_kinematic_members_in_one_program_equal_their_single_runs(monkeypatch):
    """Three members, two a call (the last call filled up with a copy of its first member):
    held as arrays, no result built before it is read, each equal to its single run to
    rounding."""
    monkeypatch.setattr(sweep_module, "CHUNK", 2)
    monkeypatch.setattr(_kinematic_members, "CHUNK", 2)
    models = _models(3, np.random.default_rng(1))
    seen = []
    sw = md.sweep(models=models, t=T, analysis=md.analyses.Kinematic(), on_member=seen.append)
    assert isinstance(sw.stacked, _kinematic_members.KinematicStack) and not sw.errors
    assert repr(sw.results) == "<3 results, 0 built>" and sorted(seen) == [0, 1, 2]
    _equal_to_single_runs(sw, models)
    assert len({round(float(sw[i]["slider.x"][-1]), 9) for i in range(3)}) == 3


@pytest.mark.slow  # long: run by CI's slow set
def test_a_kinematic_sweep_of_many_members_with_failures():
    """70 members (two calls of 64), one whose rod is shorter than the crank (its start
    cannot be assembled) and one whose rod equals the crank (a dead point on the way): each
    failed member named with the single run's error and time, the others equal to their
    single runs; the Dataset on (member, t) with the status."""
    models = _models(70, np.random.default_rng(2))
    models[5] = slider_crank(r=0.1, l=0.05)
    models[40] = slider_crank(r=0.1, l=0.1, omega=np.pi)  # the dead point at t = 0.5
    sw = md.sweep(models=models, t=T, analysis=md.analyses.Kinematic())
    assert isinstance(sw.stacked, _kinematic_members.KinematicStack)
    assert sorted(sw.errors) == [5, 40]
    _equal_to_single_runs(sw, models)
    ds = sw.dataset(["slider.x"])
    assert ds["slider.x"].dims == ("member", "t") and ds.sizes == {"member": 70, "t": len(T)}
    assert ds["status"].values[5] != "ok" and ds["status"].values[0] == "ok"
