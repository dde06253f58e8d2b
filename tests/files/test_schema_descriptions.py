"""The model-file JSON Schema carries hover help: every property of every definition has a
description (issue 14), and adding them changed nothing else in the schema."""

import hashlib
import json

import pytest

import mixdyn.io as mio
from fixtures import EXAMPLES
from mixdyn.io.schema import ModelFile, json_schema
from mixdyn.model import ELEMENTS
from mixdyn.runs import Runner

#: The specs made from an element class's declaration (mixdyn.model.element): their keys are
#: the class's declared fields, checked against the class below, and they are left out of the
#: record and of the digest, so that a new declared element changes neither.
DECLARED = {
    f"{kind.cls.__name__}Spec": kind
    for group in ELEMENTS.values()
    for kind in group.values()
    if kind.fields()
}

EXAMPLES = sorted(EXAMPLES.glob("*.yaml"))

# The property names of every definition, recorded before the descriptions were added.
PROPERTIES = {
    "AnimationSpec": "file forces fps frames html plot plot_x trace",
    "AssemblySpec": "hold",
    "BodySpec": "inertia mass name points q0 vectors",
    "ConstantSpec": "constant",
    "ExpressionSpec": "expr unit",
    "ForwardRunSpec": "animation atol drivers dt hold initial kind linear_solver "
    "method name options outputs plots prescribed rtol time velocities",
    "GroundSpec": "points",
    "HarmonicArgs": "amplitude offset omega phase",
    "HarmonicSpec": "harmonic",
    "HermiteArgs": "t unit y yd ydd",
    "HermiteSpec": "hermite",
    "InverseRunSpec": "animation drivers hold initial kind linear_solver name "
    "options outputs plots prescribed time velocities",
    "KinematicRunSpec": "animation drivers hold initial kind linear_solver max_iter "
    "name outputs plots prescribed time tol velocities",
    "MixedRunSpec": "animation atol drivers dt hold independent initial kind linear_solver method "
    "name options outputs plots prescribed rtol solver time unknown velocities",
    "ModelFile": "assembly bodies description drivers forces gravity ground joints mixdyn name "
    "output_units parameters runs strict_units units",  # output_units: issue 14; strict: 31
    "PiecewiseArgs": "breaks coeffs",
    "PiecewiseSpec": "piecewise",
    "PlotSpec": "columns file reference title x ylabel",  # x: issue 14
    "PolynomialSpec": "polynomial unit",
    "PrescribedSpec": "continuity coordinate from_run law name",  # continuity: issue 31
    "RampArgs": "rate start",
    "RampSpec": "ramp",
    "ReferenceSpec": "expr label unit",
    "SplineArgs": "kind t unit y",
    # the sweep run kind (issue 15)
    "SummarySpec": "column name reduce",
    "SweepPlotSpec": "band by file title x y",
    "SweepRunSpec": "batch_size kind name outputs plots run samples sampling seed summaries vary",
    "VarySpec": "n span values",
    # the identify and optimize run kinds (issue 15)
    "DesignVariableSpec": "bounds start",
    "FitSpec": "bounds start",
    "IdentifyRunSpec": "data fit kind max_evaluations measured name run",
    "MeasuredSpec": "column data noise",
    "ObjectiveSpec": "column reduce",
    "OptimizeRunSpec": "kind max_iterations name objective run sense vary",
    # the statics run kind (issue 13)
    "StaticsRunSpec": "animation drivers hold initial kind linear_solver max_iter "
    "name outputs plots prescribed time tol velocities",
    "SplineSpec": "spline",
    # the synthesis run kind (issue 34)
    "SynthesisFunctionSpec": "expr free_start input output pairs points ratios spacing x",
    "SynthesisMassesSpec": "density payload slider",
    "SynthesisMotionSpec": "length poses",
    "SynthesisPivotSpec": "x y",
    "SynthesisRunSpec": "bounds function grashof harmonics keep kind linkage masses max_steps "
    "min_transmission motion name pivots points reaction reaction_weight seed sense "
    "shaking shaking_force_weight shaking_moment_weight shape speed starts timing timing_from "
    "torque torque_weight",
    "TimeSpec": "n span step values",
    "UnitsSpec": "length mass time",
}

# SHA-256 of ModelFile.model_json_schema() without its descriptions (canonical JSON), taken
# before the descriptions were added (pydantic 2.14): any change of a type, default, bound,
# required key or discriminator changes it. If a pydantic upgrade alone changes the form of
# the schema, check the difference and record the new value. Recorded again when the sweep
# run kind (SweepRunSpec, VarySpec, SummarySpec, SweepPlotSpec) was added, and the identify
# and optimize kinds, a plot's x column, the statics kind and output_units; and with the
# declared elements' specs left out (the same value with the spring-dampers written by hand);
# and when the joints, drivers and forces but the cam moved to declarations (the value of
# the schema before the move, with the same specs left out); and when the cam moved too (the
# value of the schema with the cam's hand-written spec, the cam's spec left out as well); and
# with the file's strict_units setting; and with output_units also a preset's name (issue 32);
# and with a prescribed motion's continuity (issue 31: the same value without it); and with
# the animation's plotted columns (issue 32); and with the column on the x axis of the
# player's plot (issue 32); and with the synthesis run kind and bodies optional in a file of
# synthesis runs alone (issue 34); and with a synthesis run's function generation (issue 34);
# and with a synthesis run's linkage and a slider's mass (issue 34); and with a synthesis
# run's motion generation (issue 34); and with a synthesis run's Grashof type and ground-pivot
# regions (issue 34); and with a synthesis run's six-bar linkages (issue 34); and with a
# synthesis run's shape-only error (shape, harmonics, sense; issue 34).
STRIPPED_SHA256 = "d4eac3a8c354db33318c16c11d45e40659bccabf86ea0169d2169055df61a5bf"


