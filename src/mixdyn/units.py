"""Unit systems and units, the one place mixdyn reads units (with pint). A model declares one
consistent base system; every number in it and in its results is expressed in that system.
Angles are always radians. Unit strings are checked against a strict pattern (unit names,
``*``, ``/``, ``**`` with small integer exponents, parentheses) before pint sees them, so
nothing but unit names is ever evaluated.

Example: the paper's system is ``UnitSystem(length="mm", mass="kg", time="s")``, in which a
force is a ``kg*mm/s**2`` (one millinewton) and a torque a ``kg*mm**2/s**2``.
"""

from __future__ import annotations

import dataclasses
import functools
import re

from .errors import ModelError

#: Dimension of every kind of quantity, as exponents of (length, mass, time).
DIMENSIONS: dict[str, tuple[int, int, int]] = {
    "length": (1, 0, 0),
    "mass": (0, 1, 0),
    "time": (0, 0, 1),
    "angle": (0, 0, 0),
    "velocity": (1, 0, -1),
    "acceleration": (1, 0, -2),
    "angular_velocity": (0, 0, -1),
    "angular_acceleration": (0, 0, -2),
    "force": (1, 1, -2),
    "torque": (2, 1, -2),
    "inertia": (2, 1, 0),
    "energy": (2, 1, -2),
    "power": (2, 1, -3),
    "stiffness": (0, 1, -2),
    "damping": (0, 1, -1),
    "rotational_stiffness": (2, 1, -2),
    "rotational_damping": (2, 1, -1),
    "pressure": (-1, 1, -2),
    "impulse": (1, 1, -1),
    "dimensionless": (0, 0, 0),
}


@dataclasses.dataclass(frozen=True)
class UnitSystem:
    """A consistent base system of units (pint spellings); angles in radians.

    Attributes:
        length: unit of length, e.g. ``"m"`` or ``"mm"``.
        mass: unit of mass, e.g. ``"kg"``.
        time: unit of time, e.g. ``"s"``.
    """

    length: str = "m"
    mass: str = "kg"
    time: str = "s"

    def __post_init__(self):
        for kind in ("length", "mass", "time"):
            _check_unit(getattr(self, kind), kind)

    def unit(self, kind: str) -> str:
        """The unit of a kind of quantity (a key of :data:`DIMENSIONS`) in this system.

        Returns a pint-parsable string, e.g. ``"kg*mm/s**2"`` for ``"force"``, ``"rad"`` for
        angles, ``""`` for dimensionless numbers.
        """
        if kind in ("angle",):
            return "rad"
        if kind == "angular_velocity":
            return f"rad/{self.time}"
        if kind == "angular_acceleration":
            return f"rad/{self.time}**2"
        try:
            exps = DIMENSIONS[kind]
        except KeyError:
            raise KeyError(
                f"unknown kind of quantity {kind!r}; known: {sorted(DIMENSIONS)}"
            ) from None
        num, den = [], []
        for name, e in zip((self.length, self.mass, self.time), exps, strict=True):
            if e == 0:
                continue
            target = num if e > 0 else den
            target.append(name if abs(e) == 1 else f"{name}**{abs(e)}")
        order = {self.mass: 0, self.length: 1, self.time: 2}
        num.sort(key=lambda s: order.get(s.split("*")[0], 3))
        text = "*".join(num) if num else "1"
        if den:
            text += "/" + ("/".join(den))
        return "" if text == "1" else text

    def label(self, kind: str) -> str:
        """The unit of a kind of quantity named plainly, for results: a force in ``N``, a
        torque in ``N*m``, an energy in ``J``, a power in ``W``, with the SI prefix that makes
        it exactly the system's unit (in mm, kg, s: ``mN``, ``mN*mm``, ``µJ``, ``µW``; a
        stiffness ``mN/mm``), pint-parsable. Where no prefix is exact (inches, pounds,
        minutes), :meth:`unit`'s base spelling.
        """
        base = self.unit(kind)
        force = self._prefixed("N", DIMENSIONS["force"])
        if force is None or kind not in _DERIVED:
            return base
        L, T = self.length, self.time
        if kind == "force":
            return force
        if kind in ("energy", "power"):
            return self._prefixed("J" if kind == "energy" else "W", DIMENSIONS[kind]) or base
        return _DERIVED[kind].format(F=force, L=L, T=T)

    def _prefixed(self, symbol: str, exps: tuple[int, int, int]) -> str | None:
        """``symbol`` with the SI prefix equal to this system's unit of ``exps``, or None."""
        try:
            scale = 1.0
            for name, e, kind in zip((self.length, self.mass, self.time), exps, _BASE, strict=True):
                scale *= _SI_FACTORS[kind][name] ** e
        except KeyError:
            return None
        for prefix, value in _PREFIXES.items():
            if abs(scale / value - 1.0) < 1e-12:
                return prefix + symbol
        return None

    def describe(self) -> str:
        """One line naming the system, e.g. ``"length mm, mass kg, time s, angle rad"``."""
        return f"length {self.length}, mass {self.mass}, time {self.time}, angle rad"


