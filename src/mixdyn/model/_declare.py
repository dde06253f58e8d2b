"""One declaration per element: each field says once what it is, and the file schema, the
reading and writing of files, the unit kinds that studies use and the model-file reference
are made from it.

An element class registers its file name with :func:`element` and declares the fields a
file gives, each with its doc:

- :func:`reference`: a point or body by name (or another joint, ``what="joint"``);
  :func:`references`: a list of points;
- :func:`quantity`: a number of a kind of quantity, or a law (of time, or of another
  variable such as a cam's angle: :class:`Variable`), with its range;
- :func:`direction`: a direction, two numbers or the name of a body's vector;
- :func:`coordinate`: a body coordinate, written ``body.phi`` in a file;
- :func:`option`: a flag or a word (one of ``choices``).

Validation stays in the class: the numbers' declared ranges are checked by
:class:`~mixdyn.model._element.Element` when an element is made (:func:`check_declared`),
everything else by the class's ``__check_init__`` and ``bind``; a file and the Python API meet
the same checks. A check about one field names it (``ModelError(..., field=...)``), so that
a file reports it at that field's line.

Example::

    @element("belt_drive", "joints")
    class BeltDrive(Joint):
        body_i: str = reference("Pulley i: a body.", what="body")
        radius_i: jax.Array = quantity("length", "Pitch radius of pulley i.", above=0.0)
        crossed: bool = option("A crossed belt (the pulleys turn opposite ways).", False)

A quantity whose kind depends on other fields (a driver's law: an angle for ``body.phi``, a
length for ``body.x``) declares its possible kinds, ``quantity(("length", "angle"), ...)``,
and the class says which one a given element takes with the class method
``field_kind(field, values, element_class)`` (``values``: the element's field values by
name; ``element_class(name)``: the class of another element of the model, or None).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping
from typing import Any

import equinox as eqx

from ._geometry import static_direction
from ._validate import finite

#: The key of a declared field's metadata.
KEY = "mixdyn"

#: Element groups of a model file (its sections), by the name :func:`element` takes.
GROUPS = ("joints", "drivers", "forces")

#: What a :class:`Reference` may name.
REFERENCES = ("point", "body", "joint", "force")


@dataclasses.dataclass(frozen=True)
class Reference:
    """A field naming a point (``"body.point"``, ``"body"``), a body (``what="body"``),
    another joint (``what="joint"``) or a force element (``what="force"``) of the model; with
    ``many`` a list of points."""

    doc: str
    what: str = "point"
    many: bool = False


@dataclasses.dataclass(frozen=True)
class Variable:
    """The argument of a law field: its name in a file's expressions (``t``, ``theta``) and
    its kind of quantity (a key of :data:`mixdyn.units.DIMENSIONS`). A law's coefficients and
    knots are per this kind (a polynomial's ``c_k`` in the law's unit per ``kind**k``), and a
    file's expression names it by ``name`` alone (any other law variable is refused there)."""

    name: str
    kind: str


#: The variable of a law of time.
TIME = Variable("t", "time")


