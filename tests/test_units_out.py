"""Result units named plainly (issue 14): forces in N, torques in N*m, energies in J, powers in
W, with the SI prefix that makes them exactly the model's units (mN and mN*mm in mm, kg, s);
pint, reading both spellings, is the truth that they are the same unit."""

from __future__ import annotations

import pytest

import mixdyn as md
from mixdyn.io.quantities import factor
from mixdyn.units import DIMENSIONS

SYSTEMS = [
    md.SI,
    md.UnitSystem("mm", "kg", "s"),
    md.UnitSystem("mm", "g", "ms"),
    md.UnitSystem("cm", "g", "s"),
    md.UnitSystem("in", "lb", "s"),
    md.UnitSystem("km", "t", "s"),
]


@pytest.mark.parametrize("units", SYSTEMS, ids=lambda u: u.describe())
def test_every_label_is_exactly_the_models_unit(units):
    for kind in DIMENSIONS:
        label, base = units.label(kind), units.unit(kind)
        if not base:
            assert label == ""
            continue
        # pint's factor of each spelling into the model's unit of the kind: both exactly 1
        assert factor(label, kind, units) == pytest.approx(1.0, rel=1e-12), (kind, label)
        assert factor(base, kind, units) == pytest.approx(1.0, rel=1e-12), (kind, base)


def test_the_plain_names():
    si, mm = md.SI, md.UnitSystem("mm", "kg", "s")
    assert [si.label(k) for k in ("force", "torque", "energy", "power")] == ["N", "N*m", "J", "W"]
    assert [mm.label(k) for k in ("force", "torque", "energy", "power", "stiffness")] == [
        "mN",
        "mN*mm",
        "µJ",
        "µW",
        "mN/mm",
    ]
    assert md.UnitSystem("mm", "g", "ms").label("torque") == "N*mm"
    # no SI prefix is exact in inches and pounds: the base spelling
    assert md.UnitSystem("in", "lb", "s").label("force") == "lb*in/s**2"
