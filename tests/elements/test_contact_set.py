"""A contact set (md.CircleSetContact): many circles declared once, every pair on two
different bodies found when the model is built.

* its pairs, penetrations and contact frames by hand for four circles (one fixed on the
  ground, two on one body, which never meet each other);
* its generalized force, potential and columns equal the sum of the same pairs declared one
  by one as md.CircleContact (a second element, tested against closed forms), friction
  included, and zero with every pair apart;
* refusals: one circle, every circle on one body, an unknown point;
* a file's set read and written back;
* (slow) Newton's cradle of five balls declared as one set: the run equals the one with the
  four neighbouring pairs declared one by one (the other six pairs never touch), momentum is
  kept to 1e-12 and energy to 1e-8; (slow) three balls as one rigid set pass the momentum
  along at the closed-form impact time.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from mixdyn.errors import ModelError

R = 0.01  # every circle's radius [m]
LAW = dict(young_modulus=2e11, restitution=0.8, impact_speed=1.0)


def _model(forces, x=(0.0, 0.0195, 0.05)):
    """Bodies a (one circle), b (two circles, at its centre and at (0, 0.03)), c; a fixed
    circle on the ground at (0.019, -0.005) near a; a and b overlapping by 0.5 mm."""
    bodies = [
        md.Body("a", 1.0, 1e-4, q0=(x[0], 0.0, 0.0)),
        md.Body("b", 1.0, 1e-4, q0=(x[1], 0.0, 0.3), points={"top": (0.0, 0.03)}),
        md.Body("c", 1.0, 1e-4, q0=(x[2], 0.0, 0.0)),
    ]
    return md.Model(bodies, ground={"G": (0.019, -0.005)}, forces=forces)


CENTERS = ["a", "b", "b.top", "c", "ground.G"]


def test_pairs_penetrations_and_frames_by_hand():
    """Pairs of circles on different bodies only ((1, 2), both on b, left out); each
    penetration ``2R - |c_j - c_i|`` and contact point ``c_i + (R - delta / 2) n`` by hand."""
    model = _model([md.CircleSetContact("set", CENTERS, R, **LAW)])
    s = model.forces[0]
    assert s.pairs == ((0, 1), (0, 2), (0, 3), (0, 4), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4))
    q = jnp.asarray(model.q0)
    phi_b = 0.3
    c = np.array([
        [0.0, 0.0],
        [0.0195, 0.0],
        [0.0195 - 0.03 * np.sin(phi_b), 0.03 * np.cos(phi_b)],
        [0.05, 0.0],
        [0.019, -0.005],
    ])  # fmt: skip
    delta = np.asarray(s.penetration(q))
    P, n = (np.asarray(x) for x in s.frame(q))
    for k, (i, j) in enumerate(s.pairs):
        d = c[j] - c[i]
        np.testing.assert_allclose(delta[k], 2 * R - np.hypot(*d), atol=1e-15)
        np.testing.assert_allclose(n[k], d / np.hypot(*d), atol=1e-15)
        np.testing.assert_allclose(P[k], c[i] + (R - delta[k] / 2) * n[k], atol=1e-15)
    assert delta[0] == pytest.approx(5e-4, abs=1e-15)  # a and b overlap by 0.5 mm


@pytest.mark.parametrize("mu", [None, pytest.param(0.3, marks=pytest.mark.slow)])  # slow: CI's
def test_the_set_is_its_pairs_declared_one_by_one(mu):
    """The set's generalized force, elastic energy and columns equal those of its pairs
    declared as CircleContact elements (summed), at a state where a touches b and the
    ground circle; all zero with the bodies apart."""
    law = dict(LAW, mu=mu, v_stick=None if mu is None else 1e-3)
    one = _model([md.CircleSetContact("set", CENTERS, R, **law)])
    s = one.forces[0]
    pairs = [
        md.CircleContact(f"p{k}", CENTERS[i], R, CENTERS[j], R, **law)
        for k, (i, j) in enumerate(s.pairs)
    ]
    many = _model(pairs)
    q = jnp.asarray(one.q0)
    qd = jnp.asarray([0.3, -0.1, 2.0, -0.2, 0.05, -1.0, 0.0, 0.1, 0.4])
    nq = q.size

    @jax.jit
    def both(q, qd):
        """The set's and the pairs' (force, energy, columns): one program, traced once."""
        mine = (s.passive(q, qd, 0.0, nq), s.potential(q), s.outputs(q, qd, 0.0))
        theirs = [(p.passive(q, qd, 0.0, nq), p.potential(q), p.outputs(q, qd, 0.0))
                  for p in many.forces]  # fmt: skip
        return mine, theirs

    (Q1, E1, out), theirs = both(q, qd)
    Q2 = sum(np.asarray(t[0]) for t in theirs)
    assert np.max(np.abs(Q2)) > 100.0  # a real contact force
    np.testing.assert_allclose(Q1, Q2, rtol=1e-13, atol=1e-12 * np.max(np.abs(Q2)))
    np.testing.assert_allclose(float(E1), sum(float(t[1]) for t in theirs), rtol=1e-13)
    outs = [t[2] for t in theirs]
    np.testing.assert_allclose(float(out["normal"]), sum(float(o["normal"]) for o in outs),
                               rtol=1e-13)  # fmt: skip
    assert float(out["penetration"]) == max(float(o["penetration"]) for o in outs)
    if mu is not None:
        np.testing.assert_allclose(float(out["friction"]),
                                   sum(float(o["friction"]) for o in outs), rtol=1e-12)  # fmt: skip
    apart = jnp.asarray(_model([], x=(-0.1, 0.1, 0.2)).q0)
    (Q0, E0, _), _ = both(apart, qd)
    assert not np.any(np.asarray(Q0)) and float(E0) == 0.0


@pytest.mark.parametrize(
    "centers, words",
    [
        (["a"], "two circles or more"),
        (["b", "b.top"], "on one body"),
        (["a", "b.nowhere"], "no point 'nowhere'"),
    ],
)
def test_bad_sets_are_refused(centers, words):
    with pytest.raises(ModelError, match=words):
        _model([md.CircleSetContact("set", centers, R, **LAW)])


def test_a_files_set_is_read_and_written_back():
    """``circle_set_contact`` in a file: its centres read as a list, its radius in the
    file's unit; dumped and read again, the same element."""
    text = """mixdyn: 1
units: {length: mm, mass: kg, time: s}
bodies:
  - {name: a, mass: 1, inertia: 100, q0: [0, 0, 0]}
  - {name: b, mass: 1, inertia: 100, q0: [30, 0, 0]}
forces:
  - type: circle_set_contact
    name: balls
    centers: [a, b, ground.O]
    radius: 10 mm
    young_modulus: 200 GPa
    restitution: 1
ground: {points: {O: [0, -40]}}
"""
    model = mio.build(mio.reads(text, "set.yaml"))
    s = model.forces[0]
    assert s.centers == ("a", "b", "ground.O") and float(s.radius) == 10.0
    assert s.pairs == ((0, 1), (0, 2), (1, 2))
    again = mio.build(mio.reads(mio.dumps(model), "again.yaml")).forces[0]
    assert again.centers == s.centers and float(again.radius) == float(s.radius)


