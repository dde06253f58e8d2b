"""Forward dynamics against closed forms and conservation laws: the large-amplitude pendulum
period (complete elliptic integral) under every integrator, energy conservation of a closed
loop, measured convergence orders, a damped spring–mass on a slider, a pin reaction, and the
errors of bad input."""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.special import ellipk

import mixdyn as md
from fixtures import four_bar, pendulum, slider_crank, spring_slider
from mixdyn.analysis.integrators.generalized_alpha import coefficients

G = 9.81

# ----------------------------------------------------------------------------- pendulum
#: A compound pendulum swinging to 150 degrees (fixtures.pendulum).
PEND = dict(length=0.5, mass=2.0, inertia=0.01, theta0=math.radians(150.0))


def pendulum_constants(length, mass, inertia, theta0):
    """``(w2, T)``: ``w2 = m g L / J_O`` [1/s^2] (``phi'' = -w2 sin phi``) and the exact
    period ``T = 4 K(sin^2(theta0/2)) / sqrt(w2)`` [s] (``K`` the complete elliptic integral
    of the first kind, parameter ``m = k^2``)."""
    w2 = mass * G * length / (inertia + mass * length**2)
    return w2, 4.0 * ellipk(math.sin(theta0 / 2) ** 2) / math.sqrt(w2)


PERIOD_RUNS = {
    "projection": dict(rtol=1e-12, atol=1e-12),
    "partitioning": dict(rtol=1e-12, atol=1e-12),
    "baumgarte": dict(dt=1e-3),
    # Second order: its period error is 6.1e-6 at dt = 1e-3 and falls as dt^2 (1.6e-8 at
    # 5e-5); dt = 5e-6 (5e5 steps, ~2 s) reaches 1.6e-10 directly, no extrapolation needed.
    "generalized-alpha": dict(dt=5e-6, rho_inf=0.9),
}


@pytest.mark.parametrize("method", list(PERIOD_RUNS))
def test_pendulum_period_matches_elliptic_integral(method):
    """A pendulum released at rest at 150 degrees returns to rest after exactly one period
    ``T = 4 K(sin^2(75 deg)) sqrt(J_O / (m g L))``. The numerical period is found from the
    state at ``T`` by one Newton step on ``omega(t) = 0``: ``T_num = T - omega(T) /
    alpha(T)``; it agrees with the closed form to 1e-9 relative under every integrator
    (measured: projection 1e-12, partitioning 2e-13, baumgarte 2.9e-10, generalized-alpha
    1.6e-10)."""
    model = pendulum(**PEND)
    _, T = pendulum_constants(**PEND)
    res = md.forward(model, [0.0, T], method=method, **PERIOD_RUNS[method])
    omega, alpha = res["bob.omega"][-1], res["bob.alpha"][-1]
    T_num = T - omega / alpha
    assert abs(T_num - T) / T <= 1e-9
    assert abs(res["bob.phi"][-1] - PEND["theta0"]) <= 1e-8


def test_pendulum_pin_reaction_closed_form():
    """The pin's reaction on the bob (joint ``pin`` = Revolute("ground.O", "bob.O"): the
    force body i, the ground, exerts on body j, the bob) is ``F = m (a - g)`` with the centre's
    acceleration ``a = L phi'' (cos phi, sin phi) + L phi'^2 (-sin phi, cos phi)`` (tangential
    and centripetal), ``phi'' = -w2 sin phi``, ``phi'^2 = 2 w2 (cos phi - cos theta0)``: in
    closed form as a function of the angle, to 1e-9 of its largest value. At the bottom
    (t = T/4) it is vertical, ``m (g + L phi'^2)``, and the reaction moment is absent."""
    L, m, th0 = PEND["length"], PEND["mass"], PEND["theta0"]
    w2, T = pendulum_constants(**PEND)
    ts = np.linspace(0.0, T, 101)  # ts[25] = T/4
    res = md.forward(pendulum(**PEND), ts, rtol=1e-12, atol=1e-12)
    phi = res["bob.phi"]
    phid2 = 2 * w2 * (np.cos(phi) - np.cos(th0))
    phidd = -w2 * np.sin(phi)
    ax = L * phidd * np.cos(phi) - L * phid2 * np.sin(phi)
    ay = L * phidd * np.sin(phi) + L * phid2 * np.cos(phi)
    F = np.stack([m * ax, m * (ay + G)], axis=1)
    got = np.stack([res["pin.Fx"], res["pin.Fy"]], axis=1)
    np.testing.assert_allclose(got, F, rtol=0, atol=1e-9 * np.max(np.abs(F)))
    bottom = m * (G + L * 2 * w2 * (1 - math.cos(th0)))
    assert abs(phi[25]) <= 1e-9
    assert res["pin.Fy"][25] == pytest.approx(bottom, rel=1e-9)
    assert abs(res["pin.Fx"][25]) <= 1e-9 * bottom
    assert "pin.M" not in res.columns()


