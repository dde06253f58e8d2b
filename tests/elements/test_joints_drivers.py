"""Joint and driver equations: ``Phi``, ``Phi_q``, ``Phi_t`` and ``gamma`` of
:class:`mixdyn.equations.Constraints` against the planar textbook formulas (Nikravesh,
*Computer-Aided Analysis of Mechanical Systems*, ch. 3-4; Haug, *Computer-Aided Kinematics and
Dynamics*, ch. 3) and against finite differences, at random configurations and velocities.

Conventions checked: body ``i`` is the first reference, body ``j`` the second; the residual of
a two-point joint is built on ``d = r_Pj - r_Pi``; ``A(phi)`` is the rotation matrix and
``B(phi) = dA/dphi``; ``gamma = -(Phi_q qd)_q qd - 2 Phi_qt qd - Phi_tt``.
"""

import numpy as np
import pytest

import mixdyn as md
from fixtures import evaluate, fd_gamma, fd_jacobian, fd_phi_t
from mixdyn.equations import Constraints

RNG_SEED = 7

I2 = np.eye(2)


def A(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def B(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[-s, -c], [c, -s]])


# ----------------------------------------------------------------------------- set-up
#: Harmonic law of the drivers: f, f', f'' are known in closed form.
LAW = (0.6, 1.7, 0.3, 0.2)  # amplitude, omega, phase, offset


def law_values(t):
    a, w, ph, off = LAW
    s, c = np.sin(w * t + ph), np.cos(w * t + ph)
    return off + a * s, a * w * c, -a * w**2 * s


def two_bodies(rng):
    """Bodies ``i`` and ``j`` with a random point ``P`` each, and a ground point ``G``."""
    si, sj, g = rng.uniform(-1, 1, size=(3, 2))
    bodies = [
        md.Body("i", points={"P": tuple(si)}),
        md.Body("j", points={"P": tuple(sj)}),
    ]
    return bodies, {"G": tuple(g)}, si, sj, g


def state(rng):
    q = rng.uniform(-1, 1, size=6)
    q[[2, 5]] = rng.uniform(-np.pi, np.pi, size=2)
    qd = rng.uniform(-2, 2, size=6)
    t = float(rng.uniform(0, 2))
    return q, qd, t


def parts(q, qd, b):
    """``(r, phi, rd, phid)`` of body ``b`` (0 = i, 1 = j, None = ground)."""
    if b is None:
        return np.zeros(2), 0.0, np.zeros(2), 0.0
    return q[3 * b : 3 * b + 2], q[3 * b + 2], qd[3 * b : 3 * b + 2], qd[3 * b + 2]


def place(J, rows, b, block):
    """Put a (rows, 3) block in the columns of body ``b`` (nothing for the ground)."""
    if b is not None:
        J[rows, 3 * b : 3 * b + 3] += block


# --------------------------------------------------------------------- closed forms
def revolute(q, qd, bi, si, bj, sj):
    """``Phi, Phi_q, gamma`` of ``r_j + A_j s_j - r_i - A_i s_i = 0`` (Nikravesh 3.3)."""
    ri, pi, _, wi = parts(q, qd, bi)
    rj, pj, _, wj = parts(q, qd, bj)
    Phi = rj + A(pj) @ sj - ri - A(pi) @ si
    J = np.zeros((2, 6))
    place(J, slice(0, 2), bi, np.column_stack([-I2, -B(pi) @ si]))
    place(J, slice(0, 2), bj, np.column_stack([I2, B(pj) @ sj]))
    gamma = A(pj) @ sj * wj**2 - A(pi) @ si * wi**2
    return Phi, J, gamma


