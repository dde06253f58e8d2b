"""The links' inertia of a synthesized linkage and the motor torque that turns it.

A candidate's links are bars of one linear density (kg per unit length): the crank ``O2 A``,
the rocker ``O4 B`` (a four-bar's) and the coupler (a slider-crank's rod), a rigid triangle of
bars ``A B``, ``A C``, ``B C``, with an optional payload (a point mass) at the coupler point
``C``; a slider-crank's slider is a point mass at its pin ``B``; a six-bar's coupler and
rocker are the triangles of the points they carry (``A B D`` the coupler where it carries
``D``, ``O4 B F`` a Watt I's rocker, ``O4 B D`` a Watt II's; a bar otherwise; a Stephenson
I's crank the triangle ``O2 A D``), its tracer the
triangle ``D E C`` with the payload, its follower a bar. Their masses, centres of mass and inertias
follow the candidate's dimensions, so that a search can trade length for torque.

The motor torque of a crank turned at a constant speed ``Omega`` without friction is the
derivative of the mechanical energy by the input angle (power balance,
``tau Omega = dE/dt``)::

    E(theta2) = Omega^2 / 2 * sum_i (m_i |dG_i/dtheta2|^2 + J_i (dphi_i/dtheta2)^2)
                - sum_i m_i g . G_i,                       tau = dE/dtheta2,

with ``G_i`` each link's centre of mass and ``phi_i`` its angle from the assembly of
:mod:`._fourbar` (:mod:`._slidercrank`); ``tau = Omega^2 sum_i (m_i G_i' . G_i'' + J_i phi_i'
phi_i'') - sum_i m_i g . G_i'`` in closed form, the rates ``phi_i'``, ``phi_i''`` (a slider's
``s'``, ``s''``) from the closure equations differentiated by the input angle
(:func:`link_rates`, :func:`slider_rates`), so that a search differentiates an explicit
function once instead of the assembly three times; a six-bar's rates are its closed form's
first and second derivatives in forward mode (each loop's by the closure's implicit rule).
It is the driver effort of mixdyn's inverse dynamics of the same mechanism (checked in the
tests against :func:`mixdyn.inverse` of :func:`~.build.four_bar_model`,
:func:`~.build.slider_crank_model` and :func:`~.build.six_bar_model`).

The shaking force and moment (Berkof and Lowen's, 1969) are what the moving links' inertia
passes to the frame, gravity left out: with the crank at the constant speed ``Omega`` each
centre's acceleration is ``Omega^2 G_i''`` and each link's angular acceleration
``Omega^2 phi_i''``, and::

    F_sh = -Omega^2 sum_i m_i G_i'',
    M_sh = -Omega^2 sum_i (J_i phi_i'' + (G_i - O2) x m_i G_i''),

the moment about the crank's pivot ``O2`` (the motor's reaction included): the ground
pivots' reactions on the frame, and the motor's, summed (:func:`shaking`; checked in the
tests against the reactions of :func:`mixdyn.inverse`).

The joint reactions (:func:`reactions`) follow from each link's Newton-Euler equations at the
same accelerations, gravity included: ``F_in - F_out + m_i g = m_i a_i`` and the moments about
the link's centre, solved for the pins' forces and the motor's torque (a four-bar: the forces
at ``O2``, ``A``, ``B``, ``O4`` and the torque, 9 unknowns in 9 equations; a slider-crank: at
``O2``, ``A``, ``B``, the slide's normal force and the torque, 8 in 8, its slider a point mass
at ``B``; a six-bar: at its seven joints and the torque, 15 in 15). Each is the force that the
body before the joint exerts on the body after it (the ground on the crank at ``O2``, the crank
on the coupler at ``A``, the coupler on the rocker or the slider at ``B``, the ground on the
rocker at ``O4`` or on the slider at the slide), as mixdyn's ``{joint}.Fx``, ``.Fy`` columns
are.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp

from ._fourbar import FourBar, link_angles
from ._linkage import Linkage, guarded
from ._sixbar import SixBar
from ._slidercrank import SliderCrank, rod_and_slider
from ._stephenson import StephensonI, StephensonIII
from ._watt import WattI, WattII


@dataclasses.dataclass(frozen=True)
class Masses:
    """How a candidate's links weigh.

    Attributes:
        density: the bars' linear density [mass / length].
        payload: a point mass at the coupler point [mass].
        gravity: (2,) the acceleration of gravity [length / time**2].
        slider: a slider-crank's slider, a point mass at its pin [mass] (> 0 for the
            slider-crank's model: :func:`~.build.slider_crank_model`).
    """

    density: float = 1.0
    payload: float = 0.0
    gravity: tuple[float, float] = (0.0, -9.81)
    slider: float = 0.0


def _bars(ends, density):
    """Mass, centre of mass (2,) and inertia about it of bars ``[(p, q), ...]`` (uniform,
    thin) of linear density ``density``."""
    ms, cs, js = [], [], []
    for p, q in ends:
        length = jnp.sqrt(jnp.sum((q - p) ** 2))
        ms.append(density * length)
        cs.append(0.5 * (p + q))
        js.append(density * length**3 / 12.0)
    m = sum(ms)
    c = sum(mi * ci for mi, ci in zip(ms, cs, strict=True)) / m
    j = sum(ji + mi * jnp.sum((ci - c) ** 2) for mi, ci, ji in zip(ms, cs, js, strict=True))
    return m, c, j


def link_inertia(fb: Linkage, masses: Masses) -> dict[str, tuple]:
    """Each link's ``(mass, centre of mass (2,) in the link's frame, inertia about it)``.

    The frames: the crank's from ``O2`` along ``O2 -> A``, the coupler's (a slider-crank's
    ``rod``) from ``A`` along ``A -> B``, a four-bar's rocker's from ``O4`` along
    ``O4 -> B``, a slider-crank's slider's at ``B`` along the slide [mass, length,
    mass * length**2]; the slider's inertia a nominal block's, :func:`~.build.slider_crank_model`).
    """
    z = jnp.zeros(2)
    ex = jnp.array([1.0, 0.0])
    if isinstance(fb, SixBar):
        return _six_bar_inertia(fb, masses)
    crank = _bars([(z, fb.r2 * ex)], masses.density)
    coupler = _coupler(fb, masses)
    if isinstance(fb, SliderCrank):
        m = jnp.asarray(masses.slider, dtype=jnp.float64)
        return {"crank": crank, "rod": coupler, "slider": (m, z, m * (fb.r3 / 10) ** 2 / 6)}
    rocker = _bars([(z, fb.r4 * ex)], masses.density)
    return {"crank": crank, "coupler": coupler, "rocker": rocker}


def _coupler(fb: Linkage, masses: Masses):
    """The coupler's triangle of bars and payload (:func:`link_inertia`)."""
    return _plate(fb.r3, jnp.stack([fb.rcx, fb.rcy]), masses.density, masses.payload)


