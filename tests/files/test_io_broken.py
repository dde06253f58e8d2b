"""Broken model files: each gives exit code 2 and one line naming the file, the line and the
element, with no traceback; a model file never executes code."""

import pathlib

import pytest
from typer.testing import CliRunner

from mixdyn.cli import app

BASE = """\
mixdyn: 1
name: slider-crank
units: {length: m, mass: kg, time: s}
parameters:
  w: 2 rad/s
bodies:
  - name: crank
    mass: 1
    inertia: 0.01
    q0: [0.05, 0, 0]
    points: {O: [-0.05, 0], A: [0.05, 0]}
  - name: rod
    mass: 1
    inertia: 0.01
    q0: [0.25, 0, 0]
    points: {A: [-0.15, 0], B: [0.15, 0]}
  - name: slider
    mass: 1
    inertia: 0.01
    q0: [0.4, 0, 0]
joints:
  - {type: revolute, name: O, point_i: ground, point_j: crank.O}
  - {type: revolute, name: A, point_i: crank.A, point_j: rod.A}
  - {type: revolute, name: B, point_i: rod.B, point_j: slider}
  - {type: translational, name: slide, point_i: ground, point_j: slider, axis: [1, 0]}
drivers:
  - {type: coordinate, name: motor, coordinate: crank.phi, law: w*t}
forces:
  - {type: point_force, name: gas, point: slider, along: [-1, 0], law: 50 N}
  - {type: torque, name: tq, body: crank, law: 0}
runs:
  - name: kin
    kind: kinematic
    time: {span: [0, 1], n: 11}
"""

MIXED = (
    BASE.replace(
        "drivers:\n  - {type: coordinate, name: motor, coordinate: crank.phi, law: w*t}\n",
        "",
    ).replace("  - name: kin\n    kind: kinematic\n    time: {span: [0, 1], n: 11}\n", "")
    + """\
  - name: mix
    kind: mixed
    time: {span: [0, 1], n: 11}
    unknown: [tq]
    prescribed:
      - {coordinate: crank.phi, law: w*t}
"""
)


