"""Planar kinematics of one body: rotation, global points and vectors.

Coordinates of body ``b`` are ``q[3b:3b+3] = [x, y, phi]`` (frame origin, best placed at the
centre of mass, and rotation angle [rad]). The ground has index ``GROUND = -1`` and fixed
coordinates ``[0, 0, 0]``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

GROUND = -1


def pose(q, b: int):
    """``(r, phi)`` of body ``b``: r (2,) [length], phi scalar [rad]; zeros for the ground."""
    if b == GROUND:
        return jnp.zeros(2, dtype=q.dtype), jnp.zeros((), dtype=q.dtype)
    return q[3 * b : 3 * b + 2], q[3 * b + 2]


def rot(phi):
    """Rotation matrix ``A(phi)``, (2, 2)."""
    c, s = jnp.cos(phi), jnp.sin(phi)
    return jnp.array([[c, -s], [s, c]])


def point(q, b: int, s):
    """Global position (2,) of the point with body-frame coordinates ``s`` (2,) on body ``b``."""
    r, phi = pose(q, b)
    return r + rot(phi) @ s


def vector(q, b: int, u):
    """Global components (2,) of the body-frame vector ``u`` (2,) of body ``b``."""
    _, phi = pose(q, b)
    return rot(phi) @ u


def angle(q, b: int):
    """Rotation angle of body ``b`` [rad]."""
    return pose(q, b)[1]


def cross(a, b):
    """z component of the planar cross product ``a x b``."""
    return a[0] * b[1] - a[1] * b[0]


def static_direction(value):
    """A direction given as the name of a body vector (kept as is) or as numbers, stored as a
    tuple of floats: static fields must be hashable, which NumPy and JAX arrays are not."""
    if isinstance(value, str):
        return value
    return tuple(float(x) for x in np.ravel(np.asarray(value, dtype=float)))
