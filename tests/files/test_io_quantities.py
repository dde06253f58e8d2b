"""Quantities with units, converted into a model's unit system."""

import math
import re

import pytest

from mixdyn.io.quantities import DimensionError, QuantityError, convert, factor
from mixdyn.units import UnitSystem

MM = UnitSystem("mm", "kg", "s")


@pytest.mark.parametrize(
    ("value", "kind", "expected"),
    [
        (500, "torque", 500.0),  # numbers are in model units
        ("500", "torque", 500.0),
        ("500 N*mm", "torque", 500e3),  # 1 N*mm = 1000 kg*mm**2/s**2
        ("0.5 N*m", "torque", 500e3),
        ("10 N", "force", 10e3),
        ("30 deg", "angle", math.pi / 6),
        ("pi/6 rad", "angle", math.pi / 6),
        ("60 rpm", "angular_velocity", 2 * math.pi),
        ("20 g", "mass", 0.02),
        ("2e-5 kg*m^2", "inertia", 20.0),
        ("2e-5 kg*m**2", "inertia", 20.0),
        ("1 m/s", "velocity", 1000.0),
        ("9.81 m/s^2", "acceleration", 9810.0),
        ("2 N/mm", "stiffness", 2000.0),
        ("1.5 cm", "length", 15.0),
        ("2*L0 mm", "length", 6.0),
        ("L0", "length", 3.0),
        ("1e-3", "length", 1e-3),
        ("5 mm\u00b2", (2, 0, 0), 5.0),
        ("3 (N*mm)/rad", "rotational_stiffness", 3000.0),
    ],
)
def test_conversions(value, kind, expected):
    assert convert(value, kind, MM, {"L0": 3.0}) == pytest.approx(expected, rel=1e-12)


def test_scale_applies_to_values_without_units():
    assert convert(2, "force", MM, scale=1000.0) == 2000.0
    assert convert("2 N", "force", MM, scale=123.0) == 2000.0


@pytest.mark.parametrize(
    ("value", "kind", "error", "message"),
    [
        ("5 mm", "torque", DimensionError, "is a unit of length, expected a torque"),
        ("30 deg", "length", DimensionError, "expected a length"),
        ("1 kg", "inertia", DimensionError, "expected an inertia"),
        ("heavy", "mass", QuantityError, "cannot read 'heavy'"),
        ("5 furlongz", "length", QuantityError, "unknown unit"),
        ("5 degC", "length", QuantityError, "temperature"),
        (True, "mass", QuantityError, "is not a number"),
        (None, "mass", QuantityError, "is not a number"),
        (float("nan"), "mass", QuantityError, "not a finite number"),
        ([1, 2], "mass", QuantityError, "expected a number"),
        ("1 __import__('os')", "length", QuantityError, "cannot read"),
        ("10**10**10 mm", "length", QuantityError, "not a finite number"),
        ("L^2 mm", "length", QuantityError, "'^' is not a power"),
        ("x" * 300, "length", QuantityError, "longer than"),
    ],
)
def test_refused(value, kind, error, message):
    with pytest.raises(error, match=re.escape(message)):
        convert(value, kind, MM, {"L": 1.0})


def test_factor_of_any_dimension():
    assert factor("N", None, MM) == pytest.approx(1000.0)
    assert factor("N", "force", UnitSystem("m", "kg", "s")) == 1.0
