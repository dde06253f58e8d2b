"""How a model file's numbers are read: the unit each one is taken in, the checks on units
that a :class:`~mixdyn.io.load.Builder` makes as it reads them, and the record of every
number as understood (``mixdyn check --explain``, :mod:`mixdyn.io.explain`).

What is checked:

* a law or a constant expression that uses a parameter with a unit or a body state must come
  out as its field's kind (:func:`mixdyn.io.dimensions.check`); one written only with numbers
  and parameters without units is in the model's units, as a number without a unit is;
* a law written with a unit after it (``T0*(1 - crank.omega/n0) N*m``) is refused with the
  spelling that gives a law a unit (``{expr: ..., unit: N*m}``);
* with the file's ``strict_units: true``, a number other than 0 without a unit where a unit
  is needed is refused, and every law and expression is checked;
* an angle written without a unit above 2 pi (``phi: 90``) is read in radians, with a warning
  suggesting ``90 deg``.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import re

from ..errors import ModelError
from ..units import DIMENSIONS, SI, Kind, UnitSystem, factor, unit_for
from . import dimensions as d
from ._yaml import element_name, line_of
from .quantities import _NUMBER, _UNIT, QuantityError, _split, convert, exponents


@dataclasses.dataclass(frozen=True)
class Reading:
    """One number of the file as it was understood.

    Attributes:
        path: its place in the file (keys and indices).
        written: the value as the file writes it.
        kind: its kind of quantity (a key of :data:`mixdyn.units.DIMENSIONS`, exponents, or
            None for a parameter: the dimension of its own unit).
        value: the value in the model's units (None: a law that is an expression).
        unit: the unit written with it (None: none written).
        scale: model units per number written without a unit (a law's ``unit:``).
        from_parameters: an expression whose unit comes from its parameters' (``m*L**2/12``).
    """

    path: tuple
    written: object
    kind: Kind | None
    value: float | None
    unit: str | None
    scale: float = 1.0
    from_parameters: bool = False


class Readings:
    """The unit checks and the record of the numbers of one description, made as a
    :class:`~mixdyn.io.load.Builder` reads them (its ``readings``).

    Attributes:
        strict: the file's ``strict_units``.
        records: what was read, by path (:class:`Reading`).
        warnings: numbers read as written but probably meant otherwise (one line each).
    """

    def __init__(self, builder):
        self.b = builder
        self.strict = bool(getattr(builder.spec, "strict_units", False))
        self.records: dict[tuple, Reading] = {}
        self.warnings: list[str] = []
        self._parameters: dict[str, d.Parameter] | None = None
        self.variable: d.Dim = d.dim(DIMENSIONS["time"])
        #: Where not None, the parameters whose units would make the laws fit are collected
        #: here (name -> dimension) instead of being refused
        #: (:func:`mixdyn.io.dump.parameter_units`).
        self.needed: dict[str, d.Dim] | None = None

    # ----------------------------------------------------------------- parameters
    @property
    def parameters(self) -> dict[str, d.Parameter]:
        """The file's parameters with their dimensions (None: written without a unit), as
        the file writes them (a sweep's member, whose description holds numbers in model
        units, keeps the units of its file)."""
        if self._parameters is None:
            self._parameters = {}
            data = self.b.data.get("parameters") if isinstance(self.b.data, dict) else None
            for name, value in self.b.spec.parameters.items():
                if isinstance(data, dict) and name in data:
                    value = data[name]
                self._parameters[name] = d.Parameter(
                    name,
                    self._dim_of(value),
                    value,
                    line_of(self.b.lines, ("parameters", name)) if self.b.lines else None,
                    self._unit_of(value),
                )
        return self._parameters

    def parameter_value(self, name: str, value, path) -> float:
        """A value a study gives the file parameter ``name`` (a sweep's ``vary``), in model
        units, read as the parameter itself is: for a parameter with a unit (or written with
        such parameters), a value with a unit of its dimension is converted to the model's
        units and a number without a unit is in the model's units of that dimension (refused
        with ``strict_units``); a value with a unit of another dimension is refused. A
        parameter without a unit is a plain number, and so are its values: one written with
        a unit is refused.

        Args:
            name: the parameter (one of the file's).
            value: the value as the file writes it (``0.1 m``, ``100``).
            path: its place in the file, for the errors.
        """
        p = self.parameters[name]
        if p.dim is None:
            unit = self._unit_of(value)
            if unit is not None:
                line = f" (line {p.line})" if p.line else ""
                self.b.fail(
                    path,
                    f"{_shown(value)}: parameter {name!r}{line} is written without a unit, so "
                    f"it is a plain number, and a value with a unit ({unit}) is not one of it",
                    f"write the parameter with its unit (e.g. `{name}: {_shown(p.written)} "
                    f"{unit}`) or the values without one",
                )
            return self.b.scalar(value, None, path)
        if any(e.denominator != 1 for e in p.dim):
            return self.b.scalar(value, None, path)
        return self.b.scalar(value, tuple(int(e) for e in p.dim), path)

    def _dim_of(self, value) -> d.Dim | None:
        unit = self._unit_of(value)
        if unit is not None:
            return d.dim(exponents(unit))
        if isinstance(value, str) and not _NUMBER.match(value):
            known = self._parameters or {}
            used = d.leaves(value, known)
            if any(known[n].dim is not None for n in used.parameters):
                dims = {n: p.dim if p.dim is not None else d.PLAIN for n, p in known.items()}
                try:
                    return d.infer(value, dims, values=self.b.parameters)
                except (d.MismatchError, SyntaxError):
                    return None
        return None

    def _unit_of(self, value) -> str | None:
        """The unit written after a scalar of the file (None: none)."""
        if not isinstance(value, str) or _NUMBER.match(value):
            return None
        try:
            return _split(value.strip(), self.b.parameters, None, self.b.units)[1]
        except QuantityError:
            return None

    # ----------------------------------------------------------------- scalars
    def scalar(self, value, kind: Kind | None, path, result: float, scale: float = 1.0) -> None:
        """Check and record a scalar read as ``result`` (model units); ``scale`` other than 1
        or a unit given elsewhere (a law's ``unit:``) counts as a unit."""
        path = tuple(path)
        unit = self._unit_of(value)
        bare = unit is None and scale == 1.0
        if unit is not None and isinstance(value, str):
            self._unit_twice(value, unit, path)
        strict = kind is not None and bare and self.strict and _has_unit(kind) and result != 0.0
        stated = False
        if kind is not None and bare and isinstance(value, str) and not _NUMBER.match(value):
            used = d.leaves(value, self.parameters).parameters
            stated = any(self.parameters[n].dim not in (None, d.PLAIN) for n in used)
            if strict and all(self.parameters[n].dim is None for n in used):
                self._refuse_bare(value, kind, path)  # numbers and plain parameters only
            self._expression(value, kind, path, time=False)
        elif strict:
            self._refuse_bare(value, kind, path)
        if kind == "angle" and bare and abs(result) > 2 * math.pi and _is_number(value):
            shown = _shown(value)
            self.warnings.append(
                f"{self._place(path)}: the angle {shown} has no unit and is read as {shown} rad "
                f"({math.degrees(result):.4g} deg); if degrees are meant, write `{shown} deg`"
            )
        self.records[path] = Reading(path, value, kind, result, unit, scale, stated)

    def check_parameters(self) -> None:
        """Refuse a parameter written as a constant expression followed by a unit that uses
        a parameter with a unit of its own (``L2: 2*L mm`` with ``L: 1 m``: L is a number in
        model units there, and ``mm`` would convert it again, 2 m read as 2 mm in a file in
        m); the fix is the expression alone (``L2: 2*L``, which takes L's unit)."""
        for name, p in self.parameters.items():
            if p.unit is not None and isinstance(p.written, str):
                head = p.written.strip()[: -len(p.unit)].strip()
                self._unit_twice(
                    p.written,
                    p.unit,
                    ("parameters", name),
                    f"write `{name}: {head}`: it takes the units of its parameters",
                )

    def _unit_twice(self, text: str, unit: str, path, hint: str | None = None) -> None:
        """Refuse a constant expression followed by a unit that uses a parameter with a unit
        of its own (``L**2/12 kg*m**2`` with ``L: 1 m``): the parameter is a number in model
        units there, and the unit after it would convert it again. ``hint``: the fix (default:
        a field's)."""
        head = text.strip()[: -len(unit)].strip()
        if not head or _NUMBER.match(head):
            return
        used = d.leaves(head, self.parameters).parameters
        own = [n for n in used if self.parameters[n].unit is not None]
        if own:
            name = own[0]
            p = self.parameters[name]
            line = f" (line {p.line})" if p.line else ""
            self.b.fail(
                path,
                f"{text!r}: parameter {name!r}{line} has a unit of its own ({p.written}), so "
                f"the unit after the expression ({unit}) would convert it twice",
                hint
                or f"write the expression without the unit, its parameters giving it theirs "
                f"(a parameter for the rest, e.g. `m: 1 kg` and `m*{head}`), or {name} "
                "without a unit",
            )

    def _place(self, path) -> str:
        """``joint 'A', angle (line 12)``: where a number is, for warnings."""
        line = line_of(self.b.lines, path) if self.b.lines else None
        return (element_name(self.b.data, path) or "the file") + (f" (line {line})" if line else "")

    def _refuse_bare(self, value, kind, path) -> None:
        unit = self.b.units.label(kind) if isinstance(kind, str) else d.unit_of(d.dim(kind), SI)
        self.b.fail(
            path,
            f"{_shown(value)} has no unit (strict_units: every number needs one)",
            f"write `{_shown(value)} {unit}` (model units) or the unit you mean",
        )

    def _expression(self, text: str, kind, path, *, time: bool, unit_scale=None) -> None:
        target = d.PLAIN if unit_scale else d.dim(_exps(kind))
        fault = d.check(
            text,
            target,
            self.parameters,
            self.b.units,
            needed=_needed(kind, unit_scale),
            variable=self.variable,
            values=self.b.parameters,
            strict=self.strict,
            law=time,
        )
        if fault is None:
            return
        if self.needed is not None and fault.parameter is not None and fault.dim is not None:
            for name, dim in (fault.dims or {fault.parameter: fault.dim}).items():
                self.needed.setdefault(name, dim)
            return
        self.b.fail(path, fault.problem, fault.hint)

    # ----------------------------------------------------------------- laws
    def law(self, spec, kind: Kind, path, variable: str = "time") -> None:
        """Check a law as the file writes it (before it is built): a number (strict units,
        angles), an expression followed by a unit."""
        path = tuple(path)
        self.variable = d.dim(DIMENSIONS[variable])
        if isinstance(spec, bool):
            return
        if isinstance(spec, int | float):
            self.scalar(spec, kind, path, float(spec))
        elif isinstance(spec, str):
            self._unit_tail(spec, kind, path)
            try:  # a constant: a number, a quantity ("50 N") or a constant expression
                value = convert(spec, kind, self.b.units, self.b.parameters)
            except ModelError:
                return  # a law of time, or a fault the builder reports
            self.scalar(spec, kind, path, value)

    def expression(self, text: str, unit: str | None, kind: Kind, path) -> None:
        """Check a law's expression (``unit``: the unit given with it) and record it; one
        the expression parser refuses is left to it."""
        from .expressions import ExpressionError
        from .expressions import parse as parse_expression

        path = tuple(path)
        try:
            parse_expression(text, self.b.parameters, bodies=self.b.body_index)
        except ExpressionError:
            return
        self._expression(text, kind, path, time=True, unit_scale=unit)
        self.records[path] = Reading(path, text, kind, None, unit)

    def _unit_tail(self, text: str, kind: Kind, path) -> None:
        """Refuse a law of time or state followed by a unit (``10*sin(t) N``), with the
        spelling that gives it that unit, or without the unit where the law has it already
        (its parameters have units)."""
        if _parses(text):
            return
        words = text.split()
        for k in range(len(words) - 1, 0, -1):
            head, tail = " ".join(words[:k]), " ".join(words[k:])
            if not _UNIT.match(tail) or not _parses(head):
                continue
            try:
                exponents(tail)
            except QuantityError:
                continue
            uses = d.leaves(head, self.b.parameters)
            if not (uses.states or re.search(r"\bt\b", head)):
                return  # a constant followed by a unit: a quantity
            fits = d.leaves(head, self.parameters).parameters and not d.check(
                head,
                d.dim(_exps(kind)),
                self.parameters,
                self.b.units,
                needed="",
                variable=self.variable,
                values=self.b.parameters,
            )
            stated = any(self.parameters[n].dim not in (None, d.PLAIN) for n in uses.parameters)
            self.b.fail(
                path,
                f"the law {text!r} ends in a unit ({tail}); an expression's unit is given "
                "beside it",
                f"write {head} (its parameters' units make it {_needed(kind, None)} already)"
                if fits and stated
                else f"write {{expr: {head}, unit: {tail}}}",
            )


def spec_units(spec) -> UnitSystem:
    u = spec.units
    return UnitSystem(u.length, u.mass, u.time)


def _parses(text: str) -> bool:
    try:
        ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    return True


def _shown(value) -> str:
    """A number as a file would write it (``90``, not ``90.0``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        return str(value)
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else str(value)


def _is_number(value) -> bool:
    return (isinstance(value, int | float) and not isinstance(value, bool)) or (
        isinstance(value, str) and bool(_NUMBER.match(value))
    )


def _exps(kind: Kind) -> tuple[int, int, int]:
    return tuple(DIMENSIONS[kind]) if isinstance(kind, str) else tuple(kind)


def _has_unit(kind: Kind) -> bool:
    """Whether a number of ``kind`` needs a unit (angles do: rad or deg)."""
    return kind == "angle" or (kind != "dimensionless" and any(_exps(kind)))


def _needed(kind: Kind, unit: str | None) -> str:
    if unit:
        return f"a plain number (the law's value is in {unit})"
    return d.describe(d.dim(_exps(kind))) if not isinstance(kind, str) else _article(kind)


def _article(kind: str) -> str:
    name = kind.replace("_", " ")
    if kind == "dimensionless":
        return "a plain number"
    return ("an " if name[0] in "aeiou" else "a ") + name


def si_value(reading: Reading, units: UnitSystem) -> tuple[float, str, str] | None:
    """``(value in SI, SI unit, model unit)`` of a recorded number (None: an expression)."""
    if reading.value is None:
        return None
    if reading.kind is None:
        exps = exponents(reading.unit) if reading.unit else (0, 0, 0)
        model = unit_for(exps, units)
        return reading.value * factor(model or "dimensionless", exps, SI), unit_for(exps, SI), model
    if isinstance(reading.kind, str):
        model, si = units.label(reading.kind), SI.label(reading.kind)
    else:
        model, si = unit_for(reading.kind, units), unit_for(reading.kind, SI)
    return reading.value * factor(model or "dimensionless", _exps(reading.kind), SI), si, model


__all__ = ["Reading", "Readings", "si_value", "spec_units"]
