"""Typed options per integrator (``md.Projection``, ``md.Partitioning``, ``md.Baumgarte``,
``md.GeneralizedAlpha``): the same run as the method's name with keyword options, checked when
made with the keyword path's messages, immutable and hashable, refused together with
keywords, made the same from a model file's run, and traced no more than keywords are."""

from __future__ import annotations

import dataclasses
import importlib
import json

import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import new_traces, pendulum, slider_crank, traced_now
from mixdyn.analysis.methods import FIXED_STEP, OPTIONS
from mixdyn.runs import Runner, checks
from mixdyn.runtime import _programs

TS = np.linspace(0.0, 0.2, 5)

#: (method, keyword options, the same options as an object): every option off its default.
SAME_RUNS = [
    (
        "projection",
        dict(rtol=1e-9, atol=1e-11, solver="dopri5", first_step=1e-3),
        md.Projection(rtol=1e-9, atol=1e-11, solver="dopri5", first_step=1e-3),
    ),
    ("partitioning", dict(atol=1e-9, solver="dopri8"), md.Partitioning(atol=1e-9, solver="dopri8")),
    ("baumgarte", dict(dt=0.01, alpha=5.0, beta=6.0), md.Baumgarte(dt=0.01, alpha=5.0, beta=6.0)),
    (
        "generalized-alpha",
        dict(dt=0.01, rho_inf=0.7, newton="full", max_newton=30),
        md.GeneralizedAlpha(dt=0.01, rho_inf=0.7, newton="full", max_newton=30),
    ),
]


def _columns(res: md.Result) -> dict[str, np.ndarray]:
    return {"q": res.q, "qd": res.qd, "qdd": res.qdd, **res.extra}


def assert_same_run(a: md.Result, b: md.Result) -> None:
    """Every array of two results bitwise equal, and the same counters."""
    ca, cb = _columns(a), _columns(b)
    assert ca.keys() == cb.keys()
    for k in ca:
        np.testing.assert_array_equal(ca[k], cb[k], err_msg=k)
    for k in ("steps", "rejected_steps", "newton_iterations"):
        assert a.stats[k] == b.stats[k], k


# ------------------------------------------------------------------ the same runs
@pytest.mark.parametrize(("method", "kwargs", "typed"), SAME_RUNS, ids=[r[0] for r in SAME_RUNS])
def test_an_object_and_keywords_are_the_same_run_and_program(method, kwargs, typed):
    """A pendulum run with the method's name and keyword options, and with the options
    object: bitwise equal results, and the second run traces nothing (the same program)."""
    model = pendulum(theta0=0.3)
    by_name = md.forward(model, TS, method=method, **kwargs)
    before = traced_now()
    by_object = md.forward(model, TS, method=typed)
    assert new_traces(before) == {}
    assert_same_run(by_name, by_object)
    assert by_object.stats["method"] == method == typed.method
    # every option given off its default: both record the same options
    assert by_object.stats["options"] == by_name.stats["options"]


def _mixed(method, **kwargs) -> md.Result:
    """A slider–crank whose crank angle is prescribed (0.9 + 2 t rad) by an unknown torque."""
    model = slider_crank(theta0=0.9, drivers=()).replace(
        forces=[md.Torque("motor", "crank", law=0.0)]
    )
    turn = md.CoordinateDriver("turn", "crank", "phi", law=md.Ramp(0.9, 2.0))
    return md.mixed(
        model, np.linspace(0.0, 0.1, 5), prescribed=[turn], unknown=["motor"], method=method,
        **kwargs,
    )  # fmt: skip


@pytest.mark.parametrize(
    ("method", "kwargs", "typed"),
    [
        ("projection", dict(rtol=1e-9), md.Projection(rtol=1e-9)),
        (
            "generalized-alpha",
            dict(dt=0.01, rho_inf=0.5),
            md.GeneralizedAlpha(dt=0.01, rho_inf=0.5),
        ),
    ],
    ids=["projection", "generalized-alpha"],
)
def test_mixed_takes_an_object_too(method, kwargs, typed):
    """Mixed dynamics: the same run from the object as from keywords (bitwise)."""
    by_name = _mixed(method, **kwargs)
    by_object = _mixed(typed)
    assert_same_run(by_name, by_object)
    assert np.ptp(by_object["motor"]) > 0  # the unknown torque was found, not left at 0