# ------------------------------------------------------------------- conservation
def falling_four_bar():
    """The fixtures' crank–rocker without its motor, under gravity, its crank started at
    3 rad/s (a closed loop, one degree of freedom, no damping: conservative)."""
    model = four_bar(theta0=0.3).replace(drivers=(), gravity=(0.0, -G))
    return model, {"crank.phi": 3.0}


def test_four_bar_conserves_energy():
    """A four-bar swinging under gravity for 10 s (the crank sweeps 4.3 rad back and forth):
    kinetic + potential energy stays constant to 1e-9 of the energy exchanged (measured
    ~3e-12), and neither applied forces nor constraints do work."""
    model, qd0 = falling_four_bar()
    res = md.forward(
        model, np.linspace(0.0, 10.0, 501), qd0=qd0, hold=("crank.phi",), rtol=1e-12, atol=1e-12
    )
    E, K = res["energy.total"], res["energy.kinetic"]
    scale = max(abs(E[0]), np.ptp(K))
    assert np.ptp(K) > 1.0  # the motion is not trivial
    assert np.max(np.abs(E - E[0])) <= 1e-9 * scale
    assert np.max(np.abs(res["work.nonconservative"])) == 0.0
    assert np.max(np.abs(res["work.constraints"])) <= 1e-9 * scale


#: (method, solver option, nominal order, fixed steps [s]).
ORDERS = [
    ("projection", "tsit5", 5, (0.02, 0.01, 0.005, 0.0025)),
    ("partitioning", "tsit5", 5, (0.02, 0.01, 0.005, 0.0025)),
    ("baumgarte", None, 4, (0.02, 0.01, 0.005, 0.0025)),
    ("generalized-alpha", None, 2, (0.01, 0.005, 0.0025, 0.00125)),
]


@pytest.fixture(scope="module")
def order_reference():
    model, qd0 = falling_four_bar()
    ts = np.linspace(0.0, 1.0, 11)
    ref = md.forward(
        model, ts, qd0=qd0, hold=("crank.phi",), rtol=1e-14, atol=1e-14, solver="dopri8"
    )
    return model, qd0, ts, ref


@pytest.mark.parametrize("method, solver, order, steps", ORDERS, ids=[o[0] for o in ORDERS])
def test_convergence_order(order_reference, method, solver, order, steps):
    """Fixed steps on the swinging four-bar over 1 s: the largest coordinate error at 11
    output times against a dopri8 run at rtol 1e-14, for four step sizes halving; the
    least-squares slope of log(error) against log(dt) is the method's order within 0.5
    (measured: Tsit5 + projection 5.01, partitioning 5.03, RK4 + Baumgarte 4.30,
    generalized-alpha 1.91). The step is passed as a JAX scalar: traced, not static, so the
    four runs of a method share one compilation."""
    model, qd0, ts, ref = order_reference
    opts = {"solver": solver} if solver else {}
    errors = []
    for h in steps:
        res = md.forward(
            model,
            ts,
            method=method,
            dt=jnp.asarray(h),
            qd0=qd0,
            hold=("crank.phi",),
            energy_tol=None,  # the coarse steps of a convergence study: errors expected
            **opts,
        )
        errors.append(np.max(np.abs(res.q - ref.q)))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(slope - order) <= 0.5, (slope, errors)
    assert errors[-1] > 1e-12  # still above the reference's accuracy


