"""A polygon set (md.PolygonSetContact): rounded convex polygons and segments on several
bodies declared once, every pair on two different bodies a contact at each core vertex of
one against the other's core.

* geometry against plain NumPy: the signed distances of every contact point (a triangle, a
  square and two segments on two bodies and the ground) against a brute-force distance to
  the densely sampled boundary, with hand-placed truths (inside, outside near a side, near a
  corner) and their normals; each normal points to the nearest boundary point; the
  penetrations' Jacobian against autodiff's; the contact points, sliding speeds and the
  generalized force against the points' forces summed by hand, zero with the bodies apart;
* the drawing: the vertices' circles and a ground shape's sides, drawn by a scene;
* refusals (non-convex, clockwise, one vertex, on one line, counts that do not add up,
  every shape on one body), each naming the element and its field;
* a model file's set read, checked at its field's line, written and read back;
* (slow) a compliant box resting on a fixed box: statics gives the normal force m g and
  the penetration of Hertz's law's closed form;
* (slow) two equal squares colliding face on (no gravity), compliant and undamped: the
  momentum kept to 1e-9, the velocities exchanged, no rotation; rigid, a square standing on
  a corner striking a square's face through both centres: the velocities of Newton's law
  with restitution ``e`` at the closed-form instant;
* (slow) a rigid square dropped on a fixed segment (a capsule) comes to rest on it with the
  normal force m g.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from mixdyn.errors import ModelError

R = 0.002  # rounding radius [m]
H = 0.05  # half side of the squares [m]
G = 9.81
LAW = dict(young_modulus=2e11, restitution=1.0)


def _square(body, h=H, at=(0.0, 0.0)):
    """A square's vertices (counter-clockwise) of half side ``h`` about ``at`` on ``body``."""
    x, y = at
    return [(body, (x - h, y - h)), (body, (x + h, y - h)), (body, (x + h, y + h)),
            (body, (x - h, y + h))]  # fmt: skip


# The probe triangle's vertices in body c's frame: inside the square (0.03 from its top
# side), outside near its right side (0.02 away), outside near its corner (H, H) (0.03,
# 0.04 away): signed distances -0.03, 0.02, 0.05, normals along y, x and (0.6, 0.8).
PROBE = [(0.01, 0.02), (0.07, 0.01), (0.08, 0.09)]
BY_HAND = [(-0.03, (0.0, 1.0)), (0.02, (1.0, 0.0)), (0.05, (0.6, 0.8))]
POSE = (0.3, -0.2, 0.4)  # bodies p and c [m, m, rad]
SHAPES = [
    *[("p", s) for s in PROBE],  # 0: a triangle on p
    *_square("c"),  # 1: a square on c
    ("c", (0.0, 0.09)), ("c", (0.0, 0.16)),  # 2: a segment on c
    ("ground", (0.2, -0.16)), ("ground", (0.5, -0.05)),  # 3: a segment on the ground
]  # fmt: skip
COUNTS = (3, 4, 2, 2)


def _model(forces, poses=(POSE, POSE)):
    bodies = [md.Body(n, 1.0, 1e-3, q0=pose) for n, pose in zip("pc", poses, strict=True)]
    return md.Model(bodies, forces=forces)


def _place(pose, s):
    x, y, phi = pose
    c, sn = math.cos(phi), math.sin(phi)
    return np.array([x + c * s[0] - sn * s[1], y + sn * s[0] + c * s[1]])


def _brute(p, V, closed):
    """The signed distance of ``p`` (2,) to the polygon (or segment) of vertices ``V``
    (m, 2): the distance to 20001 points on each side, negative inside (left of every
    side, counter-clockwise)."""
    sides = [(V[k], V[(k + 1) % len(V)]) for k in range(len(V) if closed else 1)]
    s = np.linspace(0.0, 1.0, 20001)[:, None]
    boundary = np.concatenate([a + s * (b - a) for a, b in sides])
    d = np.min(np.hypot(*(p - boundary).T))
    inside = closed and all((b - a)[0] * (p - a)[1] - (b - a)[1] * (p - a)[0] > 0 for a, b in sides)
    return -d if inside else d, boundary


