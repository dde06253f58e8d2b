"""Quantities with units, converted into a model's unit system with pint.

A scalar in a model file is either a plain number, taken in the model's units (angles in
radians), or a string: a number or a constant expression followed by a unit, such as
``"500 N*mm"``, ``"30 deg"``, ``"pi/6 rad"`` or ``"2*L0 mm"``. It is converted to the model
unit of the quantity's kind (:func:`mixdyn.units.UnitSystem.unit`); a unit of another dimension
is an error.

Unit strings are checked against a strict pattern (unit names, ``*``, ``/``, ``**`` with small
integer exponents, parentheses) before pint sees them, so nothing but unit names is ever
evaluated.
"""

from __future__ import annotations

import functools
import math
import re

from ..errors import ModelError
from ..units import DIMENSIONS, UnitSystem

#: Longest quantity string accepted.
MAX_LENGTH = 200

_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*$")
_NUMBER_PREFIX = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")
_UNIT_NAME = r"[A-Za-z_\u00b0\u00b5\u03bc\u03a9][A-Za-z0-9_\u00b0\u00b5\u03bc\u03a9]*"
_EXPONENT = r"(?:\s*(?:\*\*|\^)\s*[-+]?\d{1,2}|[\u00b2\u00b3])?"
_POWER = rf"{_UNIT_NAME}{_EXPONENT}"
_FACTOR = rf"(?:{_POWER}|\(\s*{_POWER}(?:\s*[*/ ]\s*{_POWER})*\s*\){_EXPONENT})"
_UNIT = re.compile(rf"^\s*(?:1\s*/\s*)?{_FACTOR}(?:\s*(?:\*|/|\s)\s*{_FACTOR})*\s*$")

_DIM_KEYS = ("[length]", "[mass]", "[time]")


class QuantityError(ModelError):
    """A scalar could not be read or has the wrong dimension. Attributes: ``problem``,
    ``hint``."""

    def __init__(self, problem: str, hint: str = ""):
        self.problem = problem
        self.hint = hint
        super().__init__(problem + (f"; {hint}" if hint else ""))


class DimensionError(QuantityError):
    """A unit of the wrong dimension (a length where a torque is expected)."""


Kind = str | tuple[int, int, int]
"""A kind of quantity: a key of :data:`mixdyn.units.DIMENSIONS` or exponents of (length,
mass, time)."""


def dimension(kind: Kind) -> tuple[int, int, int]:
    """Exponents of (length, mass, time) of a kind of quantity."""
    if isinstance(kind, str):
        return tuple(DIMENSIONS[kind])
    return tuple(int(e) for e in kind)


def model_unit(kind: Kind, units: UnitSystem) -> str:
    """The model's unit of a kind (``"rad"`` for angles, ``""`` for dimensionless)."""
    if isinstance(kind, str):
        return units.unit(kind)
    return unit_for(dimension(kind), units)


def kind_name(kind: Kind) -> str:
    """A readable name of a kind (``"torque"``, ``"force per time"``)."""
    if isinstance(kind, str):
        return kind.replace("_", " ")
    return kind_of(dimension(kind)).replace("_", " ")


@functools.cache
def registry():
    """The shared pint unit registry (created on first use), its parsed definitions kept in
    mixdyn's cache folder when the persistent caches are on (building it from the definition
    files takes ~0.15 s)."""
    import os

    import pint

    from ..runtime._programs import cache_folder

    folder = cache_folder()
    cache = os.path.join(folder, "pint") if folder else None
    try:
        return pint.UnitRegistry(autoconvert_offset_to_baseunit=False, cache_folder=cache)
    except Exception:  # pragma: no cover - a cache is never a failure
        return pint.UnitRegistry(autoconvert_offset_to_baseunit=False)


#: Distinct unit strings (and (unit, kind, unit system) conversions) remembered: parsing a
#: unit with pint takes about 0.1 ms, and a model file repeats a few units many times.
CACHE_SIZE = 4096


def _cached(fn, *args):
    """``fn(*args)`` through its cache, or directly when an argument cannot be hashed."""
    try:
        hash(args)
    except TypeError:
        return fn.__wrapped__(*args)
    return fn(*args)