@pytest.mark.slow  # long: run by CI's slow set (two runs through five balls' impacts)
def test_newtons_cradle_as_one_set_equals_its_neighbouring_pairs():
    """Five balls in a row, the first moving at 1 m/s: one set of five circles (ten pairs)
    against the four neighbouring pairs declared one by one (the others never touch): the
    same motion (1e-9 m), momentum kept to 1e-12, energy to 1e-8, the last ball leaving with
    most of the momentum."""
    M, V = 0.1, 1.0
    balls = [md.Body(f"b{k}", M, 0.4 * M * R**2, q0=(x, 0.0, 0.0))
             for k, x in enumerate((-0.01, 2 * R, 4 * R, 6 * R, 8 * R))]  # fmt: skip
    law = dict(young_modulus=2e11, restitution=1.0)
    names = [f"b{k}" for k in range(5)]
    one = md.Model(balls, forces=[md.CircleSetContact("balls", names, R, **law)])
    pairs = [md.CircleContact(f"c{k}", names[k], R, names[k + 1], R, **law) for k in range(4)]
    many = md.Model(balls, forces=pairs)
    ts = np.linspace(0.0, 0.04, 201)
    qd0 = np.zeros(15)
    qd0[0] = V
    r1 = md.forward(one, ts, qd0=qd0, rtol=1e-11, atol=1e-13)
    r2 = md.forward(many, ts, qd0=qd0, rtol=1e-11, atol=1e-13)
    for k in range(5):
        assert np.max(np.abs(r1[f"b{k}.x"] - r2[f"b{k}.x"])) < 1e-9
    p = sum(r1[f"b{k}.vx"] for k in range(5)) * M
    np.testing.assert_allclose(p, M * V, rtol=1e-12)
    E = r1["energy.total"]
    assert np.max(np.abs(E - E[0])) < 1e-8 * E[0]
    assert r1["b4.vx"][-1] > 0.9 * V
    assert np.max(r1["balls.normal"]) > 0


