"""Hostile and broken inputs: every one ends in a named input error (exit 2, one line on
stderr naming the file, no traceback), found by ``mixdyn check`` or before ``mixdyn run``
computes anything; nothing is written outside ``--out`` and nothing non-finite is written.

Most cases fail while the file is read, built or planned, before any JAX program is compiled,
so the whole module runs in seconds.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pathlib
import re

import pytest
from typer.testing import CliRunner

import mixdyn as md
from mixdyn.cli import app
from mixdyn.errors import ModelError
from mixdyn.io import ExpressionError
from mixdyn.io.expressions import ExpressionLaw, constant_value
from mixdyn.runs.console import clean, progress_log

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

FWD = """\
mixdyn: 1
name: pendulum
gravity: [0, -9.81]
bodies:
  - {name: rod, mass: 1, inertia: 0.1, q0: [0, -0.5, 0], points: {pivot: [0, 0.5]}}
joints:
  - {type: revolute, name: pivot, point_i: ground, point_j: rod.pivot}
forces:
  - {type: torque, name: damper, body: rod, law: -0.1*rod.omega}
runs:
  - name: swing
    kind: forward
    time: {span: [0, 1], n: 11}
  - name: alpha
    kind: forward
    time: {span: [0, 1], n: 11}
    method: generalized-alpha
    dt: 1 ms
    options: {rho_inf: 0.9}
  - name: rk4
    kind: forward
    time: {span: [0, 1], n: 11}
    method: baumgarte
    dt: 1 ms
"""

MIXED = """\
  - name: mix
    kind: mixed
    time: {span: [0, 1], n: 11}
    unknown: [tq]
    prescribed:
      - {coordinate: crank.phi, law: w*t}
"""


def sub(old: str, new: str, text: str = BASE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


def law(expr: str) -> str:
    """BASE with the motor's law replaced by ``expr`` (quoted)."""
    return sub("law: w*t}", f"law: {json.dumps(expr)}}}")


def quantity(text: str) -> str:
    """BASE with the gas force's constant law replaced by ``text``."""
    return sub("law: 50 N}", f"law: {json.dumps(text)}}}")


def option(key: str, value: str, text: str = FWD) -> str:
    """FWD's generalized-alpha run with one more option."""
    return sub("options: {rho_inf: 0.9}", f"options: {{rho_inf: 0.9, {key}: {value}}}", text)


def run_setting(line: str, text: str = FWD) -> str:
    """FWD's first run with one more setting line."""
    return sub("  - name: swing\n", f"  - name: swing\n    {line}\n", text)


def deep(n: int) -> str:
    return "bodies: [{name: b}]\nx: " + "[" * n + "1" + "]" * n + "\n"


BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + "".join(
    f"{k}: &{k} [" + ",".join([f"*{chr(ord(k) - 1)}"] * 9) + "]\n" for k in "bcdefghi"
)

# (id, file text, expected text in the message)
BROKEN_YAML = [
    ("unclosed-bracket", sub("q0: [0.05, 0, 0]", "q0: [0.05, 0, 0"), "YAML syntax error"),
    ("bad-indent", sub("    mass: 1\n", "      mass: 1\n"), "YAML syntax error"),
    ("tab-indent", sub("    mass: 1\n", "\tmass: 1\n"), "YAML syntax error"),
    ("unterminated-quote", sub("name: slider-crank", 'name: "slider'), "YAML syntax error"),
    ("nul-byte", sub("name: slider-crank", "name: slider\x00crank"), "U+0000"),
    ("escape-byte", sub("name: slider-crank", "name: slider\x1b[31mcrank"), "U+001B"),
    ("bell-in-comment", BASE + "# ding\x07\n", "U+0007"),
    ("two-documents", BASE + "---\nname: other\n", "YAML"),
    ("scalar-document", "just a string\n", "must be a mapping"),
    ("list-document", "- a\n- b\n", "must be a mapping"),
    ("comments-only", "# nothing here\n", "must be a mapping"),
    ("empty", "", "must be a mapping"),
    ("missing-bodies", "name: x\n", "missing field 'bodies'"),
    ("wrong-version", sub("mixdyn: 1", "mixdyn: 2"), "mixdyn"),
    ("unknown-top-key", BASE + "bodys: []\n", "unknown field 'bodys'"),
    ("typo-suggested", sub("    inertia: 0.01\n", "    inertai: 0.01\n"), "did you mean 'inertia'"),
]

