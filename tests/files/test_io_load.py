"""Model files: the examples build the models the API builds, load -> dump -> load is the
identity, a Python model survives the trip to a file, and the schema exports."""

import json
import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import mixdyn as md
import mixdyn.io as mio
from fixtures import EXAMPLES, four_bar, paper_mechanism, slider_crank
from mixdyn.runs import Runner

FILES = sorted(EXAMPLES.glob("*.yaml"))
#: The examples that describe a mechanism (a file of synthesis runs alone has none).
MODEL_FILES = [f for f in FILES if mio.read(f).bodies]


def test_the_four_examples_exist():
    names = {f.name for f in FILES}
    assert {"antonya.yaml", "slider_crank.yaml", "four_bar.yaml", "pendulum.yaml"} <= names


def _equal(a, b) -> bool:
    return bool(eqx.tree_equal(a, b))


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_load_dump_load_is_the_identity(path, tmp_path):
    spec = mio.read(path)
    out = tmp_path / "again.yaml"
    mio.dump(spec, out)
    again = mio.read(out)
    assert again == spec
    if spec.bodies:
        assert _equal(mio.build(again), mio.build(spec))
    # and once more: the normal form is a fixed point
    assert mio.dumps(again) == mio.dumps(spec)


@pytest.mark.parametrize("path", MODEL_FILES, ids=lambda p: p.stem)
def test_model_to_file_to_model(path):
    """A model (not its description) written out and read back is the same model."""
    model = mio.load(path)
    text = mio.dumps(model)
    assert _equal(mio.build(mio.reads(text)), model)


def test_antonya_is_the_papers_mechanism():
    model = mio.load(EXAMPLES / "antonya.yaml")
    ref = paper_mechanism()
    assert model.units == md.UnitSystem("mm", "kg", "s")
    assert _equal(model.bodies, ref.bodies)
    assert _equal(model.joints, ref.joints)
    assert _equal(model.ground, ref.ground)
    torques = {f.name: f for f in model.forces}
    assert float(torques["M2"].law(0.3)) == 500.0
    assert float(torques["M3"].law(0.3)) == -500.0
    f1 = torques["F1"]
    assert f1.along == (1.0, 0.0) and f1.point == "slider"
    for t in (0.0, 0.5, 1.3):
        assert float(f1.law(t)) == pytest.approx(10 * math.sin(math.pi * t / 2), abs=1e-14)
    spec = mio.read(EXAMPLES / "antonya.yaml")
    mixed = spec.run("mixed")
    assert mixed.kind == "mixed" and mixed.unknown == ["F1"]
    assert mixed.prescribed[0].from_run == "forward"
    assert mixed.solver == "partition" and mixed.independent == ["coupler.phi"]


def test_slider_crank_file_matches_fixture():
    model = mio.load(EXAMPLES / "slider_crank.yaml")
    ref = slider_crank()
    assert _equal(model.bodies, ref.bodies)
    assert _equal(model.joints, ref.joints)


@pytest.mark.parametrize(
    "model",
    [
        slider_crank(),
        four_bar(),
        paper_mechanism(
            forces=[
                md.Torque("M2", "crank", law=500.0),
                md.PointForce("F1", "slider", along=(1, 0), law=md.Harmonic(10, math.pi / 2)),
                md.SpringDamper("k", "ground.A", "slider.D", 2.0, 0.1, 60.0),
                md.RotarySpringDamper(
                    "r", "crank", "coupler", 1.0, 0.5, 0.1, actuator=md.Ramp(0, 1)
                ),
            ],
            drivers=[
                md.CoordinateDriver(
                    "s", "slider", "x", law=md.Spline([0, 1, 2, 3], [80, 81, 83, 80])
                ),
                md.RelativeAngleDriver("rel", "crank", "coupler", law=mio.ExpressionLaw("0.1*t")),
            ],
        ),
    ],
    ids=["slider_crank", "four_bar", "paper"],
)
def test_python_models_round_trip(model):
    again = mio.build(mio.reads(mio.dumps(model)))
    assert _equal(again, model)


def test_a_python_function_cannot_be_written():
    model = slider_crank(drivers=[md.CoordinateDriver("m", "crank", "phi", law=lambda t: 2 * t)])
    with pytest.raises(md.ModelError, match="cannot be written"):
        mio.dumps(model)


def test_state_dependent_force_from_a_file():
    text = """
units: {length: m, mass: kg, time: s}
parameters: {c: 0.5 N*m*s}
bodies:
  - {name: wheel, mass: 1, inertia: 2, points: {O: [0, 0]}}
joints:
  - {type: revolute, name: O, point_i: ground, point_j: wheel.O}
forces:
  - {type: torque, name: drag, body: wheel, law: -c*wheel.omega}
"""
    model = mio.build(mio.reads(text))
    law = model.forces[0].law
    assert isinstance(law, md.StateFunction)
    assert float(law(jnp.zeros(3), jnp.array([0, 0, 4.0]), 0.0)) == pytest.approx(-2.0)
    assert _equal(mio.build(mio.reads(mio.dumps(model))), model)


