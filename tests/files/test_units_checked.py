"""Units are never silently assumed (docs/model-files.md, "Units of laws and parameters"): a
law's dimension is checked against its field, a parameter without a unit that makes it wrong
is named with its line and the fix, ``strict_units`` refuses numbers without units,
``check --explain`` prints every number as understood, a unit of the wrong dimension gets
its close match, a law written with a unit after it is told the spelling that gives a law a
unit, and an angle without a unit that looks like degrees is warned of.

The truths: dimensions worked out by hand from the definitions of the units (1 N*m = 1e6
kg*mm**2/s**2; an angular velocity is 1/s), the file's own text for the lines named, and the
suggested fixes applied to the file (the fixed file builds and gives the intended value)."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from typer.testing import CliRunner

import mixdyn.io as mio
from mixdyn.cli import app
from mixdyn.io import dimensions as d
from mixdyn.runs import Runner
from mixdyn.units import QuantityError, UnitSystem, factor

# A slider-crank in mm, kg, s driven by a motor whose torque falls linearly with its speed.
MOTOR = """\
mixdyn: 1
name: slider-crank-motor
units: {{length: mm, mass: kg, time: s}}
{strict}parameters:
  T0: {T0}
  n0: {n0}
ground: {{points: {{O: [0, 0]}}}}
bodies:
  - {{name: crank, mass: {mass}, inertia: 833.3 kg*mm^2, q0: [50 mm, 0 mm, {phi}],
      points: {{O: [-50 mm, 0 mm], A: [50 mm, 0 mm]}}}}
  - {{name: rod, mass: 1 kg, inertia: 7500 kg*mm^2, q0: [250 mm, 0 mm, 0 rad],
      points: {{A: [-150 mm, 0 mm], B: [150 mm, 0 mm]}}}}
  - {{name: slider, mass: 2 kg, inertia: 1000 kg*mm^2, q0: [400 mm, 0 mm, 0 rad]}}
joints:
  - {{type: revolute, name: O, point_i: ground.O, point_j: crank.O}}
  - {{type: revolute, name: A, point_i: crank.A, point_j: rod.A}}
  - {{type: revolute, name: B, point_i: rod.B, point_j: slider}}
  - {{type: translational, name: slide, point_i: ground.O, point_j: slider, axis: [1, 0]}}
forces:
  - {{type: torque, name: motor, body: crank, law: {law}}}
runs:
  - {{name: spin, kind: forward, time: {{span: [0 s, 0.1 s], n: 11}}}}
"""


def motor(
    T0="1.5",
    n0="300 rad/s",
    law="T0*(1 - crank.omega/n0)",
    mass="1 kg",
    phi="0 rad",
    strict="",
) -> str:
    return MOTOR.format(T0=T0, n0=n0, law=law, mass=mass, phi=phi, strict=strict)


def line_of(text: str, start: str) -> int:
    """The 1-based line of ``text`` that starts (after its indent) with ``start``."""
    return next(i for i, s in enumerate(text.splitlines(), 1) if s.strip().startswith(start))


def motor_torque(model, omega: float) -> float:
    """The motor's torque [model units] with the crank turning at ``omega`` [rad/s]."""
    law = model.forces[0].law
    q, qd = np.zeros(9), np.zeros(9)
    qd[2] = omega
    return float(law(q, qd, 0.0))


# ------------------------------------------------------------------ 1. dimensions of laws
def test_bare_stall_torque_is_refused_with_its_line_and_the_fix():
    """The issue's file: ``T0: 1.5`` (meant as N*m) in a law with a speed in rad/s is a plain
    number, the law dimensionless; the error names T0, its line and ``T0: 1.5 N*m``."""
    text = motor()
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(text, "motor.yaml"))
    e = info.value
    assert e.line == line_of(text, "- {type: torque")
    assert "'T0'" in e.problem and f"line {line_of(text, 'T0:')}" in e.problem
    assert "dimensionless" in e.problem and "torque" in e.problem
    assert "`T0: 1.5 N*m`" in e.hint


def test_the_command_exits_2_on_the_issue_file(tmp_path):
    path = tmp_path / "motor.yaml"
    path.write_text(motor(), encoding="utf-8")
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 2, res.output
    assert "T0: 1.5 N*m" in res.output and "ok" not in res.output.split()