# ------------------------------------------------------- generalized-alpha's Newton iteration
@pytest.mark.slow  # long: run by CI's slow set
@pytest.mark.parametrize("tol, bound", [(None, 5e-9), (1e-12, 1e-11)], ids=["default", "1e-12"])
def test_generalized_alpha_modified_newton_agrees_with_full(tol, bound):
    """Generalized-alpha's default Newton iteration (``newton="auto"``: the acceleration-level
    KKT matrix ``[[M, G], [C, 0]]``, the O(h^2) stiffness terms left out) and the exact Newton
    matrix (``"full"``) solve the same discrete equations: on the swinging four-bar over 1 s
    at dt = 1e-3 the coordinates differ by what the Newton tolerance lets through (measured
    5.0e-10 at the default tolerance, 2.1e-13 at tol = 1e-12 N), and the modified iteration
    needs few iterations per step (measured 1.32 at the default tolerance)."""
    model, qd0 = falling_four_bar()
    ts = np.linspace(0.0, 1.0, 11)
    kw = dict(method="generalized-alpha", dt=1e-3, qd0=qd0, hold=("crank.phi",), tol=tol)
    auto = md.forward(model, ts, **kw)
    full = md.forward(model, ts, newton="full", **kw)
    assert np.max(np.abs(auto.q - full.q)) <= bound
    assert np.max(np.abs(auto.qd - full.qd)) <= 10 * bound
    if tol is None:
        assert auto.stats["newton_iterations"] <= 1.5 * auto.stats["steps"]


def generalized_alpha_oscillator(m, k, c, free_length, x0, h, steps, rho_inf):
    """Generalized-alpha (the formulas of :mod:`mixdyn.analysis.integrators.generalized_alpha`)
    applied by hand to ``m x'' + c x' + k (x - free_length) = 0`` from rest: linear, so each
    step's equation for the new acceleration is solved exactly. Positions (steps + 1,)."""
    am, af, gm, bt = coefficients(rho_inf)
    beta_p = h**2 * bt * (1 - af) / (1 - am)
    gamma_p = h * gm * (1 - af) / (1 - am)
    x, v = x0, 0.0
    qdd = a = -k * (x0 - free_length) / m
    xs = [x]
    for _ in range(steps):
        a_part = (af * qdd - am * a) / (1 - am)  # a1 without its qdd1 part
        X = x + h * v + h**2 * (0.5 - bt) * a + h**2 * bt * a_part
        V = v + h * (1 - gm) * a + h * gm * a_part
        qdd1 = -(c * V + k * (X - free_length)) / (m + c * gamma_p + k * beta_p)
        a = a_part + (1 - af) / (1 - am) * qdd1
        x, v, qdd = X + beta_p * qdd1, V + gamma_p * qdd1, qdd1
        xs.append(x)
    return np.array(xs)


@pytest.mark.parametrize(
    "k",
    [pytest.param(1e7, marks=pytest.mark.slow), 2.8e6],  # slow: a long run; CI runs it
    ids=["diverging", "contracting-slowly"],
)
def test_generalized_alpha_stiff_spring_falls_back_to_full_newton(k):
    """A stiff spring (and a 200 N s/m damper) on a 1 kg slider at dt = 1 ms: 1e7 N/m (period
    2 ms), ``beta' k / m = 2.5``, and 2.8e6 N/m, ``beta' k / m = 0.7``. The modified Newton
    iteration, whose matrix leaves out the spring, diverges or contracts by ~0.7 per iteration
    and alone fails (ConvergenceError); ``newton="auto"`` switches within each step to the
    exact Newton matrix and gives the method's own answer, the same recurrence applied by
    hand to the linear oscillator, to 1e-11 of the amplitude (measured 6e-14), as does
    ``newton="full"``; two iterations per step (one modified, one full)."""
    m, c, L0, A, h = 1.0, 200.0, 0.5, 0.01, 1e-3
    model = spring_slider(m, k, c, L0, L0 + A)
    ts = np.linspace(0.0, 0.05, 51)
    ref = generalized_alpha_oscillator(m, k, c, L0, L0 + A, h, 50, 0.9)
    # the method's recurrence, not the physics: at two steps per period the numerical damping
    # dissipates the spring's energy (the energy-balance check would rightly refuse it)
    kw = dict(method="generalized-alpha", dt=h, rho_inf=0.9, energy_tol=None)
    with pytest.raises(md.ConvergenceError, match="Newton"):
        md.forward(model, ts, newton="modified", **kw)
    for newton in ("auto", "full"):
        res = md.forward(model, ts, newton=newton, **kw)
        np.testing.assert_allclose(res["slider.x"], ref, rtol=0, atol=1e-11 * A)
        np.testing.assert_allclose(res["slider.y"], 0.0, atol=1e-12)
        assert np.ptp(res["slider.x"]) > A  # the spring moves the slider
        per_step = {"auto": 2, "full": 1}[newton]
        assert res.stats["newton_iterations"] <= per_step * res.stats["steps"]


