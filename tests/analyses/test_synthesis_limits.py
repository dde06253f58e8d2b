"""The Grashof type and the ground-pivot regions of a synthesis (mixdyn.synthesis._limits):
the classification against hand-computed linkages of each type and against the kinematic
truth (the crank turns fully exactly where the loop closes at every crank angle), the gaps by
hand; slow: a search asked for crank-rockers on points that a non-Grashof four-bar passes
exactly returns only crank-rockers whose loop closes over a whole turn, and a search with a
region for ``O4`` keeps only linkages whose ``O4`` lies in it."""

import numpy as np
import pytest

from mixdyn.errors import ModelError
from mixdyn.synthesis import FourBar, FunctionTask, MotionTask, PathTask, SliderCrank, synthesize
from mixdyn.synthesis._limits import grashof_gaps, grashof_type, region_arrays, region_gaps

# (r1, r2, r3, r4) and the type by hand: s + l against p + q, and which link is the shortest.
CASES = [
    ((4.0, 1.0, 3.0, 3.5), "crank_rocker"),  # 1 + 4 <= 3 + 3.5, crank shortest
    ((1.0, 3.0, 3.5, 4.0), "double_crank"),  # 1 + 4 <= 3 + 3.5, ground shortest
    ((4.0, 3.5, 3.0, 1.0), "rocker_crank"),  # 1 + 4 <= 3 + 3.5, rocker shortest
    ((4.0, 3.0, 1.0, 3.5), "double_rocker"),  # 1 + 4 <= 3 + 3.5, coupler shortest
    ((4.0, 2.0, 2.0, 2.5), "triple_rocker"),  # 2 + 4 > 2 + 2.5: not Grashof
    ((2.0, 1.0, 2.0, 1.0), "crank_rocker"),  # a parallelogram: 1 + 2 = 1 + 2, crank shortest
]


def _closes_over_a_turn(r1, r2, r3, r4, samples=360) -> bool:
    """The loop closes at every crank angle: ``|A O4|`` (law of cosines) within
    ``[|r3 - r4|, r3 + r4]`` at ``samples`` angles over a turn."""
    t = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    d = np.sqrt(r1**2 + r2**2 - 2 * r1 * r2 * np.cos(t))
    tol = 1e-12 * (r3 + r4)
    return bool(np.all((d >= abs(r3 - r4) - tol) & (d <= r3 + r4 + tol)))


def _fourbar(r1, r2, r3, r4, x0=0.0, y0=0.0, theta0=0.0) -> FourBar:
    return FourBar.from_vector(np.array([r1, r2, r3, r4, 0.0, 0.0, x0, y0, theta0]), 1.0)


@pytest.mark.parametrize("lengths, kind", CASES)
def test_grashof_type_of_hand_computed_linkages(lengths, kind):
    """Each type by hand; the crank turns fully (the loop closes at every crank angle)
    exactly for a crank-rocker and a double crank; the gaps of the asked type are all <= 0
    exactly where the linkage is of it."""
    assert grashof_type(*lengths) == kind
    turns = kind in ("crank_rocker", "double_crank")
    assert _closes_over_a_turn(*lengths) == turns
    for asked in ("crank_rocker", "double_crank"):
        gaps = np.asarray(grashof_gaps(_fourbar(*lengths), asked))
        assert gaps.shape == (3,)
        assert (np.max(gaps) <= 1e-12) == (kind == asked)


def _some_link_turns_fully(lengths) -> bool:
    """Some link turns a full revolution relative to a neighbour: in one of the four
    inversions (each link as the ground), the loop closes at every angle of one of the
    ground's two neighbours (turned as the crank)."""
    L = list(lengths)
    for k in range(4):
        for step in (1, -1):
            if _closes_over_a_turn(*(L[(k + step * j) % 4] for j in range(4))):
                return True
    return False


@pytest.mark.parametrize("lengths, kind", [*CASES, ((3.0, 4.0, 2.0, 5.5), "triple_rocker")])
def test_plain_grashof_asks_that_some_link_turns_fully(lengths, kind):
    """``grashof="grashof"`` (any link the shortest): its one gap ``2 (s + l) - sum`` is
    <= 0 exactly where some link turns fully relative to another (the loop closing over a
    whole turn in one of the inversions), and where the type is not a triple rocker."""
    gap = np.asarray(grashof_gaps(_fourbar(*lengths), "grashof"))
    assert gap.shape == (1,)
    s, l = min(lengths), max(lengths)
    np.testing.assert_allclose(gap, [2 * (s + l) - sum(lengths)], atol=1e-15)
    assert (gap[0] <= 1e-12) == _some_link_turns_fully(lengths) == (kind != "triple_rocker")