def slot_normal(q, qd, bi, si, bj, sj, u_local):
    """``Phi, Phi_q, gamma`` of ``n_i . d = 0`` with ``n_i = B_i u'`` (= ``u_i x d``), the
    first equation of a translational or pin-in-slot joint (Nikravesh 3.4, Haug 3.3)."""
    ri, pi, rdi, wi = parts(q, qd, bi)
    rj, pj, rdj, wj = parts(q, qd, bj)
    u = A(pi) @ u_local
    n = B(pi) @ u_local
    d = rj + A(pj) @ sj - ri - A(pi) @ si
    dd = rdj + B(pj) @ sj * wj - rdi - B(pi) @ si * wi
    J = np.zeros((1, 6))
    place(J, 0, bi, np.concatenate([-n, [-n @ B(pi) @ si - u @ d]]))
    place(J, 0, bj, np.concatenate([n, [n @ B(pj) @ sj]]))
    # d/dt n = -u wi, d/dt u = n wi; second derivative without the accelerations:
    quad = -(n @ d) * wi**2 - 2 * wi * (u @ dd) + n @ (A(pi) @ si * wi**2 - A(pj) @ sj * wj**2)
    return np.array([n @ d]), J, np.array([-quad])


def relative_angle(bi, bj, offset):
    """``Phi_q`` row and ``gamma`` of ``phi_j - phi_i - offset = 0``."""
    J = np.zeros((1, 6))
    place(J, 0, bi, np.array([0.0, 0.0, -1.0]))
    place(J, 0, bj, np.array([0.0, 0.0, 1.0]))
    return J, np.zeros(1)


def distance(q, qd, bi, si, bj, sj, length):
    """``Phi, Phi_q, gamma`` of ``|d| - length = 0`` (Nikravesh 3.5)."""
    ri, pi, rdi, wi = parts(q, qd, bi)
    rj, pj, rdj, wj = parts(q, qd, bj)
    d = rj + A(pj) @ sj - ri - A(pi) @ si
    dd = rdj + B(pj) @ sj * wj - rdi - B(pi) @ si * wi
    L = np.linalg.norm(d)
    e = d / L
    J = np.zeros((1, 6))
    place(J, 0, bi, np.concatenate([-e, [-e @ B(pi) @ si]]))
    place(J, 0, bj, np.concatenate([e, [e @ B(pj) @ sj]]))
    quad = (dd @ dd - (e @ dd) ** 2) / L + e @ (A(pi) @ si * wi**2 - A(pj) @ sj * wj**2)
    return np.array([L - length]), J, np.array([-quad])


# ------------------------------------------------------------------------ the cases
def joint_case(kind, rng, to_ground):
    """A model with one joint of ``kind`` (between i and j, or between the ground and j) and
    the closed form of its equations, as a function ``(q, qd) -> (Phi, Phi_q, gamma)``."""
    bodies, ground, si, sj, g = two_bodies(rng)
    bi, ref_i, s_i = (None, "ground.G", g) if to_ground else (0, "i.P", si)
    bj, ref_j = 1, "j.P"
    axis = rng.uniform(-1, 1, size=2)
    u_local = axis / np.linalg.norm(axis)
    offset = float(rng.uniform(-1, 1))
    length = float(rng.uniform(0.5, 1.5))
    if kind == "revolute":
        joint = md.Revolute("J", ref_i, ref_j)

        def exact(q, qd):
            return revolute(q, qd, bi, s_i, bj, sj)

    elif kind == "weld":
        joint = md.Weld("J", ref_i, ref_j, angle=offset)

        def exact(q, qd):
            Phi, J, gam = revolute(q, qd, bi, s_i, bj, sj)
            Ja, ga = relative_angle(bi, bj, offset)
            _, pi, _, _ = parts(q, qd, bi)
            rel = q[3 * bj + 2] - pi - offset
            return np.append(Phi, rel), np.vstack([J, Ja]), np.append(gam, ga)

    elif kind in ("translational", "pin_in_slot"):
        cls = md.Translational if kind == "translational" else md.PinInSlot
        kw = {"angle": offset} if kind == "translational" else {}
        joint = cls("J", ref_i, ref_j, axis=axis, **kw)

        def exact(q, qd):
            Phi, J, gam = slot_normal(q, qd, bi, s_i, bj, sj, u_local)
            if kind == "pin_in_slot":
                return Phi, J, gam
            Ja, ga = relative_angle(bi, bj, offset)
            _, pi, _, _ = parts(q, qd, bi)
            rel = q[3 * bj + 2] - pi - offset
            return np.append(Phi, rel), np.vstack([J, Ja]), np.append(gam, ga)

    elif kind == "distance":
        joint = md.Distance("J", ref_i, ref_j, length=length)

        def exact(q, qd):
            return distance(q, qd, bi, s_i, bj, sj, length)

    else:
        raise AssertionError(kind)
    model = md.Model(bodies, joints=[joint], ground=ground)
    return Constraints.of(model), exact


