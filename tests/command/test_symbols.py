"""Force elements drawn: a spring's coil between its two attachment points, a damper, a
torque's arc turning the torque's way, a point force's arrow along the force with a length in
proportion to it, and names placed without covering each other."""

import math

import numpy as np
import pytest

import mixdyn as md
from fixtures import paper_mechanism, spring_slider
from mixdyn.viz.labels import place
from mixdyn.viz.scene import Scene
from mixdyn.viz.show import merge_labels
from mixdyn.viz.symbols import arc_arrow, coil, damper, symbols


def _pieces(path):
    """The polyline's pieces between NaN rows."""
    cut = np.flatnonzero(np.isnan(path[:, 0]))
    pieces = [p[~np.isnan(p[:, 0])] for p in np.split(path, cut)]
    return [p for p in pieces if len(p)]


def test_coil_runs_between_its_points_within_its_width():
    p0, p1 = np.array([[1.0, 2.0], [0.0, 0.0]]), np.array([[4.0, 6.0], [0.0, -2.0]])
    w = 0.1
    path = coil(p0, p1, w, turns=6)
    for k in range(2):
        np.testing.assert_allclose(path[k, 0], p0[k], atol=1e-12)
        np.testing.assert_allclose(path[k, -1], p1[k], atol=1e-12)
        d = p1[k] - p0[k]
        u = d / np.linalg.norm(d)
        rel = path[k] - p0[k]
        along = rel @ u
        across = rel[:, 0] * u[1] - rel[:, 1] * u[0]  # distance from the line p0-p1
        assert np.all(np.diff(along) >= -1e-12)  # it goes one way, from p0 to p1
        assert np.max(np.abs(across)) == pytest.approx(w)
        assert np.sum(np.diff(np.sign(across[np.abs(across) > 1e-9])) != 0) == 11  # 6 turns


def test_damper_spans_its_points():
    p0, p1 = np.array([[0.0, 0.0]]), np.array([[0.0, 3.0]])
    path = damper(p0, p1, 0.2)[0]
    pts = path[~np.isnan(path[:, 0])]
    assert pts[:, 1].min() == pytest.approx(0.0) and pts[:, 1].max() == pytest.approx(3.0)
    assert np.max(np.abs(pts[:, 0])) == pytest.approx(0.2)  # the cylinder's half-width
    assert len(_pieces(path)) == 4  # rod, piston plate, cylinder, rod


@pytest.mark.parametrize("turn", [2.0, -1.0])
def test_torque_arc_turns_the_torques_way(turn):
    path = arc_arrow(np.array([[5.0, 1.0]]), 0.5, np.array([turn]))[0]
    arc = _pieces(path)[0] - np.array([5.0, 1.0])
    np.testing.assert_allclose(np.hypot(*arc.T), 0.5)
    swept = np.sum(np.diff(np.unwrap(np.arctan2(arc[:, 1], arc[:, 0]))))
    assert swept == pytest.approx(turn)


def test_point_force_arrow_along_the_force_in_proportion():
    """The slider's force F1 along +x at the slider's centre: each instant's arrow points along
    the force (backwards where it is negative), its length in proportion to it, the largest a
    fifth of the scene; a force in the body's frame turns with the body."""
    force = md.PointForce("F1", "slider", along=(0.6, 0.8), law=1.0)
    push = md.PointForce("P", "crank.B", along=(1.0, 0.0), frame="body", law=1.0)
    model = paper_mechanism(forces=[force, push])
    q = np.tile(np.asarray(model.q0, dtype=float), (3, 1))
    q[:, 2] = [0.0, math.pi / 2, 1.0]  # the crank's angle
    F = np.array([2.0, -5.0, 0.0])
    P = np.array([1.0, 1.0, 1.0])
    span = 100.0
    drawn = {m["name"]: m for m in symbols(model, q, span, {"F1": F, "P": P})}
    at = q[:, 9:11]
    for k in range(2):
        shaft = _pieces(drawn["F1"]["path"][k])[0]
        np.testing.assert_allclose(shaft[0], at[k])
        v = shaft[1] - shaft[0]
        np.testing.assert_allclose(v, F[k] / 5.0 * 0.2 * span * np.array([0.6, 0.8]), atol=1e-9)
    assert "max 5" in drawn["F1"]["label"]
    for k in range(3):  # along the crank's own x axis
        v = np.diff(_pieces(drawn["P"]["path"][k])[0], axis=0)[0]
        phi = q[k, 2]
        np.testing.assert_allclose(
            v / np.linalg.norm(v), [math.cos(phi), math.sin(phi)], atol=1e-12
        )


def test_scene_draws_the_spring_between_its_points():
    model = spring_slider(x0=0.6)
    q = np.array([[0.6, 0.0, 0.0], [0.9, 0.0, 0.0]])
    (spring,) = Scene(model, q).symbols
    assert spring["kind"] == "spring_damper" and spring["name"] == "spring"
    for k in range(2):
        pts = spring["path"][k][~np.isnan(spring["path"][k][:, 0])]
        assert pts[:, 0].min() == pytest.approx(0.0) and pts[:, 0].max() == pytest.approx(q[k, 0])


def test_labels_do_not_cover_each_other_and_stay_inside():
    ring = [(15, 15), (85, 15), (15, 85), (85, 85), (50, 15), (50, 85), (97, 50)]
    anchors = np.vstack([np.full((5, 2), 50.0), ring])  # five at one spot, one at the edge
    sizes = np.tile([18.0, 8.0], (12, 1))
    frame = (0.0, 0.0, 100.0, 100.0)
    boxes = place(anchors, sizes, frame, gap=2.0)
    np.testing.assert_allclose(boxes[:, 2:] - boxes[:, :2], sizes)
    assert np.all(boxes[:, :2] >= 0) and np.all(boxes[:, 2:] <= 100)
    for i in range(len(boxes)):
        for j in range(i):
            a, b = boxes[i], boxes[j]
            assert min(a[2], b[2]) <= max(a[0], b[0]) or min(a[3], b[3]) <= max(a[1], b[1])


def test_a_joint_on_a_ground_point_of_its_name_is_named_once():
    style = {}
    merged = merge_labels(
        [("ground.O2", np.array([1.0, 2.0]), style), ("O2", np.array([1.0, 2.0]), style),
         ("ground.E", np.array([5.0, 0.0]), style), ("EF", np.array([5.0, 0.0]), style)]
    )  # fmt: skip
    assert sorted(t for t, _, _ in merged) == ["O2", "ground.E, EF"]


def test_shows_names_cover_no_other_name_and_stay_inside_the_axes():
    """The paper's mechanism under its loads, drawn: every name's box (bodies, joints,
    ground points, torques, the force) clear of every other one and inside the axes."""
    from fixtures import paper_under_loads
    from mixdyn.viz.show import figure

    model = paper_under_loads()
    fig, boxes = figure(model, np.asarray(model.q0))
    (ax,) = fig.axes
    x0, y0, x1, y1 = ax.bbox.extents
    assert len(boxes) >= 10
    assert np.all(boxes[:, 0] >= x0 - 1e-9) and np.all(boxes[:, 2] <= x1 + 1e-9)
    assert np.all(boxes[:, 1] >= y0 - 1e-9) and np.all(boxes[:, 3] <= y1 + 1e-9)
    for i in range(len(boxes)):
        for j in range(i):
            a, b = boxes[i], boxes[j]
            assert min(a[2], b[2]) <= max(a[0], b[0]) or min(a[3], b[3]) <= max(a[1], b[1])