def test_plain_grashof_of_a_slider_crank():
    """A slider-crank's ``grashof`` gap is ``min(r2, r3) + |e| - max(r2, r3)``: the crank's
    ``r2 + |e| - r3`` where the crank is the shorter, the coupler's where it is (by hand)."""
    for r2, r3, e, gap in [(1.0, 3.0, 1.5, -0.5), (1.0, 3.0, -2.5, 0.5), (3.0, 1.0, 1.5, -0.5)]:
        sc = SliderCrank.from_vector(np.array([r2, r3, e, 0, 0, 0, 0, 0]), 1.0)
        np.testing.assert_allclose(grashof_gaps(sc, "grashof"), [gap], atol=1e-15)
    PathTask(np.eye(3)[:, :2] * [1.0, 2.0], linkage="slider_crank", grashof="grashof")


def test_grashof_gaps_by_hand():
    """The triple rocker (4, 2, 2, 2.5) asked to be a crank-rocker: ``r2 + r_j - r_k - r_l``
    for j = ground, coupler, rocker is 1.5, -2.5, -1.5; as a double crank ``r1 + r_j - r_k -
    r_l`` for j = crank, coupler, rocker is 1.5, 1.5, 2.5; a slider-crank's ``r2 +- e - r3``;
    ``any`` asks nothing."""
    fb = _fourbar(4.0, 2.0, 2.0, 2.5)
    np.testing.assert_allclose(grashof_gaps(fb, "crank_rocker"), [1.5, -2.5, -1.5], atol=1e-15)
    np.testing.assert_allclose(grashof_gaps(fb, "double_crank"), [1.5, 1.5, 2.5], atol=1e-15)
    assert np.shape(grashof_gaps(fb, "any")) == (0,)
    sc = SliderCrank.from_vector(np.array([1.0, 3.0, 1.5, 0, 0, 0, 0, 0]), 1.0)
    np.testing.assert_allclose(grashof_gaps(sc, "crank_rocker"), [-0.5, -3.5], atol=1e-15)


@pytest.mark.parametrize("e, turns", [(1.5, True), (-2.0, True), (2.5, False), (-2.1, False)])
def test_a_slider_cranks_crank_turns_fully_where_its_gaps_say(e, turns):
    """The crank pin's height above the slide, ``r2 sin t - e``, stays within the rod's
    ``r3`` at every crank angle exactly where ``r2 + |e| <= r3`` (r2 = 1, r3 = 3)."""
    t = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)
    assert bool(np.all(np.abs(np.sin(t) - e) <= 3.0)) == turns
    sc = SliderCrank.from_vector(np.array([1.0, 3.0, e, 0, 0, 0, 0, 0]), 1.0)
    assert (np.max(np.asarray(grashof_gaps(sc, "crank_rocker"))) <= 0) == turns


def test_the_rocker_pivots_region_gaps_by_hand():
    """O4 = O2 + r1 (cos theta0, sin theta0) = (0.1 + sqrt 3, 1.2) for O2 = (0.1, 0.2),
    r1 = 2, theta0 = 30 deg; the gaps ``low - p`` then ``p - high``, per pivot."""
    fb = _fourbar(2.0, 0.5, 2.0, 2.0, x0=0.1, y0=0.2, theta0=np.pi / 6)
    pivots = {"O4": ((1.0, 2.0), (1.0, 1.1)), "O2": ((0.0, 1.0), (0.0, 1.0))}
    low, high = region_arrays(pivots)
    gaps = np.asarray(region_gaps(fb, ("O4", "O2"), low, high))
    o4 = np.array([0.1 + np.sqrt(3), 1.2])
    want = [1.0 - o4[0], 1.0 - o4[1], o4[0] - 2.0, o4[1] - 1.1, -0.1, -0.2, -0.9, -0.8]
    np.testing.assert_allclose(gaps, want, atol=1e-15)


