"""Laws of time: values and derivatives against closed forms and finite differences."""

import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md

RNG_SEED = 20240611


def derivs(law, t):
    """``(f, f', f'')`` of a law at ``t`` as Python floats."""
    return tuple(float(v) for v in law.derivatives(t))


def fd_derivs(law, t, h=1e-3):
    """First and second derivatives by fourth-order central differences."""
    f = [float(law(jnp.asarray(t + k * h))) for k in (-2, -1, 0, 1, 2)]
    d1 = (f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * h)
    d2 = (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * h**2)
    return d1, d2


def test_constant():
    law = md.Constant(3.25)
    for t in (-1.0, 0.0, 2.5):
        assert derivs(law, t) == (3.25, 0.0, 0.0)


def test_polynomial_matches_closed_form():
    rng = np.random.default_rng(RNG_SEED)
    c = rng.normal(size=5)  # ascending powers
    law = md.Polynomial(c)
    for t in rng.uniform(-2, 2, size=7):
        f = sum(c[k] * t**k for k in range(5))
        fd = sum(k * c[k] * t ** (k - 1) for k in range(1, 5))
        fdd = sum(k * (k - 1) * c[k] * t ** (k - 2) for k in range(2, 5))
        np.testing.assert_allclose(derivs(law, t), (f, fd, fdd), rtol=1e-13, atol=1e-13)


def test_ramp():
    law = md.Ramp(0.4, -1.5)
    np.testing.assert_allclose(derivs(law, 2.0), (0.4 - 3.0, -1.5, 0.0), rtol=0, atol=1e-15)


def test_harmonic_matches_closed_form():
    A, w, ph, off = 0.7, 3.1, 0.4, -0.2
    law = md.Harmonic(A, w, phase=ph, offset=off)
    for t in np.linspace(-1, 3, 9):
        s, c = np.sin(w * t + ph), np.cos(w * t + ph)
        np.testing.assert_allclose(
            derivs(law, t), (off + A * s, A * w * c, -A * w**2 * s), rtol=1e-13, atol=1e-14
        )


def test_function_law_matches_closed_form():
    law = md.FunctionLaw(lambda t: t**2 * jnp.sin(3 * t))
    for t in (-0.8, 0.3, 1.7):
        s, c = np.sin(3 * t), np.cos(3 * t)
        f = t**2 * s
        fd = 2 * t * s + 3 * t**2 * c
        fdd = 2 * s + 12 * t * c - 9 * t**2 * s
        np.testing.assert_allclose(derivs(law, t), (f, fd, fdd), rtol=1e-13, atol=1e-14)


def test_as_law_coerces():
    assert isinstance(md.as_law(2.0), md.Constant)
    assert isinstance(md.as_law(lambda t: t), md.FunctionLaw)
    ramp = md.Ramp(1.0, 2.0)
    assert md.as_law(ramp) is ramp
    # A driver's law given as a number or a callable is coerced on construction.
    d = md.CoordinateDriver("d", "b", "x", law=lambda t: 2 * t)
    assert derivs(d.law, 1.5) == (3.0, 2.0, 0.0)


def _every_law():
    rng = np.random.default_rng(RNG_SEED + 1)
    ts = np.linspace(0.0, 2.0, 9)
    ys = np.sin(2 * ts) + 0.1 * rng.normal(size=ts.size)
    return [
        md.Polynomial([0.3, -1.0, 0.5, 0.25]),
        md.Harmonic(1.2, 2.0, 0.3, 0.1),
        md.FunctionLaw(lambda t: jnp.exp(-t) * jnp.cos(2 * t)),
        md.Spline(ts, ys, kind="cubic"),
        md.Spline(ts, ys, kind="quintic"),
        md.QuinticHermite(ts, ys, 2 * np.cos(2 * ts), -4 * np.sin(2 * ts)),
    ]


@pytest.mark.parametrize("index", range(6))
def test_derivatives_match_finite_differences(index):
    law = _every_law()[index]
    # Inside pieces of the splines (away from the breaks, where f''' may jump).
    for t in (0.37, 0.91, 1.62):
        f, fd, fdd = derivs(law, t)
        assert f == pytest.approx(float(law(jnp.asarray(t))), abs=1e-14)
        d1, d2 = fd_derivs(law, t, h=1e-3)
        assert fd == pytest.approx(d1, abs=1e-8)
        assert fdd == pytest.approx(d2, abs=2e-6)


def test_cubic_spline_reproduces_a_cubic_and_extends_it():
    # Not-a-knot cubic splines are exact for cubic polynomials, also outside the samples
    # (the first and last pieces are extended).
    c = np.array([0.5, -1.0, 0.75, 0.3])
    ts = np.array([0.0, 0.3, 0.5, 1.1, 1.4, 2.0])
    law = md.Spline(ts, np.polyval(c[::-1], ts), kind="cubic")
    for t in (-0.2, 0.1, 0.77, 1.25, 1.99, 2.3):
        f = np.polyval(c[::-1], t)
        fd = np.polyval(np.polyder(c[::-1]), t)
        fdd = np.polyval(np.polyder(c[::-1], 2), t)
        np.testing.assert_allclose(derivs(law, t), (f, fd, fdd), rtol=1e-11, atol=1e-11)