def test_the_fix_gives_the_intended_torque():
    """With ``T0: 1.5 N*m`` the file builds, and the motor gives 1.5 N*m = 1.5e6
    kg*mm**2/s**2 at rest and half of it at half its no-load speed."""
    model = mio.build(mio.reads(motor(T0="1.5 N*m"), "motor.yaml"))
    assert motor_torque(model, 0.0) == pytest.approx(1.5e6, rel=1e-12)
    assert motor_torque(model, 150.0) == pytest.approx(0.75e6, rel=1e-12)


def test_a_bare_speed_is_named_with_its_unit():
    """``n0: 300`` makes ``1 - crank.omega/n0`` add a number and a 1/time: n0 is named, as
    an angular velocity."""
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(motor(T0="1.5 N*m", n0="300"), "motor.yaml"))
    assert "'n0'" in info.value.problem
    assert "`n0: 300 rad/s`" in info.value.hint


def test_a_law_with_its_unit_is_a_plain_number_inside():
    """``{expr: ..., unit: N*m}``: the expression's value is in N*m, its parameters plain
    numbers (T0: 1.5 is then 1.5 N*m); a T0 with a unit of its own as well is refused (it
    would be converted twice)."""
    law = "{expr: T0*(1 - crank.omega/n0), unit: N*m}"
    model = mio.build(mio.reads(motor(law=law), "motor.yaml"))
    assert motor_torque(model, 0.0) == pytest.approx(1.5e6, rel=1e-12)
    with pytest.raises(mio.FileError, match=r"'T0'|torque"):
        mio.build(mio.reads(motor(T0="1.5 N*m", law=law), "motor.yaml"))


def test_a_law_without_any_unit_is_in_model_units():
    """A law of numbers and parameters without units (``T0*(1 - t)``, no state, no unit) is
    in the model's units, as a number without a unit is: not refused."""
    model = mio.build(mio.reads(motor(law="T0*(1 - t/10)", n0="300"), "motor.yaml"))
    assert float(model.forces[0].law(0.0)) == 1.5


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("L*sin(w*t)", (1, 0, 0)),
        ("sqrt(L**2 + L*L)", (1, 0, 0)),
        ("L**0.5", (Fraction(1, 2), 0, 0)),
        ("F*L/w", (2, 1, -1)),
        ("where(t > T, F, 2*F)", (1, 1, -2)),
        ("step(t, 0, 0, T, F)", (1, 1, -2)),
        ("atan2(L, L) + 3", (0, 0, 0)),
        ("2*pi*t", None),  # numbers take the units the place needs
    ],
)
def test_dimensions_propagate(source, expected):
    """Dimensions worked out by hand: L a length, F a force, w 1/time, T a time."""
    dims = {
        "L": d.dim((1, 0, 0)),
        "F": d.dim((1, 1, -2)),
        "w": d.dim((0, 0, -1)),
        "T": d.dim((0, 0, 1)),
    }
    got = d.infer(source, dims, values={"L": 1.0, "F": 1.0, "w": 1.0, "T": 1.0})
    assert got == (None if expected is None else d.dim(expected))


@pytest.mark.parametrize(
    ("source", "fault"),
    [
        ("sin(t)", "sin() needs a dimensionless argument"),
        ("L + F", "cannot add"),
        ("where(t > T, F, L)", "where() needs both branches alike"),
        ("L**t", "exponent must be dimensionless"),
        ("L**(t/T)", "exponent must be a constant"),
        ("L**0.3183", "whole number or a simple fraction"),
        ("exp(w)", "exp() needs a dimensionless argument"),
        ("t < L", "cannot compare"),
    ],
)
def test_dimension_faults(source, fault):
    dims = {n: d.dim(e) for n, e in {"L": (1, 0, 0), "F": (1, 1, -2), "w": (0, 0, -1),
                                      "T": (0, 0, 1)}.items()}  # fmt: skip
    with pytest.raises(d.MismatchError, match=fault.replace("(", r"\(").replace(")", r"\)")):
        d.infer(source, dims, values={"L": 1.0, "F": 1.0, "w": 1.0, "T": 1.0})


# ------------------------------------------------------------------ 2. strict_units
def test_strict_units_refuses_a_bare_number_with_its_place_and_fix():
    text = motor(T0="1.5 N*m", mass="1", strict="strict_units: true\n")
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(text, "motor.yaml"))
    e = info.value
    assert e.line == line_of(text, "- {name: crank") and "mass" in e.element
    assert "strict_units" in e.problem and "`1 kg`" in e.hint