def test_mixed_runge_kutta_by_object():
    """``solver`` of :func:`md.mixed` is the mixed solver: the Runge–Kutta method of its
    integrator is chosen by the object (``Projection(solver=...)``) and recorded."""
    res = _mixed(md.Projection(solver="dopri5"), solver="augmented")
    assert res.stats["options"] == {"rtol": 1e-8, "atol": 1e-10, "solver": "dopri5"}
    assert res.stats["solver"] == "augmented"


def test_recorded_options_are_a_plain_dict(tmp_path):
    """The options a run records: with a method's name, the tolerances and the options given
    (an option given at its default included, as before typed options); with an object, the
    tolerances and the options off their defaults. ``meta.json`` holds them as a dict."""
    model = pendulum(theta0=0.3)
    res = md.forward(model, TS, method="projection", solver="tsit5")
    assert res.stats["options"] == {"solver": "tsit5", "rtol": 1e-8, "atol": 1e-10}
    fixed = md.forward(model, TS, method="baumgarte", dt=0.01, rtol=1e-3)
    assert fixed.stats["options"] == {"dt": 0.01}  # a fixed step has no tolerances
    typed = md.forward(model, TS, method=md.Projection(rtol=1e-9, solver="tsit5", dt=0.01))
    assert typed.stats["options"] == {"rtol": 1e-9, "atol": 1e-10, "dt": 0.01}
    mio.write_result(typed, tmp_path / "run")
    meta = json.loads((tmp_path / "run" / mio.results.META_JSON).read_text())
    assert meta["stats"]["options"] == {"rtol": 1e-9, "atol": 1e-10, "dt": 0.01}


# ------------------------------------------------------------------ checked when made
#: (keyword options of forward, the same as an object, the message).
BAD = [
    (dict(method="generalized-alpha", dt=1e-3, tolerance=1e-9), "did you mean tol"),
    (dict(method="projection", rtoll=1e-9), "did you mean rtol"),
    (dict(method="baumgarte", dt=1e-3, gamma=1.0), "unknown option 'gamma'"),
    (dict(method="projection", rtol=float("nan")), "rtol must be a finite number > 0"),
    (dict(method="partitioning", atol=-1.0), "atol must be a finite number > 0"),
    (dict(method="generalized-alpha", dt=1e-3, rho_inf=5), "rho_inf must be a number in"),
    (dict(method="generalized-alpha", dt=1e-3, max_newton=0), "max_newton must be a whole"),
    (dict(method="projection", max_steps=2.5), "max_steps must be a whole number"),
    (dict(method="projection", max_steps=True), "max_steps must be a whole number"),
    (dict(method="projection", first_step=0.0), "first_step must be a finite step > 0"),
    (dict(method="projection", first_step=1e-320), "first_step must be a finite step > 0"),
    (dict(method="partitioning", first_step=-1e-3), "first_step must be a finite step > 0"),
    (dict(method="baumgarte", dt=-1e-3), "dt must be a finite step > 0"),
    (dict(method="baumgarte", dt=1e-3, alpha=-1.0), "alpha must be a finite number >= 0"),
    (dict(method="projection", solver="rk4"), "solver must be one of tsit5, dopri5, dopri8"),
    (dict(method="generalized-alpha", dt=1e-3, newton="fast"), "newton must be one of auto"),
    (dict(method="generalized-alpha", dt=1e-3, project_velocities=3), "must be true or false"),
]


@pytest.mark.parametrize(("kwargs", "match"), BAD, ids=[m for _, m in BAD])
def test_bad_options_are_refused_when_made(kwargs, match, monkeypatch):
    """Unknown names (with the close matches), values out of range and wrong choices are
    ModelErrors naming the option when the object is made, with the message the keyword
    path gives (before anything is computed)."""
    kwargs = dict(kwargs)
    cls = OPTIONS[kwargs.pop("method")]
    with pytest.raises(md.ModelError, match=match) as made:
        cls(**kwargs)
    assert made.value.element == list(kwargs)[-1]  # the option at fault
    fw = importlib.import_module("mixdyn.analysis.forward")
    monkeypatch.setattr(fw, "dynamic_start", lambda *a, **k: pytest.fail("computing began"))
    with pytest.raises(md.ModelError) as keywords:
        md.forward(pendulum(), TS, method=cls.method, **kwargs)
    assert str(keywords.value) == str(made.value)


@pytest.mark.parametrize("cls", [md.Baumgarte, md.GeneralizedAlpha])
def test_a_fixed_step_method_needs_dt(cls):
    assert cls.fixed_step and cls.method in FIXED_STEP
    with pytest.raises(md.ModelError, match="fixed step: give dt") as err:
        cls()
    assert err.value.element == "dt"
    with pytest.raises(md.ModelError, match="fixed step: give dt"):
        cls(dt=None)
    # the keyword path also suggests a step from the output times
    with pytest.raises(md.ModelError, match=r"give dt \[time\], e\.g\. dt=0\.0001"):
        md.forward(pendulum(), TS, method=cls.method)