def _plate(length, c, density, payload):
    """A link from its frame's origin to ``(length, 0)`` with a third point ``c`` (2,): the
    triangle of bars through them, a point mass ``payload`` at ``c``."""
    z = jnp.zeros(2)
    b = length * jnp.array([1.0, 0.0])
    m3, g3, j3 = _bars([(z, b), (z, c), (b, c)], density)
    if payload:
        g = (m3 * g3 + payload * c) / (m3 + payload)
        j3 = j3 + m3 * jnp.sum((g3 - g) ** 2) + payload * jnp.sum((c - g) ** 2)
        m3, g3 = m3 + payload, g
    return m3, g3, j3


def _six_bar_inertia(sb: SixBar, masses: Masses) -> dict[str, tuple]:
    """A six-bar's links (:func:`link_inertia`): the crank, the coupler and the rocker each
    the triangle of its two pins and the third point it carries (``D``, or a Watt I rocker's
    ``F``), or a bar where it carries none; the tracer the triangle ``D E C`` with the
    payload at ``C``, the follower a bar; the frames as the model's
    (:func:`~.build.six_bar_model`: from ``O2``, ``A``, ``O4``, ``D``, ``X`` along their
    links)."""
    z, ex = jnp.zeros(2), jnp.array([1.0, 0.0])
    rho = masses.density
    third = {sb.DYAD_BODY: jnp.stack([sb.dx, sb.dy])}
    if sb.PIVOT_BODY == "rocker":
        third["rocker"] = jnp.stack([sb.fx, sb.fy])

    def link(name, length):
        if name in third:
            return _plate(length, third[name], rho, 0.0)
        return _bars([(z, length * ex)], rho)

    return {
        "crank": link("crank", sb.r2),
        "coupler": link("coupler", sb.r3),
        "rocker": link("rocker", sb.r4),
        "tracer": _plate(sb.r5, jnp.stack([sb.rcx, sb.rcy]), rho, masses.payload),
        "follower": _bars([(z, sb.r6 * ex)], rho),
    }