@eqx.filter_jit
def _geometry(s, q):
    """The set's penetrations and frame at ``q``: one program."""
    return s.penetration(q), s.frame(q)


def test_distances_normals_and_points_against_numpy():
    """Every contact point's ``2 R - delta`` equals the brute-force signed distance of its
    vertex to the other shape's core (1e-8 m), its normal points from there to the vertex
    (the nearest boundary point lies at ``p - d n``, within the sampling) and the contact
    point is half-way; the three hand-placed probes give their distances and normals. The
    penetrations' Jacobian, written from the normals and lever arms, equals autodiff's."""
    model = _model([md.PolygonSetContact("set", SHAPES, R, counts=COUNTS, **LAW)])
    s = model.forces[0]
    assert s.pairs == ((0, 1), (0, 2), (0, 3), (1, 3), (2, 3))  # (1, 2): both on c
    assert s.closed == (True, True, False, False)
    sizes = [3, 4, 2, 2]
    assert len(s.points) == sum(sizes[a] + sizes[b] for a, b in s.pairs)
    q = jnp.asarray(model.q0)
    both = eqx.filter_jit(
        lambda s, q: (_geometry(s, q), s._state(q, q)[1], jax.jacfwd(s.penetration)(q))
    )
    (delta, (P, n)), J, J_ad = jax.tree.map(np.asarray, both(s, q))
    poses = {"p": POSE, "c": POSE, "ground": (0.0, 0.0, 0.0)}
    glob = np.array([_place(poses[b], v) for b, v in SHAPES])
    first = np.cumsum([0, *sizes])
    k = 0
    for a, b in s.pairs:
        for own, other in ((a, b), (b, a)):
            core = glob[first[other] : first[other + 1]]
            for v in range(first[own], first[own + 1]):
                p = glob[v]
                d, boundary = _brute(p, core, sizes[other] > 2)
                assert 2 * R - delta[k] == pytest.approx(d, abs=1e-8)
                assert np.hypot(*n[k]) == pytest.approx(1.0, abs=1e-14)
                foot = p - (2 * R - delta[k]) * n[k]
                assert np.min(np.hypot(*(foot - boundary).T)) < 1e-5  # half a sample apart
                np.testing.assert_allclose(P[k], p - 0.5 * (2 * R - delta[k]) * n[k], atol=1e-15)
                k += 1
    np.testing.assert_allclose(J, J_ad, rtol=0.0, atol=1e-14)  # the rows by hand: autodiff's
    c, sn = math.cos(POSE[2]), math.sin(POSE[2])
    for k, (d, m) in enumerate(BY_HAND):  # pair (0, 1): the probe's vertices first
        assert 2 * R - delta[k] == pytest.approx(d, abs=1e-14)
        np.testing.assert_allclose(n[k], [c * m[0] - sn * m[1], sn * m[0] + c * m[1]],
                                   atol=1e-14)  # fmt: skip


def _by_hand(s, q, qd, law, delta, P, n, rate):
    """The generalized force (nq,) of the set's points' forces summed by hand: at each
    contact point ``P`` (k, 2) of normal ``n`` (k, 2), penetration ``delta`` (k,) and
    penetration rate ``rate`` (k,) (autodiff's), ``F n + F_t (z x n)`` on the vertex's body
    and the opposite on the other's (force and moment about each body's origin), and the
    sliding speeds (k,)."""
    q, qd = np.asarray(q), np.asarray(qd)
    E = law["young_modulus"] / (2 * (1 - 0.3**2))
    K = 4 / 3 * E * math.sqrt(R / 2)
    c = 0.75 * (1 - law["restitution"] ** 2) / law.get("impact_speed", 1.0)
    F = np.maximum(K * np.maximum(delta, 0) ** 1.5 * (1 + c * rate), 0.0)
    Q, vt = np.zeros_like(q), []
    for k, (v, other) in enumerate(s.points):
        t = np.array([-n[k, 1], n[k, 0]])
        vel = []
        for b in (s.bodies[s.shape_of[v]], s.bodies[other]):
            if b < 0:
                vel.append(np.zeros(2))
                continue
            arm = P[k] - q[3 * b : 3 * b + 2]
            vel.append(qd[3 * b : 3 * b + 2] + qd[3 * b + 2] * np.array([-arm[1], arm[0]]))
        vt.append((vel[0] - vel[1]) @ t)
        Ft = 0.0 if law.get("mu") is None else -law["mu"] * F[k] * np.tanh(vt[-1] / law["v_stick"])
        f = F[k] * n[k] + Ft * t
        for b, sign in ((s.bodies[s.shape_of[v]], 1.0), (s.bodies[other], -1.0)):
            if b >= 0:
                arm = P[k] - q[3 * b : 3 * b + 2]
                Q[3 * b : 3 * b + 3] += sign * np.array([f[0], f[1], arm[0] * f[1] - arm[1] * f[0]])
    return Q, np.array(vt)