def test_strict_units_accepts_a_file_with_every_unit():
    """Every number with a unit (0 needs none) builds under strict_units, to the same model
    as without it."""
    text = motor(T0="1.5 N*m", strict="strict_units: true\n")
    model = mio.build(mio.reads(text, "motor.yaml"))
    loose = mio.build(mio.reads(motor(T0="1.5 N*m"), "motor.yaml"))
    assert motor_torque(model, 10.0) == motor_torque(loose, 10.0)
    assert model.bodies[0].mass == loose.bodies[0].mass == 1.0


def test_strict_units_checks_every_law():
    """Under strict_units a law of numbers only needs its unit, and a parameter without one
    is a plain number everywhere."""
    strict = "strict_units: true\n"
    with pytest.raises(mio.FileError, match="carry no unit"):
        mio.build(mio.reads(motor(T0="1.5 N*m", law="10*sin(2*t)", strict=strict), "m.yaml"))
    law = "{expr: 10*sin(2*t), unit: N*m}"
    model = mio.build(mio.reads(motor(T0="1.5 N*m", law=law, strict=strict), "m"))
    assert float(model.forces[0].law(math.pi / 4)) == pytest.approx(1e7, rel=1e-12)
    with pytest.raises(mio.FileError, match=r"sin\(\) needs a dimensionless argument"):
        mio.build(mio.reads(motor(T0="1.5 N*m", law="T0*sin(t)"), "m.yaml"))
    with pytest.raises(mio.FileError, match="'T0'"):
        mio.build(mio.reads(motor(T0="1.5", law="T0*(1 + t)", strict=strict), "m.yaml"))


# ------------------------------------------------------------------ 3. check --explain
def test_explain_prints_every_number_with_its_units():
    """``check --explain`` on examples/slider_crank.yaml (m, kg, s): the rod length 300 mm
    is 0.3 m, the crank mass 1 kg, the rod's bare mass 1 is in model units (kg)."""
    from pathlib import Path

    path = Path(__file__).parents[2] / "examples" / "slider_crank.yaml"
    res = CliRunner().invoke(app, ["check", "--explain", str(path)])
    assert res.exit_code == 0, res.output
    out = res.output.splitlines()
    assert any(s.startswith("parameter 'l'") and "300 mm -> 0.3 m" in s for s in out)
    assert any(s.startswith("body 'crank', mass") and "1 kg -> 1 kg" in s for s in out)
    rod = next(s for s in out if s.startswith("body 'rod', mass"))
    assert "-> 1 kg (no unit: model units)" in rod
    motor_law = next(s for s in out if s.startswith("driver 'motor', law"))
    assert "omega*t" in motor_law and "rad" in motor_law


def test_explain_gives_si_values_of_a_mm_file(tmp_path):
    """In mm, kg, s: 1.5 N*m is 1.5e6 mN*mm (model units) and 1.5 N*m in SI; 833.3
    kg*mm**2 is 8.333e-4 kg*m**2."""
    path = tmp_path / "motor.yaml"
    path.write_text(motor(T0="1.5 N*m"), encoding="utf-8")
    res = CliRunner().invoke(app, ["check", "--explain", str(path)])
    assert res.exit_code == 0, res.output
    t0 = next(s for s in res.output.splitlines() if s.startswith("parameter 'T0'"))
    assert "-> 1.5e+06 mN*mm = 1.5 N*m" in t0
    inertia = next(s for s in res.output.splitlines() if s.startswith("body 'crank', inertia"))
    assert "= 0.0008333 kg*m**2" in inertia


# ------------------------------------------------------------------ 4. close matches
@pytest.mark.parametrize(
    ("written", "kind", "meant"),
    [
        ("Nm", "torque", "N*m"),
        ("Nmm", "torque", "N*mm"),
        ("kgm2", "inertia", "kg*m**2"),
        ("kg m2", "inertia", "kg*m**2"),
        ("RPM", "angular_velocity", "rpm"),
    ],
)
def test_close_unit_of_the_right_dimension_is_suggested(written, kind, meant):
    with pytest.raises(QuantityError) as info:
        factor(written, kind, UnitSystem("mm", "kg", "s"))
    assert f"'{meant}'" in info.value.hint
    # the suggestion is a unit of that kind
    assert factor(meant, kind, UnitSystem("mm", "kg", "s")) > 0


def test_close_unit_in_a_file_and_in_a_parameter():
    text = motor(T0="1.5 N*m").replace("inertia: 833.3 kg*mm^2", "inertia: 833.3 kgmm2")
    with pytest.raises(mio.FileError, match=r"did you mean 'kg\*mm\*\*2'"):
        mio.build(mio.reads(text, "m.yaml"))
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(motor(T0="1.5 Nm"), "m.yaml"))
    assert "'T0'" in info.value.problem and "`T0: 1.5 N*m`" in info.value.hint