def _rot(phi, v):
    c, s = jnp.cos(phi), jnp.sin(phi)
    return jnp.stack([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _perp(v):
    """``v`` turned by +90 degrees."""
    return jnp.stack([-v[1], v[0]])


def link_rates(fb: FourBar, theta2):
    """The coupler's and rocker's angles and their first and second derivatives by the input
    angle, from the closure equations differentiated once and twice (linear solves).

    With ``e_k = (cos phi_k, sin phi_k)``, ``n_k = perp(e_k)``, the loop
    ``r2 e2 + r3 e3 - r1 e1 - r4 e4 = 0`` gives ``M (phi3', phi4') = -r2 n2`` and
    ``M (phi3'', phi4'') = r2 e2 + r3 e3 phi3'^2 - r4 e4 phi4'^2`` with ``M = [r3 n3, -r4 n4]``.

    Returns:
        ``(phi, d, dd)``: each (2,) for (coupler, rocker) [rad, rad/rad, rad/rad**2].
    """
    phi3, phi4 = link_angles(fb, theta2)
    phi2 = fb.theta0 + theta2
    e2, e3, e4 = (jnp.stack([jnp.cos(p), jnp.sin(p)]) for p in (phi2, phi3, phi4))
    n2, n3, n4 = _perp(e2), _perp(e3), _perp(e4)
    m = jnp.stack([fb.r3 * n3, -fb.r4 * n4], axis=1)
    det = m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    det = guarded(det, 1e-12)
    inv = jnp.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]]) / det
    d = inv @ (-fb.r2 * n2)
    dd = inv @ (fb.r2 * e2 + fb.r3 * e3 * d[0] ** 2 - fb.r4 * e4 * d[1] ** 2)
    return jnp.stack([phi3, phi4]), d, dd


def slider_rates(sc: SliderCrank, theta2):
    """The rod's angle and the slider's position along the slide, and their first and second
    derivatives by the input angle, from the closure equations differentiated once and twice.

    With ``d`` the slide's direction, the loop ``A + r3 e3 - P0 - s d = 0`` gives
    ``M (phi3', s') = -r2 n2`` and ``M (phi3'', s'') = r2 e2 + r3 e3 phi3'^2`` with
    ``M = [r3 n3, -d]``.

    Returns:
        ``(x, d, dd)``: each (2,) for (rod angle, slider position) [rad, length; per rad,
        per rad**2].
    """
    phi3, s = rod_and_slider(sc, theta2)
    phi2 = sc.theta0 + theta2
    e2, e3, d = (jnp.stack([jnp.cos(p), jnp.sin(p)]) for p in (phi2, phi3, sc.theta0))
    m = jnp.stack([sc.r3 * _perp(e3), -d], axis=1)
    det = guarded(m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0], 1e-12)
    inv = jnp.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]]) / det
    rate = inv @ (-sc.r2 * _perp(e2))
    acc = inv @ (sc.r2 * e2 + sc.r3 * e3 * rate[0] ** 2)
    return jnp.stack([phi3, s]), rate, acc