def test_units_in_a_file():
    text = """
units: {length: mm, mass: kg, time: s}
gravity: [0, -9.81 m/s^2]
bodies:
  - {name: b, mass: 20 g, inertia: 2e-5 kg*m^2, q0: [1 cm, 0, 90 deg], points: {P: [1 in, 0]}}
joints:
  - {type: revolute, name: J, point_i: ground, point_j: b.P}
drivers:
  - {type: coordinate, name: d, coordinate: b.phi, law: {expr: 90*t, unit: deg}}
"""
    model = mio.build(mio.reads(text))
    b = model.bodies[0]
    assert float(b.mass) == pytest.approx(0.02)
    assert float(b.inertia) == pytest.approx(20.0)
    np.testing.assert_allclose(np.asarray(b.q0), [10.0, 0.0, math.pi / 2])
    np.testing.assert_allclose(np.asarray(b.points["P"]), [25.4, 0.0])
    np.testing.assert_allclose(np.asarray(model.gravity), [0.0, -9810.0])
    assert float(model.drivers[0].law(1.0)) == pytest.approx(math.pi / 2)


def test_law_forms():
    text = """
units: {length: m, mass: kg, time: s}
bodies: [{name: b}]
drivers:
  - {type: coordinate, name: a, coordinate: b.x, law: 2}
  - {type: coordinate, name: c, coordinate: b.y, law: {polynomial: [1, 2, 3], unit: mm}}
  - {type: coordinate, name: d, coordinate: b.phi, law: {harmonic: {amplitude: 10 deg, omega: 2}}}
  - {type: distance, name: e, point_i: ground, point_j: b, law: {ramp: {start: 1 cm, rate: 2 mm/s}}}
  - type: point
    name: f
    point: b
    coordinate: x
    law: {hermite: {t: [0, 1], y: [0, 1], yd: [0, 0], ydd: [0, 0]}}
  - type: relative_angle
    name: g
    body_i: ground
    body_j: b
    law: {spline: {t: [0, 1, 2], y: [0, 1, 0]}}
"""
    d = {x.name: x.law for x in mio.build(mio.reads(text)).drivers}
    assert float(d["a"](5.0)) == 2.0
    assert float(d["c"](2.0)) == pytest.approx((1 + 4 + 12) * 1e-3)
    assert float(d["d"](math.pi / 4)) == pytest.approx(math.radians(10))
    assert float(d["e"](1.0)) == pytest.approx(0.012)
    assert float(d["f"](0.5)) == pytest.approx(0.5)
    assert float(d["g"](1.0)) == pytest.approx(1.0)


def test_yaml_bomb_is_refused_quickly():
    bomb = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n'
    for k in "bcdefghi":
        prev = chr(ord(k) - 1)
        bomb += f"{k}: &{k} [" + ",".join([f"*{prev}"] * 9) + "]\n"
    with pytest.raises(mio.FileError, match="anchor") as info:
        mio.reads(bomb + "bodies: [{name: b}]\n", "bomb.yaml")
    assert info.value.line == 1
    assert str(info.value).startswith("bomb.yaml:1: ")


def test_error_carries_file_line_and_element():
    text = "bodies:\n  - name: crank\n    mass: 1\n  - name: rod\n    mass: 3 mm\n"
    with pytest.raises(mio.FileError) as info:
        mio.build(mio.reads(text, "m.yaml"))
    e = info.value
    assert (e.file, e.line) == ("m.yaml", 5)
    assert e.element == "body 'rod', mass"
    assert str(e).startswith("m.yaml:5: body 'rod', mass: ")
    assert "expected a mass" in str(e)


def test_json_schema():
    schema = mio.json_schema()
    text = json.dumps(schema)
    assert schema["$schema"].startswith("https://json-schema.org/")
    for key in ("bodies", "joints", "drivers", "forces", "runs", "units", "parameters"):
        assert key in schema["properties"]
    for kind in ("revolute", "translational", "point_force", "mixed", "kinematic"):
        assert f'"{kind}"' in text


# ------------------------------------------------------------------ options: a check turned off
def _pendulum_run(options: str) -> str:
    text = (EXAMPLES / "pendulum.yaml").read_text(encoding="utf-8")
    head = text[: text.index("runs:")]
    return head + (
        "runs:\n"
        "  - name: loose\n"
        "    kind: forward\n"
        "    time: {span: [0, 1], n: 11}\n"
        "    rtol: 1.0e-4\n"
        "    atol: 1.0e-6\n"
        f"    options: {options}\n"
    )


def test_energy_tol_null_turns_the_energy_check_off():
    """``options: {energy_tol: null}`` (docs/model-files.md) is accepted and turns the energy
    check off: the same run that a tolerance below its measured balance error refuses
    (a named numerical failure) then ends with that balance error recorded."""
    off = Runner(mio.reads(_pendulum_run("{energy_tol: null}"), "pendulum.yaml")).execute()
    balance = off["loose"].stats["energy_balance_error"]
    assert balance > 0
    tight = mio.reads(_pendulum_run(f"{{energy_tol: {balance / 10:.3e}}}"), "pendulum.yaml")
    with pytest.raises(md.NumericalError, match="energy"):
        Runner(tight).execute()
    with pytest.raises(mio.FileError, match=r"options\.first_step"):  # not for other options
        Runner(mio.reads(_pendulum_run("{first_step: null}"), "p.yaml"))