# ------------------------------------------------------------------ 5. a law with a unit
def test_a_law_ending_in_a_unit_is_told_the_spelling_and_the_fix_builds():
    text = motor(law="T0*(1 - crank.omega/n0) N*m")
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(text, "m.yaml"))
    e = info.value
    assert "ends in a unit (N*m)" in e.problem and "attribute" not in e.problem
    assert "{expr: T0*(1 - crank.omega/n0), unit: N*m}" in e.hint
    fixed = motor(law=e.hint[e.hint.index("{") :])
    assert motor_torque(mio.build(mio.reads(fixed, "m.yaml")), 0.0) == pytest.approx(1.5e6)


# ------------------------------------------------------------------ 6. degrees without unit
def test_a_bare_angle_above_two_pi_is_warned_of(tmp_path):
    text = motor(T0="1.5 N*m", phi="90")
    runner = Runner(mio.reads(text, "m.yaml"))
    (warning,) = runner.b.readings.warnings
    assert "body 'crank', q0[2]" in warning and "`90 deg`" in warning
    assert runner.model.bodies[0].q0[2] == 90.0  # read as written: radians
    path = tmp_path / "m.yaml"
    path.write_text(text, encoding="utf-8")
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 0 and "warning" in res.output and "90 deg" in res.output
    for phi in ("6", "90 deg", "-6.2"):
        assert not Runner(mio.reads(motor(T0="1.5 N*m", phi=phi), "m")).b.readings.warnings


def test_run_prints_the_warning_before_anything_else(tmp_path):
    """``mixdyn run`` writes the warning on stderr as it reads the file (here before it
    refuses an output folder that is a file, so nothing is computed)."""
    path = tmp_path / "m.yaml"
    path.write_text(motor(T0="1.5 N*m", phi="90"), encoding="utf-8")
    blocked = tmp_path / "out"
    blocked.write_text("a file", encoding="utf-8")
    res = CliRunner().invoke(app, ["run", str(path), "--out", str(blocked), "--no-figures"])
    assert res.exit_code == 2
    assert "warning" in res.stderr and "q0[2]" in res.stderr and "`90 deg`" in res.stderr


# ------------------------------------------------------------------ sweeps and dumps
def test_a_member_with_a_swept_number_keeps_its_parameters_units():
    """A sweep's member is the file with the varied parameter as a number in model units
    (runs/sweep.py); it keeps the unit's dimension of its file: T0 = 2e6 (model units of a
    torque, 2 N*m) builds and gives 2 N*m at rest."""
    spec = mio.reads(motor(T0="1.5 N*m"), "motor.yaml")
    member = spec.model_copy(update={"parameters": {**spec.parameters, "T0": 2e6}})
    model = mio.build(member)
    assert motor_torque(model, 0.0) == pytest.approx(2e6, rel=1e-12)


def test_a_written_model_gives_its_parameters_the_units_its_laws_need():
    """A model written back to a file (numbers in model units) gives a parameter that a law
    needs with a dimension the model's unit of it, and reads back to the same torque."""
    from mixdyn.io.dump import describe

    model = mio.build(mio.reads(motor(T0="1.5 N*m"), "motor.yaml"))
    spec = describe(model)
    assert spec.parameters["T0"] == "1500000.0 mm**2*kg/s**2"
    assert spec.parameters["n0"] == "300.0 1/s"
    again = mio.build(mio.reads(mio.dumps(spec), "again.yaml"))
    for omega in (0.0, 100.0):
        assert motor_torque(again, omega) == motor_torque(model, omega)


def test_a_law_ending_in_a_unit_whose_parameters_have_units_is_told_to_drop_it():
    """With ``T0: 1.5 N*m`` the expression is a torque already: the fix is the law alone."""
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(motor(T0="1.5 N*m", law="T0*(1 - crank.omega/n0) N*m"), "m"))
    assert "write T0*(1 - crank.omega/n0) (its parameters' units" in info.value.hint