def test_force_and_sliding_against_the_points_summed_by_hand():
    """The set's generalized force (damped, with friction) equals the contact points'
    forces summed as wrenches on the bodies, and its sliding speeds the points' relative
    velocities along ``z x n``; with the bodies apart, zero (the broad phase)."""
    law = dict(young_modulus=2e11, restitution=0.8, impact_speed=1.0, mu=0.3, v_stick=1e-3)
    shapes = [*_square("p"), *_square("c"), ("ground", (-0.2, -0.06)), ("ground", (0.2, -0.06))]
    touching = ((0.0, 0.0, 0.0), (2 * H + 2 * R - 3e-5, 0.01, 0.02))
    model = _model([md.PolygonSetContact("set", shapes, R, **law)], touching)
    s = model.forces[0]
    q = jnp.asarray(model.q0).at[1].set(-0.06 + H + 2 * R - 2e-5)  # p on the ground segment
    qd = jnp.asarray([0.3, -0.1, 2.0, -0.2, 0.05, -1.0])

    @jax.jit
    def step(q, qd):
        """The set's force and sliding speeds, and what the sum by hand takes: one program."""
        rate = jax.jvp(s.penetration, (q,), (qd,))[1]
        return (s.passive(q, qd, 0.0, 6), s.sliding(q, qd)), (*_geometry(s, q), rate)

    (Q, vt), (delta, (P, n), rate) = jax.tree.map(np.asarray, step(q, qd))
    Q_hand, vt_hand = _by_hand(s, q, qd, law, delta, P, n, rate)
    assert np.max(np.abs(Q_hand)) > 100.0  # real contact forces
    np.testing.assert_allclose(Q, Q_hand, rtol=1e-10, atol=1e-10 * np.max(np.abs(Q_hand)))
    np.testing.assert_allclose(vt, vt_hand, atol=1e-14)
    apart = jnp.asarray([-0.5, 0.5, 0.0, 0.5, 0.5, 0.0])
    (Q0, _), _ = step(apart, qd)
    assert not np.any(np.asarray(Q0))


def test_default_shapes_are_the_runs_on_one_body():
    """Without ``counts``, each run of consecutive vertices on one body is one shape."""
    s = _model([md.PolygonSetContact("set", [*_square("p"), *_square("c")], R, **LAW)]).forces[0]
    assert s.shape_of == (0, 0, 0, 0, 1, 1, 1, 1) and s.pairs == ((0, 1),)


