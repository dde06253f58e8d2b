"""Read a model file and build the :class:`mixdyn.Model` it describes.

Three stages, each with its own errors, all reported as :class:`FileError` (one line: file,
line, element, problem, what to do):

1. text -> plain data (:mod:`._yaml`: safe YAML, no aliases, line of every value);
2. data -> :class:`~mixdyn.io.schema.ModelFile` (pydantic: the form);
3. description -> :class:`mixdyn.Model` (:func:`build`: names, units, expressions).

Example::

    import mixdyn.io as mio
    spec = mio.read("examples/antonya.yaml")   # the validated description
    model = mio.build(spec)                    # the mechanism
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
import re
import stat
from typing import NoReturn

import numpy as np
from pydantic import ValidationError

from .. import model as m
from .._hints import count
from ..analysis._options import suggestions
from ..errors import ModelError
from ..model._body import GROUND_NAME
from ..model._declare import TIME, Variable
from ..units import UnitSystem
from . import schema as s
from ._errors import FileError
from ._yaml import MAX_BYTES, YamlError, element_name, line_of, read_yaml
from .expressions import CONSTANTS, FUNCTIONS, ExpressionError, ExpressionFunction, ExpressionLaw
from .expressions import parse as parse_expression
from .quantities import (
    DimensionError,
    QuantityError,
    convert,
    dimension,
    factor,
    has_unit_tail,
    looks_like_quantity,
)
from .readings import Readings

_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_RESERVED = {"t", *CONSTANTS, *FUNCTIONS}


@dataclasses.dataclass(frozen=True)
class Source:
    """Where a description came from: the file name, the line of every value, the raw data."""

    file: str
    lines: dict
    data: object


# --------------------------------------------------------------------------- reading
def read(path) -> s.ModelFile:
    """Read and validate a model file (the description; see :func:`build` for the model).

    Raises:
        FileError: unreadable file, bad YAML, or a description of the wrong form.
    """
    file = os.fspath(path)
    raw = _read_bytes(file)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise FileError(
            f"not UTF-8 text (byte {e.start})", file=file, hint="save the file as UTF-8"
        ) from None
    return reads(text, file)


def _read_bytes(file: str) -> bytes:
    """The bytes of a regular file of at most :data:`MAX_BYTES` bytes.

    The file is opened without blocking and checked before it is read, so that a FIFO, a
    device or a folder is refused at once instead of hanging or filling memory.
    """
    try:
        fd = os.open(file, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise FileError("no such file", file=file, hint="check the path") from None
    except IsADirectoryError:
        raise _not_regular(file, "a folder") from None
    except OSError as e:
        raise FileError(f"cannot read the file ({e.strerror})", file=file) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise _not_regular(file, "a folder")
        if not stat.S_ISREG(st.st_mode):
            raise _not_regular(file, "a pipe, socket or device")
        if st.st_size > MAX_BYTES:
            raise FileError(
                f"the file has {st.st_size:,} bytes, more than the limit of "
                f"{MAX_BYTES // 1_000_000} MB",
                file=file,
                hint="a model file holds a description, not data",
            )
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        with os.fdopen(fd, "rb") as f:
            fd = -1
            return f.read(MAX_BYTES + 1)
    except OSError as e:
        raise FileError(f"cannot read the file ({e.strerror})", file=file) from None
    finally:
        if fd >= 0:
            os.close(fd)


def _not_regular(file: str, what: str) -> FileError:
    hint = "give a .yaml file" if what == "a folder" else "give a model file saved on disk"
    return FileError(f"is {what}, not a model file", file=file, hint=hint)


def reads(text: str, file: str = "<string>") -> s.ModelFile:
    """Validate a model file given as text (see :func:`read`)."""
    try:
        data, lines = read_yaml(text)
    except YamlError as e:
        raise FileError(e.problem, file=file, line=e.line, hint=e.hint) from None
    if not isinstance(data, dict):
        raise FileError(
            "the file must be a mapping with keys such as units, bodies, joints, runs",
            file=file,
            line=1,
            hint="start from one of the files in examples/",
        )
    try:
        spec = s.ModelFile.model_validate(data)
    except ValidationError as e:
        raise _pydantic_error(e, data, lines, file) from None
    object.__setattr__(spec, "_mixdyn_source", Source(file, lines, data))
    return spec


def source_of(spec: s.ModelFile) -> Source | None:
    """Where ``spec`` was read from, or None if it was made in Python."""
    return getattr(spec, "_mixdyn_source", None)


def _walk(data, loc) -> tuple:
    """The YAML path of a pydantic error location (tags of unions left out)."""
    path, cur = [], data
    for part in loc:
        if (isinstance(cur, dict) and part in cur) or (
            isinstance(cur, list) and isinstance(part, int) and 0 <= part < len(cur)
        ):
            path.append(part)
            cur = cur[part]
        elif isinstance(cur, dict) and isinstance(part, str) and not path_is_tag(cur, part):
            path.append(part)  # a missing key: point at its parent's line
            cur = None
        # else: a union tag (e.g. 'revolute', 'scalar') not present in the data
    return tuple(path)


def path_is_tag(cur: dict, part: str) -> bool:
    tags = {cur.get("type"), cur.get("kind"), "scalar", *s.LAW_KEYS}
    return part in tags or part.startswith(("function-", "tuple[", "list[", "dict["))


def _pydantic_error(e: ValidationError, data, lines, file) -> FileError:
    errors = e.errors()
    err = errors[0]
    path = _walk(data, err["loc"])
    msg = err["msg"]
    if msg.startswith("Value error, "):
        msg = msg[len("Value error, ") :]
    typ = err["type"]
    field = path[-1] if path else None
    hint = ""
    if typ == "missing":
        missing = err["loc"][-1]
        msg = f"missing field {missing!r}"
        hint = f"add '{missing}:'"
    elif typ == "extra_forbidden":
        parent = _allowed_fields(data, path[:-1], unknown=str(field))
        msg = f"unknown field {field!r}"
        close = suggestions(str(field), parent)
        hint = (f"did you mean {' or '.join(map(repr, close))}? " if close else "") + (
            "remove it or fix its spelling"
            + (f"; allowed fields: {', '.join(parent)}" if parent else "")
        )
    elif typ == "union_tag_invalid":
        ctx = err.get("ctx", {})
        key = ctx.get("discriminator", "type").strip("'")
        msg = f"unknown {key} {ctx.get('tag')!r}"
        hint = f"use one of: {ctx.get('expected_tags', '').replace(chr(39), '')}"
    elif typ == "union_tag_not_found":
        key = err.get("ctx", {}).get("discriminator", "type").strip("'")
        msg = f"missing field {key!r}"
        hint = f"add '{key}:' to say what kind of element this is"
    elif typ == "value_error" and ("got True" in msg or "got False" in msg):
        hint = "YAML reads yes/no/on/off as true/false: write a number"
    elif typ in ("float_parsing", "float_type", "int_parsing", "int_type", "int_from_float"):
        hint = "write a number"
    elif typ in ("list_type", "tuple_type", "dict_type", "model_type", "model_attributes_type"):
        hint = "check the structure against examples/ or `mixdyn schema`"
    elif typ == "literal_error":
        hint = "use one of the allowed values"
    elif typ == "too_short" or typ == "too_long":
        hint = "check the number of items"
    more = f" (and {count(len(errors) - 1, 'more problem')})" if len(errors) > 1 else ""
    return FileError(
        msg + more,
        element_name(data, path),
        file=file,
        line=line_of(lines, path),
        hint=hint,
    )


def _allowed_fields(data, path, unknown: str | None = None) -> list[str]:
    """Field names of the part of the schema that the mapping at ``path`` is (for hints);
    ``unknown``: a field that part refused, so no part that declares it is the one."""
    cur = data
    for part in path:
        cur = cur[part]
    if not isinstance(cur, dict):
        return []
    best, score = None, 0
    elements = [*s.JOINT_SPECS.values(), *s.DRIVER_SPECS.values(), *s.FORCE_SPECS.values()]
    for obj in [*vars(s).values(), *elements]:
        if not (isinstance(obj, type) and issubclass(obj, s.Spec) and obj is not s.Spec):
            continue
        fields = obj.model_fields
        if unknown in fields:
            continue
        tagged = [k for k in ("type", "kind") if k in fields and k in cur]
        if tagged and all(repr(cur[k]) in str(fields[k].annotation) for k in tagged):
            return list(fields)
        n = sum(k in fields for k in cur)
        if n > score:
            best, score = obj, n
    return list(best.model_fields) if best is not None else []


# --------------------------------------------------------------------------- building
def load(path) -> m.Model:
    """Read a model file and build its model."""
    return build(read(path))


def build(spec: s.ModelFile) -> m.Model:
    """The :class:`mixdyn.Model` a description describes.

    Raises:
        FileError: unknown names, duplicate names, wrong dimensions, bad expressions...
    """
    return Builder(spec).model()


class Builder:
    """Builds a model from a description, reporting faults with their file position."""

    def __init__(self, spec: s.ModelFile):
        self.spec = spec
        src = source_of(spec)
        self.file = src.file if src else "<model>"
        self.lines = src.lines if src else {}
        self.data = src.data if src else spec.model_dump()
        self.units = self._units()
        self.parameters = self._parameters()
        self.body_names = [b.name for b in spec.bodies]
        self.body_index = {n: i for i, n in enumerate(self.body_names)}
        self._body_tuple = tuple(self.body_names)
        #: The unit checks and the record of every number read (``mixdyn check --explain``).
        self.readings = Readings(self)
        self.readings.check_parameters()

    # ----------------------------------------------------------------- errors
    def fail(self, path, problem: str, hint: str = "") -> NoReturn:
        path = tuple(path)
        raise FileError(
            problem,
            element_name(self.data, path),
            file=self.file,
            line=line_of(self.lines, path),
            hint=hint,
        )

    def path_of(self, name: str) -> tuple:
        """The path of the body or element called ``name`` (for errors of the model)."""
        for section in ("bodies", "joints", "drivers", "forces", "runs"):
            for i, it in enumerate(getattr(self.spec, section)):
                if it.name == name:
                    return (section, i)
        return ()

    def fault_path(self, path, error: ModelError) -> tuple:
        """Where to report a model error of the element at ``path``: at its field's line
        where the error names a field the file gives (``ModelError.field``), else at the
        element's."""
        path = tuple(path)
        entry = self.data
        for part in path:
            try:
                entry = entry[part]
            except (KeyError, IndexError, TypeError):
                return path
        field = getattr(error, "field", None)
        return (*path, field) if isinstance(entry, dict) and field in entry else path

    def element_class(self, name: str) -> type | None:
        """The model class of the joint, driver or force called ``name`` in the file (None:
        no such element)."""
        for section in ("joints", "drivers", "forces"):
            for e in getattr(self.spec, section):
                if e.name == name:
                    kind = m.ELEMENTS[section].get(e.type)
                    return kind.cls if kind is not None else None
        return None

    # ----------------------------------------------------------------- values
    def scalar(self, value, kind, path, *, scale: float = 1.0) -> float:
        """A scalar in model units (see :func:`mixdyn.io.quantities.convert`)."""
        try:
            x = convert(value, kind, self.units, self.parameters, scale)
        except ExpressionError as e:
            self.fail(path, e.message, e.hint)
        except QuantityError as e:
            shown = repr(value)
            self.fail(path, e.problem if shown in e.problem else f"{shown}: {e.problem}", e.hint)
        self.readings.scalar(value, kind, path, x, scale)
        return x

    def factor(self, unit: str, kind, path) -> float:
        try:
            return factor(unit, kind, self.units)
        except QuantityError as e:
            self.fail(path, e.problem, e.hint)

    def vec2(self, value, kind, path) -> tuple[float, float]:
        return tuple(self.scalar(v, kind, (*path, k)) for k, v in enumerate(value))

    def direction(self, value, path) -> tuple[float, float]:
        v = self.vec2(value, "dimensionless", path)
        if math.hypot(*v) == 0.0:
            self.fail(path, "the direction has zero length", "give a non-zero vector [x, y]")
        return v

    def _units(self) -> UnitSystem:
        u = self.spec.units
        from ..units import _KNOWN

        for kind in ("length", "mass", "time"):
            text = getattr(u, kind)
            if text in _KNOWN[kind]:  # the common spellings, without loading pint (0.4 s)
                continue
            try:
                factor(text, kind, UnitSystem())
            except QuantityError as e:
                self.fail(("units", kind), f"{text!r}: {e.problem}", e.hint)
        return UnitSystem(u.length, u.mass, u.time)

    def _parameters(self) -> dict[str, float]:
        out: dict[str, float] = {}
        bodies = {b.name for b in self.spec.bodies}
        for name, value in self.spec.parameters.items():
            path = ("parameters", name)
            if not _IDENTIFIER.match(name):
                self.fail(path, f"{name!r} is not a valid parameter name", "use letters, digits, _")
            if name in _RESERVED or name in bodies:
                self.fail(
                    path,
                    f"the name {name!r} is taken (time, a constant, a function or a body)",
                    "rename the parameter",
                )
            try:
                out[name] = convert(value, None, self.units, out)
            except ExpressionError as e:
                self.fail(path, e.message, e.hint)
            except QuantityError as e:
                self.fail(path, f"{value!r}: {e.problem}", e.hint)
        return out

    # ----------------------------------------------------------------- references
    def body(self, name: str, path, *, ground: bool = True) -> str:
        if name == GROUND_NAME:
            if not ground:
                self.fail(path, "the ground cannot be used here", "name a moving body")
            return name
        if name not in self.body_index:
            self.fail(
                path,
                f"unknown body {name!r}",
                "known bodies: " + ", ".join(["ground", *self.body_names]),
            )
        return name

    def point(self, ref: str, path, *, ground: bool = True) -> str:
        """Check ``"body"`` or ``"body.point"``; returns the reference."""
        parts = ref.split(".")
        if len(parts) > 2:
            self.fail(path, f"{ref!r} is not a point reference", "write 'body' or 'body.point'")
        body = self.body(parts[0], path, ground=ground)
        if len(parts) == 2:
            if body == "ground":
                points = self.spec.ground.points
            else:
                points = self.spec.bodies[self.body_index[body]].points
            if parts[1] not in points:
                self.fail(
                    path,
                    f"body {body!r} has no point {parts[1]!r}",
                    f"its points: {', '.join(points) or '(none; add them under points:)'}",
                )
        return ref

    def coordinate(self, ref: str, path) -> tuple[str, str]:
        """``("crank", "phi")`` from ``"crank.phi"``."""
        parts = ref.split(".")
        if len(parts) != 2 or parts[1] not in m._model.COORDINATES:
            self.fail(
                path,
                f"{ref!r} is not a coordinate",
                "write 'body.x', 'body.y' or 'body.phi'",
            )
        self.body(parts[0], path, ground=False)
        return parts[0], parts[1]

    # ----------------------------------------------------------------- laws
    def law(self, spec, kind, path, *, state: bool = False, variable: Variable = TIME):
        """A :class:`mixdyn.Law` (or, with ``state``, possibly a StateFunction) of ``kind``,
        a function of ``variable`` (default time; a law of another variable, such as a cam's
        angle ``theta``, names it in its expressions, and its coefficients and knots are per
        that variable's kind)."""
        path = tuple(path)
        if variable != TIME:
            spec = self._renamed(spec, variable, path)
        self.readings.law(spec, kind, path, variable.kind)
        if isinstance(spec, int | float):
            return m.Constant(float(spec))
        if isinstance(spec, str):
            try:
                return m.Constant(convert(spec, kind, self.units, self.parameters))
            except DimensionError as e:
                if re.search(r"\bt\b", spec):  # "600 rpm * t": pint read t as a tonne
                    self.fail(
                        path,
                        f"{spec!r} reads as a quantity whose unit has a tonne (t) in it, not as "
                        "a law of the time t",
                        "write a law of time in model units (e.g. '20*pi*t'), as "
                        "{expr: ..., unit: ...}, or as a ramp: {ramp: {rate: 600 rpm}}",
                    )
                self.fail(path, f"{spec!r}: {e.problem}", e.hint)
            except QuantityError as e:
                if looks_like_quantity(spec) or has_unit_tail(spec):
                    self.fail(path, f"{spec!r}: {e.problem}", e.hint)
            except ExpressionError:
                pass
            return self.expression(spec, None, kind, path, state)
        if isinstance(spec, s.ExpressionSpec):
            return self.expression(spec.expr, spec.unit, kind, (*path, "expr"), state)
        if isinstance(spec, s.ConstantSpec):
            return m.Constant(self.scalar(spec.constant, kind, (*path, "constant")))
        dim = dimension(kind)
        if isinstance(spec, s.PolynomialSpec):
            f = 1.0 if spec.unit is None else self.factor(spec.unit, kind, (*path, "unit"))
            coeffs = [
                self.scalar(c, _per(dim, variable, k), (*path, "polynomial", k), scale=f)
                for k, c in enumerate(spec.polynomial)
            ]
            return m.Polynomial(coeffs)
        if isinstance(spec, s.RampSpec):
            p = (*path, "ramp")
            return m.Ramp(
                self.scalar(spec.ramp.start, kind, (*p, "start")),
                self.scalar(spec.ramp.rate, _per(dim, variable, 1), (*p, "rate")),
            )
        if isinstance(spec, s.HarmonicSpec):
            h, p = spec.harmonic, (*path, "harmonic")
            return m.Harmonic(
                self.scalar(h.amplitude, kind, (*p, "amplitude")),
                self.scalar(h.omega, _rate_of_angle(variable), (*p, "omega")),
                self.scalar(h.phase, "angle", (*p, "phase")),
                self.scalar(h.offset, kind, (*p, "offset")),
            )
        if isinstance(spec, s.SplineSpec):
            a, p = spec.spline, (*path, "spline")
            f = 1.0 if a.unit is None else self.factor(a.unit, kind, (*p, "unit"))
            t = self.times(a.t, (*p, "t"), variable.kind)
            y = [self.scalar(v, kind, (*p, "y", k), scale=f) for k, v in enumerate(a.y)]
            if len(y) != len(t):
                self.fail((*p, "y"), f"{len(y)} values for {len(t)} times", "give one per time")
            try:
                return m.Spline(t, y, a.kind)
            except ValueError as e:
                self.fail(p, str(e))
        if isinstance(spec, s.HermiteSpec):
            a, p = spec.hermite, (*path, "hermite")
            f = 1.0 if a.unit is None else self.factor(a.unit, kind, (*p, "unit"))
            t = self.times(a.t, (*p, "t"), variable.kind)
            cols = []
            for k, key in enumerate(("y", "yd", "ydd")):
                vals = [
                    self.scalar(v, _per(dim, variable, k), (*p, key, i), scale=f)
                    for i, v in enumerate(getattr(a, key))
                ]
                if len(vals) != len(t):
                    self.fail((*p, key), f"{len(vals)} values for {len(t)} times", "one per time")
                cols.append(vals)
            return m.QuinticHermite(t, *cols)
        if isinstance(spec, s.PiecewiseSpec):
            a, p = spec.piecewise, (*path, "piecewise")
            breaks = np.asarray(a.breaks, dtype=float)
            if np.any(np.diff(breaks) <= 0) or not np.all(np.isfinite(breaks)):
                self.fail((*p, "breaks"), "break points must increase", "sort them")
            widths = {len(r) for r in a.coeffs}
            if widths != {len(breaks) - 1}:
                self.fail(
                    (*p, "coeffs"),
                    f"each row of coeffs needs {len(breaks) - 1} entries (one per interval)",
                    "use the scipy PPoly layout",
                )
            return m.PiecewisePolynomial(breaks, np.asarray(a.coeffs, dtype=float))
        raise AssertionError(type(spec))  # pragma: no cover

    def times(self, values, path, kind="time") -> list[float]:
        """Knots of a law (times, or values of its variable of ``kind``), increasing."""
        t = [self.scalar(v, kind, (*path, k)) for k, v in enumerate(values)]
        if any(b <= a for a, b in itertools.pairwise(t)):
            what = "times" if kind == "time" else "knots"
            self.fail(path, f"{what} must be strictly increasing", "sort them and drop repeats")
        return t

    def _renamed(self, spec, variable: Variable, path):
        """A law's description whose expression names ``variable`` written with ``t`` (the
        variable of an expression law); a ``t`` of its own is refused."""
        text = spec if isinstance(spec, str) else getattr(spec, "expr", None)
        if text is None:
            return spec
        if re.search(r"\bt\b", text):
            at = path if isinstance(spec, str) else (*path, "expr")
            self.fail(
                at,
                f"this law is a law of {variable.name} [{variable.kind}], not of time t",
                f"write it with {variable.name}",
            )
        text = re.sub(rf"\b{variable.name}\b", "t", text)
        return text if isinstance(spec, str) else spec.model_copy(update={"expr": text})

    def expression(self, text, unit, kind, path, state: bool):
        scale = 1.0 if unit is None else self.factor(unit, kind, (*path[:-1], "unit"))
        self.readings.expression(text, unit, kind, path)
        try:
            # A law of t (no body state) parses the same without the bodies: that parse is
            # cached and is the one ExpressionLaw repeats.
            parse_expression(text, self.parameters)
        except ExpressionError:
            pass
        else:
            return ExpressionLaw(text, self.parameters, unit, scale)
        try:
            p = parse_expression(text, self.parameters, bodies=self.body_index)
        except ExpressionError as e:
            self.fail(path, e.message, e.hint or "a law is an expression of t, e.g. '2*t'")
        if p.uses_state:
            if not state:
                self.fail(
                    path,
                    f"expression {text!r} uses the state of a body",
                    "a prescribed motion may depend on t only; body states may be used in "
                    "force magnitudes",
                )
            fn = ExpressionFunction._of_parsed(p, self._body_tuple, self.parameters, unit, scale)
            return m.StateFunction(fn)
        return ExpressionLaw(text, self.parameters, unit, scale)

    # ----------------------------------------------------------------- the model
    def model(self) -> m.Model:
        spec = self.spec
        self._check_names()
        ground = m.Ground(
            {
                k: self.vec2(v, "length", ("ground", "points", k))
                for k, v in spec.ground.points.items()
            }
        )
        bodies = [self._body(i, b) for i, b in enumerate(spec.bodies)]
        joints = [self._joint(i, j) for i, j in enumerate(spec.joints)]
        drivers = [self.driver(d, ("drivers", i)) for i, d in enumerate(spec.drivers)]
        forces = [self._force(i, f) for i, f in enumerate(spec.forces)]
        gravity = self.vec2(spec.gravity, "acceleration", ("gravity",))
        for k, ref in enumerate(spec.assembly.hold):
            self.coordinate(ref, ("assembly", "hold", k))
        try:
            return m.Model(
                bodies,
                joints,
                drivers,
                forces,
                ground=ground,
                gravity=gravity,
                units=self.units,
                name=spec.name,
            )
        except ModelError as e:
            element = e.element
            msg = str(e)
            if element and msg.startswith(f"{element}: "):
                msg = msg[len(element) + 2 :]
            self.fail(self.fault_path(self.path_of(element), e) if element else (), msg)

    def _check_names(self):
        seen: dict[str, tuple] = {}
        for i, b in enumerate(self.spec.bodies):
            path = ("bodies", i, "name")
            if b.name == "ground":
                self.fail(path, "'ground' is the fixed frame's name", "rename the body")
            if b.name in seen:
                self.fail(path, f"duplicate body name {b.name!r}", "every body needs its own name")
            seen[b.name] = path
            for section in ("points", "vectors"):
                for key in getattr(b, section):
                    if not _IDENTIFIER.match(key):
                        self.fail(
                            ("bodies", i, section, key),
                            f"{key!r} is not a valid name",
                            "use letters, digits and _",
                        )
        for key in self.spec.ground.points:
            if not _IDENTIFIER.match(key):
                self.fail(("ground", "points", key), f"{key!r} is not a valid name", "use letters")
        elements: dict[str, tuple] = {}
        for section in ("joints", "drivers", "forces"):
            for i, e in enumerate(getattr(self.spec, section)):
                path = (section, i, "name")
                if e.name in elements:
                    other = element_name(self.data, elements[e.name][:2])
                    self.fail(
                        path,
                        f"duplicate name {e.name!r} (also {other})",
                        "joints, drivers and forces need names unique among them all",
                    )
                if e.name == "t":
                    self.fail(path, "'t' is reserved for the time column", "rename it")
                elements[e.name] = path
        runs: set[str] = set()
        for i, r in enumerate(self.spec.runs):
            if r.name in runs:
                self.fail(("runs", i, "name"), f"duplicate run name {r.name!r}", "rename it")
            runs.add(r.name)

    def _body(self, i, b: s.BodySpec) -> m.Body:
        p = ("bodies", i)
        mass = self.scalar(b.mass, "mass", (*p, "mass"))
        inertia = self.scalar(b.inertia, "inertia", (*p, "inertia"))
        if mass < 0:
            self.fail((*p, "mass"), f"negative mass {mass:g}", "a mass must be >= 0")
        if inertia < 0:
            self.fail((*p, "inertia"), f"negative inertia {inertia:g}", "an inertia must be >= 0")
        q0 = (
            self.scalar(b.q0[0], "length", (*p, "q0", 0)),
            self.scalar(b.q0[1], "length", (*p, "q0", 1)),
            self.scalar(b.q0[2], "angle", (*p, "q0", 2)),
        )
        points = {k: self.vec2(v, "length", (*p, "points", k)) for k, v in b.points.items()}
        vectors = {k: self.direction(v, (*p, "vectors", k)) for k, v in b.vectors.items()}
        return m.Body(b.name, mass, inertia, q0=q0, points=points, vectors=vectors)

    #: The model package, for the element specs' ``build`` (``mixdyn.io.schema.JOINT_SPECS``).
    m = m

    def axis(self, axis, point_ref: str, path):
        """A joint's direction: ``[x, y]`` (normalized) or the name of a vector of the body
        of ``point_ref``."""
        if isinstance(axis, str):
            body = point_ref.split(".")[0]
            vecs = {} if body == "ground" else self.spec.bodies[self.body_index[body]].vectors
            if axis not in vecs:
                self.fail(
                    path,
                    f"body {body!r} has no vector {axis!r}",
                    f"its vectors: {', '.join(vecs) or '(none)'}; or give [x, y]",
                )
            return axis
        return self.direction(axis, path)

    def _joint(self, i, j) -> m.Joint:
        return j.build(self, ("joints", i))

    def driver(self, d, p) -> m.Driver:
        """A driver from its description at path ``p`` (also used for prescribed motions)."""
        return d.build(self, tuple(p))

    def _force(self, i, f) -> m.ForceElement:
        return f.build(self, ("forces", i))


def _per(dim, variable: Variable, k: int) -> tuple[int, int, int]:
    """The dimension of ``dim`` per (the kind of ``variable``)**k."""
    return tuple(d - k * v for d, v in zip(dim, dimension(variable.kind), strict=True))


def _rate_of_angle(variable: Variable):
    """The kind of an angle per unit of ``variable`` (a harmonic's ``omega``)."""
    if variable == TIME:
        return "angular_velocity"
    return _per(dimension("angle"), variable, 1)


__all__ = ["Builder", "FileError", "Source", "build", "element_name", "load", "read", "reads"]
