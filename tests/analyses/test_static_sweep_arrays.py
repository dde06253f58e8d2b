"""A quasi-static sweep held as arrays (:mod:`mixdyn.analysis._static_members`): at least
:data:`~mixdyn.analysis._schedule.CHUNK` members (two here) run by one vectorized program,
each member's result built when it is read. Truth: the same members run one by one by the
single run (:func:`~mixdyn.analysis._members.run_members`, a second method) and the closed
forms of a slider on a spring."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import mixdyn as md
from fixtures import four_bar, pushed_spring_slider, slider_crank
from mixdyn.analysis import _members, _static_members

SWEEP = sys.modules["mixdyn.analysis.sweep"]

T = np.linspace(0.0, 1.0, 3)
VALUE = md.analyses.QuasiStatic()


@pytest.fixture
def two_a_call(monkeypatch):
    """The array path from two members, two members a call."""
    monkeypatch.setattr(SWEEP, "CHUNK", 2)
    monkeypatch.setattr(_static_members, "CHUNK", 2)


def _one_by_one(models):
    return _members.run_members(models, T, VALUE)


def _same_error(a, b) -> None:
    assert type(a) is type(b) and str(a) == str(b) and a.time == b.time


def test_members_whose_start_cannot_be_made_fail_as_one_by_one(two_a_call):
    """Four-bars whose ground pivots lie farther apart than their links reach cannot be
    assembled: each member is reported with the error its single run raises."""
    models = [four_bar(d=2.0), four_bar(d=2.5)]
    swept = md.sweep(models=models, t=T, analysis=VALUE)
    assert isinstance(swept.stacked, _static_members.StaticStack)
    assert sorted(swept.errors) == [0, 1] and list(swept.results) == [None, None]
    for i, (_, err) in enumerate(_one_by_one(models)):
        _same_error(swept.errors[i], err)
    with pytest.raises(type(swept.errors[0])):
        swept[0]


def _same_columns(a: md.Result, b: md.Result) -> None:
    """Every column of ``a`` equals ``b``'s to 1e-12 of its largest magnitude, and at least
    of one model unit (a column that is zero but for rounding)."""
    ca, cb = a.columns(), b.columns()
    assert list(ca) == list(cb)
    for k, v in cb.items():
        scale = max(float(np.max(np.abs(v))), 1.0)
        assert float(np.max(np.abs(np.asarray(ca[k]) - v))) <= 1e-12 * scale, k


@pytest.mark.slow  # long: run by CI's slow set
def test_a_member_that_does_not_converge_fails_as_one_by_one(two_a_call):
    """A slider-crank whose rod is shorter than its crank assembles at its start but has no
    equilibrium once the crank has turned: it fails with its single run's error (a
    ConvergenceError at the same time), the others equal their single runs."""
    models = [slider_crank(l=0.05), slider_crank(), slider_crank(l=0.42)]
    swept = md.sweep(models=models, t=T, analysis=VALUE)
    assert isinstance(swept.stacked, _static_members.StaticStack)
    assert list(swept.errors) == [0]
    truth = _one_by_one(models)
    _same_error(swept.errors[0], truth[0][1])
    assert isinstance(swept.errors[0], md.errors.ConvergenceError) and swept.errors[0].time > 0
    cols, _ = swept.columns()
    assert np.isnan(cols["motor"][0]).all()
    for i in (1, 2):
        _same_columns(swept[i], truth[i][0])
        for k, v in truth[i][0].columns().items():
            if k != "t":
                scale = max(float(np.max(np.abs(v))), 1.0)
                np.testing.assert_allclose(cols[k][i], v, rtol=0, atol=1e-12 * scale)


@pytest.mark.slow  # long: run by CI's slow set
def test_members_sharing_a_start_rest_where_the_spring_balances_the_push(two_a_call):
    """A slider on a spring (free length 0.5 m) pushed along its rail by ``F``, over the
    spring's stiffness and the push (forces only: every member from member 0's start):
    each rests at ``x = 0.5 + F / k`` at every time, with its single run's columns and
    stiffness eigenvalues; the member without a spring has no equilibrium and fails as its
    single run does (at the first time)."""
    model = pushed_spring_slider(gravity=(0.0, -9.81))
    vary = md.grid(**{"spring.stiffness": [0.0, 100.0, 400.0], "push.law.value": [10.0, 30.0]})
    swept = md.sweep(model, T, vary=vary, analysis=VALUE)
    assert isinstance(swept.stacked.models, md.Model)  # one start, shared
    assert sorted(swept.errors) == [0, 1]
    truth = _one_by_one(SWEEP.vary_models(model, vary))
    cols, _ = swept.columns()
    for i, (result, err) in enumerate(truth):
        k, f = vary["spring.stiffness"][i], vary["push.law.value"][i]
        if err is not None:
            _same_error(swept.errors[i], err)
            assert err.time == 0.0
            continue
        np.testing.assert_allclose(cols["slider.x"][i], 0.5 + f / k, rtol=1e-12)
        _same_columns(swept[i], result)
        ours, theirs = swept[i].stats, result.stats
        np.testing.assert_allclose(ours["min_eigenvalue"], theirs["min_eigenvalue"], rtol=1e-12)
        assert ours["newton_iterations"] == theirs["newton_iterations"]
        assert ours["stable"] and theirs["stable"]


def _hanging(model: md.Model) -> md.Model:
    """``model`` under gravity (-y, SI)."""
    return md.Model(
        bodies=model.bodies,
        joints=model.joints,
        drivers=model.drivers,
        ground=model.ground,
        gravity=(0.0, -9.81),
        units=md.SI,
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_starts_made_by_the_program_equal_each_set_up(two_a_call):
    """Four-bars of other cranks and start angles under gravity, each start assembled with
    the crank's angle held: the program's starts and equilibria equal each member's single
    run; the four-bar whose pivots lie beyond its links' reach fails with its single run's
    AssemblyError."""
    models = [
        _hanging(four_bar(a=a, d=d, theta0=th))
        for a, d, th in [(0.2, 0.6, 0.1), (0.22, 0.6, 0.5), (0.18, 2.0, 1.0), (0.25, 0.6, 2.0)]
    ]
    value = md.analyses.QuasiStatic(hold=("crank.phi",))
    swept = md.sweep(models=models, t=T, analysis=value)
    assert isinstance(swept.stacked, _static_members.StaticStack)
    assert list(swept.errors) == [2]
    truth = _members.run_members(models, T, value)
    assert isinstance(truth[2][1], md.errors.AssemblyError)
    assert type(swept.errors[2]) is type(truth[2][1]) and str(swept.errors[2]) == str(truth[2][1])
    for i in (0, 1, 3):
        _same_columns(swept[i], truth[i][0])