def _crank_and_coupler(lk: Linkage, inertia: dict, theta2, phi3, w3, a3):
    """The crank's and the coupler's centre velocities and accelerations by the input angle,
    ``(d (2, 2), dd (2, 2))``: the crank pin ``A' = r2 n2``, ``A'' = -r2 e2``; a centre ``g``
    in a link's frame turning with ``phi``: ``(R g)' = phi' perp(R g)``, ``(R g)'' = phi''
    perp(R g) - phi'^2 R g``."""
    phi2 = lk.theta0 + theta2
    e2 = jnp.stack([jnp.cos(phi2), jnp.sin(phi2)])
    crank, coupler = (inertia[k] for k in list(inertia)[:2])
    g2 = _rot(phi2, crank[1])
    g3 = _rot(phi3, coupler[1])
    d = jnp.stack([_perp(g2), lk.r2 * _perp(e2) + w3 * _perp(g3)])
    dd = jnp.stack([-g2, -lk.r2 * e2 + a3 * _perp(g3) - w3**2 * g3])
    return d, dd


def _four_bar_rates(fb: FourBar, inertia: dict, theta2):
    """Each link's centre velocity and acceleration (3, 2) and angular rates (3,) by the
    input angle: crank, coupler, rocker."""
    (phi3, phi4), (w3, w4), (a3, a4) = link_rates(fb, theta2)
    d, dd = _crank_and_coupler(fb, inertia, theta2, phi3, w3, a3)
    g4 = _rot(phi4, inertia["rocker"][1])
    d = jnp.concatenate([d, (w4 * _perp(g4))[None]])
    dd = jnp.concatenate([dd, (a4 * _perp(g4) - w4**2 * g4)[None]])
    return d, dd, jnp.stack([1.0, w3, w4]), jnp.stack([0.0, a3, a4])


def _slider_crank_rates(sc: SliderCrank, inertia: dict, theta2):
    """Each link's centre velocity and acceleration (3, 2) and angular rates (3,) by the
    input angle: crank, rod, slider (translating along the slide)."""
    (phi3, _), (w3, v), (a3, acc) = slider_rates(sc, theta2)
    d, dd = _crank_and_coupler(sc, inertia, theta2, phi3, w3, a3)
    along = jnp.stack([jnp.cos(sc.theta0), jnp.sin(sc.theta0)])
    d = jnp.concatenate([d, (v * along)[None]])
    dd = jnp.concatenate([dd, (acc * along)[None]])
    return d, dd, jnp.stack([1.0, w3, 0.0]), jnp.stack([0.0, a3, 0.0])


def _six_bar_pose(sb: SixBar, inertia: dict, theta2):
    """A six-bar's links' centres of mass from ``O2`` (5, 2) [length] and angles (5,) [rad]
    at ``theta2``: crank, coupler, rocker, tracer, follower (frames from ``O2``, ``A``,
    ``O4``, ``D``, ``X``)."""
    j = sb.joints(theta2)
    origins = (j["O2"], j["A"], j["O4"], j["D"], j["X"])
    angles = jnp.stack([sb.theta0 + theta2, j["phi3"], j["phi4"], j["phi5"], j["phi6"]])
    g = jnp.stack([o - j["O2"] + _rot(a, v[1]) for o, a, v in
                   zip(origins, angles, inertia.values(), strict=True)])  # fmt: skip
    return g, angles


