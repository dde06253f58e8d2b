"""Laws that jump are input errors: a cam's law over its turn (and across the wrap-around
``theta = 2 pi -> 0``) and a driver's law over a run must be continuous with their slopes,
and with their second derivatives where the run reports accelerations, unless the element
declares ``continuity="C1"``. The jumps found are checked against the laws' own definitions
(the place of a ``where``'s switch, the size of a step, of a kink or of a change of
acceleration from the segments' closed forms); smooth laws made of segments that meet with
equal value, slope and second derivative (cycloidal, 3-4-5 polynomial) pass, a
constant-acceleration law passes with ``continuity="C1"``, and so does a steep smooth bump
narrower than the first grid."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
from mixdyn.model._smoothness import jumps

TWO_PI = 2 * math.pi
H, BASE = 0.02, 0.05
RESOLUTION = TWO_PI / 2048  # the coarse grid: every jump is placed much closer than this


def cam_model(law, continuity="C2"):
    """A cam on a pin at the origin, a knife-edge follower on a vertical guide above it."""
    return md.Model(
        bodies=[
            md.Body("cam", 1.0, 1e-3, q0=(0, 0, 0)),
            md.Body("follower", 0.5, 1e-4, q0=(0, BASE, 0)),
        ],
        ground={"O": (0.0, 0.0)},
        joints=[
            md.Revolute("O", "ground.O", "cam"),
            md.Translational("guide", "ground.O", "follower", axis=(0, 1)),
            md.CamFollower(
                "cam_pair",
                "cam",
                "follower",
                law=md.FunctionLaw(law),
                base=BASE,
                continuity=continuity,
            ),
        ],
        drivers=[md.CoordinateDriver("motor", "cam", "phi", law=md.Ramp(0.0, 2.0))],
        units=md.SI,
    )


def turn(law):
    return jumps(md.FunctionLaw(law), 0.0, TWO_PI, periodic=True)


def step(th):
    return jnp.where(th < math.pi, 0.0, H)


def sawtooth(th):
    return H * (th / TWO_PI - jnp.floor(th / TWO_PI))


def linear_rise_dwell_return(th):
    """Rise over the first third, dwell, return over the last third: continuous, with
    kinks (slope 3H/(2 pi), then 0, then -3H/(2 pi))."""
    a, b = TWO_PI / 3, 2 * TWO_PI / 3
    return jnp.where(th < a, H * th / a, jnp.where(th < b, H, H * (TWO_PI - th) / a))


def cycloidal_rise_dwell_return(th):
    """Cycloidal rise over [0, 2 pi/3], dwell, cycloidal return over [4 pi/3, 2 pi]: equal
    value, slope and second derivative where the segments meet."""
    beta = TWO_PI / 3
    u = th / beta
    w = (th - 2 * beta) / beta
    rise = H * (u - jnp.sin(TWO_PI * u) / TWO_PI)
    back = H * (1 - (w - jnp.sin(TWO_PI * w) / TWO_PI))
    return jnp.where(th < beta, rise, jnp.where(th < 2 * beta, H, back))


def polynomial_345(th):
    """3-4-5 polynomial rise over the first half turn, the mirror image back."""
    u = jnp.where(th < math.pi, th / math.pi, (TWO_PI - th) / math.pi)
    return H * (10 * u**3 - 15 * u**4 + 6 * u**5)


def constant_acceleration(th):
    """Parabolic rise and return (constant accelerations +-a): continuous with its slope,
    its second derivative jumps at every quarter turn."""
    q = math.pi / 2
    return jnp.where(
        th < q,
        2 * H * (th / math.pi) ** 2,
        jnp.where(
            th < math.pi,
            H - 2 * H * ((math.pi - th) / math.pi) ** 2,
            jnp.where(
                th < 3 * q,
                H - 2 * H * ((th - math.pi) / math.pi) ** 2,
                2 * H * ((TWO_PI - th) / math.pi) ** 2,
            ),
        ),
    )


def narrow_bump(th):
    """A Gaussian bump 1e-3 rad wide (a third of the first grid's step): smooth."""
    return H * jnp.exp(-(((th - 2.0) / 1e-3) ** 2))


def test_a_step_is_refused_where_it_steps():
    (j,) = [j for j in turn(step) if j.at < 6]  # the second jump is the wrap, H -> 0
    assert j.order == 0 and j.size == pytest.approx(H)
    assert abs(j.at - math.pi) < RESOLUTION / 2048**2
    with pytest.raises(md.ModelError, match=r"cam_pair.*jumps by \+0\.02 .* in its value") as e:
        cam_model(step)
    assert e.value.field == "law" and "theta = 3.14159 rad (180 deg)" in str(e.value)


def test_a_sawtooth_is_refused_at_the_wrap():
    (j,) = turn(sawtooth)
    assert j.order == 0 and j.size == pytest.approx(-H)
    assert TWO_PI - j.at < RESOLUTION
    with pytest.raises(md.ModelError, match="where the turn wraps around to theta = 0"):
        cam_model(sawtooth)
    # the same with the law given over the turn alone (the cam reads it theta mod 2 pi)
    (j,) = turn(lambda th: H * th / TWO_PI)
    assert j.order == 0 and j.size == pytest.approx(-H)


def test_a_kinked_law_is_refused_with_its_slope_jump():
    found = turn(linear_rise_dwell_return)
    slope = 3 * H / TWO_PI
    assert [j.order for j in found] == [1, 1, 1]
    np.testing.assert_allclose([j.at for j in found], [TWO_PI / 3, 2 * TWO_PI / 3, TWO_PI])
    np.testing.assert_allclose([j.size for j in found], [-slope, -slope, 2 * slope], rtol=1e-9)
    with pytest.raises(md.ModelError, match=r"in its slope at theta = 2\.0944 rad \(120 deg\)"):
        cam_model(linear_rise_dwell_return)


@pytest.mark.parametrize(
    "law",
    [cycloidal_rise_dwell_return, polynomial_345, narrow_bump],
    ids=lambda f: f.__name__,
)
def test_smooth_laws_pass(law):
    """Continuous with their second derivatives: accepted by default (C2)."""
    assert turn(law) == []
    assert jumps(md.FunctionLaw(law), 0.0, TWO_PI, periodic=True, order=2) == []
    cam_model(law)


def test_a_constant_acceleration_cam_is_refused_by_default_and_accepted_with_c1():
    """The parabolic rise and return's second derivative, 4H/pi**2 then -4H/pi**2 and back
    (by hand from its segments), jumps by -8H/pi**2 at the rise's middle, pi/2, and by
    +8H/pi**2 at the return's, 3 pi/2, and nowhere else (it meets at pi and across the
    wrap-around): refused by default at pi/2 (the first), accepted with ``continuity="C1"``,
    which asks for value and slope only (none jump)."""
    found = jumps(md.FunctionLaw(constant_acceleration), 0.0, TWO_PI, periodic=True, order=2)
    size = 8 * H / math.pi**2
    assert [j.order for j in found] == [2, 2]
    assert abs(found[0].at - math.pi / 2) < RESOLUTION / 2048**2
    assert abs(found[1].at - 3 * math.pi / 2) < RESOLUTION / 2048**2
    np.testing.assert_allclose([j.size for j in found], [-size, size], rtol=1e-9)
    with pytest.raises(md.ModelError) as e:
        cam_model(constant_acceleration)
    assert e.value.field == "law"
    assert f"jumps by {-size:+.6g} (model units) in its second derivative" in str(e.value)
    assert "theta = 1.5708 rad (90 deg)" in str(e.value) and "continuity: C1" in str(e.value)
    assert turn(constant_acceleration) == []
    cam_model(constant_acceleration, continuity="C1")
    with pytest.raises(md.ModelError, match="continuity must be one of C1, C2"):
        cam_model(cycloidal_rise_dwell_return, continuity="C3")


def test_an_infinite_slope_is_refused():
    (j,) = turn(lambda th: H * jnp.sqrt(th / TWO_PI) * (1 - th / TWO_PI))
    assert not j.finite and j.at == 0.0


def driven(law, continuity="C2"):
    """A crank on a pin driven by ``law``."""
    motor = md.CoordinateDriver(
        "motor", "crank", "phi", law=md.FunctionLaw(law), continuity=continuity
    )
    return md.Model(
        bodies=[md.Body("crank", 1.0, 0.1, q0=(0, 0, 0))],
        joints=[md.Revolute("O", "ground", "crank")],
        drivers=[motor],
        units=md.SI,
    )


def test_a_driver_that_jumps_is_refused_when_run():
    model = driven(lambda t: jnp.where(t < 0.3, 2 * t, 2 * t + 0.1))
    with pytest.raises(md.ModelError, match=r"motor.*jumps by \+0\.1 .* value at t = 0\.3"):
        md.kinematic(model, np.linspace(0, 1, 5))
    # over a span before the jump it runs
    res = md.kinematic(model, np.linspace(0, 0.25, 5))
    np.testing.assert_allclose(res["crank.phi"], 2 * np.linspace(0, 0.25, 5), atol=1e-12)


def test_a_driver_with_a_kink_is_refused_and_one_with_an_acceleration_jump_runs_with_c1():
    """A kink is refused whatever the continuity. A trapezoidal speed (4 rad/s**2 to
    t = 0.25, then 1 rad/s: its acceleration drops by 4 there, by hand) is refused by default
    where accelerations are reported, at t = 0.25 with that size; with ``continuity="C1"`` it
    runs and reports the accelerations of its segments, and a statics run (no accelerations)
    takes it by default."""
    kink = driven(lambda t: jnp.where(t < 0.5, t, 0.5 + 3 * (t - 0.5)), continuity="C1")
    with pytest.raises(md.ModelError, match=r"jumps by \+2 .* slope at t = 0\.5"):
        md.kinematic(kink, np.linspace(0, 1, 5))

    def trapezoid(t):
        return jnp.where(t < 0.25, 2 * t**2, 0.125 + (t - 0.25))

    with pytest.raises(md.ModelError, match=r"jumps by -4 .* second derivative at t = 0\.25"):
        md.kinematic(driven(trapezoid), np.array([0.0, 0.1, 0.5]))
    driven(trapezoid).drivers[0].check_law(0.0, 0.5, accelerations=False)
    res = md.kinematic(driven(trapezoid, continuity="C1"), np.array([0.0, 0.1, 0.5]))
    np.testing.assert_allclose(res["crank.alpha"], [4.0, 4.0, 0.0], atol=1e-9)


@pytest.mark.parametrize(
    ("law", "periodic"),
    [
        (md.PiecewisePolynomial([0.0, 1.0, 2.0], [[1.0, 0.0], [0.0, 1.0]]), False),  # a kink
        (md.PiecewisePolynomial([0.0, 1.0, 2.0], [[1.0, 0.0], [0.0, 2.0]]), False),  # a step
        (md.Spline(np.linspace(0, TWO_PI, 13), 1 - np.cos(np.linspace(0, TWO_PI, 13))), True),
        (md.Spline(np.linspace(0, TWO_PI, 13), np.linspace(0, TWO_PI, 13)), True),
        (md.QuinticHermite([0.0, 1.0, 2.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0, 0]), False),
        # t**2, then 1 + 2s - s**2: value and slope meet at 1, the second derivative 2 -> -2
        (md.PiecewisePolynomial([0.0, 1.0, 2.0], [[1.0, -1.0], [0.0, 2.0], [0.0, 1.0]]), False),
        (md.Spline(np.linspace(0, 2, 7), np.sin(np.linspace(0, 2, 7))), False),  # C2
    ],
    ids=["kink", "step", "spline-wrap-slope", "spline-wrap-value", "hermite", "bend", "spline"],
)
@pytest.mark.parametrize("order", [1, 2])
def test_piecewise_polynomials_are_read_from_their_pieces_as_sampled(law, periodic, order):
    """A piecewise polynomial's jumps, read from its pieces at the breaks, are those found by
    sampling the same law (a second method), up to the slope and up to the second
    derivative."""
    stop = TWO_PI if periodic else 2.0
    pieces = jumps(law, 0.0, stop, periodic=periodic, order=order)
    sampled = jumps(md.FunctionLaw(lambda x: law(x)), 0.0, stop, periodic=periodic, order=order)
    assert [j.order for j in pieces] == [j.order for j in sampled]
    for a, b in zip(pieces, sampled, strict=True):
        assert abs(a.at - b.at) <= b.resolution + 1e-12
        assert a.size == pytest.approx(b.size, rel=1e-6)


def test_which_expressions_are_smooth_by_their_form():
    from mixdyn.io.expressions import ExpressionLaw

    smooth = ["w*t", "10*sin(pi*t/2)", "3*t**2 + 1", "exp(-t)*cos(3*t)", "step5(t, 0, 0, 1, 5)"]
    sampled = ["where(t < 1, 0, 1)", "abs(t - 1)", "1/t", "sqrt(t)", "t**0.5", "t % 1"]
    assert [ExpressionLaw(s, {"w": 2.0}).smooth for s in smooth] == [True] * len(smooth)
    assert [ExpressionLaw(s, {}).smooth for s in sampled] == [False] * len(sampled)
    # to the second derivative: the cubic step's jumps at its ends, the quintic's does not
    assert [ExpressionLaw(s, {"w": 2.0}).smooth_to(2) for s in smooth] == [True] * len(smooth)
    assert not ExpressionLaw("step(t, 0, 0, 1, 5)", {}).smooth_to(2)
    assert ExpressionLaw("step(t, 0, 0, 1, 5)", {}).smooth_to(1)
