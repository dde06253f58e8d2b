"""The member models of a model file's sweep, made from the swept run's model.

A member is the swept run of the file with the member's numbers (:mod:`.sweep`). Building
the whole model from the file again for every member costs as much as running it (~10-20
ms on the paper's model), so where the varied numbers reach only force elements and the
bodies' masses and inertias, :func:`quick_members` builds just those again (once for each
value of the varied parameters they reach) and holds their numbers as columns of the run's model's
leaves, a row per member (:class:`Members`; a member's model is one unflatten): the same
numbers as a model built from the file, and a start the members share
(:func:`mixdyn.analysis.sweep.shares_start`), hence one stacked problem
(:mod:`mixdyn.analysis._stacked`). A file parameter reaches what names it: the
text of a body's or element's entries, or of another parameter (whose value then changes
too); a number named by its path (``slider.mass``, ``F1.law.amplitude``) reaches itself.

Where a varied number reaches anything else (a joint, a driver, a body's points or start, the
ground, gravity, the run's own settings) :func:`quick_members` returns None, and each member
is built from its file.
"""

from __future__ import annotations

import dataclasses
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import paths
from ..analysis._schedule import CHUNK
from ..errors import ModelError
from ..io._errors import FileError
from ..io.load import Builder
from ..model import Model

#: A name in a file's text (a parameter is named like this in an expression or a quantity).
_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")

#: A body's fields that do not enter a forward or mixed run's start.
_INERTIAL = ("mass", "inertia")


@dataclasses.dataclass(frozen=True)
class Members:
    """The member models of a sweep whose varied numbers reach only forces and bodies'
    masses and inertias, held as the swept run's model and the columns of its leaves that
    the members change.

    Attributes:
        model: the swept run's model.
        count: M, the number of members.
        positions: the indices, among ``model``'s leaves, of the leaves the members change.
        values: for each of ``positions``, its (M, ...) values, a row per member [model
            units].
        names: for each of ``positions``, a name: a body's ``"slider.mass"``, a force's
            ``"F1[k]"`` (its ``k``-th leaf), a number's path.
        reached: the parameter paths the varied numbers reach (``"slider.mass"``, ``"F1"``
            for a force built again), for :func:`mixdyn.analysis.sweep.shares_start`.
    """

    model: Model
    count: int
    positions: tuple[int, ...]
    values: tuple[np.ndarray, ...]
    names: tuple[str, ...]
    reached: tuple[str, ...]

    @property
    def models(self) -> list[Model]:
        """(M,) the member models: the swept run's model with the member's numbers (one
        unflatten a member)."""
        leaves, treedef = jax.tree_util.tree_flatten(self.model)
        models = []
        for i in range(self.count):
            row = list(leaves)
            for k, v in zip(self.positions, self.values, strict=True):
                row[k] = jnp.asarray(v[i])
            models.append(jax.tree_util.tree_unflatten(treedef, row))
        return models


def _names(value) -> set[str]:
    """Every name in the strings of ``value`` (a file entry: a spec, a mapping, a list, a
    string or a number)."""
    if isinstance(value, str):
        return set(_NAME.findall(value))
    if hasattr(value, "model_dump"):
        value = value.model_dump()
    if isinstance(value, dict):
        return set().union(*(_names(k) | _names(v) for k, v in value.items()))
    if isinstance(value, list | tuple):
        return set().union(*(_names(v) for v in value))
    return set()


def _parameters(spec, values: dict[str, np.ndarray], i: int) -> tuple[object, dict]:
    """Member ``i``'s description and its parameters' values (model units)."""
    params = {k: float(v[i]) for k, v in values.items() if "." not in k}
    if not params:
        return spec, None
    member = spec.model_copy(update={"parameters": {**spec.parameters, **params}})
    return member, Builder(member)


@dataclasses.dataclass(frozen=True)
class _Part:
    """A part of the model built again per member: a body's mass or inertia (``field``), a
    force (``force``: its index in the file) or a number named by its path (``path``).

    Attributes:
        start, count: its leaves' place among the model's leaves.
        tree: a force's structure, which the member's must equal.
    """

    start: int
    count: int
    body: int | None = None
    field: str | None = None
    force: int | None = None
    path: str | None = None
    tree: object = None


def quick_members(runner, plan, model: Model) -> Members | None:
    """The members of sweep ``plan`` as ``model`` (the swept run's model) and the columns
    of its leaves that change, made by building again only the forces and the bodies'
    masses and inertias that the varied numbers reach (a part once for each value of the
    varied parameters it reaches: a grid's axes are built, not its combinations, and a
    builder made for those members alone); None where they
    reach anything else, or a member's part cannot be built or differs in structure (then
    each member is built from its file, which reports it).
    """
    spec = runner.spec
    values = plan.values
    named = [k for k in values if "." in k]
    reach = _reach(spec.parameters)
    varied = {k for k in values if "." not in k}
    changed = {p for p in spec.parameters if reach({p}) & varied}
    outside = _names([spec.ground, spec.gravity, spec.joints, spec.drivers, plan.base.spec])
    outside |= _names([b.model_dump(exclude={"mass", "inertia"}) for b in spec.bodies])
    if changed & outside:
        return None
    by_name = {f.name: n for n, f in enumerate(model.forces)}
    parts = []
    for j, b in enumerate(spec.bodies):
        for f in _INERTIAL:
            if changed & _names(getattr(b, f)):
                at = _position(model, lambda m, j=j, f=f: getattr(m.bodies[j], f))
                parts.append(_Part(at, 1, body=j, field=f))
    for k, f in enumerate(spec.forces):
        if not changed & _names(f):
            continue
        if f.name not in by_name:
            return None  # a force the run leaves out
        n = by_name[f.name]
        tree = jax.tree_util.tree_structure(model.forces[n])
        at = _position(model, lambda m, n=n: m.forces[n])
        parts.append(_Part(at, tree.num_leaves, force=k, tree=tree))
    for path in named:
        parts.append(_Part(_position(model, paths.getter(model, path)[0]), 1, path=path))
    # a part is built once for each value of the varied parameters it reaches
    keys = [sorted(reach(_names(_entry(spec, p))) & varied) for p in parts]
    built: list[dict] = [{} for _ in parts]  # per part: its parameters' values -> its leaves
    rows: list[list] = [[] for _ in parts]  # per part: each member's leaves
    for i in range(plan.members):
        for n, part in enumerate(parts):
            if part.path is not None:
                rows[n].append([values[part.path][i]])
                continue
            key = tuple(float(values[k][i]) for k in keys[n])
            new = built[n].get(key)
            if new is None:
                member, b = _parameters(spec, values, i)
                try:
                    new = _leaves(part, model, member, b, values, i)
                except (FileError, ModelError):
                    return None
                if new is None:
                    return None
                new = built[n][key] = [np.asarray(x) for x in new]
            rows[n].append(new)
    return _columns(model, parts, rows, plan.members, spec)