def driver_case(kind, rng):
    """A model with one driver of ``kind`` and its closed form ``(q, qd, t) -> (Phi, Phi_q,
    Phi_t, gamma)``."""
    bodies, ground, si, sj, _ = two_bodies(rng)
    law = md.Harmonic(LAW[0], LAW[1], phase=LAW[2], offset=LAW[3])
    if kind == "coordinate_phi":
        driver = md.CoordinateDriver("D", "j", "phi", law=law)

        def exact(q, qd, t):
            J = np.zeros((1, 6))
            J[0, 5] = 1.0
            f, fd, fdd = law_values(t)
            return np.array([q[5] - f]), J, np.array([-fd]), np.array([fdd])

    elif kind == "coordinate_x":
        driver = md.CoordinateDriver("D", "i", "x", law=law)

        def exact(q, qd, t):
            J = np.zeros((1, 6))
            J[0, 0] = 1.0
            f, fd, fdd = law_values(t)
            return np.array([q[0] - f]), J, np.array([-fd]), np.array([fdd])

    elif kind in ("point_x", "point_y"):
        k = 0 if kind == "point_x" else 1
        driver = md.PointDriver("D", "j.P", "xy"[k], law=law)

        def exact(q, qd, t):
            r, p, _, w = parts(q, qd, 1)
            J = np.zeros((1, 6))
            J[0, 3:6] = np.concatenate([I2[k], [(B(p) @ sj)[k]]])
            f, fd, fdd = law_values(t)
            gam = (A(p) @ sj)[k] * w**2 + fdd
            return np.array([(r + A(p) @ sj)[k] - f]), J, np.array([-fd]), np.array([gam])

    elif kind == "relative_angle":
        driver = md.RelativeAngleDriver("D", "i", "j", law=law)

        def exact(q, qd, t):
            J, _ = relative_angle(0, 1, 0.0)
            f, fd, fdd = law_values(t)
            return np.array([q[5] - q[2] - f]), J, np.array([-fd]), np.array([fdd])

    elif kind == "distance":
        driver = md.DistanceDriver("D", "i.P", "j.P", law=law)

        def exact(q, qd, t):
            f, fd, fdd = law_values(t)
            Phi, J, gam = distance(q, qd, 0, si, 1, sj, f)
            return Phi, J, np.array([-fd]), gam + fdd

    else:
        raise AssertionError(kind)
    model = md.Model(bodies, drivers=[driver], ground=ground)
    return Constraints.of(model), exact


JOINTS = ["revolute", "weld", "translational", "pin_in_slot", "distance"]
DRIVERS = ["coordinate_phi", "coordinate_x", "point_x", "point_y", "relative_angle", "distance"]