def test_step_count_is_checked_at_the_run():
    """A step too small for the span (more than ``max_steps`` steps) is known only with the
    output times: refused by the run, before computing, for the object as for keywords."""
    opts = md.Baumgarte(dt=1e-3, max_steps=100)  # 200 steps over 0.2 s
    with pytest.raises(md.ModelError, match="more than max_steps = 100"):
        md.forward(pendulum(), TS, method=opts)


@pytest.mark.parametrize("scale", [0.5, 1.0, 2.0])
def test_a_first_step_is_checked_against_the_runs_times(scale, monkeypatch):
    """A first step below the shortest step that advances the run's times in float64,
    ``1e-13 * max(|t|, 1)`` (the integrator's own collapsed step: below it, the run would
    end at its start with a step-size failure), or longer than the span is refused before
    computing, naming first_step; from the floor up, the run gives the motion of a first
    step of 1 ms (another grid of steps: the same motion within the tolerances; the options
    of SAME_RUNS, one program)."""
    model = pendulum(theta0=0.3)
    ts = TS + 1e3 * (scale - 1.0)  # 0..0.2 s, or later: the floor grows with |t|
    floor = 1e-13 * max(float(np.max(np.abs(ts))), 1.0)

    def run(first_step):
        method = md.Projection(rtol=1e-9, atol=1e-11, solver="dopri5", first_step=first_step)
        return md.forward(model, ts, method=method)

    np.testing.assert_allclose(run(floor).q, run(1e-3).q, atol=1e-7)
    fw = importlib.import_module("mixdyn.analysis.forward")
    monkeypatch.setattr(fw, "dynamic_start", lambda *a, **k: pytest.fail("computing began"))
    for bad, match in [(floor * 0.99, "cannot advance time"), (0.21, "at most the run's span")]:
        for method in (md.Projection(first_step=bad), md.Partitioning(first_step=bad)):
            with pytest.raises(md.ModelError, match=match) as err:
                md.forward(model, ts, method=method)
            assert err.value.element == "first_step"
        with pytest.raises(md.ModelError, match=match):
            md.forward(model, ts, first_step=bad)


def test_objects_are_immutable_hashable_and_plain():
    """Equal options make equal objects with equal hashes (usable as keys); no field can be
    set; numbers are kept as Python numbers; only keywords; the base class is not a method."""
    a = md.GeneralizedAlpha(dt=np.float64(1e-3), max_newton=30.0, project_velocities=True)
    b = md.GeneralizedAlpha(dt=1e-3, max_newton=30, project_velocities=True)
    assert a == b and hash(a) == hash(b) and len({a, b}) == 1
    assert type(a.dt) is float and type(a.max_newton) is int and a.project_velocities is True
    assert md.Projection() != md.Projection(rtol=1e-9)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.dt = 1.0
    with pytest.raises(TypeError):
        md.Projection(1e-9)
    with pytest.raises(TypeError, match="base"):
        md.IntegratorOptions()
    assert dataclasses.replace(b, rho_inf=0.5).rho_inf == 0.5
    with pytest.raises(md.ModelError, match="rho_inf must be"):
        dataclasses.replace(b, rho_inf=2.0)


def test_defaults():
    """Each class's options and defaults (those of the integrators before typed options)."""
    adaptive = dict(
        rtol=1e-8, atol=1e-10, dt=None, solver="tsit5", max_steps=1_000_000, first_step=None
    )
    assert md.Projection.defaults() == adaptive
    assert md.Partitioning.defaults() == adaptive
    assert md.Baumgarte.defaults() == dict(dt=None, alpha=10.0, beta=10.0, max_steps=10_000_000)
    assert md.GeneralizedAlpha.defaults() == dict(
        dt=None,
        rho_inf=0.9,
        tol=None,
        max_newton=20,
        newton="auto",
        project_velocities=True,
        max_steps=10_000_000,
    )
    assert {c.method: c for c in OPTIONS.values()} == OPTIONS
    assert set(OPTIONS) == set(md.analysis.INTEGRATORS)


