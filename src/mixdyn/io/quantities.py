"""Quantities with units in model files, converted into a model's unit system
(:mod:`mixdyn.units`).

A scalar in a model file is either a plain number, taken in the model's units (angles in
radians), or a string: a number or a constant expression followed by a unit, such as
``"500 N*mm"``, ``"30 deg"``, ``"pi/6 rad"`` or ``"2*L0 mm"``. It is converted to the model
unit of the quantity's kind (:func:`mixdyn.units.UnitSystem.unit`); a unit of another dimension
is an error.
"""

from __future__ import annotations

import math
import re

from ..units import (  # noqa: F401  (the units' names, read here by the file layer)
    _UNIT,
    CACHE_SIZE,
    MAX_LENGTH,
    DimensionError,
    Kind,
    QuantityError,
    UnitSystem,
    _article,
    _cached,
    _unit,
    dimension,
    exponents,
    factor,
    kind_name,
    kind_of,
    model_unit,
    registry,
    unit_for,
)

_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*$")
_NUMBER_PREFIX = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def convert(
    value,
    kind: Kind | None,
    units: UnitSystem,
    constants: dict[str, float] | None = None,
    scale: float = 1.0,
) -> float:
    """A scalar of a model file in the model's unit of ``kind``.

    Args:
        value: a number (already in model units) or a string: a number or a constant
            expression (numbers, ``pi``, ``e``, the names in ``constants``, arithmetic, the
            functions of :mod:`mixdyn.io.expressions`) optionally followed by a unit.
        kind: a key of :data:`mixdyn.units.DIMENSIONS` or exponents (length, mass, time), or
            None for any dimension (the value is then expressed in the model's base units of
            its own dimension).
        units: the model's unit system.
        constants: named values usable in the expression (the file's parameters).
        scale: factor applied to values written without a unit (default 1: model units).

    Raises:
        QuantityError: not a number, unknown unit, or a unit of the wrong dimension.
    """
    if isinstance(value, bool) or value is None:
        raise QuantityError(f"{value!r} is not a number", _example_hint(kind, units))
    if isinstance(value, int | float):
        out = float(value) * scale
        if not math.isfinite(out):
            raise QuantityError(f"{value!r} is not a finite number", _example_hint(kind, units))
        return out
    if not isinstance(value, str):
        raise QuantityError(
            f"expected a number, got {type(value).__name__} {value!r}", _example_hint(kind, units)
        )
    text = value.strip()
    if len(text) > MAX_LENGTH:
        raise QuantityError(f"the value is longer than {MAX_LENGTH} characters", "")
    if _NUMBER.match(text):
        return _finite(float(text) * scale, value, kind, units)
    magnitude, unit = _split(text, constants or {}, kind, units)
    f = scale if unit is None else factor(unit, kind, units)
    return _finite(magnitude * f, value, kind, units)


def _finite(x: float, value, kind, units) -> float:
    if not math.isfinite(x):
        raise QuantityError(f"{value!r} is not a finite number", _example_hint(kind, units))
    return x


def looks_like_quantity(text: str) -> bool:
    """Whether ``text`` reads as a number followed by a unit (``"50 N"``, ``"3 furlongs"``)."""
    m = _NUMBER_PREFIX.match(text)
    return bool(m and m.group(2) and _UNIT.match(m.group(2)))


def has_unit_tail(text: str) -> bool:
    """Whether ``text`` reads as numeric arithmetic followed by a unit (``"1/0 N"``,
    ``"2*L mm"``)."""
    words = text.split()
    return any(
        _UNIT.match(" ".join(words[k:]))
        and re.search(r"[0-9]", " ".join(words[:k]))
        and _parses(" ".join(words[:k]))
        for k in range(1, len(words))
    )


def _parses(text: str) -> bool:
    """Whether ``text`` is a complete expression (``"pi/2 +"`` is not: in ``"pi/2 + omega*t"``
    the words after it are the rest of a formula, not a unit)."""
    import ast

    try:
        ast.parse(text, mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return False
    return True


def _split(text: str, constants, kind, units) -> tuple[float, str | None]:
    """Split ``"EXPR UNIT"`` into the expression's value and the unit text."""
    from .expressions import ExpressionError, constant_value

    m = _NUMBER_PREFIX.match(text)
    if m and m.group(2) and _UNIT.match(m.group(2)):
        return float(m.group(1)), m.group(2)
    words = text.split()
    with_unit, without_unit = None, None
    for k in range(len(words), 0, -1):
        head, tail = " ".join(words[:k]), " ".join(words[k:])
        if tail and not _UNIT.match(tail):
            continue
        try:
            v = constant_value(head, constants)
        except ExpressionError as e:
            if re.search(r"[0-9()*/+^-]", head):  # an attempt at an expression
                if tail and with_unit is None:
                    with_unit = e
                elif not tail:
                    without_unit = e
            continue
        return v, (tail or None)
    error = with_unit or without_unit
    if error is not None:
        raise QuantityError(
            f"cannot read {text!r}: {error.message}", error.hint or _example_hint(kind, units)
        )
    raise QuantityError(f"cannot read {text!r} as a number with a unit", _example_hint(kind, units))


def _example_hint(kind: Kind | None, units: UnitSystem) -> str:
    examples = {
        "length": "'25' (in {u}) or '25 mm'",
        "mass": "'0.02' (in {u}) or '20 g'",
        "angle": "'0.5' (in rad) or '30 deg'",
        "force": "'10' (in {u}) or '10 N'",
        "torque": "'500' (in {u}) or '0.5 N*m'",
        "inertia": "'20' (in {u}) or '2e-5 kg*m**2'",
        "time": "'2' (in {u}) or '2 s'",
    }
    if kind is None:
        return "write a number or a number with units, e.g. '10 N'"
    ex = (
        examples.get(kind, "a number (in {u}) or a number with units")
        if isinstance(kind, str)
        else "a number (in {u}) or a number with units"
    )
    return "write " + ex.format(u=model_unit(kind, units) or "model units")
