"""Parameter paths: the numbers of a model named by text, as sweeps, gradients, fits,
optimizations and model files name them.

A path is ``"name.field[.field...]"``: a body or element of the model by its name, then a
numeric field of it, the fields of a law included::

    "slider.mass"          a body's mass [mass]
    "crank.q0"             a body's rough start (3,) [length, length, rad]
    "F1.law.amplitude"     the amplitude of force F1's law
    "spring.stiffness"     a spring's stiffness

Only numbers that are array leaves of the model can be named: fields that decide the
structure (static fields: which bodies a joint connects, a law's kind) and geometry bound
from the bodies' points (a joint's ``si``, ``sj``...) are refused by name, with what to do
instead (build the models with the change: ``md.sweep(models=[...])``).

* :func:`getter` ``(model, path) -> (get, shape)``: the checked accessor, for any model of
  the same structure (``get(member)``);
* :func:`get` and :func:`replace`: read one number, or a model with one number replaced;
* :func:`shape` and :func:`group`: the number's shape and the kind of its owner (``"bodies"``,
  ``"joints"``, ``"drivers"``, ``"forces"``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .errors import ModelError
from .model import Model

#: Fields that hold geometry bound from body points: a number there would disagree with the
#: bodies' points; vary the points by building the models instead (``models=``).
BOUND = frozenset({"si", "sj", "s", "u", "points", "vectors"})

#: The groups of a model's named elements, in the order a name is looked up after the bodies.
GROUPS = ("joints", "drivers", "forces")


def _locate(model: Model, head: str) -> Callable[[Model], object]:
    """A function ``m -> the body or element called head`` in a model of this structure."""
    for k, b in enumerate(model.bodies):
        if b.name == head:
            return lambda m, k=k: m.bodies[k]
    for g in GROUPS:
        for k, e in enumerate(getattr(model, g)):
            if e.name == head:
                return lambda m, g=g, k=k: getattr(m, g)[k]
    known = [b.name for b in model.bodies]
    known += [e.name for e in (*model.joints, *model.drivers, *model.forces)]
    raise ModelError(
        f"no body or element {head!r} to vary; known: {', '.join(known)}", f"vary {head!r}"
    )


def getter(model: Model, path: str) -> tuple[Callable[[Model], jax.Array], tuple[int, ...]]:
    """The number of ``model`` named by ``path``, checked, as an accessor.

    Args:
        model: the mechanism.
        path: ``"name.field[.field...]"`` (``"slider.mass"``, ``"F1.law.amplitude"``).

    Returns:
        ``(get, shape)``: ``get(m)`` the array leaf at ``path`` in any model ``m`` of the same
        structure (for ``eqx.tree_at(get, m, value)``), and its shape.

    Raises:
        ModelError: no such body or element, no such field (its fields listed), a field that
            is part of the structure or bound geometry, or not a floating-point number; the
            error names ``vary 'path'``.
    """
    head, _, rest = path.partition(".")
    if not rest:
        raise ModelError(
            "a varied quantity is 'name.field' (a body's or element's field, e.g. "
            "'slider.mass', 'F1.law.a')",
            f"vary {path!r}",
        )
    locate = _locate(model, head)
    obj = locate(model)
    fields = rest.split(".")
    for f in fields:
        names = (
            {x.name: x for x in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) else {}
        )
        if f in BOUND:
            raise ModelError(
                f"{f!r} is geometry bound from the bodies' points; build the member models "
                "with the points changed and pass them as models=[...]",
                f"vary {path!r}",
            )
        if f not in names:
            raise ModelError(
                f"{type(obj).__name__} {getattr(obj, 'name', head)!r} has no field {f!r}; its "
                f"fields: {', '.join(sorted(n for n in names if n != 'name'))}",
                f"vary {path!r}",
            )
        if names[f].metadata.get("static", False):
            raise ModelError(
                f"field {f!r} is part of the structure (it decides the equations), not a "
                "number; build the member models instead (models=[...])",
                f"vary {path!r}",
            )
        obj = getattr(obj, f)
    if not (eqx.is_array(obj) and jnp.issubdtype(jnp.asarray(obj).dtype, jnp.floating)):
        raise ModelError(
            f"{path!r} is not a number of the model ({type(obj).__name__}); name a numeric field",
            f"vary {path!r}",
        )

    def get(m):
        x = locate(m)
        for f in fields:
            x = getattr(x, f)
        return x

    return get, tuple(np.shape(obj))


def get(model: Model, path: str) -> jax.Array:
    """The number of ``model`` at ``path`` [model units] (an array of its :func:`shape`)."""
    return getter(model, path)[0](model)


def replace(model: Model, path: str, value) -> Model:
    """``model`` with the number at ``path`` replaced by ``value`` [model units], of the
    same shape (a float64 array).

    Raises:
        ModelError: a bad path (:func:`getter`), or a value of another shape.
    """
    get_, shape_ = getter(model, path)
    v = jnp.asarray(value, dtype=jnp.float64)
    if v.shape != shape_:
        raise ModelError(
            f"a value of shape {shape_} expected, got shape {v.shape}", f"vary {path!r}"
        )
    return eqx.tree_at(get_, model, v)


def shape(model: Model, path: str) -> tuple[int, ...]:
    """The shape of the number at ``path`` (``()`` for a scalar)."""
    return getter(model, path)[1]


def group(model: Model, path: str) -> str:
    """The group of the body or element a path names: ``"bodies"``, ``"joints"``,
    ``"drivers"`` or ``"forces"`` (the path's first part looked up by name).

    Raises:
        ModelError: no body or element of that name.
    """
    head = path.partition(".")[0]
    if any(b.name == head for b in model.bodies):
        return "bodies"
    for g in GROUPS:
        if any(e.name == head for e in getattr(model, g)):
            return g
    _locate(model, head)  # raises, naming the known ones
    raise AssertionError("unreachable")  # pragma: no cover


__all__ = ["BOUND", "GROUPS", "get", "getter", "group", "replace", "shape"]
