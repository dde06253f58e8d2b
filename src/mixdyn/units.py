"""Unit systems. A model declares one consistent base system; every number in it and in its
results is expressed in that system. Angles are always radians.

Example: the paper's system is ``UnitSystem(length="mm", mass="kg", time="s")``, in which a
force is a ``kg*mm/s**2`` (one millinewton) and a torque a ``kg*mm**2/s**2``.
"""

from __future__ import annotations

import dataclasses

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

    def describe(self) -> str:
        """One line naming the system, e.g. ``"length mm, mass kg, time s, angle rad"``."""
        return f"length {self.length}, mass {self.mass}, time {self.time}, angle rad"


#: Common spellings accepted without asking pint (fast, and no import at start-up).
_KNOWN = {
    "length": {"m", "mm", "cm", "dm", "km", "um", "µm", "nm", "in", "inch", "ft", "foot"},
    "mass": {"kg", "g", "mg", "t", "tonne", "lb", "pound"},
    "time": {"s", "ms", "us", "µs", "min", "h", "hour", "second", "minute"},
}


def _check_unit(text, kind: str) -> None:
    """Refuse a unit that pint does not know or that is not of ``kind`` (``"length"``...)."""
    from .errors import ModelError

    if not isinstance(text, str) or not text.strip():
        raise ModelError(f"the {kind} unit must be a unit name such as 'm', got {text!r}")
    if text in _KNOWN[kind]:
        return
    from .io.quantities import QuantityError, exponents

    try:
        exps = exponents(text)
    except QuantityError as e:
        raise ModelError(f"{kind} unit {text!r}: {e.problem}", "units") from None
    if exps != DIMENSIONS[kind]:
        raise ModelError(f"{text!r} is not a unit of {kind}", "units")


SI = UnitSystem("m", "kg", "s")
