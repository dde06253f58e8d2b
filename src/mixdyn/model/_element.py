"""The base of every named element (joint, driver, force) and name resolution."""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._arrays import as_f64
from ..errors import ModelError
from ._body import GROUND_NAME
from ._declare import check_declared
from ._geometry import GROUND, static_direction  # noqa: F401  (re-exported)


class Element(eqx.Module):
    """Something with a unique name that refers to bodies and points by name.

    Subclasses are created by the user with references (``"crank.B"``), then *bound* by the
    :class:`~mixdyn.Model`, which fills in body indices and point coordinates.
    """

    name: str = eqx.field(static=True)

    #: The fields holding body indices (filled by :meth:`bind`): the constraint set reads an
    #: element's bodies from a local vector through them (``mixdyn.equations``).
    body_fields: ClassVar[tuple[str, ...]] = ("b", "bi", "bj")

    def __check_init__(self):
        """Check the declared numbers: finite and in their declared ranges
        (:func:`~mixdyn.model._declare.check_declared`)."""
        check_declared(self)

    def bind(self, r: Resolver) -> Element:
        """Return a copy with every reference resolved (called by the model)."""
        return self

    def body_indices(self) -> tuple[int, ...]:
        """Indices of the moving bodies this element touches (its Jacobian columns)."""
        return ()


class Resolver:
    """Resolves names of bodies, points and vectors for one model, with clear errors."""

    def __init__(self, ground, bodies):
        self.ground = ground
        self.bodies = {b.name: i for i, b in enumerate(bodies)}
        self._body_objs = bodies

    def body(self, name: str, element: str) -> int:
        """Index of the body called ``name`` (``GROUND`` for the ground)."""
        if name == GROUND_NAME:
            return GROUND
        if name not in self.bodies:
            raise ModelError(
                f"unknown body {name!r}; known bodies: {', '.join([GROUND_NAME, *self.bodies])}",
                element,
            )
        return self.bodies[name]

    def point(self, ref, element: str):
        """``(body index, body-frame coordinates (2,))`` of a point reference.

        ``ref`` is ``"body.point"``, ``"body"`` (the body frame's origin) or
        ``("body", (x, y))`` (coordinates in the body frame).
        """
        if isinstance(ref, tuple | list) and len(ref) == 2 and isinstance(ref[0], str):
            b = self.body(ref[0], element)
            return b, jnp.asarray(np.asarray(ref[1], dtype=float))
        if not isinstance(ref, str):
            raise ModelError(f"a point reference must be 'body.point', got {ref!r}", element)
        body_name, _, pname = ref.partition(".")
        b = self.body(body_name, element)
        if not pname:
            return b, as_f64(np.zeros(2))
        points = self.ground.points if b == GROUND else self._body_objs[b].points
        if pname not in points:
            raise ModelError(
                f"body {body_name!r} has no point {pname!r}; its points: "
                f"{', '.join(sorted(points)) or '(none)'}",
                element,
            )
        return b, points[pname]

    def vector(self, ref, body: int, element: str):
        """A unit vector (2,) in the frame of ``body``: a name on that body or two numbers."""
        if isinstance(ref, str):
            if body == GROUND:
                raise ModelError(f"the ground has no named vector {ref!r}; give (x, y)", element)
            vecs = self._body_objs[body].vectors
            if ref not in vecs:
                raise ModelError(
                    f"unknown vector {ref!r} on body {self._body_objs[body].name!r}", element
                )
            v = np.asarray(vecs[ref])
        else:
            v = np.asarray(ref, dtype=float)
            if v.shape != (2,):
                raise ModelError(f"a direction must be two numbers (x, y), got {ref!r}", element)
        n = np.linalg.norm(v)
        if not np.isfinite(n) or n == 0:
            raise ModelError(f"direction {ref!r} has zero length", element)
        return as_f64(v / n)


def body_name(ref) -> str:
    """The name of the body of a point reference (``"body.point"``, ``"body"`` or
    ``("body", (x, y))``), for messages."""
    if isinstance(ref, tuple | list) and ref and isinstance(ref[0], str):
        return ref[0]
    return str(ref).partition(".")[0]


def moving(*bodies: int) -> tuple[int, ...]:
    """The distinct moving bodies among ``bodies`` (the ground dropped), in order."""
    out = []
    for b in bodies:
        if b != GROUND and b not in out:
            out.append(b)
    return tuple(out)