# ------------------------------------------------------------------ damped oscillator
def test_spring_mass_damper_on_slider():
    """A 2 kg mass on a slider with a spring (800 N/m, free length 0.5 m) and a damper
    (4 N s/m) to the ground, released at rest 0.1 m out: ``w_n = 20 rad/s``, ``zeta =
    0.05``, and ``x - 0.5 = 0.1 e^(-zeta w_n t) (cos w_d t + zeta w_n / w_d sin w_d t)``,
    ``w_d = w_n sqrt(1 - zeta^2)``, over 2 s (~6 periods), to 1e-9 of the amplitude in
    position and velocity; the slider stays on its line; energy plus the damper's
    dissipated work is constant."""
    m, k, c, L0, A = 2.0, 800.0, 4.0, 0.5, 0.1
    res = md.forward(
        spring_slider(m, k, c, L0, L0 + A), np.linspace(0.0, 2.0, 201), rtol=1e-12, atol=1e-12
    )
    wn = math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta**2)
    t = res.t
    env = A * np.exp(-zeta * wn * t)
    x = L0 + env * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    v = -env * (wn**2 / wd) * np.sin(wd * t)
    np.testing.assert_allclose(res["slider.x"], x, rtol=0, atol=1e-9 * A)
    np.testing.assert_allclose(res["slider.vx"], v, rtol=0, atol=1e-9 * A * wn)
    np.testing.assert_allclose(res["slider.y"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["slider.phi"], 0.0, atol=1e-12)
    balance = res["energy.total"] - res["work.nonconservative"]
    np.testing.assert_allclose(balance, balance[0], rtol=0, atol=1e-9 * 0.5 * k * A**2)


# ----------------------------------------------------------------------- bad input
def test_massless_body_is_refused_by_name():
    """A body without mass or inertia cannot take part in a dynamic run: a ModelError names
    it."""
    model = slider_crank(drivers=())
    rod = model.bodies[1]
    massless = md.Body("rod", 0.0, 0.0, q0=rod.q0, points=rod.points)
    model = model.replace(bodies=(model.bodies[0], massless, model.bodies[2]))
    with pytest.raises(md.ModelError, match="mass") as info:
        md.forward(model, [0.0, 0.1])
    assert info.value.element == "rod"


def test_start_that_cannot_be_assembled():
    """A four-bar whose links cannot close (0.1 + 0.1 + 0.1 < 1) has no consistent start: an
    AssemblyError (a NumericalError) naming the joint equations involved."""
    model = four_bar(a=0.1, b=0.1, c=0.1, d=1.0).replace(drivers=())
    with pytest.raises(md.AssemblyError) as info:
        md.forward(model, [0.0, 0.1])
    assert isinstance(info.value, md.NumericalError)
    assert info.value.elements


def test_unknown_newton_iteration_is_refused():
    with pytest.raises(md.ModelError, match="newton"):
        md.forward(pendulum(**PEND), [0.0, 0.01], method="generalized-alpha", dt=1e-3, newton="x")


def test_newton_failure_of_a_huge_implicit_step():
    """Generalized-alpha with a 1 s step on a 1e8 N/m spring (period 0.6 ms): the Newton
    iteration of the first step does not converge; a ConvergenceError carries the time
    reached (the start)."""
    model = spring_slider(mass=1.0, stiffness=1e8, damping=0.0, free_length=1.0, x0=1.2)
    with pytest.raises(md.ConvergenceError, match="Newton") as info:
        md.forward(model, [0.0, 1.0], method="generalized-alpha", dt=1.0)
    assert isinstance(info.value, md.NumericalError)
    assert info.value.time == 0.0