def _six_bar_rates(sb: SixBar, inertia: dict, theta2):
    """Each link's centre velocity and acceleration (5, 2) and angular rates (5,) by the
    input angle: the closed form's first and second derivatives in forward mode (each loop's
    derivatives the closure equations' implicit rule, :mod:`._sixbar`)."""

    def first(t):
        return jax.jvp(lambda s: _six_bar_pose(sb, inertia, s), (t,), (jnp.ones_like(t),))[1]

    theta2 = jnp.asarray(theta2, dtype=jnp.float64)
    (d, w), (dd, a) = jax.jvp(first, (theta2,), (jnp.ones_like(theta2),))
    return d, dd, w, a


#: Each linkage type's link rates (:func:`_torque_one`).
_RATES = {
    FourBar: _four_bar_rates,
    SliderCrank: _slider_crank_rates,
    StephensonI: _six_bar_rates,
    StephensonIII: _six_bar_rates,
    WattI: _six_bar_rates,
    WattII: _six_bar_rates,
}

#: The linkage types whose dynamics are computed here.
DYNAMICS = tuple(_RATES)


def _centres(lk: Linkage, inertia: dict, theta2) -> jax.Array:
    """Each link's centre of mass from the crank's pivot ``O2`` (3, 2) [length]: crank,
    coupler (rod), rocker (slider); a six-bar's five (:func:`_six_bar_pose`)."""
    if isinstance(lk, SixBar):
        return _six_bar_pose(lk, inertia, theta2)[0]
    phi2 = lk.theta0 + theta2
    e2 = jnp.stack([jnp.cos(phi2), jnp.sin(phi2)])
    crank, coupler, third = (v[1] for v in inertia.values())
    if isinstance(lk, SliderCrank):
        phi3, _ = rod_and_slider(lk, theta2)  # the angles alone, not their rates
        e3 = jnp.stack([jnp.cos(phi3), jnp.sin(phi3)])
        last = lk.r2 * e2 + lk.r3 * e3  # the slider's pin B
    else:
        phi3, phi4 = link_angles(lk, theta2)
        e1 = jnp.stack([jnp.cos(lk.theta0), jnp.sin(lk.theta0)])
        last = lk.r1 * e1 + _rot(phi4, third)
    return jnp.stack([_rot(phi2, crank), lk.r2 * e2 + _rot(phi3, coupler), last])


def _shaking_one(lk: Linkage, inertia: dict, _grav, theta2, speed):
    """The shaking force (2,) and moment about ``O2`` at one input angle (module docstring;
    gravity left out)."""
    _, dd, _, a = _RATES[type(lk)](lk, inertia, theta2)
    g = _centres(lk, inertia, theta2)
    m = jnp.stack([jnp.asarray(v[0], dtype=jnp.float64) for v in inertia.values()])
    j = jnp.stack([jnp.asarray(v[2], dtype=jnp.float64) for v in inertia.values()])
    acc, alpha = speed**2 * dd, speed**2 * a
    force = -jnp.sum(m[:, None] * acc, axis=0)
    moment = -jnp.sum(j * alpha + m * (g[:, 0] * acc[:, 1] - g[:, 1] * acc[:, 0]))
    return force, moment


#: A six-bar's four-bar joints (the bodies: crank, coupler, rocker, tracer, follower).
_SIX_BAR_JOINTS = (
    ("O2", -1, 0, False),
    ("A", 0, 1, False),
    ("B", 1, 2, False),
    ("O4", -1, 2, False),
)


def _six_bar_joints(cls: type[SixBar]) -> tuple:
    """A six-bar type's joints (:data:`JOINTS`): the four-bar's, ``D`` (on the coupler or
    the rocker), ``E``, and the follower's other end (``O6`` on the ground, ``F`` on the
    rocker)."""
    body = {"ground": -1, "crank": 0, "coupler": 1, "rocker": 2}
    end = "O6" if cls.PIVOT_BODY == "ground" else "F"
    return (
        *_SIX_BAR_JOINTS,
        ("D", body[cls.DYAD_BODY], 3, False),
        ("E", 3, 4, False),
        (end, body[cls.PIVOT_BODY], 4, False),
    )


