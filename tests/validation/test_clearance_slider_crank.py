"""Flores' slider-crank with a revolute clearance joint (the parameters in
``tests/data/flores_clearance_slider_crank.txt``: Flores, Ambrosio, Claro and Lankarani,
Proc. IMechE K 220 (2006) 21-34): the crank driven at 5000 rpm, its torque sought (a mixed
run), the pin between the rod and the slider a journal in a bearing.

Truths:

- The journal stays within ``c + delta`` of the bearing's centre, so the slider's position
  departs from the ideal joint's by at most ``sqrt(1 + tan(beta)**2) (c + delta_max)`` (its
  own offset along the guide and the rod's turn across it, ``tan(beta) <= r / sqrt(l**2 -
  r**2)``): as the clearance tends to zero the motion tends to the ideal joint's.
- The published behaviour: free flight, impacts and continuous contact in one turn, told
  apart by the contacts' durations, and a driving torque and a slider acceleration whose
  spikes exceed the ideal joint's.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

import mixdyn as md
from fixtures.paths import DATA, EXAMPLES

pytestmark = pytest.mark.slow  # long: run by CI's slow set


def reference() -> dict[str, float]:
    """The numbers of the reference file: ``name value`` lines and the bodies' table."""
    out = {}
    for line in (DATA / "flores_clearance_slider_crank.txt").read_text().splitlines():
        words = line.split("#")[0].split()
        if len(words) >= 2 and words[0] in ("crank", "rod", "slider"):
            length = math.nan if words[1] == "-" else float(words[1])
            out |= {f"{words[0]}.length": length, f"{words[0]}.mass": float(words[2]),
                    f"{words[0]}.inertia": float(words[3])}  # fmt: skip
        elif len(words) >= 2:
            with contextlib.suppress(ValueError):  # words: the law, the stiffness's formula
                out[words[0]] = float(words[1])
    return out


REF = reference()
L1, L2 = REF["crank.length"], REF["rod.length"]
OMEGA = 5000 * 2 * math.pi / 60  # the reference's crank speed [rad/s]
TS = np.linspace(0.0, 2 * math.pi / OMEGA, 241)  # one turn


def slider_crank(clearance: float | None) -> md.Model:
    contact = (
        {}
        if clearance is None
        else dict(
            clearance=clearance,
            journal_radius=REF["journal_radius"],
            young_modulus=REF["young_modulus"],
            poisson=REF["poisson"],
            restitution=REF["restitution"],
            impact_speed=0.5,
        )
    )
    bodies = [
        md.Body("crank", REF["crank.mass"], REF["crank.inertia"], q0=(L1 / 2, 0.0, 0.0),
                points={"O": (-L1 / 2, 0.0), "A": (L1 / 2, 0.0)}),
        md.Body("rod", REF["rod.mass"], REF["rod.inertia"], q0=(L1 + L2 / 2, 0.0, 0.0),
                points={"A": (-L2 / 2, 0.0), "B": (L2 / 2, 0.0)}),
        md.Body("slider", REF["slider.mass"], REF["slider.inertia"], q0=(L1 + L2, 0.0, 0.0)),
    ]  # fmt: skip
    joints = [
        md.Revolute("O", "ground", "crank.O"),
        md.Revolute("A", "crank.A", "rod.A"),
        md.Revolute("B", "rod.B", "slider", **contact),
        md.Translational("slide", "ground", "slider"),
    ]
    return md.Model(bodies, joints, forces=[md.Torque("motor", "crank")], gravity=(0.0, -9.81))


def run(clearance):
    drive = md.CoordinateDriver("drive", "crank", "phi", law=md.Polynomial([0.0, OMEGA]))
    return md.mixed(
        slider_crank(clearance), TS, prescribed=[drive], unknown=["motor"], rtol=1e-7, atol=1e-9
    )


@pytest.fixture(scope="module")
def runs():
    return {c: run(c) for c in (None, 5e-4, 1e-4)}


def test_the_reference_numbers_are_read():
    assert (L1, L2, REF["clearance"], REF["restitution"]) == (0.05, 0.12, 5e-4, 0.9)
    assert REF["bearing_radius"] - REF["journal_radius"] == pytest.approx(REF["clearance"])


def test_as_the_clearance_shrinks_the_motion_tends_to_the_ideal_joints(runs):
    ideal = runs[None]["slider.x"]
    tan_beta = L1 / math.sqrt(L2**2 - L1**2)
    errors = {}
    for c in (5e-4, 1e-4):
        r = runs[c]
        reach = c + max(float(np.max(r["B.penetration"])), 0.0)
        errors[c] = float(np.max(np.abs(r["slider.x"] - ideal)))
        assert errors[c] <= math.sqrt(1 + tan_beta**2) * reach * 1.01, c
    assert errors[1e-4] < 0.4 * errors[5e-4]


def _contact_intervals(touching) -> list[int]:
    """The lengths [samples] of the runs of consecutive samples in contact."""
    edges = np.flatnonzero(np.diff(np.r_[0, touching.astype(int), 0]))
    return list(np.diff(edges)[::2])