# ------------------------------------------------------------------ objects and keywords
@pytest.mark.parametrize(
    "kwargs",
    [dict(rtol=1e-9), dict(atol=1e-9), dict(dt=0.01), dict(solver="dopri8")],
    ids=lambda k: next(iter(k)),
)
def test_an_object_with_keywords_is_refused(kwargs):
    """An options object holds the integrator's options: the same given again as keywords
    (even at their default) is refused, naming them, before computing."""
    with pytest.raises(md.ModelError, match="Projection object") as err:
        md.forward(pendulum(), TS, method=md.Projection(), **kwargs)
    assert err.value.element == next(iter(kwargs))
    if "solver" not in kwargs:  # mixed's own solver is the mixed solver
        with pytest.raises(md.ModelError, match="GeneralizedAlpha object"):
            _mixed(md.GeneralizedAlpha(dt=0.01), **kwargs)


def test_a_class_or_unknown_name_is_refused():
    with pytest.raises(md.ModelError, match=r"give an object of it, e\.g\. method=Projection"):
        md.forward(pendulum(), TS, method=md.Projection)
    with pytest.raises(md.ModelError, match="did you mean projection"):
        md.forward(pendulum(), TS, method="projektion")
    with pytest.raises(md.ModelError, match="unknown integrator"):
        md.forward(pendulum(), TS, method=42)


# ------------------------------------------------------------------ model files
FILE = """\
mixdyn: 1
name: pendulum
gravity: [0, -9.81]
bodies:
  - {name: rod, mass: 1, inertia: 0.1, q0: [0, -0.5, 0], points: {pivot: [0, 0.5]}}
joints:
  - {type: revolute, name: pivot, point_i: ground, point_j: rod.pivot}
forces:
  - {type: torque, name: tq, body: rod, law: 0}
runs:
"""

#: (kind, run lines, the object its options make).
FILE_RUNS = [
    (
        "forward",
        "rtol: 1.0e-9\n    options: {solver: dopri5, first_step: 1.0e-4, max_steps: 5000}",
        md.Projection(rtol=1e-9, solver="dopri5", first_step=1e-4, max_steps=5000),
    ),
    (
        "forward",
        "method: partitioning\n    atol: 1.0e-9\n    options: {solver: dopri8}",
        md.Partitioning(atol=1e-9, solver="dopri8"),
    ),
    (
        "forward",
        "method: baumgarte\n    dt: 2 ms\n    options: {alpha: 5, beta: 6, energy_tol: 1.0e-3}",
        md.Baumgarte(dt=0.002, alpha=5.0, beta=6.0),
    ),
    (
        "forward",
        "method: generalized-alpha\n    dt: 1 ms\n    options: {rho_inf: 0.7, newton: full, "
        "project_velocities: false, max_newton: 30, tol: 1.0e-9}",
        md.GeneralizedAlpha(
            dt=1e-3, rho_inf=0.7, newton="full", project_velocities=False, max_newton=30, tol=1e-9
        ),
    ),
    (
        "mixed",
        "atol: 1.0e-9\n    options: {first_step: 1.0e-4}",
        md.Projection(atol=1e-9, first_step=1e-4),
    ),
    (
        "mixed",
        "method: generalized-alpha\n    dt: 1 ms\n    options: {rho_inf: 0.5}",
        md.GeneralizedAlpha(dt=1e-3, rho_inf=0.5),
    ),
]


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ("1.0e-320", "not subnormal"),
        ("1.0e-16", "cannot advance time in float64"),
        ("0", "finite step > 0"),
        ("-1.0e-3", "finite step > 0"),
        (".nan", "finite step > 0"),
        ("0.5", "at most the run's span 0.1"),
    ],
)
def test_a_model_files_first_step_is_refused_at_its_line(value, problem, monkeypatch):
    """An absurd ``options.first_step`` in a file is a named input error at its line, found
    when the file is read, before anything is computed."""
    run = (
        "  - name: r\n    kind: forward\n    time: {span: [0, 0.1], n: 3}\n"
        f"    options: {{first_step: {value}}}\n"
    )
    fw = importlib.import_module("mixdyn.analysis.forward")
    monkeypatch.setattr(fw, "simulate", lambda *a, **k: pytest.fail("computing began"))
    text = FILE + run
    with pytest.raises(mio.FileError, match=problem) as err:
        Runner(mio.reads(text)).execute()
    assert err.value.line == text.splitlines().index(f"    options: {{first_step: {value}}}") + 1
    assert "options.first_step" in str(err.value)


class _CapturedError(Exception):
    """Stops a run once its integrator options are known."""


