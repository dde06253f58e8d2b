"""The member models of a model file's sweep, made from the swept run's model.

A member is the swept run of the file with the member's numbers (:mod:`.sweep`). Building
the whole model from the file again for every member costs as much as running it (~10-20
ms on the paper's model), so where the varied numbers reach only force elements and the
bodies' masses and inertias, :func:`quick_members` builds just those again, member by member,
and puts their numbers into the run's model (one unflatten a member): the same numbers as a
model built from the file, and a start the members share
(:func:`mixdyn.analysis.sweep.shares_start`). A file parameter reaches what names it: the
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
    masses and inertias.

    Attributes:
        models: (M,) the member models: the swept run's model with the member's numbers.
        reached: the parameter paths the varied numbers reach (``"slider.mass"``, ``"F1"``
            for a force built again), for :func:`mixdyn.analysis.sweep.shares_start`.
    """

    models: list[Model]
    reached: tuple[str, ...]


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
    """The member models of sweep ``plan``, made from ``model`` (the swept run's model) by
    building again only the forces and the bodies' masses and inertias that the varied
    numbers reach; None where they reach anything else, or a member's part cannot be built
    or differs in structure (then each member is built from its file, which reports it).
    """
    spec = runner.spec
    values = plan.values
    named = [k for k in values if "." in k]
    builders = [_parameters(spec, values, i) for i in range(plan.members)]
    nominal = runner.b.parameters
    changed = set()
    for _, b in builders:
        if b is not None:
            changed |= {k for k, v in b.parameters.items() if v != nominal.get(k)}
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
    leaves, treedef = jax.tree_util.tree_flatten(model)
    models = []
    for i, (member, b) in enumerate(builders):
        row = list(leaves)
        for part in parts:
            try:
                new = _leaves(part, model, member, b, values, i)
            except (FileError, ModelError):
                return None
            if new is None:
                return None
            row[part.start : part.start + part.count] = new
        models.append(jax.tree_util.tree_unflatten(treedef, row))
    reached = [
        f"{spec.bodies[p.body].name}.{p.field}" if p.body is not None
        else spec.forces[p.force].name if p.force is not None
        else p.path
        for p in parts
    ]  # fmt: skip
    return Members(models, tuple(reached))


def _leaves(part: _Part, model: Model, member, b: Builder | None, values, i: int):
    """Member ``i``'s leaves of ``part`` (None: a force of another structure)."""
    if part.path is not None:
        return [jnp.asarray(float(values[part.path][i]))]
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
