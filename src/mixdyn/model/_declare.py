"""One declaration per element: each field says once what it is, and the file schema, the
reading and writing of files, the unit kinds that studies use and the model-file reference
are made from it.

An element class registers its file name with :func:`element` and declares the fields a
file gives with :func:`reference` (a point or body by name), :func:`quantity` (a number of a
kind of quantity, or a law of time) and :func:`option` (a flag or a word), each with its
doc. Validation stays in the class (``__check_init__`` and ``bind``): a file and the Python
API meet the same checks.

Example::

    @element("belt_drive", "joints")
    class BeltDrive(Joint):
        body_i: str = reference("Pulley i: a body.")
        radius_i: jax.Array = quantity("length", "Pitch radius of pulley i.")
        crossed: bool = option("A crossed belt (the pulleys turn opposite ways).", False)
"""

from __future__ import annotations

import dataclasses
from typing import Any

import equinox as eqx

#: The key of a declared field's metadata.
KEY = "mixdyn"

#: Element groups of a model file (its sections), by the name :func:`element` takes.
GROUPS = ("joints", "drivers", "forces")


@dataclasses.dataclass(frozen=True)
class Reference:
    """A field naming a point (``"body.point"``, ``"body"``) or a body (``what="body"``)."""

    doc: str
    what: str = "point"


@dataclasses.dataclass(frozen=True)
class Quantity:
    """A field holding a number of a kind of quantity (a key of
    :data:`mixdyn.units.DIMENSIONS`), or with ``law`` a law of time in that kind (``state``:
    the law may read body states)."""

    kind: str
    doc: str
    law: bool = False
    state: bool = False


@dataclasses.dataclass(frozen=True)
class Option:
    """A field holding a flag or a word, read as it is."""

    doc: str


Declaration = Reference | Quantity | Option


@dataclasses.dataclass(frozen=True)
class ElementKind:
    """A registered element class: its file name (the ``type`` of its section's entries),
    its section (:data:`GROUPS`) and its class."""

    file_name: str
    group: str
    cls: type

    def fields(self) -> tuple[tuple[str, Declaration, Any], ...]:
        """``(name, declaration, default)`` of the declared fields, in declaration order
        (default ``dataclasses.MISSING`` where the field is required)."""
        return declared_fields(self.cls)


#: The registered element classes: by section (:data:`GROUPS`), then by file name.
ELEMENTS: dict[str, dict[str, ElementKind]] = {group: {} for group in GROUPS}


def element(file_name: str, group: str):
    """Register an element class under ``file_name`` in the section ``group`` of a model
    file (:data:`GROUPS`)."""
    if group not in GROUPS:
        raise ValueError(f"group must be one of {GROUPS}, got {group!r}")

    def register(cls):
        known = ELEMENTS[group].get(file_name)
        if known is not None and known.cls.__name__ != cls.__name__:
            raise ValueError(f"{group} file name {file_name!r} registered twice")
        ELEMENTS[group][file_name] = ElementKind(file_name, group, cls)
        return cls

    return register


def kind_of(cls: type) -> ElementKind | None:
    """The registration of the element class ``cls`` (None: not registered)."""
    for group in ELEMENTS.values():
        for kind in group.values():
            if kind.cls is cls:
                return kind
    return None


def reference(doc: str, *, what: str = "point", default: Any = dataclasses.MISSING):
    """A static field naming a point (or a body, ``what="body"``)."""
    return eqx.field(static=True, default=default, metadata={KEY: Reference(doc, what)})


def quantity(
    kind: str,
    doc: str,
    default: Any = dataclasses.MISSING,
    *,
    converter=None,
    law: bool = False,
    state: bool = False,
):
    """A field holding a number of ``kind`` (or a law of time in that kind)."""
    kwargs = {} if converter is None else {"converter": converter}
    return eqx.field(default=default, metadata={KEY: Quantity(kind, doc, law, state)}, **kwargs)


def option(doc: str, default: Any = dataclasses.MISSING):
    """A static field holding a flag or a word."""
    return eqx.field(static=True, default=default, metadata={KEY: Option(doc)})


def declared_fields(cls: type) -> tuple[tuple[str, Declaration, Any], ...]:
    """``(name, declaration, default)`` of the declared fields of ``cls``."""
    out = []
    for f in dataclasses.fields(cls):
        decl = f.metadata.get(KEY)
        if decl is not None:
            out.append((f.name, decl, f.default))
    return tuple(out)


def number_kind(element_obj: Any, field: str) -> str | None:
    """The kind of quantity of the number ``field`` of an element (None: not a declared
    number), as studies read it to convert a varied number's unit."""
    for name, decl, _ in declared_fields(type(element_obj)):
        if name == field and isinstance(decl, Quantity) and not decl.law:
            return decl.kind
    return None


__all__ = [
    "ELEMENTS",
    "GROUPS",
    "KEY",
    "Declaration",
    "ElementKind",
    "Option",
    "Quantity",
    "Reference",
    "declared_fields",
    "element",
    "kind_of",
    "number_kind",
    "option",
    "quantity",
    "reference",
]