def _unit(text: str):
    """The pint unit of ``text`` (cached: pint units are immutable; errors are not cached)."""
    return _cached(_parse_unit, text)


@functools.lru_cache(maxsize=CACHE_SIZE)
def _parse_unit(text: str):
    text = text.replace("\u00b2", "**2").replace("\u00b3", "**3").replace("^", "**")
    if len(text) > MAX_LENGTH or not _UNIT.match(text):
        raise QuantityError(
            f"{text!r} is not a unit", "write units like 'mm', 'N*mm', 'kg*mm**2', 'rad/s'"
        )
    import pint

    try:
        return registry().parse_units(text)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError) as e:
        raise QuantityError(
            f"unknown unit in {text!r} ({e})", "check the spelling: e.g. 'mm', 'N', 'deg', 's'"
        ) from None
    except Exception as e:  # pint raises assorted errors on malformed input
        raise QuantityError(f"{text!r} is not a unit ({type(e).__name__})", "") from None


def exponents(unit_text: str) -> tuple[int, int, int]:
    """Dimension of a unit as exponents of (length, mass, time).

    Raises:
        QuantityError: the unit is not mechanical (a temperature, a current...).
    """
    return _cached(_exponents, unit_text)


@functools.lru_cache(maxsize=CACHE_SIZE)
def _exponents(unit_text: str) -> tuple[int, int, int]:
    dim = dict(registry().Quantity(1.0, _unit(unit_text)).dimensionality)
    other = [k for k in dim if k not in _DIM_KEYS]
    if other:
        raise QuantityError(
            f"unit {unit_text!r} has dimension {', '.join(other)}",
            "use units of length, mass, time and angle only",
        )
    exps = tuple(dim.get(k, 0) for k in _DIM_KEYS)
    if any(float(e) != int(e) for e in exps):
        raise QuantityError(f"unit {unit_text!r} has a fractional dimension", "")
    return tuple(int(e) for e in exps)


def kind_of(exps: tuple[int, int, int]) -> str:
    """A readable name of a dimension (``"force"``), or the exponents if it has none."""
    for kind, e in DIMENSIONS.items():
        if tuple(e) == tuple(exps) and kind not in ("energy", "rotational_stiffness"):
            return kind
    return "length^{} mass^{} time^{}".format(*exps)


def unit_for(exps: tuple[int, int, int], units: UnitSystem) -> str:
    """The model's unit (pint spelling) of the dimension ``exps``."""
    num, den = [], []
    for name, e in zip((units.length, units.mass, units.time), exps, strict=True):
        if e:
            (num if e > 0 else den).append(name if abs(e) == 1 else f"{name}**{abs(e)}")
    text = "*".join(num) if num else ""
    if den:
        text = (text or "1") + "/" + "/".join(den)
    return text


def factor(unit_text: str, kind: Kind | None, units: UnitSystem) -> float:
    """How many model units of ``kind`` one ``unit_text`` is (e.g. ``"N"`` -> 1000 in a
    kg/mm/s system). ``kind=None`` accepts any mechanical dimension.

    Raises:
        QuantityError: unknown unit, or a dimension other than that of ``kind``.
    """
    return _cached(_factor, unit_text, kind, units)


@functools.lru_cache(maxsize=CACHE_SIZE)
def _factor(unit_text: str, kind: Kind | None, units: UnitSystem) -> float:
    exps = exponents(unit_text)
    if kind is not None and exps != dimension(kind):
        name = kind_name(kind)
        raise DimensionError(
            f"{unit_text!r} is a unit of {kind_of(exps).replace('_', ' ')}, expected "
            f"{_article(name)} ({model_unit(kind, units) or 'dimensionless'})",
            f"give the value in a unit of {name}",
        )
    target = unit_for(exps, units)
    q = registry().Quantity(1.0, _unit(unit_text))
    value = q.to(target).magnitude if target else q.to("dimensionless").magnitude
    return float(value)


def _article(name: str) -> str:
    return ("an " if name[0] in "aeiou" else "a ") + name


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
