"""Four-bar motion generation (mixdyn.synthesis.MotionTask) against Burmester's construction
for three poses: any point ``a`` of the moving body is a circle point, its three positions
``P_i + R(alpha_i) a`` lie on a circle whose centre (the circumcentre, the centre point) is a
ground pivot, so two circle points and their centre points make a four-bar that carries the
body through the three poses exactly (Burmester 1888; Sandor and Erdman, Advanced Mechanism
Design, section 3.4). The construction is plain NumPy here, independent of mixdyn's
assembly."""

import numpy as np
import pytest

import mixdyn as md
from mixdyn.errors import ModelError
from mixdyn.synthesis import FourBar, MotionTask

#: Three poses of the moving body: its reference point [m] and angle [rad].
POSES = np.array([[0.0, 0.0, 0.0], [0.3, 0.25, np.deg2rad(40.0)], [0.45, 0.6, np.deg2rad(85.0)]])

#: Pairs of circle points (the crank pin's, the rocker pin's) in the body's frame [m].
CIRCLE_POINTS = [((-0.4, 0.4), (0.2, 0.35)), ((0.4, -0.25), (-0.35, 0.15))]


def _rot(a: float) -> np.ndarray:
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def _circumcentre(p: np.ndarray) -> np.ndarray:
    """The centre of the circle through the three points ``p`` (3, 2): equidistant from
    them, the 2x2 linear system of the two perpendicular bisectors."""
    a = 2.0 * (p[1:] - p[0])
    b = np.sum(p[1:] ** 2, axis=1) - np.sum(p[0] ** 2)
    return np.linalg.solve(a, b)


def burmester(a, b, poses=POSES):
    """The four-bar of circle points ``a`` (crank pin) and ``b`` (rocker pin) in the body's
    frame: ``(numbers in the order of NAMES, assembly side at each pose (3,), crank angles
    (3,) [rad], the body's line's angle in the coupler's frame [rad])``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    pa = np.array([p[:2] + _rot(p[2]) @ a for p in poses])
    pb = np.array([p[:2] + _rot(p[2]) @ b for p in poses])
    o2, o4 = _circumcentre(pa), _circumcentre(pb)
    ground = o4 - o2
    theta0 = np.arctan2(ground[1], ground[0])
    line = b - a  # the coupler's line A -> B, in the body's frame
    beta = np.arctan2(line[1], line[0])
    rc = _rot(-beta) @ (-a)  # the body's reference point in the coupler's frame
    numbers = [
        np.linalg.norm(ground),
        np.linalg.norm(pa[0] - o2),
        np.linalg.norm(line),
        np.linalg.norm(pb[0] - o4),
        rc[0],
        rc[1],
        o2[0],
        o2[1],
        theta0,
    ]
    theta = np.unwrap(np.arctan2(pa[:, 1] - o2[1], pa[:, 0] - o2[0]) - theta0)
    u, v = o4 - pa, pb - pa  # B on the left (+1) or right (-1) of A -> O4
    side = np.sign(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    return np.array(numbers), side, theta, -beta


@pytest.mark.parametrize("a, b", CIRCLE_POINTS)
def test_burmesters_four_bar_has_no_pose_error(a, b):
    """The constructed four-bar, assembled by mixdyn's closed form on its branch, carries the
    body through the poses: MotionTask's error <= 1e-9 (it is ~1e-31). Moving one pose's
    point by eps adds eps^2; turning one pose by delta adds L^2 * (2/3) delta^2 (the
    least-squares offset spreads it: -delta/3, 2 delta/3, -delta/3)."""
    numbers, side, theta, _ = burmester(a, b)
    assert abs(side.sum()) == 3  # one assembly branch through the three poses
    fb = FourBar(*numbers, np.float64(side[0]))
    task = MotionTask(POSES)
    assert task.error(fb, theta) <= 1e-9
    eps, delta = 1e-3, 1e-3
    moved = POSES + np.array([[0, 0, 0], [eps, 0, 0], [0, 0, 0]])
    assert MotionTask(moved).error(fb, theta) == pytest.approx(eps**2, rel=1e-6)
    turned = POSES + np.array([[0, 0, 0], [0, 0, delta], [0, 0, 0]])
    task = MotionTask(turned)
    expected = task.weight_length**2 * (2 / 3) * delta**2
    assert task.error(fb, theta) == pytest.approx(expected, rel=1e-6)
    assert MotionTask(turned, length=2.0).error(fb, theta) == pytest.approx(
        4.0 * (2 / 3) * delta**2, rel=1e-6
    )


def test_the_size_is_the_poses_spread():
    task = MotionTask(POSES)
    centre = POSES[:, :2].mean(axis=0)
    spread = np.max(np.linalg.norm(POSES[:, :2] - centre, axis=1))
    assert task.weight_length == pytest.approx(spread, rel=1e-15)
    assert task.timing is None and task.box().shape == (9, 2)


@pytest.mark.parametrize(
    "poses, options, words",
    [
        (POSES[:2], {}, "three or more"),
        (POSES[:, :2], {}, "three or more"),
        (np.where(np.eye(3, dtype=bool), np.nan, POSES), {}, "finite"),
        (np.tile([1.0, 2.0, 0.0], (3, 1)) + [0, 0, 0.1] * np.arange(3)[:, None], {}, "coincide"),
        (POSES, {"length": -1.0}, "length"),
        (POSES, {"bounds": {"r9": (1, 2)}}, "r9"),
        (POSES, {"min_transmission": 2.0}, "pi/2"),
    ],
)
def test_bad_motion_tasks_are_named(poses, options, words):
    with pytest.raises(ModelError, match=words):
        MotionTask(poses, **options)


@pytest.mark.slow  # long: run by CI's slow set (the search and the written model compile)
@pytest.mark.parametrize("linkage, body", [("four_bar", "coupler"), ("slider_crank", "rod")])
def test_a_search_reaches_the_poses_and_its_model_file_passes_them(linkage, body, tmp_path):
    """From random starts the batched Levenberg-Marquardt search reaches error <= 1e-8 on the
    three poses, in order of the crank angle; its best linkage, written as a model file and
    assembled by md.kinematic (Newton's assembly of the written model: a second method),
    puts the coupler's P on the poses' points and its angle on theirs (a slider-crank's
    coupler: the connecting rod)."""
    out = md.synthesize(MotionTask(POSES, linkage=linkage), starts=64, seed=0, chunk=64)
    best = out.best
    assert best.error <= 1e-8
    assert np.all(np.diff(best.angles) >= 0) and best.angles[-1] - best.angles[0] <= 2 * np.pi
    assert out.task.error(best.fourbar, best.angles) == pytest.approx(best.error, abs=1e-20)
    path = tmp_path / "best.yaml"
    out.write(path)
    loaded = md.load(path)
    t = (best.angles - best.angles[0]) / out.objective.speed
    run = md.kinematic(loaded.model, t)
    p, _, _ = run.point(f"{body}.P")
    np.testing.assert_allclose(p, POSES[:, :2], atol=1e-7)
    turn = np.angle(np.exp(1j * (np.asarray(run[f"{body}.phi"]) - POSES[:, 2])))
    assert np.max(np.abs(turn)) < 1e-7