_BASE = ("length", "mass", "time")
#: SI value of the common base units (those whose derived units may take an SI prefix).
_SI_FACTORS = {
    "length": {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "dm": 1e-1, "km": 1e3, "um": 1e-6,
               "µm": 1e-6, "nm": 1e-9},
    "mass": {"kg": 1.0, "g": 1e-3, "mg": 1e-6, "t": 1e3, "tonne": 1e3},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "second": 1.0},
}  # fmt: skip
#: SI prefixes and their values.
_PREFIXES = {
    "": 1.0, "k": 1e3, "M": 1e6, "G": 1e9, "T": 1e12, "m": 1e-3, "µ": 1e-6, "n": 1e-9,
    "p": 1e-12, "c": 1e-2, "d": 1e-1, "da": 1e1, "h": 1e2,
}  # fmt: skip
#: Plain spellings of derived units from the force's ({F}), the length ({L}) and time ({T}).
_DERIVED = {
    "force": "{F}",
    "torque": "{F}*{L}",
    "energy": "",
    "power": "",
    "stiffness": "{F}/{L}",
    "damping": "{F}*{T}/{L}",
    "rotational_stiffness": "{F}*{L}/rad",
    "rotational_damping": "{F}*{L}*{T}/rad",
    "pressure": "{F}/{L}**2",
    "impulse": "{F}*{T}",
}

#: Common spellings accepted without asking pint (fast, and no import at start-up).
_KNOWN = {
    "length": {"m", "mm", "cm", "dm", "km", "um", "µm", "nm", "in", "inch", "ft", "foot"},
    "mass": {"kg", "g", "mg", "t", "tonne", "lb", "pound"},
    "time": {"s", "ms", "us", "µs", "min", "h", "hour", "second", "minute"},
}


def _check_unit(text, kind: str) -> None:
    """Refuse a unit that pint does not know or that is not of ``kind`` (``"length"``...)."""
    if not isinstance(text, str) or not text.strip():
        raise ModelError(f"the {kind} unit must be a unit name such as 'm', got {text!r}")
    if text in _KNOWN[kind]:
        return
    try:
        exps = exponents(text)
    except QuantityError as e:
        raise ModelError(f"{kind} unit {text!r}: {e.problem}", "units") from None
    if exps != DIMENSIONS[kind]:
        raise ModelError(f"{text!r} is not a unit of {kind}", "units")


def size_in(unit_text: str, kind: str, system: UnitSystem) -> float:
    """How many of ``system``'s units of ``kind`` one ``unit_text`` is (``"N"`` -> 1000 in
    mm, kg, s; ``"deg"`` -> pi/180 for an angle). Raises ``QuantityError`` (a
    :class:`mixdyn.errors.ModelError`) for a unit of another kind or an unknown one."""
    return factor(unit_text, kind, system)


# --------------------------------------------------------------------------- pint
#: Longest quantity string accepted.
MAX_LENGTH = 200

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

    from .runtime._programs import cache_folder

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
    text = plain(text).replace("^", "**")
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
    try:
        exps = exponents(unit_text)
    except QuantityError as e:
        close = close_units(unit_text, kind)
        if not close:
            raise
        raise QuantityError(e.problem, f"did you mean {_either(close)}?") from None
    if kind is not None and exps != dimension(kind):
        name = kind_name(kind)
        close = close_units(unit_text, kind)
        raise DimensionError(
            f"{unit_text!r} is a unit of {kind_of(exps).replace('_', ' ')}, expected "
            f"{_article(name)} ({model_unit(kind, units) or 'dimensionless'})",
            f"did you mean {_either(close)}?" if close else f"give the value in a unit of {name}",
        )
    target = unit_for(exps, units)
    q = registry().Quantity(1.0, _unit(unit_text))
    value = q.to(target).magnitude if target else q.to("dimensionless").magnitude
    return float(value)