#: Each linkage type's joints for :func:`reactions`: ``(name, body before, body after,
#: slide)`` with the bodies' places in :func:`link_inertia` (-1: the ground) and ``slide``
#: True for a frictionless slide (its force along the slide's normal only).
JOINTS = {
    FourBar: (("O2", -1, 0, False), ("A", 0, 1, False), ("B", 1, 2, False), ("O4", -1, 2, False)),
    SliderCrank: (
        ("O2", -1, 0, False),
        ("A", 0, 1, False),
        ("B", 1, 2, False),
        ("slide", -1, 2, True),
    ),
    StephensonI: _six_bar_joints(StephensonI),
    StephensonIII: _six_bar_joints(StephensonIII),
    WattI: _six_bar_joints(WattI),
    WattII: _six_bar_joints(WattII),
}


def _joint_points(lk: Linkage, theta2) -> jax.Array:
    """The joints' points from the crank's pivot (J, 2) [length], in :data:`JOINTS`' order (a
    slide's: the slider's pin)."""
    if isinstance(lk, SixBar):
        j = lk.joints(theta2)
        return jnp.stack([j[k] - j["O2"] for k in ("O2", "A", "B", "O4", "D", "E", "X")])
    phi2 = lk.theta0 + theta2
    a = lk.r2 * jnp.stack([jnp.cos(phi2), jnp.sin(phi2)])
    phi3 = lk.coupler_angle(theta2)
    b = a + lk.r3 * jnp.stack([jnp.cos(phi3), jnp.sin(phi3)])
    if isinstance(lk, SliderCrank):
        return jnp.stack([jnp.zeros(2), a, b, b])
    o4 = lk.r1 * jnp.stack([jnp.cos(lk.theta0), jnp.sin(lk.theta0)])
    return jnp.stack([jnp.zeros(2), a, b, o4])


def _reactions_one(lk: Linkage, inertia: dict, grav, theta2, speed):
    """The joints' forces (J, 2) and the motor's torque at one input angle (module
    docstring): each moving link's three Newton-Euler equations, one linear solve."""
    _, dd, _, alpha = _RATES[type(lk)](lk, inertia, theta2)
    acc, alpha = speed**2 * dd, speed**2 * alpha
    g = _centres(lk, inertia, theta2)
    p = _joint_points(lk, theta2)
    m = [jnp.asarray(v[0], dtype=jnp.float64) for v in inertia.values()]
    j = [jnp.asarray(v[2], dtype=jnp.float64) for v in inertia.values()]
    normal = _perp(jnp.stack([jnp.cos(lk.theta0), jnp.sin(lk.theta0)]))
    bases = [normal[:, None] if slide else jnp.eye(2) for *_, slide in JOINTS[type(lk)]]
    n = sum(b.shape[1] for b in bases) + 1  # the torque last
    nb = len(inertia)
    rows = [jnp.zeros((3, n)) for _ in range(nb)]
    at = 0
    for (_, before, after, _), basis, point in zip(JOINTS[type(lk)], bases, p, strict=True):
        k = basis.shape[1]
        for body, sign in ((after, 1.0), (before, -1.0)):
            if body < 0:
                continue
            r = point - g[body]
            block = jnp.concatenate([basis, (r[0] * basis[1] - r[1] * basis[0])[None]]) * sign
            rows[body] = rows[body].at[:, at : at + k].add(block)
        at += k
    rows[0] = rows[0].at[2, n - 1].set(1.0)  # the motor's torque on the crank
    rhs = [jnp.concatenate([m[i] * (acc[i] - grav), (j[i] * alpha[i])[None]]) for i in range(nb)]
    # A slider (a point mass at its pin) on a slide: its moment is the slide's, not solved for.
    keep = [slice(None)] * nb
    for _, _, after, slide in JOINTS[type(lk)]:
        if slide:
            keep[after] = slice(0, 2)
    matrix = jnp.concatenate([r[k] for r, k in zip(rows, keep, strict=True)])
    x = jnp.linalg.solve(matrix, jnp.concatenate([b[k] for b, k in zip(rhs, keep, strict=True)]))
    forces, at = [], 0
    for basis in bases:
        k = basis.shape[1]
        forces.append(basis @ x[at : at + k])
        at += k
    return jnp.stack(forces), x[-1]