@dataclasses.dataclass(frozen=True)
class Quantity:
    """A field holding a number of a kind of quantity (a key of
    :data:`mixdyn.units.DIMENSIONS`), or with ``law`` a law of ``variable`` (default time)
    in that kind (``state``: the law may read body states).

    ``kind`` is one kind, or a tuple of the kinds the field may take (the class's
    ``field_kind`` picks one). A number is finite, and ``> above`` / ``>= at_least`` where
    given; a field whose default is None is optional (None: not given, left unchecked).
    ``file_default`` is the default as a file shows it (``"20 deg"``), where it is not the
    class's default number.
    """

    kind: str | tuple[str, ...]
    doc: str
    law: bool = False
    state: bool = False
    above: float | None = None
    at_least: float | None = None
    file_default: Any = None
    variable: Variable = TIME

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds the field may take."""
        return (self.kind,) if isinstance(self.kind, str) else tuple(self.kind)

    @property
    def shown(self) -> str:
        """The kinds in words (``"velocity or angular velocity"``)."""
        return " or ".join(k.replace("_", " ") for k in self.kinds)


@dataclasses.dataclass(frozen=True)
class Direction:
    """A field holding a direction: two numbers ``(x, y)``, or with ``on`` also the name of a
    vector of the body of the point field ``on`` (a slider's axis along a body's vector)."""

    doc: str
    on: str | None = None


@dataclasses.dataclass(frozen=True)
class Coordinate:
    """A field holding the name of a body coordinate (``x``, ``y`` or ``phi``) of the body in
    the field ``body``; a file gives both as one reference, ``crank.phi``."""

    doc: str
    body: str = "body"


@dataclasses.dataclass(frozen=True)
class Option:
    """A field holding a flag, a word or a number (one of ``choices`` where given), read as
    it is."""

    doc: str
    choices: tuple = ()


Declaration = Reference | Quantity | Direction | Coordinate | Option


@dataclasses.dataclass(frozen=True)
class ElementKind:
    """A registered element class: its file name (the ``type`` of its section's entries),
    its section (:data:`GROUPS`) and its class."""

    file_name: str
    group: str
    cls: type

    def fields(self) -> tuple[tuple[str, Declaration, Any], ...]:
        """``(name, declaration, default)`` of the declared fields (see
        :func:`declared_fields`)."""
        return declared_fields(self.cls)


#: The registered element classes: by section (:data:`GROUPS`), then by file name.
ELEMENTS: dict[str, dict[str, ElementKind]] = {group: {} for group in GROUPS}


def element(file_name: str, group: str):
    """Register an element class under ``file_name`` in the section ``group`` of a model
    file (:data:`GROUPS`); its declarations are checked against each other."""
    if group not in GROUPS:
        raise ValueError(f"group must be one of {GROUPS}, got {group!r}")

    def register(cls):
        known = ELEMENTS[group].get(file_name)
        if known is not None and known.cls.__name__ != cls.__name__:
            raise ValueError(f"{group} file name {file_name!r} registered twice")
        _check_declarations(cls)
        ELEMENTS[group][file_name] = ElementKind(file_name, group, cls)
        return cls

    return register


def _check_declarations(cls: type) -> None:
    """Refuse declarations that do not fit together (a programming error in ``cls``)."""
    names = {f.name for f in dataclasses.fields(cls)}
    declared = {name: decl for name, decl, _ in declared_fields(cls)}
    for name, decl in declared.items():
        if isinstance(decl, Quantity) and len(decl.kinds) > 1 and not hasattr(cls, "field_kind"):
            raise TypeError(f"{cls.__name__}.{name} has several kinds: define field_kind")
        if (
            isinstance(decl, Direction)
            and decl.on is not None
            and not isinstance(declared.get(decl.on), Reference)
        ):
            raise TypeError(f"{cls.__name__}.{name}: {decl.on!r} is no declared reference")
        if isinstance(decl, Coordinate) and decl.body not in names:
            raise TypeError(f"{cls.__name__}.{name}: no field {decl.body!r} for the body")
        if isinstance(decl, Reference) and decl.what not in REFERENCES:
            raise TypeError(f"{cls.__name__}.{name}: a reference names one of {REFERENCES}")


def kind_of(cls: type) -> ElementKind | None:
    """The registration of the element class ``cls`` (None: not registered)."""
    for group in ELEMENTS.values():
        for kind in group.values():
            if kind.cls is cls:
                return kind
    return None


def reference(
    doc: str, *, what: str = "point", default: Any = dataclasses.MISSING, kw_only: bool = False
):
    """A static field naming a point (a body, ``what="body"``; another joint,
    ``what="joint"``; a force element, ``what="force"``); ``default=None``: an optional
    one."""
    kwargs: dict[str, Any] = {"kw_only": True} if kw_only else {}
    return eqx.field(static=True, default=default, metadata={KEY: Reference(doc, what)}, **kwargs)


def references(doc: str):
    """A static field naming a list of points (``["ball1", "ball2.C"]``), held as a tuple."""
    return eqx.field(static=True, converter=tuple, metadata={KEY: Reference(doc, "point", True)})


def quantity(
    kind: str | tuple[str, ...],
    doc: str,
    default: Any = dataclasses.MISSING,
    *,
    converter=None,
    law: bool = False,
    state: bool = False,
    above: float | None = None,
    at_least: float | None = None,
    file_default: Any = None,
    variable: Variable = TIME,
    kw_only: bool = False,
):
    """A field holding a number of ``kind`` (or a law of ``variable``, default time, in that
    kind), finite and ``> above`` / ``>= at_least`` where given (see :class:`Quantity`);
    ``default=None``: an optional number."""
    kwargs: dict[str, Any] = {} if converter is None else {"converter": converter}
    if kw_only:
        kwargs["kw_only"] = True
    decl = Quantity(kind, doc, law, state, above, at_least, file_default, variable)
    return eqx.field(default=default, metadata={KEY: decl}, **kwargs)


def direction(
    doc: str, default: Any = dataclasses.MISSING, *, on: str | None = None, kw_only: bool = False
):
    """A static field holding a direction (see :class:`Direction`), stored as a tuple of
    floats or a vector's name (:func:`~mixdyn.model._element.static_direction`)."""
    kwargs: dict[str, Any] = {"kw_only": True} if kw_only else {}
    return eqx.field(
        static=True,
        default=default,
        converter=static_direction,
        metadata={KEY: Direction(doc, on)},
        **kwargs,
    )


def coordinate(doc: str, *, body: str = "body"):
    """A static field holding a body coordinate's name, ``x``, ``y`` or ``phi``, of the body
    named in the field ``body`` (see :class:`Coordinate`)."""
    return eqx.field(static=True, metadata={KEY: Coordinate(doc, body)})


def option(
    doc: str,
    default: Any = dataclasses.MISSING,
    *,
    choices: tuple = (),
    converter=None,
    kw_only: bool = False,
):
    """A static field holding a flag, a word or a number (one of ``choices`` where given;
    ``converter``: how the class stores it, e.g. ``float`` for the choices ``(1, -1)``)."""
    kwargs: dict[str, Any] = {} if converter is None else {"converter": converter}
    if kw_only:
        kwargs["kw_only"] = True
    decl = Option(doc, tuple(choices))
    return eqx.field(static=True, default=default, metadata={KEY: decl}, **kwargs)


@functools.cache
def declared_fields(cls: type) -> tuple[tuple[str, Declaration, Any], ...]:
    """``(name, declaration, default)`` of the declared fields of ``cls`` in the order of its
    constructor (the positional fields, then the keyword-only ones; default
    ``dataclasses.MISSING`` where the field is required)."""
    fields = sorted(dataclasses.fields(cls), key=lambda f: f.kw_only is True)
    return tuple((f.name, f.metadata[KEY], f.default) for f in fields if KEY in f.metadata)


def _no_class(name: str) -> None:
    return None


def quantity_kind(
    cls: type,
    field: str,
    values: Mapping[str, Any],
    element_class: Callable[[str], type | None] = _no_class,
) -> str:
    """The kind of quantity of the declared quantity ``field`` of an element of class ``cls``
    whose fields hold ``values`` (the class's ``field_kind`` where the field may take several
    kinds; ``element_class(name)`` gives another element's class)."""
    decl = dict((name, d) for name, d, _ in declared_fields(cls))[field]
    if len(decl.kinds) == 1:
        return decl.kinds[0]
    kind = cls.field_kind(field, values, element_class)
    if kind not in decl.kinds:  # pragma: no cover - a programming error in the class
        raise TypeError(f"{cls.__name__}.field_kind gave {kind!r} for {field!r}")
    return kind


def number_kind(element_obj: Any, field: str, model: Any = None) -> str | None:
    """The kind of quantity of the number ``field`` of an element (None: not a declared
    number), as studies read it to convert a varied number's unit; ``model`` (the element's
    model) answers what a kind may depend on in other elements."""
    cls = type(element_obj)
    for name, decl, _ in declared_fields(cls):
        if name == field and isinstance(decl, Quantity) and not decl.law:
            values = {f.name: getattr(element_obj, f.name) for f in dataclasses.fields(cls)}
            if model is None:
                return quantity_kind(cls, name, values)
            return quantity_kind(cls, name, values, lambda n: type(model.element(n)))
    return None


def check_declared(element_obj: Any) -> None:
    """Raise a :class:`~mixdyn.errors.ModelError` naming the field unless every declared
    number of an element is finite and in its declared range, and every direction given by
    numbers is finite (called by :class:`~mixdyn.model._element.Element` when an element is
    made)."""
    for name, decl, _ in declared_fields(type(element_obj)):
        value = getattr(element_obj, name)
        if isinstance(decl, Quantity) and not decl.law and value is not None:
            finite(
                value,
                name,
                element_obj.name,
                above=decl.above,
                at_least=decl.at_least,
                field=name,
            )
        elif isinstance(decl, Direction) and not isinstance(value, str):
            finite(value, name, element_obj.name, field=name)


__all__ = [
    "ELEMENTS",
    "GROUPS",
    "KEY",
    "REFERENCES",
    "TIME",
    "Coordinate",
    "Declaration",
    "Direction",
    "ElementKind",
    "Option",
    "Quantity",
    "Reference",
    "Variable",
    "check_declared",
    "coordinate",
    "declared_fields",
    "direction",
    "element",
    "kind_of",
    "number_kind",
    "option",
    "quantity",
    "quantity_kind",
    "reference",
]