@pytest.mark.parametrize(
    "make, element, words",
    [
        (lambda p: PathTask(p, grashof="drag_link"), "grashof", "one of"),
        (lambda p: PathTask(p, linkage="slider_crank", grashof="double_crank"), "grashof",
         "no double crank"),
        (lambda p: PathTask(p, linkage="slider_crank", pivots={"O4": ((0, 1), (0, 1))}), "O4",
         "no ground pivot"),
        (lambda p: PathTask(p, pivots={"O4": ((1, 0), (0, 1))}), "O4", "low < high"),
        (lambda p: PathTask(p, pivots={"O4": (0, 1)}), "O4", "low < high"),
        (lambda p: PathTask(p, bounds={"y0": (0, 1)}, pivots={"O2": ((0, 1), (0, 1))}), "O2",
         "twice"),
        (lambda p: FunctionTask([0, 1], [0, 1], grashof="rocker"), "grashof", "one of"),
        (lambda p: MotionTask(np.c_[p, [0, 1, 2]], grashof="x"), "grashof", "one of"),
    ],
)  # fmt: skip
def test_bad_limits_are_refused(make, element, words):
    points = np.array([[0.0, 0.0], [1.0, 0.5], [1.5, 1.2]])
    with pytest.raises(ModelError) as e:
        make(points)
    assert e.value.element == element and words in e.value.message


# A triple rocker (not Grashof) [m, rad] and eight points of its coupler curve at given crank
# angles over most of its crank's swing (|cos mu| < 0.95 from -2.566 to 2.566 rad).
TRIPLE = np.array([1.0, 0.8, 0.9, 0.85, 0.5, 0.3, 0.0, 0.0, 0.1])
THETA = np.linspace(-2.56, 2.56, 8)


def _targets():
    from mixdyn.synthesis import coupler_curve

    return np.asarray(coupler_curve(FourBar.from_vector(TRIPLE, 1.0), THETA))


def _assembles_over_a_turn(fb) -> bool:
    """The candidate assembled at 360 crank angles: ``B = A + r3 e^{i phi3}`` lies at ``r4``
    from ``O4`` everywhere (where the loop opens, the closed form's nearest configuration
    does not)."""
    import jax

    from mixdyn.synthesis import link_angles

    v = {n: float(getattr(fb, n)) for n in fb.NAMES}
    t = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)
    phi2 = v["theta0"] + t
    phi3 = np.asarray(jax.vmap(lambda x: link_angles(fb, x)[0])(t))
    bx = v["x0"] + v["r2"] * np.cos(phi2) + v["r3"] * np.cos(phi3)
    by = v["y0"] + v["r2"] * np.sin(phi2) + v["r3"] * np.sin(phi3)
    o4x = v["x0"] + v["r1"] * np.cos(v["theta0"])
    o4y = v["y0"] + v["r1"] * np.sin(v["theta0"])
    return np.max(np.abs(np.hypot(bx - o4x, by - o4y) - v["r4"])) < 1e-9 * v["r4"]