@pytest.mark.parametrize(
    ("kind", "lines", "expected"), FILE_RUNS, ids=[f"{k}-{e.method}" for k, _, e in FILE_RUNS]
)
def test_a_model_file_run_makes_the_same_object(kind, lines, expected, monkeypatch):
    """A run of a model file, forward or mixed, integrates with the object its method,
    tolerances, step and ``options`` make, equal to the one made in Python; ``energy_tol``
    stays the analysis' own."""
    run = f"  - name: r\n    kind: {kind}\n    time: {{span: [0, 0.1], n: 3}}\n    {lines}\n"
    if kind == "mixed":
        run += "    unknown: [tq]\n    prescribed:\n      - {coordinate: rod.phi, law: 0.5*t}\n"
    seen = {}

    def simulate(case, progress=None):
        seen.update(options=case.options, energy_tol=case.energy_tol)
        raise _CapturedError

    monkeypatch.setattr(importlib.import_module(f"mixdyn.analysis.{kind}"), "simulate", simulate)
    spec = mio.reads(FILE + run)
    runner = Runner(spec)
    with pytest.raises(_CapturedError):
        runner.execute()
    assert seen["options"] == expected
    assert type(seen["options"]) is type(expected)
    assert seen["energy_tol"] == (1e-3 if "energy_tol" in lines else "auto")
    # the names a file's run may give are the class's fields but the run's own settings
    known = checks.known_options(spec.runs[0])
    fields = set(expected.defaults()) - set(checks.RUN_SETTINGS)
    if kind == "mixed":
        fields.discard("solver")  # a mixed run's 'solver' is the mixed solver
    assert set(known) == fields | set(checks.DYNAMIC_OPTIONS)


# ------------------------------------------------------------------ tracing
def test_a_second_run_with_an_object_traces_nothing():
    """Other numbers of the model and other tolerances with the same structure and options
    are the same program: nothing traced again, and the motion does change."""
    first = md.forward(pendulum(theta0=0.3), TS, method=md.Projection(rtol=1e-9))
    md.forward(pendulum(theta0=0.3), TS, method=md.GeneralizedAlpha(dt=0.01))
    before = traced_now()
    other = md.forward(pendulum(theta0=0.4, mass=3.0), TS, method=md.Projection(rtol=1e-7))
    md.forward(pendulum(theta0=0.2), TS, method=md.GeneralizedAlpha(dt=0.01))
    assert new_traces(before) == {}
    assert not np.allclose(first.q, other.q)


@pytest.mark.parametrize(
    ("first", "second"),
    [
        (md.Baumgarte(dt=0.01, alpha=5.0, beta=6.0), md.Baumgarte(dt=0.005, alpha=8.0, beta=9.0)),
        (md.GeneralizedAlpha(dt=0.01, rho_inf=0.9), md.GeneralizedAlpha(dt=0.005, rho_inf=0.6)),
        (md.Projection(dt=0.01), md.Projection(dt=0.005)),
    ],
    ids=["baumgarte", "generalized-alpha", "projection-fixed"],
)
def test_another_step_is_the_same_program(first, second):
    """The step ``dt`` (and Baumgarte's ``alpha``, ``beta``, generalized-alpha's ``rho_inf``)
    are numbers of the program, not part of it: a convergence study or an edited step traces
    nothing again, and the run does take the new step (0.2 s in steps of 0.005 s: 40)."""
    model = pendulum(theta0=0.3)
    a = md.forward(model, TS, method=first)
    assert a.stats["steps"] == 20
    before = traced_now()
    b = md.forward(model, TS, method=second)
    assert new_traces(before) == {}
    assert b.stats["steps"] == 40
    assert not np.array_equal(a.q, b.q)
    assert np.allclose(a.q, b.q, atol=1e-3)


def test_objects_key_the_persistent_cache(tmp_path):
    """With mixdyn's persistent cache on, a run with an options object is exported and keyed
    (an object of a mixdyn class is trusted), not traced by a fallback; an equal object
    makes the same program: nothing traced, the same numbers."""
    assert _programs.set_cache(tmp_path / "cache") is not None
    # outputs of a number no other test uses: a program is new to this process (the test
    # session's own cache may hold this structure on another grid already)
    ts = np.linspace(0.0, 0.2, 7)
    try:
        fallback, exported = _programs.stats["fallback"], _programs.stats["exported"]
        model = pendulum(theta0=0.3)
        a = md.forward(model, ts, method=md.GeneralizedAlpha(dt=0.02, rho_inf=0.8))
        assert _programs.stats["fallback"] == fallback
        assert _programs.stats["exported"] > exported
        before = traced_now()
        b = md.forward(model, ts, method=md.GeneralizedAlpha(dt=0.02, rho_inf=0.8))
        assert new_traces(before) == {}
        assert_same_run(a, b)
    finally:
        _programs.set_cache(False)