HOSTILE_YAML = [
    ("alias-bomb", BOMB + BASE, "anchor"),
    ("alias", BASE + "extra: *nothing\n", "alias"),
    ("anchor", sub("mass: 1\n", "mass: &m 1\n"), "anchor"),
    ("merge-key", sub("  - name: rod\n", "  - <<: {name: x}\n    name: rod\n"), "merge"),
    ("python-object", sub("name: slider-crank", "name: !!python/object:os.system x"), "tag"),
    (
        "python-apply",
        sub("name: slider-crank", "name: !!python/object/apply:os.system ['echo pwned']"),
        "tag",
    ),
    ("python-name", sub("name: slider-crank", "name: !!python/name:os.system ''"), "tag"),
    ("binary-tag", sub("name: slider-crank", "name: !!binary aGVsbG8="), "tag"),
    ("set-tag", sub("name: slider-crank", "name: !!set {a, b}"), "tag"),
    ("empty-float-tag", sub("mass: 1\n", 'mass: !!float ""\n'), "bad value"),
    ("empty-int-tag", sub("mass: 1\n", 'mass: !!int ""\n'), "bad value"),
    ("local-tag", sub("name: slider-crank", "name: !evil x"), "tag"),
    ("timestamp", sub("name: slider-crank", "name: 2001-12-14"), "tag"),
    ("deep-lists", deep(200), "nested"),
    ("deep-maps", "bodies: [{name: b}]\nx: " + "{a: " * 60 + "1" + "}" * 60 + "\n", "nested"),
    ("complex-key", BASE + "? [a, b]\n: 1\n", "key"),
    ("duplicate-key", sub("    mass: 1\n", "    mass: 1\n    mass: 2\n"), "duplicate key"),
    ("null-key", BASE + "~: 1\n", "key"),
]

EXPRESSIONS = [
    ("div-zero", law("1/0"), "division by zero"),
    ("div-zero-t", law("1/0*t"), "division by zero"),
    ("div-zero-sum", law("t/(1-1)"), "division by zero"),
    ("mod-zero", law("t%0"), "remainder by zero"),
    ("tower", law("9**9**9**9"), "not a finite number"),
    ("overflow", law("1e308*10*t"), "not a finite number"),
    ("sqrt-neg", law("sqrt(-1)+t"), "not a finite number"),
    ("log-zero", law("log(0)*t"), "not a finite number"),
    ("exp-huge", law("exp(1000)"), "not a finite number"),
    ("zero-neg-power", law("0**-1"), "not a finite number"),
    ("acos-out", law("acos(2)"), "not a finite number"),
    ("nan-name", law("nan"), "unknown name 'nan'"),
    ("inf-name", law("inf*t"), "unknown name 'inf'"),
    ("huge-literal", law("9" * 400), "too large"),
    ("huge-float", law("1e999"), "too large"),
    ("deep-unary", law("-" * 300 + "t"), "nested more than"),
    ("deep-power", law("t" + "**1" * 200), "nested more than"),
    ("too-long", law("t+" * 600 + "t"), "longer than"),
    ("import", law("__import__('os').system('echo pwned')"), "only the listed functions"),
    ("lambda", law("(lambda: 1)()"), "only the listed functions"),
    ("attribute", law("t.__class__"), "attribute access"),
    ("subscript", law("t[0]"), "subscripts"),
    ("string", law("'abc'"), "not a number"),
    ("fstring", law("f'{t}'"), "strings"),
    ("walrus", law("(x := 1)"), "assignment"),
    ("if-else", law("1 if t else 0"), "'if ... else'"),
    ("bool-op", law("t and 1"), "'and'/'or'"),
    ("not", law("not t"), "operator Not"),
    ("bit-shift", law("1 << 1000"), "operator LShift"),
    ("invert", law("~t"), "operator Invert"),
    ("caret", law("t^2"), "'^' is not a power"),
    ("chained", law("0 < t < 1"), "chained"),
    ("keyword-arg", law("sin(x=t)"), "keyword"),
    ("arg-count", law("sin(t, t)"), "takes 1"),
    ("unknown-func", law("eval('1')"), "not allowed"),
    ("true", law("True"), "not a number"),
    ("ellipsis", law("..."), "not a number"),
    ("bare-function", law("sin"), "must be called"),
    ("empty-expr", law(" "), "empty"),
    ("syntax", law("sin(t"), "syntax error"),
    ("state-in-driver", law("2*rod.phi"), "uses the state"),
    ("body-no-state", sub("law: -0.1*rod.omega}", "law: -0.1*rod}", FWD), "needs a state"),
    ("state-div-zero", sub("law: -0.1*rod.omega}", "law: rod.omega/0}", FWD), "by zero"),
    ("param-div-zero", sub("  w: 2 rad/s\n", "  w: 1/0\n"), "division by zero"),
    ("param-nonfinite", sub("  w: 2 rad/s\n", "  w: exp(1000)\n"), "not a finite number"),
    ("singular-in-span", law("1/(t-0.5)"), "not finite at t = 0.5"),
    ("log-in-span", law("log(t)"), "not finite at t = 0"),
]

