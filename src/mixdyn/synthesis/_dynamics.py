"""The links' inertia of a synthesized four-bar and the motor torque that turns it.

A candidate's links are bars of one linear density (kg per unit length): the crank ``O2 A``,
the rocker ``O4 B`` and the coupler, a rigid triangle of bars ``A B``, ``A C``, ``B C``, with an
optional payload (a point mass) at the coupler point ``C``. Their masses, centres of mass and
inertias follow the candidate's dimensions, so that a search can trade length for torque.

The motor torque of a crank turned at a constant speed ``Omega`` without friction is the
derivative of the mechanical energy by the input angle (power balance,
``tau Omega = dE/dt``)::

    E(theta2) = Omega^2 / 2 * sum_i (m_i |dG_i/dtheta2|^2 + J_i (dphi_i/dtheta2)^2)
                - sum_i m_i g . G_i,                       tau = dE/dtheta2,

with ``G_i`` each link's centre of mass and ``phi_i`` its angle from the assembly of
:mod:`._fourbar`; ``tau = Omega^2 sum_i (m_i G_i' . G_i'' + J_i phi_i' phi_i'') - sum_i m_i g .
G_i'`` in closed form, the rates ``phi_i'``, ``phi_i''`` from the closure equations
differentiated by the input angle (:func:`link_rates`), so that a search differentiates an
explicit function once instead of the assembly three times. It is the driver effort of
mixdyn's inverse dynamics of the same mechanism (checked in the tests against
:func:`mixdyn.inverse` of :func:`~.build.four_bar_model`).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp

from ._fourbar import FourBar, link_angles


@dataclasses.dataclass(frozen=True)
class Masses:
    """How a candidate's links weigh.

    Attributes:
        density: the bars' linear density [mass / length].
        payload: a point mass at the coupler point [mass].
        gravity: (2,) the acceleration of gravity [length / time**2].
    """

    density: float = 1.0
    payload: float = 0.0
    gravity: tuple[float, float] = (0.0, -9.81)


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


def link_inertia(fb: FourBar, masses: Masses) -> dict[str, tuple]:
    """Each link's ``(mass, centre of mass (2,) in the link's frame, inertia about it)``.

    The frames: the crank's from ``O2`` along ``O2 -> A``, the coupler's from ``A`` along
    ``A -> B``, the rocker's from ``O4`` along ``O4 -> B`` [mass, length, mass * length**2].
    """
    z = jnp.zeros(2)
    ex = jnp.array([1.0, 0.0])
    crank = _bars([(z, fb.r2 * ex)], masses.density)
    rocker = _bars([(z, fb.r4 * ex)], masses.density)
    b, c = fb.r3 * ex, jnp.stack([fb.rcx, fb.rcy])
    m3, g3, j3 = _bars([(z, b), (z, c), (b, c)], masses.density)
    if masses.payload:
        mp = masses.payload
        g = (m3 * g3 + mp * c) / (m3 + mp)
        j3 = j3 + m3 * jnp.sum((g3 - g) ** 2) + mp * jnp.sum((c - g) ** 2)
        m3, g3 = m3 + mp, g
    return {"crank": crank, "coupler": (m3, g3, j3), "rocker": rocker}


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
    det = jnp.where(jnp.abs(det) < 1e-12, jnp.where(det < 0, -1e-12, 1e-12), det)
    inv = jnp.array([[m[1, 1], -m[0, 1]], [-m[1, 0], m[0, 0]]]) / det
    d = inv @ (-fb.r2 * n2)
    dd = inv @ (fb.r2 * e2 + fb.r3 * e3 * d[0] ** 2 - fb.r4 * e4 * d[1] ** 2)
    return jnp.stack([phi3, phi4]), d, dd


def _torque_one(fb: FourBar, inertia: dict, grav, theta2, speed):
    """The motor torque at one input angle: ``dE/dtheta2`` in closed form (module docstring)
    from the links' angular rates and their centres' first and second derivatives."""
    (phi3, phi4), (w3, w4), (a3, a4) = link_rates(fb, theta2)
    phi2 = fb.theta0 + theta2
    e2 = jnp.stack([jnp.cos(phi2), jnp.sin(phi2)])
    # The crank pin A: A' = r2 n2, A'' = -r2 e2; a centre g in a link's frame turning with
    # phi: (R g)' = phi' perp(R g), (R g)'' = phi'' perp(R g) - phi'^2 R g.
    g2 = _rot(phi2, inertia["crank"][1])
    g3 = _rot(phi3, inertia["coupler"][1])
    g4 = _rot(phi4, inertia["rocker"][1])
    d = jnp.stack([_perp(g2), fb.r2 * _perp(e2) + w3 * _perp(g3), w4 * _perp(g4)])
    dd = jnp.stack([-g2, -fb.r2 * e2 + a3 * _perp(g3) - w3**2 * g3, a4 * _perp(g4) - w4**2 * g4])
    m = jnp.stack([inertia[k][0] for k in ("crank", "coupler", "rocker")])
    j = jnp.stack([inertia[k][2] for k in ("crank", "coupler", "rocker")])
    w, a = jnp.stack([1.0, w3, w4]), jnp.stack([0.0, a3, a4])
    return speed**2 * jnp.sum(m * jnp.sum(d * dd, axis=1) + j * w * a) - jnp.sum(m * (d @ grav))


@eqx.filter_jit
def motor_torque(fb: FourBar, masses: Masses, theta2, speed) -> jax.Array:
    """The torque on the crank that turns it at ``speed`` through ``theta2`` (compiled once
    per shape and ``masses``).

    Args:
        fb: the four-bar (unbatched).
        masses: how its links weigh.
        theta2: (K,) input angles [rad].
        speed: the crank's constant speed [rad / time].

    Returns:
        (K,) the motor torque [mass * length**2 / time**2], positive along ``theta2``.
    """
    inertia = link_inertia(fb, masses)
    grav = jnp.asarray(masses.gravity, dtype=jnp.float64)
    theta2 = jnp.asarray(theta2, dtype=jnp.float64)
    return jax.vmap(lambda t: _torque_one(fb, inertia, grav, t, speed))(theta2)


__all__ = ["Masses", "link_inertia", "link_rates", "motor_torque"]
