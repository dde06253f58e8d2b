"""A plot's reference curve (``reference: {expr, unit}``) is checked as a law of ``t`` of the
kind of the plot's first column, in whose panel and unit it is drawn (docs/model-files.md,
"Units of numbers, laws and parameters"): a reference for an angle that comes out as a
length, or a unit of another dimension, is refused at its line before anything is computed.

The truths: dimensions worked out by hand (``L*sin(t)`` with ``L: 300 mm`` is a length; the
moment ``F*L`` a torque), the file's own text for the lines, and the curve drawn for a reference
in ``deg`` against its closed form in radians."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mixdyn.io as mio
from mixdyn.runs import Runner
from mixdyn.runs.analyses import _reference

MODEL = """\
mixdyn: 1
name: rod-mm
units: {length: mm, mass: kg, time: s}
gravity: [0, 0]
parameters:
  L: 300 mm
  F: 2 N
  w: 1 rad/s
bodies:
  - {name: rod, mass: 1 kg, inertia: 7500 kg*mm**2, q0: [150, 0, 0],
     points: {O: [-150, 0], tip: [150, 0]}}
joints:
  - {type: revolute, name: O, point_i: ground, point_j: rod.O}
drivers:
  - {type: coordinate, name: motor, coordinate: rod.phi, law: {polynomial: [0, 1]}}
runs:
  - name: turn
    kind: inverse
    time: {span: [0, 1], n: 3}
    plots:
      - {file: p.png, columns: [COLUMN], reference: REFERENCE}
"""


def _file(column: str, reference: str) -> str:
    return MODEL.replace("COLUMN", column).replace("REFERENCE", reference)


@pytest.mark.parametrize(
    ("column", "reference", "problem"),
    [
        ("rod.phi", "{expr: L*sin(w*t)}", "comes out as a length, not an angle"),
        ("rod.phi", "{expr: 0.5*sin(t), unit: mm}", "unit of length, expected an angle"),
        ("motor", "{expr: F*sin(w*t)}", "comes out as a force, not a torque"),
        ("rod.tip.x", "{expr: L*w}", "comes out as a velocity, not a length"),
    ],
)
def test_a_reference_of_another_dimension_is_refused_at_its_line(column, reference, problem):
    text = _file(column, reference)
    with pytest.raises(mio.FileError, match=problem) as err:
        Runner(mio.reads(text))
    assert (
        err.value.line
        == text.splitlines().index(
            f"      - {{file: p.png, columns: [{column}], reference: {reference}}}"
        )
        + 1
    )
    assert "reference" in str(err.value)


@pytest.mark.parametrize(
    ("column", "reference"),
    [
        ("rod.phi", "{expr: 0.5*sin(w*t)}"),
        ("rod.tip.x", "{expr: L*cos(w*t)}"),
        ("motor", "{expr: F*L*sin(w*t)}"),
        ("motor", "{expr: 2*t, unit: N*m}"),
        ("O.Fx", "{expr: -F*cos(w*t)}"),
    ],
)
def test_a_reference_of_its_columns_dimension_is_accepted(column, reference):
    Runner(mio.reads(_file(column, reference)))


def test_a_reference_in_degrees_is_drawn_in_radians():
    """``30*sin(t)`` in deg for an angle: the curve is pi/6 sin(t) rad (model units)."""
    runner = Runner(mio.reads(_file("rod.phi", "{expr: 30*sin(t), unit: deg}")))
    ref = runner.plans["turn"].spec.plots[0].reference
    t = np.linspace(0.0, 1.0, 5)
    np.testing.assert_allclose(_reference(runner, ref, t), math.pi / 6 * np.sin(t), rtol=1e-14)