def test_quintic_spline_reproduces_a_quintic():
    c = np.array([0.1, 0.4, -0.7, 0.2, 0.3, -0.05])
    ts = np.linspace(0.0, 2.0, 8)
    law = md.Spline(ts, np.polyval(c[::-1], ts), kind="quintic")
    p = c[::-1]
    for t in (0.05, 0.6, 1.33, 1.97):
        expect = (np.polyval(p, t), np.polyval(np.polyder(p), t), np.polyval(np.polyder(p, 2), t))
        np.testing.assert_allclose(derivs(law, t), expect, rtol=1e-10, atol=1e-10)


def piece_derivatives(law, i, t, n):
    """Derivatives 0..n at ``t`` of piece ``i`` of a piecewise polynomial (its layout:
    ``breaks`` and ``coeffs``, highest power first), to compare one-sided limits at a break."""
    p = np.asarray(law.coeffs)[:, i]
    dt = t - float(law.breaks[i])
    return np.array([np.polyval(np.polyder(p, k), dt) for k in range(n + 1)])


@pytest.mark.parametrize(("kind", "order"), [("cubic", 2), ("quintic", 4)])
def test_spline_interpolates_and_is_smooth(kind, order):
    rng = np.random.default_rng(RNG_SEED + 2)
    ts = np.cumsum(rng.uniform(0.2, 0.5, size=10))
    ys = rng.normal(size=ts.size)
    law = md.Spline(ts, ys, kind=kind)
    np.testing.assert_allclose([float(law(jnp.asarray(t))) for t in ts], ys, atol=1e-12)
    # Continuity of the derivatives 0..order at every interior break: both pieces agree.
    breaks = np.asarray(law.breaks)
    for i in range(1, breaks.size - 1):
        left = piece_derivatives(law, i - 1, breaks[i], order)
        right = piece_derivatives(law, i, breaks[i], order)
        np.testing.assert_allclose(left, right, rtol=1e-8, atol=1e-8 * np.abs(right).max())
    # The law's own derivatives agree with the pieces, at and between breaks.
    for t in (breaks[3], 0.5 * (breaks[4] + breaks[5])):
        i = int(np.searchsorted(breaks, t, side="right")) - 1
        np.testing.assert_allclose(
            derivs(law, t), piece_derivatives(law, i, t, 2), rtol=1e-12, atol=1e-12
        )


def test_cubic_spline_end_conditions():
    ts = np.linspace(0.0, 1.0, 6)
    ys = np.array([0.0, 0.4, -0.1, 0.3, 0.9, 0.2])
    natural = md.Spline(ts, ys, bc_type="natural")
    assert derivs(natural, 0.0)[2] == pytest.approx(0.0, abs=1e-12)
    assert derivs(natural, 1.0)[2] == pytest.approx(0.0, abs=1e-12)
    clamped = md.Spline(ts, ys, bc_type="clamped")
    assert derivs(clamped, 0.0)[1] == pytest.approx(0.0, abs=1e-12)
    assert derivs(clamped, 1.0)[1] == pytest.approx(0.0, abs=1e-12)


def test_quintic_hermite_reproduces_samples():
    rng = np.random.default_rng(RNG_SEED + 3)
    ts = np.cumsum(rng.uniform(0.1, 0.4, size=8))
    y, yd, ydd = rng.normal(size=(3, ts.size))
    law = md.QuinticHermite(ts, y, yd, ydd)
    for k, t in enumerate(ts):
        np.testing.assert_allclose(derivs(law, t), (y[k], yd[k], ydd[k]), rtol=1e-9, atol=1e-9)
        if k > 0:  # the piece on the left reaches the same values (C2)
            left = piece_derivatives(law, k - 1, t, 2)
            np.testing.assert_allclose(left, (y[k], yd[k], ydd[k]), rtol=1e-9, atol=1e-9)


def test_quintic_hermite_is_exact_for_a_quintic():
    p = np.array([0.02, -0.3, 0.5, 0.1, -1.0, 0.4])  # highest power first
    ts = np.array([0.0, 0.4, 1.1, 1.5])
    law = md.QuinticHermite(
        ts, np.polyval(p, ts), np.polyval(np.polyder(p), ts), np.polyval(np.polyder(p, 2), ts)
    )
    for t in (0.1, 0.75, 1.3, 1.45):
        expect = (np.polyval(p, t), np.polyval(np.polyder(p), t), np.polyval(np.polyder(p, 2), t))
        np.testing.assert_allclose(derivs(law, t), expect, rtol=1e-11, atol=1e-11)


def test_spline_rejects_bad_samples():
    with pytest.raises(ValueError, match="increasing"):
        md.Spline([0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="kind"):
        md.Spline([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], kind="septic")
    with pytest.raises(ValueError, match="6 samples"):
        md.Spline([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], kind="quintic")
    with pytest.raises(ValueError, match="increasing"):
        md.QuinticHermite([0.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0])