@pytest.mark.parametrize(
    "shapes, counts, field, words",
    [
        ([*_square("p"), ("c", (0, 0)), ("c", (1, 0)), ("c", (0.5, 0.2)), ("c", (0, 1))], (),
         "vertices", "not convex"),
        ([*_square("p")[::-1], ("c", (0, 0)), ("c", (1, 0))], (), "vertices", "clockwise"),
        ([*_square("p"), ("c", (0, 0))], (), "vertices", "one vertex"),
        ([*_square("p"), ("c", (0, 0)), ("c", (1, 0)), ("c", (2, 0))], (), "vertices",
         "on one line"),
        ([*_square("p"), ("c", (0, 0)), ("c", (0, 0))], (), "vertices", "coincide"),
        ([*_square("p"), ("c", (0, 0)), ("c", (1, 0))], (4, 1, 1), "counts", "one vertex"),
        ([*_square("p"), ("c", (0, 0)), ("c", (1, 0))], (4, 3), "counts", "add up to 7"),
        ([*_square("p"), ("c", (0, 0)), ("c", (1, 0))], (3, 3), "counts", "several bodies"),
        ([*_square("p"), *_square("p", at=(1.0, 0.0))], (4, 4), "vertices", "on one body"),
    ],
)  # fmt: skip
def test_bad_shapes_are_refused(shapes, counts, field, words):
    with pytest.raises(ModelError, match=words) as info:
        _model([md.PolygonSetContact("set", shapes, R, counts=counts, **LAW)])
    assert str(info.value).startswith("set: ") and info.value.field == field


def test_the_drawing_outlines_the_shapes():
    """Each core vertex's circle of radius R (a body's outline wraps them) and, for a shape
    on the ground, its sides moved out by R (a segment's on both sides), which a scene
    draws among its guides."""
    from mixdyn.viz.scene import Scene

    ground = [("ground", v) for v in ((-0.3, -0.1), (0.3, -0.1), (0.3, 0.0), (-0.3, 0.0))]
    segment = [("ground", (0.4, 0.0)), ("ground", (0.4, 0.3))]
    model = _model([md.PolygonSetContact("set", [*_square("p"), *ground, *segment], R,
                                         counts=(4, 4, 2), **LAW)])  # fmt: skip
    d = model.forces[0].drawing()
    assert [(b, tuple(np.asarray(s)), r) for b, s, r in d["circles"]] == [
        (b, v, R) for b, v in ([(0, v) for _, v in _square("p")] + [(-1, v) for _, v in
                                                                     ground + segment])
    ]  # fmt: skip
    want = [((-0.3, -0.1 - R), (0.3, -0.1 - R)), ((0.3 + R, -0.1), (0.3 + R, 0.0)),
            ((0.3, R), (-0.3, R)), ((-0.3 - R, 0.0), (-0.3 - R, -0.1)),
            ((0.4 + R, 0.0), (0.4 + R, 0.3)), ((0.4 - R, 0.0), (0.4 - R, 0.3))]  # fmt: skip
    np.testing.assert_allclose(np.array(d["edges"], dtype=float), want, atol=1e-15)
    guides = Scene(model, np.asarray(model.q0)[None]).guides
    for a, b in want:
        assert np.any(np.all(np.abs(guides - np.array([a, b])) < 1e-15, axis=(1, 2)))


FILE = """mixdyn: 1
units: {length: mm, mass: kg, time: s}
bodies:
  - name: box
    mass: 1
    inertia: 1000
    q0: [0, 60, 0]
    points: {c1: [-50, -50], c2: [50, -50], c3: [50, 50], c4: [-50, 50]}
forces:
  - type: polygon_set_contact
    name: blocks
    vertices: [box.c1, box.c2, box.c3, box.c4, ground.A, ground.B, ground.C, ground.D, ground.E,
               ground.F]
    counts: [4, 4, 2]
    radius: 2 mm
    young_modulus: 200 GPa
    restitution: 1
ground:
  points: {A: [-300, -100], B: [300, -100], C: [300, 0], D: [-300, 0], E: [400, 0], F: [400, 300]}
"""


def test_a_files_set_is_read_checked_and_written_back():
    """``polygon_set_contact`` in a file: its vertices named points, its counts, its radius
    in the file's unit; a clockwise shape refused at the vertices' line; dumped and read
    again, the same element."""
    model = mio.build(mio.reads(FILE, "set.yaml"))
    s = model.forces[0]
    assert s.counts == (4, 4, 2) and float(s.radius) == 2.0
    assert s.bodies == (0, -1, -1) and s.pairs == ((0, 1), (0, 2))
    np.testing.assert_array_equal(s.local[4:8], [[-300, -100], [300, -100], [300, 0], [-300, 0]])
    bad = FILE.replace("ground.A, ground.B, ground.C, ground.D", "ground.A, ground.D, ground.C, "
                       "ground.B")  # fmt: skip
    with pytest.raises(mio.FileError, match=r"bad\.yaml:12: .*shape 2 .*clockwise"):
        mio.build(mio.reads(bad, "bad.yaml"))
    again = mio.build(mio.reads(mio.dumps(model), "again.yaml")).forces[0]
    assert again.vertices == s.vertices and again.counts == s.counts
    assert float(again.radius) == 2.0 and again.points == s.points


