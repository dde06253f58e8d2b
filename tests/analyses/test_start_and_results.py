"""Given start velocities are kept, every option is checked before computing, and no result
holds a non-finite number.

Truths: the velocity constraints (a four-bar's loop closed in velocities), the user's own
numbers (kept bit for bit), and the closed form of a uniformly rotating crank.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import double_four_bar, four_bar, pendulum
from mixdyn.equations import Constraints

TS = np.linspace(0.0, 0.2, 5)


def free_four_bar() -> md.Model:
    """The fixtures' crank-rocker without its motor, under gravity (one degree of freedom)."""
    return four_bar(theta0=0.3).replace(drivers=(), gravity=(0.0, -9.81))


# ------------------------------------------------------------------ start velocities
def test_given_velocity_is_kept_and_the_others_follow():
    """``qd0={"crank.phi": 3}``: the crank starts at exactly 3 rad/s (it used to be replaced
    by the least change of the whole vector onto the constraints: another speed), and the
    other velocities satisfy the loop's velocity constraints with it."""
    model = free_four_bar()
    res = md.forward(model, TS, qd0={"crank.phi": 3.0})
    assert res["crank.omega"][0] == 3.0
    c = Constraints.of(model)
    J = np.asarray(c.phi_q(res.q[0], 0.0))
    assert np.max(np.abs(J @ res.qd[0])) <= 1e-12 * 3.0


@pytest.mark.slow  # long: run by CI's slow set
def test_the_double_four_bar_crank_speed_of_the_issue_is_kept():
    """The report: ``velocities: {crank0.phi: -1 rad/s}`` on the double four-bar became
    -0.174 rad/s. Now the crank starts at -1 rad/s, and all cranks of the parallelogram at the
    same speed (the velocity constraints: the crank tips move together)."""
    model, _ = double_four_bar(2)
    res = md.forward(model, TS, qd0={"crank0.phi": -1.0})
    assert res["crank0.omega"][0] == -1.0
    for i in (1, 2):
        assert res[f"crank{i}.omega"][0] == pytest.approx(-1.0, abs=1e-12)


def test_inconsistent_velocity_conditions_are_named():
    """Two speeds on a one-degree-of-freedom four-bar that its loop does not allow together
    are an input error naming both coordinates, found before integrating."""
    model = free_four_bar()
    with pytest.raises(md.ModelError) as err:
        md.forward(model, TS, qd0={"crank.phi": 3.0, "rocker.phi": 3.0})
    assert "crank.phi" in str(err.value) and "rocker.phi" in str(err.value)
    assert "inconsistent" in str(err.value)


def test_a_full_inconsistent_velocity_vector_is_refused():
    """A full vector ``qd0`` that violates the velocity constraints is not silently changed:
    a ModelError says by how much it would change and how to give conditions instead; a
    consistent one (the fixture's) is taken as it is, to rounding."""
    model = free_four_bar()
    qd = np.zeros(model.nq)
    qd[model.coordinate_index("crank.phi")] = 3.0
    with pytest.raises(md.ModelError, match="violate the velocity constraints"):
        md.forward(model, TS, qd0=qd)
    fourbar, qd0 = double_four_bar(2)
    res = md.forward(fourbar, TS, qd0=qd0)
    np.testing.assert_allclose(res.qd[0], np.asarray(qd0), rtol=0, atol=1e-15)


def test_velocity_of_a_held_coordinate_is_the_given_one():
    """A held coordinate keeps its given speed (0 if none is given): holding the pendulum's
    angle with ``qd0={"bob.phi": 2}`` starts it at 2 rad/s, its centre moving on its circle
    (v = omega length = 2 x 0.5 m/s for ``fixtures.pendulum``)."""
    model = pendulum()
    res = md.forward(model, TS, qd0={"bob.phi": 2.0}, hold=("bob.phi",))
    assert res["bob.omega"][0] == 2.0
    speed = math.hypot(res["bob.vx"][0], res["bob.vy"][0])
    assert speed == pytest.approx(2.0 * 0.5, rel=1e-12)


# ------------------------------------------------------------------ options
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(method="generalized-alpha", dt=1e-3, tolerance=1e-9), "did you mean tol"),
        (dict(method="generalized-alpha", dt=1e-9), "more than max_steps"),
        (dict(method="baumgarte", dt=1e-9), "more than max_steps"),
        (dict(method="generalized-alpha"), "fixed step"),
        (dict(rtol=float("nan")), "rtol must be"),
        (dict(atol=-1.0), "atol must be"),
        (dict(method="generalized-alpha", dt=1e-3, rho_inf=5), "rho_inf must be"),
        (dict(method="generalized-alpha", dt=1e-3, max_newton=0), "max_newton must be"),
        (dict(method="generalized-alpha", dt=1e-3, tol=float("nan")), "tol must be"),
        (dict(max_steps=-1), "max_steps must be"),
        (dict(solver="rk4"), "solver must be one of"),
        (dict(method="projektion"), "did you mean projection"),
        (dict(energy_tol=-1.0), "energy_tol must be"),
        (dict(first_step=0.0), "first_step must be"),
    ],
)
def test_bad_options_are_input_errors_before_computing(kwargs, match, monkeypatch):
    """Unknown options (with the close match), values out of range and absurd step counts
    are ModelErrors raised before anything is assembled or compiled (the assembly is made to
    fail loudly if it is reached)."""
    fw = importlib.import_module("mixdyn.analysis.forward")

    def reached(*a, **k):
        raise AssertionError("computing started before the options were checked")

    monkeypatch.setattr(fw, "dynamic_start", reached)
    model = free_four_bar()
    with pytest.raises(md.ModelError, match=match):
        md.forward(model, TS, qd0={"crank.phi": 1.0}, **kwargs)


# ------------------------------------------------------------------ non-finite results
def test_non_finite_force_is_a_named_failure():
    """An inverse run whose load torque is ``sqrt(t - 0.1)`` (NaN before t = 0.1 s... made
    to appear at t >= 0.15 here: ``log(0.15 - t)``) gives no NaN column: a NonFiniteError
    names the first time, the column and the element."""
    import jax.numpy as jnp

    model = four_bar(omega=2.0).replace(
        forces=(md.Torque("load", "rocker", law=lambda t: jnp.log(0.15 - t)),)
    )
    with pytest.raises(md.NonFiniteError) as err:
        md.inverse(model, TS)
    assert err.value.time == pytest.approx(0.15)
    assert "column" in str(err.value)


def test_result_columns_are_checked_for_any_analysis():
    """The check sits in the result itself: a Result built with an infinity anywhere is
    refused, naming the column and time."""
    model = free_four_bar()
    q = np.tile(np.asarray(model.q0), (3, 1))
    qd = np.zeros_like(q)
    qdd = np.zeros_like(q)
    qdd[2, model.coordinate_index("coupler.phi")] = np.inf
    with pytest.raises(md.NonFiniteError) as err:
        md.Result("forward", model, np.array([0.0, 0.1, 0.2]), q, qd, qdd)
    assert err.value.time == pytest.approx(0.2)
    assert "coupler.alpha" in str(err.value)
    assert err.value.elements == ("coupler",)