def test_strict_units_refuses_a_constant_expression_without_its_unit():
    """``pi/6`` for an angle is a number without a unit too; ``pi/6 rad`` is not, and the
    law ``50`` for a torque is refused where ``50 N*m`` is read as 5e7 kg*mm**2/s**2."""
    strict = "strict_units: true\n"
    with pytest.raises(mio.FileError, match="strict_units"):
        mio.build(mio.reads(motor(T0="1.5 N*m", phi="pi/6", strict=strict), "m.yaml"))
    model = mio.build(mio.reads(motor(T0="1.5 N*m", phi="pi/6 rad", strict=strict), "m"))
    assert model.bodies[0].q0[2] == pytest.approx(math.pi / 6, rel=1e-15)
    with pytest.raises(mio.FileError, match="strict_units"):
        mio.build(mio.reads(motor(T0="1.5 N*m", law="50", strict=strict), "m.yaml"))
    model = mio.build(mio.reads(motor(T0="1.5 N*m", law="50 N*m", strict=strict), "m"))
    assert float(model.forces[0].law(0.0)) == pytest.approx(5e7, rel=1e-12)


def test_a_parameter_with_a_unit_before_another_unit_is_refused():
    """``L**2/12 kg*m**2`` with ``L: 300 mm`` in a file in mm would read L as 300 (mm) and
    convert the result as kg*m**2: 7500 kg*m**2 instead of 7500 kg*mm**2. Refused, naming L;
    ``m*L**2/12`` with ``m: 1 kg`` gives 7500 kg*mm**2."""
    text = motor(T0="1.5 N*m").replace("  n0:", "  L: 300 mm\n  m: 1 kg\n  n0:")
    twice = text.replace("inertia: 7500 kg*mm^2", "inertia: L**2/12 kg*m**2")
    with pytest.raises(mio.FileError, match=r"'L' \(line 6\) has a unit of its own"):
        mio.build(mio.reads(twice, "m.yaml"))
    once = text.replace("inertia: 7500 kg*mm^2", "inertia: m*L**2/12")
    assert mio.build(mio.reads(once, "m.yaml")).bodies[1].inertia == pytest.approx(7500.0)


PARAMETER_EXPRESSION = """\
mixdyn: 1
name: lengths
units: {{length: {length}, mass: kg, time: s}}
parameters:
  L: 1 m
  k: 2
  L2: {L2}
bodies:
  - {{name: rod, mass: 1 kg, inertia: 1 kg*m**2, q0: [L2, 0, 0]}}
"""


@pytest.mark.parametrize("length", ["m", "mm"])
def test_a_parameter_expression_with_a_unit_is_not_converted_twice(length):
    """``L2: 2*L mm`` with ``L: 1 m`` would read L as a number in model units and convert it
    again (in a file in m: 2 mm instead of 2 m): refused at L2's line, naming L, with the fix
    ``L2: 2*L``, which gives 2 m (by hand: 2 in m, 2000 in mm). With a plain parameter the
    unit after it is the expression's own: ``3*k mm`` with ``k: 2`` is 6 mm."""
    per_metre = {"m": 1.0, "mm": 1000.0}[length]
    for written in ("2*L mm", "2*L m", "(2*L) m"):
        text = PARAMETER_EXPRESSION.format(length=length, L2=written)
        with pytest.raises(mio.FileError, match=r"parameter 'L' \(line 5\) has a unit") as e:
            mio.build(mio.reads(text, "p.yaml"))
        assert e.value.line == 7 and "`L2: " in e.value.hint
    fixed = mio.build(mio.reads(PARAMETER_EXPRESSION.format(length=length, L2="2*L"), "p"))
    assert fixed.bodies[0].q0[0] == pytest.approx(2.0 * per_metre, rel=1e-15)
    plain = mio.build(mio.reads(PARAMETER_EXPRESSION.format(length=length, L2="3*k mm"), "p"))
    assert plain.bodies[0].q0[0] == pytest.approx(0.006 * per_metre, rel=1e-15)


def test_strict_units_takes_an_expression_whose_parameters_give_its_unit():
    """Under strict_units, ``inertia: m*L**2/12`` with ``m: 1 kg`` and ``L: 300 mm`` takes its
    unit from its parameters (7500 kg*mm**2 by hand in a file in mm); numbers alone
    (``inertia: 750*10``) still need a unit."""
    text = motor(T0="1.5 N*m", strict="strict_units: true\n").replace(
        "  n0:", "  L: 300 mm\n  m: 1 kg\n  n0:"
    )
    model = mio.build(mio.reads(text.replace("inertia: 7500 kg*mm^2", "inertia: m*L**2/12")))
    assert model.bodies[1].inertia == pytest.approx(7500.0, rel=1e-15)
    with pytest.raises(mio.FileError, match="strict_units"):
        mio.build(mio.reads(text.replace("inertia: 7500 kg*mm^2", "inertia: 750*10")))
