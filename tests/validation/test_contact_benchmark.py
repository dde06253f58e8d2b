"""The measures of the contact benchmark (``benchmarks/contact.py``) against closed forms.

- ``first_bounce`` reads the impact time ``sqrt(2 h0 / g)`` and the apex ``e**2 h0`` of a
  rigid bouncing ball written out here in closed form, sampled at 1 ms (whether or not a
  sample falls in the contact), and 0 for a ball that stays on the ground.
- ``hertz_duration`` and ``linear_damping_ratio``, which set the peers' contact, against
  SciPy's integration of the elastic Hertz impact and of a linear spring-damper's impact.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fixtures import ROOT


def _bench():
    spec = importlib.util.spec_from_file_location("contact", ROOT / "benchmarks" / "contact.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


bench = _bench()
G, H0 = 9.81, 0.05


def rigid_bounce(t, e, penetration=0.0):
    """The bottom's height and vertical velocity of a ball released at rest ``H0`` above the
    ground, rebounding with Newton's restitution ``e`` (closed form, first bounce only); with
    ``penetration`` > 0, the samples within 0.3 ms after the impact read as in contact and
    rebounding (0.1 m/s up)."""
    t1 = math.sqrt(2 * H0 / G)
    v1 = e * G * t1
    tau = t - t1
    gap = np.where(t < t1, H0 - G * t**2 / 2, v1 * tau - G * tau**2 / 2)
    vy = np.where(t < t1, -G * t, v1 - G * tau)
    contact = (tau >= 0) & (tau < 3e-4)
    return np.where(contact, -penetration, gap), np.where(contact, 0.1, vy)


@pytest.mark.parametrize("offset", [0.0, 0.4e-3])  # the impact between samples, or a sample in it
def test_first_bounce_reads_the_closed_form_impact_time_and_apex(offset):
    e = 0.9
    t = np.arange(0.0, 0.25, 1e-3) + offset
    gap, vy = rigid_bounce(t, e, penetration=3e-5 if offset else 0.0)
    t_impact, h1 = bench.first_bounce(t, gap, vy, G)
    assert t_impact == pytest.approx(math.sqrt(2 * H0 / G), abs=1e-14)
    assert h1 == pytest.approx(e**2 * H0, rel=1e-12)


def test_a_ball_that_stays_down_has_no_apex():
    t = np.arange(0.0, 0.25, 1e-3)
    gap, vy = rigid_bounce(t, 0.9)
    down = t > math.sqrt(2 * H0 / G)
    gap, vy = np.where(down, -1e-5, gap), np.where(down, 1e-4 * np.sin(t * 1e4), vy)  # jitter
    assert bench.first_bounce(t, gap, vy, G)[1] == 0.0


def test_hertz_duration_and_linear_damping_against_integrated_impacts():
    m, k, v = 0.1, 1.465e10, 0.99

    def separation(_, y):
        return y[0]

    separation.terminal, separation.direction = True, -1
    hertz = solve_ivp(
        lambda _, y: [y[1], -k * max(y[0], 0.0) ** 1.5 / m], (0, 1e-2), [0.0, v],
        events=separation, rtol=1e-11, atol=1e-16, max_step=1e-6,
    )  # fmt: skip
    assert bench.hertz_duration(m, k, v) == pytest.approx(hertz.t_events[0][0], rel=2e-3)
    # a linear spring-damper rebounds with e = exp(-zeta pi / sqrt(1 - zeta**2))
    e, omega = 0.9, 1e4
    zeta = bench.linear_damping_ratio(e)
    linear = solve_ivp(
        lambda _, y: [y[1], -2 * zeta * omega * y[1] - omega**2 * y[0]], (0, 1.0), [0.0, v],
        events=separation, rtol=1e-12, atol=1e-16,
    )  # fmt: skip
    assert -linear.y_events[0][0][1] / v == pytest.approx(e, rel=1e-9)