def sub(old: str, new: str, text: str = BASE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + "".join(
    f"{k}: &{k} [" + ",".join([f"*{chr(ord(k) - 1)}"] * 9) + "]\n" for k in "bcdefghi"
)

# (id, file text, expected text in the message, expected line or None)
CASES = [
    (
        "yaml-syntax",
        sub("  - name: rod\n", "  - name: rod\n   mass: [1\n"),
        "YAML syntax error",
        None,
    ),
    ("yaml-bomb", BOMB + BASE, "anchor", 1),
    ("yaml-alias", BASE + "extra: *nothing\n", "alias", None),
    (
        "duplicate-key",
        sub("    mass: 1\n", "    mass: 1\n    mass: 2\n"),
        "duplicate key 'mass'",
        9,
    ),
    (
        "python-tag",
        sub("name: slider-crank", "name: !!python/object/apply:os.system ['echo pwned']"),
        "tag",
        2,
    ),
    ("not-a-mapping", "- just\n- a list\n", "must be a mapping", 1),
    ("empty-file", "", "must be a mapping", 1),
    ("missing-field", sub(", point_j: crank.O}", "}"), "missing field 'point_j'", 22),
    (
        "unknown-field",
        sub("    inertia: 0.01\n    q0: [0.05", "    inertai: 0.01\n    q0: [0.05"),
        "unknown field 'inertai'",
        9,
    ),
    ("unknown-joint-type", sub("type: revolute, name: A", "type: hinge, name: A"), "'hinge'", 23),
    ("unknown-run-kind", sub("kind: kinematic", "kind: static"), "static", 32),
    ("unknown-body", sub("point_j: rod.A}", "point_j: rodd.A}"), "unknown body 'rodd'", 23),
    ("unknown-point", sub("point_j: rod.A}", "point_j: rod.Q}"), "no point 'Q'", 23),
    (
        "duplicate-body",
        sub("  - name: slider\n", "  - name: rod\n"),
        "duplicate body name 'rod'",
        17,
    ),
    ("duplicate-element", sub("name: gas,", "name: motor,"), "duplicate name 'motor'", 29),
    ("ground-as-body", sub("  - name: slider\n", "  - name: ground\n"), "fixed frame", 17),
    (
        "self-joint",
        sub("point_i: crank.A, point_j: rod.A", "point_i: rod.A, point_j: rod.B"),
        "both points are on 'rod'",
        23,
    ),
    ("wrong-dimension", sub("    mass: 1\n", "    mass: 3 mm\n"), "expected a mass", 8),
    ("wrong-dimension-law", sub("law: 50 N}", "law: 50 N*m}"), "expected a force", 29),
    ("non-numeric", sub("    mass: 1\n", "    mass: heavy\n"), "cannot read 'heavy'", 8),
    ("boolean", sub("    inertia: 0.01\n", "    inertia: yes\n"), "expected a number", 9),
    ("list-for-number", sub("    mass: 1\n", "    mass: [1, 2]\n"), "expected a number", 8),
    ("negative-mass", sub("    mass: 1\n", "    mass: -1\n"), "negative mass", 8),
    ("unknown-unit", sub("law: 50 N}", "law: 50 furlongz}"), "unknown unit", 29),
    ("bad-model-units", sub("length: m,", "length: kg,"), "expected a length", 3),
    ("zero-axis", sub("axis: [1, 0]", "axis: [0, 0]"), "zero length", 25),
    ("bad-expression", sub("law: w*t}", "law: sin(w*t}"), "syntax error", 27),
    (
        "malicious-import",
        sub("law: w*t}", "law: \"__import__('os').system('echo pwned')\"}"),
        "only the listed functions",
        27,
    ),
    ("malicious-attribute", sub("law: w*t}", "law: t.__class__.__base__}"), "attribute access", 27),
    (
        "malicious-call",
        sub("law: w*t}", "law: \"open('/etc/passwd')\"}"),
        "function 'open' is not allowed",
        27,
    ),
    ("unknown-name", sub("law: w*t}", "law: v*t}"), "unknown name 'v'", 27),
    ("power-caret", sub("law: w*t}", "law: w*t^2}"), "'^' is not a power", 27),
    ("state-in-driver", sub("law: w*t}", "law: 2*rod.phi}"), "uses the state", 27),
    ("reserved-parameter", sub("  w: 2 rad/s\n", "  sin: 2\n"), "taken", 5),
    ("bad-parameter", sub("  w: 2 rad/s\n", "  w: 2 rad/\n"), "w", 5),
    (
        "dof-too-few",
        sub("drivers:\n  - {type: coordinate, name: motor, coordinate: crank.phi, law: w*t}\n", ""),
        "1 degree of freedom but the kinematic run has 0 drivers",
        30,
    ),
    (
        "dof-too-many",
        sub(
            "law: w*t}\n",
            "law: w*t}\n  - {type: coordinate, name: m2, coordinate: slider.x, law: 0.3}\n",
        ),
        "driver m2 prescribes a motion the joints or other drivers already fix",
        33,
    ),
    ("empty-span", sub("span: [0, 1]", "span: [1, 0]"), "empty", 34),
    (
        "time-form",
        sub("time: {span: [0, 1], n: 11}", "time: {span: [0, 1]}"),
        "give 'span' with either 'n' or 'step'",
        34,
    ),
    (
        "plot-column",
        BASE + "    plots: [{file: a.png, columns: [slider.xx]}]\n",
        "no column 'slider.xx'",
        35,
    ),
    (
        "plot-file",
        BASE + "    plots: [{file: ../../evil.png, columns: [slider.x]}]\n",
        "relative file name",
        35,
    ),
    ("zero-mass-dynamic", sub("    mass: 1\n", "    mass: 0\n", MIXED), "is dynamic", 8),
    (
        "mixed-unknown-force",
        sub("unknown: [tq]", "unknown: [nothing]", MIXED),
        "unknown force 'nothing'",
        None,
    ),
    (
        "mixed-count",
        sub("unknown: [tq]", "unknown: [tq, gas]", MIXED),
        "2 unknown forces but 1 prescribed motion",
        None,
    ),
    (
        "mixed-from-unknown-run",
        sub("{coordinate: crank.phi, law: w*t}", "{coordinate: crank.phi, from_run: nope}", MIXED),
        "unknown run 'nope'",
        None,
    ),
    (
        "mixed-self-replay",
        sub("{coordinate: crank.phi, law: w*t}", "{coordinate: crank.phi, from_run: mix}", MIXED),
        "cannot replay itself",
        None,
    ),
    (  # a tag-like unknown field is told against the prescribed motion's own fields
        "tag-like-unknown-field",
        sub(
            "{coordinate: crank.phi, law: w*t}",
            "{coordinate: crank.phi, law: w*t, type: revolute}",
            MIXED,
        ),
        "unknown field 'type'; remove it or fix its spelling; allowed fields: coordinate, name",
        None,
    ),
]


@pytest.fixture(scope="module")
def cli():
    return CliRunner()


def test_at_least_25_kinds():
    assert len(CASES) >= 25


@pytest.mark.parametrize(("case", "text", "expected", "line"), CASES, ids=[c[0] for c in CASES])
def test_broken_file(cli, tmp_path, case, text, expected, line):
    path = tmp_path / f"{case}.yaml"
    path.write_text(text, encoding="utf-8")
    res = cli.invoke(app, ["check", str(path)])
    err = res.stderr
    assert res.exit_code == 2, (res.exit_code, res.output)
    assert "Traceback" not in res.output
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    msg = lines[0]
    assert msg.startswith(str(path)), msg
    assert expected in msg, msg
    if line is not None:
        assert msg.startswith(f"{path}:{line}: "), msg
    assert "pwned" not in res.stdout


@pytest.mark.parametrize("command", ["run", "check"])
def test_unsolvable_mixed_run(cli, tmp_path, command):
    """The unknown force (a torque on the slider, which cannot turn) cannot produce the
    prescribed crank motion: found by `check` before anything runs and by `run` when the run
    starts; exit 2, naming the run and the force."""
    text = sub("unknown: [tq]", "unknown: [ts]", MIXED)
    text = sub(
        "  - {type: torque, name: tq, body: crank, law: 0}\n",
        "  - {type: torque, name: tq, body: crank, law: 0}\n"
        "  - {type: torque, name: ts, body: slider, law: 0}\n",
        text,
    )
    path = tmp_path / "unsolvable.yaml"
    path.write_text(text, encoding="utf-8")
    args = ["run", str(path), "--run", "mix", "--out", str(tmp_path / "o")]
    res = cli.invoke(app, args if command == "run" else ["check", str(path)])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output
    assert lines[0].startswith(f"{path}:") and "run 'mix'" in lines[0], lines[0]
    assert "ts" in lines[0]


def test_missing_file(cli, tmp_path):
    res = cli.invoke(app, ["check", str(tmp_path / "nope.yaml")])
    assert res.exit_code == 2
    assert res.stderr.strip() == f"{tmp_path / 'nope.yaml'}: no such file; check the path"


def test_file_is_never_executed(cli, tmp_path):
    marker = tmp_path / "pwned"
    payloads = [
        f"name: !!python/object/apply:os.system ['touch {marker}']\nbodies: [{{name: b}}]\n",
        f"bodies: [{{name: b, mass: \"__import__('os').system('touch {marker}')\"}}]\n",
        "bodies: [{name: b}]\ndrivers:\n  - {type: coordinate, name: d, coordinate: b.x, "
        f"law: \"__import__('os').system('touch {marker}')\"}}\n",
    ]
    for k, text in enumerate(payloads):
        path = tmp_path / f"p{k}.yaml"
        path.write_text(text)
        res = cli.invoke(app, ["check", str(path)])
        assert res.exit_code == 2, res.output
    assert not pathlib.Path(marker).exists()