@pytest.mark.slow  # long: run by CI's slow set (a statics compiled with the contact)
def test_a_box_resting_on_a_fixed_box_carries_its_weight():
    """A box of mass m resting on a wider fixed box (its two lower corners on the fixed
    top): at the equilibrium (statics) the set's normal force is m g and each corner's
    penetration Hertz's ``(m g / (2 K))**(2/3)``, ``K = (4/3) E / (2 (1 - nu**2))
    sqrt(R / 2)``, the box's centre at ``H + 2 R - delta`` above the fixed top."""
    m = 2.0
    box = md.Body("box", m, m * (2 * H) ** 2 / 6, q0=(0.01, H + 2 * R - 1e-6, 0.0))  # pressed
    ground = [("ground", v) for v in ((-0.3, -0.1), (0.3, -0.1), (0.3, 0.0), (-0.3, 0.0))]
    law = dict(young_modulus=2e11, poisson=0.3, restitution=1.0)
    contact = md.PolygonSetContact("c", [*_square("box"), *ground], R, **law)
    model = md.Model([box], gravity=(0.0, -G), forces=[contact])
    st = md.statics(model)
    K = 4 / 3 * 2e11 / (2 * (1 - 0.3**2)) * math.sqrt(R / 2)
    delta = (m * G / (2 * K)) ** (2 / 3)
    out = eqx.filter_jit(lambda c, q: c.outputs(q, jnp.zeros_like(q), 0.0))(
        model.forces[0], jnp.asarray(st.q)
    )
    np.testing.assert_allclose(float(out["normal"]), m * G, rtol=1e-9)
    np.testing.assert_allclose(float(out["penetration"]), delta, rtol=1e-9)
    np.testing.assert_allclose(st.q[1], H + 2 * R - delta, rtol=0.0, atol=1e-12)
    assert abs(st.q[2]) < 1e-12


