"""Planar kinematics of one body: rotation, global points and vectors.

Coordinates of body ``b`` are ``q[3b:3b+3] = [x, y, phi]`` (frame origin, best placed at the
centre of mass, and rotation angle [rad]). The ground has index ``GROUND = -1`` and fixed
coordinates ``[0, 0, 0]``.
"""

from __future__ import annotations

import contextlib
import contextvars

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


#: Whether the elements being traced are evaluated vectorized over the elements of a kind (the
#: sparse path's ``vmap``), set by :func:`vectorized_elements`.
_VECTORIZED = contextvars.ContextVar("mixdyn_vectorized_elements", default=False)


@contextlib.contextmanager
def vectorized_elements():
    """Within it, :func:`rotate` traces the batched 2 x 2 matrix product (one kernel for all
    the elements of a kind under ``vmap``); outside it, the products written out element-wise.

    Measured (CPU time per step): element-wise, a 4-link chain's RK4 step takes 18 us against
    25 us with the matrix product (each product is a call of its own, most of the step's
    calls), while vectorized over 16 joints the element-wise form takes a generalized-alpha
    step from 48 to 78 us."""
    token = _VECTORIZED.set(True)
    try:
        yield
    finally:
        _VECTORIZED.reset(token)


def rotate(phi, u):
    """``A(phi) u`` (2,) for ``u`` (2,) (see :func:`vectorized_elements` for its form)."""
    if _VECTORIZED.get():
        return rot(phi) @ u
    c, s = jnp.cos(phi), jnp.sin(phi)
    u = jnp.asarray(u)
    return jnp.stack([c * u[0] - s * u[1], s * u[0] + c * u[1]])


def point(q, b: int, s):
    """Global position (2,) of the point with body-frame coordinates ``s`` (2,) on body ``b``."""
    r, phi = pose(q, b)
    return r + rotate(phi, s)


def vector(q, b: int, u):
    """Global components (2,) of the body-frame vector ``u`` (2,) of body ``b``."""
    _, phi = pose(q, b)
    return rotate(phi, u)


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
