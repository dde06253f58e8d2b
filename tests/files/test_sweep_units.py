"""A sweep's values of a file parameter go through the units rule of the parameter
(docs/model-files.md, "Units of numbers, laws and parameters"): for a parameter with a unit, a
value with a unit is converted to the model's units and a number without one is in the model's
units of the parameter's dimension; a unit of another dimension, and any unit for a parameter
written without one (a plain number), is refused at the value's line.

The truths: the single runs of the file with the parameter written in (``L: 100 mm``), and
the closed form of the motor torque of a rod turned about its end, ``m L**2 / 3`` times the
angular acceleration (1 rad/s**2), in kg*mm**2/s**2."""

from __future__ import annotations

import numpy as np
import pytest

import mixdyn.io as mio
from mixdyn.runs import Runner, execute

# A uniform rod of length L in a file in mm, turned about its end O with phi = t**2 / 2.
MODEL = """\
mixdyn: 1
name: rod-mm
units: {length: mm, mass: kg, time: s}
gravity: [0, 0]
parameters:
  L: 300 mm
  m: 1 kg
  k: 2
bodies:
  - {name: rod, mass: m, inertia: m*L**2/12, q0: [L/2, 0, 0],
     points: {O: [-L/2, 0], tip: [L/2, 0]}}
joints:
  - {type: revolute, name: O, point_i: ground, point_j: rod.O}
drivers:
  - {type: coordinate, name: motor, coordinate: rod.phi, law: {polynomial: [0, 0, 0.5]}}
runs:
  - name: turn
    kind: inverse
    time: {span: [0, 1], n: 3}
  - name: kin
    kind: kinematic
    time: {span: [0, 1], n: 3}
"""

SWEEP = """\
  - name: sweep
    kind: sweep
    run: {run}
    vary:
      {name}: {spec}
    summaries:
      - {{name: {summary}}}
      - {{name: x, column: rod.x, reduce: first}}
"""

#: The first summary of a sweep of each run.
SUMMARY = {
    "turn": "torque, column: motor, reduce: first",
    "kin": "a, column: rod.alpha, reduce: first",
}


def _sweep(values: str, name: str = "L", head: str = "", run: str = "kin") -> str:
    """The file with a sweep of run ``run`` over ``values`` of ``name`` (a list, or a
    mapping: a span)."""
    spec = values if values.startswith("{") else f"{{values: {values}}}"
    sweep = SWEEP.format(name=name, spec=spec, run=run, summary=SUMMARY[run])
    return head + MODEL + sweep


def test_values_with_units_are_read_in_model_units():
    """``[0.1 m, 0.2 m]``, ``[10 cm, 20 cm]``, ``[100 mm, 200 mm]`` and ``[100, 200]`` (model
    units of the parameter's dimension) are 100 and 200 in a file in mm (by hand)."""
    for values in ("[0.1 m, 0.2 m]", "[10 cm, 20 cm]", "[100 mm, 200 mm]", "[100, 200]"):
        plan = Runner(mio.reads(_sweep(values))).plans["sweep"]
        np.testing.assert_allclose(plan.values["L"], [100.0, 200.0], rtol=1e-15)
        assert plan.value_units == {"L": "mm"}


@pytest.fixture(scope="module")
def swept():
    """The kinematic run swept over L: [0.1 m, 0.2 m] (a program compiled in about a
    second)."""
    return execute(mio.reads(_sweep("[0.1 m, 0.2 m]")), ["sweep"])["sweep"]


def test_members_are_the_motion_of_their_length(swept):
    """The rod's centre starts at L/2 = 50 and 100 mm, its angular acceleration is
    1 rad/s**2 (phi = t**2/2) whatever L."""
    assert not swept.sweep.errors
    table = swept.members()
    np.testing.assert_allclose(table["x"], [50.0, 100.0], rtol=1e-12)
    np.testing.assert_allclose(table["a"], [1.0, 1.0], rtol=1e-12)