@pytest.mark.slow  # long: run by CI's slow set (a run with rigid impacts)
def test_a_rigid_set_passes_the_momentum_along():
    """Three balls as one rigid set (e = 1), the last two touching: two impacts at the
    closed-form time 0.01 m / V, the momentum passed to the last ball, the kinetic energy
    kept (1e-12)."""
    m, V = 0.1, 1.0
    balls = [md.Body(f"b{k}", m, 0.4 * m * R**2, q0=(x, 0.0, 0.0))
             for k, x in enumerate((-0.01, 2 * R, 4 * R))]  # fmt: skip
    law = dict(contact_model="rigid", restitution=1.0)
    model = md.Model(balls, forces=[md.CircleSetContact("balls", ["b0", "b1", "b2"], R, **law)])
    qd0 = np.zeros(9)
    qd0[0] = V
    r = md.forward(model, np.linspace(0.0, 0.05, 11), qd0=qd0, rtol=1e-11, atol=1e-13)
    imp = r.stats["impacts"]
    assert imp["contact"] == ["balls", "balls"]
    np.testing.assert_allclose(imp["t"], [0.01 / V, 0.01 / V], atol=1e-12)
    vx = np.stack([r[f"b{k}.vx"] for k in range(3)], axis=1)
    np.testing.assert_allclose(vx[-1], [0.0, 0.0, V], atol=1e-12)
    np.testing.assert_allclose(r["energy.kinetic"], 0.5 * m * V**2, rtol=1e-12)


def test_a_sets_held_points_are_rows_of_their_own_bodies():
    """The rows holding a rigid set's points at rest (a ball on a fixed one, a ball on that
    ball; a pendulum first, so that the set's bodies are not the model's first), evaluated
    per element on each row's own bodies, equal the whole vector's Jacobian."""
    from mixdyn.analysis._problem import Problem
    from mixdyn.analysis._resting import hold, holding
    from mixdyn.equations import Constraints
    from mixdyn.model._compliant import rigid_contacts

    R_ = 0.05
    bodies = [
        md.Body("p", 1.0, 0.01, q0=(1.0, 0.0, 0.0)),
        md.Body("a", 1.0, 1e-3, q0=(0.01, 2 * R_, 0.0)),
        md.Body("b", 2.0, 2e-3, q0=(0.03, 4 * R_, 0.0)),
    ]
    balls = md.CircleSetContact("balls", ["ground.O", "a", "b"], R_, contact_model="rigid",
                                restitution=0.3)  # fmt: skip
    model = md.Model(bodies, joints=[md.Revolute("pin", "ground.Q", "p")], forces=[balls],
                     ground={"O": (0.0, 0.0), "Q": (1.0, 0.0)})  # fmt: skip
    (contact,) = rigid_contacts(model)
    held = holding(Problem(model, Constraints.of(model)),
                   tuple(hold(contact, k, 3) for k in (0, 2)))  # fmt: skip
    q = jnp.asarray(model.q0)
    dense = np.asarray(held.c.phi_q(q, 0.0))
    rows, cols = held.c.coo()
    local = np.zeros_like(dense)
    np.add.at(local, (rows, cols), np.asarray(held.c.jacobian_values(q, 0.0)))
    np.testing.assert_allclose(local, dense, rtol=0, atol=1e-15)
    assert np.abs(dense[2:, 3:]).max() > 0.5 and not dense[2:, :3].any()  # a and b, not p


@pytest.mark.slow  # long: run by CI's slow set (a run with rigid impacts until rest)
def test_two_balls_of_a_rigid_set_come_to_rest_stacked_on_a_fixed_one():
    """Ball a dropped on a fixed ball, ball b dropped on a (a pendulum hanging still
    elsewhere, so that the set's bodies are not the model's first): both pairs come to rest,
    a's centre at ``2 R`` above the fixed one's and b's at ``4 R``; the set's normal column
    is the pairs' ``(m_a + m_b) g + m_b g``; the pendulum's pin carries its weight."""
    R_, g, m_a, m_b = 0.05, 9.81, 1.0, 2.0
    bodies = [
        md.Body("p", 1.0, 0.01, q0=(1.0, 0.0, 0.0)),
        md.Body("a", m_a, 0.5 * m_a * R_**2, q0=(0.0, 2 * R_ + 0.01, 0.0)),
        md.Body("b", m_b, 0.5 * m_b * R_**2, q0=(0.0, 4 * R_ + 0.03, 0.0)),
    ]
    balls = md.CircleSetContact("balls", ["ground.O", "a", "b"], R_, contact_model="rigid",
                                restitution=0.3)  # fmt: skip
    pin = md.Revolute("pin", "ground.Q", "p")
    model = md.Model(bodies, joints=[pin], forces=[balls], gravity=(0, -g),
                     ground={"O": (0.0, 0.0), "Q": (1.0, 0.0)})  # fmt: skip
    r = md.forward(model, np.linspace(0.0, 1.0, 11))
    assert sorted(r.stats["rests"]["end"]) == [1.0, 1.0]
    last = r.t > max(r.stats["rests"]["start"])
    np.testing.assert_allclose(r["a.y"][last], 2 * R_, atol=1e-9)
    np.testing.assert_allclose(r["b.y"][last], 4 * R_, atol=1e-9)
    np.testing.assert_allclose(np.r_[r["a.x"][last], r["b.x"][last]], 0.0, atol=1e-9)
    np.testing.assert_allclose(r["balls.normal"][last], (m_a + 2 * m_b) * g, rtol=1e-9)
    np.testing.assert_allclose(r["pin.Fy"][last], g, rtol=1e-9)