@eqx.filter_jit
def reactions(lk: Linkage, masses: Masses, theta2, speed) -> tuple[jax.Array, jax.Array]:
    """The joint reactions and the motor's torque of a linkage whose crank turns at ``speed``
    through ``theta2``, gravity included (module docstring).

    Args:
        lk: the four-bar or slider-crank (unbatched).
        masses: how its links weigh.
        theta2: (K,) input angles [rad].
        speed: the crank's constant speed [rad / time].

    Returns:
        ``(forces (K, J, 2), torque (K,))``: the joints' forces in :data:`JOINTS`' order
        (``O2``, ``A``, ``B``, ``O4`` or the slide; a six-bar's seven) [mass * length /
        time**2] and the motor's torque [mass * length**2 / time**2] (:func:`motor_torque`'s).
    """
    return _over_angles(_reactions_one, lk, masses, theta2, speed)


@eqx.filter_jit
def shaking(lk: Linkage, masses: Masses, theta2, speed) -> tuple[jax.Array, jax.Array]:
    """The shaking force and moment of a linkage whose crank turns at ``speed`` through
    ``theta2`` (module docstring; gravity left out).

    Args:
        lk: the four-bar or slider-crank (unbatched).
        masses: how its links weigh.
        theta2: (K,) input angles [rad].
        speed: the crank's constant speed [rad / time].

    Returns:
        ``(force (K, 2), moment (K,))``: on the frame [mass * length / time**2], and about the
        crank's pivot ``O2`` [mass * length**2 / time**2].
    """
    return _over_angles(_shaking_one, lk, masses, theta2, speed)


def _torque_one(fb: Linkage, inertia: dict, grav, theta2, speed):
    """The motor torque at one input angle: ``dE/dtheta2`` in closed form (module docstring)
    from the links' angular rates and their centres' first and second derivatives."""
    d, dd, w, a = _RATES[type(fb)](fb, inertia, theta2)
    m = jnp.stack([jnp.asarray(v[0], dtype=jnp.float64) for v in inertia.values()])
    j = jnp.stack([jnp.asarray(v[2], dtype=jnp.float64) for v in inertia.values()])
    return speed**2 * jnp.sum(m * jnp.sum(d * dd, axis=1) + j * w * a) - jnp.sum(m * (d @ grav))


@eqx.filter_jit
def motor_torque(fb: Linkage, masses: Masses, theta2, speed) -> jax.Array:
    """The torque on the crank that turns it at ``speed`` through ``theta2`` (compiled once
    per shape and ``masses``).

    Args:
        fb: the four-bar or slider-crank (unbatched).
        masses: how its links weigh.
        theta2: (K,) input angles [rad].
        speed: the crank's constant speed [rad / time].

    Returns:
        (K,) the motor torque [mass * length**2 / time**2], positive along ``theta2``.
    """
    return _over_angles(_torque_one, fb, masses, theta2, speed)


def _over_angles(one, lk: Linkage, masses: Masses, theta2, speed):
    """``one(lk, inertia, gravity (2,), theta, speed)`` at each input angle of ``theta2``
    (K,), stacked along a first axis."""
    inertia = link_inertia(lk, masses)
    grav = jnp.asarray(masses.gravity, dtype=jnp.float64)
    theta2 = jnp.asarray(theta2, dtype=jnp.float64)
    return jax.vmap(lambda t: one(lk, inertia, grav, t, speed))(theta2)


__all__ = [
    "DYNAMICS",
    "JOINTS",
    "Masses",
    "link_inertia",
    "link_rates",
    "motor_torque",
    "reactions",
    "shaking",
    "slider_rates",
]
