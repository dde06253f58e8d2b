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
  ``"joints"``, ``"drivers"``, ``"forces"``);
* :func:`check` and :func:`check_bounds`: candidate values of numbers (a sweep's members,
  a fit's or an optimization's bounds) put through the checks of the constructors that own
  them, before any computing.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Mapping

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .errors import ModelError
from .model import Body, Model
from .model._body import INERTIAL_AT_LEAST, check_inertial
from .model._declare import Quantity, declared_fields

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
    same shape (a float64 array): the model built with that number (its owner's checks met,
    :func:`check`; a start bound again, as :func:`mixdyn.sweep` binds a member's).

    Raises:
        ModelError: a bad path (:func:`getter`), a value of another shape, or one a model
            built with it refuses.
    """
    get_, shape_ = getter(model, path)
    v = jnp.asarray(value, dtype=jnp.float64)
    if v.shape != shape_:
        raise ModelError(
            f"a value of shape {shape_} expected, got shape {v.shape}", f"vary {path!r}"
        )
    check(model, {path: np.asarray(v)[None]}, label=lambda i: "the value")
    out = eqx.tree_at(get_, model, v)
    if path.split(".")[1] == "q0":  # the elements' constants from the start follow it
        out = bound_again(out)
    return out


def bound_again(model: Model) -> Model:
    """``model`` with its elements bound again to its bodies, as its constructor binds them:
    the constants an element takes from the bodies' start (a gear mesh's phase, a rolling
    disk's side) follow a start that was replaced."""
    m = model
    return Model(m.bodies, m.joints, m.drivers, m.forces, m.ground, m.gravity, m.units, m.name)


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


def _remake(obj, changes: dict):
    """``obj`` made again by its constructor with ``changes`` (field -> value, or field ->
    the changes of the object in that field), so that its own checks see them: a body's
    mass and inertia by :func:`~mixdyn.model._body.check_inertial`, an element or a law by
    its class (declared ranges, :func:`~mixdyn.model._declare.check_declared`, and the
    class's checks between fields)."""
    made = {
        f: _remake(getattr(obj, f), c) if isinstance(c, dict) else c for f, c in changes.items()
    }
    if isinstance(obj, Body):
        for label in ("mass", "inertia"):
            if label in made:
                check_inertial(label, made[label], obj.name)
        return obj
    return dataclasses.replace(obj, **made)


def _changes(fields_values: list[tuple[list[str], np.ndarray]], rows) -> dict:
    """The nested changes of one owner: its fields' values at ``rows`` (an index: one
    member's value; a slice: the members' values stacked along the first axis)."""
    out: dict = {}
    for fields, v in fields_values:
        node = out
        for f in fields[:-1]:
            node = node.setdefault(f, {})
        node[fields[-1]] = jnp.asarray(v[rows])
    return out


def check(
    model: Model,
    values: Mapping[str, object],
    label: Callable[[int], str] = lambda i: f"member {i}",
    where: Callable[[str], str] = lambda path: f"vary {path!r}",
) -> None:
    """Put candidate values of numbers through the checks a model built with them meets:
    each row ``i`` of ``values`` (path -> (B, *shape) values) made into the body or element
    that owns the number by its constructor (an element's declared ranges,
    :func:`~mixdyn.model._declare.check_declared`, and its class's checks between fields;
    a body's mass and inertia finite and >= 0), all rows at once, the first one refused
    then found by halving.

    Args:
        model: the nominal mechanism (the other numbers of each owner as they are there).
        values: path -> (B, *shape) candidate values [model units], one row per candidate.
        label: row index -> words naming it (``"member 3"``, ``"the low bound"``).
        where: path -> the error's place (default ``"vary 'path'"``).

    Raises:
        ModelError: the first row (in the order of the owners, then of the rows) that its
            owner refuses, naming the row, the path, the value and the owner's reason.
    """
    owners: dict[str, list[tuple[str, list[str], np.ndarray]]] = {}
    for path, v in values.items():
        getter(model, path)  # a bad path is named as such
        head, _, rest = path.partition(".")
        owners.setdefault(head, []).append((path, rest.split("."), np.asarray(v, dtype=float)))
    for head, entries in owners.items():
        obj = _locate(model, head)(model)
        fields_values = [(fields, v) for _, fields, v in entries]
        count = len(entries[0][2])

        def refused(rows, obj=obj, fields_values=fields_values) -> ModelError | None:
            try:
                with warnings.catch_warnings():  # the owner's warnings were given when made
                    warnings.simplefilter("ignore", DeprecationWarning)
                    _remake(obj, _changes(fields_values, rows))
            except ModelError as refusal:
                return refusal
            return None

        def stacked(stop: int) -> bool:
            """Whether the rows before ``stop``, made at once, are refused (a check not
            written for stacked values counts as refusing them: the rows are then made one
            by one)."""
            try:
                return refused(slice(0, stop)) is not None
            except (TypeError, ValueError):
                return True

        if not stacked(count):
            continue
        lo, hi = 0, count  # the first refused row is in [lo, hi)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (lo, mid) if stacked(mid) else (mid, hi)
        err, first = None, lo
        for first in range(lo, count):  # a stacked refusal no single row shares: none refused
            try:
                err = refused(first)
            except (TypeError, ValueError):  # pragma: no cover - an owner its class cannot remake
                err = None
            if err is not None:
                break
        if err is None:
            continue
        named = [p for p, fields, _ in entries if len(fields) == 1 and fields[0] == err.field]
        named = named or [p for p, _, _ in entries]
        shown = ", ".join(f"{p} = {_shown(v[first])}" for p, _, v in entries if p in named)
        raise ModelError(f"{label(first)}: {shown} is refused: {err}", where(named[0]))


def lower_limit(model: Model, path: str) -> float:
    """The least value the number at ``path`` may take, from its owner's declaration (an
    element's declared quantity: ``above`` or ``at_least``; a body's mass and inertia:
    :data:`~mixdyn.model._body.INERTIAL_AT_LEAST`); ``-inf`` where none is declared (a
    declared ``above`` is itself refused: a search bounded by it stays above it).
    """
    getter(model, path)
    head, _, rest = path.partition(".")
    obj = _locate(model, head)(model)
    if "." in rest:
        return -np.inf
    if isinstance(obj, Body):
        return INERTIAL_AT_LEAST if rest in ("mass", "inertia") else -np.inf
    for name, decl, _ in declared_fields(type(obj)):
        if name == rest and isinstance(decl, Quantity) and not decl.law:
            ends = [v for v in (decl.above, decl.at_least) if v is not None]
            return float(max(ends)) if ends else -np.inf
    return -np.inf


#: Words naming the ends of bounds ``(low, high)``, by index.
BOUND_ENDS = ("the low bound", "the high bound")


def check_bounds(model: Model, path: str, bounds, where: str | None = None) -> None:
    """Refuse bounds ``(low, high)`` of the number at ``path`` with a finite end that a model
    built with it would refuse (:func:`check`): a search within them would compute with
    impossible numbers (a negative mass).

    Raises:
        ModelError: naming the end, its value and the owner's reason, at ``where`` (default
            ``"bounds of 'path'"``).
    """
    ends = [(k, float(v)) for k, v in enumerate(bounds) if np.isfinite(v)]
    if not ends:
        return
    check(
        model,
        {path: np.asarray([v for _, v in ends])},
        label=lambda i: BOUND_ENDS[ends[i][0]],
        where=lambda p: where or f"bounds of {p!r}",
    )


def _shown(v) -> str:
    a = np.asarray(v)
    return f"{float(a):g}" if a.ndim == 0 else str(a.tolist())


__all__ = [
    "BOUND",
    "BOUND_ENDS",
    "GROUPS",
    "bound_again",
    "check",
    "check_bounds",
    "get",
    "getter",
    "group",
    "lower_limit",
    "replace",
    "shape",
]