def _columns(
    model: Model, parts: list[_Part], rows: list[list], count: int, spec
) -> Members | None:
    """The members of ``parts`` built (``rows``: per part, each member's leaves) as the
    columns of the model's leaves that change (a later part of one leaf wins: a number
    named by its path over a parameter's); None where a changing leaf is not a float."""
    leaves = jax.tree_util.tree_leaves(model)
    columns: dict[int, tuple[str, np.ndarray]] = {}
    for part, member_leaves in zip(parts, rows, strict=True):
        force = spec.forces[part.force].name if part.force is not None else None
        for k in range(part.count):
            column = np.stack([np.asarray(r[k]) for r in member_leaves])
            at = part.start + k
            if at not in columns and np.array_equal(
                column, np.broadcast_to(leaves[at], column.shape)
            ):
                continue  # the same in every member: the model's own leaf
            if column.dtype.kind != "f":
                return None  # pragma: no cover - a varied leaf that is not a float
            name = f"{force}[{k}]" if force is not None else _reached(spec, part)
            columns[at] = name, np.asarray(column, dtype=np.float64)
    order = sorted(columns)
    reached = [_reached(spec, p) for p in parts]
    return Members(
        model,
        count,
        tuple(order),
        tuple(columns[k][1] for k in order),
        tuple(columns[k][0] for k in order),
        tuple(reached),
    )


def _reach(parameters: dict):
    """A function: names -> the file parameters among them and those their values are
    written with, directly or through other parameters."""
    uses = {name: _names(text) & set(parameters) for name, text in parameters.items()}

    def reach(names: set[str]) -> set[str]:
        found, todo = set(), [n for n in names if n in uses]
        while todo:
            name = todo.pop()
            if name not in found:
                found.add(name)
                todo.extend(uses[name])
        return found

    return reach


def _entry(spec, part: _Part):
    """The file's entry that ``part`` is built from (a number named by its path: none)."""
    if part.body is not None:
        return getattr(spec.bodies[part.body], part.field)
    return spec.forces[part.force] if part.force is not None else ""


def _reached(spec, part: _Part) -> str:
    """The parameter path ``part`` reaches: ``"slider.mass"``, a force's name, a path."""
    if part.body is not None:
        return f"{spec.bodies[part.body].name}.{part.field}"
    return spec.forces[part.force].name if part.force is not None else part.path


def _leaves(part: _Part, model: Model, member, b: Builder | None, values, i: int):
    """Member ``i``'s leaves of a body's or force's ``part`` (None: a force of another
    structure)."""
    if part.body is not None:
        body = b._body(part.body, member.bodies[part.body])  # its checks (a negative mass)
        return [jnp.asarray(getattr(body, part.field))]
    force = model.bind_force(b._force(part.force, member.forces[part.force]))
    if jax.tree_util.tree_structure(force) != part.tree:
        return None
    return jax.tree_util.tree_leaves(force)


class _Marker:
    """A leaf put where a part built again sits (:func:`_position`)."""


def _position(model: Model, where) -> int:
    """The index among ``model``'s leaves of the first leaf of ``where(model)``."""
    marker = _Marker()
    marked = jax.tree_util.tree_leaves(eqx.tree_at(where, model, marker))
    return next(k for k, leaf in enumerate(marked) if leaf is marker)


def in_chunks(run, count: int, size: int) -> list:
    """The outcomes of ``count`` members run ``size`` at a time: ``run(indices, first)`` runs
    the members ``indices`` (``first`` the chunk's first member) and returns their outcomes;
    the last chunk is filled up with copies of its first member (one program shape for any
    count), whose outcomes are dropped."""
    out = []
    for first in range(0, count, size):
        idx = list(range(first, min(first + size, count)))
        out += run(idx + [idx[0]] * (size - len(idx)), first)[: len(idx)]
    return out


def chunk_size(batch_size: int | None, members: int) -> int | None:
    """The members a sweep whose members share one start runs at a time: :data:`CHUNK` on a
    CPU, where the file gives no ``batch_size`` and there are at least :data:`CHUNK` members;
    None otherwise (the file's ``batch_size``, or the single run's program member by
    member)."""
    if batch_size is None and members >= CHUNK and jax.default_backend() == "cpu":
        return CHUNK
    return None


__all__ = ["CHUNK", "Members", "chunk_size", "in_chunks", "quick_members"]