def test_free_flight_impacts_and_contact_and_the_torques_spikes(runs):
    """One turn with 0.5 mm: the journal flies (gap), impacts and rides the bearing: contacts
    of one or two samples (50 us each) apart, impacts with flight between, and contacts of a
    millisecond or more (20 samples), continuous contact; the motor torque's peak and the
    slider acceleration's exceed the ideal joint's (the impacts' spikes: 1.5 and 5 times),
    and the contact force's peak exceeds the steady inertial load of the slider
    ``m r omega**2``."""
    r = runs[5e-4]
    pen, F = r["B.penetration"], r["B.normal"]
    first = np.argmax(F > 0)
    assert first > 0 and np.any(pen[first:] < 0) and np.sum(F > 0) > 20
    lengths = _contact_intervals(F > 0)
    assert sum(n <= 2 for n in lengths) >= 3 and max(lengths) >= 20, lengths
    ideal_ax = runs[None]["slider.ax"]
    assert np.max(np.abs(r["slider.ax"])) > 5 * np.max(np.abs(ideal_ax))
    # the journal's orbit: its distance from the bearing's centre is the clearance plus
    # the penetration, and its direction in the rod's frame turns with the load
    orbit = np.hypot(r["B.ex"], r["B.ey"])
    np.testing.assert_allclose(orbit, pen + 5e-4, rtol=1e-12, atol=1e-15)
    assert np.ptp(np.arctan2(r["B.ey"], r["B.ex"])[first:]) > 3.0
    ideal = runs[None]["motor"]
    assert np.max(np.abs(r["motor"])) > 1.5 * np.max(np.abs(ideal))
    assert np.max(F) > 5 * REF["slider.mass"] * L1 * OMEGA**2


def with_guide_clearance(clearance: float) -> md.Model:
    """The ideal slider-crank but for a gap in the slider's guide (a slider 50 mm long with
    5 mm corners: numbers of this test, not the paper's)."""
    ideal = slider_crank(None)
    slide = md.Translational(
        "slide", "ground", "slider", clearance=clearance, slider_length=0.05,
        corner_radius=0.005, young_modulus=REF["young_modulus"], restitution=0.9,
        impact_speed=0.5,
    )  # fmt: skip
    return ideal.replace(joints=(*ideal.joints[:3], slide))


def test_a_gap_in_the_guide_tends_to_the_ideal_slide(runs):
    """A translational joint with clearance: the slider's centre stays within ``c +
    delta_max`` of the guide's line (it lies between its ends), its position along the guide
    departs from the ideal joint's less as the gap shrinks (0.5 mm -> 0.1 mm)."""
    drive = md.CoordinateDriver("drive", "crank", "phi", law=md.Polynomial([0.0, OMEGA]))
    ideal = runs[None]["slider.x"]
    errors = {}
    for c in (5e-4, 1e-4):
        r = md.mixed(with_guide_clearance(c), TS, prescribed=[drive], unknown=["motor"],
                     rtol=1e-7, atol=1e-9)  # fmt: skip
        reach = c + max(float(np.max(r["slide.penetration"])), 0.0)
        assert np.max(np.abs(r["slider.y"])) <= reach * (1 + 1e-9)
        assert np.max(r["slide.normal"]) > 0  # it touched
        errors[c] = float(np.max(np.abs(r["slider.x"] - ideal)))
    assert errors[1e-4] < 0.5 * errors[5e-4]


def test_a_sweep_over_the_clearance_is_its_single_runs(runs):
    """``md.sweep`` over ``B.clearance`` (compiled once): the member at 0.5 mm is the single
    run (<= 1e-9 m), and every member's slider stays within its clearance's reach of the
    ideal joint's (as above)."""
    drive = md.CoordinateDriver("drive", "crank", "phi", law=md.Polynomial([0.0, OMEGA]))
    sizes = [5e-4, 2.5e-4, 1e-4]
    sw = md.sweep(
        slider_crank(5e-4),
        TS,
        vary={"B.clearance": sizes},
        analysis=md.analyses.Mixed(
            prescribed=[drive], unknown=["motor"], method=md.Projection(rtol=1e-7, atol=1e-9)
        ),
    )
    np.testing.assert_allclose(sw.results[0]["slider.x"], runs[5e-4]["slider.x"], atol=1e-9)
    tan_beta = L1 / math.sqrt(L2**2 - L1**2)
    for c, r in zip(sizes, sw.results, strict=True):
        reach = c + max(float(np.max(r["B.penetration"])), 0.0)
        error = np.max(np.abs(r["slider.x"] - runs[None]["slider.x"]))
        assert error <= math.sqrt(1 + tan_beta**2) * reach * 1.01, c


def test_the_clearance_sweep_example_runs_and_its_member_is_the_single_run(tmp_path):
    """``mixdyn run examples/clearance_sweep.yaml``: five members, 0.1 to 0.5 mm, every one
    ok; the member at 0.5 mm is the file's single run (``one_turn``): its peak contact force
    and peak motor torque equal those of the single run's columns (1e-9 relative), and every
    member's peak force exceeds the slider's steady inertial load ``m r omega**2``."""
    import pandas as pd
    from typer.testing import CliRunner

    from mixdyn.cli import app

    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(EXAMPLES / "clearance_sweep.yaml"), "--out",
                                   str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    members = pd.read_csv(out / "sweep" / "members.csv")
    np.testing.assert_allclose(members["c [m]"], np.linspace(1e-4, 5e-4, 5), rtol=1e-12)
    assert list(members["status"]) == ["ok"] * 5
    single = pd.read_csv(out / "one_turn" / "results.csv")
    last = members.iloc[-1]
    np.testing.assert_allclose(last["F_peak [N]"], single["B.normal [N]"].max(), rtol=1e-9)
    np.testing.assert_allclose(
        last["torque_peak [N·m]"], single["motor [N·m]"].abs().max(), rtol=1e-9
    )
    assert np.all(members["F_peak [N]"] > REF["slider.mass"] * L1 * OMEGA**2)