#: Common units of each kind, the spellings :func:`close_units` suggests.
COMMON_UNITS: dict[str, tuple[str, ...]] = {
    "length": ("m", "mm", "cm", "km", "um", "in", "ft"),
    "mass": ("kg", "g", "mg", "t", "lb"),
    "time": ("s", "ms", "min", "h"),
    "angle": ("rad", "deg", "rev"),
    "velocity": ("m/s", "mm/s", "km/h"),
    "acceleration": ("m/s**2", "mm/s**2"),
    "angular_velocity": ("rad/s", "rpm", "deg/s", "rev/s", "Hz"),
    "angular_acceleration": ("rad/s**2", "deg/s**2"),
    "force": ("N", "kN", "mN", "lbf"),
    "torque": ("N*m", "N*mm", "N*cm", "kN*m", "mN*m", "lbf*ft", "lbf*in"),
    "inertia": ("kg*m**2", "kg*mm**2", "kg*cm**2", "g*cm**2", "g*mm**2"),
    "energy": ("J", "kJ", "mJ"),
    "power": ("W", "kW"),
    "stiffness": ("N/m", "N/mm", "kN/m"),
    "damping": ("N*s/m", "N*s/mm"),
    "rotational_stiffness": ("N*m/rad", "N*mm/rad", "N*m/deg"),
    "rotational_damping": ("N*m*s/rad", "N*mm*s/rad"),
    "pressure": ("Pa", "kPa", "MPa", "GPa", "N/mm**2"),
    "impulse": ("N*s", "mN*s"),
}


def _squashed(text: str) -> str:
    """A unit's spelling without separators and powers' marks (``kg*m**2`` -> ``kgm2``)."""
    return re.sub(r"[\s*·.^]", "", text.replace("**", "")).replace("²", "2").replace("³", "3")


def close_units(text: str, kind: Kind | None = None) -> list[str]:
    """Common units (:data:`COMMON_UNITS`) spelled like ``text`` but for separators, powers'
    marks or case (``Nm`` -> ``N*m``, ``kg m2`` -> ``kg*m**2``, ``RPM`` -> ``rpm``), of the
    dimension of ``kind`` where given, best first; then near misses of one letter."""
    import difflib

    want = None if kind is None else dimension(kind)
    names = [
        u
        for k, units in COMMON_UNITS.items()
        if want is None or DIMENSIONS[k] == want
        for u in units
        if u != text
    ]
    names = list(dict.fromkeys(names))
    key = _squashed(text)
    same = [u for u in names if _squashed(u) == key]
    if not same:
        same = [u for u in names if _squashed(u).lower() == key.lower()]
    if same or want is None:
        return same
    squashed = {_squashed(u): u for u in names}
    near = difflib.get_close_matches(key, list(squashed), n=2, cutoff=0.75)
    return [squashed[k] for k in near]


def _either(units: list[str]) -> str:
    return " or ".join(f"'{u}'" for u in units)


def _article(name: str) -> str:
    return ("an " if name[0] in "aeiou" else "a ") + name


# --------------------------------------------------------------------------- labels
_SUPERSCRIPTS = str.maketrans(
    "0123456789-", "\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079\u207b"
)
_PLAIN_DIGITS = {
    v: k
    for k, v in zip(
        "0123456789-",
        "\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079\u207b",
        strict=True,
    )
}
_MICRO = {"um": "\u00b5m", "us": "\u00b5s"}


def engineering(unit: str) -> str:
    """A unit as an engineer writes it, for tables, figures and files: products with a
    middle dot, powers as superscripts, micro as µ (``mN*mm`` -> ``mN·mm``,
    ``mm/s**2`` -> ``mm/s²``, ``kg*mm**2`` -> ``kg·mm²``, ``um`` -> ``µm``). mixdyn reads
    these spellings back (:func:`plain`); ``""`` stays ``""``."""
    text = re.sub(
        r"\s*\*\*\s*([-+]?\d+)", lambda m: m[1].lstrip("+").translate(_SUPERSCRIPTS), unit
    )
    text = re.sub(r"\s*\*\s*", "\u00b7", text)
    return re.sub(r"[A-Za-z_]+", lambda m: _MICRO.get(m[0], m[0]), text)


def plain(unit: str) -> str:
    """The pint spelling of a unit written by :func:`engineering` (``N·m`` -> ``N*m``,
    ``mm/s²`` -> ``mm/s**2``); other spellings as they are."""
    text = re.sub(
        "[\u2070\u00b9\u00b2\u00b3\u2074-\u2079\u207b]+",
        lambda m: "**" + "".join(_PLAIN_DIGITS[c] for c in m[0]),
        unit,
    )
    return text.replace("\u00b7", "*").replace("\u22c5", "*")