@pytest.mark.parametrize("to_ground", [False, True], ids=["body-body", "ground-body"])
@pytest.mark.parametrize("kind", JOINTS)
def test_joint_equations(kind, to_ground):
    rng = np.random.default_rng([RNG_SEED, JOINTS.index(kind), int(to_ground)])
    c, exact = joint_case(kind, rng, to_ground)
    for _ in range(3):
        q, qd, t = state(rng)
        Phi, Phi_q, Phi_t, gamma = evaluate(c, q, qd, t)
        Phi_x, Phi_q_x, gamma_x = exact(q, qd)
        assert Phi.shape == Phi_x.shape == (c.m,)
        np.testing.assert_allclose(Phi, Phi_x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(Phi_q, Phi_q_x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(
            gamma, gamma_x, rtol=0, atol=1e-12 * max(1, np.abs(gamma_x).max())
        )
        np.testing.assert_array_equal(Phi_t, np.zeros(c.m))
        # and against finite differences of Phi itself
        np.testing.assert_allclose(Phi_q, fd_jacobian(c, q, t), rtol=0, atol=1e-8)
        np.testing.assert_allclose(gamma, fd_gamma(c, q, qd, t), rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("kind", DRIVERS)
def test_driver_equations(kind):
    rng = np.random.default_rng([RNG_SEED, 100 + DRIVERS.index(kind)])
    c, exact = driver_case(kind, rng)
    for _ in range(3):
        q, qd, t = state(rng)
        Phi, Phi_q, Phi_t, gamma = evaluate(c, q, qd, t)
        Phi_x, Phi_q_x, Phi_t_x, gamma_x = exact(q, qd, t)
        np.testing.assert_allclose(Phi, Phi_x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(Phi_q, Phi_q_x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(Phi_t, Phi_t_x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(gamma, gamma_x, rtol=0, atol=1e-12)
        np.testing.assert_allclose(Phi_q, fd_jacobian(c, q, t), rtol=0, atol=1e-8)
        np.testing.assert_allclose(Phi_t, fd_phi_t(c, q, t), rtol=0, atol=1e-8)
        np.testing.assert_allclose(gamma, fd_gamma(c, q, qd, t), rtol=1e-6, atol=1e-6)


def test_sparsity_pattern_covers_the_jacobian():
    """``Constraints.pattern`` (used to partition coordinates) marks every nonzero entry."""
    rng = np.random.default_rng(RNG_SEED + 1)
    bodies, ground, *_ = two_bodies(rng)
    bodies.append(md.Body("k", points={"P": (0.3, 0.1)}))
    model = md.Model(
        bodies,
        joints=[md.Revolute("R", "ground.G", "i.P"), md.Distance("L", "i.P", "k.P", length=1.0)],
        drivers=[md.RelativeAngleDriver("D", "j", "k", law=0.0)],
        ground=ground,
    )
    c = Constraints.of(model)
    q = rng.uniform(-1, 1, size=9)
    J = evaluate(c, q, np.zeros(9), 0.0)[1]
    P = c.pattern()
    assert P.shape == J.shape == (4, 9)
    assert not np.any((J != 0) & ~P)
    assert P[:2, 3:].sum() == 0  # the ground revolute touches body i only


def test_translational_axis_is_normalised_and_fixed_in_body_i():
    """The slot axis ``(3, 4)`` acts as the unit vector ``(0.6, 0.8)`` rotating with body i."""
    model = md.Model(
        [md.Body("i"), md.Body("j")],
        joints=[md.Translational("T", "i", "j", axis=(3.0, 4.0))],
    )
    c = Constraints.of(model)
    # body i turned by 90 deg: its axis points along (-0.8, 0.6); j displaced along it.
    q = np.array([0.0, 0.0, np.pi / 2, -0.8 * 2.5, 0.6 * 2.5, np.pi / 2])
    np.testing.assert_allclose(np.asarray(c(q, 0.0)), [0.0, 0.0], atol=1e-15)
    q[3] += 0.1  # off the axis by 0.1 along x: normal distance 0.1 * |u_y| = 0.06
    np.testing.assert_allclose(abs(float(c(q, 0.0)[0])), 0.06, rtol=1e-12)
