"""Function generation by slider-cranks and six-bars (mixdyn.synthesis.FunctionTask with
``linkage=``): the output a search follows against independent truths.

* A slider-crank's slider position along its slide, from the point ``P0`` of the slide
  nearest the crank's pivot, is the offset slider-crank's closed form ``s(theta2) = r2 cos
  theta2 + sqrt(r3^2 - (e - r2 sin theta2)^2)`` (the rod's length from the crank pin to the
  slider's pin at height ``e``; Norton, Design of Machinery, section 4.6), written here.
* A Watt II's and a Stephenson III's follower angle (the link pivoted at the third ground
  pivot ``O6``) is found here by two circle intersections in plain NumPy: the coupler's pin
  ``B`` from the crank pin ``A`` and the rocker's pivot ``O4``, then the follower's pin ``E``
  from the dyad's start ``D`` (on the rocker, a Watt II; on the coupler, a Stephenson III)
  and ``O6``.

The searches run from random starts; their best linkages' outputs at the inputs, and the
kinematic runs of their written model files (Newton's assembly of the model, not the
search's closed forms), are compared with those truths.
"""

import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import (
    FUNCTION_LINKAGES,
    FunctionCandidate,
    FunctionTask,
    SliderCrank,
    StephensonIII,
    WattII,
)

#: A known offset slider-crank [m]: crank, rod, offset.
SLIDER = (0.04, 0.15, 0.02)
#: The crank's angles of the slider-crank's pairs [rad].
SLIDER_INPUTS = np.linspace(0.3, 2.2, 6)

#: Known six-bars (ground link 1): r2..r6, dx, dy, gx, gy and the branch code b4 + 2 b6.
SIX_BARS = {
    "watt2": ((0.35, 1.1, 0.8, 0.9, 0.7, 0.6, 0.3, 1.4, 0.8), 3.0),
    "stephenson3": ((0.35, 1.1, 0.8, 0.9, 0.7, 0.5, 0.4, 0.6, 1.3), 3.0),
}
SIX_INPUTS = np.linspace(0.4, 1.6, 6)


def slider_position(theta, r2, r3, e):
    """The slider's position [m] from ``P0``, the slider ahead of the crank pin."""
    theta = np.asarray(theta, dtype=float)
    return r2 * np.cos(theta) + np.sqrt(r3**2 - (e - r2 * np.sin(theta)) ** 2)


def _circles(p, q, rp, rq, side):
    """The point at ``rp`` from ``p`` and ``rq`` from ``q``, left of ``p -> q`` (side +1) or
    right of it (-1)."""
    d = q - p
    dist = np.hypot(*d)
    u = d / dist
    along = (rp**2 - rq**2 + dist**2) / (2 * dist)
    h = np.sqrt(rp**2 - along**2)
    return p + along * u + side * h * np.array([-u[1], u[0]])


def follower_angle(kind, numbers, code, theta):
    """A six-bar's follower angle ``O6 -> E`` [rad] at the crank's angles ``theta`` (ground
    link 1 along x from the crank's pivot at the origin)."""
    r2, r3, r4, r5, r6, dx, dy, gx, gy = numbers
    b6 = 1.0 if code > 0 else -1.0
    b4 = code - 2 * b6
    o4, o6 = np.array([1.0, 0.0]), np.array([gx, gy])
    out = []
    for t in np.asarray(theta, dtype=float):
        a = r2 * np.array([np.cos(t), np.sin(t)])
        b = _circles(a, o4, r3, r4, b4)
        origin, line = (o4, b - o4) if kind == "watt2" else (a, b - a)
        c, s = line / np.hypot(*line)
        d = origin + np.array([c * dx - s * dy, s * dx + c * dy])
        e = _circles(d, o6, r5, r6, b6)
        out.append(np.arctan2(e[1] - o6[1], e[0] - o6[0]))
    return np.unwrap(np.array(out))


def _six_bar(kind, numbers, code):
    r = (1.0, *numbers[:5])
    rest = (*numbers[5:], 0.0, 0.0, 0.0, 0.0, 0.0)
    return FUNCTION_LINKAGES[kind](*np.array((*r, *rest)), np.float64(code))


def test_the_outputs_are_the_closed_forms():
    """A slider-crank's output is the closed form's slider position; a Watt II's and a
    Stephenson III's the follower angle of the two circle intersections (1e-12)."""
    r2, r3, e = SLIDER
    sc = SliderCrank(*np.array([r2, r3, e, 0, 0, 0, 0, 0]), np.float64(1.0))
    candidate = FunctionCandidate(sc, 0.0, 0.0, 0.0, 0.0)
    assert candidate.fourbar is candidate.linkage is sc  # the field's other name
    got = candidate.output(SLIDER_INPUTS)
    np.testing.assert_allclose(got, slider_position(SLIDER_INPUTS, *SLIDER), atol=1e-15)
    assert SliderCrank.OUTPUT == "length" and WattII.OUTPUT == StephensonIII.OUTPUT == "angle"
    for kind, (numbers, code) in SIX_BARS.items():
        want = follower_angle(kind, numbers, code, SIX_INPUTS)
        got = FunctionCandidate(_six_bar(kind, numbers, code), 0.0, 0.0, 0.0, 0.0)
        np.testing.assert_allclose(got.output(SIX_INPUTS, want[0]), want, atol=1e-12)


