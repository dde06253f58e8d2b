"""Four-bar function generation (mixdyn.synthesis.FunctionTask) against Freudenstein's
closed form: at three precision points with the angles measured from the ground link, the
link ratios follow from a 3x3 linear solve of Freudenstein's equation
``K1 cos theta4 - K2 cos theta2 + K3 = cos(theta2 - theta4)``, ``K1 = d/a``, ``K2 = d/c``,
``K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c)`` (Freudenstein 1955; Norton, Design of Machinery,
section 5). The case: y = log10(x) over [1, 2], three Chebyshev points, the crank from 0
through 60 deg, the rocker from 240 deg through -60 deg."""

import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import FourBar, FunctionCandidate, FunctionTask, chebyshev


def _task(**options) -> FunctionTask:
    return FunctionTask.from_function(
        np.log10,
        (1.0, 2.0),
        np.deg2rad(60.0),
        np.deg2rad(-60.0),
        output_start=np.deg2rad(240.0),
        **options,
    )


def freudenstein(theta2, theta4, d=1.0):
    """Crank a, coupler b, rocker c of ground d through three (theta2, theta4) pairs."""
    k1, k2, k3 = np.linalg.solve(
        np.column_stack([np.cos(theta4), -np.cos(theta2), np.ones(3)]), np.cos(theta2 - theta4)
    )
    a, c = d / k1, d / k2
    return a, np.sqrt(a * a + c * c + d * d - 2 * a * c * k3), c


def test_chebyshev_points_and_the_task():
    x = chebyshev(1.0, 2.0, 3)
    np.testing.assert_allclose(x, [1.5 - np.sqrt(3) / 4, 1.5, 1.5 + np.sqrt(3) / 4], rtol=1e-15)
    task = _task()
    np.testing.assert_allclose(task.inputs, np.deg2rad(60.0) * (x - 1.0), rtol=1e-15)
    y = np.log10(x) / np.log10(2.0)
    np.testing.assert_allclose(task.outputs, np.deg2rad(240.0 - 60.0 * y), rtol=1e-15)


def test_the_closed_form_linkage_generates_the_pairs():
    """The four-bar of Freudenstein's solve, assembled by mixdyn's dyad (the search's own
    kinematics, on the branch where its pin lies), passes the three pairs to 1e-12: the
    search's angles are Freudenstein's."""
    task = _task()
    a, b, c = freudenstein(task.inputs, task.outputs)
    assert min(a, b, c) > 0
    gaps = []
    for branch in (1.0, -1.0):
        fb = FourBar(*np.array([1.0, a, b, c, 0, 0, 0, 0, 0]), np.float64(branch))
        out = FunctionCandidate(fb, 0.0, 0.0, 0.0, 0.0).output(task.inputs, task.outputs[0])
        gaps.append(np.max(np.abs(out - task.outputs)))
    assert min(gaps) < 1e-12 and max(gaps) > 1e-3  # one branch passes them, not the other


def test_bad_function_tasks_are_named():
    with pytest.raises(ModelError, match="increase"):
        FunctionTask([0.0, 0.5, 0.4], [0.0, 0.1, 0.2])
    with pytest.raises(ModelError, match="as many"):
        FunctionTask([0.0, 0.5, 0.7], [0.0, 0.1])
    with pytest.raises(ModelError, match="different"):
        FunctionTask.from_function(np.cos, (-1.0, 1.0), 1.0, 1.0)
    with pytest.raises(ModelError, match="objective"):
        md.synthesize(_task(), md.synthesis.Objective())


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_synthesis_finds_freudensteins_linkage():
    """The batched Levenberg-Marquardt search from random ratios finds the closed form's
    four-bar: its ratios to 1e-9 and its output angles at the three points to 1e-9; the
    search given as a SearchSettings value finds the same."""
    task = _task()
    out = md.synthesize(task, starts=64, seed=0)
    best = out.best
    # the same search as one value: the same outcome, bit for bit
    again = md.synthesize(task, search=md.synthesis.SearchSettings(starts=64, seed=0)).best
    assert again.error == best.error and float(again.linkage.r3) == float(best.linkage.r3)
    a, b, c = freudenstein(task.inputs, task.outputs)
    found = [float(best.linkage.r2), float(best.linkage.r3), float(best.linkage.r4)]
    np.testing.assert_allclose(found, [a, b, c], rtol=1e-9)
    np.testing.assert_allclose(best.output(task.inputs, task.outputs[0]), task.outputs, atol=1e-9)
    assert best.error < 1e-18


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_free_start_angles_are_found():
    """Five pairs of a known four-bar counted from its own start angles (only differences
    given): the search finds its ratios and its start angles."""
    fb = FourBar(*np.array([1.0, 0.45, 0.9, 0.7, 0, 0, 0, 0, 0]), np.float64(1.0))
    theta = np.linspace(0.5, 2.0, 5)
    rocker = FunctionCandidate(fb, 0.0, 0.0, 0.0, 0.0).output(theta)
    task = FunctionTask(theta - theta[0], rocker - rocker[0], free_start=True)
    best = md.synthesize(task, starts=256, seed=0).best
    found = [float(best.linkage.r2), float(best.linkage.r3), float(best.linkage.r4)]
    np.testing.assert_allclose(found, [0.45, 0.9, 0.7], rtol=1e-8)
    assert best.input_start == pytest.approx(theta[0], abs=1e-8)
    assert np.angle(np.exp(1j * (best.output_start - rocker[0]))) == pytest.approx(0, abs=1e-8)