@pytest.mark.slow  # long: run by CI's slow set (an inverse run's program compiled, ~5 s)
def test_values_with_units_equal_the_single_runs_and_the_closed_form():
    """``L: {values: [0.1 m, 0.2 m]}`` in a file in mm of the inverse run: each member equal
    to the file run with ``L: 100 mm`` / ``L: 200 mm`` written in and to the closed-form
    torque ``m L**2 / 3`` (times 1 rad/s**2)."""
    swept = execute(mio.reads(_sweep("[0.1 m, 0.2 m]", run="turn")), ["sweep"])["sweep"]
    assert not swept.sweep.errors
    table = swept.members()
    for i, length in enumerate((100.0, 200.0)):
        single = execute(mio.reads(MODEL.replace("L: 300 mm", f"L: {length:g} mm")))["turn"]
        member = swept.sweep[i]
        np.testing.assert_allclose(member["motor"], single["motor"], rtol=1e-12)
        assert table["torque"][i] == pytest.approx(1.0 * length**2 / 3, rel=1e-12)
        assert table["x"][i] == pytest.approx(length / 2, rel=1e-12)


@pytest.mark.parametrize(
    ("name", "values", "problem"),
    [
        ("L", "[0.1 kg, 0.2 kg]", "'kg' is a unit of mass, expected a length"),
        ("L", "{span: [1 s, 2 s], n: 2}", "expected a length"),
        ("k", "[1 m, 2 m]", r"parameter 'k' \(line 8\) is written without a unit"),
        ("k", "[30 deg]", "a plain number"),
    ],
)
def test_values_of_another_unit_are_refused_at_their_line(name, values, problem):
    text = _sweep(values, name)
    with pytest.raises(mio.FileError, match=problem) as err:
        Runner(mio.reads(text))
    line = next(k for k, x in enumerate(text.splitlines(), 1) if x.startswith(f"      {name}:"))
    assert err.value.line == line


def test_a_plain_parameters_values_are_plain_numbers():
    plan = Runner(mio.reads(_sweep("[1, 2.5]", "k"))).plans["sweep"]
    np.testing.assert_array_equal(plan.values["k"], [1.0, 2.5])


def test_strict_units_refuses_values_without_a_unit():
    """Under ``strict_units`` (the driver's coefficient given its unit), ``[0.1 m, 0.2 m]``
    is read as without it, and ``[100, 200]`` is refused at the sweep's line."""
    strict = "strict_units: true\n"
    text = _sweep("[0.1 m, 0.2 m]", head=strict).replace("0, 0, 0.5]", "0, 0, 0.5 rad/s**2]")
    text = text.replace("span: [0, 1]", "span: [0, 1 s]")
    plan = Runner(mio.reads(text)).plans["sweep"]
    np.testing.assert_array_equal(plan.values["L"], [100.0, 200.0])
    bare = text.replace("[0.1 m, 0.2 m]", "[100, 200]")
    with pytest.raises(mio.FileError, match="has no unit") as err:
        Runner(mio.reads(bare))
    assert err.value.line == bare.splitlines().index("      L: {values: [100, 200]}") + 1


def test_members_csv_names_its_units_and_reads_back(swept, tmp_path):
    """``members.csv`` has ``name [unit]`` headers as ``results.csv`` (the varied length in
    the model's mm, the summaries in rad/s² and mm, the failure time in s; the member index,
    status and error without), and ``read_table`` gives back the member table and its
    units."""
    from mixdyn.io.results import MEMBERS_CSV, write_sweep

    write_sweep(swept, tmp_path)
    head = (tmp_path / MEMBERS_CSV).read_text(encoding="utf-8").partition("\n")[0]
    assert head.split(",") == [
        "member",
        "L [mm]",
        "status",
        "error",
        "t_error [s]",
        "a [rad/s²]",
        "x [mm]",
    ]
    back = mio.read_table(tmp_path / MEMBERS_CSV)
    members = swept.members()
    assert list(back.columns) == list(members.columns)
    assert back.attrs["units"] == {"L": "mm", "t_error": "s", "a": "rad/s²", "x": "mm"}
    for c in ("member", "L", "a", "x"):
        np.testing.assert_array_equal(back[c].to_numpy(), members[c].to_numpy())
    assert list(back["status"]) == ["ok", "ok"]