QUANTITIES = [
    ("q-div-zero", quantity("1/0 N"), "division by zero"),
    ("q-sqrt-neg", quantity("sqrt(-1) N"), "not a finite number"),
    ("q-overflow", quantity("1e999 N"), "finite"),
    ("q-unit-twice", quantity("5 N N"), "expected a force"),
    ("q-unknown-unit", quantity("5 furlongz"), "unknown unit"),
    ("q-temperature", quantity("5 degC"), "unit"),
    ("q-wrong-dim", quantity("5 m"), "expected a force"),
    ("q-long", quantity("1" + "0" * 250 + " N"), "longer than"),
    ("q-unit-code", quantity("5 __import__"), "unit"),
    ("q-model-units", sub("length: m,", "length: furlongz,"), "unknown unit"),
    ("q-model-dimension", sub("length: m,", "length: s,"), "expected a length"),
]

NUMBERS = [
    ("mass-nan", sub("    mass: 1\n", "    mass: .nan\n"), "finite"),
    ("mass-inf", sub("    mass: 1\n", "    mass: .inf\n"), "finite"),
    ("mass-neg", sub("    mass: 1\n", "    mass: -1\n"), "negative mass"),
    ("inertia-neg-inf", sub("    inertia: 0.01\n", "    inertia: -.inf\n"), "finite"),
    ("q0-nan", sub("q0: [0.05, 0, 0]", "q0: [.nan, 0, 0]"), "finite"),
    ("q0-inf", sub("q0: [0.05, 0, 0]", "q0: [0.05, .inf, 0]"), "finite"),
    ("q0-string-inf", sub("q0: [0.05, 0, 0]", "q0: ['1e999', 0, 0]"), "finite"),
    ("point-nan", sub("O: [-0.05, 0]", "O: [.nan, 0]"), "finite"),
    ("gravity-nan", sub("units: {", "gravity: [.nan, 0]\nunits: {"), "finite"),
    ("axis-zero", sub("axis: [1, 0]", "axis: [0, 0]"), "zero length"),
    ("axis-nan", sub("axis: [1, 0]", "axis: [.nan, 1]"), "finite"),
    (
        "distance-negative",
        sub(
            "  - {type: revolute, name: B, point_i: rod.B, point_j: slider}",
            "  - {type: distance, name: B, point_i: rod.B, point_j: slider, length: -1}",
        ),
        "not positive",
    ),
    (
        "distance-zero",
        sub(
            "  - {type: revolute, name: B, point_i: rod.B, point_j: slider}",
            "  - {type: distance, name: B, point_i: rod.B, point_j: slider, length: 0}",
        ),
        "not positive",
    ),
    ("ramp-inf", sub("law: w*t}", "law: {ramp: {rate: .inf}}}"), "finite"),
    ("harmonic-nan", sub("law: w*t}", "law: {harmonic: {amplitude: 1, omega: .nan}}}"), "finite"),
    ("polynomial-nan", sub("law: w*t}", "law: {polynomial: [0, .nan]}}"), "finite"),
    (
        "piecewise-nan",
        sub("law: w*t}", "law: {piecewise: {breaks: [0, .nan], coeffs: [[1]]}}}"),
        "",
    ),
    (
        "spline-unsorted",
        sub("law: w*t}", "law: {spline: {t: [1, 0, 2], y: [0, 1, 2]}}}"),
        "increas",
    ),
    ("span-inf", sub("span: [0, 1]", "span: [0, .inf]"), "finite"),
    ("span-empty", sub("span: [0, 1]", "span: [1, 1]"), "empty"),
    ("n-zero", sub("n: 11", "n: 0"), "greater than or equal to 2"),
    ("n-huge", sub("n: 11", "n: 10000000"), "less than or equal"),
    ("step-zero", sub("n: 11", "step: 0"), "positive"),
    ("step-tiny", sub("n: 11", "step: 1e-9"), "too many"),
    ("values-empty", sub("time: {span: [0, 1], n: 11}", "time: {values: []}"), "at least 1"),
    ("values-unsorted", sub("time: {span: [0, 1], n: 11}", "time: {values: [1, 0]}"), "increasing"),
    ("kin-tol-nan", sub("    kind: kinematic\n", "    kind: kinematic\n    tol: .nan\n"), "tol"),
    ("kin-tol-neg", sub("    kind: kinematic\n", "    kind: kinematic\n    tol: -1\n"), "tol"),
    ("kin-tol-inf", sub("    kind: kinematic\n", "    kind: kinematic\n    tol: .inf\n"), "tol"),
    (
        "kin-max-iter",
        sub("    kind: kinematic\n", "    kind: kinematic\n    max_iter: 0\n"),
        "max_iter",
    ),
    ("rtol-nan", run_setting("rtol: .nan"), "rtol"),
    ("rtol-neg", run_setting("rtol: -1.0e-8"), "rtol"),
    ("atol-inf", run_setting("atol: .inf"), "atol"),
    ("dt-zero", run_setting("dt: 0"), "positive"),
    ("dt-neg", run_setting("dt: -1 ms"), "positive"),
    ("dt-nan", run_setting("dt: .nan"), "finite"),
    ("dt-wrong-unit", run_setting("dt: 1 m"), "expected a time"),
    ("velocity-nan", run_setting("velocities: {rod.phi: .nan}"), "finite"),
    ("initial-inf", run_setting("initial: {rod.phi: .inf}"), "finite"),
    (
        "spring-nan",
        sub(
            "forces:\n",
            "forces:\n  - {type: spring_damper, name: k, point_i: ground, point_j: rod, "
            "stiffness: .nan}\n",
            FWD,
        ),
        "finite",
    ),
]