@pytest.mark.slow  # long: run by CI's slow set (two searches compile their programs)
def test_a_crank_rocker_search_returns_only_crank_rockers_that_turn_fully():
    """Unconstrained, the best four-bar through the triple rocker's timed points is not a
    crank-rocker (it is the triple rocker, error ~0); asked for crank-rockers, every kept
    candidate is one (Grashof, its crank the shortest link, by hand) and its loop closes at
    360 crank angles over a whole turn; asked for Grashof alone, every kept one is Grashof."""
    points = _targets()
    free = synthesize(PathTask(points, timing=THETA), starts=256, chunk=256)
    best = free.best.fourbar
    lengths = [float(getattr(best, n)) for n in ("r1", "r2", "r3", "r4")]
    assert free.best.error < 1e-12 and grashof_type(*lengths) != "crank_rocker"
    assert not _assembles_over_a_turn(best)
    out = synthesize(PathTask(points, timing=THETA, grashof="crank_rocker"), starts=256, chunk=256)
    assert len(out.candidates) >= 2
    for c in out.candidates:
        r = np.array([float(getattr(c.fourbar, n)) for n in ("r1", "r2", "r3", "r4")])
        s = np.sort(r)
        assert s[0] + s[3] <= s[1] + s[2] and r[1] == s[0]
        assert _assembles_over_a_turn(c.fourbar)
    assert out.best.error > free.best.error
    plain = synthesize(PathTask(points, timing=THETA, grashof="grashof"), starts=256, chunk=256)
    assert len(plain.candidates) >= 2  # Grashof, any link the shortest (s + l <= p + q)
    for c in plain.candidates:
        s = np.sort([float(getattr(c.fourbar, n)) for n in ("r1", "r2", "r3", "r4")])
        assert s[0] + s[3] <= s[1] + s[2] * (1 + 1e-9)
    assert plain.best.error > free.best.error


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_every_kept_candidates_rocker_pivot_lies_in_its_region():
    """The triple rocker's O4 (0.995, 0.0998) lies outside the region asked for; every kept
    candidate's O4 = O2 + r1 (cos theta0, sin theta0), computed by hand, lies inside it."""
    region = ((1.2, 1.6), (-0.6, -0.1))
    task = PathTask(_targets(), timing=THETA, pivots={"O4": region})
    out = synthesize(task, starts=256, chunk=256)
    assert out.candidates
    for c in out.candidates:
        fb = c.fourbar
        x = float(fb.x0) + float(fb.r1) * np.cos(float(fb.theta0))
        y = float(fb.y0) + float(fb.r1) * np.sin(float(fb.theta0))
        assert region[0][0] <= x <= region[0][1] and region[1][0] <= y <= region[1][1]


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_a_slider_crank_search_asked_to_turn_fully_returns_full_turning_cranks():
    """Timed points of a slider-crank whose crank cannot turn fully (r2 + |e| = 0.4 > r3 =
    0.35); asked for ``crank_rocker``, every kept slider-crank has ``r2 + |e| <= r3`` (by hand)
    and, assembled at 360 crank angles, its rod's end ``A + r3 e^{i phi3}`` lies on the slide
    everywhere."""
    from mixdyn.synthesis import coupler_curve, rod_and_slider

    jammed = SliderCrank.from_vector(np.array([0.3, 0.35, 0.1, 0.15, 0.08, 0.0, 0.0, 0.2]), 1.0)
    theta = np.deg2rad(np.linspace(-50.0, 230.0, 8))
    points = np.asarray(coupler_curve(jammed, theta))
    task = PathTask(points, timing=theta, linkage="slider_crank", grashof="crank_rocker")
    out = synthesize(task, starts=256, chunk=256)
    assert out.candidates
    t = np.linspace(0.0, 2 * np.pi, 360, endpoint=False)
    for c in out.candidates:
        v = {n: float(getattr(c.fourbar, n)) for n in c.fourbar.NAMES}
        assert v["r2"] + abs(v["e"]) <= v["r3"]
        import jax

        phi3 = np.asarray(jax.vmap(lambda x, sc=c.fourbar: rod_and_slider(sc, x)[0])(t))
        phi2 = v["theta0"] + t
        # the rod's end from O2, across the slide's direction: the offset e everywhere
        bx = v["r2"] * np.cos(phi2) + v["r3"] * np.cos(phi3)
        by = v["r2"] * np.sin(phi2) + v["r3"] * np.sin(phi3)
        across = -np.sin(v["theta0"]) * bx + np.cos(v["theta0"]) * by
        assert np.max(np.abs(across - v["e"])) < 1e-9 * v["r3"]


@pytest.mark.slow  # long: run by CI's slow set (the search compiles its program)
def test_a_function_search_asked_for_crank_rockers_returns_crank_rockers():
    """The triple rocker's rocker angles at six crank angles: asked for crank-rockers, every
    kept four-bar is one (by hand) and its loop closes over a whole turn."""
    from mixdyn.synthesis import link_angles

    fb = FourBar.from_vector(np.array([1.0, 0.8, 0.9, 0.85, 0, 0, 0, 0, 0]), 1.0)
    inputs = np.linspace(-2.4, 2.4, 6)
    outputs = np.array([float(link_angles(fb, x)[1]) for x in inputs])
    out = synthesize(FunctionTask(inputs, outputs, grashof="crank_rocker"), starts=256)
    assert out.candidates
    for c in out.candidates:
        r = np.array([1.0, float(c.fourbar.r2), float(c.fourbar.r3), float(c.fourbar.r4)])
        s = np.sort(r)
        assert s[0] + s[3] <= s[1] + s[2] and r[1] == s[0]
        assert _closes_over_a_turn(*r)