#: ``output_units`` presets: every kind of quantity of the results in one named system
#: (``output_units: SI``; ``{preset: mm-N-s, angle: deg}`` changes some of them).
OUTPUT_PRESETS: dict[str, dict[str, str]] = {
    "SI": {
        "length": "m", "mass": "kg", "time": "s", "angle": "rad", "velocity": "m/s",
        "acceleration": "m/s**2", "angular_velocity": "rad/s",
        "angular_acceleration": "rad/s**2", "force": "N", "torque": "N*m",
        "inertia": "kg*m**2", "energy": "J", "power": "W", "stiffness": "N/m",
        "damping": "N*s/m", "rotational_stiffness": "N*m/rad",
        "rotational_damping": "N*m*s/rad", "pressure": "Pa", "impulse": "N*s",
    },
    "mm-N-s": {
        "length": "mm", "mass": "kg", "time": "s", "angle": "rad", "velocity": "mm/s",
        "acceleration": "mm/s**2", "angular_velocity": "rad/s",
        "angular_acceleration": "rad/s**2", "force": "N", "torque": "N*mm",
        "inertia": "kg*mm**2", "energy": "mJ", "power": "mW", "stiffness": "N/mm",
        "damping": "N*s/mm", "rotational_stiffness": "N*mm/rad",
        "rotational_damping": "N*mm*s/rad", "pressure": "MPa", "impulse": "N*s",
    },
}  # fmt: skip


def preset(name: str) -> dict[str, str]:
    """The units of the ``output_units`` preset ``name`` (:data:`OUTPUT_PRESETS`): kind of
    quantity -> unit. Raises :class:`~mixdyn.errors.ModelError` for an unknown name."""
    if name not in OUTPUT_PRESETS:
        from ._hints import did_you_mean

        raise ModelError(
            f"no preset of output units {name!r}; {did_you_mean(name, OUTPUT_PRESETS, 'presets')}"
        )
    return dict(OUTPUT_PRESETS[name])


SI = UnitSystem("m", "kg", "s")

#: Names of energy and power units by their size in J and W (:func:`completed`).
_NAMED = {
    "energy": {1.0: "J", 1e3: "kJ", 1e6: "MJ", 1e-3: "mJ", 1e-6: "uJ"},
    "power": {1.0: "W", 1e3: "kW", 1e6: "MW", 1e-3: "mW", 1e-6: "uW"},
}


def _named(kind: str, size: float, spelled: str) -> str:
    """The unit of ``kind`` of ``size`` [J or W]: its name where it has one (``mJ``), else
    ``spelled``."""
    for s, name in _NAMED[kind].items():
        if abs(size - s) <= 1e-12 * s:
            return name
    return spelled


def completed(output_units: dict[str, str], model_units: UnitSystem | None) -> dict[str, str]:
    """``output_units`` with the energy and the power following the units given by hand,
    where they are not given themselves: the energy in the torque's unit (``N*m`` -> ``J``,
    ``N*mm`` -> ``mJ``), else in the force's unit times the length's; the power in the
    energy's unit per the time's unit (the model's where not given): ``{torque: N*m}`` shows a
    motor's power in W, not in the model's µW.

    Args:
        output_units: kind of quantity -> unit (presets expanded).
        model_units: the model's unit system (its time unit where none is given).
    """
    out = dict(output_units)
    if "energy" not in out:
        if "torque" in out:
            spelled = out["torque"]
        elif "force" in out and "length" in out:
            spelled = f"{out['force']}*{out['length']}"
        else:
            spelled = None
        if spelled is not None:
            out["energy"] = _named("energy", size_in(spelled, "energy", SI), spelled)
    if "power" not in out and "energy" in out:
        time = out.get("time") or (model_units.time if model_units is not None else "s")
        spelled = f"({out['energy']})/{time}"
        size = size_in(out["energy"], "energy", SI) / size_in(time, "time", SI)
        out["power"] = _named("power", size, spelled)
    return out


def in_units(result, columns: dict, units: dict, output_units: dict | None, kinds=None):
    """``(columns, units)`` with every column of a kind named in ``output_units`` (kind ->
    unit, e.g. ``{"angle": "deg", "torque": "N*m"}``, or a preset's name: ``"SI"``,
    ``"mm-N-s"``, :data:`mixdyn.units.OUTPUT_PRESETS`) converted into that unit; the others
    as they are (the model's units). ``columns`` and ``units`` as from
    :func:`mixdyn.viz.result_columns` or ``result.columns()``/``result.units()``; ``kinds``:
    the columns' kinds of quantity by name where they are not the result's
    (``result.kind_of``)."""
    if not output_units:
        return columns, units
    import numpy as np

    factor = size_in

    if isinstance(output_units, str):
        output_units = preset(output_units)
    output_units = completed(output_units, result.model.units)

    cols, out = dict(columns), dict(units)
    for name in columns:
        kind = result.kind_of(name) if kinds is None else kinds.get(name)
        if kind in output_units:
            cols[name] = np.asarray(columns[name]) / factor(
                output_units[kind], kind, result.model.units
            )
            out[name] = output_units[kind]
    return cols, out
