"""Passage through singular positions, the same on every CPU.

The IFToMM N-four-bar (``fixtures.double_four_bar``) turns over and over; at every horizontal
position all its bars lie on the ground line and its Jacobian loses ``N`` ranks at once: the
parallelogram may bifurcate there. Its exact 1-DOF reduction
(``fixtures.nfourbar_exact``) is the truth. Whether a run passes a flat position used
to depend on the last bits of rounding (the CPU, FMA contraction, library versions), so each
case here is run from several start states perturbed at the 1e-13 level and with several first
step sizes: every one must follow the reduction, or (where a method is known to struggle)
fail with a named error, never return a wrong branch.

Each analysis checks its energy balance (``energy_tol``): a run that leaves its branch breaks
it by a finite amount and raises :class:`mixdyn.EnergyBalanceError`; the last tests check that
this monitor catches a branch jump made on purpose.
"""

from __future__ import annotations

import numpy as np
import pytest

import mixdyn as md
from fixtures import double_four_bar, nfourbar_exact

#: Start states perturbed at the 1e-13 level (seeds) and first step sizes [s]. Seeds 2 and 3
#: are long validation runs (marked slow: CI runs them after the README's test command).
SEEDS = (1, pytest.param(2, marks=pytest.mark.slow), pytest.param(3, marks=pytest.mark.slow))
FIRST_STEPS = (1e-7, 3.7e-4, 2e-2)
#: 0-2 s: two flat positions (theta = pi/2 at ~0.75 s, 3 pi/2 at ~1.5 s).
TS = np.linspace(0.0, 2.0, 21)


def perturbed_start(model: md.Model, qd0, seed: int):
    """``(q0, qd0)``: the fixture's start with every coordinate and velocity moved by a random
    amount of relative size 1e-13 (rounding-level, like another CPU's)."""
    rng = np.random.default_rng(seed)
    q0 = np.asarray(model.q0) * (1 + 1e-13 * rng.standard_normal(model.nq))
    qd = np.asarray(qd0) * (1 + 1e-13 * rng.standard_normal(model.nq))
    return q0, qd


def tip_error(res: md.Result, n: int) -> float:
    """Largest distance [m] of crank 0's tip from the exact reduction at the outputs."""
    return float(np.max(np.abs(res.point("crank0.B")[0] - nfourbar_exact(n, res.t))))


@pytest.fixture(scope="module")
def fourbar():
    return double_four_bar(2)


#: (method options, accuracy [m] the crank tip must keep over 0-2 s).
FOLLOWING = {
    "tsit5-default": (dict(), 1e-5),
    "tsit5-tight": (dict(rtol=1e-12, atol=1e-12), 1e-7),
    "dopri8-loose": (dict(solver="dopri8", rtol=1e-9, atol=1e-9), 1e-6),
    "dopri8-tight": (dict(solver="dopri8", rtol=1e-12, atol=1e-12), 1e-7),
    "partitioning": (dict(method="partitioning"), 1e-4),
}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize(
    "case",
    [pytest.param(c, marks=pytest.mark.slow) if c == "dopri8-tight" else c for c in FOLLOWING],
)  # dopri8-tight in CI's slow set (the README's command within 6 min)
def test_adaptive_methods_follow_the_branch_from_perturbed_starts(fourbar, case, seed):
    """Adaptive methods at loose and tight tolerances, from three perturbed starts, stay on
    the parallelogram branch through two flat positions. (The tight tolerances used to do
    worse than the loose ones: near the flat position ``1/s`` of the losing singular value
    turned rounding and RK-stage drift into kicks of the accelerations and projections;
    the damped solve there keeps them bounded.)"""
    model, qd0 = fourbar
    opts, acc = FOLLOWING[case]
    q0, qd = perturbed_start(model, qd0, seed)
    res = md.forward(model, TS, q0=q0, qd0=qd, **opts)
    assert tip_error(res, 2) <= acc


@pytest.mark.parametrize("first_step", FIRST_STEPS)
@pytest.mark.parametrize("case", ["tsit5-tight", "dopri8-tight", "partitioning"])
def test_adaptive_methods_follow_the_branch_whatever_the_first_step(fourbar, case, first_step):
    """The same from the unperturbed start with first steps from 1e-7 s to 2e-2 s: another
    first step is another grid of steps, which lands elsewhere near the flat positions."""
    model, qd0 = fourbar
    opts, acc = FOLLOWING[case]
    res = md.forward(model, TS, qd0=qd0, first_step=first_step, **opts)
    assert tip_error(res, 2) <= acc


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize(
    ("opts", "acc"),
    [
        (dict(method="generalized-alpha", dt=2e-3), 2e-3),
        (dict(method="generalized-alpha", dt=2.5e-4, rho_inf=0.95), 1e-4),
        (dict(method="baumgarte", dt=1e-2), 1e-3),
    ],
    ids=["gen-alpha-2ms", "gen-alpha-0.25ms", "baumgarte-10ms"],
)
def test_fixed_step_methods_follow_the_branch_from_perturbed_starts(fourbar, opts, acc, seed):
    """Fixed-step methods from three perturbed starts: generalized-alpha at dt = 2 ms (which
    used to end 2 m off, on the other branch) and 0.25 ms, RK4 + Baumgarte at 10 ms."""
    model, qd0 = fourbar
    q0, qd = perturbed_start(model, qd0, seed)
    res = md.forward(model, TS, q0=q0, qd0=qd, **opts)
    assert tip_error(res, 2) <= acc