OPTIONS = [
    ("rho-inf-5", option("rho_inf", "5").replace("rho_inf: 0.9, ", ""), "rho_inf is 5"),
    ("rho-inf-nan", sub("rho_inf: 0.9", "rho_inf: .nan", FWD), "rho_inf"),
    ("rho-inf-neg", sub("rho_inf: 0.9", "rho_inf: -0.1", FWD), "rho_inf"),
    ("tol-nan", option("tol", ".nan"), "tol is nan"),
    ("tol-neg", option("tol", "-1"), "tol is -1"),
    ("tol-zero", option("tol", "0"), "tol is 0"),
    ("max-steps-neg", option("max_steps", "-1"), "max_steps is -1"),
    ("max-steps-frac", option("max_steps", "2.5"), "whole number"),
    ("max-steps-bool", option("max_steps", "true"), "max_steps is True"),
    ("max-newton-zero", option("max_newton", "0"), "max_newton is 0"),
    ("newton-choice", option("newton", "fast"), "use one of: auto, modified, full"),
    ("project-velocities", option("project_velocities", "3"), "true or false"),
    ("tolerance-typo", option("tolerance", "1e-3"), "did you mean 'tol'"),
    ("rho-typo", option("rhoinf", "0.5"), "did you mean 'rho_inf'"),
    ("rtol-clash", option("rtol", "1e-3"), "setting of the run"),
    ("dt-clash", option("dt", "0.1"), "setting of the run"),
    ("linear-solver-clash", option("linear_solver", "dense"), "setting of the run"),
    ("method-clash", option("method", "baumgarte"), "setting of the run"),
    ("solver-for-alpha", option("solver", "dopri8"), "unknown option 'solver'"),
    (
        "solver-choice",
        run_setting("options: {solver: rk4}"),
        "use one of: tsit5, dopri5, dopri8",
    ),
    (
        "alpha-neg",
        sub(
            "    method: baumgarte\n    dt: 1 ms\n",
            "    method: baumgarte\n    dt: 1 ms\n    options: {alpha: -1}\n",
            FWD,
        ),
        "alpha is -1",
    ),
    (
        "baumgarte-unknown",
        sub(
            "    method: baumgarte\n    dt: 1 ms\n",
            "    method: baumgarte\n    dt: 1 ms\n    options: {gamma: 1}\n",
            FWD,
        ),
        "unknown option 'gamma'",
    ),
    ("no-dt-alpha", sub("    dt: 1 ms\n    options", "    options", FWD), "gives no dt"),
    (
        "no-dt-rk4",
        sub("    method: baumgarte\n    dt: 1 ms\n", "    method: baumgarte\n", FWD),
        "gives no dt",
    ),
    (
        "absurd-steps",
        sub("    dt: 1 ms\n    options", "    dt: 1e-12\n    options", FWD),
        "more than max_steps",
    ),
    (
        "absurd-steps-10s",
        sub(
            "time: {span: [0, 1], n: 11}\n    method: baumgarte\n    dt: 1 ms",
            "time: {span: [0, 10], n: 11}\n    method: baumgarte\n    dt: 1e-12",
            FWD,
        ),
        "more than max_steps",
    ),
    (
        "steps-over-own-limit",
        option("max_steps", "10"),
        "more than max_steps = 10",
    ),
    (
        "inverse-unknown-option",
        BASE + "  - name: inv\n    kind: inverse\n    time: {span: [0, 1], n: 11}\n"
        "    options: {tolerance: 1e-9}\n",
        "did you mean 'tol'",
    ),
    (
        "inverse-max-iter",
        BASE + "  - name: inv\n    kind: inverse\n    time: {span: [0, 1], n: 11}\n"
        "    options: {max_iter: 0}\n",
        "max_iter is 0",
    ),
    (
        "mixed-solver-option",
        sub(
            "    unknown: [tq]\n",
            "    unknown: [tq]\n    options: {solver: dopri8}\n",
            BASE.replace(
                "drivers:\n  - {type: coordinate, name: motor, coordinate: crank.phi, law: w*t}\n",
                "",
            )
            + MIXED,
        ),
        "mixed solver",
    ),
]

