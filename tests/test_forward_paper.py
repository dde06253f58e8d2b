"""The paper's example, forward run (0–2 s, loads of the paper README): the four integrators
agree with each other to <= 1e-7 in the slider's x [mm] and the crank's angle [rad]."""

from __future__ import annotations

import numpy as np
import pytest

import mixdyn as md
from fixtures import paper_mechanism
from test_mixed import paper_loads

TS = np.linspace(0.0, 2.0, 41)
HOLD = ("crank.phi", "coupler.phi")
COLS = ("slider.x", "crank.phi")


@pytest.fixture(scope="module")
def model():
    return paper_mechanism(forces=paper_loads())


@pytest.fixture(scope="module")
def runs(model):
    out = {
        "projection": md.forward(model, TS, hold=HOLD, rtol=1e-12, atol=1e-12),
        "projection-dopri8": md.forward(
            model, TS, hold=HOLD, rtol=1e-13, atol=1e-13, solver="dopri8"
        ),
        "partitioning": md.forward(
            model, TS, method="partitioning", hold=HOLD, rtol=1e-12, atol=1e-12
        ),
        "baumgarte": md.forward(model, TS, method="baumgarte", hold=HOLD, dt=2e-4),
    }
    # Generalized-alpha is second order: at dt = 1e-4 its error is ~1e-5 mm. Two step sizes
    # and Richardson extrapolation, x = (4 x(h/2) - x(h)) / 3, give its own converged answer
    # (the ratio of the two errors, ~4, is checked: it proves the method's order).
    ga1 = md.forward(model, TS, method="generalized-alpha", hold=HOLD, dt=1e-4, rho_inf=0.9)
    ga2 = md.forward(model, TS, method="generalized-alpha", hold=HOLD, dt=5e-5, rho_inf=0.9)
    out["generalized-alpha"] = {c: (4 * ga2[c] - ga1[c]) / 3 for c in COLS}
    out["_ga_raw"] = (ga1, ga2)
    return out


@pytest.mark.parametrize("method", ["projection", "partitioning", "baumgarte", "generalized-alpha"])
def test_integrators_agree(runs, method):
    ref = runs["projection-dopri8"]
    for col in COLS:
        assert np.max(np.abs(runs[method][col] - ref[col])) <= 1e-7, col


def test_generalized_alpha_is_second_order(runs):
    ref = runs["projection-dopri8"]
    ga1, ga2 = runs["_ga_raw"]
    e1 = np.max(np.abs(ga1["slider.x"] - ref["slider.x"]))
    e2 = np.max(np.abs(ga2["slider.x"] - ref["slider.x"]))
    assert 3.5 < e1 / e2 < 4.5


def test_constraints_and_energy_bookkeeping(runs):
    """Constraints held to rounding; energy balance T + V - W = const holds (the loads are
    non-conservative: their work is integrated alongside)."""
    r = runs["projection"]
    assert r.stats["max_violation"] < 1e-9
    E = r["energy.total"] - r["work.nonconservative"] - r["work.constraints"]
    assert np.max(np.abs(E - E[0])) <= 1e-8 * np.max(np.abs(r["energy.kinetic"]))
