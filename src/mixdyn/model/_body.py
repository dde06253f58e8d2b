"""Rigid bodies and the ground."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._arrays import as_f64
from ..errors import ModelError

GROUND_NAME = "ground"


def _points(points, owner: str) -> dict[str, jax.Array]:
    out = {}
    for key, value in dict(points or {}).items():
        arr = np.asarray(value, dtype=float)
        if arr.shape != (2,) or not np.all(np.isfinite(arr)):
            raise ModelError(
                f"point {key!r} must be two finite numbers (x, y), got {value!r}", owner
            )
        out[str(key)] = as_f64(arr)
    return out


#: The least mass and inertia of a body (0: a body for kinematics only).
INERTIAL_AT_LEAST = 0.0


def check_inertial(label: str, value, body: str) -> None:
    """Raise a :class:`ModelError` unless a body's ``mass`` or ``inertia`` (``label``) is
    finite and ``>=`` :data:`INERTIAL_AT_LEAST` (an array: every entry, e.g. a sweep's
    candidates)."""
    a = np.asarray(value, dtype=float)
    if not (np.all(np.isfinite(a)) and np.all(a >= INERTIAL_AT_LEAST)):
        shown = f"{float(a.ravel()[0]):g}" if a.size == 1 else str(a.tolist())
        raise ModelError(
            f"{label} must be a finite number >= {INERTIAL_AT_LEAST:g}, got {shown}", body
        )


class Ground(eqx.Module):
    """The fixed frame. Its points are given in global coordinates [length].

    Attributes:
        points: named points, each (2,) [length].
    """

    points: dict[str, jax.Array]
    name: str = eqx.field(static=True, default=GROUND_NAME)

    def __init__(self, points=None):
        self.points = _points(points, GROUND_NAME)
        self.name = GROUND_NAME


class Body(eqx.Module):
    """A rigid body in the plane, with absolute coordinates ``[x, y, phi]``.

    The body frame's origin is the centre of mass (inertia is taken about it).

    Attributes:
        name: unique name.
        mass: mass [mass]; 0 is allowed for kinematics only.
        inertia: moment of inertia about the centre of mass [mass * length**2].
        q0: (3,) rough initial ``[x, y, phi]`` [length, length, rad]; assembly corrects it.
        points: named points in the body frame, each (2,) [length]. The frame origin is
            always available as the point named by the body alone (``"crank"``).
        vectors: named unit vectors in the body frame, each (2,), e.g. a slider axis.
    """

    name: str = eqx.field(static=True)
    mass: jax.Array
    inertia: jax.Array
    q0: jax.Array
    points: dict[str, jax.Array]
    vectors: dict[str, jax.Array]

    def __init__(self, name, mass=0.0, inertia=0.0, q0=(0.0, 0.0, 0.0), points=None, vectors=None):
        if not isinstance(name, str) or not name or "." in name:
            raise ModelError(f"body name must be a non-empty string without '.', got {name!r}")
        if name == GROUND_NAME:
            raise ModelError(f"{GROUND_NAME!r} is reserved for the fixed frame")
        self.name = name
        for label, v in (("mass", mass), ("inertia", inertia)):
            float(v)  # one number
            check_inertial(label, v, name)
        self.mass = as_f64(float(mass))
        self.inertia = as_f64(float(inertia))
        q0 = np.asarray(q0, dtype=float)
        if q0.shape != (3,) or not np.all(np.isfinite(q0)):
            raise ModelError("q0 must be three finite numbers [x, y, phi]", name)
        self.q0 = as_f64(q0)
        self.points = _points(points, name)
        vecs = _points(vectors, name)
        for key, v in vecs.items():
            if float(jnp.linalg.norm(v)) == 0.0:
                raise ModelError(f"vector {key!r} has zero length", name)
        self.vectors = vecs