SEMANTIC = [
    ("unknown-body", sub("point_j: rod.A}", "point_j: rodd.A}"), "unknown body 'rodd'"),
    ("unknown-point", sub("point_j: rod.A}", "point_j: rod.Q}"), "no point 'Q'"),
    ("duplicate-body", sub("  - name: slider\n", "  - name: rod\n"), "duplicate body name"),
    ("duplicate-element", sub("name: gas,", "name: motor,"), "duplicate name 'motor'"),
    ("ground-body", sub("  - name: slider\n", "  - name: ground\n"), "fixed frame"),
    ("bad-name", sub("  - name: slider\n", "  - name: 'sl ider'\n"), "not a valid name"),
    ("long-name", sub("  - name: slider\n", f"  - name: {'s' * 65}\n"), "at most 64"),
    (
        "run-driver",
        sub("    kind: kinematic\n", "    kind: kinematic\n    drivers: [nope]\n"),
        "unknown driver 'nope'",
    ),
    (
        "hold-unknown",
        sub("    kind: kinematic\n", "    kind: kinematic\n    hold: [nope.phi]\n"),
        "unknown body 'nope'",
    ),
    (
        "hold-not-coordinate",
        sub("    kind: kinematic\n", "    kind: kinematic\n    hold: [crank.z]\n"),
        "not a coordinate",
    ),
    (
        "initial-unknown",
        sub("    kind: kinematic\n", "    kind: kinematic\n    initial: {crank.q: 1}\n"),
        "not a coordinate",
    ),
    (
        "velocities-kinematic",
        sub("    kind: kinematic\n", "    kind: kinematic\n    velocities: {crank.phi: 1}\n"),
        "no effect",
    ),
    (
        "dup-run",
        BASE + "  - name: kin\n    kind: kinematic\n    time: {span: [0, 1], n: 3}\n",
        "duplicate run name",
    ),
    (
        "model-name-escape",
        sub("name: slider-crank", 'name: "slider\\e[31mcrank"'),
        "control character",
    ),
    (
        "title-bidi",
        BASE + '    plots: [{file: a.png, columns: [slider.x], title: "a\\u202eb"}]\n',
        "control character",
    ),
    (
        "description-escape",
        sub("name: slider-crank", 'name: x\ndescription: "a\\x1bb"'),
        "control character",
    ),
    ("plot-suffix", BASE + "    plots: [{file: a.jpg, columns: [slider.x]}]\n", "use .png"),
    ("plot-no-suffix", BASE + "    plots: [{file: a, columns: [slider.x]}]\n", "use .png"),
    ("plot-dotfile", BASE + "    plots: [{file: .png, columns: [slider.x]}]\n", "use .png"),
    ("plot-escape-path", BASE + "    plots: [{file: ../x.png, columns: [slider.x]}]\n", "relative"),
    ("plot-absolute", BASE + "    plots: [{file: /tmp/x.png, columns: [slider.x]}]\n", "relative"),
    (
        "plot-twice",
        BASE + "    plots: [{file: a.png, columns: [slider.x]}, "
        "{file: a.png, columns: [slider.y]}]\n",
        "twice",
    ),
    ("plot-column", BASE + "    plots: [{file: a.png, columns: [slider.xx]}]\n", "no column"),
    ("animation-suffix", BASE + "    animation: {file: a.avi}\n", "use .gif"),
    (
        "animation-plot-column",
        BASE + "    animation: {file: a.gif, plot: [crank.phi, slider.xx]}\n",
        "animation.plot[1]: no column 'slider.xx'",
    ),
    (
        "animation-plot-x-column",
        BASE + "    animation: {file: a.gif, plot: [slider.x],\n      plot_x: crank.phii}\n",
        f":{BASE.count(chr(10)) + 2}: run 'kin', animation.plot_x: no column 'crank.phii'",
    ),
    (
        "animation-plot-x-no-plot",
        BASE + "    animation: {file: a.gif, plot: [], plot_x: crank.phi}\n",
        "animation.plot_x: the player has no plot",
    ),
    (
        "mixed-unknown-force",
        BASE.replace(
            "drivers:\n  - {type: coordinate, name: motor, coordinate: crank.phi, law: w*t}\n", ""
        )
        + MIXED.replace("unknown: [tq]", "unknown: [nothing]"),
        "unknown force 'nothing'",
    ),
    ("mixed-self", BASE + MIXED.replace("law: w*t}", "from_run: mix}"), "cannot replay itself"),
    (
        "mixed-from-unknown",
        BASE + MIXED.replace("law: w*t}", "from_run: nope}"),
        "unknown run 'nope'",
    ),
]


