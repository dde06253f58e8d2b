"""Coulomb friction in joints (``md.JointFriction``): stick and slip against closed forms.

- A block on an incline (translational joint): it sticks below the friction angle
  ``atan(mu)``, with the friction force ``m g sin`` and the normal force ``m g cos``, and slides
  above it at ``g (sin - mu cos)``, the friction's work equal to ``-mu m g cos`` times the
  distance.
- A flywheel on a pin (revolute joint) driven by a torque rising from zero: it sticks until
  the torque reaches ``mu r m g`` (the pin's reaction is the weight), then turns with
  ``I alpha = M(t) - mu r m g``.
- A slider-crank driven at constant speed against a load, with friction at the slider
  (inverse dynamics): the motor torque against the hand-derived result (massless crank and
  rod, a two-force rod, the slider's friction ``mu |N|`` from the rod's force).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import EXAMPLES

G = 9.81
TS = np.linspace(0.0, 1.0, 11)


def incline(theta: float, mu: float, m: float = 2.0) -> md.Model:
    c, s = math.cos(theta), math.sin(theta)
    return md.Model(
        bodies=[md.Body("block", m, 0.1, q0=(0.0, 0.0, -theta))],
        joints=[md.Translational("slide", "ground", "block", axis=(c, -s))],
        forces=[md.JointFriction("friction", "slide", mu=mu)],
        gravity=(0.0, -G),
    )


@pytest.mark.slow  # long: run by CI's slow set
def test_a_block_sticks_below_the_friction_angle():
    theta, mu, m = 0.25, 0.3, 2.0  # atan(0.3) = 0.2915
    r = md.forward(incline(theta, mu, m), TS, rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(r.q[:, :2])) < 1e-12  # it does not move
    tab = r.table()
    np.testing.assert_allclose(np.abs(tab["friction"]), m * G * math.sin(theta), rtol=1e-12)
    np.testing.assert_allclose(tab["friction.normal"], m * G * math.cos(theta), rtol=1e-12)
    np.testing.assert_allclose(tab["friction.limit"], mu * m * G * math.cos(theta), rtol=1e-12)


@pytest.mark.parametrize("mu", [pytest.param(0.0, marks=pytest.mark.slow), 0.3])  # slow: CI's
def test_a_block_slides_above_the_friction_angle_at_g_sin_minus_mu_cos(mu):
    theta, m = 0.5, 2.0
    r = md.forward(incline(theta, mu, m), TS, rtol=1e-10, atol=1e-12)
    a = G * (math.sin(theta) - mu * math.cos(theta))
    d = np.hypot(r.q[:, 0], r.q[:, 1])
    np.testing.assert_allclose(d, 0.5 * a * TS**2, rtol=1e-9, atol=1e-12)
    tab = r.table()
    np.testing.assert_allclose(tab["friction.speed"], a * TS, rtol=1e-9, atol=1e-12)
    # the friction's work: -mu m g cos(theta) times the distance (the dissipated energy)
    work = np.asarray(tab["work.nonconservative"])
    np.testing.assert_allclose(work, -mu * m * G * math.cos(theta) * d, atol=1e-9)
    np.testing.assert_allclose(
        tab["friction.power"], -mu * m * G * math.cos(theta) * a * TS, atol=1e-9
    )


def flywheel(mu=0.2, radius=0.01, m=5.0, R=0.15, rate=0.2) -> md.Model:
    return md.Model(
        bodies=[md.Body("wheel", m, 0.5 * m * R**2, q0=(0.0, 0.0, 0.0))],
        joints=[md.Revolute("pin", "ground", "wheel")],
        forces=[
            md.JointFriction("pin_friction", "pin", mu=mu, radius=radius),
            md.Torque("drive", "wheel", law=md.Ramp(0.0, rate)),
        ],
        gravity=(0.0, -G),
    )


def test_a_flywheel_sticks_until_the_torque_passes_mu_r_m_g_then_turns():
    mu, radius, m, R, rate = 0.2, 0.01, 5.0, 0.15, 0.2
    t = np.linspace(0.0, 1.0, 21)
    r = md.forward(flywheel(mu, radius, m, R, rate), t, rtol=1e-10, atol=1e-12)
    limit = mu * radius * m * G
    t0 = limit / rate  # the torque reaches the friction torque
    inertia = 0.5 * m * R**2
    tt = np.maximum(t - t0, 0.0)
    omega = (0.5 * rate * tt**2) / inertia  # I alpha = rate (t - t0)
    phi = (rate * tt**3 / 6) / inertia
    np.testing.assert_allclose(r.qd[:, 2], omega, atol=2e-6)
    np.testing.assert_allclose(r.q[:, 2], phi, atol=2e-6)
    tab = r.table()
    np.testing.assert_allclose(tab["pin_friction.normal"], m * G, rtol=1e-10)
    still = t < t0 - 0.02
    np.testing.assert_allclose(np.abs(tab["pin_friction"])[still], rate * t[still], atol=1e-10)
    np.testing.assert_allclose(np.abs(tab["pin_friction"])[t > t0 + 0.02], limit, rtol=1e-10)


def slider_crank(mu: float, r=0.1, l=0.3, omega=2 * math.pi, m_slider=1.5, P=40.0):
    """A slider-crank with (nearly) massless crank and rod, the crank driven at ``omega``,
    a load ``P`` [N] against the slider (along -x) and friction ``mu`` at the slide."""
    tiny = 1e-6
    return md.Model(
        bodies=[
            md.Body(
                "crank", tiny, tiny, q0=(r / 2, 0, 0), points={"O": (-r / 2, 0), "A": (r / 2, 0)}
            ),
            md.Body(
                "rod", tiny, tiny, q0=(r + l / 2, 0, 0), points={"A": (-l / 2, 0), "B": (l / 2, 0)}
            ),
            md.Body("slider", m_slider, 0.01, q0=(r + l, 0, 0)),
        ],
        joints=[
            md.Revolute("O", "ground", "crank.O"),
            md.Revolute("A", "crank.A", "rod.A"),
            md.Revolute("B", "rod.B", "slider"),
            md.Translational("slide", "ground", "slider", axis=(1, 0)),
        ],
        drivers=[md.CoordinateDriver("motor", "crank", "phi", law=md.Ramp(0.3, omega))],
        forces=[
            md.PointForce("load", "slider", along=(-1, 0), law=P),
            md.JointFriction("slide_friction", "slide", mu=mu),
        ],
    )


def hand_derived_torque(t, mu, r=0.1, l=0.3, omega=2 * math.pi, m_slider=1.5, P=40.0):
    """The motor torque of :func:`slider_crank` by hand: the rod is a two-force member of
    force ``F`` along ``e`` (slider -> crank pin); on the slider ``m x'' = F e_x - P + f``,
    ``N = F e_y``, ``f = -mu |N| sign(x')``; on the massless crank ``T = A x (F e)``.
    ``x(t)`` is the closed-form slider position, differentiated by 4th-order central
    differences."""

    def x_of(t):
        th = 0.3 + omega * t
        return r * np.cos(th) + np.sqrt(l**2 - (r * np.sin(th)) ** 2)

    h = 1e-4
    xd = (-x_of(t + 2 * h) + 8 * x_of(t + h) - 8 * x_of(t - h) + x_of(t - 2 * h)) / (12 * h)
    xdd = (
        -x_of(t + 2 * h) + 16 * x_of(t + h) - 30 * x_of(t) + 16 * x_of(t - h) - x_of(t - 2 * h)
    ) / (12 * h**2)
    th = 0.3 + omega * t
    A = np.stack([r * np.cos(th), r * np.sin(th)])
    e = (A - np.stack([x_of(t), 0 * t])) / l
    rhs = m_slider * xdd + P
    s = np.sign(xd)
    F = rhs / (e[0] - mu * np.abs(e[1]) * s)  # with |F| = F; else |F| = -F:
    neg = F < 0
    F = np.where(neg, rhs / (e[0] + mu * np.abs(e[1]) * s), F)
    return F * (A[0] * e[1] - A[1] * e[0])


@pytest.mark.parametrize("mu", [0.0, 0.25])
def test_slider_crank_motor_torque_with_slide_friction_matches_the_hand_derivation(mu):
    t = np.linspace(0.0, 1.0, 41)[1:-1]
    res = md.inverse(slider_crank(mu), t)
    T = np.asarray(res.table()["motor"])
    ref = hand_derived_torque(t, mu)
    moving = np.abs(np.asarray(res.table()["slide_friction.speed"])) > 1e-3
    np.testing.assert_allclose(T[moving], ref[moving], rtol=2e-5, atol=1e-6 * ref.max())
    if mu > 0:  # the same motion: the motor's extra power is what the friction dissipates
        T0 = np.asarray(md.inverse(slider_crank(0.0), t).table()["motor"])
        dissipated = -np.asarray(res.table()["slide_friction.power"])
        assert np.all(dissipated >= 0) and dissipated.max() > 0.5
        np.testing.assert_allclose((T - T0) * 2 * math.pi, dissipated, atol=1e-4)


@pytest.mark.parametrize(
    "make, words",
    [
        (
            lambda: md.Model(
                bodies=[md.Body("b", 1.0, 0.1)],
                joints=[md.Weld("w", "ground", "b")],
                forces=[md.JointFriction("f", "w", mu=0.1)],
            ),
            "revolute, translational and pin-in-slot",
        ),
        (
            lambda: md.Model(
                bodies=[md.Body("b", 1.0, 0.1)],
                joints=[md.Revolute("p", "ground", "b")],
                forces=[md.JointFriction("f", "p", mu=0.1)],
            ),
            "radius",
        ),
        (
            lambda: md.Model(
                bodies=[md.Body("b", 1.0, 0.1)],
                joints=[md.Revolute("p", "ground", "b")],
                forces=[md.JointFriction("f", "q", mu=0.1, radius=0.01)],
            ),
            "no joint 'q'",
        ),
        (lambda: md.JointFriction("f", "p", mu=-0.1), ">= 0"),
    ],
    ids=["weld", "no-radius", "unknown-joint", "negative-mu"],
)
def test_bad_friction_is_refused_by_name(make, words):
    with pytest.raises(md.ModelError, match=words):
        make()


def test_friction_is_refused_where_it_is_not_modelled():
    model = incline(0.2, 0.3)
    with pytest.raises(md.ModelError, match=r"joint friction \(friction\).*generalized-alpha"):
        md.forward(model, TS, method="generalized-alpha", dt=0.01)
    with pytest.raises(md.ModelError, match=r"joint friction \(friction\).*statics"):
        md.statics(model)


def test_a_block_thrown_up_an_incline_stops_and_sticks():
    """Slip, then stick: launched up the incline at v0 it decelerates at g (sin + mu cos),
    stops at v0 / a, and (below the friction angle) stays: within the stick band's creep."""
    theta, mu, v0 = 0.2, 0.3, 1.0
    c, s = math.cos(theta), math.sin(theta)
    model = incline(theta, mu)
    qd0 = (-v0 * c, v0 * s, 0.0)  # up the slope (the axis points down it)
    t = np.linspace(0.0, 1.0, 51)
    r = md.forward(model, t, qd0=qd0, rtol=1e-10, atol=1e-12)
    a = G * (s + mu * c)
    t_stop = v0 / a
    up = v0 * np.minimum(t, t_stop) - 0.5 * a * np.minimum(t, t_stop) ** 2
    d = np.hypot(r.q[:, 0], r.q[:, 1])
    creep = 1e-6 * (t[-1] - t_stop)  # v_stick (1e-6 m/s) at most, after the stop
    np.testing.assert_allclose(d, up, atol=1e-8 + creep)
    speed = np.asarray(r.table()["friction.speed"])
    assert np.all(np.abs(speed[t > t_stop + 0.02]) <= 1e-6)


def test_a_slides_friction_is_drawn_against_the_motion_at_its_limit():
    from mixdyn.viz.arrows import force_arrows

    theta, mu, m = 0.5, 0.3, 2.0
    r = md.forward(incline(theta, mu, m), TS, rtol=1e-10, atol=1e-12)
    (arrow,) = force_arrows(r, ["friction"])
    F = arrow["F"][1:]
    v = np.asarray(r.qd)[1:, :2]
    np.testing.assert_allclose(np.hypot(F[:, 0], F[:, 1]), mu * m * G * math.cos(theta), rtol=1e-12)
    cosang = np.sum(F * v, axis=1) / np.hypot(F[:, 0], F[:, 1]) / np.hypot(v[:, 0], v[:, 1])
    np.testing.assert_allclose(cosang, -1.0, atol=1e-12)
    np.testing.assert_allclose(arrow["at"], np.asarray(r.q)[:, :2], atol=1e-12)


@pytest.mark.slow  # compiles a reverse-mode run and a vectorized sweep (~40 s); CI runs it
def test_friction_is_differentiable_and_sweeps_equal_single_runs():
    """The sliding block's distance d = g (sin - mu cos) t^2 / 2: its derivative with respect to
    mu through a run (reverse mode) is -g cos t^2 / 2; a vectorized sweep over mu equals the
    single runs and sticks where mu > tan(theta)."""
    import jax

    theta, m = 0.5, 2.0
    f, mu0 = md.differentiable(incline(theta, 0.3, m), TS, ["friction.mu"], rtol=1e-10, atol=1e-12)

    def distance(p):
        q = f(p)["q"][-1]
        return jax.numpy.hypot(q[0], q[1])

    g = float(jax.grad(distance)(mu0)[0])
    np.testing.assert_allclose(g, -G * math.cos(theta) * TS[-1] ** 2 / 2, rtol=1e-7)
    mus = [0.2, 0.4, 0.7]  # tan(0.5) = 0.546: the last sticks
    sw = md.sweep(
        incline(theta, 0.3, m), TS, vary={"friction.mu": mus}, batch_size=3, rtol=1e-10, atol=1e-12
    )
    assert not sw.errors
    for k, mu in enumerate(mus):
        d = np.hypot(sw[k].q[-1, 0], sw[k].q[-1, 1])
        a = max(G * (math.sin(theta) - mu * math.cos(theta)), 0.0)
        np.testing.assert_allclose(d, 0.5 * a * TS[-1] ** 2, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "forces, code, words",
    [("[hold1, hold2]", 0, "ok"), ("[hold1, pin_friction]", 2, "friction torque: it has no arrow")],
)
def test_a_files_animation_draws_a_slides_friction_not_a_pins(tmp_path, forces, code, words):

    from typer.testing import CliRunner

    from mixdyn.cli import app

    example = EXAMPLES / "friction.yaml"
    text = example.read_text().replace("forces: true}", f"forces: {forces}}}")
    path = tmp_path / "friction.yaml"
    path.write_text(text)
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == code and words in res.output


def test_a_mixed_run_recovers_the_push_that_overcomes_friction():
    """Mixed dynamics: the block is prescribed up the incline at a = 1 m/s^2 from rest and the
    push along the slope is unknown: P = m (a + g sin + mu g cos), friction included (from
    t = 0, where the prescribed motion is about to go up)."""
    theta, mu, m, a = 0.3, 0.25, 2.0, 1.0
    c, s = math.cos(theta), math.sin(theta)
    model = incline(theta, mu, m).replace(
        forces=[
            md.JointFriction("friction", "slide", mu=mu),
            md.PointForce("push", "block", along=(-c, s), law=0.0),
        ]
    )
    t = np.linspace(0.0, 1.0, 11)
    law = md.Polynomial([0.0, 0.0, -0.5 * a * c])  # x(t) of the block going up (axis: down)
    res = md.mixed(
        model,
        t,
        prescribed=[md.CoordinateDriver("up", "block", "x", law=law)],
        unknown=["push"],
        solver="augmented",
        rtol=1e-10,
        atol=1e-12,
    )
    np.testing.assert_allclose(res["push"], m * (a + G * s + mu * G * c), rtol=1e-8)
    np.testing.assert_allclose(res["friction.normal"], m * G * c, rtol=1e-8)
