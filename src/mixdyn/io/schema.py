"""The model-file schema: a validated description of a mechanism and its analyses.

A model file (YAML) is read into a :class:`ModelFile`, a tree of pydantic models that checks the
*form* of the description: required fields, types, allowed keys, the kinds of joints, drivers,
forces and runs. The *meaning* (names that exist, units of the right dimension, expressions
that parse) is checked when the description is built into a :class:`mixdyn.Model`
(:mod:`mixdyn.io.load`), where the model's unit system is known.

Scalars (:data:`Scalar`) are numbers in the model's units, or strings with units
(``"500 N*mm"``, ``"30 deg"``) or constant expressions (``"pi/6"``). Laws of time
(:data:`LawSpec`) are numbers, expression strings (``"10*sin(pi*t/2)"``) or one-key mappings
(``{polynomial: [0, 2]}``, ``{harmonic: {amplitude: 1, omega: 2}}``, ...).

``mixdyn schema`` writes :func:`json_schema` for editors and validators.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import operator
import re
import warnings
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    create_model,
    model_validator,
)
from pydantic.json_schema import GenerateJsonSchema

from ..errors import ModelError
from ..model import _declare as _decl

FORMAT_VERSION = 1

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_\-]*$")


def _name(v: str) -> str:
    if not _NAME.match(v) or len(v) > 64:
        raise ValueError(
            f"{v!r} is not a valid name: use letters, digits, '_' and '-', starting with a "
            "letter or '_' (at most 64 characters)"
        )
    return v


def _scalar(v: Any) -> Any:
    if isinstance(v, bool) or not isinstance(v, int | float | str):
        raise ValueError(f"expected a number or a string with units (e.g. '500 N*mm'), got {v!r}")
    if isinstance(v, float) and not math.isfinite(v):
        raise ValueError(f"{v!r} is not a finite number")
    if isinstance(v, str) and not v.strip():
        raise ValueError("empty value; write a number or a number with units")
    return v


def _ref(v: str) -> str:
    if not v or any(not _NAME.match(p) for p in v.split(".")) or len(v) > 200:
        raise ValueError(f"{v!r} is not a reference; write 'body' or 'body.point'")
    return v


def _relative_file(v: str) -> str:
    p = v.replace("\\", "/")
    if not p or p.startswith("/") or ".." in p.split("/") or ":" in p:
        raise ValueError(
            f"{v!r} must be a relative file name inside the run's output folder (no '..')"
        )
    return v


#: File types of figures and animations (those of :mod:`mixdyn.viz`).
PLOT_SUFFIXES = (".png", ".svg", ".pdf")
ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")


def _suffixed(suffixes: tuple[str, ...], what: str):
    def check(v: str) -> str:
        if not v.lower().endswith(suffixes) or v.rsplit("/", 1)[-1].startswith("."):
            raise ValueError(f"cannot write {_article(what)} to {v!r}: use {', '.join(suffixes)}")
        return v

    return check


def _article(what: str) -> str:
    return ("an " if what[0] in "aeiou" else "a ") + what


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def _text(v: str) -> str:
    """One line of plain text: no control characters (no terminal escapes)."""
    if _CONTROL.search(v):
        raise ValueError("contains a control character; write plain text on one line")
    return v


def _paragraph(v: str) -> str:
    """Plain text that may span lines: no control characters other than newlines and tabs."""
    return _text(v.replace("\n", " ").replace("\t", " ").replace("\r", " "))


Name = Annotated[str, AfterValidator(_name)]
"""A name: letters, digits, ``_`` and ``-``, starting with a letter or ``_``."""

Scalar = Annotated[float | str, BeforeValidator(_scalar)]
"""A number in model units, or a string: a number or constant expression with a unit."""

Ref = Annotated[str, AfterValidator(_ref)]
"""A reference: ``"body"``, ``"body.point"``, ``"body.x"`` (coordinates), ``"ground.A"``."""

Vec2 = tuple[Scalar, Scalar]
"""Two scalars ``[x, y]``."""


def _data_file(v: str) -> str:
    p = v.replace("\\", "/")
    if not p or p.startswith("/") or ".." in p.split("/") or ":" in p:
        raise ValueError(f"{v!r} must be a file name relative to the model file's folder (no '..')")
    if not p.lower().endswith(".csv"):
        raise ValueError(f"{v!r}: measured data is read from a .csv file")
    return v


RelativeFile = Annotated[str, AfterValidator(_relative_file)]
DataFile = Annotated[str, AfterValidator(_data_file)]
PlotFile = Annotated[RelativeFile, AfterValidator(_suffixed(PLOT_SUFFIXES, "plot"))]
AnimationFile = Annotated[RelativeFile, AfterValidator(_suffixed(ANIMATION_SUFFIXES, "animation"))]
Text = Annotated[str, AfterValidator(_text)]
"""One line of plain text (a title, a label, the model's name)."""


@functools.cache
def _field_docstrings() -> dict[str, dict[str, str]]:
    """The docstrings of the fields of this module's classes (the string below each field),
    by class name and field name, cleaned as pydantic cleans them."""
    import ast
    import inspect
    import pathlib

    tree = ast.parse(pathlib.Path(__file__).read_text(encoding="utf-8"))
    docs: dict[str, dict[str, str]] = {}
    for node in tree.body:
        if not isinstance(node, ast.ClassDef):
            continue
        fields = docs.setdefault(node.name, {})
        for stmt, nxt in zip(node.body, node.body[1:], strict=False):
            if (
                isinstance(stmt, ast.AnnAssign)
                and isinstance(stmt.target, ast.Name)
                and isinstance(nxt, ast.Expr)
                and isinstance(nxt.value, ast.Constant)
                and isinstance(nxt.value.value, str)
            ):
                fields[stmt.target.id] = inspect.cleandoc(nxt.value.value)
    return docs


class _DocumentedJsonSchema(GenerateJsonSchema):
    """The JSON Schema with each field's docstring as its description (hover help in
    editors). Read from the source only when a schema is asked for: pydantic's own
    ``use_attribute_docstrings`` reads every class's source on import (0.09 s of each run)."""

    def model_schema(self, schema):
        json_schema = super().model_schema(schema)
        props = json_schema.get("properties")
        if props:
            docs = _field_docstrings()
            for name, prop in props.items():
                for cls in schema["cls"].__mro__:
                    text = docs.get(cls.__name__, {}).get(name)
                    if text and cls.__module__ == __name__:
                        prop.setdefault("description", text)
                        break
        return json_schema


class Spec(BaseModel):
    """Base of every part of the description: unknown keys are errors; values immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    @classmethod
    def model_json_schema(cls, *args, **kwargs):
        """pydantic's, with the fields' docstrings as their descriptions (hover help)."""
        kwargs.setdefault("schema_generator", _DocumentedJsonSchema)
        return super().model_json_schema(*args, **kwargs)


# --------------------------------------------------------------------------- declared elements
#: What the ``name`` of an element of each section is used for (its description), unless
#: the class says (``name_doc``); a contact joint's (``generic_reaction`` false) names its
#: contact forces.
_NAME_DOCS = {
    "joints": "Unique name of the joint; its reactions are the result columns ``name.Fx``, "
    "``name.Fy``, ``name.M``.",
    "drivers": "Unique name of the driver; its driving effort is the result column of that name.",
    "forces": "Unique name of the force element (used in a mixed run's ``unknown``).",
}
_CONTACT_NAME_DOC = "Unique name of the pair; its contact forces are result columns ``name.*``."
_TYPE_DOCS = {"joints": "Joint", "drivers": "Driver", "forces": "Force"}


class _DeclaredSpec(Spec):
    """An element described by its class's declaration (:mod:`mixdyn.model._declare`): its
    fields, their kinds and docs, read once from the class."""

    def build(self, b, p):
        """The element, every declared field read from the file at its own path; a fault the
        class finds in one field is reported at that field's line."""
        kind = self.declared
        values = {}
        for field, decl, _ in kind.fields():
            value, at = getattr(self, field), (*p, field)
            if isinstance(decl, _decl.Reference):
                if decl.many:
                    value = tuple(value)
                    for k, ref in enumerate(value):
                        b.point(ref, (*at, k))
                elif value is not None and decl.what == "body":
                    b.body(value, at)
                elif value is not None and decl.what == "point":
                    b.point(value, at)
            elif isinstance(decl, _decl.Direction):
                value = (
                    b.direction(value, at)
                    if decl.on is None
                    else b.axis(value, values[decl.on], at)
                )
            elif isinstance(decl, _decl.Coordinate):
                values[decl.body], value = b.coordinate(value, at)
            elif isinstance(decl, _decl.Quantity) and value is not None:
                unit = _decl.quantity_kind(kind.cls, field, values, b.element_class)
                value = (
                    b.law(value, unit, at, state=decl.state, variable=decl.variable)
                    if decl.law
                    else b.scalar(value, unit, at)
                )
            values[field] = value
        try:
            with warnings.catch_warnings():
                # What the class only warns of in Python (a deprecated default, a warning
                # that starts with the element's name) a file has to give.
                warnings.filterwarnings("error", f"{re.escape(self.name)}: ", DeprecationWarning)
                return kind.cls(self.name, **values)
        except ModelError as e:
            b.fail(b.fault_path(p, e), _without_element(e, self.name))
        except DeprecationWarning as w:
            b.fail(p, _without_element(ModelError(str(w)), self.name))

    @classmethod
    def from_element(cls, e, d):
        """The description of the element ``e`` (numbers in the model's units).

        Raises:
            ModelError: a reference a file cannot hold (a point given by coordinates).
        """
        values = {}
        for field, decl, _ in cls.declared.fields():
            value = getattr(e, field)
            if isinstance(decl, _decl.Reference) and decl.many:
                if not all(isinstance(v, str) for v in value):
                    raise ModelError(
                        f"{field}: a point given by coordinates cannot be written to a file; "
                        "name it among its body's points",
                        e.name,
                    )
                value = list(value)
            elif isinstance(decl, _decl.Reference):
                if value is not None and not isinstance(value, str):
                    raise ModelError(
                        f"{field}: a point given by coordinates cannot be written to a file; "
                        "name it among its body's points",
                        e.name,
                    )
            elif isinstance(decl, _decl.Direction):
                value = d.axis(value)
            elif isinstance(decl, _decl.Coordinate):
                value = f"{getattr(e, decl.body)}.{value}"
            elif isinstance(decl, _decl.Quantity) and value is not None:
                value = d.law(value, e.name, decl.variable) if decl.law else float(value)
            values[field] = value
        return cls(type=cls.declared.file_name, name=e.name, **values)


def _without_element(error: ModelError, name: str) -> str:
    """A model error's text without its element's name in front."""
    text = str(error)
    return text[len(name) + 2 :] if text.startswith(f"{name}: ") else text


#: The annotation of a reference field, by what it names.
_REFERENCE_TYPES = {"point": Ref, "body": Name, "joint": Name, "force": Name}


def _declared_field(decl, default):
    """The pydantic annotation and field of a declared field."""
    doc = decl.doc
    if isinstance(decl, _decl.Reference) and decl.many:
        annotation = list[Ref]
    elif isinstance(decl, _decl.Reference):
        annotation = _REFERENCE_TYPES[decl.what]
        if default is None:
            annotation = annotation | None
    elif isinstance(decl, _decl.Direction):
        annotation = Vec2 if decl.on is None else Vec2 | Name
    elif isinstance(decl, _decl.Coordinate):
        annotation = Ref
    elif isinstance(decl, _decl.Quantity):
        annotation = LawSpec if decl.law else Scalar
        if default is None and not decl.law:
            annotation = annotation | None
        doc = f"{decl.doc} [{decl.shown}]"
        if decl.file_default is not None:
            default = decl.file_default
    elif decl.choices:
        annotation = Literal[decl.choices]
    else:
        annotation = type(default) if default is not dataclasses.MISSING else str
    if default is dataclasses.MISSING:
        return annotation, Field(description=doc)
    if hasattr(default, "shape"):  # a number the class converted to an array
        default = float(default)
    return annotation, Field(default=default, description=doc)


def _declared_spec(kind) -> type[Spec]:
    """The file spec of a registered element class (:func:`mixdyn.model.element`)."""
    cls = kind.cls
    name_doc = getattr(cls, "name_doc", None) or (
        _CONTACT_NAME_DOC
        if kind.group == "joints" and not cls.generic_reaction
        else _NAME_DOCS[kind.group]
    )
    fields = {
        "type": (
            Literal[kind.file_name],
            Field(description=f"{_TYPE_DOCS[kind.group]} type: ``{kind.file_name}``."),
        ),
        "name": (Name, Field(description=name_doc)),
    }
    for field, decl, default in kind.fields():
        fields[field] = _declared_field(decl, default)
    doc = (cls.__doc__ or cls.__name__).strip().split("\n\n")[0]
    spec = create_model(f"{cls.__name__}Spec", __base__=_DeclaredSpec, __doc__=doc, **fields)
    spec.declared = kind
    spec.element_class = cls.__name__
    return spec


def _declared_specs(group: str, registry: dict) -> None:
    """Fill ``registry`` with the spec made from the declaration of every element class of
    ``group`` that declares its fields, in the order the classes were registered."""
    registry.clear()
    for kind in _decl.ELEMENTS[group].values():
        if kind.fields():
            registry[kind.cls.__name__] = _declared_spec(kind)


# --------------------------------------------------------------------------- laws
class ExpressionSpec(Spec):
    """``{expr: "10*sin(pi*t/2)", unit: N}``: an expression of ``t`` [model time unit]; its
    value is in ``unit`` (default: the model's unit of what it drives)."""

    expr: str
    """An expression of ``t`` [model time unit] and the parameters, e.g. ``"10*sin(pi*t/2)"``;
    force magnitudes may also use body states (``-c*wheel.omega``)."""
    unit: str | None = None
    """Unit of the expression's value, e.g. ``deg`` or ``N`` (default: the model's unit of the
    driven quantity)."""


class ConstantSpec(Spec):
    """``{constant: 5}``."""

    constant: Scalar
    """The constant value: a number in model units (angles in rad) or a quantity such as ``"5
    N"``."""


class PolynomialSpec(Spec):
    """``{polynomial: [c0, c1, ...]}``: ``sum c_k t**k``, coefficients in ``unit`` per time**k
    (default: model units)."""

    polynomial: list[Scalar] = Field(min_length=1)
    """Coefficients ``[c0, c1, ...]`` of ``c0 + c1 t + c2 t**2 + ...``; ``c_k`` in ``unit`` per
    time unit**k."""
    unit: str | None = None
    """Unit of the law's value, e.g. ``deg`` (default: the model's unit of the driven quantity)."""


class RampArgs(Spec):
    """Arguments of a ramp law: ``start + rate t``."""

    start: Scalar = 0.0
    """Value at ``t = 0``, in model units of the driven quantity (angles in rad) or with a unit.
    Default 0."""
    rate: Scalar
    """Rate of change per model time unit, e.g. ``"2 rad/s"``."""


class RampSpec(Spec):
    """``{ramp: {start: 0, rate: "2 rad/s"}}``: ``start + rate t``."""

    ramp: RampArgs
    """The ramp's ``start`` and ``rate``."""


class HarmonicArgs(Spec):
    """Arguments of a harmonic law: ``offset + amplitude sin(omega t + phase)``."""

    amplitude: Scalar
    """Amplitude, in model units of the driven quantity (angles in rad) or with a unit."""
    omega: Scalar
    """Angular frequency [rad per model time unit], e.g. ``"2 rad/s"``."""
    phase: Scalar = 0.0
    """Phase [rad] (or with a unit, ``"90 deg"``). Default 0."""
    offset: Scalar = 0.0
    """Constant added to the sine, in model units of the driven quantity. Default 0."""


class HarmonicSpec(Spec):
    """``{harmonic: {amplitude, omega, phase, offset}}``: ``offset + amplitude sin(omega t +
    phase)``."""

    harmonic: HarmonicArgs
    """The harmonic's ``amplitude``, ``omega``, ``phase`` and ``offset``."""


class SplineArgs(Spec):
    """Arguments of an interpolating spline law through ``(t, y)`` points."""

    t: list[Scalar] = Field(min_length=2)
    """Knot times [model time unit], strictly increasing (at least 2)."""
    y: list[Scalar] = Field(min_length=2)
    """Values at the knot times, one per time, in ``unit`` (default: model units)."""
    kind: Literal["cubic", "quintic"] = "cubic"
    """Spline degree: ``cubic`` (default) or ``quintic``."""
    unit: str | None = None
    """Unit of the values ``y``, e.g. ``deg`` (default: the model's unit of the driven quantity)."""


class SplineSpec(Spec):
    """``{spline: {t: [...], y: [...], kind: cubic}}``: an interpolating spline."""

    spline: SplineArgs
    """The spline's times ``t``, values ``y``, ``kind`` and ``unit``."""


class HermiteArgs(Spec):
    """Arguments of a quintic Hermite law: values and first two derivatives at given times."""

    t: list[Scalar] = Field(min_length=2)
    """Knot times [model time unit], strictly increasing (at least 2)."""
    y: list[Scalar] = Field(min_length=2)
    """Values at the knot times, one per time, in ``unit`` (default: model units)."""
    yd: list[Scalar] = Field(min_length=2)
    """First time derivatives at the knot times, in ``unit`` per time unit."""
    ydd: list[Scalar] = Field(min_length=2)
    """Second time derivatives at the knot times, in ``unit`` per time unit**2."""
    unit: str | None = None
    """Unit of the values, e.g. ``deg`` (default: the model's unit of the driven quantity)."""


class HermiteSpec(Spec):
    """``{hermite: {t, y, yd, ydd}}``: quintic Hermite through values and two derivatives."""

    hermite: HermiteArgs
    """The times ``t``, values ``y``, derivatives ``yd``, ``ydd`` and ``unit``."""


class PiecewiseArgs(Spec):
    """Arguments of a piecewise polynomial law (scipy ``PPoly`` layout), in model units."""

    breaks: list[float] = Field(min_length=2)
    """Break points [model time unit], strictly increasing (at least 2)."""
    coeffs: list[list[float]] = Field(min_length=1)
    """Coefficient rows: ``coeffs[k][i]`` multiplies ``(t - breaks[i])**(K-k)``; each row has one
    entry per interval. Plain numbers in model units."""


class PiecewiseSpec(Spec):
    """``{piecewise: {breaks, coeffs}}``: a piecewise polynomial (scipy ``PPoly`` layout:
    ``coeffs[k][i]`` of ``(t - breaks[i])**(K-k)``), in model units."""

    piecewise: PiecewiseArgs
    """The ``breaks`` and ``coeffs``."""


LAW_KEYS = ("expr", "constant", "polynomial", "ramp", "harmonic", "spline", "hermite", "piecewise")


def _law_tag(v: Any) -> str | None:
    if isinstance(v, Spec):
        for k in LAW_KEYS:
            if k in type(v).model_fields:
                return k
        return None
    if isinstance(v, dict):
        keys = [k for k in LAW_KEYS if k in v]
        return keys[0] if len(keys) == 1 else None
    if isinstance(v, int | float | str) and not isinstance(v, bool):
        return "scalar"
    return None


LawSpec = Annotated[
    Annotated[Scalar, Tag("scalar")]
    | Annotated[ExpressionSpec, Tag("expr")]
    | Annotated[ConstantSpec, Tag("constant")]
    | Annotated[PolynomialSpec, Tag("polynomial")]
    | Annotated[RampSpec, Tag("ramp")]
    | Annotated[HarmonicSpec, Tag("harmonic")]
    | Annotated[SplineSpec, Tag("spline")]
    | Annotated[HermiteSpec, Tag("hermite")]
    | Annotated[PiecewiseSpec, Tag("piecewise")],
    Discriminator(
        _law_tag,
        custom_error_type="law",
        custom_error_message=(
            "a law is a number, an expression such as '2*t', or a mapping with exactly one of "
            "the keys " + ", ".join(LAW_KEYS)
        ),
    ),
]
"""A law of time (or, for force magnitudes, of the state)."""


# --------------------------------------------------------------------------- model parts
class UnitsSpec(Spec):
    """The model's unit system (pint spellings); angles are always radians."""

    length: str = "m"
    """Unit of length for every number without a unit (pint spelling, e.g. ``mm``). Default
    ``m``."""
    mass: str = "kg"
    """Unit of mass (pint spelling, e.g. ``g``). Default ``kg``."""
    time: str = "s"
    """Unit of time, also that of ``t`` in laws (pint spelling, e.g. ``ms``). Default ``s``."""


class GroundSpec(Spec):
    """The fixed frame: named points in global coordinates [length]."""

    points: dict[str, Vec2] = Field(default_factory=dict)
    """Named fixed points ``{A: [x, y]}`` in global coordinates [length]; referred to as
    ``ground.A``."""


class BodySpec(Spec):
    """A rigid body; its frame is at the centre of mass.

    ``q0`` is the rough starting pose ``[x, y, phi]``; ``points`` and ``vectors`` are given in
    the body frame.
    """

    name: Name
    """Unique name of the body (letters, digits, ``_``, ``-``); ``ground`` is reserved."""
    mass: Scalar = 0.0
    """Mass [mass unit]; 0 (the default) is allowed for kinematics only."""
    inertia: Scalar = 0.0
    """Moment of inertia about the centre of mass [mass*length**2], e.g. ``"20 kg*mm^2"``; >= 0.
    Default 0."""
    q0: tuple[Scalar, Scalar, Scalar] = (0.0, 0.0, 0.0)
    """Rough starting pose ``[x, y, phi]`` of the centre of mass [length, length, rad]; assembly
    corrects it. Default ``[0, 0, 0]``."""
    points: dict[str, Vec2] = Field(default_factory=dict)
    """Named points ``{B: [x, y]}`` in the body frame [length]; referred to as ``body.B``
    (``body`` alone is the centre of mass)."""
    vectors: dict[str, Vec2] = Field(default_factory=dict)
    """Named directions ``{u: [x, y]}`` in the body frame (e.g. a slider axis, used by a joint's
    ``axis``)."""


#: The element registries: an element kind (joint, driver, force) is one model class
#: (``mixdyn.model``) and the spec made from the class's declaration
#: (:func:`_declared_specs`), by the model class's name. The spec builds the element
#: (``build``) and describes one (``from_element``). Loading, writing back and the schema's
#: ``joints``, ``drivers`` and ``forces`` unions read these registries; nothing else in
#: ``io`` names an element kind.
JOINT_SPECS: dict[str, type] = {}


#: The driver and force registries, as :data:`JOINT_SPECS`.
DRIVER_SPECS: dict[str, type] = {}
FORCE_SPECS: dict[str, type] = {}


_declared_specs("joints", JOINT_SPECS)
JointSpec = Annotated[
    functools.reduce(operator.or_, JOINT_SPECS.values()),
    Field(discriminator="type"),
]
"""Any registered joint kind (:data:`JOINT_SPECS`), told apart by ``type``."""


_declared_specs("drivers", DRIVER_SPECS)
DriverSpec = Annotated[
    functools.reduce(operator.or_, DRIVER_SPECS.values()),
    Field(discriminator="type"),
]
"""Any registered driver kind (:data:`DRIVER_SPECS`), told apart by ``type``."""


_declared_specs("forces", FORCE_SPECS)


ForceSpec = Annotated[
    functools.reduce(operator.or_, FORCE_SPECS.values()),
    Field(discriminator="type"),
]
"""Any registered force kind (:data:`FORCE_SPECS`), told apart by ``type``."""


class AssemblySpec(Spec):
    """How the starting pose is closed: coordinates held at their ``q0`` value."""

    hold: list[Ref] = Field(default_factory=list)
    """Coordinates (``body.x``, ``body.y``, ``body.phi``) kept at their ``q0`` value while the
    joints are closed, e.g. ``[crank.phi]``. Default none."""


# --------------------------------------------------------------------------- runs
class TimeSpec(Spec):
    """Output times: ``span`` with ``n`` points or a ``step``, or explicit ``values``."""

    span: tuple[Scalar, Scalar] | None = None
    """Start and end time ``[t0, t1]`` [model time unit]; give with ``n`` or ``step``."""
    n: int | None = Field(default=None, ge=2, le=1_000_000)
    """Number of output times over ``span``, including both ends (2 to 1,000,000)."""
    step: Scalar | None = None
    """Spacing of the output times over ``span`` [model time unit], e.g. ``"1 ms"``."""
    values: list[Scalar] | None = Field(default=None, min_length=1)
    """Explicit output times [model time unit], increasing; give alone, without ``span``."""

    @model_validator(mode="after")
    def _one_form(self):
        explicit = self.values is not None and (self.span, self.n, self.step) == (None,) * 3
        spanned = self.values is None and self.span is not None
        ok = explicit or (spanned and (self.n is None) != (self.step is None))
        if not ok:
            raise ValueError("give 'span' with either 'n' or 'step', or give 'values' alone")
        return self


class PrescribedSpec(Spec):
    """A prescribed motion: ``coordinate`` (``slider.x``; ``slider.D.x`` for a point) follows
    ``law`` or the motion computed by the run ``from_run``."""

    coordinate: Ref
    """The prescribed coordinate: ``body.x``, ``body.y``, ``body.phi``, or a point's ``body.P.x``
    / ``body.P.y``."""
    name: Name | None = None
    """Name of the prescribed motion (its effort's result column); default ``prescribed
    <coordinate>``."""
    law: LawSpec | None = None
    """The motion as a law of time (length or rad); give either this or ``from_run``."""
    from_run: Name | None = None
    """Name of another run whose computed motion of this coordinate is replayed (that run is
    executed first)."""
    continuity: Literal["C1", "C2"] = "C2"
    """How smooth the law must be: ``C2`` (default: continuous with its slope and second
    derivative, as the accelerations and forces a run reports need) or ``C1`` (its second
    derivative may jump: constant-acceleration segments, a trapezoidal speed)."""

    @model_validator(mode="after")
    def _one_source(self):
        if (self.law is None) == (self.from_run is None):
            raise ValueError("give exactly one of 'law' and 'from_run'")
        return self


class ReferenceSpec(Spec):
    """A reference curve drawn beside the plotted columns: an expression of ``t``."""

    expr: str
    """The reference curve: an expression of ``t`` [model time unit] and the parameters."""
    label: Text | None = None
    """Legend label of the reference curve."""
    unit: str | None = None
    """Unit of the expression's value, e.g. ``deg`` (default: model units)."""


class PlotSpec(Spec):
    """A figure of some columns against time (or another column), a panel per unit, written
    to the run's output folder."""

    file: PlotFile
    """Figure file relative to the run's output folder: ``.png``, ``.svg`` or ``.pdf``."""
    columns: list[str] = Field(min_length=1)
    """Result columns to plot, e.g. ``[slider.x, crank.phi, A.Fx]`` (one panel per unit)."""
    x: str = "t"
    """The column on the x axis (default ``t``), e.g. ``crank.phi`` for the torque against the
    crank angle."""
    title: Text | None = None
    """Figure title (default: none)."""
    ylabel: Text | None = None
    """Label of the y axis (default: none)."""
    reference: ReferenceSpec | None = None
    """A reference curve ``{expr, label, unit}`` drawn beside the columns."""


class AnimationSpec(Spec):
    """An animation of the run, written to the run's output folder."""

    file: AnimationFile = "animation.gif"
    """Animation file relative to the run's output folder: ``.gif``, ``.mp4`` (needs ffmpeg) or
    ``.html``. Default ``animation.gif``."""
    html: bool = True
    """Also write an interactive ``.html`` animation beside ``file`` (same name). Default true."""
    fps: int = Field(default=20, ge=1, le=120)
    """Frames per second (1 to 120). Default 20."""
    frames: int = Field(default=80, ge=2, le=2000)
    """Largest number of frames of a GIF or MP4, at evenly spaced output times (2 to 2000).
    Default 80. The HTML player shows every output time."""
    trace: list[Ref] = Field(default_factory=list)
    """Points whose paths are drawn, e.g. ``[coupler.C]``. Default none."""
    forces: bool | list[Name] = False
    """Forces drawn as arrows (one scale for all): ``true`` for every joint's reaction (on its
    body j) and every point force, or a list of joint and force names. Not in kinematic runs.
    Default false."""
    plot: list[str] | None = None
    """Result columns the HTML player offers first in its plot (any other is chosen in the
    page); a cursor follows the frame, a click on the plot moves the animation there. Default:
    the drivers' efforts (else the unknown forces, else the bodies' angles); ``[]`` for no
    plot."""
    plot_x: str = "t"
    """The column on the x axis of the HTML player's plot on opening (default ``t``), e.g.
    ``crank.phi`` for the slider's position against the crank angle (a phase plot: the cursor
    is the frame's point, a click goes to the nearest point on the curve)."""


class _RunSpec(Spec):
    """Settings common to every kind of run."""

    name: Name
    """Unique name of the run (its output folder's name)."""
    time: TimeSpec
    """Output times: ``{span: [0, 2], n: 201}``, ``{span, step}`` or ``{values: [...]}``."""
    linear_solver: Literal["auto", "dense", "unrolled", "sparse", "banded"] = "auto"
    """Linear algebra, as :class:`mixdyn.LinearSolver` names it: ``auto`` (default:
    straight-line code for a few rows, sparse for large mechanisms of small bandwidth, else
    dense), ``dense``, ``unrolled`` (straight-line factorizations, for a few rows) or
    ``sparse`` (also ``banded``)."""
    drivers: list[Name] | None = None
    """Names of the model's drivers used by this run (default: all)."""
    prescribed: list[PrescribedSpec] = Field(default_factory=list)
    """Extra prescribed motions of this run (in a mixed run, one per unknown force)."""
    hold: list[Ref] | None = None
    """Coordinates kept at their starting value (and speed) while the joints are closed (default:
    ``assembly.hold``; ``[]`` holds nothing)."""
    initial: dict[str, Scalar] = Field(default_factory=dict)
    """Rough start positions ``{coordinate: value}`` overriding ``q0``, e.g. ``{crank.phi: 10
    deg}`` [length or rad]."""
    velocities: dict[str, Scalar] = Field(default_factory=dict)
    """Start velocities kept exactly, forward/mixed runs only, ``{coordinate: value}`` [length or
    rad per time unit], e.g. ``{crank.phi: 1 rad/s}`` (default: at rest)."""
    outputs: list[Ref] = Field(default_factory=list)
    """Points whose global position, velocity and acceleration are written to
    ``results.csv`` as columns ``body.P.x``, ``.y``, ``.vx``, ``.vy``, ``.ax``, ``.ay``, e.g.
    ``[coupler.P]`` (plots may use any point without listing it). Default none."""
    plots: list[PlotSpec] = Field(default_factory=list)
    """Figures of result columns to write."""
    animation: AnimationSpec | None = None
    """An animation of the run to write."""


class KinematicRunSpec(_RunSpec):
    """Motion prescribed for every degree of freedom (``mixdyn.kinematic``)."""

    kind: Literal["kinematic"]
    """Run kind: ``kinematic``."""
    tol: float | None = Field(default=None, gt=0, allow_inf_nan=False)
    """Newton tolerance on the largest constraint residual [length] (default: 1e-12 times the
    mechanism's size)."""
    max_iter: int = Field(default=25, ge=1, le=1000)
    """Newton iterations per output time (1 to 1000). Default 25."""


class StaticsRunSpec(_RunSpec):
    """The equilibrium under the loads, or a sequence of them as the drivers move
    (``mixdyn.statics``): free degrees of freedom settle, drivers hold theirs."""

    kind: Literal["statics"]
    """Run kind: ``statics`` (a quasi-static analysis over several output times)."""
    tol: float = Field(default=1e-10, gt=0, allow_inf_nan=False)
    """Relative tolerance of Newton's method on the force and constraint residuals. Default
    1e-10."""
    max_iter: int = Field(default=100, ge=1, le=10_000)
    """Newton iterations per output time (1 to 10,000). Default 100."""


Method = Literal["projection", "baumgarte", "partitioning", "generalized-alpha"]
Option = float | int | str | bool | None  # None: a check turned off (energy_tol: null)


class ForwardRunSpec(_RunSpec):
    """Forces known, motion sought (``mixdyn.forward``)."""

    kind: Literal["forward"]
    """Run kind: ``forward``."""
    method: Method = "projection"
    """Integrator: ``projection`` (default), ``baumgarte``, ``partitioning`` or
    ``generalized-alpha``."""
    rtol: float = Field(default=1e-8, gt=0, allow_inf_nan=False)
    """Relative tolerance of the adaptive integrators. Default 1e-8."""
    atol: float = Field(default=1e-10, gt=0, allow_inf_nan=False)
    """Absolute tolerance of the adaptive integrators, in model units. Default 1e-10."""
    dt: Scalar | None = None
    """Time step of the fixed-step methods [model time unit], e.g. ``"1 ms"``."""
    options: dict[str, Option] = Field(default_factory=dict)
    """Integrator options, e.g. ``{rho_inf: 0.9}``, ``{energy_tol: 1.0e-3}`` (``null`` turns the
    energy check off), ``{solver: dopri8, max_steps: 100000}``; unknown options are errors."""


class InverseRunSpec(_RunSpec):
    """Motion prescribed, driving forces and reactions sought (``mixdyn.inverse``)."""

    kind: Literal["inverse"]
    """Run kind: ``inverse``."""
    options: dict[str, Option] = Field(default_factory=dict)
    """Options of the position analysis: ``tol`` [length], ``max_iter`` (default 25),
    ``singular_tol`` (default 1e-7), ``assemble_first`` (default true); unknown ones are errors."""


class MixedRunSpec(_RunSpec):
    """Some forces unknown, as many motions prescribed (``mixdyn.mixed``)."""

    kind: Literal["mixed"]
    """Run kind: ``mixed``."""
    unknown: list[Name] = Field(min_length=1)
    """Force elements whose magnitude is sought, e.g. ``[F1]`` (as many as prescribed motions)."""
    solver: Literal["augmented", "partition"] = "augmented"
    """Mixed solver: ``augmented`` (default, general) or ``partition`` (coordinate partitioning)."""
    independent: list[Ref] | None = None
    """For ``solver: partition``, the independent coordinates, e.g. ``[coupler.phi]`` (default:
    chosen by pivoted LU)."""
    method: Method = "projection"
    """Integrator: ``projection`` (default), ``baumgarte``, ``partitioning`` or
    ``generalized-alpha``."""
    rtol: float = Field(default=1e-8, gt=0, allow_inf_nan=False)
    """Relative tolerance of the adaptive integrators. Default 1e-8."""
    atol: float = Field(default=1e-10, gt=0, allow_inf_nan=False)
    """Absolute tolerance of the adaptive integrators, in model units. Default 1e-10."""
    dt: Scalar | None = None
    """Time step of the fixed-step methods [model time unit], e.g. ``"1 ms"``."""
    options: dict[str, Option] = Field(default_factory=dict)
    """Integrator options, e.g. ``{rho_inf: 0.9}``, ``{energy_tol: 1.0e-3}`` (``null`` turns the
    energy check off), ``{solver: dopri8, max_steps: 100000}``; unknown options are errors."""


class VarySpec(Spec):
    """The values a swept quantity takes: ``values``, or a ``span`` with ``n`` evenly spaced
    values (a grid), or a ``span`` alone (``sampling: latin_hypercube``)."""

    values: list[Scalar] | None = Field(default=None, min_length=1)
    """Explicit values, e.g. ``[5 N, 10 N, 20 N]`` (numbers: model units)."""
    span: tuple[Scalar, Scalar] | None = None
    """Lowest and highest value ``[low, high]``, e.g. ``[5, 15]``."""
    n: int | None = Field(default=None, ge=1, le=1_000_000)
    """Number of evenly spaced values over ``span``, both ends included (grid sampling)."""

    @model_validator(mode="after")
    def _one_form(self):
        if self.values is not None and (self.span is not None or self.n is not None):
            raise ValueError("give 'values' alone, or 'span' (with 'n' for a grid)")
        if self.values is None and self.span is None:
            raise ValueError("give 'values', or 'span' (with 'n' for a grid)")
        return self


SUMMARY_REDUCTIONS = ("max", "min", "absmax", "mean", "rms", "first", "last", "range")


class SummarySpec(Spec):
    """A number per member made from a result column over time, e.g. the peak of a
    reaction: ``{name: x_peak, column: slider.x, reduce: max}``."""

    name: Name
    """Name of the summary (its column in ``members.csv``; usable in plots)."""
    column: str
    """The result column it reduces, e.g. ``slider.x``, ``A.Fx``, ``F1``."""
    reduce: Literal["max", "min", "absmax", "mean", "rms", "first", "last", "range"] = "absmax"
    """How: ``max``, ``min``, ``absmax`` (default: the largest magnitude), ``mean``, ``rms``
    (over the output times), ``first``, ``last``, ``range`` (max - min)."""


class SweepPlotSpec(Spec):
    """A figure of a sweep: a summary against a swept quantity (``x``, ``y``, optional
    ``by``: one curve per value), or the band of a column's time histories (``band``)."""

    file: PlotFile
    """Figure file relative to the run's output folder: ``.png``, ``.svg`` or ``.pdf``."""
    x: str | None = None
    """A swept quantity on the x axis (a name in ``vary``)."""
    y: Name | None = None
    """A summary on the y axis (a name in ``summaries``)."""
    by: str | None = None
    """Another swept quantity: one curve per value of it (at most 8 drawn, evenly picked);
    with Latin hypercube sampling, the points' colour."""
    band: str | None = None
    """A result column: its time histories over the members drawn as a band (the range, the
    10-90 % band and the median), instead of ``x``/``y``."""
    title: Text | None = None
    """Figure title (default: none)."""

    @model_validator(mode="after")
    def _one_form(self):
        against = self.x is not None or self.y is not None
        if self.band is not None and (against or self.by is not None):
            raise ValueError("give either 'band' or 'x' and 'y' (with an optional 'by')")
        if self.band is None and (self.x is None or self.y is None):
            raise ValueError("give 'x' (a swept quantity) and 'y' (a summary), or 'band'")
        return self


class SweepRunSpec(Spec):
    """Another run repeated over many values of some numbers (``mixdyn.sweep``)."""

    kind: Literal["sweep"]
    """Run kind: ``sweep``."""
    name: Name
    """Unique name of the run (its output folder's name)."""
    run: Name
    """The run swept: its analysis, output times, solver settings, start and prescribed
    motions (laws, not ``from_run``) are every member's."""
    vary: dict[str, VarySpec] = Field(min_length=1)
    """What changes, by name: a file parameter (``F0``) or a number of a body or element
    (``slider.mass``, ``F1.law.amplitude``; numbers in model units), each with its values:
    ``{F0: {span: [5, 15], n: 40}, m5: {values: [0.005, 0.01]}}``."""
    sampling: Literal["grid", "latin_hypercube"] = "grid"
    """``grid`` (default: every combination of the values) or ``latin_hypercube`` (``samples``
    members spread over the spans)."""
    samples: int | None = Field(default=None, ge=1, le=1_000_000)
    """Number of members of a Latin hypercube sampling."""
    seed: int = Field(default=0, ge=0)
    """Seed of the Latin hypercube sampling (the same seed, the same members). Default 0."""
    summaries: list[SummarySpec] = Field(default_factory=list)
    """Numbers per member, written to ``members.csv``, e.g. ``{name: x_peak, column:
    slider.x, reduce: max}``."""
    outputs: list[str] | None = None
    """Result columns of every member written to ``table.csv`` in long format (one row per
    member and output time); default: the columns the summaries and bands use."""
    batch_size: int | None = Field(default=None, ge=1)
    """Members integrated by one vectorized program at a time (default: member by member on
    a CPU, 32,768 on an accelerator)."""
    plots: list[SweepPlotSpec] = Field(default_factory=list)
    """Figures of the sweep: ``{file, x, y, by}`` or ``{file, band}``."""

    @model_validator(mode="after")
    def _sampling(self):
        if self.sampling == "latin_hypercube":
            if self.samples is None:
                raise ValueError("latin_hypercube sampling needs 'samples' (how many members)")
            bad = [k for k, v in self.vary.items() if v.span is None or v.n is not None]
            if bad:
                raise ValueError(
                    f"latin_hypercube sampling takes a 'span' alone for each swept quantity "
                    f"(not {', '.join(bad)})"
                )
        else:
            if self.samples is not None:
                raise ValueError("'samples' is for latin_hypercube sampling; a grid has none")
            bad = [k for k, v in self.vary.items() if v.values is None and v.n is None]
            if bad:
                raise ValueError(f"a grid needs 'values' or 'span' with 'n' for {', '.join(bad)}")
        return self


class MeasuredSpec(Spec):
    """A measured column: which result column it measures, where it is in the data file and
    how noisy it is."""

    column: Ref
    """The result column measured: a body coordinate (``slider.x``, ``crank.phi``) or
    velocity (``slider.vx``, ``crank.omega``)."""
    data: str
    """Its column in the data file (values in model units)."""
    noise: Scalar
    """Standard deviation of the measurement, e.g. ``0.1 mm``, ``1 mrad`` (the residuals'
    weight)."""


class FitSpec(Spec):
    """A number to fit: where it starts and its bounds."""

    start: Scalar | None = None
    """First guess (default: the model's value)."""
    bounds: tuple[Scalar, Scalar] | None = None
    """``[low, high]`` the fit stays within (default: unbounded)."""


class IdentifyRunSpec(Spec):
    """Numbers of the model fitted to a measured motion (``mixdyn.fit``)."""

    kind: Literal["identify"]
    """Run kind: ``identify``."""
    name: Name
    """Unique name of the run (its output folder's name)."""
    run: Name
    """The forward or mixed run whose settings (solver, tolerances, start) the fit uses; its
    output times are the data's times."""
    data: DataFile
    """The measurements: a CSV file (relative to the model file) with a column ``t`` [model
    time unit], increasing, and the measured columns."""
    measured: list[MeasuredSpec] = Field(min_length=1)
    """The measured columns: ``{column: slider.x, data: x, noise: 0.1 mm}``."""
    fit: dict[str, FitSpec] = Field(min_length=1)
    """The numbers to fit, by path (``slider.mass``, ``damper.damping``: numbers of bodies and
    force elements, model units): ``{slider.mass: {start: 1.3, bounds: [0.1, 10]}}``."""
    max_evaluations: int = Field(default=200, ge=1, le=100_000)
    """Runs the fit may make at most. Default 200."""


class ObjectiveSpec(Spec):
    """A scalar of a run: a result column reduced over the output times."""

    column: str
    """The column: a body coordinate or velocity (``slider.x``, ``crank.omega``), or in an
    inverse run a reaction or driver effort (``B.Fx``, ``motor``)."""
    reduce: Literal["max", "min", "absmax", "mean", "rms", "first", "last", "range"] = "rms"
    """How: ``rms`` (default), ``max``, ``min``, ``absmax``, ``mean``, ``first``, ``last``,
    ``range``."""


class DesignVariableSpec(Spec):
    """A number to choose: its bounds and where the search starts."""

    bounds: tuple[Scalar, Scalar]
    """``[low, high]``, e.g. ``[0 N/mm, 100 N/mm]``."""
    start: Scalar | None = None
    """First guess (default: the model's value, moved into the bounds)."""


class OptimizeRunSpec(Spec):
    """Numbers of the model chosen to minimize (or maximize) a scalar of a run
    (``mixdyn.optimize``)."""

    kind: Literal["optimize"]
    """Run kind: ``optimize``."""
    name: Name
    """Unique name of the run (its output folder's name)."""
    run: Name
    """The forward, mixed or inverse run whose result the objective reduces (its times,
    solver and start)."""
    objective: ObjectiveSpec
    """The scalar: ``{column: motor, reduce: rms}``."""
    sense: Literal["minimize", "maximize"] = "minimize"
    """``minimize`` (default) or ``maximize`` the objective."""
    vary: dict[str, DesignVariableSpec] = Field(min_length=1)
    """The numbers to choose, by path (numbers of bodies and force elements):
    ``{spring.stiffness: {bounds: [0 N/mm, 100 N/mm]}}``."""
    max_iterations: int = Field(default=500, ge=1, le=100_000)
    """Iterations of L-BFGS-B at most. Default 500."""


class SynthesisMassesSpec(Spec):
    """How a synthesized linkage's links weigh: bars of one linear density (the coupler a
    triangle of bars through its pins and the coupler point), a payload at the coupler point
    and a slider-crank's slider."""

    density: Scalar
    """The bars' linear density [mass/length], e.g. ``2 kg/m``."""
    payload: Scalar = 0.0
    """A point mass at the coupler point [mass], e.g. ``0.5 kg``. Default 0."""
    slider: Scalar = 0.0
    """A slider-crank's slider, a point mass at its pin [mass], e.g. ``0.5 kg``; needed
    (> 0) with a slider-crank's masses."""


class SynthesisFunctionSpec(Spec):
    """Function generation: the linkage's output (the run's ``linkage``: a four-bar's rocker
    angle, a slider-crank's slider position, a six-bar's follower angle) as a function of the
    crank's angle, as pairs or as ``y = f(x)`` over a range mapped onto the crank's angles
    and the outputs."""

    pairs: list[tuple[Scalar, Scalar]] | None = Field(default=None, min_length=2)
    """``[crank angle, output]`` pairs from the ground link: the output an angle [rad] (a
    four-bar's rocker, a six-bar's follower), e.g. ``[[0 deg, 240 deg], ...]``, or a
    slider-crank's slider position along its slide [length], e.g. ``[[0 deg, 120 mm],
    ...]``."""
    expr: Text | None = None
    """``f`` as an expression of ``x`` (and the file's parameters), e.g. ``log10(x)``."""
    x: tuple[Scalar, Scalar] | None = None
    """The range ``[x0, x1]`` of ``x``."""
    input: tuple[Scalar, Scalar] | None = None
    """The crank's angles at ``x0`` and ``x1`` [rad], e.g. ``[0 deg, 60 deg]``."""
    output: tuple[Scalar, Scalar] | None = None
    """The outputs at ``f(x0)`` and ``f(x1)``: angles [rad], e.g. ``[240 deg, 180 deg]``, or a
    slider-crank's positions [length], e.g. ``[100 mm, 160 mm]``."""
    points: int = Field(default=3, ge=2, le=1000)
    """Precision points of ``f``. Default 3."""
    spacing: Literal["chebyshev", "even"] = "chebyshev"
    """The precision points' spacing: ``chebyshev`` (default) or ``even``."""
    free_start: bool = False
    """The inputs and outputs count from starts found too (only differences count). Default
    false."""
    ratios: tuple[Scalar, Scalar] = (0.05, 20.0)
    """Bounds of the link lengths as multiples of the ground link (a slider-crank's crank and
    rod: of the outputs' span; its offset, a six-bar's dyad points within ``±high``). Default
    ``[0.05, 20]``."""

    @model_validator(mode="after")
    def _one_form(self):
        given = [self.x, self.input, self.output]
        if (self.pairs is None) == (self.expr is None):
            raise ValueError("give 'pairs', or 'expr' with 'x', 'input' and 'output'")
        if self.expr is not None and any(v is None for v in given):
            raise ValueError("'expr' needs 'x', 'input' and 'output'")
        if self.pairs is not None and any(v is not None for v in given):
            raise ValueError("'x', 'input' and 'output' go with 'expr', not with 'pairs'")
        return self


class SynthesisMotionSpec(Spec):
    """Motion generation: the coupler carried through precision poses (its coupler point and
    the angle of a line fixed in it), in their order as the crank turns."""

    poses: list[tuple[Scalar, Scalar, Scalar]] = Field(min_length=3)
    """Three or more poses ``[x, y, angle]``: the coupler point [length] and the coupler's
    angle with its unit, e.g. ``[[0 mm, 0 mm, 0 deg], [300 mm, 250 mm, 40 deg], ...]``."""
    length: Scalar | None = None
    """The length that weighs the angle error (an angle error of 1/length rad counts as
    a point missed by a unit of length) [length]. Default: the poses' size."""


class SynthesisPivotSpec(Spec):
    """A rectangle in which a ground pivot of a synthesized linkage lies."""

    x: tuple[Scalar, Scalar]
    """``[low, high]`` of the pivot's x [length], e.g. ``[400 mm, 600 mm]``."""
    y: tuple[Scalar, Scalar]
    """``[low, high]`` of the pivot's y [length], e.g. ``[-100 mm, 0 mm]``."""


class SynthesisRunSpec(Spec):
    """A linkage synthesized to draw a path, carry its coupler through poses or generate a
    function (``mixdyn.synthesize``): random starts refined by Levenberg-Marquardt, a path's
    or a motion's motor torque optionally in the objective. Needs no mechanism in the
    file."""

    kind: Literal["synthesis"]
    """Run kind: ``synthesis``."""
    name: Name
    """Unique name of the run (its output folder's name)."""
    points: list[Vec2] | None = Field(default=None, min_length=2)
    """Path generation: the target points ``[x, y]`` [length], in the order the coupler
    point passes them as the crank turns positively, e.g. ``[[500 mm, 300 mm], ...]``."""
    shape: Literal["points", "fourier"] = "points"
    """The path's error: ``points`` (default: the coupler point through each point) or
    ``fourier`` (shape alone: the points are a closed curve's; the coupler curve over a full
    crank turn takes its shape by normalised elliptic Fourier descriptors, then is placed
    onto them)."""
    harmonics: int = Field(default=8, ge=2, le=64)
    """The elliptic Fourier harmonics compared with ``shape: fourier``; more than twice as
    many points needed. Default 8."""
    sense: Literal["either", "positive"] = "either"
    """With ``shape: fourier``: ``either`` (default: the points run through in either sense,
    the crank turning backwards where reversed) or ``positive`` (in their order as the crank
    turns positively)."""
    function: SynthesisFunctionSpec | None = None
    """Function generation instead of a path: ``{expr: log10(x), x: [1, 2], input: [0 deg,
    60 deg], output: [240 deg, 180 deg]}`` or ``{pairs: [[crank, rocker], ...]}``."""
    motion: SynthesisMotionSpec | None = None
    """Motion generation instead of a path: ``{poses: [[0 mm, 0 mm, 0 deg], [300 mm, 250 mm,
    40 deg], ...]}`` (the coupler point and angle at each pose)."""
    linkage: Literal["four_bar", "slider_crank", "stephenson1", "stephenson3", "watt1", "watt2"] = (
        "four_bar"
    )
    """``four_bar`` (default), ``slider_crank`` (its coupler point on the rod),
    ``stephenson1``, ``stephenson3``, ``watt1`` or ``watt2`` (a six-bar; its coupler point on
    ``D E``). A function's output: a four-bar's rocker angle, a slider's position, a
    ``stephenson3``'s or ``watt2``'s follower angle."""
    timing: Literal["free"] | list[Scalar] = "free"
    """``free`` (default: the crank's angles at the points are found, increasing within a
    turn) or the crank's angle at each point [rad], e.g. ``[0 deg, 40 deg, ...]`` (only
    their differences count, unless ``timing_from: ground``)."""
    timing_from: Literal["first", "ground"] = "first"
    """``first`` (default: the timing counts from the crank's angle at the first point, which
    the search finds) or ``ground`` (the timing is the crank's angle from the ground link,
    a slider-crank's from its slide)."""
    bounds: dict[str, tuple[Scalar, Scalar]] = Field(default_factory=dict)
    """``[low, high]`` of the linkage's numbers: a four-bar's ``r1``-``r4``, a slider-crank's
    ``r2``, ``r3``, ``e`` (offset); ``rcx``, ``rcy`` (coupler point), ``x0``, ``y0`` (crank
    pivot) [length], ``theta0`` [rad]. Default: lengths 0.05-5 target sizes."""
    min_transmission: Scalar = 0.0
    """The least transmission angle along the motion [rad], e.g. ``40 deg``. Default 0."""
    grashof: Literal["any", "grashof", "crank_rocker", "double_crank"] = "any"
    """The Grashof type: ``crank_rocker`` (the crank the shortest link: it turns fully; a
    slider-crank's ``r2 + |e| <= r3``), ``double_crank`` (the ground the shortest),
    ``grashof`` (any link the shortest, ``s + l <= p + q``) or ``any`` (default)."""
    pivots: dict[str, SynthesisPivotSpec] = Field(default_factory=dict)
    """Rectangles in which the ground pivots lie: ``O2`` (the crank's) and a four-bar's ``O4``
    (the rocker's), e.g. ``{O4: {x: [400 mm, 600 mm], y: [-100 mm, 0 mm]}}``. Default none."""
    masses: SynthesisMassesSpec | None = None
    """How the links weigh (needed for the torque): ``{density: 2 kg/m, payload: 0.5
    kg}``; gravity is the file's ``gravity``. Default: none (kinematics only)."""
    speed: Scalar = 1.0
    """The crank's constant speed [rad/time], e.g. ``2*pi rad/s``. Default 1."""
    torque: Literal["rms", "peak"] = "rms"
    """The motor torque's measure in the objective: ``rms`` (default) or ``peak``."""
    torque_weight: Scalar = 0.0
    """Weight of the torque measure squared beside the squared path error
    [length**2/torque**2], e.g. ``1e-4 m^2/(N*m)^2``. Default 0: the path alone."""
    shaking: Literal["rms", "peak"] = "rms"
    """The shaking force's and moment's measure in the objective: ``rms`` (default) or
    ``peak``."""
    shaking_force_weight: Scalar = 0.0
    """Weight of the shaking force's measure squared (what the links' inertia passes to the
    frame) [length**2/force**2], e.g. ``1e-4 m^2/N^2``. Default 0."""
    shaking_moment_weight: Scalar = 0.0
    """Weight of the shaking moment's measure squared (about the crank's pivot)
    [length**2/torque**2], e.g. ``1e-4 m^2/(N*m)^2``. Default 0."""
    reaction: Literal["peak", "rms"] = "peak"
    """The joint reactions' measure in the objective: ``peak`` (default: a smooth stand-in for
    the largest joint force over the joints and the motion) or ``rms``."""
    reaction_weight: Scalar = 0.0
    """Weight of the joint reactions' measure squared (gravity included)
    [length**2/force**2], e.g. ``1e-4 m^2/N^2``. Default 0."""
    starts: int = Field(default=2048, ge=1, le=1_000_000)
    """Random starts, each refined by Levenberg-Marquardt. Default 2048."""
    seed: int = Field(default=0, ge=0)
    """Seed of the random starts (the same seed, the same result). Default 0."""
    keep: int = Field(default=10, ge=1, le=1000)
    """Distinct candidates kept and written at most. Default 10."""
    max_steps: int = Field(default=300, ge=1, le=100_000)
    """Levenberg-Marquardt steps per start at most. Default 300."""

    @model_validator(mode="after")
    def _shape_keys(self):
        if self.shape != "fourier" and {"harmonics", "sense"} & self.model_fields_set:
            raise ValueError("'harmonics' and 'sense' go with 'shape: fourier'")
        return self

    @model_validator(mode="after")
    def _one_task(self):
        if sum(t is not None for t in (self.points, self.function, self.motion)) != 1:
            raise ValueError(
                "give one of 'points' (a path), 'motion' (poses) or 'function' (function "
                "generation)"
            )
        return self


RunSpec = Annotated[
    KinematicRunSpec
    | StaticsRunSpec
    | ForwardRunSpec
    | InverseRunSpec
    | MixedRunSpec
    | SweepRunSpec
    | IdentifyRunSpec
    | OptimizeRunSpec
    | SynthesisRunSpec,
    Field(discriminator="kind"),
]


class ModelFile(Spec):
    """A model file: a mechanism in one unit system, and named runs of analyses on it."""

    mixdyn: Literal[1] = FORMAT_VERSION
    """Format version of the file: 1."""
    name: Text = "mechanism"
    """Name of the mechanism (one line). Default ``mechanism``."""
    description: Annotated[str, AfterValidator(_paragraph)] | None = None
    """Free text describing the model."""
    units: UnitsSpec = UnitsSpec()
    """The model's unit system, e.g. ``{length: mm, mass: kg, time: s}``: every number without a
    unit is in these (angles in rad). Default m, kg, s."""
    strict_units: bool = False
    """Refuse every number other than 0 written without a unit where a unit is needed (a
    length, a mass, a law of force, an angle...), and check the units of every law and
    expression. Default false: such a number is in the model's units (angles in rad)."""
    gravity: Vec2 = (0.0, 0.0)
    """Gravitational acceleration ``[gx, gy]`` [length/time**2], e.g. ``[0, -9.81 m/s^2]``.
    Default ``[0, 0]``."""
    output_units: dict[str, str] | str = Field(default_factory=dict)
    """Units of the results by kind of quantity, e.g. ``{angle: deg, torque: N*m}``; or a
    preset for every kind: ``SI`` (m, N, N*m, J, W) or ``mm-N-s`` (mm, N, N*mm, mJ, mW),
    changed as ``{preset: SI, angle: deg}``; energy and power, not given, follow the torque's
    and time's. Default: the model's units."""
    parameters: dict[str, Scalar] = Field(default_factory=dict)
    """Named constants usable in expressions and quantities, e.g. ``{L: 120 mm, F0: 10 N}``."""
    ground: GroundSpec = GroundSpec()
    """The fixed frame and its named points."""
    bodies: list[BodySpec] = Field(default_factory=list)
    """The rigid bodies: at least one, except in a file whose runs are all ``synthesis``
    runs, which need no mechanism."""
    joints: list[JointSpec] = Field(default_factory=list)
    """Joints: ``revolute``, ``weld``, ``translational``, ``pin_in_slot``, ``distance``,
    ``gear_pair``, ``rolling_disks``, ``rack_pinion``, ``rolling_on_line``, ``cam_follower``."""
    drivers: list[DriverSpec] = Field(default_factory=list)
    """Drivers prescribing motions: ``coordinate``, ``point``, ``relative_angle``, ``distance``."""
    forces: list[ForceSpec] = Field(default_factory=list)
    """Force elements: ``point_force``, ``torque``, ``joint_friction``, ``spring_damper``,
    ``rotary_spring_damper``."""
    assembly: AssemblySpec = AssemblySpec()
    """How the starting pose is closed: ``{hold: [crank.phi]}``."""
    runs: list[RunSpec] = Field(default_factory=list)
    """Named analyses: ``kinematic``, ``statics``, ``forward``, ``inverse``, ``mixed``,
    ``sweep`` (another
    run over many values of some numbers), ``identify`` (numbers fitted to measurements) and
    ``optimize`` (numbers chosen to minimize a scalar of a run), ``synthesis`` (a four-bar
    that draws a path)."""

    @model_validator(mode="after")
    def _a_mechanism(self):
        if self.bodies or (self.runs and all(r.kind == "synthesis" for r in self.runs)):
            return self
        only = "only a file whose runs are all synthesis runs describes no mechanism"
        if "bodies" not in self.model_fields_set:
            raise ValueError(f"missing field 'bodies': add 'bodies:' ({only})")
        raise ValueError(f"'bodies' is empty: a mechanism needs at least one body ({only})")

    def __eq__(self, other) -> bool:
        # Equal descriptions, whatever file (and lines) they were read from.
        if not isinstance(other, ModelFile):
            return NotImplemented
        return self.model_dump() == other.model_dump()

    __hash__ = None  # type: ignore[assignment]

    def run(self, name: str):
        """The run called ``name``."""
        for r in self.runs:
            if r.name == name:
                return r
        known = ", ".join(r.name for r in self.runs) or "(none)"
        raise KeyError(f"no run {name!r}; runs: {known}")


def json_schema() -> dict:
    """The JSON Schema of a model file (draft 2020-12)."""
    schema = ModelFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema.setdefault("title", "mixdyn model file")
    return schema