@pytest.mark.slow  # long: run by CI's slow set (a run through a compliant impact)
def test_two_squares_colliding_face_on_compliant():
    """Two equal squares, one at 1 m/s against the other at rest, faces parallel, no
    gravity, undamped (e = 1): the momentum is kept to 1e-9 throughout, no square turns,
    and after the impact their velocities are exchanged (1e-6: the energy is kept)."""
    m, V = 2.0, 1.0
    A = md.Body("A", m, m * (2 * H) ** 2 / 6, q0=(-2 * H - 2 * R - 0.01, 0.0, 0.0))
    B = md.Body("B", m, m * (2 * H) ** 2 / 6, q0=(0.0, 0.0, 0.0))
    sq = md.PolygonSetContact("c", [*_square("A"), *_square("B")], R, young_modulus=2e9,
                              restitution=1.0)  # fmt: skip
    model = md.Model([A, B], gravity=(0.0, 0.0), forces=[sq])
    qd0 = np.array([V, 0.0, 0.0, 0.0, 0.0, 0.0])
    r = md.forward(model, np.linspace(0.0, 0.03, 31), qd0=qd0, rtol=1e-10, atol=1e-12)
    assert np.max(r["c.normal"]) > 100.0
    np.testing.assert_allclose(m * (r["A.vx"] + r["B.vx"]), m * V, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(m * (r["A.vy"] + r["B.vy"]), 0.0, atol=1e-9)
    assert np.max(np.abs(np.r_[r["A.phi"], r["B.phi"]])) < 1e-9
    assert r["c.penetration"][-1] < 0.0  # apart again
    np.testing.assert_allclose([r["A.vx"][-1], r["B.vx"][-1]], [0.0, V], atol=1e-6)


@pytest.mark.slow  # long: run by CI's slow set (a run with a rigid impact)
@pytest.mark.parametrize("face_on", [False, True], ids=["corner", "face-on"])
def test_a_rigid_central_impact_follows_newtons_law(face_on):
    """A square strikes an equal square's face at 1 m/s along the line of both centres (no
    gravity), rigid with e = 0.6: standing on a corner (turned 45 degrees), one impact;
    face on, its two corners and the other's two struck at once (Newton's law at each,
    solved together); at the closed-form instant ``gap / V``, after which
    ``v_A = (1 - e) V / 2``, ``v_B = (1 + e) V / 2`` and neither turns."""
    m, V, e = 2.0, 1.0, 0.6
    d = H if face_on else H * math.sqrt(2)
    diamond = [("A", (0.0, -d)), ("A", (d, 0.0)), ("A", (0.0, d)), ("A", (-d, 0.0))]
    A = md.Body("A", m, m * (2 * H) ** 2 / 6, q0=(-0.2, 0.0, 0.0))
    B = md.Body("B", m, m * (2 * H) ** 2 / 6, q0=(0.0, 0.0, 0.0))
    shape = _square("A") if face_on else diamond
    rigid = md.PolygonSetContact("c", [*shape, *_square("B")], R, contact_model="rigid",
                                 restitution=e)  # fmt: skip
    model = md.Model([A, B], gravity=(0.0, 0.0), forces=[rigid])
    qd0 = np.array([V, 0.0, 0.0, 0.0, 0.0, 0.0])
    r = md.forward(model, np.linspace(0.0, 0.2, 11), qd0=qd0, rtol=1e-10, atol=1e-12)
    imp = r.stats["impacts"]
    gap = (0.2 - d) - H - 2 * R  # the corner (or face) to the rounded face
    points = 4 if face_on else 1
    np.testing.assert_allclose(imp["t"], [gap / V] * points, atol=1e-12)
    np.testing.assert_allclose(np.sum(imp["impulse"]), m * (1 + e) * V / 2, rtol=1e-12)
    np.testing.assert_allclose([r["A.vx"][-1], r["B.vx"][-1]], [(1 - e) * V / 2, (1 + e) * V / 2],
                               atol=1e-12)  # fmt: skip
    assert np.max(np.abs(np.r_[r["A.phi"], r["B.phi"], r["A.vy"], r["B.vy"]])) < 1e-12


@pytest.mark.slow  # long: run by CI's slow set (rigid impacts until the square rests)
def test_a_rigid_square_dropped_on_a_segment_rests_with_its_weight():
    """A square dropped from rest 15 cm above a fixed segment (a capsule of radius 1 mm: a
    fall of 1.7 m/s crosses it in 2.3 ms) lands on it flat, bounces (e = 0.2) and comes to
    rest on it: its centre at ``H + 2 r`` above the segment, level, the normal force m g.
    The steps keep up with the speed the fall reaches, so that the square never passes
    through the segment between two steps."""
    m, r_ = 2.0, 0.001
    box = md.Body("box", m, m * (2 * H) ** 2 / 6, q0=(0.01, H + 2 * r_ + 0.15, 0.0))
    segment = [("ground", (-0.3, 0.0)), ("ground", (0.3, 0.0))]
    contact = md.PolygonSetContact("c", [*_square("box"), *segment], r_, contact_model="rigid",
                                   restitution=0.2)  # fmt: skip
    model = md.Model([box], gravity=(0.0, -G), forces=[contact])
    r = md.forward(model, np.linspace(0.0, 0.5, 11))
    t_land = math.sqrt(2 * 0.15 / G)
    assert r.stats["impacts"]["t"][0] == pytest.approx(t_land, abs=1e-9)
    assert len(r.stats["impacts"]["t"]) >= 2 and r.stats["rests"]["contact"]
    np.testing.assert_allclose(r["box.y"][-1], H + 2 * r_, atol=1e-9)
    assert abs(r["box.phi"][-1]) < 1e-9
    np.testing.assert_allclose(r["c.normal"][-1], m * G, rtol=1e-9)
