"""The unit kinds of the numbers that studies vary come from the elements' declarations
(mixdyn.model._declare.number_kind): a swept, fitted or optimized number of a joint or force
given with a unit is converted to the model's units by its declared kind, a kind that
depends on the element (a rotary spring's stiffness, the stick band of friction in a
revolute joint) included; a unit of the wrong kind is refused at its line."""

from __future__ import annotations

import math

import pytest

import mixdyn.io as mio
from mixdyn.io._errors import FileError
from mixdyn.model._declare import number_kind
from mixdyn.runs import Runner

MODEL = """\
mixdyn: 1
units: {length: mm, mass: kg, time: s}
bodies:
  - {name: crank, mass: 1, inertia: 100, points: {O: [0, 0], A: [50, 0]}}
  - {name: slider, mass: 1, inertia: 100, q0: [150, 0, 0]}
joints:
  - {type: revolute, name: O, point_i: ground, point_j: crank.O}
  - {type: distance, name: rod, point_i: crank.A, point_j: slider, length: 100}
  - {type: translational, name: slide, point_i: ground, point_j: slider}
forces:
  - {type: spring_damper, name: spring, point_i: ground, point_j: slider, stiffness: 1}
  - {type: rotary_spring_damper, name: coil, body_i: ground, body_j: crank}
  - {type: joint_friction, name: pin, joint: O, mu: 0.1, radius: 5}
  - {type: joint_friction, name: guide, joint: slide, mu: 0.1}
runs:
  - {name: fwd, kind: forward, time: {span: [0, 0.1], n: 3}}
  - name: sweep
    kind: sweep
    run: fwd
    vary:
"""

#: A varied number with a unit, and its value in the model's units (mm, kg, s: a force in
#: mN, a torque in mN*mm).
VARIED = {
    "rod.length": ("0.1 m", 100.0),
    "spring.stiffness": ("2 N/mm", 2000.0),
    "spring.free_length": ("3 cm", 30.0),
    "coil.stiffness": ("500 N*mm/rad", 5e5),
    "coil.free_angle": ("90 deg", math.pi / 2),
    "pin.radius": ("0.5 cm", 5.0),
    "pin.v_stick": ("1 deg/s", math.pi / 180),
    "guide.v_stick": ("1 mm/s", 1.0),
}


def _file(vary: dict[str, str]) -> str:
    lines = [f"      {name}: {{values: [{value!r}]}}\n" for name, value in vary.items()]
    return MODEL + "".join(lines)


def test_a_varied_element_number_is_converted_by_its_declared_kind():
    runner = Runner(mio.reads(_file({k: v for k, (v, _) in VARIED.items()})))
    values = runner.plans["sweep"].values
    for name, (_, expected) in VARIED.items():
        assert values[name][0] == pytest.approx(expected, rel=1e-12), name


def test_the_kinds_are_the_declarations():
    model = mio.build(mio.reads(_file({"rod.length": "1 m"})))
    kinds = {
        name: number_kind(model.element(name.split(".")[0]), name.split(".")[1], model)
        for name in VARIED
    }
    assert kinds == {
        "rod.length": "length",
        "spring.stiffness": "stiffness",
        "spring.free_length": "length",
        "coil.stiffness": "rotational_stiffness",
        "coil.free_angle": "angle",
        "pin.radius": "length",
        "pin.v_stick": "angular_velocity",
        "guide.v_stick": "velocity",
    }
    assert number_kind(model.element("spring"), "actuator") is None  # a law


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("pin.v_stick", "1 mm/s", "expected an angular velocity"),
        ("guide.v_stick", "1 deg/s", "expected a velocity"),
        ("rod.length", "1 N", "expected a length"),
    ],
)
def test_a_unit_of_another_kind_is_refused_at_its_line(name, value, words):
    text = _file({name: value})
    with pytest.raises(FileError, match=words) as err:
        Runner(mio.reads(text))
    assert err.value.line == text.count("\n")  # the varied number's line, the last