def test_linkages_without_a_grounded_output_are_refused():
    """A Watt I and a Stephenson I (the follower on the rocker), an unknown name, a six-bar's
    Grashof type and a slider's positions all alike are refused, saying why."""
    pairs = (SIX_INPUTS, np.linspace(0.0, 0.5, 6))
    for kind in ("watt1", "stephenson1"):
        with pytest.raises(ModelError, match="only grounded output is the rocker") as e:
            FunctionTask(*pairs, linkage=kind)
        assert "'four_bar'" in str(e.value) and e.value.element == "linkage"
    with pytest.raises(ModelError, match="four_bar, slider_crank, stephenson3, watt2"):
        FunctionTask(*pairs, linkage="crank_slider")
    with pytest.raises(ModelError, match="Grashof type is a four-bar's or a slider-crank's"):
        FunctionTask(*pairs, linkage="watt2", grashof="crank_rocker")
    with pytest.raises(ModelError, match="different"):
        FunctionTask(SIX_INPUTS, np.full(6, 0.1), linkage="slider_crank")
    task = FunctionTask(*pairs, linkage="slider_crank", grashof="crank_rocker")
    assert task.linkage is SliderCrank and task.scale == pytest.approx(0.5, rel=1e-15)


@pytest.mark.slow  # long: run by CI's slow set (the search and the model's run compile)
def test_a_slider_crank_is_found_and_its_model_file_runs(tmp_path):
    """Six positions of a known offset slider-crank: the search (32 starts) finds it (error
    below 1e-10 span^2), its outputs pass the targets, and its model file, loaded and run by
    md.kinematic, moves the slider as the closed form of the found numbers."""
    targets = slider_position(SLIDER_INPUTS, *SLIDER)
    span = np.ptp(targets)
    task = FunctionTask(SLIDER_INPUTS, targets, linkage="slider_crank")
    out = md.synthesize(task, starts=32, seed=0)
    best = out.best
    assert best.error < 1e-10 * span**2
    np.testing.assert_allclose(best.output(SLIDER_INPUTS), targets, atol=1e-8 * span)
    found = [float(getattr(best.linkage, n)) for n in ("r2", "r3", "e")]
    np.testing.assert_allclose(found, SLIDER, rtol=1e-6)
    assert list(out.table().columns[:3]) == ["r2", "r3", "e"]
    path = tmp_path / "best.yaml"
    out.write(path)
    model = md.load(path).model
    theta = np.linspace(SLIDER_INPUTS[0], SLIDER_INPUTS[-1], 25)
    run = md.kinematic(model, theta - theta[0])  # the crank from the first input at 1 rad/s
    np.testing.assert_allclose(run["crank.phi"], theta, atol=1e-12)
    np.testing.assert_allclose(run["slider.x"], slider_position(theta, *found), atol=1e-9 * span)


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_a_slider_cranks_free_start_is_found():
    """The same positions counted from the first input and the first position (only their
    differences given): the search finds the slider-crank and both starts."""
    targets = slider_position(SLIDER_INPUTS, *SLIDER)
    task = FunctionTask(
        SLIDER_INPUTS - SLIDER_INPUTS[0],
        targets - targets[0],
        linkage="slider_crank",
        free_start=True,
    )
    best = md.synthesize(task, starts=64, seed=0).best
    assert best.error < 1e-10 * np.ptp(targets) ** 2
    found = [float(getattr(best.linkage, n)) for n in ("r2", "r3", "e")]
    np.testing.assert_allclose(found, SLIDER, rtol=1e-6)
    assert best.input_start == pytest.approx(SLIDER_INPUTS[0], abs=1e-7)
    assert best.output_start == pytest.approx(targets[0], abs=1e-8)


@pytest.mark.slow  # long: run by CI's slow set (the search and the model's run compile)
@pytest.mark.parametrize("kind", ["watt2", "stephenson3"])
def test_a_six_bar_generates_its_follower_angles_and_its_model_runs(kind):
    """Six follower angles of a known six-bar (the circle intersections above): the search
    (64 starts) reaches an error below 1e-16 rad^2; the best candidate's model, run by
    md.kinematic, turns the follower through the targets."""
    numbers, code = SIX_BARS[kind]
    targets = follower_angle(kind, numbers, code, SIX_INPUTS)
    task = FunctionTask(SIX_INPUTS, targets, linkage=kind)
    out = md.synthesize(task, starts=64, seed=0, max_steps=1000)
    best = out.best
    assert type(best.linkage) is FUNCTION_LINKAGES[kind] and best.error < 1e-16
    assert list(out.table().columns[:9]) == [
        *(f"r{k}" for k in range(2, 7)),
        "dx",
        "dy",
        "gx",
        "gy",
    ]
    run = md.kinematic(out.model(), SIX_INPUTS - SIX_INPUTS[0])
    gap = np.angle(np.exp(1j * (run["follower.phi"] - targets)))
    assert np.max(np.abs(gap)) < 1e-8
    text = out.model_file()
    assert "follower.phi" in text and "rad^2" in text