def _replay(span: str) -> str:
    """A forward run, then a mixed run replaying its motion over ``span``."""
    return FWD + (
        "  - name: mix\n    kind: mixed\n"
        f"    time: {{span: {span}, n: 11}}\n"
        "    unknown: [damper]\n"
        "    prescribed: [{coordinate: rod.phi, from_run: swing}]\n"
    )


SEMANTIC += [
    ("replay-longer", _replay("[0, 2]"), "covers t = 0..1"),
    ("replay-earlier", _replay("[-1, 1]"), "covers t = 0..1"),
    (
        "replay-cycle",
        _replay("[0, 1]").replace("from_run: swing}", "from_run: mix2}")
        + "  - name: mix2\n    kind: mixed\n    time: {span: [0, 1], n: 11}\n"
        "    unknown: [damper]\n    prescribed: [{coordinate: rod.phi, from_run: mix}]\n",
        "cycle",
    ),
]

CASES = BROKEN_YAML + HOSTILE_YAML + EXPRESSIONS + QUANTITIES + NUMBERS + OPTIONS + SEMANTIC

_NONFINITE = re.compile(r"\b(nan|NaN|inf|Infinity)\b")


@pytest.fixture(scope="module")
def cli():
    return CliRunner()


def _tree(root: pathlib.Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def _invoke(cli, args, cwd: pathlib.Path):
    """Run the command in ``cwd`` and return the result."""
    old = os.getcwd()
    os.chdir(cwd)
    try:
        return cli.invoke(app, [str(a) for a in args])
    finally:
        os.chdir(old)


def expect_input_error(cli, tmp_path, args, expected="", *, file=None, out=None, code=2):
    """Assert exit ``code`` with one clean line on stderr, and nothing written outside
    ``out``; return that line."""
    before = _tree(tmp_path)
    res = _invoke(cli, args, tmp_path)
    err = res.stderr
    assert res.exit_code == code, (res.exit_code, res.output, err)
    assert "Traceback" not in res.output + err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert "\x1b" not in line and "\x00" not in line
    if file is not None:
        assert line.startswith(str(file)), line
    assert expected in line, line
    assert "internal error" not in line
    assert "pwned" not in res.stdout
    new = _tree(tmp_path) - before
    if out is not None:
        new = {p for p in new if not (tmp_path / p).resolve().is_relative_to(out.resolve())}
    assert not new, new
    return line


def assert_finite_files(folder: pathlib.Path) -> None:
    """No NaN or infinity in any text file written under ``folder``."""
    for p in folder.rglob("*"):
        if p.is_file() and p.suffix in (".csv", ".json", ".html", ".yaml"):
            text = p.read_text(encoding="utf-8", errors="replace")
            assert not _NONFINITE.search(text), (p, _NONFINITE.search(text))


def test_at_least_100_cases():
    assert len(CASES) >= 100
    assert len({c[0] for c in CASES}) == len(CASES)


@pytest.mark.parametrize(("case", "text", "expected"), CASES, ids=[c[0] for c in CASES])
def test_check_refuses(cli, tmp_path, case, text, expected):
    path = tmp_path / "model.yaml"
    path.write_text(text, encoding="utf-8")
    expect_input_error(cli, tmp_path, ["check", path], expected, file=path)


@pytest.mark.parametrize(
    "case",
    ["tolerance-typo", "absurd-steps", "rho-inf-5", "plot-suffix", "replay-longer", "div-zero"],
)
def test_run_refuses_before_computing(cli, tmp_path, case):
    text = dict((c[0], c[1]) for c in CASES)[case]
    path = tmp_path / "model.yaml"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    expect_input_error(cli, tmp_path, ["run", path, "--out", out], file=path, out=out)
    assert not out.exists()


# ------------------------------------------------------------------ files that are not files
def test_fifo_is_refused_without_blocking(cli, tmp_path):
    fifo = tmp_path / "model.yaml"
    os.mkfifo(fifo)
    expect_input_error(cli, tmp_path, ["check", fifo], "pipe, socket or device", file=fifo)


@pytest.mark.parametrize(
    ("target", "expected"),
    [("folder", "is a folder"), ("/dev/null", "pipe, socket or device"), ("nope", "no such")],
)
def test_not_a_model_file(cli, tmp_path, target, expected):
    path = tmp_path if target == "folder" else pathlib.Path(target)
    if target == "nope":
        path = tmp_path / "nope.yaml"
    expect_input_error(cli, tmp_path, ["check", path], expected, file=path)


def test_size_limit(cli, tmp_path):
    path = tmp_path / "big.yaml"
    with open(path, "wb") as f:
        f.truncate(20_000_001)  # sparse: costs no disk
    expect_input_error(cli, tmp_path, ["check", path], "limit of 20 MB", file=path)


def test_not_utf8(cli, tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(BASE.replace("slider-crank", "gr\xfc\xdf").encode("latin-1"))
    expect_input_error(cli, tmp_path, ["check", path], "not UTF-8", file=path)


def test_escapes_in_the_path_are_shown_escaped(cli, tmp_path):
    path = tmp_path / "red\x1b[31m.yaml"
    line = expect_input_error(cli, tmp_path, ["check", path], "no such file")
    assert "\\x1b[31m" in line


# ------------------------------------------------------------------ output paths
@pytest.fixture
def model_file(tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(BASE, encoding="utf-8")
    return path


def test_run_out_is_a_file(cli, tmp_path, model_file):
    out = tmp_path / "out"
    out.write_text("not a folder")
    expect_input_error(cli, tmp_path, ["run", model_file, "--out", out], "not a folder")


def test_run_out_below_a_file(cli, tmp_path, model_file):
    expect_input_error(cli, tmp_path, ["run", model_file, "--out", model_file / "out"], "is a file")


def test_run_folder_of_a_run_is_a_file(cli, tmp_path, model_file):
    out = tmp_path / "out"
    out.mkdir()
    (out / "kin").write_text("x")
    expect_input_error(cli, tmp_path, ["run", model_file, "--out", out], "not a folder", out=out)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_run_out_not_writable(cli, tmp_path, model_file):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    expect_input_error(cli, tmp_path, ["run", model_file, "--out", locked / "o"], "writable")


def test_run_unknown_run(cli, tmp_path, model_file):
    expect_input_error(cli, tmp_path, ["run", model_file, "--run", "nope"], "no run 'nope'")


@pytest.mark.parametrize("command", ["schema", "dump"])
def test_output_is_a_folder(cli, tmp_path, model_file, command):
    args = ["schema"] if command == "schema" else ["dump", model_file]
    expect_input_error(cli, tmp_path, [*args, "-o", tmp_path], "is a folder")


@pytest.mark.parametrize("command", ["schema", "dump"])
def test_output_below_a_file(cli, tmp_path, model_file, command):
    args = ["schema"] if command == "schema" else ["dump", model_file]
    expect_input_error(cli, tmp_path, [*args, "-o", model_file / "x.json"], "is a file")


def test_schema_to_a_new_folder(cli, tmp_path):
    target = tmp_path / "missing" / "dir" / "x.json"
    res = _invoke(cli, ["schema", "-o", target], tmp_path)
    assert res.exit_code == 0, res.output
    json.loads(target.read_text())
    assert_finite_files(tmp_path / "missing")


def test_dump_refuses_a_broken_file(cli, tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(law("1/0"), encoding="utf-8")
    expect_input_error(cli, tmp_path, ["dump", path, "-o", tmp_path / "o.yaml"], "by zero")


# ------------------------------------------------------------------ plot and animate
@pytest.fixture
def results(tmp_path):
    folder = tmp_path / "res" / "kin"
    folder.mkdir(parents=True)
    (folder / "results.csv").write_text("t,slider.x\n0,0.4\n1,0.3\n")
    (folder / "meta.json").write_text(json.dumps({"units": {"t": "s", "slider.x": "m"}}))
    return folder


def test_plot_missing_results(cli, tmp_path):
    expect_input_error(cli, tmp_path, ["plot", tmp_path / "nope", "-c", "t"], "no results")


def test_plot_unknown_column(cli, tmp_path, results):
    expect_input_error(cli, tmp_path, ["plot", results, "-c", "slider.z"], "no column")


def test_plot_bad_suffix(cli, tmp_path, results):
    args = ["plot", results, "-c", "slider.x", "-o", tmp_path / "x.jpg"]
    expect_input_error(cli, tmp_path, args, "cannot write a plot")


def test_plot_output_is_a_folder(cli, tmp_path, results):
    os.mkdir(tmp_path / "x.png")
    args = ["plot", results, "-c", "slider.x", "-o", tmp_path / "x.png"]
    expect_input_error(cli, tmp_path, args, "is a folder")


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--run", "kin", "-o", "x.avi"], "cannot write an animation"),
        (["--run", "nope", "-o", "x.gif"], "no run 'nope'"),
        (["--run", "kin", "-o", "x.gif", "--trace", "rod.Z"], "no point 'Z'"),
        (["--run", "kin", "-o", "x.gif", "--results", "nowhere"], "no results"),
    ],
)
def test_animate_refuses(cli, tmp_path, model_file, extra, expected):
    expect_input_error(cli, tmp_path, ["animate", model_file, *extra], expected)


def test_missing_arguments_exit_2(cli, tmp_path):
    res = _invoke(cli, ["check"], tmp_path)
    assert res.exit_code == 2 and "Traceback" not in res.output


# ------------------------------------------------------------------ the Python API
API = [
    ("distance-negative", lambda: md.Distance("d", "a", "b", length=-1)),
    ("distance-nan", lambda: md.Distance("d", "a", "b", length=math.nan)),
    ("units-unknown", lambda: md.UnitSystem("furlongz")),
    ("units-dimension", lambda: md.UnitSystem("m", "s", "s")),
    ("gravity-nan", lambda: md.Model([md.Body("b", 1, 1)], gravity=(math.nan, 0))),
    ("gravity-shape", lambda: md.Model([md.Body("b", 1, 1)], gravity=(0, 0, 0))),
    ("constant-inf", lambda: md.Constant(math.inf)),
    ("polynomial-nan", lambda: md.Polynomial([0, math.nan])),
    ("harmonic-nan", lambda: md.Harmonic(1, math.nan)),
    ("weld-angle", lambda: md.Weld("w", "a", "b", angle=math.inf)),
    ("axis-nan", lambda: md.Translational("s", "a", "b", axis=(math.nan, 1))),
    ("spring-nan", lambda: md.SpringDamper("k", "a", "b", stiffness=math.nan)),
    ("spring-free-length", lambda: md.SpringDamper("k", "a", "b", free_length=-1)),
    ("body-mass-nan", lambda: md.Body("b", math.nan, 1)),
]


@pytest.mark.parametrize(("case", "make"), API, ids=[c[0] for c in API])
def test_api_refuses(case, make):
    with pytest.raises(ModelError):
        make()


HOSTILE_EXPRESSIONS = [
    "1/0",
    "9**9**9**9",
    "1e308*10",
    "sqrt(-1)",
    "(-8)**(1/3)",
    "0**-1",
    "log(-1)",
    "-" * 500 + "1",
    "(" * 300 + "1" + ")" * 300,
    "1" + "**1" * 400,
    "9" * 500,
    "x" * 2000,
    "1e999",
    "min(" + "1," * 50 + "1)",
    "exp(exp(exp(10)))",
    "atan2(0, 0)",
    "0 % 0",
]


@pytest.mark.parametrize("expr", HOSTILE_EXPRESSIONS, ids=range(len(HOSTILE_EXPRESSIONS)))
def test_expressions_raise_only_named_errors(expr):
    """Constant expressions give a finite value or an ExpressionError, never a raw Python
    exception; laws of time likewise when built."""
    try:
        value = constant_value(expr)
    except ExpressionError:
        value = 0.0
    assert math.isfinite(value)
    with contextlib.suppress(ExpressionError):
        ExpressionLaw(f"t + ({expr})")


# ------------------------------------------------------------------ messages and progress
def test_clean_escapes_control_characters():
    assert clean("a\x1b[31mb\x07c\u202ed\nok") == "a\\x1b[31mb\\x07c\\u202ed\nok"


class _Plan:
    name = "swing\x1b]0;pwned\x07"
    times = (0.0, 2.0)


def test_progress_lines_without_a_terminal(capsys):
    at = progress_log(_Plan(), every=0.0)
    at(0.5)
    at(1.0)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2
    assert "t = 0.5 of 2 (25%)" in lines[0] and "\x1b" not in lines[0]


def test_progress_lines_are_throttled(capsys):
    at = progress_log(_Plan(), every=3600.0)
    for t in (0.1, 0.2, 0.3):
        at(t)
    assert capsys.readouterr().err == ""
