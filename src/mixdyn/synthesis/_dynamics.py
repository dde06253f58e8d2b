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

with ``G_i`` each link's centre of mass and ``phi_i`` its angle from the implicit assembly of
:mod:`._fourbar` (derivatives by ``jax.jvp`` through it). It is the driver effort of
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


def _centres(fb: FourBar, inertia: dict, theta2):
    """Each link's centre of mass (3, 2) and angle (3,) at ``theta2`` (crank, coupler,
    rocker)."""
    o2, o4 = fb.pivots()
    phi2 = fb.theta0 + theta2
    phi3, phi4 = link_angles(fb, theta2)
    a = fb.crank_pin(theta2)
    g = jnp.stack(
        [
            o2 + _rot(phi2, inertia["crank"][1]),
            a + _rot(phi3, inertia["coupler"][1]),
            o4 + _rot(phi4, inertia["rocker"][1]),
        ]
    )
    return g, jnp.stack([phi2, phi3, phi4])


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
    m = jnp.stack([inertia[k][0] for k in ("crank", "coupler", "rocker")])
    j = jnp.stack([inertia[k][2] for k in ("crank", "coupler", "rocker")])
    grav = jnp.asarray(masses.gravity, dtype=jnp.float64)

    def energy(t):
        (g, _), (dg, dphi) = jax.jvp(lambda s: _centres(fb, inertia, s), (t,), (1.0,))
        kinetic = 0.5 * speed**2 * jnp.sum(m * jnp.sum(dg**2, axis=1) + j * dphi**2)
        return kinetic - jnp.sum(m * (g @ grav))

    def torque(t):
        return jax.jvp(energy, (t,), (jnp.ones_like(t),))[1]

    return jax.vmap(torque)(jnp.asarray(theta2, dtype=jnp.float64))


__all__ = ["Masses", "link_inertia", "motor_torque"]
