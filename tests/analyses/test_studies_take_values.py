"""The studies take an analysis value (``md.sweep``, ``md.differentiable``, ``md.fit``,
``md.optimize``): the same members and functions as the deprecated keyword spelling, which
warns with the value to give; a value together with keywords is refused."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import mixdyn as md
from fixtures import pendulum, slider_crank
from mixdyn.analyses import Forward, Inverse, Kinematic, QuasiStatic
from mixdyn.analysis.sweep import vary_models

TS = np.linspace(0.0, 0.2, 5)


def assert_bitwise(a: md.Result, b: md.Result) -> None:
    """Every column bitwise equal, and the same statistics."""
    for name in ("t", "q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.extra.keys() == b.extra.keys()
    for k in a.extra:
        np.testing.assert_array_equal(a.extra[k], b.extra[k], err_msg=k)
    assert a.stats == b.stats


# ------------------------------------------------------------------ the studies take the value
def test_a_sweep_of_the_value_equals_the_keyword_spelling():
    """``md.sweep(..., analysis=Forward(...))`` equals the deprecated keyword spelling member
    by member, bit for bit (the same options recorded too), and each member its single run;
    a value with keywords is refused."""
    model = pendulum(theta0=0.3)
    vary = {"bob.mass": [2.0, 3.0], "bob.inertia": [0.01, 0.05]}
    value = Forward(method=md.Projection(rtol=1e-9, atol=1e-10))
    by_value = md.sweep(model, TS, vary=vary, analysis=value)
    with pytest.warns(DeprecationWarning):
        by_keywords = md.sweep(model, TS, vary=vary, rtol=1e-9, atol=1e-10)
    for i, member in enumerate(vary_models(model, vary)):
        assert_bitwise(by_value[i], by_keywords[i])
        assert_bitwise(by_value[i], md.forward(member, TS, method=value.method))
    with pytest.raises(md.ModelError, match="holds the analysis' options") as err:
        md.sweep(model, TS, vary=vary, analysis=value, rtol=1e-9)
    assert err.value.element == "rtol"


def test_run_members_warns_with_the_sweep_of_the_value():
    """``mixdyn.analysis.sweep.run_members`` (an analysis' name and each member's keywords)
    still runs, with a DeprecationWarning naming ``mixdyn.sweep(models=...)``: the same
    outcomes, bit for bit, as the sweep of the members with the analysis value."""
    from mixdyn.analysis.sweep import run_members

    model = pendulum(theta0=0.3)
    members = vary_models(model, {"bob.mass": [2.0, 3.0]})
    value = Forward(method=md.Projection(rtol=1e-9, atol=1e-10))
    swept = md.sweep(models=members, t=TS, analysis=value)
    with pytest.warns(DeprecationWarning, match=r"mixdyn\.sweep\(models=\[\.\.\.\]"):
        outcomes = run_members(members, TS, "forward", lambda i: dict(rtol=1e-9, atol=1e-10))
    for i, (res, err) in enumerate(outcomes):
        assert err is None
        assert_bitwise(res, swept[i])
    with pytest.warns(DeprecationWarning), pytest.raises(md.ModelError) as bad:
        run_members(members, TS, "forward", lambda i: dict(rtoll=1e-9))
    assert "in member 0 of the sweep" in " ".join(bad.value.__notes__)


def test_memberwise_sweeps_take_the_value():
    model = slider_crank()
    t = np.linspace(0.0, 0.5, 6)
    vary = {"rod.mass": [0.5, 2.0]}
    sw = md.sweep(model, t, vary=vary, analysis=Inverse())
    with pytest.warns(DeprecationWarning, match=r"analysis=mixdyn\.analyses\.Inverse\(\)"):
        old = md.sweep(model, t, vary=vary, analysis="inverse")
    for i in range(2):
        assert_bitwise(sw[i], old[i])
    with pytest.raises(md.ModelError, match="member by member"):
        md.sweep(model, t, vary=vary, analysis=Kinematic(), batch_size=2)


@pytest.mark.slow  # long: run by CI's slow set
def test_differentiable_takes_the_value():
    """``md.differentiable(..., analysis=Forward(...))``: the same function values as the
    keyword spelling and as the run itself; an inverse value; a kinematic or quasi-static
    value is refused by name."""
    model = pendulum(theta0=0.3)
    params = ["bob.mass", "bob.inertia"]
    f, th0 = md.differentiable(model, TS, params, analysis=Forward(method=md.Projection(rtol=1e-9)))
    with pytest.warns(DeprecationWarning, match=r"Forward\(method=mixdyn\.Projection\(rtol"):
        g, th1 = md.differentiable(model, TS, params, rtol=1e-9)
    np.testing.assert_array_equal(th0, th1)
    q = np.asarray(jax.jit(f)(th0)["q"])
    np.testing.assert_array_equal(q, np.asarray(jax.jit(g)(th1)["q"]))
    np.testing.assert_array_equal(q, md.forward(model, TS, rtol=1e-9).q)
    crank = slider_crank()
    t = np.linspace(0.0, 0.5, 6)
    h, m0 = md.differentiable(crank, t, ["rod.mass"], analysis=Inverse())
    np.testing.assert_array_equal(h(m0)["motor"], md.inverse(crank, t)["motor"])
    with pytest.raises(md.ModelError, match="depends on no number"):
        md.differentiable(crank, t, ["rod.mass"], analysis=Kinematic())
    with pytest.raises(md.ModelError, match="not differentiable"):
        md.differentiable(crank, t, ["rod.mass"], analysis=QuasiStatic())


# ------------------------------------------------------------------ deprecated spellings
@pytest.mark.parametrize(
    ("call", "spelled"),
    [
        (lambda m, t: md.sweep(m, t, vary={"bob.mass": [1.0]}, atol=1e-9),
         r"md\.sweep\(\.\.\., analysis=mixdyn\.analyses\.Forward\(method=mixdyn\.Projection"),
        (lambda m, t: md.differentiable(m, t, ["bob.mass"], analysis="forward"),
         r"md\.differentiable\(\.\.\., analysis=mixdyn\.analyses\.Forward\(\)\)"),
    ],
    ids=["sweep", "differentiable"],
)  # fmt: skip
def test_the_keyword_spelling_of_a_study_warns_with_the_value(call, spelled):
    with pytest.warns(DeprecationWarning, match=spelled):
        call(pendulum(theta0=0.3), TS)
