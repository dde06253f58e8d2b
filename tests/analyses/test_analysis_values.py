"""Analyses as values (``mixdyn.analyses``): ``prepare(model, analysis)`` and
``run(setup, t)`` give each analysis function's result bit for bit; a set-up serves several
time grids without being made again; the deprecated ``prepared=`` warns with the new
spelling; options are checked when a value is made."""

from __future__ import annotations

import dataclasses
import importlib

import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum, slider_crank, spring_slider
from mixdyn.analyses import Forward, Inverse, Kinematic, Mixed, QuasiStatic, Static

TS = np.linspace(0.0, 0.2, 5)


def assert_bitwise(a: md.Result, b: md.Result) -> None:
    """Every column bitwise equal, and the same statistics."""
    assert a.kind == b.kind
    for name in ("t", "q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.extra.keys() == b.extra.keys()
    for k in a.extra:
        np.testing.assert_array_equal(a.extra[k], b.extra[k], err_msg=k)
    assert a.stats.keys() == b.stats.keys()
    for k in a.stats:
        if k not in ("min_eigenvalue",):
            assert a.stats[k] == b.stats[k], k


# ------------------------------------------------------------------ the same runs
def test_forward_by_prepare_and_run_is_md_forward_bit_for_bit():
    """``run(prepare(model, Forward(...)), t)`` is ``md.forward(model, t, ...)``: every column
    and counter, the recorded options included, for a method object and for its keywords."""
    model = pendulum(theta0=0.3)
    value = Forward(method=md.Projection(rtol=1e-9, solver="dopri5"), qd0={"bob.phi": 0.5})
    by_value = md.run(md.prepare(model, value), TS)
    assert_bitwise(by_value, md.forward(model, TS, method=value.method, qd0={"bob.phi": 0.5}))
    keywords = md.forward(model, TS, rtol=1e-9, solver="dopri5", qd0={"bob.phi": 0.5})
    for name in ("q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(by_value, name), getattr(keywords, name))
    assert by_value.stats["options"] == keywords.stats["options"]


@pytest.mark.slow  # long: run by CI's slow set
def test_each_analysis_by_prepare_and_run_is_its_function():
    """Kinematic, inverse, mixed, static and quasi-static: the value prepared and run equals
    the analysis function's result, bit for bit."""
    crank = slider_crank()
    t = np.linspace(0.0, 0.5, 6)
    assert_bitwise(md.run(md.prepare(crank, Kinematic(max_iter=30)), t),
                   md.kinematic(crank, t, max_iter=30))  # fmt: skip
    assert_bitwise(md.run(md.prepare(crank, Inverse()), t), md.inverse(crank, t))

    # a slider-crank whose crank angle (0.9 + 2 t rad) an unknown torque prescribes
    driven = slider_crank(theta0=0.9, drivers=()).replace(
        forces=[md.Torque("motor", "crank", law=0.0)]
    )
    turn = md.CoordinateDriver("turn", "crank", "phi", law=md.Ramp(0.9, 2.0))
    mixed = dict(prescribed=[turn], unknown=["motor"])
    value = Mixed(**mixed, method=md.Projection(rtol=1e-9))
    assert_bitwise(md.run(md.prepare(driven, value), TS),
                   md.mixed(driven, TS, **mixed, rtol=1e-9))  # fmt: skip

    spring = spring_slider()
    eq = md.run(md.prepare(spring, Static(tol=1e-11)), 0.0)
    single = md.statics(spring, tol=1e-11)
    np.testing.assert_array_equal(eq.q, single.q)
    np.testing.assert_array_equal(eq.eigenvalues, single.eigenvalues)
    assert_bitwise(eq.result, single.result)
    times = [0.0, 0.1, 0.2]
    assert_bitwise(md.run(md.prepare(crank, QuasiStatic()), times),
                   md.quasi_static(crank, times))  # fmt: skip


def test_a_set_up_serves_two_time_grids_without_being_made_again(monkeypatch):
    """One set-up run over a coarse and a fine grid from its ``t0``: each run equals
    ``md.forward`` over that grid, and the start is assembled and analysed once."""
    model = pendulum(theta0=0.4)
    setup = md.prepare(model, Forward(method=md.Projection(rtol=1e-10)), t0=0.0)
    forward_module = importlib.import_module("mixdyn.analysis.forward")
    monkeypatch.setattr(forward_module, "dynamic_start", lambda *a, **k: pytest.fail("again"))
    coarse, fine = np.linspace(0.0, 0.2, 3), np.linspace(0.0, 0.4, 41)
    a, b = md.run(setup, coarse), md.run(setup, fine)
    monkeypatch.undo()
    assert_bitwise(a, md.forward(model, coarse, rtol=1e-10))
    assert_bitwise(b, md.forward(model, fine, rtol=1e-10))
    with pytest.raises(md.ModelError, match=r"start at 0\.1") as err:
        md.run(setup, np.linspace(0.1, 0.2, 3))
    assert err.value.element == "t"


def test_a_set_up_carries_its_value_and_start():
    model = slider_crank()
    value = Kinematic(hold=["crank.phi"])
    setup = md.prepare(model, value, t0=0.25)
    assert setup.analysis is value and setup.model is model and setup.t0 == 0.25
    assert setup.start.q.shape == (model.nq,) and setup.start.report.dof == 1
    res = md.run(setup, [0.25, 0.3])
    np.testing.assert_array_equal(res.q, md.kinematic(model, [0.25, 0.3], hold=["crank.phi"]).q)


# ------------------------------------------------------------------ deprecated prepared=
def test_prepared_warns_with_prepare_and_run():
    """The analysis functions' ``prepared=`` (a start made beforehand) still works, checked,
    with a DeprecationWarning naming ``mixdyn.prepare`` and ``mixdyn.run``."""
    model = pendulum(theta0=0.3)
    prep = md.prepare(model, Forward()).start
    with pytest.warns(DeprecationWarning, match=r"mixdyn\.prepare\(model, .*mixdyn\.run"):
        res = md.forward(model, TS, prepared=prep)
    assert_bitwise(res, md.forward(model, TS))


# ------------------------------------------------------------------ checked when made
@pytest.mark.parametrize(
    ("make", "option", "words"),
    [
        (lambda: Forward(rtoll=1e-9), "rtoll", r"did you mean method=mixdyn\.Projection\(rtol"),
        (lambda: Forward(rtol=1e-9), "rtol", "an option of the integrator"),
        (lambda: Forward(holdd=["a.phi"]), "holdd", "did you mean hold"),
        (lambda: Forward(energy_tol=-1.0), "energy_tol", "energy_tol must be"),
        (lambda: Forward(method="baumgarte"), "dt", "fixed step"),
        (lambda: Forward(method="projektion"), "method", "did you mean projection"),
        (lambda: Forward(linear_solver="fast"), None, "linear_solver must be one of"),
        (lambda: Forward(q0="abc"), "q0", "q0 must be numbers"),
        (lambda: Mixed(prescribed=[], unknown=[], solver="lu"), "solver", "unknown mixed"),
        (lambda: Mixed(unknown=["F1"]), None, "prescribed"),
        (lambda: Kinematic(max_iter=0), "max_iter", "whole number from 1 to 1000"),
        (lambda: Kinematic(assemble_first=1), "assemble_first", "true or false"),
        (lambda: Inverse(singular_tol=2.0), "singular_tol", "a number in"),
        (lambda: Static(tol=-1.0), "tol", "tol must be a finite number > 0"),
        (lambda: QuasiStatic(maxiter=5), "maxiter", "did you mean max_iter"),
    ],
)
def test_a_bad_option_is_a_model_error_naming_it(make, option, words):
    with pytest.raises((md.ModelError, TypeError), match=words) as err:
        make()
    if option is not None:
        assert isinstance(err.value, md.ModelError) and err.value.element == option


def test_values_are_immutable_equal_and_hashable():
    a = Forward(method="projection", hold="crank.phi")
    b = Forward(method=md.Projection(), hold=("crank.phi",))
    assert a == b and hash(a) == hash(b) and a.hold == ("crank.phi",)
    assert Forward() != Forward(method=md.Projection(rtol=1e-9))
    assert isinstance(a.linear_solver, md.LinearSolver)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.energy_tol = None
    with pytest.raises(TypeError):
        Forward(md.Projection())  # keywords only
    with pytest.raises(TypeError, match="base"):
        md.Analysis()
    q0 = Kinematic(q0=[0.0, 0.1, 0.2]).q0
    assert q0.dtype == np.float64 and not q0.flags.writeable
    with pytest.raises(md.ModelError, match="analysis value"):
        md.prepare(pendulum(), "forward")
    with pytest.raises(md.ModelError, match=r"made by mixdyn\.prepare"):
        md.run("setup", TS)
    with pytest.raises(md.ModelError, match="no per-time progress"):
        md.run(md.prepare(slider_crank(), Kinematic()), [0.0, 0.1], progress=print)


def test_values_pickle_whole():
    """A value crosses a process boundary whole (a Dask sweep sends it to its workers), a
    fixed-step method's options included; made again by pickle, it is equal."""
    import pickle

    values = [
        Forward(method=md.Baumgarte(dt=1e-3), qd0={"bob.phi": 1.0}),
        Mixed(prescribed=[md.CoordinateDriver("x", "slider", "x", law=1.0)], unknown="F1"),
        Inverse(q0=[0.0, 0.1, 0.2]),
        QuasiStatic(tol=1e-9),
    ]
    for value in values:
        assert pickle.loads(pickle.dumps(value)) == value