def test_branch_jump_is_caught_by_the_energy_balance(fourbar):
    """A run made to leave its branch on purpose: the velocities of the start are those of the
    parallelogram, but its first step is so large (dt = 0.4 s, RK4 + Baumgarte) that the
    motion is garbage; the run must not end quietly: the energy balance names the failure and
    its time. With ``energy_tol=None`` the same run returns (the check is what stops it)."""
    model, qd0 = fourbar
    with pytest.raises(md.EnergyBalanceError) as err:
        md.forward(model, TS, qd0=qd0, method="baumgarte", dt=0.1)
    assert err.value.time is not None and 0 < err.value.time <= 2.0
    res = md.forward(model, TS, qd0=qd0, method="baumgarte", dt=0.1, energy_tol=None)
    assert res.stats["energy_balance_error"] > 1e-4
    assert tip_error(res, 2) > 1e-3  # what the check kept from being returned


def test_energy_balance_of_a_good_run_is_reported(fourbar):
    """A run on its branch reports its energy balance error (relative to its energy scale)
    in ``stats``, far below the tolerance: T + V - E0 - W is conserved to the tolerances."""
    model, qd0 = fourbar
    res = md.forward(model, TS, qd0=qd0, rtol=1e-10, atol=1e-10)
    assert res.stats["energy_balance_error"] <= 1e-8
    balance = res["energy.total"] - res["energy.total"][0] - res["work.nonconservative"]
    assert np.max(np.abs(balance - res["work.constraints"])) <= 1e-8 * np.ptp(
        res["energy.potential"]
    )


# ------------------------------------------------------------------ the whole study (slow)
#: Every integrator at tolerances or steps a user may pick (the IFToMM benchmark's
#: high-precision tolerance, 1e-3 m, is the accuracy a run on its branch must keep).
STUDY = {
    "tsit5-default": dict(),
    "tsit5-1e-11": dict(rtol=1e-11, atol=1e-11),
    "dopri8-1e-9": dict(solver="dopri8", rtol=1e-9, atol=1e-9),
    "dopri8-1e-11": dict(solver="dopri8", rtol=1e-11, atol=1e-11),
    "partitioning": dict(method="partitioning"),
    "baumgarte-1ms": dict(method="baumgarte", dt=1e-3),
    "gen-alpha-1ms": dict(method="generalized-alpha", dt=1e-3),
}


#: Step limit of the adaptive runs: a run that stalls on another CPU ends with a named error
#: in minutes instead of running to the default million steps.
STUDY_MAX_STEPS = 25_000

#: (N, case) pairs: every case at N = 5; at N = 40 all but Dopri8 at 1e-11 (two minutes here).
STUDY_CASES = [(5, c) for c in STUDY] + [(40, c) for c in STUDY if c != "dopri8-1e-11"]


@pytest.mark.slow
@pytest.mark.parametrize(("n", "case"), STUDY_CASES)
def test_nfourbar_study_over_20s(n, case):
    """The N-four-bar (N = 5: 33 coordinates, dense path; N = 40: 243 coordinates, sparse
    path) over the benchmark's 20 s (about twenty flat positions), from a start perturbed at
    1e-13: each run follows the exact reduction within 1e-3 m or fails with a named numerical
    error, never returns another branch; the default method must follow it."""
    model, qd0 = double_four_bar(n)
    q0, qd = perturbed_start(model, qd0, seed=7)
    ts = np.linspace(0.0, 20.0, 201)
    opts = dict(STUDY[case])
    if "dt" not in opts:  # adaptive: a bounded run (4-5 thousand steps here, N = 40, Tsit5 1e-11)
        opts.setdefault("max_steps", STUDY_MAX_STEPS)
    try:
        res = md.forward(model, ts, q0=q0, qd0=qd, **opts)
    except md.NumericalError as err:
        assert case != "tsit5-default", err
        assert err.time is not None
        return
    assert tip_error(res, n) <= 1e-3