def _definitions(schema: dict) -> dict[str, dict]:
    return {"ModelFile": schema, **schema["$defs"]}


def _declared_ref(value) -> bool:
    refs = {f"#/$defs/{name}" for name in DECLARED}
    if isinstance(value, dict):
        return value.get("$ref") in refs
    return isinstance(value, str) and value in refs


def _strip(node):
    """The schema without its descriptions (a property called ``description`` stays) and
    without the declared elements' specs (:data:`DECLARED`) and the references to them."""
    if isinstance(node, dict):
        return {
            k: _strip(v)
            for k, v in node.items()
            if not (k == "description" and isinstance(v, str))
            and k not in DECLARED
            and not _declared_ref(v)
        }
    if isinstance(node, list):
        return [_strip(v) for v in node if not _declared_ref(v)]
    return node


def test_every_property_has_a_description():
    missing = [
        f"{name}.{prop}"
        for name, d in _definitions(ModelFile.model_json_schema()).items()
        for prop, sub in d.get("properties", {}).items()
        if not (isinstance(sub.get("description"), str) and sub["description"].strip())
    ]
    assert not missing, f"properties without a description: {missing}"


def test_every_definition_has_a_description():
    schema = ModelFile.model_json_schema()
    missing = [n for n, d in _definitions(schema).items() if not str(d.get("description", ""))]
    assert not missing


def test_descriptions_are_short_plain_text():
    for name, d in _definitions(ModelFile.model_json_schema()).items():
        for prop, sub in d.get("properties", {}).items():
            text = sub["description"]
            assert len(text) <= 300, f"{name}.{prop}: {len(text)} characters"
            assert "\t" not in text and not text.startswith(" "), f"{name}.{prop}"


def test_the_properties_are_the_recorded_ones():
    got = {
        n: " ".join(sorted(d.get("properties", {})))
        for n, d in _definitions(ModelFile.model_json_schema()).items()
        if n not in DECLARED
    }
    assert got == PROPERTIES


def _file_default(decl, default):
    """The default a file shows for a declared field: a quantity's ``file_default`` where
    given, else the class's (a tuple as a JSON list)."""
    shown = getattr(decl, "file_default", None)
    if shown is not None:
        return shown
    return list(default) if isinstance(default, tuple) else default


def test_a_declared_elements_keys_are_its_declared_fields():
    """A spec made from a declaration has ``type``, ``name`` and the class's declared fields,
    each described by its declaration (with the unit kinds of a quantity), its defaults the
    class's; it is in the schema under its section's union."""
    definitions = _definitions(ModelFile.model_json_schema())
    assert DECLARED and set(DECLARED) <= set(definitions)
    for name, kind in DECLARED.items():
        props = definitions[name]["properties"]
        assert set(props) == {"type", "name", *(f for f, _, _ in kind.fields())}
        assert props["type"]["const"] == kind.file_name
        for field, decl, default in kind.fields():
            assert props[field]["description"].startswith(decl.doc)
            if hasattr(decl, "kind"):
                words = " or ".join(k.replace("_", " ") for k in decl.kinds)
                assert props[field]["description"].endswith(f"[{words}]")
            shown = _file_default(decl, default)
            if shown is not None and not callable(shown) and "default" in props[field]:
                if isinstance(shown, str | bool):
                    assert props[field]["default"] == shown
                else:
                    assert props[field]["default"] == pytest.approx(shown)


def test_the_schema_without_descriptions_is_unchanged():
    stripped = _strip(ModelFile.model_json_schema())
    text = json.dumps(stripped, sort_keys=True, separators=(",", ":"))
    assert hashlib.sha256(text.encode()).hexdigest() == STRIPPED_SHA256


def test_json_schema_keeps_the_descriptions():
    schema = json_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert "rad" in schema["$defs"]["BodySpec"]["properties"]["q0"]["description"]
    assert schema["properties"]["units"]["description"]
    json.dumps(schema)  # serializable as written by ``mixdyn schema``


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_the_examples_still_load(path):
    spec = mio.read(path)
    assert isinstance(spec, ModelFile)
    if spec.bodies:
        assert mio.build(spec).bodies
    else:  # a file of synthesis runs alone: no mechanism, its runs checked
        runner = Runner(spec)
        assert runner.model is None and {p.spec.kind for p in runner.plans.values()} == {
            "synthesis"
        }


def test_a_file_names_every_linear_solver_the_api_names():
    import typing

    from mixdyn.io.schema import _RunSpec
    from mixdyn.linalg._choice import NAMES

    allowed = typing.get_args(_RunSpec.model_fields["linear_solver"].annotation)
    assert set(allowed) == set(NAMES)
